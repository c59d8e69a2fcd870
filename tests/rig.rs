//! The rig as exported, read back from the .glb bytes and played the way a glTF viewer plays it
//! ([`play_glb`]): fitted weights (at most K per vertex, non-negative, summing to 1, JOINTS_1 past 4) beat
//! rigid ones; with fixed joints every bone keeps its length over the clip; with residual morph targets the
//! clip reproduces every training pose within 1e-5 of the diagonal. On a generated quadruped (native and
//! wasm) and, natively, on horse-gallop when ../shared is present.

#[macro_use]
mod common;

use posemfa::articulate::rig::{build, Joints, RigOptions, RigWeights};
use posemfa::articulate::Articulation;
use posemfa::export::gltf::{play_glb, to_glb, GltfOptions, Morphs, Weights};
use posemfa::export::rig_report::{rig_error, RigError};
use posemfa::geometry::{norm, sub};
use posemfa::mesh::Population;
use posemfa::parts::hierarchy::fit;
use posemfa::synth::generate;
use posemfa::synth::presets::example;

fn quadruped() -> (Population, Articulation) {
    let (pop, model) = quadruped_fit();
    let art = Articulation::new(&model, &pop).unwrap();
    (pop, art)
}

fn quadruped_fit() -> (Population, posemfa::mfa::Model) {
    let ex = example("quadruped").unwrap();
    let spec = posemfa::synth::Spec { vertices: 1500, poses: 8, seed: 4, ..ex.spec };
    let pop = generate(&spec).unwrap().population;
    let r = fit(&pop, &ex.params, &mut |_| true).unwrap();
    (pop, r.model)
}

fn exported(
    pop: &Population,
    art: &Articulation,
    opts: &GltfOptions,
) -> (RigError, posemfa::export::gltf::GlbPlayback) {
    let glb = to_glb(art, opts).unwrap();
    let play = play_glb(&glb).unwrap();
    (rig_error(pop, &play, opts.rig_options().bind_pose).unwrap(), play)
}

/// Largest change of any bone's length (joint to parent joint) over the clip, relative to the diagonal.
fn bone_length_change(play: &posemfa::export::gltf::GlbPlayback, diagonal: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for (j, p) in play.joint_parent.iter().enumerate() {
        let Some(p) = *p else { continue };
        let lengths: Vec<f64> = play.joint_positions.iter().map(|f| norm(sub(f[j], f[p]))).collect();
        let (lo, hi) = lengths.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &l| (a.min(l), b.max(l)));
        worst = worst.max((hi - lo) / diagonal);
    }
    worst
}

dual_test! {
    fn fitted_weights_respect_their_limits_and_beat_rigid_ones() {
        let (pop, art) = quadruped();
        let (rigid, _) = exported(&pop, &art, &GltfOptions::default());
        let mut last = f64::INFINITY;
        for k in [1usize, 2, 4, 8] {
            let rig = build(&art, &RigOptions { weights: RigWeights::Fitted, influences: k, ..Default::default() }).unwrap();
            for v in 0..pop.n_vertices() {
                let inf: Vec<(usize, f64)> = rig.weights.influences(v).collect();
                assert!(!inf.is_empty() && inf.len() <= k, "vertex {v}: {} influences for K = {k}", inf.len());
                assert!(inf.iter().all(|x| x.1 > 0.0));
                assert!((inf.iter().map(|x| x.1).sum::<f64>() - 1.0).abs() < 1e-12);
            }
            // the alternation lowers the error (the smoothness term and the K cap may cost a little per step)
            for w in rig.trace.windows(2) {
                assert!(w[1] <= w[0] * 1.01, "K = {k}: trace {:?}", rig.trace);
            }
            assert!(rig.trace.last() <= rig.trace.first(), "K = {k}: trace {:?}", rig.trace);
            let opts = GltfOptions { weights: Weights::Fitted, influences: k, ..Default::default() };
            let glb = to_glb(&art, &opts).unwrap();
            let (root, _) = posemfa::export::gltf::parse_glb(&glb).unwrap();
            let attrs = &root.meshes[0].primitives[0].attributes;
            let has = |s| attrs.contains_key(&gltf_json::validation::Checked::Valid(s));
            assert!(has(gltf_json::mesh::Semantic::Joints(0)));
            assert_eq!(has(gltf_json::mesh::Semantic::Joints(1)), k > 4, "K = {k}");
            let play = play_glb(&glb).unwrap();
            let err = rig_error(&pop, &play, 0).unwrap();
            // the file plays what the solver fitted (f32 storage only)
            let mut sq = 0.0;
            for i in 0..pop.n_shapes() {
                for (p, q) in rig.pose(i).iter().zip(&pop.unit_shapes()[i]) {
                    let d = norm(sub(*p, *q));
                    sq += d * d;
                }
            }
            let unit_diag = posemfa::export::rig_report::bbox_diagonal(&pop.unit_shapes()[0]);
            let e_fit = 1000.0 * (sq / (3 * pop.n_vertices() * pop.n_shapes()) as f64).sqrt() / unit_diag;
            assert!((err.e_rms - e_fit).abs() <= 1e-3 * e_fit + 1e-4, "K = {k}: glb {} vs fit {e_fit}", err.e_rms);
            assert!(err.e_rms <= last * 1.02, "K = {k}: {} after {last}", err.e_rms);
            last = err.e_rms;
            if k >= 4 {
                assert!(err.e_rms < 0.8 * rigid.e_rms, "K = {k}: fitted {} vs rigid {}", err.e_rms, rigid.e_rms);
            }
        }
    }

    fn the_fit_and_its_rigid_rig_have_one_error() {
        // the fit's E_RMS (the result's figure beside its RMSE) is the rigid rig's, as the file plays it
        let (pop, model) = quadruped_fit();
        let art = Articulation::new(&model, &pop).unwrap();
        let (rigid, _) = exported(&pop, &art, &GltfOptions::default());
        let own = posemfa::export::rig_report::fit_e_rms(&pop, &model);
        assert!(own > 0.0 && (rigid.e_rms - own).abs() <= 1e-3 * own, "rigid rig {} vs fit {own}", rigid.e_rms);
    }

    fn fixed_joints_keep_every_bone_length() {
        let (pop, art) = quadruped();
        let free = GltfOptions { weights: Weights::Fitted, ..Default::default() };
        let (e_free, p_free) = exported(&pop, &art, &free);
        let (e_fixed, p_fixed) = exported(&pop, &art, &GltfOptions { joints: Joints::Fixed, ..free });
        let change_fixed = bone_length_change(&p_fixed, e_fixed.diagonal);
        let change_free = bone_length_change(&p_free, e_free.diagonal);
        assert!(change_fixed <= 1e-5, "fixed joints: a bone length changes by {change_fixed} of the diagonal");
        // free joints' nodes sit at their pivots (articulate::joints::pivot), where parent and child move most
        // alike: the bones still stretch, less than when the nodes sat at the contact centroids (> 1e-3)
        assert!(change_free > 1e-4, "free joints: bone lengths change by {change_free} only");
        // the constraint costs something, but the rig still beats rigid weights
        let (rigid, _) = exported(&pop, &art, &GltfOptions::default());
        assert!(e_fixed.e_rms >= e_free.e_rms * 0.999 && e_fixed.e_rms < rigid.e_rms, "fixed {} free {} rigid {}", e_fixed.e_rms, e_free.e_rms, rigid.e_rms);
        // rigid weights with fixed joints too
        let (_, p) = exported(&pop, &art, &GltfOptions { joints: Joints::Fixed, ..Default::default() });
        assert!(bone_length_change(&p, e_fixed.diagonal) <= 1e-5);
    }

    fn residual_morphs_reproduce_every_pose() {
        let (pop, art) = quadruped();
        for weights in [Weights::Rigid, Weights::Fitted] {
            for joints in [Joints::Free, Joints::Fixed] {
                let opts = GltfOptions { weights, joints, morphs: Morphs::Residual, ..Default::default() };
                let (err, _) = exported(&pop, &art, &opts);
                assert!(err.max_error_over_diagonal <= 1e-5, "{weights:?} {joints:?}: {}", err.max_error_over_diagonal);
                let (plain, _) = exported(&pop, &art, &GltfOptions { morphs: Morphs::None, ..opts });
                assert!(plain.max_error_over_diagonal > 1e-3, "{weights:?} {joints:?}: without morphs {}", plain.max_error_over_diagonal);
            }
        }
    }

    fn scaled_and_affine_bones_play_what_the_solver_fitted() {
        let (pop, art) = quadruped();
        let unit_diag = posemfa::export::rig_report::bbox_diagonal(&pop.unit_shapes()[0]);
        let fitted = GltfOptions { weights: Weights::Fitted, ..Default::default() };
        let (plain, _) = exported(&pop, &art, &fitted);
        let mut errors = Vec::new();
        for (scale, affine) in [(true, false), (false, true)] {
            let opts = GltfOptions { bone_scale: scale, bone_affine: affine, ..fitted };
            let rig = build(&art, &opts.rig_options()).unwrap();
            let sc = rig.scale.as_ref().expect("scale channels");
            assert_eq!(sc.turning.is_some(), affine);
            let mut sq = 0.0;
            for i in 0..pop.n_shapes() {
                for (p, q) in rig.pose(i).iter().zip(&pop.unit_shapes()[i]) {
                    let d = norm(sub(*p, *q));
                    sq += d * d;
                }
            }
            let e_fit = 1000.0 * (sq / (3 * pop.n_vertices() * pop.n_shapes()) as f64).sqrt() / unit_diag;
            // the file's joints, scale leaves and (affine) turning leaves play the solver's A x + t
            let (err, _) = exported(&pop, &art, &opts);
            assert!((err.e_rms - e_fit).abs() <= 1e-3 * e_fit + 1e-4, "scale {scale} affine {affine}: glb {} vs fit {e_fit}", err.e_rms);
            errors.push(err.e_rms);
        }
        // more freedom, no more error (each a few per cent either way of the others on this rigid quadruped)
        assert!(errors[0] <= plain.e_rms * 1.02 && errors[1] <= errors[0] * 1.02, "rigid {} scale {} affine {}", plain.e_rms, errors[0], errors[1]);
    }

    fn bad_rig_options_are_named() {
        let (_, art) = quadruped();
        let fitted = GltfOptions { weights: Weights::Fitted, ..Default::default() };
        for (opts, word) in [
            (GltfOptions { influences: 0, ..Default::default() }, "influences"),
            (GltfOptions { influences: 9, ..Default::default() }, "influences"),
            (GltfOptions { bind_pose: 99, ..Default::default() }, "bind pose"),
            (GltfOptions { bone_affine: true, ..Default::default() }, "affine bones need fitted weights"),
            (GltfOptions { bone_affine: true, bone_scale: true, ..fitted }, "exclude each other"),
            (GltfOptions { iterations: 0, ..fitted }, "alternations"),
        ] {
            let e = to_glb(&art, &opts).unwrap_err().to_string();
            assert!(e.contains(word), "{e}");
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn horse_gallop_fitted_rig() {
    let Some(dir) = common::shared_dir("data/horse-gallop", "horse_gallop_fitted_rig") else { return };
    let pop = Population::new(posemfa::mesh::Sources::paths(&[dir])).unwrap();
    let r = fit(&pop, &Default::default(), &mut |_| true).unwrap();
    let art = Articulation::new(&r.model, &pop).unwrap();
    let bind = pop.names.iter().position(|n| n.starts_with("reference")).unwrap_or(0);
    let (rigid, _) = exported(&pop, &art, &GltfOptions { bind_pose: bind, ..Default::default() });
    let (fitted, _) =
        exported(&pop, &art, &GltfOptions { bind_pose: bind, weights: Weights::Fitted, ..Default::default() });
    eprintln!("horse-gallop, {} parts: E_RMS rigid {:.3}, fitted {:.3}", r.model.n_parts(), rigid.e_rms, fitted.e_rms);
    assert!(fitted.e_rms < 0.8 * rigid.e_rms && fitted.e_rms < 1.5, "fitted {} rigid {}", fitted.e_rms, rigid.e_rms);
}
