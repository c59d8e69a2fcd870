//! Properties of generated populations: closed consistent meshes, resolution, determinism, ground truth that
//! really is the motion, OBJ round trip.

use posemfa::geometry::rotation::angle_between;
use posemfa::geometry::{add, cross, mat_vec, norm, sub, Vec3, IDENTITY};
use posemfa::mesh::{Normalization, Population};
use posemfa::metrics::adjusted_rand_index;
use posemfa::synth::{generate, obj_files, part_index, Generated, Preset, Spec};
use std::collections::HashMap;

const PRESETS: [Preset; 7] = Preset::ALL;
/// The creatures of other proportions (beyond the quadruped, for the part rule), made for 3 000 vertices and more.
const NEW: [Preset; 3] = [Preset::Spider, Preset::Giraffe, Preset::Hand];

/// Checks that the triangles form a closed, consistently oriented 2-manifold of sphere topology with no
/// degenerate triangle, and that it encloses positive volume (outward normals) in every shape.
fn check_closed_sphere(pop: &Population, what: &str) {
    let nv = pop.n_vertices();
    let faces: &[[u32; 3]] = &pop.faces;
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for (k, f) in faces.iter().enumerate() {
        assert!(f.iter().all(|&v| (v as usize) < nv), "{what}: triangle {k} has an index out of range");
        assert!(f[0] != f[1] && f[1] != f[2] && f[0] != f[2], "{what}: triangle {k} repeats a vertex: {f:?}");
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            *directed.entry((a, b)).or_insert(0) += 1;
        }
    }
    for (&(a, b), &c) in &directed {
        assert_eq!(c, 1, "{what}: directed edge {a}->{b} used {c} times (inconsistent orientation)");
        assert_eq!(directed.get(&(b, a)), Some(&1), "{what}: edge {a}-{b} has one triangle only (hole)");
    }
    let n_edges = directed.len() / 2;
    // every vertex used, and its triangles form ONE fan (disc neighbourhood)
    let mut next: Vec<Vec<(u32, u32)>> = vec![Vec::new(); nv];
    for f in faces {
        for e in 0..3 {
            next[f[e] as usize].push((f[(e + 1) % 3], f[(e + 2) % 3]));
        }
    }
    for (v, fan) in next.iter().enumerate() {
        assert!(fan.len() >= 3, "{what}: vertex {v} is in {} triangles", fan.len());
        let map: HashMap<u32, u32> = fan.iter().cloned().collect();
        assert_eq!(map.len(), fan.len(), "{what}: vertex {v} is not a manifold vertex");
        let start = fan[0].0;
        let mut cur = start;
        let mut steps = 0;
        loop {
            cur = map[&cur];
            steps += 1;
            if cur == start {
                break;
            }
            assert!(steps <= fan.len(), "{what}: vertex {v}: fan does not close");
        }
        assert_eq!(steps, fan.len(), "{what}: vertex {v}: its triangles form more than one fan");
    }
    let euler = nv as i64 - n_edges as i64 + faces.len() as i64;
    assert_eq!(euler, 2, "{what}: Euler characteristic {euler} (V {nv}, E {n_edges}, F {})", faces.len());
    for (i, shape) in pop.unit_shapes().iter().enumerate() {
        let mut volume = 0.0;
        let mut min_area = f64::INFINITY;
        for f in faces {
            let (a, b, c) = (shape[f[0] as usize], shape[f[1] as usize], shape[f[2] as usize]);
            let n = cross(sub(b, a), sub(c, a));
            min_area = min_area.min(0.5 * norm(n));
            volume += posemfa::geometry::dot(a, n) / 6.0;
        }
        assert!(min_area > 1e-12, "{what}, shape {i}: a triangle has area {min_area:e}");
        assert!(volume > 1e-4, "{what}, shape {i}: enclosed volume {volume} (normals must point outwards)");
    }
}

fn spec(preset: Preset, vertices: usize, poses: usize) -> Spec {
    Spec { preset, vertices, poses, ..Spec::default() }
}

#[test]
fn every_preset_is_a_closed_sphere_near_the_target_size() {
    for preset in PRESETS {
        let targets = if NEW.contains(&preset) { [3_000, 12_000, 50_000] } else { [2_000, 12_000, 60_000] };
        for target in targets {
            let g = generate(&spec(preset, target, 3)).unwrap();
            let what = format!("{preset:?} at {target}");
            let nv = g.population.n_vertices();
            let ratio = nv as f64 / target as f64;
            assert!((0.8..=1.2).contains(&ratio), "{what}: {nv} vertices");
            check_closed_sphere(&g.population, &what);
            assert_eq!(g.population.normalization, Normalization::IDENTITY, "{what}");
            assert_eq!(g.part_of_vertex.len(), nv);
            // every part has vertices
            for p in 0..g.n_parts() {
                assert!(g.part_of_vertex.iter().any(|&l| l as usize == p), "{what}: part {} is empty", g.part_names[p]);
            }
        }
    }
}

/// Largest angle (degrees) between the normals of two triangles sharing an edge.
fn max_dihedral_deg(x: &[Vec3], faces: &[[u32; 3]]) -> f64 {
    let normal = |f: &[u32; 3]| {
        let n = cross(sub(x[f[1] as usize], x[f[0] as usize]), sub(x[f[2] as usize], x[f[0] as usize]));
        posemfa::geometry::scale(n, 1.0 / norm(n))
    };
    let mut by_edge: HashMap<(u32, u32), usize> = HashMap::new();
    let mut worst: f64 = 0.0;
    for (k, f) in faces.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            if let Some(&other) = by_edge.get(&(b, a)) {
                let c = posemfa::geometry::dot(normal(f), normal(&faces[other])).clamp(-1.0, 1.0);
                worst = worst.max(c.acos().to_degrees());
            } else {
                by_edge.insert((a, b), k);
            }
        }
    }
    worst
}

#[test]
fn rest_meshes_are_smooth() {
    // limb sockets keep small wrinkles at the corners of their rectangular holes; the spider's thin legs leave the
    // sharpest (about 70 degrees at 40 000 vertices, measured)
    for (preset, limit) in [
        (Preset::Quadruped, 50.0),
        (Preset::Arm, 10.0),
        (Preset::Snake, 20.0),
        (Preset::Blob, 10.0),
        (Preset::Spider, 80.0),
        (Preset::Giraffe, 60.0),
        (Preset::Hand, 60.0),
    ] {
        let g = generate(&spec(preset, 40_000, 2)).unwrap();
        let d = max_dihedral_deg(&g.rest, &g.population.faces);
        assert!(d < limit, "{preset:?}: adjacent triangles meet at {d:.1} degrees");
    }
}

#[test]
fn large_quadruped_is_closed_and_on_target() {
    let g = generate(&spec(Preset::Quadruped, 200_000, 2)).unwrap();
    let nv = g.population.n_vertices();
    assert!((160_000..=240_000).contains(&nv), "{nv}");
    check_closed_sphere(&g.population, "quadruped at 200k");
}

#[test]
fn small_targets_give_the_coarsest_mesh_still_closed() {
    for preset in PRESETS {
        let g = generate(&spec(preset, 100, 2)).unwrap();
        check_closed_sphere(&g.population, &format!("{preset:?} at 100"));
        let coarsest = if NEW.contains(&preset) { 3_000 } else { 1_500 };
        assert!(g.population.n_vertices() < coarsest, "{preset:?}: {}", g.population.n_vertices());
    }
}

#[test]
fn same_seed_same_output_other_seed_other_poses() {
    for preset in PRESETS {
        let s = Spec { preset, vertices: 3_000, poses: 4, seed: 7, noise: 0.001, ..Spec::default() };
        let a = generate(&s).unwrap();
        let b = generate(&s).unwrap();
        assert_eq!(a, b, "{preset:?}: same spec, different output");
        let c = generate(&Spec { seed: 8, ..s.clone() }).unwrap();
        assert_eq!(a.population.faces, c.population.faces);
        assert_eq!(a.part_of_vertex, c.part_of_vertex);
        for i in 0..4 {
            assert_ne!(
                a.population.unit_shapes()[i],
                c.population.unit_shapes()[i],
                "{preset:?}: seeds 7 and 8 give pose {i} alike"
            );
            assert_ne!(a.rotations[i], c.rotations[i]);
        }
    }
}

/// Largest |x_pose - (R x_rest + t)| over the vertices that follow a single part.
fn rigid_residual(g: &Generated) -> (f64, usize) {
    let mut worst: f64 = 0.0;
    let mut n = 0;
    for (i, shape) in g.population.unit_shapes().iter().enumerate() {
        for (j, b) in g.blend.iter().enumerate() {
            if !b.is_rigid() {
                continue;
            }
            n += 1;
            let p = b.parts[0] as usize;
            let pred = add(mat_vec(&g.rotations[i][p], g.rest[j]), g.translations[i][p]);
            worst = worst.max(norm(sub(shape[j], pred)));
        }
    }
    (worst, n)
}

#[test]
fn rigid_parts_follow_their_ground_truth_motion() {
    for preset in [Preset::Quadruped, Preset::Arm, Preset::Snake, Preset::Spider, Preset::Giraffe, Preset::Hand] {
        // band 0: every vertex follows its part exactly
        let g =
            generate(&Spec { preset, vertices: 5_000, poses: 6, joint_band: 0.0, seed: 3, ..Spec::default() }).unwrap();
        assert!(g.blend.iter().all(|b| b.is_rigid()));
        let (worst, n) = rigid_residual(&g);
        assert_eq!(n, 6 * g.population.n_vertices());
        // (the population stores its coordinates in f32: each within 6e-8 of the generated one)
        assert!(worst < 2e-7, "{preset:?} band 0: residual {worst:e}");
        // with a band: the vertices outside every band are rigid, the others are blended, and the blend
        // region grows with the band
        let g1 = generate(&Spec { preset, vertices: 5_000, poses: 6, joint_band: 0.03, seed: 3, ..Spec::default() })
            .unwrap();
        let g2 = generate(&Spec { preset, vertices: 5_000, poses: 6, joint_band: 0.08, seed: 3, ..Spec::default() })
            .unwrap();
        let blended = |g: &Generated| g.blend.iter().filter(|b| !b.is_rigid()).count();
        assert!(blended(&g1) > 0 && blended(&g2) > blended(&g1), "{preset:?}: {} vs {}", blended(&g1), blended(&g2));
        let (worst, _) = rigid_residual(&g2);
        assert!(worst < 2e-7, "{preset:?} band 0.08: residual {worst:e}");
        // same angles whatever the band: the rotations do not depend on it
        assert_eq!(g.rotations, g2.rotations);
        // blended vertices are NOT on either part's rigid motion (the data is not piecewise rigid)
        let mut off = 0.0f64;
        for (i, shape) in g2.population.unit_shapes().iter().enumerate() {
            for (j, b) in g2.blend.iter().enumerate() {
                if b.weight > 0.3 && b.weight < 0.7 {
                    for &p in &b.parts {
                        let p = p as usize;
                        let pred = add(mat_vec(&g2.rotations[i][p], g2.rest[j]), g2.translations[i][p]);
                        off = off.max(norm(sub(shape[j], pred)));
                    }
                }
            }
        }
        assert!(off > 1e-3, "{preset:?}: blended vertices move rigidly ({off})");
    }
}

#[test]
fn parts_really_move_and_respect_the_angle_scale() {
    let mean_rel = |max_angle_deg: f64| {
        let g = generate(&Spec { max_angle_deg, poses: 10, vertices: 2_000, ..Spec::default() }).unwrap();
        let mut s = 0.0;
        let mut n = 0;
        for i in 0..10 {
            for c in 0..g.n_parts() {
                if let Some(p) = g.parent[c] {
                    let a = angle_between(&g.rotations[i][p], &g.rotations[i][c]).to_degrees();
                    // the largest per-axis fraction is 1.2 on at most three axes
                    assert!(a <= 1.2 * 3f64.sqrt() * max_angle_deg + 1e-9, "{a} > limit for {max_angle_deg}");
                    s += a;
                    n += 1;
                }
            }
            // root stays put without root motion
            assert!(angle_between(&g.rotations[i][0], &IDENTITY) < 1e-15);
        }
        s / n as f64
    };
    let small = mean_rel(10.0);
    let large = mean_rel(60.0);
    assert!(small > 2.0 && large > 4.0 * small, "{small} {large}");
}

#[test]
fn root_motion_moves_the_whole_creature() {
    let g = generate(&Spec { root_motion: true, poses: 5, vertices: 2_000, ..Spec::default() }).unwrap();
    for i in 0..5 {
        assert!(angle_between(&g.rotations[i][0], &IDENTITY) > 1e-3);
    }
    let (worst, _) = rigid_residual(&g);
    // (f32 coordinates, as above)
    assert!(worst < 2e-7, "{worst:e}");
}

#[test]
fn tied_front_legs_form_one_rigid_body() {
    let names = ["upper", "lower", "foot"];
    let tied: Vec<(usize, usize)> = names
        .iter()
        .map(|s| {
            (
                part_index(Preset::Quadruped, &format!("front_left_{s}")).unwrap(),
                part_index(Preset::Quadruped, &format!("front_right_{s}")).unwrap(),
            )
        })
        .collect();
    let g = generate(&Spec { tied: tied.clone(), poses: 6, vertices: 4_000, seed: 11, ..Spec::default() }).unwrap();
    for i in 0..6 {
        for &(a, b) in &tied {
            assert_eq!(g.rotations[i][a], g.rotations[i][b]);
            // same rotation AND same translation: one rigid motion for both legs
            assert!(
                norm(sub(g.translations[i][a], g.translations[i][b])) < 1e-12,
                "{:?} {:?} {:?} {:?}",
                g.translations[i][a],
                g.translations[i][b],
                g.joint_centers[a],
                g.joint_centers[b]
            );
        }
    }
    // hind legs are not tied: they move apart
    let (hl, hr) = (
        part_index(Preset::Quadruped, "hind_left_upper").unwrap(),
        part_index(Preset::Quadruped, "hind_right_upper").unwrap(),
    );
    assert!((0..6).any(|i| angle_between(&g.rotations[i][hl], &g.rotations[i][hr]) > 0.05));
}

#[test]
fn blob_is_one_part_and_not_rigid() {
    let g = generate(&Spec { preset: Preset::Blob, poses: 5, vertices: 3_000, ..Spec::default() }).unwrap();
    assert_eq!(g.n_parts(), 1);
    assert!(g.part_of_vertex.iter().all(|&l| l == 0));
    let mut worst = 0.0f64;
    for (i, shape) in g.population.unit_shapes().iter().enumerate() {
        for (j, p) in shape.iter().enumerate() {
            worst = worst.max(norm(sub(*p, add(mat_vec(&g.rotations[i][0], g.rest[j]), g.translations[i][0]))));
        }
    }
    assert!(worst > 0.02, "the blob must deform non-rigidly ({worst})");
}

#[test]
fn noise_has_the_requested_size() {
    let base = Spec { vertices: 4_000, poses: 3, joint_band: 0.0, ..Spec::default() };
    let clean = generate(&base).unwrap();
    let noisy = generate(&Spec { noise: 0.002, ..base }).unwrap();
    assert_eq!(clean.rotations, noisy.rotations);
    // both are normalised with their own box; compare through the ground truth instead
    let mut s = 0.0;
    let mut n = 0;
    for (i, shape) in noisy.population.unit_shapes().iter().enumerate() {
        for (j, b) in noisy.blend.iter().enumerate() {
            let p = b.parts[0] as usize;
            let d = sub(shape[j], add(mat_vec(&noisy.rotations[i][p], noisy.rest[j]), noisy.translations[i][p]));
            s += d.iter().map(|x| x * x).sum::<f64>();
            n += 3;
        }
    }
    // rest pose longest side is 1 before the final rescale into the unit box (scale <= 1)
    let rms = (s / n as f64).sqrt();
    let rest_side = (0..3)
        .map(|d| {
            let (lo, hi) =
                noisy.rest.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[d]), h.max(p[d])));
            hi - lo
        })
        .fold(0.0, f64::max);
    let rel = rms / rest_side;
    assert!((rel - 0.002).abs() < 0.0002, "noise rms {rel}");
}

#[test]
fn labels_compare_with_ari() {
    let g = generate(&Spec { vertices: 3_000, poses: 2, ..Spec::default() }).unwrap();
    let shuffled: Vec<u32> = g.part_of_vertex.iter().map(|&l| (l * 7 + 3) % 101).collect();
    assert_eq!(adjusted_rand_index(&g.part_of_vertex, &shuffled), 1.0);
    let coarse: Vec<u32> = g.part_of_vertex.iter().map(|&l| l.min(1)).collect();
    assert!(adjusted_rand_index(&g.part_of_vertex, &coarse) < 0.9);
}

#[test]
fn obj_files_round_trip_through_the_importer() {
    let g =
        generate(&Spec { preset: Preset::Snake, vertices: 2_000, poses: 3, noise: 1e-3, ..Spec::default() }).unwrap();
    let files = obj_files(&g);
    assert_eq!(files.iter().map(|f| f.0.as_str()).collect::<Vec<_>>(), vec!["pose01.obj", "pose02.obj", "pose03.obj"]);
    assert!(files[0].1.starts_with("# posemfa synthetic population: preset snake"));
    // reversed input order: the population orders by name
    let bytes: Vec<(String, Vec<u8>)> = files.into_iter().rev().map(|(n, t)| (n, t.into_bytes())).collect();
    let back = Population::new(posemfa::mesh::Sources::Files(bytes)).unwrap();
    assert_eq!(back.names, g.population.names);
    assert_eq!(back.faces, g.population.faces);
    assert_eq!(back.normalization, Normalization::IDENTITY);
    assert_eq!(back.unit_shapes(), g.population.unit_shapes(), "coordinates must come back bit for bit");
}

#[test]
fn joint_centres_are_fixed_points_of_the_relative_motion() {
    let g =
        generate(&Spec { preset: Preset::Quadruped, vertices: 2_000, poses: 3, root_motion: true, ..Spec::default() })
            .unwrap();
    for i in 0..3 {
        for c in 0..g.n_parts() {
            if let (Some(p), Some(j)) = (g.parent[c], g.joint_centers[c]) {
                let by_parent = add(mat_vec(&g.rotations[i][p], j), g.translations[i][p]);
                let by_child = add(mat_vec(&g.rotations[i][c], j), g.translations[i][c]);
                assert!(norm(sub(by_parent, by_child)) < 1e-12, "{}", g.part_names[c]);
            }
        }
    }
    let _: Vec<Vec3> = g.rest.clone();
}

/// Whether segment p-q crosses triangle abc (Moller-Trumbore, both ends included).
fn segment_hits_triangle(p: Vec3, q: Vec3, [a, b, c]: [Vec3; 3]) -> bool {
    use posemfa::geometry::dot;
    let (e1, e2, d) = (sub(b, a), sub(c, a), sub(q, p));
    let h = cross(d, e2);
    let det = dot(e1, h);
    if det.abs() < 1e-18 {
        return false;
    }
    let s = sub(p, a);
    let u = dot(s, h) / det;
    let qq = cross(s, e1);
    let v = dot(d, qq) / det;
    let t = dot(e2, qq) / det;
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&t)
}

/// Pairs of triangles with no common vertex that cross each other (a uniform grid of about two edge lengths
/// finds the candidates).
fn self_intersections(x: &[Vec3], faces: &[[u32; 3]]) -> usize {
    let edge: f64 =
        faces.iter().map(|f| norm(sub(x[f[0] as usize], x[f[1] as usize]))).sum::<f64>() / faces.len() as f64;
    let cell = 2.0 * edge;
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (k, f) in faces.iter().enumerate() {
        let lo = [0, 1, 2].map(|d| f.iter().map(|&v| x[v as usize][d]).fold(f64::INFINITY, f64::min));
        let hi = [0, 1, 2].map(|d| f.iter().map(|&v| x[v as usize][d]).fold(f64::NEG_INFINITY, f64::max));
        let c = |v: f64| (v / cell).floor() as i64;
        for i in c(lo[0])..=c(hi[0]) {
            for j in c(lo[1])..=c(hi[1]) {
                for l in c(lo[2])..=c(hi[2]) {
                    grid.entry([i, j, l]).or_default().push(k);
                }
            }
        }
    }
    let mut crossing = std::collections::HashSet::new();
    for list in grid.values() {
        for (ia, &a) in list.iter().enumerate() {
            for &b in &list[ia + 1..] {
                let (fa, fb) = (faces[a], faces[b]);
                if fa.iter().any(|v| fb.contains(v)) {
                    continue;
                }
                let (ta, tb) = (fa.map(|v| x[v as usize]), fb.map(|v| x[v as usize]));
                let hit = (0..3).any(|e| {
                    segment_hits_triangle(ta[e], ta[(e + 1) % 3], tb)
                        || segment_hits_triangle(tb[e], tb[(e + 1) % 3], ta)
                });
                if hit {
                    crossing.insert((a.min(b), a.max(b)));
                }
            }
        }
    }
    crossing.len()
}

#[test]
fn self_intersection_check_finds_a_crossing() {
    // two unit triangles through each other, and the same pair moved apart
    let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.9, 0.9, 0.0]];
    let faces = [[0, 1, 2], [3, 4, 5]];
    assert_eq!(self_intersections(&x, &faces), 1);
    let apart: Vec<Vec3> =
        x.iter().enumerate().map(|(k, &p)| if k >= 3 { add(p, [5.0, 0.0, 0.0]) } else { p }).collect();
    assert_eq!(self_intersections(&apart, &faces), 0);
}

#[test]
fn new_creatures_do_not_cross_themselves_at_the_default_angles() {
    for preset in NEW {
        for seed in 0..3 {
            let g = generate(&Spec { preset, vertices: 3_000, poses: 10, seed, ..Spec::default() }).unwrap();
            assert_eq!(self_intersections(&g.rest, &g.population.faces), 0, "{preset:?}: rest pose");
            for (i, shape) in g.population.unit_shapes().iter().enumerate() {
                let n = self_intersections(shape, &g.population.faces);
                assert_eq!(n, 0, "{preset:?} seed {seed} pose {}: {n} pairs of triangles cross", i + 1);
            }
        }
    }
}
