//! Checks shared by the fuzz targets: what must hold for every population that loads and for every fit that
//! succeeds. A broken invariant panics, which libFuzzer reports as a crash (with the input saved).

pub use posemfa::fuzzing::params_from;
use posemfa::mesh::Population;
use posemfa::mfa::Model;
use posemfa::parts::hierarchy::fit;
use posemfa::Error;

/// Largest population that the targets fit (the fit is the slow part: keep executions fast).
pub const FIT_MAX_VERTICES: usize = 48;
pub const FIT_MAX_SHAPES: usize = 6;

/// Invariants of a loaded population: ≥ 2 shapes of the same length, faces in range, every coordinate
/// finite and inside the unit box, a usable normalisation.
pub fn check_population(pop: &Population) {
    assert!(pop.n_shapes() >= 2, "a population with {} shapes loaded", pop.n_shapes());
    assert_eq!(pop.names.len(), pop.n_shapes());
    let nv = pop.n_vertices();
    assert!(nv >= 1);
    assert!(!pop.faces.is_empty());
    for f in pop.faces.iter() {
        assert!(f.iter().all(|&v| (v as usize) < nv), "face {f:?} out of range for {nv} vertices");
    }
    let n = pop.normalization;
    assert!(n.scale.is_finite() && n.scale > 0.0, "normalisation scale {}", n.scale);
    assert!(n.offset.iter().all(|o| o.is_finite()), "normalisation offset {:?}", n.offset);
    let eps = 1e-9;
    for (i, shape) in pop.shapes().enumerate() {
        assert_eq!(shape.len(), nv, "shape {i}");
        for p in shape.iter() {
            assert!(p.iter().all(|c| c.is_finite() && *c >= -eps && *c <= 1.0 + eps), "shape {i}: point {p:?}");
        }
    }
}

/// Every number of a fitted model is finite, rotations are proper (det +1, orthonormal), variances and
/// weights positive, labels in range, the log-likelihood trace finite.
pub fn check_model(model: &Model, pop: &Population) {
    assert_eq!(model.n_vertices, pop.n_vertices());
    assert_eq!(model.n_shapes, pop.n_shapes());
    assert!(model.n_parts() >= 1);
    assert_eq!(model.labels.len(), model.n_vertices);
    assert!(model.labels.iter().all(|&l| (l as usize) < model.n_parts()), "label out of range");
    assert!(model.latent.iter().flatten().all(|v| v.is_finite()), "non-finite latent shape");
    assert!(model.log_likelihood.iter().all(|l| l.is_finite()), "log-likelihood trace {:?}", model.log_likelihood);
    for (k, c) in model.parts.iter().enumerate() {
        assert!(c.weight.is_finite() && c.weight >= 0.0, "part {k}: weight {}", c.weight);
        assert!(c.lambda.iter().all(|l| l.is_finite() && *l > 0.0), "part {k}: lambda {:?}", c.lambda);
        assert!(c.variances.iter().all(|s| s.is_finite() && *s > 0.0), "part {k}: variances {:?}", c.variances);
        assert!(c.translations.iter().flatten().all(|t| t.is_finite()), "part {k}: translations");
        for r in &c.rotations {
            assert!(r.iter().all(|x| x.is_finite()), "part {k}: rotation {r:?}");
            let d = posemfa::geometry::det(r);
            assert!((d - 1.0).abs() < 1e-6, "part {k}: det {d} of {r:?}");
            assert!(posemfa::geometry::orthonormality_error(r) < 1e-6, "part {k}: not orthonormal {r:?}");
        }
    }
    let rmse = model.rmse(pop);
    assert!(rmse.is_finite(), "rmse {rmse}");
}

/// Runs Algorithm 1 with small caps on a small population and checks the outcome: a sane model, or an
/// error that is a parameter/data complaint with a message.
pub fn bounded_fit(pop: &Population, cfg: u8) {
    if pop.n_vertices() > FIT_MAX_VERTICES || pop.n_shapes() > FIT_MAX_SHAPES {
        return;
    }
    let params = params_from(cfg);
    match fit(pop, &params, &mut |_| true) {
        Ok(result) => {
            check_model(&result.model, pop);
            assert!(result.complete);
        }
        // The fit may refuse a loaded population only for these documented reasons, each checked here
        // independently of the library; any other refusal (say, of a small part inside the refinement) is a bug.
        Err(Error::Data(m)) if pop.n_vertices() < 3 => assert!(m.contains("at least 3 are needed"), "{m}"),
        Err(Error::Params(m)) if params.algorithm1.parts > pop.n_vertices() => {
            assert!(m.contains(&format!("parts = {}", params.algorithm1.parts)) && m.contains("vertices"), "{m}")
        }
        Err(Error::Data(m)) if all_shapes_same(pop) => assert!(m.contains("shapes are the same"), "{m}"),
        Err(e) => panic!("the fit refused a population it should fit: {e:?}"),
    }
}

/// Every shape is the first one, up to a translation (compared after centring, within the tolerance the fit
/// allows for the f32 storage of the coordinates, `posemfa::mfa::aecm::SAME_PLACE`).
fn all_shapes_same(pop: &Population) -> bool {
    let centroid = |s: &[[f64; 3]]| {
        let n = s.len() as f64;
        [0, 1, 2].map(|d| s.iter().map(|p| p[d]).sum::<f64>() / n)
    };
    let shapes: Vec<Vec<[f64; 3]>> = pop.shapes().map(|s| s.to_vec()).collect();
    let c0 = centroid(&shapes[0]);
    shapes[1..].iter().all(|s| {
        let c = centroid(s);
        s.iter()
            .zip(&shapes[0])
            .all(|(p, q)| (0..3).all(|d| ((p[d] - c[d]) - (q[d] - c0[d])).abs() <= posemfa::mfa::aecm::SAME_PLACE))
    })
}

pub use posemfa::fuzzing::check_mesh;

/// Lowers the memory budget of the readers and fits to 256 MiB (once per process), well under libFuzzer's
/// RSS limit, so that a file refused by the budget is an error and an allocation the budget does not cover
/// is an out-of-memory crash.
pub fn limit_memory() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| std::env::set_var("POSEMFA_MEMORY_BUDGET", "256M"));
}
