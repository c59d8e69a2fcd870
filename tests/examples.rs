//! The page's built-in examples do what their notes say (native and wasm).

#[macro_use]
mod common;

use posemfa::metrics::{adjusted_rand_index, ground_truth_accuracy, median, rotation_errors_deg};
use posemfa::parts::hierarchy::{fit, FitResult};
use posemfa::synth::presets::{example, examples};
use posemfa::synth::{generate, Generated};

fn run(id: &str) -> (Generated, FitResult) {
    let ex = example(id).expect("example exists");
    let g = generate(&ex.spec).unwrap();
    let r = fit(&g.population, &ex.params, &mut |_| true).unwrap();
    (g, r)
}

dual_test! {
    fn the_quadruped_is_recovered() {
        let (g, r) = run("quadruped");
        let m = &r.model;
        let ari = adjusted_rand_index(&m.labels, &g.part_of_vertex);
        let fitted: Vec<_> = m.parts.iter().map(|p| p.rotations.clone()).collect();
        let errs = rotation_errors_deg(&fitted, &m.labels, &g.rotations, &g.part_of_vertex).unwrap();
        let med = median(&errs);
        assert!(ari >= 0.95, "adjusted Rand {ari} with {} parts", m.n_parts());
        assert!(med <= 2.0, "median rotation error {med} degrees");
    }

    fn two_legs_that_always_move_together_get_one_motion_and_stay_apart_by_connectivity() {
        let (g, r) = run("too-few-poses");
        let tied = ground_truth_accuracy(&r.model, &g).unwrap().tied;
        let names: Vec<String> = tied.iter().map(|t| t.names.join(" / ")).collect();
        assert_eq!(
            names,
            ["front_left_upper / front_right_upper", "front_left_lower / front_right_lower", "front_left_foot / front_right_foot"]
        );
        for t in &tied {
            // two parts (the legs do not touch: islands.rs keeps every part one connected piece) whose motions
            // the data cannot tell apart, as the example's note says, while the legs do turn
            assert_ne!(t.fitted[0], t.fitted[1], "{:?}: the left and the right leg are one part", t.names);
            assert!(t.motion_gap_deg < 1.0, "{:?}: left and right move {} degrees apart", t.names, t.motion_gap_deg);
            assert!(t.turn_deg > 5.0, "{:?}: the tied legs turn only {} degrees", t.names, t.turn_deg);
        }
    }

    fn every_example_is_valid() {
        let all = examples();
        assert_eq!(all[0].id, "quadruped");
        for e in &all {
            e.spec.validate().unwrap();
            e.params.validate().unwrap();
            assert!(!e.note.is_empty() && e.note.len() < 260);
        }
    }
}
