//! Multi-resolution Algorithm 1: the coarse and refinement stages run on a well-spread subset of the vertices,
//! their labels are carried to every vertex by the E-step of the stage's components on the whole population,
//! and the final AECM runs on all vertices (so the final model is a converged fit of the full data, at the
//! full data's tolerance).
//!
//! The subset ([`spread_subset`]): one vertex per occupied cell of a grid over the vertex's positions in two
//! shapes at once (the first shape, and the shape farthest from it), 6-dimensional cells, the cell size chosen
//! by bisection so that about `target` cells are occupied. Dense and sparse regions of the mesh get the same
//! density of samples, and two places that coincide in one shape but move apart in the other fall in different
//! cells, so a small part that moves on its own is sampled too.

use crate::mesh::Population;
use crate::mfa::aecm::labels_from_gamma;
use crate::mfa::aecm::Fit;
use crate::mfa::component::Component;
use crate::mfa::data::{to_frame, Data};
use crate::mfa::estep::e_step_pruned;
use crate::mfa::params::InFit;
use crate::mfa::result::Model;

/// Vertex ids (ascending) of about `target` well-spread vertices (see the module doc); all vertices when the
/// population has at most `target`.
pub fn spread_subset(pop: &Population, target: usize) -> Vec<usize> {
    let nv = pop.n_vertices();
    if target == 0 || nv <= target || pop.n_shapes() == 0 {
        return (0..nv).collect();
    }
    let first = pop.shape(0);
    // the shape farthest from the first (summed squared displacement)
    let far = (1..pop.n_shapes())
        .map(|i| {
            let d: f64 = pop
                .shape(i)
                .iter()
                .zip(first.iter())
                .map(|(p, q)| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2))
                .sum();
            (d, i)
        })
        .fold((f64::NEG_INFINITY, 0), |a, b| if b.0 > a.0 { b } else { a })
        .1;
    let second = pop.shape(far);
    let cells = |size: f64| -> Vec<(u64, usize)> {
        let q = |v: f64| ((v / size).floor() as i64 & 0x3ff) as u64;
        let mut keyed: Vec<(u64, usize)> = (0..nv)
            .map(|j| {
                let (a, b) = (first.get(j), second.get(j));
                let key = q(a[0]) | q(a[1]) << 10 | q(a[2]) << 20 | q(b[0]) << 30 | q(b[1]) << 40 | q(b[2]) << 50;
                (key, j)
            })
            .collect();
        keyed.sort_unstable();
        keyed.dedup_by_key(|e| e.0);
        keyed
    };
    // unit-box coordinates: 1 / 1023 (the finest cell the keys hold) to 1
    let (mut lo, mut hi) = (1.0 / 1023.0, 1.0);
    let mut best = cells(lo);
    if best.len() > target {
        // the most cells not above target
        best = cells(hi);
        for _ in 0..40 {
            let mid = (lo * hi).sqrt();
            let c = cells(mid);
            if c.len() > target {
                lo = mid;
            } else {
                hi = mid;
                best = c;
            }
            if hi / lo < 1.01 {
                break;
            }
        }
    }
    // one vertex per cell (the lowest id in it)
    let mut out: Vec<usize> = best.into_iter().map(|(_, j)| j).collect();
    out.sort_unstable();
    out
}

/// The labels of every vertex of `full` (argmax of the E-step) under `comps`, whose translations are in
/// unit-box coordinates (as in a [`crate::mfa::Model`]).
pub fn labels_everywhere(full: &Data, comps: &[Component]) -> Vec<u32> {
    let shifted = to_frame(full, comps);
    let mut gamma = Vec::new();
    e_step_pruned(full, &shifted, &mut gamma);
    labels_from_gamma(&gamma, shifted.len())
}

/// A stage's model of a subset carried to every vertex: its components (unit-box translations) with the
/// E-step on the whole population (labels, responsibilities, latent shape of all vertices); the trace,
/// iterations and convergence stay the subset run's.
pub fn model_everywhere(pop: &Population, sub: &Model, params: &impl InFit) -> Model {
    let full = Data::from_population(pop);
    let comps = to_frame(&full, &sub.parts);
    let mut model = Fit::from_components(full, comps, params).model();
    model.log_likelihood = sub.log_likelihood.clone();
    model.iterations = sub.iterations;
    model.converged = sub.converged;
    model
}

/// Labels of every vertex from labels given on the subset `subset` only (`labels[j]` for j in `subset`; the
/// rest are ignored): one component per label started from its subset vertices (per-part Procrustes, as the
/// final stage starts), then every vertex takes the label of its most responsible component.
pub fn extend_labels(pop: &Population, subset: &[usize], labels: &[u32], floor: f64) -> Vec<u32> {
    let full = Data::from_population(pop);
    let mut ids: Vec<u32> = subset.iter().map(|&j| labels[j]).collect();
    ids.sort_unstable();
    ids.dedup();
    let mut members = vec![Vec::new(); ids.len()];
    for &j in subset {
        let k = ids.binary_search(&labels[j]).expect("a label of the subset");
        members[k].push(j);
    }
    let comps: Vec<Component> =
        members.iter().map(|mem| crate::mfa::init::component_from_points(&full, mem, subset.len(), floor)).collect();
    let mut gamma = Vec::new();
    e_step_pruned(&full, &comps, &mut gamma);
    labels_from_gamma(&gamma, comps.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_subset_is_spread_and_about_the_size_asked() {
        // a dense cluster of 9000 vertices and a sparse one of 1000: both get samples
        let n = 10_000;
        let shapes: Vec<Vec<[f64; 3]>> = (0..2)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        let t = j as f64;
                        if j < 9000 {
                            [0.1 * (t * 0.37).sin().abs(), 0.1 * (t * 0.11).cos().abs(), 0.1 * (t * 0.07).sin().abs()]
                        } else {
                            [
                                0.5 + 0.5 * (t * 0.37).sin().abs(),
                                0.5 + 0.5 * (t * 0.11).cos().abs(),
                                0.5 * i as f64 * (t * 0.07).sin().abs(),
                            ]
                        }
                    })
                    .collect()
            })
            .collect();
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces: vec![[0, 1, 2]],
            shapes,
        })
        .unwrap();
        let s = spread_subset(&pop, 1000);
        assert!(s.len() >= 900 && s.len() <= 1000, "{}", s.len());
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        let sparse = s.iter().filter(|&&j| j >= 9000).count();
        // the sparse cluster is 10 % of the vertices and far larger in space: it gets most samples
        assert!(sparse > s.len() / 2, "{sparse} of {}", s.len());
        assert_eq!(spread_subset(&pop, 20_000).len(), n);
    }
}
