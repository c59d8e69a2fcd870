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
    ("inspect", &[]),
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
    ("generate", &["--out", "--vertices", "--poses", "--seed", "--band", "--noise", "--max-angle"]),
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
    ("export-gltf", &["--out", "--weights", "--bind", "--samples", "--band", "--seed"]),
    ("articulate-report", &["--from", "--to", "--t", "--glb", "--validate", "--band", "--tol"]),
];

#[test]
fn help_lists_every_subcommand_with_its_options() {
    let all = posemfa(&["help"]);
    assert!(all.status.success(), "{}", text(&all.stderr));
    let all = text(&all.stdout);
    for (cmd, opts) in COMMANDS {
        assert!(all.contains(&format!("posemfa {cmd} ")), "`posemfa help` misses {cmd}:\n{all}");
        for opt in *opts {
            assert!(all.contains(&format!("    {opt} ")), "`posemfa help` misses {opt}:\n{all}");
        }
        for asked in [posemfa(&["help", cmd]), posemfa(&[cmd, "--help"])] {
            assert!(asked.status.success(), "help {cmd}: {}", text(&asked.stderr));
            let one = text(&asked.stdout);
            assert!(one.contains(&format!("posemfa {cmd} ")), "help {cmd}:\n{one}");
            for opt in *opts {
                assert!(one.contains(&format!("    {opt} ")), "help {cmd} misses {opt}:\n{one}");
            }
        }
    }
    // one command's help lists only its own options
    let gen = text(&posemfa(&["help", "generate"]).stdout);
    assert!(!gen.contains("--literal-eq18") && !gen.contains("--from "), "{gen}");
    assert_eq!(text(&posemfa(&["--help"]).stdout), all);
}

#[test]
fn an_unknown_option_or_command_is_named() {
    let r = posemfa(&["fit", "synth:arm", "--prats", "3"]);
    assert_eq!(r.status.code(), Some(1));
    let e = text(&r.stderr);
    assert!(e.contains("unknown option --prats") && e.contains("posemfa help fit"), "{e}");
    assert!(r.stdout.is_empty());

    let r = posemfa(&["generate", "arm", "-x"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("unknown option -x"), "{}", text(&r.stderr));

    // an option of another subcommand
    let r = posemfa(&["generate", "arm", "--parts", "3", "--out", "/nonexistent/x"]);
    assert!(text(&r.stderr).contains("unknown option --parts"), "{}", text(&r.stderr));

    let r = posemfa(&["fitt", "synth:arm"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r.stderr).contains("unknown command 'fitt'"), "{}", text(&r.stderr));
}

#[test]
fn a_missing_or_bad_value_is_named() {
    for (args, want) in [
        (&["fit", "synth:arm", "--parts"][..], "--parts needs a value"),
        (&["fit", "synth:arm", "--json", "--quiet"][..], "--json needs a value"),
        (&["fit", "synth:arm", "--tol", "fast"][..], "--tol: 'fast' is not a valid number"),
        (&["fit", "synth:arm", "--quiet=yes"][..], "--quiet"),
        (&["interpolate", "synth:arm", "--skin", "soft", "--out", "x.obj"][..], "--skin: 'soft': use rigid or smooth"),
        (&["fit"][..], "no input"),
        (&["generate", "arm", "--vertices", "500"][..], "generate needs --out DIR"),
        (&["generate", "horse", "--out", "/nonexistent/x"][..], "unknown preset 'horse'"),
        (&["fit", "synth:arm", "--parts", "0"][..], "parts"),
        (&["fit", "synth:arm:600:6:1", "--bones", "0"][..], "target_parts = 0"),
        (&["fit", "synth:arm:600:6:1", "--bones", "some"][..], "--bones: 'some' is not a valid number"),
        (&["export-gltf", "synth:arm:600:6:1", "--out", "x.glb", "--bones", "100000"][..], "ask for at most"),
    ] {
        let r = posemfa(args);
        assert_eq!(r.status.code(), Some(1), "{args:?}");
        let e = text(&r.stderr);
        assert!(e.starts_with("error: ") && e.contains(want), "{args:?}: expected '{want}' in:\n{e}");
    }
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

/// `posemfa generate --format F` writes each format a user can try, and `posemfa fit` reads each back to the
/// same population: the same fit as from the OBJ files (labels with adjusted Rand index >= 0.99), and the
/// `poses:` line says where the poses came from.
#[test]
fn generate_writes_every_format_and_fit_reads_it_back() {
    let root = std::env::temp_dir().join(format!("posemfa-cli-formats-{}", std::process::id()));
    let labels_of = |format: &str, want: &str| -> Vec<u32> {
        let dir = root.join(format);
        let dir_arg = dir.to_str().expect("utf-8 temp path");
        let r = posemfa(&["generate", "arm", "--vertices", "600", "--poses", "5", "--format", format, "--out", dir_arg]);
        assert!(r.status.success(), "generate --format {format}: {}", text(&r.stderr));
        let json = root.join(format!("{format}.json"));
        let r = posemfa(&["fit", dir_arg, "--parts", "3", "--json", json.to_str().unwrap()]);
        let out = text(&r.stdout);
        assert!(r.status.success(), "fit of --format {format}: {}", text(&r.stderr));
        let line = out.lines().find(|l| l.trim_start().starts_with("poses: ")).unwrap_or_else(|| panic!("no poses line:\n{out}"));
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
