//! Hostile inputs per reader, through `posemfa fit` as a user runs it: cut files, huge counts, deep nesting, NaN
//! and infinite coordinates, degenerate and non-manifold faces, poses of different vertex counts. Each is either
//! refused with an error that names the file and what is wrong, or read, as the table in docs/testing.md
//! ("Hostile inputs per reader") says; never a panic, an abort (a stack overflow) or a hang. The files are made
//! here from a generated population and the committed Blender / USD fixtures.
#![cfg(not(target_arch = "wasm32"))]

#[macro_use]
#[allow(unused_macros)]
mod common;

use common::glb::{container, join, split};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a case must get.
enum Expect {
    /// Exit 1 with these words in the message (the file's name among them).
    Refused(&'static [&'static str]),
    /// A fit.
    Read,
}

/// `posemfa fit DIR`, killed after two minutes: (exit code, stdout, stderr); None when killed by a signal.
fn fit(dir: &Path) -> (Option<i32>, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_posemfa"))
        .arg("fit")
        .arg(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("posemfa runs");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("posemfa fit {} hung (killed after 120 s)", dir.display());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("output");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn fixture(rel: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(rel)).expect("fixture")
}

/// A generated snake's poses as OBJ text, in order.
fn snake(dir: &Path) -> Vec<(String, String)> {
    let d = dir.join("snake");
    let out = Command::new(env!("CARGO_BIN_EXE_posemfa"))
        .args(["generate", "snake", "--vertices", "300", "--poses", "4", "--out"])
        .arg(&d)
        .output()
        .expect("generate");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    (1..=4)
        .map(|i| {
            let n = format!("pose0{i}.obj");
            let t = std::fs::read_to_string(d.join(&n)).unwrap();
            (n, t)
        })
        .collect()
}

fn vertices(obj: &str) -> Vec<[f32; 3]> {
    obj.lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| {
            let c: Vec<f32> = l.split_whitespace().skip(1).map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect()
}

fn faces(obj: &str) -> Vec<[usize; 3]> {
    obj.lines()
        .filter(|l| l.starts_with("f "))
        .map(|l| {
            let c: Vec<usize> = l.split_whitespace().skip(1).map(|x| x.parse().unwrap()).collect();
            [c[0] - 1, c[1] - 1, c[2] - 1]
        })
        .collect()
}

/// Line `k` (0-based among the `v` lines) with its first coordinate replaced.
fn with_x(obj: &str, k: usize, x: &str) -> String {
    let mut seen = 0;
    obj.lines()
        .map(|l| {
            if l.starts_with("v ") {
                seen += 1;
                if seen == k + 1 {
                    let rest: Vec<&str> = l.split_whitespace().skip(2).collect();
                    return format!("v {x} {}", rest.join(" "));
                }
            }
            l.to_string()
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// The OBJ without its last vertex and the triangles that use it.
fn without_last_vertex(obj: &str) -> String {
    let n = vertices(obj).len();
    let mut seen = 0;
    let mut out = String::new();
    for l in obj.lines() {
        if l.starts_with("v ") {
            seen += 1;
            if seen == n {
                continue;
            }
        }
        if l.starts_with("f ") && l.split_whitespace().skip(1).any(|x| x == n.to_string()) {
            continue;
        }
        out += l;
        out += "\n";
    }
    out
}

/// An ASCII PLY of an OBJ's mesh; `count` overrides the vertex count in the header; `x0` the first x.
fn ply(obj: &str, count: Option<u64>, x0: Option<&str>) -> String {
    let (v, f) = (vertices(obj), faces(obj));
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        count.unwrap_or(v.len() as u64),
        f.len()
    );
    for (i, p) in v.iter().enumerate() {
        let x = if i == 0 { x0.map(String::from) } else { None }.unwrap_or(p[0].to_string());
        s += &format!("{x} {} {}\n", p[1], p[2]);
    }
    for t in &f {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    s
}

fn pc2(frames: &[Vec<[f32; 3]>], count: Option<i32>) -> Vec<u8> {
    let mut b = b"POINTCACHE2\0".to_vec();
    b.extend(1i32.to_le_bytes());
    b.extend(count.unwrap_or(frames[0].len() as i32).to_le_bytes());
    b.extend(0f32.to_le_bytes());
    b.extend(1f32.to_le_bytes());
    b.extend((frames.len() as i32).to_le_bytes());
    for p in frames.iter().flatten() {
        p.iter().for_each(|c| b.extend(c.to_le_bytes()));
    }
    b
}

/// A .glb of `doc` with `more` written in place of its JSON text's closing brace (text a JSON value could not
/// hold without recursing as deep as it nests).
fn glb_with_text(doc: &Value, bin: &[u8], more: &str) -> Vec<u8> {
    let text = serde_json::to_string(doc).unwrap();
    container(format!("{}{more}", text.strip_suffix('}').unwrap()).into_bytes(), bin.to_vec())
}

/// The Blender glb with its first POSITION's y of vertex 5 set to `y`.
fn glb_with_y(y: f32) -> Vec<u8> {
    let (doc, mut bin) = split(&fixture("blender/quadruped-shapekeys.glb"));
    let pos = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize;
    let a = &doc["accessors"][pos];
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let at = v["byteOffset"].as_u64().unwrap_or(0) as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    bin[at + 12 * 5 + 4..at + 12 * 5 + 8].copy_from_slice(&y.to_le_bytes());
    join(doc, bin)
}

/// A binary FBX 7.4 of `depth` nodes named N, each the only child of the one before.
fn fbx_nested(depth: usize) -> Vec<u8> {
    let mut b = b"Kaydara FBX Binary  \x00\x1a\x00".to_vec();
    b.extend(7400u32.to_le_bytes());
    let header = 13 + 1;
    let start = |i: usize| 27 + i * header;
    // the innermost node ends after its header; every other after its child's end and its list's null record
    let mut ends = vec![0usize; depth];
    ends[depth - 1] = start(depth - 1) + header;
    for i in (0..depth - 1).rev() {
        ends[i] = ends[i + 1] + 13;
    }
    for end in ends {
        b.extend((end as u32).to_le_bytes());
        b.extend([0u8; 8]);
        b.extend([1u8, b'N']);
    }
    b.extend(std::iter::repeat(0u8).take(13 * depth + 160));
    b
}

fn usda_nested(depth: usize) -> String {
    let mut s = String::from("#usda 1.0\n");
    (0..depth).for_each(|i| s += &format!("def Xform \"a{i}\" {{\n"));
    (0..depth).for_each(|_| s += "}\n");
    s
}

#[test]
fn hostile_inputs_are_refused_by_name_or_read_never_a_crash() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hostile-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let objs = snake(&root);
    let obj_with = |i: usize, text: String| -> Vec<(String, Vec<u8>)> {
        objs.iter()
            .enumerate()
            .map(|(k, (n, t))| (n.clone(), if k == i { text.clone() } else { t.clone() }.into_bytes()))
            .collect()
    };
    let every_obj = |f: &dyn Fn(&str) -> String| -> Vec<(String, Vec<u8>)> {
        objs.iter().map(|(n, t)| (n.clone(), f(t).into_bytes())).collect()
    };
    let plys = |i: usize, text: String| -> Vec<(String, Vec<u8>)> {
        objs.iter()
            .enumerate()
            .map(|(k, (n, t))| {
                (n.replace(".obj", ".ply"), if k == i { text.clone() } else { ply(t, None, None) }.into_bytes())
            })
            .collect()
    };
    let second = &objs[1].1;
    let frames: Vec<Vec<[f32; 3]>> = objs.iter().map(|(_, t)| vertices(t)).collect();
    let mut nan_frames = frames.clone();
    nan_frames[2][7][1] = f32::NAN;
    let cache =
        |bytes: Vec<u8>| vec![("base.obj".to_string(), objs[0].1.clone().into_bytes()), ("anim.pc2".into(), bytes)];
    let usda = String::from_utf8(fixture("usd/arm-pointcache.usda")).unwrap();
    let at = usda.find("points.timeSamples").unwrap();
    let first = at + usda[at..].find("[(").unwrap() + 2;
    let number_end = first + usda[first..].find(',').unwrap();
    let usda_x = |x: &str| format!("{}{x}{}", &usda[..first], &usda[number_end..]);
    let glb = fixture("blender/quadruped-shapekeys.glb");
    let (doc, bin) = split(&glb);
    let pos = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize;
    let mut huge = doc.clone();
    huge["accessors"][pos]["count"] = json!(4_000_000_000u64);
    let mut deep = doc.clone();
    let n0 = deep["nodes"].as_array().unwrap().len();
    for i in 0..100_000 {
        let node = if i + 1 < 100_000 { json!({"children": [n0 + i + 1]}) } else { json!({}) };
        deep["nodes"].as_array_mut().unwrap().push(node);
    }
    deep["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(n0));
    let fbx = fixture("blender/quadruped-shapekeys.fbx");
    let one = |name: &str, bytes: Vec<u8>| vec![(name.to_string(), bytes)];

    let cases: Vec<(&str, Vec<(String, Vec<u8>)>, Expect)> = vec![
        (
            "OBJ cut in half",
            obj_with(1, second[..second.len() / 2].to_string()),
            Expect::Refused(&["pose02.obj", "cut short"]),
        ),
        (
            "OBJ x = nan",
            obj_with(1, with_x(second, 5, "nan")),
            Expect::Refused(&["pose02.obj", "line", "not a finite number"]),
        ),
        (
            "OBJ x = inf",
            obj_with(1, with_x(second, 5, "inf")),
            Expect::Refused(&["pose02.obj", "line", "not a finite number"]),
        ),
        (
            "OBJ x = 1e400",
            obj_with(1, with_x(second, 5, "1e400")),
            Expect::Refused(&["pose02.obj", "line", "overflows"]),
        ),
        (
            "OBJ face index 4e9",
            obj_with(1, format!("{second}f 4000000000 1 2\n")),
            Expect::Refused(&["pose02.obj", "out of range"]),
        ),
        (
            "OBJ poses of different vertex counts",
            obj_with(1, without_last_vertex(second)),
            Expect::Refused(&["pose02.obj", "pose01.obj"]),
        ),
        ("OBJ a triangle with a repeated vertex", every_obj(&|t| format!("{t}f 1 1 2\n")), Expect::Read),
        ("OBJ an edge of three triangles", every_obj(&|t| format!("{t}f 1 2 3\n")), Expect::Read),
        (
            "PLY cut in half",
            plys(1, {
                let p = ply(second, None, None);
                p[..p.len() / 2].to_string()
            }),
            Expect::Refused(&["pose02.ply", "cut"]),
        ),
        (
            "PLY 4e9 vertices in the header",
            plys(1, ply(second, Some(4_000_000_000), None)),
            Expect::Refused(&["pose02.ply", "4000000000"]),
        ),
        (
            "PLY x = nan",
            plys(1, ply(second, None, Some("nan"))),
            Expect::Refused(&["pose02.ply", "not a finite number"]),
        ),
        ("pc2 cut", cache(pc2(&frames, None)[..200].to_vec()), Expect::Refused(&["anim.pc2", "cut"])),
        (
            "pc2 2^31 - 1 vertices in the header",
            cache(pc2(&frames, Some(i32::MAX))),
            Expect::Refused(&["anim.pc2", "2147483647"]),
        ),
        ("pc2 a NaN coordinate", cache(pc2(&nan_frames, None)), Expect::Refused(&["anim.pc2", "non-finite"])),
        ("glb cut in half", one("a.glb", glb[..glb.len() / 2].to_vec()), Expect::Refused(&["a.glb", "cut"])),
        (
            "glb POSITION count 4e9",
            one("a.glb", join(huge, bin.clone())),
            Expect::Refused(&["a.glb", "4000000000", "past the end"]),
        ),
        (
            "glb a NaN coordinate",
            one("a.glb", glb_with_y(f32::NAN)),
            Expect::Refused(&["a.glb", "not a finite number"]),
        ),
        (
            "glb an infinite coordinate",
            one("a.glb", glb_with_y(f32::INFINITY)),
            Expect::Refused(&["a.glb", "not a finite number"]),
        ),
        ("glb a chain of 100 000 nodes", one("a.glb", join(deep, bin.clone())), Expect::Read),
        (
            "glb extras nested 100 000 deep",
            one(
                "a.glb",
                glb_with_text(&doc, &bin, &format!(",\"extras\":{}{}}}", "[".repeat(100_000), "]".repeat(100_000))),
            ),
            Expect::Read,
        ),
        ("FBX cut in half", one("a.fbx", fbx[..fbx.len() / 2].to_vec()), Expect::Refused(&["a.fbx", "cut"])),
        (
            "FBX nodes nested 100 000 deep",
            one("a.fbx", fbx_nested(100_000)),
            Expect::Refused(&["a.fbx", "deeper than 64"]),
        ),
        (
            "USDA cut in half",
            one("a.usda", usda[..usda.len() / 2].as_bytes().to_vec()),
            Expect::Refused(&["a.usda", "cut"]),
        ),
        ("USDA x = nan", one("a.usda", usda_x("nan").into_bytes()), Expect::Refused(&["a.usda", "not finite"])),
        ("USDA x = inf", one("a.usda", usda_x("inf").into_bytes()), Expect::Refused(&["a.usda", "not finite"])),
        (
            "USDA prims nested 100 000 deep",
            one("a.usda", usda_nested(100_000).into_bytes()),
            Expect::Refused(&["a.usda", "deeper than 128"]),
        ),
    ];
    let mut failures = Vec::new();
    for (i, (what, files, expect)) in cases.iter().enumerate() {
        let dir: PathBuf = root.join(format!("case{i:02}"));
        std::fs::create_dir_all(&dir).unwrap();
        for (n, b) in files {
            std::fs::write(dir.join(n), b).unwrap();
        }
        let (code, out, err) = fit(&dir);
        let got = match expect {
            Expect::Refused(words) => {
                code == Some(1) && !err.contains("panicked") && words.iter().all(|w| err.contains(w))
            }
            Expect::Read => code == Some(0) && out.contains("RMSE"),
        };
        if !got {
            failures.push(format!("{what}: exit {code:?}\n  stdout: {}\n  stderr: {}", out.trim(), err.trim()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&root);
}
