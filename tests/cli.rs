//! The `posemfa` binary as a user runs it: help, errors for bad options, and a small fit.
#![cfg(not(target_arch = "wasm32"))]

use std::process::{Command, Output};

fn posemfa(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_posemfa")).args(args).output().expect("the posemfa binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Every subcommand and, for each, options from each of its option groups.
const COMMANDS: &[(&str, &[&str])] = &[
    ("inspect", &["--json", "--geometry", "--object", "--frames"]),
    (
        "fit",
        &[
            "--parts",
            "--seed",
            "--tol",
            "--max-iter",
            "--floor",
            "--literal-eq18",
            "--no-refine",
            "--json",
            "--quiet",
            "--repeat",
        ],
    ),
    ("bench", &["--parts", "--json", "--repeat"]),
    ("generate", &["--out", "--format", "--vertices", "--poses", "--seed", "--band", "--noise", "--max-angle"]),
    (
        "interpolate",
        &[
            "--from",
            "--to",
            "--t",
            "--out",
            "--skin",
            "--blend",
            "--no-residual",
            "--paper-root",
            "--paper",
            "--linear",
            "--band",
            "--parts",
        ],
    ),
    (
        "export-gltf",
        &["--out", "--weights", "--influences", "--joints", "--morphs", "--bind", "--samples", "--band", "--seed"],
    ),
    ("rig-report", &["--glb", "--truth", "--out", "--weights", "--bind", "--band", "--parts"]),
    ("pose", &["--out", "--json"]),
    ("crossval", &["--json", "--weights", "--bones", "--parts"]),
    ("subdivide", &["--out", "--levels", "--object", "--animation", "--frames", "--poses-from"]),
    ("articulate-report", &["--from", "--to", "--t", "--glb", "--validate", "--band", "--tol"]),
    ("completions", &[]),
];

/// What the help says the inputs may be: every format read (the list in posemfa::mesh::load).
fn formats_line() -> String {
    format!("posemfa reads {}", posemfa::mesh::load::formats_read())
}

#[test]
fn help_lists_every_subcommand_and_each_its_options() {
    let all = posemfa(&["help"]);
    assert!(all.status.success(), "{}", text(&all.stderr));
    let all = text(&all.stdout);
    // the inputs: every format read, not "a folder of OBJ files"
    let flat = all.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(flat.contains(&formats_line()) && !all.contains("OBJ files"), "{all}");
    for (cmd, opts) in COMMANDS {
        assert!(
            all.lines().any(|l| l.trim_start().starts_with(&format!("{cmd} "))),
            "`posemfa help` misses {cmd}:\n{all}"
        );
        for asked in [posemfa(&["help", cmd]), posemfa(&[cmd, "--help"]), posemfa(&[cmd, "-h"])] {
            assert!(asked.status.success(), "help {cmd}: {}", text(&asked.stderr));
            assert!(asked.stderr.is_empty(), "help {cmd}: {}", text(&asked.stderr));
            let one = text(&asked.stdout);
            assert!(one.contains(&format!("Usage: posemfa {cmd} ")), "help {cmd}:\n{one}");
            for opt in *opts {
                assert!(
                    one.contains(&format!("    {opt} ")) || one.contains(&format!("    {opt}\n")),
                    "help {cmd} misses {opt}:\n{one}"
                );
            }
        }
    }
    // one command's help lists only its own options
    let gen = text(&posemfa(&["help", "generate"]).stdout);
    assert!(!gen.contains("--literal-eq18") && !gen.contains("--from "), "{gen}");
    // a fitting command's help says what the inputs may be
    let fit = text(&posemfa(&["fit", "--help"]).stdout);
    assert!(fit.split_whitespace().collect::<Vec<_>>().join(" ").contains(&formats_line()), "{fit}");
    assert_eq!(text(&posemfa(&["--help"]).stdout), all);
    // no command: the help, on stderr, exit 1
    let none = posemfa(&[]);
    assert_eq!(none.status.code(), Some(1));
    assert!(text(&none.stderr).contains("Commands:") && none.stdout.is_empty(), "{}", text(&none.stderr));
}

#[test]
fn an_unknown_option_or_command_is_named() {
    // a typo: clap names it and says which option was meant
    let r = posemfa(&["fit", "synth:arm", "--prats", "3"]);
    assert_eq!(r.status.code(), Some(1));
    let e = text(&r.stderr);
    assert!(e.starts_with("error: unexpected argument '--prats' found"), "{e}");
    assert!(e.contains("a similar argument exists: '--parts'"), "{e}");
    assert!(r.stdout.is_empty());

    let r = posemfa(&["fit", "synth:arm", "--frobnicate"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).starts_with("error: unexpected argument '--frobnicate' found"), "{}", text(&r.stderr));

    let r = posemfa(&["generate", "arm", "-x"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("unexpected argument '-x'"), "{}", text(&r.stderr));

    // an option of another subcommand
    let r = posemfa(&["generate", "arm", "--parts", "3", "--out", "/nonexistent/x"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("unexpected argument '--parts'"), "{}", text(&r.stderr));

    let r = posemfa(&["fitt", "synth:arm"]);
    assert_eq!(r.status.code(), Some(1));
    let e = text(&r.stderr);
    assert!(e.contains("unrecognized subcommand 'fitt'") && e.contains("a similar subcommand exists: 'fit'"), "{e}");

    let r = posemfa(&["help", "interpolat"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("unrecognized subcommand 'interpolat'"), "{}", text(&r.stderr));
}

#[test]
fn a_missing_or_bad_value_is_named() {
    for (args, want) in [
        (&["fit", "synth:arm", "--parts"][..], "a value is required for '--parts <M>'"),
        (&["fit", "synth:arm", "--json", "--quiet"][..], "a value is required for '--json <OUT>'"),
        (&["fit", "synth:arm", "--tol", "fast"][..], "invalid value 'fast' for '--tol <T>': 'fast' is not a number: it must be a positive number (try 1e-3)"),
        (&["fit", "synth:arm", "--quiet=yes"][..], "unexpected value 'yes' for '--quiet'"),
        (&["interpolate", "synth:arm", "--skin", "soft", "--out", "x.obj"][..], "invalid value 'soft' for '--skin <rigid|smooth>'"),
        (&["interpolate", "synth:arm", "--from", "0x", "--to", "2", "--t", "0.5", "--out", "x.obj"][..], "'0x' is not a pose number"),
        (&["interpolate", "synth:arm", "--from", "1", "--to", "2", "--out", "x.obj"][..], "--t <T>"),
        (&["fit"][..], "the following required arguments were not provided:\n  <DIR_OR_FILES>..."),
        (&["generate", "arm", "--vertices", "500"][..], "the following required arguments were not provided:\n  --out <DIR>"),
        (&["generate", "horse", "--out", "/nonexistent/x"][..], "invalid value 'horse' for '[PRESET]'"),
        (&["generate", "arm", "--format", "stl", "--out", "/nonexistent/x"][..], "invalid value 'stl' for '--format <F>'"),
        (&["fit", "synth:horse"][..], "unknown preset 'horse'"),
        (&["fit", "synth:arm", "--parts", "0"][..], "parts"),
        (&["fit", "synth:arm:600:6:1", "--bones", "0"][..], "target_parts = 0"),
        (&["fit", "synth:arm:600:6:1", "--bones", "some"][..], "invalid value 'some' for '--bones <N>': 'some' is not a whole number: it must be a positive whole number, or auto"),
        (&["fit", "synth:arm:600:6:1", "--refine-threshold", "1e-4", "--part-rule", "distinct"][..], "--part-rule distinct"),
        (&["export-gltf", "synth:arm:600:6:1", "--out", "x.glb", "--bones", "100000"][..], "ask for at most"),
        (&["completions", "tcsh"][..], "invalid value 'tcsh' for '<SHELL>'"),
    ] {
        let r = posemfa(args);
        assert_eq!(r.status.code(), Some(1), "{args:?}");
        let e = text(&r.stderr);
        assert!(e.starts_with("error: ") && e.contains(want), "{args:?}: expected '{want}' in:\n{e}");
        assert!(r.stdout.is_empty(), "{args:?}: {}", text(&r.stdout));
    }
    // the possible values of a choice are listed
    let e = text(&posemfa(&["generate", "horse", "--out", "/nonexistent/x"]).stderr);
    assert!(e.contains("[possible values: quadruped, arm, snake, blob, spider, giraffe, hand]"), "{e}");
}

/// A file of an extension posemfa does not read is refused by name with the list of what it reads (it used to
/// be parsed as OBJ: "a NUL byte at column ..."); in a folder such files are left out, .mtl files included.
#[test]
fn a_file_of_another_extension_is_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("posemfa-cli-ext-{}", std::process::id()));
    let dir_arg = dir.to_str().expect("utf-8 temp path");
    let r = posemfa(&["generate", "arm", "--vertices", "300", "--poses", "3", "--out", dir_arg]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    std::fs::write(dir.join("scene.blend"), b"BLENDER-v300\0\0\0binary").unwrap();
    std::fs::write(dir.join("arm.mtl"), b"newmtl skin\n").unwrap();
    let blend = dir.join("scene.blend");
    let r = posemfa(&["fit", blend.to_str().unwrap(), dir.join("pose01.obj").to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(1));
    assert_eq!(
        text(&r.stderr),
        "error: file scene.blend: posemfa reads .obj, .ply, .glb/.gltf, .fbx, .usd/.usda/.usdc/.usdz, .pc2/.mdd with a base mesh; not .blend: \
         export the poses as one of these (e.g. glTF from Blender), or leave the file out\n"
    );
    let r = posemfa(&["fit", dir_arg, "--parts", "2", "--quiet"]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert!(text(&r.stdout).contains("poses: 3 OBJ files"), "{}", text(&r.stdout));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `posemfa completions SHELL` writes a script that names every subcommand, and bash can read it.
#[test]
fn completions_for_bash_zsh_and_fish() {
    for (shell, marker) in
        [("bash", "complete -F _posemfa"), ("zsh", "#compdef posemfa"), ("fish", "complete -c posemfa")]
    {
        let r = posemfa(&["completions", shell]);
        assert!(r.status.success(), "{shell}: {}", text(&r.stderr));
        let script = text(&r.stdout);
        assert!(script.contains(marker), "{shell}: no '{marker}'");
        for (cmd, opts) in COMMANDS {
            assert!(script.contains(cmd), "{shell}: misses {cmd}");
            for opt in *opts {
                assert!(script.contains(opt.trim_start_matches('-')), "{shell}: misses {opt}");
            }
        }
        assert!(script.contains("morph-targets") && script.contains("ply-ascii"), "{shell}: the choices are completed");
    }
    // bash parses the script
    let script = std::env::temp_dir().join(format!("posemfa-completion-{}.bash", std::process::id()));
    std::fs::write(&script, posemfa(&["completions", "bash"]).stdout).unwrap();
    if let Ok(check) = Command::new("bash").arg("-n").arg(&script).output() {
        assert!(check.status.success(), "bash -n: {}", text(&check.stderr));
    }
    let _ = std::fs::remove_file(&script);
}

#[test]
fn a_small_fit_on_the_arm_writes_its_json() {
    let json = std::env::temp_dir().join(format!("posemfa-cli-{}.json", std::process::id()));
    let json_arg = json.to_str().expect("utf-8 temp path");
    let r = posemfa(&["fit", "synth:arm:600:6:1", "--parts", "3", "--quiet", "--json", json_arg]);
    let out = text(&r.stdout);
    assert!(r.status.success(), "{}\n{out}", text(&r.stderr));
    assert!(r.stderr.is_empty(), "--quiet: {}", text(&r.stderr));
    assert!(
        out.contains("6 shapes x ") && out.contains("ground truth") && out.contains(&format!("wrote {json_arg}")),
        "{out}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the JSON was written")).unwrap();
    let _ = std::fs::remove_file(&json);
    assert_eq!(v["shapes"].as_array().map(Vec::len), Some(6));
    let n = v["n_vertices"].as_u64().expect("n_vertices") as usize;
    assert!(out.contains(&format!("6 shapes x {n} vertices")), "{out}");
    assert_eq!(v["labels"].as_array().map(Vec::len), Some(n));
    // the two-link arm: the ground truth line reports how well the parts were found
    let line = out.lines().find(|l| l.contains("ground truth")).unwrap();
    let truth: serde_json::Value = serde_json::from_str(line.trim().trim_start_matches("ground truth: ")).unwrap();
    let ari = truth["ari"].as_f64().expect("ari");
    assert!(ari > 0.8, "adjusted Rand index {ari}: {line}");
}

#[test]
fn a_model_saved_with_its_rig_gives_that_rig_without_solving_it_again() {
    let dir = std::env::temp_dir().join(format!("posemfa-cli-rig-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().expect("utf-8 temp path").to_string();
    let input = "synth:quadruped:900:5:2";
    let r = posemfa(&["fit", input, "--quiet", "--save", &p("m.posemfa"), "--with-rig"]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert!(text(&r.stdout).contains("with the rig of --weights fitted"), "{}", text(&r.stdout));
    // export-gltf: the kept rig, and the bytes of the command that fits and solves
    let fitting = posemfa(&["export-gltf", input, "--weights", "fitted", "--out", &p("a.glb")]);
    let kept = posemfa(&["export-gltf", "--model", &p("m.posemfa"), "--weights", "fitted", "--out", &p("b.glb")]);
    assert!(fitting.status.success() && kept.status.success(), "{} {}", text(&fitting.stderr), text(&kept.stderr));
    assert!(text(&kept.stdout).contains("the rig kept in the model file"), "{}", text(&kept.stdout));
    assert!(std::fs::read(p("a.glb")).unwrap() == std::fs::read(p("b.glb")).unwrap(), "the same .glb");
    // other options build their own rig
    let other = posemfa(&[
        "export-gltf",
        "--model",
        &p("m.posemfa"),
        "--weights",
        "fitted",
        "--influences",
        "2",
        "--out",
        &p("c.glb"),
    ]);
    assert!(
        other.status.success() && !text(&other.stdout).contains("kept in the model file"),
        "{}",
        text(&other.stdout)
    );
    // rig-report says where its rig came from, and measures the same rig
    let report = |args: &[&str]| -> serde_json::Value {
        let r = posemfa(args);
        assert!(r.status.success(), "{}", text(&r.stderr));
        serde_json::from_str(&text(&r.stdout)).expect("rig-report prints JSON")
    };
    let a = report(&["rig-report", input, "--weights", "fitted"]);
    let b = report(&["rig-report", "--model", &p("m.posemfa"), "--weights", "fitted"]);
    assert_eq!(a["rig_source"], "built");
    assert_eq!(b["rig_source"], "model file");
    assert_eq!(a["e_rms"], b["e_rms"]);
    assert_eq!(a["solver_trace"], b["solver_trace"]);
    // a model without its poses cannot solve a rig
    let r = posemfa(&["fit", "--model", &p("m.posemfa"), "--quiet", "--save", &p("bare.posemfa"), "--without-poses"]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let r = posemfa(&["fit", "--model", &p("bare.posemfa"), "--quiet", "--save", &p("x.posemfa"), "--with-rig"]);
    assert!(
        !r.status.success() && text(&r.stderr).contains("--with-rig: the model file holds no poses"),
        "{}",
        text(&r.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bones_n_gives_exactly_n_parts() {
    let json = std::env::temp_dir().join(format!("posemfa-cli-bones-{}.json", std::process::id()));
    let json_arg = json.to_str().expect("utf-8 temp path");
    let r = posemfa(&["fit", "synth:arm:600:6:1", "--bones", "5", "--quiet", "--json", json_arg]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the JSON was written")).unwrap();
    let _ = std::fs::remove_file(&json);
    assert_eq!(v["parts"].as_array().map(Vec::len), Some(5), "{}", text(&r.stdout));
    assert_eq!(v["islands"].as_u64(), Some(0));
}

/// `--start-labels`: the fit from a given partition keeps its count (a fit JSON's labels, or an array of them);
/// a file that is no partition is refused naming the flag and the file.
#[test]
fn start_labels_fit_from_a_partition_with_its_count() {
    let dir = std::env::temp_dir().join(format!("posemfa-cli-start-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let first = dir.join("first.json");
    let r = posemfa(&["fit", "synth:quadruped:1500:8:1", "--bones", "7", "--quiet", "--json", first.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&first).unwrap()).unwrap();
    let labels: Vec<u32> = serde_json::from_value(v["labels"].clone()).unwrap();
    // the seven parts given as a plain array, with part 0 and part 1 as one: six parts
    let six: Vec<u32> = labels.iter().map(|&l| l.max(1) - 1).collect();
    let array = dir.join("six.json");
    std::fs::write(&array, serde_json::to_string(&six).unwrap()).unwrap();
    let out = dir.join("out.json");
    for (start, want) in [(&first, 7), (&array, 6)] {
        let r = posemfa(&[
            "fit",
            "synth:quadruped:1500:8:1",
            "--start-labels",
            start.to_str().unwrap(),
            "--quiet",
            "--json",
            out.to_str().unwrap(),
        ]);
        assert!(r.status.success(), "{}", text(&r.stderr));
        let w: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(w["parts"].as_array().map(Vec::len), Some(want), "{}", start.display());
    }
    std::fs::write(&array, "{\"a\": 1}").unwrap();
    let r = posemfa(&["fit", "synth:quadruped:1500:8:1", "--start-labels", array.to_str().unwrap()]);
    assert!(!r.status.success());
    let e = text(&r.stderr);
    assert!(
        e.contains("--start-labels") && e.contains("six.json") && e.contains("nor a fit JSON with `labels`"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `posemfa generate --format F` writes each format a user can try, and `posemfa fit` reads each back to the
/// same population: the same fit as from the OBJ files (labels with adjusted Rand index >= 0.99), and the
/// `poses:` line says where the poses came from.
#[test]
fn generate_writes_every_format_and_fit_reads_it_back() {
    let root = std::env::temp_dir().join(format!("posemfa-cli-formats-{}", std::process::id()));
    let labels_of = |format: &str, want: &str| -> Vec<u32> {
        let dir = root.join(format);
        let dir_arg = dir.to_str().expect("utf-8 temp path");
        let r =
            posemfa(&["generate", "arm", "--vertices", "600", "--poses", "5", "--format", format, "--out", dir_arg]);
        assert!(r.status.success(), "generate --format {format}: {}", text(&r.stderr));
        let json = root.join(format!("{format}.json"));
        let r = posemfa(&["fit", dir_arg, "--parts", "3", "--json", json.to_str().unwrap()]);
        let out = text(&r.stdout);
        assert!(r.status.success(), "fit of --format {format}: {}", text(&r.stderr));
        let line = out
            .lines()
            .find(|l| l.trim_start().starts_with("poses: "))
            .unwrap_or_else(|| panic!("no poses line:\n{out}"));
        assert!(line.contains(want), "--format {format}: expected '{want}' in '{line}'");
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(v["shapes"].as_array().map(Vec::len), Some(5), "--format {format}");
        v["labels"].as_array().unwrap().iter().map(|l| l.as_u64().unwrap() as u32).collect()
    };
    let obj = labels_of("obj", "5 OBJ files");
    for (format, want) in [
        ("ply", "5 PLY files"),
        ("ply-ascii", "5 PLY files"),
        ("pc2", "5 frames of the point cache poses.pc2"),
        ("glb", "5 frames of animation 'Poses'"),
    ] {
        let labels = labels_of(format, want);
        let ari = posemfa::metrics::adjusted_rand_index(&obj, &labels);
        assert!(ari >= 0.99, "--format {format}: ARI {ari} against the OBJ files' fit");
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// `posemfa subdivide`: every triangle in four, the same in every pose; the finer population keeps the names,
/// has V + E vertices and 4F triangles, and fits to the same parts as the coarse one.
#[test]
fn subdivide_writes_a_registered_finer_population_that_fits_to_the_same_parts() {
    let root = std::env::temp_dir().join(format!("posemfa-cli-subdivide-{}", std::process::id()));
    let (coarse, fine) = (root.join("coarse"), root.join("fine"));
    let r = posemfa(&["generate", "arm", "--vertices", "400", "--poses", "5", "--out", coarse.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let r = posemfa(&["subdivide", coarse.to_str().unwrap(), "--out", fine.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let read = |dir: &std::path::Path| {
        let mut names: Vec<_> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        names.sort();
        let first = posemfa::mesh::obj::parse_obj(&names[0], &std::fs::read(dir.join(&names[0])).unwrap()).unwrap();
        (names, first)
    };
    let ((names, a), (fine_names, b)) = (read(&coarse), read(&fine));
    assert_eq!(names, fine_names);
    let mut edges = std::collections::HashSet::new();
    for t in &a.faces {
        for k in 0..3 {
            edges.insert((t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])));
        }
    }
    assert_eq!(b.positions.len(), a.positions.len() + edges.len());
    assert_eq!(b.faces.len(), 4 * a.faces.len());
    assert!(
        text(&r.stdout).contains(&format!("wrote 5 poses of {} vertices", b.positions.len())),
        "{}",
        text(&r.stdout)
    );
    // the old vertices where they were (to the f32 storage of the unit box)
    let side = (0..3)
        .map(|d| {
            a.positions.iter().map(|p| p[d]).fold(f64::MIN, f64::max)
                - a.positions.iter().map(|p| p[d]).fold(f64::MAX, f64::min)
        })
        .fold(0.0, f64::max);
    for (p, q) in a.positions.iter().zip(&b.positions) {
        assert!((0..3).all(|d| (p[d] - q[d]).abs() <= 1e-6 * side), "{p:?} vs {q:?}");
    }
    // both fit to the same parts on the old vertices
    let labels = |dir: &std::path::Path, name: &str| -> Vec<u32> {
        let json = root.join(name);
        let r = posemfa(&["fit", dir.to_str().unwrap(), "--quiet", "--json", json.to_str().unwrap()]);
        assert!(r.status.success(), "{}", text(&r.stderr));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        v["labels"].as_array().unwrap().iter().map(|l| l.as_u64().unwrap() as u32).collect()
    };
    let (lc, lf) = (labels(&coarse, "coarse.json"), labels(&fine, "fine.json"));
    let ari = posemfa::metrics::adjusted_rand_index(&lc, &lf[..lc.len()]);
    assert!(ari >= 0.9, "adjusted Rand {ari} between the coarse and the subdivided arm's parts");
    // a population from one file (a .glb of 5 frames): one OBJ per pose, none overwritten
    let (glb, from_glb) = (root.join("glb"), root.join("from-glb"));
    let r = posemfa(&[
        "generate",
        "arm",
        "--vertices",
        "300",
        "--poses",
        "5",
        "--format",
        "glb",
        "--out",
        glb.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let r = posemfa(&["subdivide", glb.to_str().unwrap(), "--out", from_glb.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert_eq!(std::fs::read_dir(&from_glb).unwrap().count(), 5, "{}", text(&r.stdout));
    let r = posemfa(&["fit", from_glb.to_str().unwrap(), "--quiet"]);
    assert!(r.status.success() && text(&r.stdout).contains("5 shapes"), "{}{}", text(&r.stdout), text(&r.stderr));
    // the input options a fit takes: 3 evenly spaced times of the clip, one OBJ each
    let three = root.join("three");
    let r = posemfa(&["subdivide", glb.to_str().unwrap(), "--frames", "3", "--out", three.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert_eq!(std::fs::read_dir(&three).unwrap().count(), 3, "{}", text(&r.stdout));
    // a result larger than the memory budget is refused, nothing written
    let big = root.join("big");
    let r = Command::new(env!("CARGO_BIN_EXE_posemfa"))
        .args(["subdivide", coarse.to_str().unwrap(), "--levels", "4", "--out", big.to_str().unwrap()])
        .env("POSEMFA_MEMORY_BUDGET", "10M")
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("fewer levels") && !big.exists(), "{}", text(&r.stderr));
    // a missing input is named
    let r = posemfa(&["subdivide", root.join("nothing").to_str().unwrap(), "--out", fine.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("nothing"), "{}", text(&r.stderr));
    let _ = std::fs::remove_dir_all(&root);
}

/// `--object NAME` picks the mesh of an FBX / USD (or glTF) file; a name the file does not hold is refused
/// with the list of its meshes; `--mesh` is the same option.
#[test]
fn object_picks_the_mesh_of_an_fbx_or_usd_file() {
    let fbx = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/blender/quadruped-shapekeys.fbx");
    for flag in ["--object", "--mesh"] {
        let r = posemfa(&["fit", fbx, flag, "Nope", "--quiet"]);
        assert!(!r.status.success());
        let err = text(&r.stderr);
        assert!(
            err.contains("quadruped-shapekeys.fbx: no mesh is called or numbered `Nope`; the file has posed"),
            "{err}"
        );
    }
    let usd = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/usd/arm-pointcache.usda");
    let r = posemfa(&["fit", usd, "--object", "/World/Character/Body", "--parts", "2", "--max-iter", "5"]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let out = text(&r.stdout) + &text(&r.stderr);
    assert!(out.contains("5 frames of Body in arm-pointcache.usda"), "{out}");
}

/// `robustness --drop-each`: one run per pose, each without that pose, with their own agreement line and JSON.
/// The generated arm (3 rigid parts, ground truth from the generator) keeps its parts with any pose dropped.
#[test]
fn robustness_drops_each_pose_in_turn() {
    let json = std::env::temp_dir().join(format!("posemfa-cli-robust-{}.json", std::process::id()));
    let out =
        posemfa(&["robustness", "synth:arm:600:5", "--seeds", "1", "--drop-each", "--json", json.to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    for k in 1..=5 {
        assert!(stdout.contains(&format!("pose {k} dropped")), "{stdout}");
    }
    assert!(!stdout.contains("pose 6 dropped"), "{stdout}");
    assert!(stdout.contains("each pose dropped: parts 3-3 (spread 0)"), "{stdout}");
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let _ = std::fs::remove_file(&json);
    let each = &doc["eachDropped"];
    assert_eq!(each["runs"].as_array().map(|r| r.len()), Some(5), "{doc}");
    assert_eq!(each["agreement"]["mostParts"], 3);
    assert!(each["runs"][0]["truthAri"].as_f64().unwrap() > 0.97, "{doc}");
    // without the flag there is no such section
    let plain = posemfa(&["robustness", "synth:arm:600:5", "--seeds", "1"]);
    assert!(!text(&plain.stdout).contains("each pose dropped"));
}

/// `posemfa inspect` reads what `fit` reads (read as OBJ, an .fbx or .usdc would give "a NUL
/// byte ... not an OBJ text file"): each format posemfa generates, Blender's and usd-core's fixtures, a .zip and
/// one pose file alone, with their pose, vertex and triangle counts and what the reader welded.
#[test]
fn inspect_reads_every_format_fit_reads() {
    let root = std::env::temp_dir().join(format!("posemfa-cli-inspect-{}", std::process::id()));
    let inspect = |path: &std::path::Path| -> serde_json::Value {
        let r = posemfa(&["inspect", "--json", path.to_str().expect("utf-8 path")]);
        assert!(r.status.success(), "inspect {}: {}", path.display(), text(&r.stderr));
        serde_json::from_str(&text(&r.stdout)).unwrap_or_else(|e| panic!("inspect {}: {e}", path.display()))
    };
    let counts = |v: &serde_json::Value| (v["n_poses"].as_u64(), v["n_vertices"].as_u64(), v["n_triangles"].as_u64());
    let mut generated = Vec::new();
    for format in ["obj", "ply", "pc2", "glb"] {
        let dir = root.join(format);
        let r = posemfa(&[
            "generate",
            "arm",
            "--vertices",
            "600",
            "--poses",
            "5",
            "--format",
            format,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(r.status.success(), "{}", text(&r.stderr));
        generated.push((format, inspect(&dir)));
    }
    let (_, obj) = &generated[0];
    let (n_poses, n_vertices, n_triangles) = counts(obj);
    assert_eq!(n_poses, Some(5));
    assert!(n_vertices.unwrap() > 500 && n_triangles.unwrap() > n_vertices.unwrap(), "{obj}");
    for (format, v) in &generated {
        assert_eq!(counts(v), (n_poses, n_vertices, n_triangles), "--format {format}: {v}");
        assert!(v["welded"].is_null(), "--format {format}: {v}");
    }
    assert_eq!(obj["source"], "5 OBJ files");
    assert_eq!(
        generated[2].1["source"].as_str().map(|s| s.starts_with("5 frames of the point cache poses.pc2")),
        Some(true)
    );

    // the readers of other tools' files, with what they weld
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    for (file, want) in [
        ("blender/quadruped-shapekeys.fbx", (6, 1198, 2392)),
        ("blender/quadruped-skinned-seams.glb", (121, 1198, 2392)),
        ("usd/arm-pointcache.usda", (5, 408, 812)),
        ("usd/arm-pointcache.usdc", (5, 408, 812)),
        ("usd/arm-pointcache.usdz", (5, 408, 812)),
    ] {
        let v = inspect(&fixtures.join(file));
        assert_eq!(counts(&v), (Some(want.0), Some(want.1), Some(want.2)), "{file}: {v}");
        if file.ends_with("seams.glb") {
            assert_eq!(v["welded"]["vertices_in_file"], 7176, "{v}");
            assert_eq!(v["welded"]["vertices"], 1198, "{v}");
            assert_eq!(v["welded"]["why"], "seams split by the exporter", "{v}");
        } else {
            assert!(v["welded"].is_null(), "{file}: {v}");
        }
    }

    // a .zip of the OBJ files in two folders, with a README and a resource fork
    let zip_path = root.join("poses.zip");
    let mut files: Vec<_> = std::fs::read_dir(root.join("obj")).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    let mut entries: Vec<(String, Vec<u8>)> = files
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let name = f.file_name().unwrap().to_str().unwrap();
            (format!("walk/{}/{name}", if k < 2 { "a" } else { "b" }), std::fs::read(f).unwrap())
        })
        .collect();
    entries.push(("README.txt".into(), b"five poses of an arm".to_vec()));
    entries.push(("__MACOSX/walk/a/._pose01.obj".into(), vec![0, 5, 22, 7]));
    std::fs::write(&zip_path, zip_of(&entries)).unwrap();
    let v = inspect(&zip_path);
    assert_eq!(counts(&v), (n_poses, n_vertices, n_triangles), "{v}");
    assert_eq!(
        v["source"],
        "5 OBJ files; read from poses.zip (5 mesh files; skipped README.txt (not a mesh file), \
         __MACOSX/walk/a/._pose01.obj (macOS resource fork))"
    );
    assert_eq!(v["poses"][2], "poses.zip/walk/b/pose03.obj");

    // the text form, and one pose file alone (which fit refuses: it needs two poses)
    let r = posemfa(&["inspect", fixtures.join("blender/quadruped-skinned-seams.glb").to_str().unwrap()]);
    let out = text(&r.stdout);
    assert!(r.status.success(), "{}", text(&r.stderr));
    assert!(out.contains("\nposes:      121: quadruped-skinned-seams.glb frame 001, "), "{out}");
    assert!(out.contains("\nvertices:   1198\ntriangles:  2392\n"), "{out}");
    assert!(
        out.contains("\nwelded:     7176 vertices in the file welded to 1198 (seams split by the exporter)\n"),
        "{out}"
    );
    let one = root.join("obj/pose01.obj");
    let v = inspect(&one);
    assert_eq!(counts(&v), (Some(1), n_vertices, n_triangles), "{v}");
    assert_eq!(v["source"], "1 OBJ file (one pose: fit needs at least 2 poses of the same mesh)");
    let r = posemfa(&["inspect", "--json", "--geometry", one.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_str(&text(&r.stdout)).unwrap();
    assert_eq!(v["vertices"].as_array().map(Vec::len) as Option<usize>, n_vertices.map(|n| n as usize));
    assert_eq!(v["triangles"].as_array().map(Vec::len) as Option<usize>, n_triangles.map(|n| n as usize));

    // errors are the reader's, exit 1
    let bad = root.join("bad.usdc");
    std::fs::write(&bad, b"PXR-USDC\0\x08\0\0\0\0\0\0").unwrap();
    let r = posemfa(&["inspect", bad.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(1));
    assert!(
        text(&r.stderr).starts_with("error: file bad.usdc: cannot read the USD crate file (usdc): "),
        "{}",
        text(&r.stderr)
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// A zip of `entries` (path, bytes), deflated, as zip tools write one.
fn zip_of(entries: &[(String, Vec<u8>)]) -> Vec<u8> {
    use std::io::Write;
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    for (path, bytes) in entries {
        let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        w.start_file(path.as_str(), options).unwrap();
        w.write_all(bytes).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// `posemfa fit poses.zip` fits what the folder of the same files fits (the page opens a .zip; so does the CLI
/// now), and a zip bomb is refused by name.
#[test]
fn fit_reads_a_zip_as_the_folder_and_refuses_a_bomb() {
    let root = std::env::temp_dir().join(format!("posemfa-cli-zip-{}", std::process::id()));
    let dir = root.join("set");
    let r = posemfa(&["generate", "arm", "--vertices", "600", "--poses", "5", "--out", dir.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let entries: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|f| (format!("arm/{}", f.file_name().unwrap().to_str().unwrap()), std::fs::read(&f).unwrap()))
        .collect();
    let zip_path = root.join("arm.zip");
    std::fs::write(&zip_path, zip_of(&entries)).unwrap();
    let fit = |input: &std::path::Path| {
        let json = root.join("fit.json");
        let r = posemfa(&["fit", input.to_str().unwrap(), "--json", json.to_str().unwrap(), "--quiet"]);
        assert!(r.status.success(), "fit {}: {}", input.display(), text(&r.stderr));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (text(&r.stdout), v["labels"].clone(), v["rmse"].as_f64().unwrap())
    };
    let (_, labels, rmse) = fit(&dir);
    let (out, zip_labels, zip_rmse) = fit(&zip_path);
    assert!(out.contains("poses: 5 OBJ files; read from arm.zip (5 mesh files)"), "{out}");
    assert_eq!(zip_labels, labels);
    assert_eq!(zip_rmse, rmse);

    // a bomb: 3 MiB of spaces (3 kB deflated) with the memory budget at 4 MiB (a zip may unpack to half)
    let bomb = root.join("bomb.zip");
    std::fs::write(&bomb, zip_of(&[("pose1.obj".into(), vec![b' '; 3 << 20])])).unwrap();
    let r = Command::new(env!("CARGO_BIN_EXE_posemfa"))
        .args(["fit", bomb.to_str().unwrap()])
        .env("POSEMFA_MEMORY_BUDGET", "4M")
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(1));
    assert_eq!(
        text(&r.stderr),
        "error: file bomb.zip: its mesh files unpack to 3.0 MiB (as the archive declares), more than the 2.0 MiB a \
         zip archive may unpack to (half the memory budget); the archive is a zip bomb, or far larger than a pose \
         population: unzip it and give the folder instead\n"
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// `--trace` prints what the fit's stages decided (the core's trace, `posemfa::trace`); without it, nothing.
#[test]
fn trace_prints_the_stages_decisions_only_when_asked() {
    let out = posemfa(&["fit", "synth:arm:600:5", "--quiet", "--trace"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("trace: tree: ") && err.contains("patches, start at"), "{err}");
    let quiet = posemfa(&["fit", "synth:arm:600:5", "--quiet"]);
    assert!(!String::from_utf8_lossy(&quiet.stderr).contains("trace:"));
}
