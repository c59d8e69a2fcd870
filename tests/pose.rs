//! Posing what was learned ([`posemfa::articulate::pose`]): new frames solved onto a rig with the
//! weights fixed recover a generated creature's own bone motions; the pose space reproduces its training poses
//! and its mean; a turn moves only the turned part's subtree and keeps its joint; a rig .glb read back and written
//! with a `frames` clip plays (from the file's own numbers) what the solve found.

#[macro_use]
mod common;

use posemfa::articulate::pose::{
    e_rms, local_rotations, pose_from_locals, solve_frames, sse, turn, PoseSpace, SkinnedRig,
};
use posemfa::articulate::rig::{build, RigOptions, RigWeights};
use posemfa::articulate::skin::SkinWeights;
use posemfa::articulate::{Articulation, RigidMotion};
use posemfa::export::gltf::{play_glb_clip, write_glb, GltfOptions, Weights};
use posemfa::export::pose_glb::{max_distance, read_rig};
use posemfa::geometry::rotation::angle_between;
use posemfa::geometry::{norm, sub, Vec3};
use posemfa::mesh::Population;
use posemfa::parts::hierarchy::fit;
use posemfa::synth::presets::example;
use posemfa::synth::{generate, Generated, Spec};

fn creature(poses: usize, seed: u64) -> Generated {
    generate(&Spec { vertices: 1500, poses, seed, ..Spec::default() }).unwrap()
}

/// The generator's own rig: its rest mesh, its skinning, its skeleton and joint centres.
fn true_rig(g: &Generated) -> SkinnedRig {
    let n = g.n_parts();
    let influences = g
        .blend
        .iter()
        .map(|b| {
            if b.parts[0] == b.parts[1] || b.weight == 0.0 {
                vec![(b.parts[0], 1.0)]
            } else if b.weight == 1.0 {
                vec![(b.parts[1], 1.0)]
            } else {
                vec![(b.parts[0], 1.0 - b.weight), (b.parts[1], b.weight)]
            }
        })
        .collect();
    let mut order: Vec<usize> = Vec::new();
    while order.len() < n {
        for k in 0..n {
            if !order.contains(&k) && g.parent[k].is_none_or(|p| order.contains(&p)) {
                order.push(k);
            }
        }
    }
    let joint_points = (0..n)
        .map(|k| {
            g.joint_centers[k].unwrap_or_else(|| {
                let (lo, hi) = posemfa::geometry::bounds(&g.rest);
                [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0]
            })
        })
        .collect();
    SkinnedRig {
        rest: g.rest.clone(),
        weights: SkinWeights { influences },
        parent: g.parent.clone(),
        order,
        joint_points,
    }
}

fn true_motions(g: &Generated, i: usize) -> Vec<RigidMotion> {
    (0..g.n_parts()).map(|k| RigidMotion { rotation: g.rotations[i][k], translation: g.translations[i][k] }).collect()
}

dual_test! {
    fn frames_solved_onto_the_true_rig_recover_the_true_bones() {
        let g = creature(5, 3);
        let rig = true_rig(&g);
        let solved = solve_frames(&rig, &g.population.unit_shapes()).unwrap();
        let d = rig.diagonal();
        for (i, frame) in g.population.unit_shapes().iter().enumerate() {
            let e = e_rms(solved.sse[i], rig.n_vertices(), d);
            assert!(e < 1e-4, "pose {i}: E_RMS {e} on the generator's own rig");
            for k in 0..g.n_parts() {
                let a = angle_between(&solved.bones[i][k].rotation, &g.rotations[i][k]);
                assert!(a < 1e-5, "pose {i}, part {} ({}): rotation off by {a} rad", k, g.part_names[k]);
            }
            assert!(max_distance(&rig.skin(&solved.bones[i]), frame) < 1e-6 * d);
        }
    }

    fn the_pose_space_reproduces_its_poses_and_its_mean() {
        let g = creature(8, 5);
        let rig = true_rig(&g);
        let poses: Vec<Vec<RigidMotion>> = (0..8).map(|i| true_motions(&g, i)).collect();
        let space = PoseSpace::new(&rig, &poses).unwrap();
        assert!(space.n_modes() >= 1 && space.n_modes() <= 7, "{} modes from 8 poses", space.n_modes());
        assert!(space.sd.windows(2).all(|w| w[0] >= w[1]), "modes by variance: {:?}", space.sd);
        // sliders at 0: the mean
        let at0 = space.vector(&vec![0.0; space.n_modes()]);
        assert!(at0.iter().zip(&space.mean).all(|(a, b)| (a - b).abs() < 1e-12));
        for i in 0..8 {
            // each training pose's projection reproduces it
            let x = space.vector(&space.coords[i]);
            let worst = x.iter().zip(&space.training[i]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-9, "pose {i}: projection off by {worst}");
            // and its local rotations, carried down the skeleton from the true root, give the pose itself
            let locals = space.locals(rig.n_bones(), &x);
            let truth = local_rotations(&rig, &poses[i]);
            for &k in &space.bones {
                assert!(angle_between(&locals[k], &truth[k]) < 1e-9);
            }
            let root = rig.order[0];
            let posed = pose_from_locals(&rig, poses[i][root], &locals);
            let d = max_distance(&rig.skin(&posed), &g.population.unit_shapes()[i]);
            assert!(d < 1e-6 * rig.diagonal(), "pose {i}: carried pose off by {d}");
        }
        // random poses stay within the training range
        for seed in 0..5 {
            let c = space.random(seed);
            for (m, r) in space.range.iter().enumerate() {
                assert!(c[m] >= r[0] && c[m] <= r[1]);
            }
        }
    }

    fn a_turn_moves_only_the_subtree_and_keeps_its_joint() {
        let g = creature(2, 1);
        let rig = true_rig(&g);
        let d = rig.diagonal();
        let start = true_motions(&g, 1);
        let before = rig.skin(&start);
        for k in rig.order.iter().copied().filter(|&k| rig.parent[k].is_some()).take(6) {
            let turned = turn(&rig, &start, k, [0.3, 1.0, -0.2], 0.7).unwrap();
            let after = rig.skin(&turned);
            let mut moved_inside = 0.0f64;
            for v in 0..rig.n_vertices() {
                let touches = rig.weights.influences(v).any(|(b, _)| rig.in_subtree(k, b));
                let m = norm(sub(after[v], before[v]));
                if touches {
                    moved_inside = moved_inside.max(m);
                } else {
                    assert!(m < 1e-6 * d, "part {k}: vertex {v} outside its subtree moved by {m}");
                }
            }
            assert!(moved_inside > 1e-3 * d, "part {k}: nothing moved");
            let p = rig.parent[k].unwrap();
            let joint_before = start[p].apply(rig.joint_points[k]);
            let joint_after = turned[k].apply(rig.joint_points[k]);
            assert!(norm(sub(joint_before, joint_after)) < 1e-4 * d);
            // the turn is the part's angle from the rest pose changed by (at most) the turn itself
            let q = local_rotations(&rig, &turned);
            assert!(q[k].iter().all(|x| x.is_finite()));
        }
        assert!(turn(&rig, &start, 999, [1.0, 0.0, 0.0], 0.1).is_err());
        assert!(turn(&rig, &start, rig.order[1], [0.0; 3], 0.1).is_err());
    }
}

fn fitted(pop: &Population) -> (Articulation, posemfa::articulate::rig::Rig) {
    let ex = example("quadruped").unwrap();
    let r = fit(pop, &ex.params, &mut |_| true).unwrap();
    let art = Articulation::new(&r.model, pop).unwrap();
    let rig = build(&art, &RigOptions { weights: RigWeights::Fitted, ..Default::default() }).unwrap();
    (art, rig)
}

fn subset(pop: &Population, keep: impl Fn(usize) -> bool) -> Population {
    let idx: Vec<usize> = (0..pop.n_shapes()).filter(|&i| keep(i)).collect();
    Population::new(posemfa::mesh::Sources::UnitShapes {
        names: idx.iter().map(|&i| pop.names[i].clone()).collect(),
        faces: pop.faces.to_vec(),
        shapes: idx
            .iter()
            .map(|&i| pop.unit_shapes()[i].iter().map(|&p| pop.normalization.to_original(p)).collect())
            .collect(),
    })
    .unwrap()
}

dual_test! {
    fn a_fitted_rig_solves_its_own_poses_as_well_and_new_ones_nearly_as_well() {
        let g = creature(12, 8);
        let train = subset(&g.population, |i| i % 2 == 0);
        let (art, rig) = fitted(&train);
        let skinned = SkinnedRig::from_rig(&rig);
        let d = skinned.diagonal();
        let nv = skinned.n_vertices();
        let own: f64 = (0..train.n_shapes()).map(|i| sse(&rig.pose(i), &art.shape(i))).sum();
        let resolved = solve_frames(&skinned, &art.population.unit_shapes()).unwrap();
        let again: f64 = resolved.sse.iter().sum();
        assert!(again <= own * 1.0001 + 1e-18, "the solve on the training poses: {again} > the rig's own {own}");
        // held-out poses, in the training population's unit box
        let held: Vec<Vec<Vec3>> = (0..12)
            .filter(|i| i % 2 == 1)
            .map(|i| g.population.unit_shapes()[i].iter().map(|&p| train.normalization.to_unit(g.population.normalization.to_original(p))).collect())
            .collect();
        let solved = solve_frames(&skinned, &held).unwrap();
        let e_in = e_rms(own, nv * train.n_shapes(), d);
        let e_out = e_rms(solved.sse.iter().sum(), nv * held.len(), d);
        eprintln!("quadruped, fitted rig on 6 poses: E_RMS in sample {e_in:.3}, held out {e_out:.3}");
        assert!(e_out < 3.0 * e_in + 0.5, "held out {e_out} vs in sample {e_in}");
    }

    fn a_posers_training_angles_are_each_bones_largest_over_its_training_poses() {
        let g = creature(6, 3);
        let (art, _) = fitted(&g.population);
        let mut poser = posemfa::export::pose_glb::Poser::new(&art, &g.population, &GltfOptions::default(), None).unwrap();
        let most = poser.training_angles();
        assert_eq!(most.len(), poser.rig.rig.n_bones());
        let mut reached = vec![false; most.len()];
        for i in 0..g.population.n_shapes() {
            poser.set_training(i).unwrap();
            for (k, a) in poser.angles().iter().enumerate() {
                assert!(*a <= most[k] + 1e-9, "pose {i}, bone {k}: {a} > {}", most[k]);
                reached[k] |= (most[k] - a).abs() < 1e-9;
            }
        }
        assert!(reached.iter().all(|&r| r), "each bone's largest is one of the poses'");
        // the parts that move turn by tens of degrees in the generator's poses
        assert!(most.iter().any(|&a| a > 10.0), "{most:?}");
    }

    fn a_rig_glb_read_back_and_written_with_frames_plays_the_solve() {
        let g = creature(6, 2);
        let (art, rig) = fitted(&g.population);
        let opts = GltfOptions { weights: Weights::Fitted, ..Default::default() };
        let glb = write_glb(&art, &rig, &opts).unwrap();
        let read = read_rig("rig.glb", &glb).unwrap();
        assert_eq!(read.rig.n_vertices(), g.population.n_vertices());
        assert_eq!(read.rig.order.len(), rig.tree.order.len());
        let d = read.rig.diagonal();
        // the rest state is the bind pose: identity skin matrices
        for m in read.rest_bones() {
            assert!(posemfa::geometry::rotation::angle(&m.rotation) < 1e-5 && norm(m.translation) < 1e-5 * d, "{m:?}");
        }
        // bind positions as written (original units)
        let rest = art.to_original(&rig.rest);
        assert!(max_distance(&read.rig.rest, &rest) < 1e-6 * d);
        let frames: Vec<Vec<Vec3>> = g.population.unit_shapes().iter().map(|s| art.to_original(s)).collect();
        let solved = solve_frames(&read.rig, &frames).unwrap();
        let out = read.with_clip("frames", &solved.bones).unwrap();
        let play = play_glb_clip(&out, "frames").unwrap();
        assert_eq!(play.frames.len(), frames.len());
        for (f, shown) in play.frames.iter().enumerate() {
            let want = read.rig.skin(&solved.bones[f]);
            let off = max_distance(shown, &want);
            assert!(off < 1e-5 * d, "frame {f}: the file plays {off} away from the solve");
        }
        assert!(play.clips.contains(&"training poses".to_string()) && play.clips.contains(&"frames".to_string()));
        // written again: the clip is replaced, not doubled
        let again = read_rig("out.glb", &out).unwrap().with_clip("frames", &solved.bones[..1]).unwrap();
        let names = play_glb_clip(&again, "frames").unwrap().clips;
        assert_eq!(names.iter().filter(|c| *c == "frames").count(), 1);
        // a frame of another mesh is refused with the counts
        let e = solve_frames(&read.rig, &[vec![[0.0; 3]; 10]]).unwrap_err().to_string();
        assert!(e.contains("10 vertices"), "{e}");
        assert!(read_rig("x.glb", b"not a glb").is_err());
    }
}
