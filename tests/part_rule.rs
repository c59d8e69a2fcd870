//! The default part rule (`parts::distinct`) against generated ground truth, at default parameters:
//! the right part count, the right parts (adjusted Rand index) and the right motions (rotation error), and the
//! diagnosis: every creature articulated, the blob not. Natively and in wasm. The wider table (3 k to 50 k
//! vertices, 10 and 20 poses, seeds 0-4) is `cargo run --release --example part_table`.

#[macro_use]
mod common;

use posemfa::metrics::ground_truth_accuracy;
use posemfa::mfa::Params;
use posemfa::parts::diagnosis::diagnose;
use posemfa::parts::hierarchy::fit;
use posemfa::synth::{generate, Preset, Spec};

/// (parts, ARI, worst rotation error, median rotation error, articulated) at default parameters.
fn run(preset: Preset, vertices: usize, poses: usize, seed: u64) -> (usize, f64, f64, f64, bool) {
    let g = generate(&Spec { preset, vertices, poses, seed, ..Spec::default() }).unwrap();
    let r = fit(&g.population, &Params { seed, ..Params::default() }, &mut |_| true).unwrap();
    let acc = ground_truth_accuracy(&r.model, &g).unwrap();
    let d = diagnose(&g.population, &r.model);
    (r.model.n_parts(), acc.ari, acc.rotation_error_deg_max, acc.rotation_error_deg, d.articulated)
}

dual_test! {
    fn creatures_get_their_parts_at_default_parameters() {
        for seed in 0..2 {
            for (preset, lo, hi) in [
                (Preset::Quadruped, 17, 19),
                (Preset::Arm, 3, 3),
                (Preset::Snake, 7, 9),
                (Preset::Spider, 17, 19),
                (Preset::Giraffe, 14, 16),
                (Preset::Hand, 15, 17),
            ] {
                let (parts, ari, worst, median, articulated) = run(preset, 3000, 10, seed);
                let what = format!("{preset:?} seed {seed}: {parts} parts, ARI {ari:.3}, rotation worst {worst:.2} median {median:.2}");
                assert!((lo..=hi).contains(&parts), "{what}");
                assert!(ari >= 0.97, "{what}");
                assert!(articulated, "{what}: diagnosed not articulated");
                // the rotation bar: every part within 5 degrees, the median within 1 (natively and in wasm, whose
                // fit agrees with the native one to rounding)
                if preset == Preset::Quadruped {
                    assert!(median <= 1.0, "{what}");
                    assert!(worst <= 5.0, "{what}");
                }
            }
        }
    }

    /// The record of the part rule's rounds adds up: the start's parts, its flesh dissolved, then round by round
    /// the parts judged, dissolved and merged, down to the fit's own count.
    fn the_part_rule_records_every_round() {
        for preset in [Preset::Quadruped, Preset::Spider] {
            let g = generate(&Spec { preset, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
            let r = fit(&g.population, &Params::default(), &mut |_| true).unwrap();
            let rounds = &r.part_rounds;
            assert!(!rounds.is_empty(), "{preset:?}: no round recorded");
            let start = r.start_parts().unwrap_or(r.stages.coarse_parts);
            assert!(start <= r.stages.coarse_parts, "{preset:?}: {start} parts after the start's flesh, cut {}", r.stages.coarse_parts);
            // a round judges at most what the AECM before it kept
            assert!(rounds[0].parts <= start, "{preset:?}: {rounds:?} from {start}");
            for (k, w) in rounds.iter().enumerate() {
                assert!(w.after + w.dissolved <= w.parts, "{preset:?} round {k}: {w:?}");
                if let Some(next) = rounds.get(k + 1) {
                    assert!(next.parts <= w.after, "{preset:?} round {k}: {w:?} then {next:?}");
                }
            }
            // the last round changed nothing, and its count is the fit's
            let last = rounds.last().unwrap();
            assert_eq!((last.dissolved, last.after), (0, last.parts), "{preset:?}: {rounds:?}");
            assert_eq!(last.after, r.model.n_parts(), "{preset:?}: {rounds:?}");
        }
    }

    fn the_blob_is_diagnosed_not_articulated() {
        for seed in 0..3 {
            let (parts, _, _, _, articulated) = run(Preset::Blob, 2000, 8, seed);
            assert!(!articulated, "blob seed {seed}: {parts} parts, diagnosed articulated");
        }
    }
}

#[test]
fn the_rule_does_not_depend_on_resolution_or_pose_count() {
    // the same creature at 4 x the vertices and 2 x the poses: the same parts
    for seed in 0..2 {
        let (parts, ari, worst, median, _) = run(Preset::Quadruped, 12000, 20, seed);
        let what = format!("seed {seed}: {parts} parts, ARI {ari:.3}, rotation worst {worst:.2} median {median:.2}");
        assert!((17..=19).contains(&parts) && ari >= 0.97 && median <= 1.0, "{what}");
    }
}

#[test]
fn the_parts_do_not_depend_on_how_the_poses_are_turned() {
    // Every fifth frame of horse-gallop (10 of its poses), and the same turned, scaled by 7.3 and shifted: the
    // same parts, vertex for vertex. The turn changes the poses' bounding box, which sets the unit box; while the
    // variance floor was a fixed number of unit-box units² the two gave 22 and 24 parts.
    let Some(dir) = common::shared_dir("data/horse-gallop", "the_parts_do_not_depend_on_how_the_poses_are_turned")
    else {
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "obj"))
        .collect();
    files.sort();
    let every_fifth: Vec<_> =
        files.iter().filter(|p| p.file_stem().is_some_and(|s| s != "reference")).step_by(5).collect();
    let pop = posemfa::mesh::Population::new(posemfa::mesh::Sources::paths(&every_fifth)).unwrap();
    let moved = posemfa::parts::robustness::Variant::Moved.apply(&pop).unwrap();
    let a = fit(&pop, &Params::default(), &mut |_| true).unwrap().model;
    let b = fit(&moved, &Params::default(), &mut |_| true).unwrap().model;
    assert_eq!((a.n_parts(), &a.labels), (b.n_parts(), &b.labels));
    let (ra, rb) = (
        pop.normalization.length_to_original(a.rmse(&pop)),
        moved.normalization.length_to_original(b.rmse(&moved)) / 7.3,
    );
    assert!((ra / rb - 1.0).abs() < 1e-3, "RMSE {ra} against {rb} (original units, the second over 7.3)");
}
