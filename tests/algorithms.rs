//! The algorithm tests on generated articulated chains with known parts and rotations. Each test is
//! written once and runs natively (`cargo test`) AND in wasm (Node and headless Chromium, see
//! scripts/test.sh).
//!
//! The chain fixture: P rigid tube segments end to end along x; every pose bends every joint by a random
//! rotation (up to ~70 degrees), segments follow by forward kinematics; Gaussian noise on every coordinate.

#[macro_use]
mod common;

use posemfa::geometry::rotation::{angle_between, axis_angle};
use posemfa::geometry::{add, det, mat_mul, mat_vec, orthonormality_error, sub, transpose, Mat3, Vec3};
use posemfa::mesh::Population;
use posemfa::metrics::adjusted_rand_index;
use posemfa::mfa::aecm::Fit;
use posemfa::mfa::data::Data;
use posemfa::mfa::estep::{e_step, e_step_pruned};
use posemfa::mfa::{LambdaRule, Params};
use posemfa::parts::hierarchy::Pipeline;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

struct Chain {
    pop: Population,
    part_of: Vec<u32>,
    /// rotations[pose][part]: world rotation of each segment.
    rotations: Vec<Vec<Mat3>>,
}

fn gauss(rng: &mut Pcg64) -> f64 {
    // Box-Muller
    let u: f64 = rng.gen::<f64>().max(1e-300);
    let v: f64 = rng.gen();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// `parts` segments of `rings` x `around` vertices each, `poses` poses, noise σ in unit-box units.
fn chain(parts: usize, poses: usize, noise: f64, seed: u64) -> Chain {
    let (rings, around) = (6usize, 8usize);
    let seg_len = 0.25;
    let radius = 0.04;
    let mut rest = Vec::new();
    let mut part_of = Vec::new();
    for p in 0..parts {
        for r in 0..rings {
            // keep the segment's rings off the joints so that parts are rigid pieces
            let x = p as f64 * seg_len + seg_len * (0.1 + 0.8 * r as f64 / (rings - 1) as f64);
            for a in 0..around {
                let t = std::f64::consts::TAU * a as f64 / around as f64;
                // slightly elliptic and varying radius: no symmetric ambiguity of the rigid fit
                let rad = radius * (1.0 + 0.3 * (r as f64 / rings as f64));
                rest.push([x, rad * t.cos(), 0.6 * rad * t.sin()]);
                part_of.push(p as u32);
            }
        }
    }
    let mut faces = Vec::new();
    for p in 0..parts {
        for r in 0..rings - 1 {
            for a in 0..around {
                let v = |rr: usize, aa: usize| (p * rings * around + rr * around + aa % around) as u32;
                faces.push([v(r, a), v(r + 1, a), v(r + 1, a + 1)]);
                faces.push([v(r, a), v(r + 1, a + 1), v(r, a + 1)]);
            }
        }
    }
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut shapes = Vec::new();
    let mut rotations = Vec::new();
    for _ in 0..poses {
        let mut rots: Vec<Mat3> = Vec::new();
        let mut origins: Vec<Vec3> = Vec::new();
        for p in 0..parts {
            let local = axis_angle([gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)], rng.gen_range(-1.2..1.2));
            let (r, o) = if p == 0 {
                (local, [0.0, 0.0, 0.0])
            } else {
                let prev = rots[p - 1];
                let joint = add(origins[p - 1], mat_vec(&prev, [seg_len, 0.0, 0.0]));
                (mat_mul(&prev, &local), joint)
            };
            rots.push(r);
            origins.push(o);
        }
        let shape: Vec<Vec3> = rest
            .iter()
            .zip(&part_of)
            .map(|(&q, &p)| {
                let p = p as usize;
                let local = sub(q, [p as f64 * seg_len, 0.0, 0.0]);
                let w = add(origins[p], mat_vec(&rots[p], local));
                [w[0] + noise * gauss(&mut rng), w[1] + noise * gauss(&mut rng), w[2] + noise * gauss(&mut rng)]
            })
            .collect();
        shapes.push(shape);
        rotations.push(rots);
    }
    let names = (0..poses).map(|i| format!("pose{i:02}.obj")).collect();
    Chain {
        pop: Population::new(posemfa::mesh::Sources::UnitShapes { names, faces, shapes }).expect("valid chain"),
        part_of,
        rotations,
    }
}

/// Worst angle (degrees) between fitted and true RELATIVE rotations R^i (R^0)^T, each fitted part matched
/// to the true part holding most of its vertices (the latent frame of a fitted part is arbitrary).
fn worst_rotation_error(c: &Chain, labels: &[u32], parts: &[posemfa::mfa::Component]) -> f64 {
    let n_true = c.rotations[0].len();
    let mut worst: f64 = 0.0;
    for (k, comp) in parts.iter().enumerate() {
        let mut votes = vec![0usize; n_true];
        for (l, t) in labels.iter().zip(&c.part_of) {
            if *l as usize == k {
                votes[*t as usize] += 1;
            }
        }
        let t = (0..n_true).max_by_key(|&p| votes[p]).unwrap_or(0);
        for i in 1..c.rotations.len() {
            let fit_rel = mat_mul(&comp.rotations[i], &transpose(&comp.rotations[0]));
            let true_rel = mat_mul(&c.rotations[i][t], &transpose(&c.rotations[0][t]));
            worst = worst.max(angle_between(&fit_rel, &true_rel).to_degrees());
        }
    }
    worst
}

fn assert_never_decreases(trace: &[f64], what: &str) {
    for w in trace.windows(2) {
        assert!(w[1] >= w[0] - 1e-9 * w[0].abs(), "{what}: log-likelihood dropped from {} to {}", w[0], w[1]);
    }
}

dual_test! {
    fn recovers_parts_and_rotations_of_chains_from_3_to_10_parts() {
        for (parts, seed) in [(3usize, 1u64), (5, 2), (7, 3), (10, 4)] {
            let c = chain(parts, 6, 2e-4, seed);
            // Algorithm 1 as the paper uses it: a small initial m, the refinement finds the rest.
            let params = Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: parts.div_ceil(2), ..Default::default() }, seed, ..Params::default() };
            let result = Pipeline::new(&c.pop, &params).unwrap().run(&mut |_| true).unwrap();
            let m = &result.model;
            let ari = adjusted_rand_index(&m.labels, &c.part_of);
            assert!(ari >= 0.98, "{parts} parts: adjusted Rand {ari} (found {} parts)", m.n_parts());
            let err = worst_rotation_error(&c, &m.labels, &m.parts);
            assert!(err <= 1.0, "{parts} parts: rotation error {err} degrees");
            for comp in &m.parts {
                for r in &comp.rotations {
                    assert!((det(r) - 1.0).abs() < 1e-9 && orthonormality_error(r) < 1e-9);
                }
            }
            assert!(m.rmse(&c.pop) < 2e-3, "rmse {}", m.rmse(&c.pop));
        }
    }

    fn log_likelihood_never_decreases_across_single_steps() {
        for (parts, seed) in [(3usize, 11u64), (6, 12)] {
            let c = chain(parts, 5, 1e-3, seed);
            // more components than parts, from k-means: the hard case for monotonicity
            let params = Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: parts + 2, ..Default::default() }, seed, tol: 1e-12, ..Params::default() };
            let mut fit = Fit::new(Data::from_population(&c.pop), &params).unwrap();
            let mut trace = vec![fit.initial_log_likelihood()];
            for _ in 0..40 {
                let info = fit.step();
                trace.push(info.log_likelihood);
                if fit.is_finished() {
                    break;
                }
            }
            assert!(trace.len() > 5);
            assert_never_decreases(&trace, &format!("{parts}-part chain"));
        }
    }

    fn neither_does_it_with_or_without_the_parameter_expanded_step_or_the_acceleration_over_many_seeds() {
        // PX-EM (Params::px_em) only re-parametrises after a proper CM step, and SQUAREM (Params::accelerate)
        // keeps an extrapolated state only when its log-likelihood is at least the plain step's; over many
        // starts, no iteration that removes no component may lower the log-likelihood, with either on or off
        for (px_em, accelerate) in [(true, true), (true, false), (false, true), (false, false)] {
            let mut kept = 0;
            for seed in 0..20u64 {
                for parts in [3usize, 6] {
                    let c = chain(parts, 5, 1e-3, seed);
                    let params = Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: parts + 2, ..Default::default() }, seed, tol: 1e-12, px_em, accelerate, ..Params::default() };
                    let mut fit = Fit::new(Data::from_population(&c.pop), &params).unwrap();
                    let mut prev = fit.initial_log_likelihood();
                    for _ in 0..40 {
                        let info = fit.step();
                        if info.dropped == 0 {
                            let ll = info.log_likelihood;
                            assert!(
                                ll >= prev - 1e-9 * prev.abs(),
                                "px_em={px_em} accelerate={accelerate} seed={seed} parts={parts} it={}: {prev} -> {ll}",
                                info.iteration
                            );
                        }
                        prev = info.log_likelihood;
                        if fit.is_finished() {
                            break;
                        }
                    }
                    kept += fit.extrapolations_kept;
                    if !accelerate {
                        assert_eq!(fit.extrapolations_tried, 0);
                    }
                }
            }
            // the accelerated runs did take extrapolated steps (else this would only test the plain step again)
            if accelerate {
                assert!(kept >= 20, "px_em={px_em}: only {kept} extrapolations kept over 40 runs");
            }
        }
    }

    fn the_pipeline_trace_never_decreases_either() {
        let c = chain(4, 6, 5e-4, 21);
        let mut pipe = Pipeline::new(&c.pop, &Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 3, ..Default::default() }, ..Params::default() }).unwrap();
        // (an iteration that drops a component, whose mass fell below `min_part_vertices`, is another model: it
        // may lower the likelihood)
        let mut last: Option<(String, usize, f64)> = None;
        let mut compared = 0;
        while !pipe.is_done() {
            let p = pipe.step().unwrap();
            let run = format!("{:?}", p.stage);
            if let Some((r, parts, ll)) = &last {
                if *r == run && p.iteration > 1 && *parts == p.parts {
                    assert!(p.log_likelihood >= ll - 1e-9 * ll.abs(), "{run}: {ll} -> {}", p.log_likelihood);
                    compared += 1;
                }
            }
            last = Some((run, p.parts, p.log_likelihood));
        }
        assert!(compared >= 3, "only {compared} iterations compared");
    }

    fn a_lesson_steps_through_algorithm_1_whatever_the_part_rule() {
        use posemfa::parts::hierarchy::{FinalRun, Rule, Stage};
        let c = chain(4, 6, 5e-4, 21);
        // the default part rule (the merge tree) starts at the final AECM from its own partition, and says so
        let tree = Pipeline::new(&c.pop, &Params::default()).unwrap();
        assert!(
            matches!(tree.stage(), Stage::Final { rule: Rule::MergeTree, run: FinalRun::First, number: 1, .. }),
            "{:?}",
            tree.stage()
        );
        assert!(tree.result().from_merge_tree());
        let coarse_only = Pipeline::new(&c.pop, &Params { refine: false, ..Params::default() }).unwrap();
        assert!(!coarse_only.result().from_merge_tree());
        let mut lesson = Pipeline::for_teaching(
            &c.pop,
            &Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 3, ..Default::default() }, ..Params::default() },
            &posemfa::mfa::FitStart::default(),
        ).unwrap();
        assert_eq!(lesson.stage(), Stage::Coarse);
        let mut refined = false;
        while !lesson.is_done() {
            refined |= matches!(lesson.step().unwrap().stage, Stage::Refine { .. });
        }
        assert!(refined, "a lesson shows the refinement");
        assert_eq!(lesson.result().model.n_parts(), 4);
        assert!(!lesson.result().from_merge_tree());
    }

    fn pruned_e_step_equals_the_plain_one() {
        let c = chain(5, 5, 1e-3, 31);
        let data = Data::from_population(&c.pop);
        let mut fit = Fit::new(data.clone(), &Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 5, ..Default::default() }, seed: 3, ..Params::default() }).unwrap();
        for _ in 0..3 {
            fit.step();
        }
        let comps = fit.components().to_vec();
        let mut g_plain = Vec::new();
        let ll_plain = e_step(&data, &comps, &mut g_plain);
        // without a hint (first E-step) and with the previous responsibilities as the hint
        for mut g in [Vec::new(), fit.responsibilities().to_vec()] {
            let (ll, evals) = e_step_pruned(&data, &comps, &mut g);
            assert!(evals < data.n_vertices * comps.len() * data.n_shapes, "pruning skips work");
            assert!((ll - ll_plain).abs() <= 1e-12 * ll_plain.abs(), "{ll} vs {ll_plain}");
            for (a, b) in g.iter().zip(&g_plain) {
                assert!((a - b).abs() < 1e-14);
            }
        }
    }

    fn the_literal_eq18_option_runs_and_returns_its_best_state() {
        let c = chain(4, 6, 5e-4, 41);
        let params = Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 4, ..Default::default() }, seed: 1, lambda_rule: LambdaRule::PaperEq18, max_iter: 40, ..Params::default() };
        let mut fit = Fit::new(Data::from_population(&c.pop), &params).unwrap();
        fit.run(&mut |_| true);
        let trace = fit.trace().to_vec();
        assert!(!trace.is_empty() && trace.iter().all(|v| v.is_finite()));
        let model = fit.model();
        for comp in &model.parts {
            for r in &comp.rotations {
                assert!((det(r) - 1.0).abs() < 1e-9);
            }
        }
        // The model handed back is the best state seen (eq 18 can lower the likelihood): its log-likelihood,
        // recomputed here directly from the population, is the trace's maximum.
        let best18 = trace.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let mut ll_model = 0.0;
        for j in 0..c.pop.n_vertices() {
            let h: Vec<Vec3> = c.pop.unit_shapes().iter().map(|s| s[j]).collect();
            let logs: Vec<f64> = model.parts.iter().map(|p| p.log_weighted_density(&p.woodbury(), &h)).collect();
            let mx = logs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            ll_model += mx + logs.iter().map(|l| (l - mx).exp()).sum::<f64>().ln();
        }
        assert!((ll_model - best18).abs() <= 1e-8 * best18.abs(), "model {ll_model} vs best of trace {best18}");
    }

    fn reconstruction_equals_eq22_and_rmse_matches() {
        let c = chain(3, 5, 1e-3, 51);
        let result = Pipeline::new(&c.pop, &Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 3, ..Default::default() }, ..Params::default() }).unwrap().run(&mut |_| true).unwrap();
        let m = &result.model;
        let mut s = 0.0;
        for i in 0..c.pop.n_shapes() {
            for j in 0..c.pop.n_vertices() {
                let k = m.labels[j] as usize;
                let r = &m.parts[k].rotations[i];
                let q = add(mat_vec(r, m.latent[j]), m.parts[k].translations[i]);
                let d = sub(c.pop.unit_shapes()[i][j], q);
                s += d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            }
        }
        let rmse = (s / (c.pop.n_shapes() * c.pop.n_vertices()) as f64).sqrt();
        assert!((rmse - m.rmse(&c.pop)).abs() < 1e-12);
        // noise σ = 1e-3 per coordinate in unit-box units before normalisation: the fit cannot beat the noise
        // by much, and a rigid chain must be explained down to it.
        assert!(rmse < 4e-3, "{rmse}");
    }
}
