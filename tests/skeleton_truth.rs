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
    // (the fixture's joints are posemfa's own nodes of the time, at the contact centroids; the rig's nodes are
    // now at the pivots, about 1 % away: issue 59's bar, 1.5 %)
    assert!(median < 0.015 && back < 0.015, "joints a median {median} / {back} of the diagonal away");
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

/// The real characters of `scripts/fixtures/rigged-characters.sh` (Debian's assimp-testmodels, fetched at test
/// time, never committed): skipped with a message when they have not been fetched.
#[test]
fn real_characters_when_fetched() {
    let dir = std::env::var("POSEMFA_CHARACTERS")
        .unwrap_or_else(|_| format!("{}/target/rigged-characters", env!("CARGO_MANIFEST_DIR")));
    let bcn = format!("{dir}/bcn_epileptic.glb");
    let wuson = format!("{dir}/wuson.glb");
    if !std::path::Path::new(&bcn).exists() || !std::path::Path::new(&wuson).exists() {
        eprintln!("skipped: no rigged characters in {dir}; run scripts/fixtures/rigged-characters.sh to fetch them");
        return;
    }
    let report = |f: &str, more: &[&str]| -> serde_json::Value {
        let mut args = vec!["rig-report", f, "--truth", f, "--weights", "fitted"];
        args.extend_from_slice(more);
        let r = posemfa(&args);
        assert!(r.status.success(), "{f}: {}", text(&r.stderr));
        serde_json::from_str(&text(&r.stdout)).expect("rig-report prints JSON")
    };
    // the dancing man: 54 joints, of which 16 hold vertices and turn at least 10 degrees against their parent
    let v = report(&bcn, &[]);
    let s = &v["skeleton"];
    assert_eq!((s["artist_joints"].as_u64(), s["moving_joints"].as_u64()), (Some(54), Some(16)), "{s}");
    assert_eq!(s["root"]["central_part"], "B_Root_Pelvis_L");
    // as measured when the table in docs/rig.md was made (0.83 % and 0.969): a regression guard
    assert!(s["artist_to_fitted"]["median"].as_f64().unwrap() < 0.015, "{}", s["artist_to_fitted"]["median"]);
    assert!(s["parts_ari"].as_f64().unwrap() > 0.9, "{}", s["parts_ari"]);
    // Wuson's two roots: the back spine is measured against the front one
    let v = report(&wuson, &["--animation", "Wuson_Walk"]);
    let s = &v["skeleton"];
    assert_eq!((s["artist_joints"].as_u64(), s["moving_joints"].as_u64()), (Some(37), Some(26)), "{s}");
    let back = s["artist"].as_array().unwrap().iter().find(|j| j["name"] == "Spine_Back01").unwrap();
    assert_eq!(back["parent"], serde_json::Value::Null);
    assert_eq!(back["part"], "Spine_Front01", "{back}");
}

/// Issue 59's joint bars on the real characters of `scripts/fixtures/rigged-characters.sh` where docs/rig.md's
/// table says they are met: the man meets all (median at most 1.5 %, largest at most 5 % of the diagonal, both
/// ways, the root on his pelvis); Mr. Fixit (assimp-testmodels' IQM folder) the medians, the converse's largest
/// against every artist joint that holds vertices, and the root on his hips; the Minetest player (minetest-data)
/// its root on the body, its parts, the parents of four of its five moving joints and the joint bars. Skipped with a message when the characters have not been fetched.
#[test]
fn joints_where_the_artist_put_them_when_fetched() {
    let dir = std::env::var("POSEMFA_CHARACTERS")
        .unwrap_or_else(|_| format!("{}/target/rigged-characters", env!("CARGO_MANIFEST_DIR")));
    let [bcn, fixit, minetest] =
        ["bcn_epileptic.glb", "mrfixit.glb", "minetest_character.glb"].map(|f| format!("{dir}/{f}"));
    if let Some(f) = [&bcn, &fixit, &minetest].into_iter().find(|f| !std::path::Path::new(f).exists()) {
        eprintln!("skipped: no {f}; run scripts/fixtures/rigged-characters.sh to fetch the characters");
        return;
    }
    let skeleton = |f: &str| -> serde_json::Value {
        let r = posemfa(&["rig-report", f, "--truth", f, "--weights", "fitted"]);
        assert!(r.status.success(), "{f}: {}", text(&r.stderr));
        let v: serde_json::Value = serde_json::from_str(&text(&r.stdout)).expect("rig-report prints JSON");
        v["skeleton"].clone()
    };
    let g = |s: &serde_json::Value, side: &str, k: &str| s[side][k].as_f64().unwrap_or(f64::NAN);
    let s = skeleton(&bcn);
    let (am, ax) = (g(&s, "artist_to_fitted", "median"), g(&s, "artist_to_fitted", "max"));
    let (fm, fx) = (g(&s, "fitted_to_artist", "median"), g(&s, "fitted_to_artist", "max"));
    assert!(am <= 0.015 && fm <= 0.015 && ax <= 0.05 && fx <= 0.05, "the man: {am} / {ax}, {fm} / {fx}");
    assert_eq!(s["root"]["on_central_part"], true, "the man: {}", s["root"]);
    assert!(s["parts_ari"].as_f64().unwrap() >= 0.9, "{}", s["parts_ari"]);
    let s = skeleton(&fixit);
    let (am, fm) = (g(&s, "artist_to_fitted", "median"), g(&s, "fitted_to_artist", "median"));
    let fx = g(&s, "fitted_to_any_artist", "max");
    assert!(am <= 0.015 && fm <= 0.015 && fx <= 0.05, "Mr. Fixit: {am}, {fm}, any {fx}");
    assert!(g(&s, "fitted_to_any_artist", "median") <= fm, "more artist joints, no farther");
    assert_eq!(s["root"]["on_central_part"], true, "Mr. Fixit: {}", s["root"]);
    let s = skeleton(&minetest);
    assert_eq!(s["root"]["on_central_part"], true, "the Minetest player: {}", s["root"]);
    // its head, keyed to turn 10 degrees, reads 9.999997 from the file's f32 rotations: it moves
    assert_eq!(s["moving_joints"].as_u64(), Some(5), "{s}");
    // six separate boxes, each a part, joined where they move least apart: every limb on the body but one leg,
    // which moves more like the other leg (the clip sits and lies with both legs together) than like the body
    assert!(s["parts_ari"].as_f64().unwrap() >= 0.99, "{}", s["parts_ari"]);
    assert!(s["parents"]["agreeing"].as_u64().unwrap() >= 4, "{}", s["parents"]);
    // the boxes touch face to face: each joint at the middle of the child along its hinge's axis, from the face
    let (am, ax) = (g(&s, "artist_to_fitted", "median"), g(&s, "artist_to_fitted", "max"));
    let (fm, fx) = (g(&s, "fitted_to_artist", "median"), g(&s, "fitted_to_artist", "max"));
    assert!(am <= 0.015 && fm <= 0.015 && ax <= 0.05 && fx <= 0.05, "the Minetest player: {am} / {ax}, {fm} / {fx}");
}

/// Red Eclipse's drone (redeclipse-data, every clip of the game in one): the medians both ways, the converse's
/// largest and the root on the abdomen meet issue 59's bars. Its two hands and its left toes are 11-12 % and 7 %
/// from the nearest fitted joint: the part rule merges each into its neighbour (scores 2.0-3.7, under the distinct
/// ratio 4: they turn 20-45° in 6-56 of the 134 frames); docs/rig.md. Skipped with a message when not fetched.
#[test]
fn the_drone_when_fetched() {
    let dir = std::env::var("POSEMFA_CHARACTERS")
        .unwrap_or_else(|_| format!("{}/target/rigged-characters", env!("CARGO_MANIFEST_DIR")));
    let drone = format!("{dir}/redeclipse_drone.glb");
    if !std::path::Path::new(&drone).exists() {
        eprintln!("skipped: no {drone}; run scripts/fixtures/rigged-characters.sh to fetch the characters");
        return;
    }
    let r = posemfa(&["rig-report", &drone, "--truth", &drone, "--weights", "fitted"]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let v: serde_json::Value = serde_json::from_str(&text(&r.stdout)).expect("rig-report prints JSON");
    let s = &v["skeleton"];
    let g = |side: &str, k: &str| s[side][k].as_f64().unwrap_or(f64::NAN);
    assert_eq!(s["moving_joints"].as_u64(), Some(16), "{s}");
    let (am, fm, fx) = (g("artist_to_fitted", "median"), g("fitted_to_artist", "median"), g("fitted_to_artist", "max"));
    assert!(am <= 0.015 && fm <= 0.015 && fx <= 0.05, "the drone: {am}, {fm} / {fx}");
    assert_eq!(s["root"]["on_central_part"], true, "the drone: {}", s["root"]);
}
