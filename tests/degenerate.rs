//! Degenerate populations get a clear answer, never NaN, a panic or a hang. One test per case; each
//! asserts either an error of the right kind whose message names the problem and what to do, or a sane model
//! (finite log-likelihood, every number finite, every rotation proper). Every test runs natively and in wasm
//! (Node and headless Chromium, see scripts/test.sh) and takes well under a second.
//!
//! The answers, case by case:
//! - one shape: `Error::Population` "a population needs at least 2 shapes, got 1; add more poses" (and
//!   `Error::Data` from a fit given one-shape data directly).
//! - all shapes identical (or the same up to one translation of the whole mesh): the population loads (it can
//!   be looked at), the fit refuses with `Error::Data` "all N shapes are the same ... no motion to learn".
//! - shapes that differ only by one global rigid motion: a model whose every part carries that motion (the
//!   right rotations, det +1) and a finite log-likelihood (the variance floor bounds it). The fit does not
//!   invent articulation: with `parts = 1` it is one part; with more parts it returns pieces that all move
//!   the same way (the data cannot say otherwise; each piece's rotations are the global ones).
//! - collinear, coplanar or coincident vertices: a sane model (Λ and the variances have floors; rotations of
//!   a rank-deficient cross-covariance are still proper).
//! - a part with fewer than 3 vertices (a tiny separate piece): a sane model.
//! - more parts than vertices for Algorithm 1: `Error::Params` "parts = P is more than the N vertices of the mesh; ask for at
//!   most N parts"; exactly as many parts as vertices is a sane model; the merge tree (the default) ignores `parts`.
//! - NaN/inf coordinates: OBJ text `Error::Obj` naming file, line and coordinate; shapes given as numbers
//!   (`Population::read` of meshes or of unit-box shapes) `Error::Population` naming the file and the vertex; data
//!   given to a fit directly `Error::Data` naming the vertex and the shape. An extent too small or too large to
//!   scale into the unit box is refused by name too.
//! - a population too large for the memory budget: `Error::Data` giving the estimated size, the budget
//!   (1 GiB in wasm32, 8 GiB natively, `POSEMFA_MEMORY_BUDGET` to change it natively) and what to change,
//!   before the fit allocates its working set (see posemfa::memory).

#[macro_use]
mod common;

use posemfa::geometry::rotation::{angle_between, axis_angle};
use posemfa::geometry::{add, det, mat_mul, mat_vec, orthonormality_error, transpose, Mat3, Vec3};
use posemfa::memory;
use posemfa::mesh::{Mesh, Population};
use posemfa::mfa::aecm::Fit;
use posemfa::mfa::data::Data;
use posemfa::mfa::{Model, Params};
use posemfa::parts::hierarchy::{fit, FitResult};
use posemfa::Error;

/// Small and fast fit settings (the cases are about answers, not accuracy).
fn quick(parts: usize) -> Params {
    Params {
        max_iter: 40,
        restarts: 2,
        algorithm1: posemfa::mfa::Algorithm1Params { parts, refine_max_iter: 20, ..Default::default() },
        ..Params::default()
    }
}

fn names(n: usize) -> Vec<String> {
    (1..=n).map(|i| format!("pose{i}.obj")).collect()
}

/// A fan of triangles over the first vertices (the fit does not use the faces; the population needs some).
fn fan(n_vertices: usize) -> Vec<[u32; 3]> {
    (1..n_vertices.saturating_sub(1) as u32).map(|k| [0, k, k + 1]).collect()
}

/// An irregular point cloud (no symmetry, so its rigid motion is identifiable), about 0.5 across.
fn blob(n: usize, seed: f64) -> Vec<Vec3> {
    (0..n)
        .map(|j| {
            let t = j as f64 + seed;
            [
                0.25 * (t * 0.7).sin() + 0.01 * t,
                0.15 * (t * 1.3).cos(),
                0.08 * (t * 0.37).sin() + 0.05 * (t * 2.1).cos(),
            ]
        })
        .collect()
}

/// Every number of the model is finite, every rotation proper, the trace finite; returns the model.
fn assert_sane(result: &FitResult, pop: &Population) -> Model {
    let model = result.model.clone();
    assert_eq!(model.n_vertices, pop.n_vertices());
    assert!(model.n_parts() >= 1);
    assert!(!model.log_likelihood.is_empty(), "no iteration ran");
    assert!(model.log_likelihood.iter().all(|l| l.is_finite()), "log-likelihood {:?}", model.log_likelihood);
    assert!(model.labels.iter().all(|&l| (l as usize) < model.n_parts()));
    assert!(model.latent.iter().flatten().all(|v| v.is_finite()), "non-finite latent shape");
    for (k, c) in model.parts.iter().enumerate() {
        assert!(c.weight.is_finite() && c.weight > 0.0, "part {k}: weight {}", c.weight);
        assert!(c.lambda.iter().all(|l| l.is_finite() && *l > 0.0), "part {k}: Λ {:?}", c.lambda);
        assert!(c.variances.iter().all(|s| s.is_finite() && *s > 0.0), "part {k}: variances {:?}", c.variances);
        assert!(c.translations.iter().flatten().all(|t| t.is_finite()), "part {k}: translations");
        for (i, r) in c.rotations.iter().enumerate() {
            assert!((det(r) - 1.0).abs() < 1e-9, "part {k}, shape {i}: det {}", det(r));
            assert!(orthonormality_error(r) < 1e-9, "part {k}, shape {i}: not a rotation {r:?}");
        }
    }
    assert!(model.rmse(pop).is_finite());
    model
}

/// Err of the expected kind whose message holds every needle (case-sensitive).
fn assert_err_has(e: &Error, needles: &[&str]) {
    let shown = e.to_string();
    for n in needles {
        assert!(shown.contains(n), "message {shown:?} lacks {n:?}");
    }
}

/// R_k^i (R_k^0)^T: the motion of a part from shape 0 to shape i.
fn relative(r: &[Mat3], i: usize) -> Mat3 {
    mat_mul(&r[i], &transpose(&r[0]))
}

dual_test! {
    fn one_shape_is_refused_with_the_count_and_what_to_do() {
        let shape = blob(10, 0.0);
        let e = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(1), faces: fan(10), shapes: vec![shape.clone()] }).unwrap_err();
        assert!(matches!(e, Error::Population { ref file, .. } if file == "pose1.obj"), "{e:?}");
        assert_err_has(&e, &["at least 2 shapes, got 1", "add more poses"]);
        let obj = posemfa::export::obj::write_obj(&shape, &fan(10), "one");
        let e = Population::new(posemfa::mesh::Sources::Files(vec![("only.obj".into(), obj.into_bytes())])).unwrap_err();
        assert_err_has(&e, &["only.obj", "at least 2 shapes"]);
        let e = Population::new(posemfa::mesh::Sources::Meshes(Vec::new())).unwrap_err();
        assert_err_has(&e, &["got 0"]);
        // data handed to a fit directly
        let h: Vec<f64> = shape.iter().flatten().copied().collect();
        let data = Data::from_f64(10, 1, &h, vec![[0.0; 3]]);
        let e = Fit::new(data, &quick(2)).err().expect("one shape must be refused");
        assert!(matches!(e, Error::Data(_)), "{e:?}");
        assert_err_has(&e, &["1 shape(s)", "at least 2 poses"]);
    }

    fn identical_shapes_load_but_the_fit_says_there_is_no_motion() {
        let shape = blob(30, 0.0);
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(4), faces: fan(30), shapes: vec![shape.clone(); 4] }).unwrap();
        let e = fit(&pop, &quick(3), &mut |_| true).err().expect("identical shapes must be refused");
        assert!(matches!(e, Error::Data(_)), "{e:?}");
        assert_err_has(&e, &["all 4 shapes are the same", "no motion to learn", "poses in which the parts move"]);
        // the same mesh moved by one translation: still nothing to learn
        let moved: Vec<Vec<Vec3>> = (0..3).map(|i| shape.iter().map(|&p| add(p, [0.1 * i as f64, 0.03, 0.0])).collect()).collect();
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(3), faces: fan(30), shapes: moved }).unwrap();
        let e = fit(&pop, &quick(1), &mut |_| true).err().expect("translated copies must be refused");
        assert_err_has(&e, &["all 3 shapes are the same", "translation"]);
        // one vertex moving is motion: no refusal
        let mut shapes = vec![shape.clone(); 3];
        shapes[2][7][1] += 0.05;
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(3), faces: fan(30), shapes }).unwrap();
        assert_sane(&fit(&pop, &quick(2), &mut |_| true).unwrap(), &pop);
    }

    fn one_global_rigid_motion_gives_parts_with_that_motion() {
        let rest = blob(40, 0.3);
        let truth: Vec<Mat3> = (0..5).map(|i| axis_angle([0.3, 1.0, 0.2 * i as f64], 0.35 * i as f64)).collect();
        let shapes: Vec<Vec<Vec3>> = truth
            .iter()
            .enumerate()
            .map(|(i, g)| rest.iter().map(|&p| add(mat_vec(g, p), [0.05 * i as f64, -0.02 * i as f64, 0.1])).collect())
            .collect();
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(5), faces: fan(40), shapes }).unwrap();
        for parts in [1, 3] {
            let result = fit(&pop, &quick(parts), &mut |_| true).unwrap();
            let model = assert_sane(&result, &pop);
            if parts == 1 {
                assert_eq!(model.n_parts(), 1);
            }
            for (k, c) in model.parts.iter().enumerate() {
                for i in 1..5 {
                    let err = angle_between(&relative(&c.rotations, i), &relative(&truth, i));
                    assert!(err < 1e-6, "parts={parts}: part {k}, shape {i}: rotation off by {err} rad");
                }
                // exact rigid data: every variance sits on the floor, which keeps the likelihood finite
                assert!(c.variances.iter().all(|&s| s <= 1e-6), "part {k}: variances {:?}", c.variances);
            }
            assert!(model.rmse(&pop) < 1e-3, "rmse {}", model.rmse(&pop));
        }
    }

    fn collinear_coplanar_and_coincident_vertices_give_a_sane_model() {
        // a straight rod (all vertices on one line in every shape) turning about a point
        let rod: Vec<Vec3> = (0..12).map(|j| [0.05 * j as f64, 0.0, 0.0]).collect();
        let rod_shapes: Vec<Vec<Vec3>> =
            (0..4).map(|i| rod.iter().map(|&p| mat_vec(&axis_angle([0.0, 0.4, 1.0], 0.3 * i as f64), p)).collect()).collect();
        // a flat sheet (coplanar) with a hinged half
        let sheet: Vec<Vec3> = (0..24).map(|j| [0.05 * (j % 6) as f64, 0.05 * (j / 6) as f64, 0.0]).collect();
        let sheet_shapes: Vec<Vec<Vec3>> = (0..4)
            .map(|i| {
                let r = axis_angle([0.0, 1.0, 0.0], 0.5 * i as f64);
                sheet.iter().map(|&p| if p[0] > 0.12 { add(mat_vec(&r, [p[0] - 0.125, p[1], 0.0]), [0.125, 0.0, 0.0]) } else { p }).collect()
            })
            .collect();
        // every vertex duplicated (coincident pairs), and a cluster of 6 vertices at one point
        let mut dup = blob(15, 1.0);
        dup.extend(dup.clone());
        dup.extend(vec![[0.3, 0.3, 0.3]; 6]);
        let dup_shapes: Vec<Vec<Vec3>> =
            (0..3).map(|i| dup.iter().map(|&p| mat_vec(&axis_angle([1.0, 0.0, 0.5], 0.4 * i as f64), p)).collect()).collect();
        for (what, shapes) in [("rod", rod_shapes), ("sheet", sheet_shapes), ("coincident", dup_shapes)] {
            let n = shapes[0].len();
            let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(shapes.len()), faces: fan(n), shapes }).unwrap();
            for parts in [1, 2, 4] {
                let result = fit(&pop, &quick(parts), &mut |_| true).unwrap_or_else(|e| panic!("{what}, parts {parts}: {e}"));
                assert_sane(&result, &pop);
            }
        }
    }

    fn a_part_with_fewer_than_3_vertices_gives_a_sane_model() {
        // a body of 40 vertices that turns, and a separate piece of 2 vertices (then 1) moving its own way
        let body = blob(40, 2.0);
        for piece_len in [2usize, 1] {
            let shapes: Vec<Vec<Vec3>> = (0..4)
                .map(|i| {
                    let mut s: Vec<Vec3> = body.iter().map(|&p| mat_vec(&axis_angle([0.0, 0.0, 1.0], 0.3 * i as f64), p)).collect();
                    for v in 0..piece_len {
                        s.push(add([0.8, 0.02 * v as f64, 0.0], [0.0, 0.1 * i as f64, 0.05 * (i * i) as f64]));
                    }
                    s
                })
                .collect();
            let n = shapes[0].len();
            let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(4), faces: fan(n), shapes }).unwrap();
            for (parts, min_part_vertices) in [(2, 1), (3, 1), (2, 4)] {
                let params = Params { min_part_vertices, ..quick(parts) };
                let result = fit(&pop, &params, &mut |_| true).unwrap();
                assert_sane(&result, &pop);
            }
        }
    }

    fn more_parts_than_vertices_is_a_parameter_error() {
        let shapes: Vec<Vec<Vec3>> = (0..3).map(|i| blob(5, i as f64)).collect();
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(3), faces: fan(5), shapes }).unwrap();
        // Algorithm 1 starts from `parts` k-means clusters; the merge tree (the default) does not use the field,
        // so it does not refuse it (the page greys it as ignored)
        let distinct = |parts| Params { part_rule: posemfa::mfa::PartRule::Distinct, ..quick(parts) };
        let e = fit(&pop, &distinct(6), &mut |_| true).err().expect("6 parts for 5 vertices must be refused");
        assert!(matches!(e, Error::Params(_)), "{e:?}");
        assert_err_has(&e, &["parts = 6", "5 vertices", "at most 5 parts"]);
        // as many parts as vertices is allowed and sane
        let params = Params { min_part_vertices: 1, ..distinct(5) };
        assert_sane(&fit(&pop, &params, &mut |_| true).unwrap(), &pop);
        assert_sane(&fit(&pop, &quick(6), &mut |_| true).unwrap(), &pop);
        // and the part count's own limit is still checked first
        let e = fit(&pop, &quick(0), &mut |_| true).err().unwrap();
        assert_err_has(&e, &["parts = 0"]);
    }

    fn non_finite_coordinates_are_refused_naming_file_and_vertex() {
        // OBJ text
        let good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_string();
        for (bad, needle) in [("nan", "`nan`"), ("inf", "`inf`"), ("-1.#INF", "`-1.#INF`"), ("1e999", "`1e999` overflows")] {
            let text = format!("v 0 0 0\nv 1 {bad} 0\nv 0 1 0\nf 1 2 3\n");
            let e = Population::new(posemfa::mesh::Sources::Files(vec![("a.obj".into(), good.clone().into_bytes()), ("b.obj".into(), text.into_bytes())]))
                .unwrap_err();
            assert!(matches!(e, Error::Obj { ref file, line: 2, .. } if file == "b.obj"), "{e:?}");
            assert_err_has(&e, &["b.obj", "line 2", "y coordinate", needle]);
        }
        // numbers: from unit-box shapes and from meshes
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut shapes = vec![blob(6, 0.0), blob(6, 1.0)];
            shapes[1][2][0] = bad;
            let e = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(2), faces: fan(6), shapes }).unwrap_err();
            assert!(matches!(e, Error::Population { ref file, .. } if file == "pose2.obj"), "{e:?}");
            assert_err_has(&e, &["pose2.obj", "vertex 3", "non-finite", "fix or remove it"]);
            let mut m = Mesh { positions: blob(6, 0.0), faces: fan(6) };
            m.positions[4][2] = bad;
            let e = Population::new(posemfa::mesh::Sources::Meshes(vec![("x.obj".into(), Mesh { positions: blob(6, 1.0), faces: fan(6) }), ("y.obj".into(), m)]))
                .unwrap_err();
            assert_err_has(&e, &["y.obj", "vertex 5", "non-finite"]);
        }
        // data given to a fit directly (no population in between)
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(2), faces: fan(6), shapes: vec![blob(6, 0.0), blob(6, 1.0)] }).unwrap();
        let data = Data::from_population(&pop);
        let mut h: Vec<f64> = (0..data.n_vertices).flat_map(|j| data.vertex(j).to_vec()).flatten().collect();
        h[(4 * 2 + 1) * 3 + 2] = f64::NAN; // vertex 5, shape 2, z
        let data = Data::from_f64(data.n_vertices, data.n_shapes, &h, data.offsets.clone());
        let e = Fit::new(data, &quick(2)).err().expect("NaN data must be refused");
        assert!(matches!(e, Error::Data(_)), "{e:?}");
        assert_err_has(&e, &["vertex 5 of shape 2", "non-finite", "NaN"]);
        // finite numbers whose extent cannot be scaled into the unit box
        for (a, b) in [(1e-310, 0.0), (-1.5e308, 1.5e308)] {
            let mut shapes = vec![vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]];
            shapes[0][1][0] = a;
            shapes[1][2][0] = b;
            let e = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(2), faces: fan(3), shapes }).unwrap_err();
            assert_err_has(&e, &["pose1.obj", "cannot scale into a unit box", "rescale"]);
        }
        // all at one point
        let e = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(2), faces: fan(3), shapes: vec![vec![[0.5; 3]; 3]; 2] }).unwrap_err();
        assert_err_has(&e, &["at one point"]);
    }

    fn too_large_for_the_memory_budget_is_refused_before_allocating() {
        let budget = memory::budget_bytes().unwrap();
        if cfg!(target_arch = "wasm32") {
            assert_eq!(budget, 1 << 30);
        } else if std::env::var_os("POSEMFA_MEMORY_BUDGET").is_none() {
            assert_eq!(budget, 8 << 30);
        }
        // A small population (40 000 vertices x 2 shapes, 1.0 MB) with a request whose working set is not:
        // 512 parts, each split up to 64 ways by the refinement -> responsibilities for up to 32 768 parts,
        // about 10 GB. The fit refuses at once, before k-means or the responsibilities are allocated.
        let n = 40_000;
        let shapes: Vec<Vec<Vec3>> = (0..2)
            .map(|i| (0..n).map(|j| [(j % 200) as f64 / 200.0, (j / 200) as f64 / 200.0, 0.01 * i as f64 * (j % 7) as f64]).collect())
            .collect();
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names: names(2), faces: fan(4), shapes }).unwrap();
        // (Algorithm 1's working set: the merge tree's start does not grow with `parts`)
        let params = Params {
            algorithm1: posemfa::mfa::Algorithm1Params { parts: 512, max_subparts: 64, ..Default::default() },
            part_rule: posemfa::mfa::PartRule::Distinct,
            ..Params::default()
        };
        let need = memory::estimate_bytes(n, 2, 512 * 64);
        assert!(need > 8 << 30 && need > budget, "{need}");
        let e = fit(&pop, &params, &mut |_| true).err().expect("must be refused");
        assert!(matches!(e, Error::Data(_)), "{e:?}");
        let budget_text = memory::show_bytes(budget);
        assert_err_has(
            &e,
            &["40000 vertices x 2 shapes", "up to 32768 parts", "GiB of memory", &budget_text, "fewer vertices", "fewer poses", "fewer parts"],
        );
        // without the refinement the same 512 parts would fit (not run: it is a slow fit)
        assert!(memory::estimate_bytes(n, 2, memory::max_components(512, false, 64, n)) < budget);
        // The check that Population::read makes (the smallest fit, 1 part) for a population too large
        // to build in a test: 2 million vertices x 200 poses.
        let e = memory::check(2_000_000, 200, 1, budget).unwrap_err();
        assert_err_has(&e, &["2000000 vertices x 200 shapes needs about", "GiB", "fewer vertices", "fewer poses"]);
        assert!(!e.to_string().contains("parts"), "{e}");
        // and a small budget refuses a small population the same way
        // (1000 x 10 x 48 + 1000 x 11 x 8 + 1000 x 128 + 11 x 10 x 392 = 739 120 bytes, memory::estimate_bytes)
        let e = memory::check(1000, 10, 11, 512 << 10).unwrap_err();
        assert_err_has(&e, &["needs about 721.8 KiB", "budget of 512.0 KiB"]);
        assert!(memory::check(1000, 10, 11, 1 << 20).is_ok());
    }
}
