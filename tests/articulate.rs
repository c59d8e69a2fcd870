//! Articulation (Algorithm 2, interpolation, skinning) on generated creatures (posemfa::synth) and, natively, on the horse when
//! ../shared/data/horse-poses exists. Most tests run natively and in wasm (scripts/test.sh).
//!
//! Two kinds of model: the generator's ground truth turned into a [`Model`] (exact rigid parts, no fit:
//! for properties that must hold exactly) and a fitted model (Algorithm 1 on the generated shapes).

#[macro_use]
mod common;

use posemfa::articulate::graph::TreeRule;
use posemfa::articulate::report::{edge_stretch, max_distance, signed_volume};
use posemfa::articulate::{Articulation, Blend, Options, RootRule, Skin};
use posemfa::geometry::rotation::{angle_between, axis_angle};
use posemfa::geometry::{mat_vec, norm, sub, Vec3};
use posemfa::mesh::Population;
use posemfa::mfa::{Component, Model, Params};
use posemfa::synth::{generate, Generated, Preset, Spec};

fn creature(vertices: usize, poses: usize, seed: u64, band: f64, max_angle: f64) -> Generated {
    generate(&Spec {
        preset: Preset::Quadruped,
        vertices,
        poses,
        seed,
        joint_band: band,
        max_angle_deg: max_angle,
        ..Spec::default()
    })
    .expect("generate")
}

/// The generator's ground truth as a fitted model would give it: latent = rest shape, R/b per part.
fn truth_model(g: &Generated) -> Model {
    let ns = g.population.n_shapes();
    let n_parts = g.part_names.len();
    Model {
        n_shapes: ns,
        n_vertices: g.population.n_vertices(),
        parts: (0..n_parts)
            .map(|k| Component {
                rotations: (0..ns).map(|i| g.rotations[i][k]).collect(),
                translations: (0..ns).map(|i| g.translations[i][k]).collect(),
                lambda: [10.0; 3],
                variances: vec![1e-6; ns],
                weight: 1.0 / n_parts as f64,
            })
            .collect(),
        labels: g.part_of_vertex.clone(),
        latent: g.rest.clone(),
        log_likelihood: Vec::new(),
        iterations: 0,
        converged: true,
    }
}

fn fitted(pop: &Population) -> Model {
    posemfa::parts::hierarchy::fit(pop, &Params::default(), &mut |_| true).expect("fit").model
}

/// Every combination of the interpolation options.
fn all_options() -> Vec<Options> {
    let mut v = Vec::new();
    for root in [RootRule::Anchor, RootRule::Paper] {
        for tree in [TreeRule::Strongest, TreeRule::BreadthFirst] {
            for residual in [true, false] {
                for (skin, blend, edge_blend) in [
                    (Skin::Rigid, Blend::DualQuaternion, true),
                    (Skin::Smooth, Blend::DualQuaternion, true),
                    (Skin::Smooth, Blend::DualQuaternion, false),
                    (Skin::Smooth, Blend::Linear, true),
                ] {
                    v.push(Options { root, tree, exact_ends: true, residual, skin, blend, edge_blend });
                }
            }
        }
    }
    v
}

fn volume_change(art: &Articulation, x: &[Vec3], i: usize, j: usize) -> f64 {
    let v_ref = 0.5 * (signed_volume(&art.shape(i), &art.faces) + signed_volume(&art.shape(j), &art.faces));
    signed_volume(x, &art.faces) / v_ref - 1.0
}

dual_test! {
    fn endpoints_are_exact_with_every_option() {
        let g = creature(1500, 5, 11, 0.05, 50.0);
        let model = fitted(&g.population);
        let art = Articulation::new(&model, &g.population).unwrap();
        for (i, j) in [(0, 4), (3, 1)] {
            for o in all_options() {
                let (ti, tj) = if o.residual { (&art.shape(i), &art.shape(j)) } else { (&art.rigid(i), &art.rigid(j)) };
                let e0 = max_distance(&art.interpolate(i, j, 0.0, &o).unwrap(), ti);
                let e1 = max_distance(&art.interpolate(i, j, 1.0, &o).unwrap(), tj);
                assert!(e0 <= 1e-6 && e1 <= 1e-6, "{i}->{j} {o:?}: {e0:e} {e1:e}");
            }
        }
        // Algorithm 2 as printed misses its own end poses on a fitted model (docs/method.md, item 9)
        let plain = Options { residual: false, ..Options::paper() };
        let miss = max_distance(&art.interpolate(0, 4, 1.0, &plain).unwrap(), &art.rigid(4));
        assert!(miss > 1e-4, "{miss}");
    }

    fn edges_inside_a_part_keep_their_length_without_residual() {
        let g = creature(1500, 5, 12, 0.05, 50.0);
        let model = fitted(&g.population);
        let art = Articulation::new(&model, &g.population).unwrap();
        let o = Options { residual: false, ..Options::default() };
        let mut checked = 0;
        for t in [0.3, 0.5, 0.8] {
            let x = art.interpolate(1, 3, t, &o).unwrap();
            for e in &art.edges {
                let (a, b) = (e[0] as usize, e[1] as usize);
                if art.model.labels[a] == art.model.labels[b] {
                    let latent = norm(sub(art.model.latent[a], art.model.latent[b]));
                    let now = norm(sub(x[a], x[b]));
                    assert!((now - latent).abs() <= 1e-9 * latent.max(1.0), "edge {a}-{b} at t={t}: {now} vs {latent}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 3 * art.edges.len() / 2);
        // with the residual the same edges do change (the parts are not exactly rigid in the data)
        let x = art.interpolate(1, 3, 0.5, &Options::default()).unwrap();
        let moved = art.edges.iter().any(|e| {
            let (a, b) = (e[0] as usize, e[1] as usize);
            art.model.labels[a] == art.model.labels[b]
                && (norm(sub(x[a], x[b])) - norm(sub(art.model.latent[a], art.model.latent[b]))).abs() > 1e-6
        });
        assert!(moved);
    }

    fn volume_is_kept_half_way_while_linear_blending_loses_more() {
        for seed in [21, 22] {
            let g = creature(1500, 4, seed, 0.05, 70.0);
            let model = fitted(&g.population);
            let art = Articulation::new(&model, &g.population).unwrap();
            for (i, j) in [(0, 1), (2, 3)] {
                let lin = volume_change(&art, &art.linear(i, j, 0.5).unwrap(), i, j);
                for o in [Options::default(), Options { skin: Skin::Smooth, ..Options::default() }] {
                    let dv = volume_change(&art, &art.interpolate(i, j, 0.5, &o).unwrap(), i, j);
                    assert!(dv.abs() <= 0.01, "seed {seed} {i}->{j} {:?}: {dv}", o.skin);
                    assert!(lin < -dv.abs(), "seed {seed} {i}->{j}: linear {lin} vs {dv}");
                }
            }
        }
    }

    fn slerp_takes_the_short_arc() {
        // A creature turned about z by +170 and by -170 degrees: half way it must be turned by 180 (20
        // degrees each way), not back to 0 (340 degrees).
        let g = creature(1200, 2, 3, 0.0, 20.0);
        let turn = |deg: f64| axis_angle([0.0, 0.0, 1.0], deg.to_radians());
        let (r0, r1) = (turn(170.0), turn(-170.0));
        let shapes: Vec<Vec<Vec3>> = [r0, r1].iter().map(|r| g.rest.iter().map(|&v| mat_vec(r, v)).collect()).collect();
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: vec!["a".into(), "b".into()], faces: g.population.faces.to_vec(), shapes }).unwrap();
        let mut model = truth_model(&g);
        // latent = shape a turned back; every part: R = (r0, r1), b = (0, x^b - r1 latent)
        model.latent = pop.unit_shapes()[0].iter().map(|&x| posemfa::geometry::mat_t_vec(&r0, x)).collect();
        let b1 = sub(pop.unit_shapes()[1][0], mat_vec(&r1, model.latent[0]));
        for p in &mut model.parts {
            p.rotations = vec![r0, r1];
            p.translations = vec![[0.0; 3], b1];
        }
        let art = Articulation::new(&model, &pop).unwrap();
        assert!(max_distance(&art.rigid(0), &pop.unit_shapes()[0]) < 1e-9);
        // (pose b is stored in f32 on its own: its rigid image from pose a is exact to f32 rounding, 6e-8)
        assert!(max_distance(&art.rigid(1), &pop.unit_shapes()[1]) < 1e-6);
        for rule in [RootRule::Anchor, RootRule::Paper] {
            let o = Options { root: rule, residual: false, ..Options::default() };
            for m in &art.part_motions(0, 1, 0.5, &o).unwrap() {
                assert!(angle_between(&m.rotation, &turn(180.0)) < 1e-6, "{rule:?}");
            }
            // the shape is the creature turned by 180 degrees (up to a translation)
            let x = art.interpolate(0, 1, 0.5, &o).unwrap();
            let want: Vec<Vec3> = model.latent.iter().map(|&v| mat_vec(&turn(180.0), v)).collect();
            let d0 = sub(x[0], want[0]);
            let err = x.iter().zip(&want).map(|(a, b)| norm(sub(sub(*a, *b), d0))).fold(0.0, f64::max);
            assert!(err < 1e-9, "{rule:?}: {err}");
            // a quarter of the way: turned by 170 + 5 = 175 degrees
            for m in &art.part_motions(0, 1, 0.25, &o).unwrap() {
                assert!(angle_between(&m.rotation, &turn(175.0)) < 1e-6, "{rule:?}");
            }
        }
    }

    fn anchor_root_is_the_trunk_and_paper_root_turns_least() {
        let g = creature(1500, 6, 5, 0.0, 60.0);
        let model = truth_model(&g);
        let art = Articulation::new(&model, &g.population).unwrap();
        let trunk = g.parent.iter().position(|p| p.is_none()).unwrap();
        assert_eq!(art.anchor, trunk, "{} vs {}", g.part_names[art.anchor], g.part_names[trunk]);
        for (i, j) in [(0, 1), (2, 5)] {
            let r = art.root(RootRule::Paper, i, j);
            for k in art.graph.used_parts() {
                assert!(art.rotation_angle(r, i, j) <= art.rotation_angle(k, i, j));
            }
        }
        // the default tree of the exact model is the generator's skeleton
        let tree = art.tree(&Options::default(), 0, 1);
        assert_eq!(tree.parent, g.parent);
        // and its joints sit at the generator's joint centres, in every pose
        let sk = art.skeleton(3).unwrap();
        for k in 0..g.parent.len() {
            if let Some(c) = g.joint_centers[k] {
                let want = art.model.parts[k].place(3, c);
                let got = sk.positions[k].unwrap();
                assert!(norm(sub(got, want)) < 0.02, "{}: {got:?} vs {want:?}", g.part_names[k]);
            }
        }
    }

    fn rigid_skin_is_the_one_hot_case_of_the_skinned_formula() {
        let g = creature(1500, 4, 9, 0.05, 50.0);
        let model = fitted(&g.population);
        let art = Articulation::new(&model, &g.population).unwrap();
        for residual in [true, false] {
            let o = Options { residual, edge_blend: false, ..Options::default() };
            let m = art.part_motions(0, 3, 0.4, &o).unwrap();
            let eq24 = art.place_rigid(&m, 0, 3, 0.4, residual);
            let skinned = art.place_skinned(&m, &art.rigid_weights, 0, 3, 0.4, &o);
            assert!(max_distance(&eq24, &skinned) < 1e-12);
        }
    }

    fn smooth_skin_stretches_boundary_edges_less_than_rigid_parts() {
        let g = creature(1500, 4, 13, 0.05, 60.0);
        let model = fitted(&g.population);
        let art = Articulation::new(&model, &g.population).unwrap();
        // every vertex's weights: positive, summing to 1, and many vertices blend several parts
        let mut blended = 0;
        for v in 0..art.n_vertices() {
            let w: Vec<(usize, f64)> = art.smooth_weights.influences(v).collect();
            assert!(w.iter().all(|x| x.1 > 0.0));
            assert!((w.iter().map(|x| x.1).sum::<f64>() - 1.0).abs() < 1e-12);
            blended += (w.len() > 1) as usize;
        }
        assert!(blended > art.n_vertices() / 10, "{blended}");
        for (i, j) in [(0, 1), (2, 3)] {
            let rigid = edge_stretch(&art, &art.interpolate(i, j, 0.5, &Options::default()).unwrap(), i, j, 0.5);
            let smooth = edge_stretch(&art, &art.interpolate(i, j, 0.5, &Options { skin: Skin::Smooth, ..Options::default() }).unwrap(), i, j, 0.5);
            assert!(smooth.boundary_p99 < rigid.boundary_p99, "{i}->{j}: {smooth:?} vs {rigid:?}");
            assert!(smooth.boundary_p99 < 0.25, "{i}->{j}: {smooth:?}");
        }
    }

    fn keyframes_pass_through_every_pose_and_are_continuous() {
        let g = creature(1200, 4, 14, 0.05, 50.0);
        let model = fitted(&g.population);
        let art = Articulation::new(&model, &g.population).unwrap();
        let keys = [2, 0, 3, 1];
        let o = Options::default();
        for (s, &k) in keys.iter().enumerate() {
            let x = art.keyframes(&keys, s as f64, &o).unwrap();
            assert!(max_distance(&x, &art.shape(k)) <= 1e-6, "key {s}");
        }
        // approaching key 1 from both sides
        let before = art.keyframes(&keys, 1.0 - 1e-7, &o).unwrap();
        let after = art.keyframes(&keys, 1.0 + 1e-7, &o).unwrap();
        assert!(max_distance(&before, &after) < 1e-4);
        assert!(art.keyframes(&keys, 3.5, &o).is_err());
        assert!(art.keyframes(&[0, 9], 0.5, &o).is_err());
        assert!(art.interpolate(0, 1, 1.5, &o).is_err());
    }

    fn gltf_training_clip_reproduces_the_rigid_reconstructions() {
        use posemfa::export::gltf::{check_glb, to_glb, GltfOptions, Weights};
        let g = creature(1200, 4, 15, 0.05, 50.0);
        let model = fitted(&g.population);
        let art = Articulation::new(&model, &g.population).unwrap();
        for bind_pose in [0, 2] {
            let glb = to_glb(&art, &GltfOptions { bind_pose, ..GltfOptions::default() }).unwrap();
            let check = check_glb(&art, &glb).unwrap();
            assert_eq!(check.frame_error.len(), 4);
            assert!(check.max_frame_error <= 1e-4, "{check:?}");
            assert_eq!(check.clips, vec!["training poses".to_string(), "interpolated".to_string()]);
            assert_eq!(check.joints, art.graph.used_parts().len());
        }
        // smooth weights are not exact at the training poses (they blend), but stay close
        let glb = to_glb(&art, &GltfOptions { weights: Weights::Smooth, ..GltfOptions::default() }).unwrap();
        let check = check_glb(&art, &glb).unwrap();
        assert!(check.max_frame_error > 1e-4 && check.max_frame_error < 0.1, "{check:?}");
        assert!(to_glb(&art, &GltfOptions { bind_pose: 4, ..GltfOptions::default() }).is_err());
    }
}

/// The horse, poses 3 -> 8 (when ../shared/data/horse-poses exists): the figures docs/method.md quotes.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn horse_poses_3_to_8() {
    let Some(dir) = common::shared_dir("data/horse-poses", "horse_poses_3_to_8") else { return };
    let pop = Population::new(posemfa::mesh::Sources::paths(&[&dir])).unwrap();
    let model = fitted(&pop);
    let art = Articulation::new(&model, &pop).unwrap();
    let rep = posemfa::articulate::report::report(&art, 2, 7, 0.5).unwrap();
    let by =
        |prefix: &str| rep.methods.iter().find(|m| m.name.starts_with(prefix)).unwrap_or_else(|| panic!("{prefix}"));
    let rigid = by("rigid (default");
    let rigid_off = by("rigid, residual off");
    let smooth = by("smooth dual-quaternion skin");
    let linear = by("linear vertex");
    for m in [rigid, rigid_off, smooth] {
        assert!(m.endpoint_error[0] <= 1e-5 && m.endpoint_error[1] <= 1e-5, "{}: {:?}", m.name, m.endpoint_error);
    }
    assert!(rigid.volume_change.abs() <= 0.01, "{}", rigid.volume_change);
    assert!(smooth.volume_change.abs() <= 0.01, "{}", smooth.volume_change);
    assert!(linear.volume_change < -0.05, "{}", linear.volume_change);
    assert!(smooth.stretch.boundary_p99 <= 0.25, "{:?}", smooth.stretch);
    assert!(smooth.stretch.boundary_p99 < rigid.stretch.boundary_p99);
    let glb = posemfa::export::gltf::to_glb(&art, &Default::default()).unwrap();
    let check = posemfa::export::gltf::check_glb(&art, &glb).unwrap();
    assert!(check.max_frame_error <= 1e-4, "{check:?}");
    eprintln!("{}", serde_json::to_string(&rep).unwrap());
}
