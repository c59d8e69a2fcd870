//! `posemfa rig-report --truth CHARACTER.glb`: the rig's skeleton against the skeleton of a rigged, animated
//! character read from the same file (`articulate::skeleton_match`), and the refusals of a truth that is not
//! the poses' own.
#![cfg(not(target_arch = "wasm32"))]

use std::process::{Command, Output};

fn posemfa(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_posemfa")).args(args).output().expect("the posemfa binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/blender/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The skinned quadruped is posemfa's own rig of a generated population (13 parts as bones, one clip) passed
/// through Blender: its skeleton is the generator's parts, so a fit of its clip must find them again.
#[test]
fn a_rig_of_the_clip_finds_the_skeleton_that_made_it() {
    let f = fixture("quadruped-skinned-seams.glb");
    let r = posemfa(&["rig-report", &f, "--truth", &f, "--weights", "fitted"]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let v: serde_json::Value = serde_json::from_str(&text(&r.stdout)).expect("rig-report prints JSON");
    let s = &v["skeleton"];
    assert_eq!(s["artist_joints"], 13);
    // every non-root bone of the generated quadruped turns more than 10 degrees in its clip
    assert_eq!(s["moving_joints"], 12);
    assert_eq!(s["artist"].as_array().unwrap().len(), 13);
    assert_eq!(s["artist_to_fitted"]["joints"].as_array().unwrap().len(), 12);
    let fitted = s["fitted_joints"].as_u64().unwrap() as usize;
    assert_eq!(fitted + 1, v["bones"].as_u64().unwrap() as usize, "every fitted joint but the root");
    assert_eq!(s["fitted_to_artist"]["joints"].as_array().unwrap().len(), fitted);
    let median = s["artist_to_fitted"]["median"].as_f64().unwrap();
    let back = s["fitted_to_artist"]["median"].as_f64().unwrap();
    assert!(median < 0.01 && back < 0.01, "joints a median {median} / {back} of the diagonal away");
    for side in ["artist_to_fitted", "fitted_to_artist"] {
        let d = &s[side];
        let (m, x, any) =
            (d["median"].as_f64().unwrap(), d["max"].as_f64().unwrap(), d["max_any_pose"].as_f64().unwrap());
        assert!(0.0 <= m && m <= x && x <= any && any < 1.0, "{side}: {m} {x} {any}");
    }
    assert!(s["parts_ari"].as_f64().unwrap() > 0.9, "{}", s["parts_ari"]);
    assert_eq!(s["root"]["on_central_part"], true, "{}", s["root"]);
    assert!(s["parents"]["share"].as_f64().unwrap() >= 0.5, "{}", s["parents"]);
    assert!(v["timings_ms"]["skeleton"].as_f64().is_some());
}

#[test]
fn a_truth_that_is_not_the_poses_own_skinned_clip_is_refused_by_name() {
    let skinned = fixture("quadruped-skinned-seams.glb");
    let morphs = fixture("quadruped-shapekeys.glb");
    // morph targets, no skin
    let r = posemfa(&["rig-report", &morphs, "--truth", &morphs]);
    let e = text(&r.stderr);
    assert!(
        !r.status.success() && e.contains("quadruped-shapekeys.glb") && e.contains("not a skin's animation"),
        "{e}"
    );
    // another character's clip
    let r = posemfa(&["rig-report", &morphs, "--truth", &skinned]);
    let e = text(&r.stderr);
    assert!(!r.status.success() && e.contains("quadruped-skinned-seams.glb") && e.contains("poses of"), "{e}");
    // the same clip sampled differently
    let r = posemfa(&["rig-report", &skinned, "--frames", "30", "--truth", &skinned]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    // a file that is not there
    let r = posemfa(&["rig-report", &skinned, "--truth", "/nonexistent/c.glb"]);
    let e = text(&r.stderr);
    assert!(!r.status.success() && e.contains("cannot read --truth /nonexistent/c.glb"), "{e}");
    // a rig read from a file has no fit to compare
    let r = posemfa(&["rig-report", &skinned, "--glb", &skinned, "--truth", &skinned]);
    assert!(!r.status.success() && text(&r.stderr).contains("--truth"), "{}", text(&r.stderr));
}
