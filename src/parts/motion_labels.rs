//! Labels by rigid motion: every vertex goes to the part (its own or a part it shares a mesh edge with) whose
//! rigid motion moves it best, in the least-squares sense with one and the same variance for every part.
//!
//! Eq 20 labels a vertex by its responsibility, which weighs each part's residual by that part's own variance
//! s_k^i. Where two parts meet through soft flesh (a skinning blend band), the part with the larger variance
//! (usually the one whose own joints are softer, or the larger one) then takes more than its share of the
//! band: the boundary moves off the joint. With equal variances the boundary falls where the blend is half and
//! half, which is where the joint is. For vertex j and part k the residual is
//!
//!   r_k(j) = Σ_i |R_k^i^T (h_j^i - b_k^i) - ȳ|²,  ȳ = (1/n_s) Σ_i R_k^i^T (h_j^i - b_k^i),
//!
//! the spread of the vertex's back-transformed positions (the pose-to-pose variance of the latent image under
//! part k). Only the labels and the moved vertices' latent images (eq 21 under their new part) change; the
//! parts' motions stay.

use crate::mesh::Population;
use crate::mfa::result::Model;

/// The residual r_k(j) of vertex `h` (one point per shape) under a part's motion.
pub fn motion_residual(part: &crate::mfa::Component, h: &[[f64; 3]]) -> f64 {
    let ns = h.len();
    // the back-transformed points on the stack (no allocation per vertex and part) unless there are many shapes
    const ON_STACK: usize = 64;
    let mut stack = [[0.0; 3]; ON_STACK];
    let mut heap = Vec::new();
    let ys: &mut [[f64; 3]] = if ns <= ON_STACK {
        &mut stack[..ns]
    } else {
        heap.resize(ns, [0.0; 3]);
        &mut heap
    };
    for ((i, &p), slot) in h.iter().enumerate().zip(ys.iter_mut()) {
        *slot = part.unplace(i, p);
    }
    spread_about_mean(ys)
}

/// Σ_i |y_i - ȳ|² of the points `ys`, with ȳ summed as y_i / n in order (so [`motion_residual`] and its bound
/// add the same way).
fn spread_about_mean(ys: &[[f64; 3]]) -> f64 {
    let n = ys.len() as f64;
    let mut mean = [0.0; 3];
    for y in ys {
        for a in 0..3 {
            mean[a] += y[a] / n;
        }
    }
    ys.iter().map(|y| (0..3).map(|a| (y[a] - mean[a]).powi(2)).sum::<f64>()).sum()
}

/// A lower bound of [`motion_residual`] from the shapes in `some` alone (at most [`BOUND_SHAPES`]): their
/// back-transformed points' spread about their own mean, which is at most their spread about the mean of all,
/// at most the whole sum.
fn motion_residual_bound(part: &crate::mfa::Component, h: &[[f64; 3]], some: &[usize]) -> f64 {
    debug_assert!(some.len() <= BOUND_SHAPES);
    let mut ys = [[0.0; 3]; BOUND_SHAPES];
    for (&i, slot) in some.iter().zip(ys.iter_mut()) {
        *slot = part.unplace(i, h[i]);
    }
    spread_about_mean(&ys[..some.len()])
}

/// Most shapes [`label_by_motion`] bounds a neighbour's residual with before it works the residual out.
const BOUND_SHAPES: usize = 8;

/// Relabels every vertex by [`motion_residual`] among its own part and the parts adjacent to it on the mesh;
/// returns how many vertices moved. A neighbour whose residual on a few evenly spaced shapes alone
/// ([`motion_residual_bound`]) already reaches the best so far is passed over: the same labels, with most
/// neighbours judged on those shapes only (most of them: docs/decisions.md, "Figures behind src/parts").
pub fn label_by_motion(model: &mut Model, pop: &Population) -> usize {
    let m = model.n_parts();
    if m < 2 {
        return 0;
    }
    let (adjacent, _) = super::labels::adjacency(&model.labels, pop.graph_faces(), m);
    let mut moved = 0;
    let ns = pop.n_shapes();
    let mut h = vec![[0.0; 3]; ns];
    let some: Vec<usize> = (0..ns).step_by(ns.div_ceil(BOUND_SHAPES).max(1)).collect();
    for j in 0..model.n_vertices {
        let own = model.labels[j] as usize;
        if adjacent[own].is_empty() {
            continue;
        }
        for (i, s) in pop.shapes().enumerate() {
            h[i] = s.get(j);
        }
        let mut best = (own, motion_residual(&model.parts[own], &h));
        for &k in &adjacent[own] {
            // (a margin for the two sums' rounding)
            if some.len() < ns && motion_residual_bound(&model.parts[k], &h, &some) * (1.0 - 1e-9) >= best.1 {
                continue;
            }
            let r = motion_residual(&model.parts[k], &h);
            if r < best.1 {
                best = (k, r);
            }
        }
        if best.0 != own {
            model.labels[j] = best.0 as u32;
            model.latent[j] = model.parts[best.0].latent_image(&h);
            moved += 1;
        }
    }
    moved
}

/// Removes parts left without a vertex (relabelling can empty a small part): labels renumbered in part order,
/// mixing weights renormalised. Returns how many went.
pub fn drop_empty_parts(model: &mut Model) -> usize {
    let mut count = vec![0usize; model.n_parts()];
    for &l in &model.labels {
        count[l as usize] += 1;
    }
    if count.iter().all(|&c| c > 0) {
        return 0;
    }
    let mut new_id = vec![u32::MAX; count.len()];
    let mut next = 0u32;
    for (k, &c) in count.iter().enumerate() {
        if c > 0 {
            new_id[k] = next;
            next += 1;
        }
    }
    for l in model.labels.iter_mut() {
        *l = new_id[*l as usize];
    }
    let before = model.parts.len();
    let mut k = 0;
    model.parts.retain(|_| {
        k += 1;
        count[k - 1] > 0
    });
    let total: f64 = model.parts.iter().map(|c| c.weight).sum();
    for c in model.parts.iter_mut() {
        c.weight /= total.max(f64::MIN_POSITIVE);
    }
    before - model.parts.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;

    #[test]
    fn residual_is_zero_for_a_point_that_moves_with_the_part_and_grows_with_the_mismatch() {
        let ns = 4;
        let rots: Vec<_> = (0..ns).map(|i| axis_angle([0.0, 0.0, 1.0], 0.3 * i as f64)).collect();
        let part = crate::mfa::Component {
            rotations: rots.clone(),
            translations: (0..ns).map(|i| [0.1 * i as f64, 0.0, -0.2]).collect(),
            lambda: [0.1; 3],
            variances: vec![1e-4; ns],
            weight: 1.0,
        };
        let v = [0.3, -0.1, 0.2];
        let h: Vec<[f64; 3]> = (0..ns).map(|i| part.place(i, v)).collect();
        assert!(motion_residual(&part, &h) < 1e-24);
        let mut off = h.clone();
        off[2][0] += 0.01;
        let r = motion_residual(&part, &off);
        // one point displaced by 0.01: spread = 0.01² (1 - 1/ns)
        assert!((r - 1e-4 * (1.0 - 1.0 / ns as f64)).abs() < 1e-12, "{r}");
    }

    /// The bound label_by_motion passes neighbours over by never exceeds the residual, for any shapes taken,
    /// and equals it with every shape.
    #[test]
    fn the_bound_on_some_shapes_is_at_most_the_residual() {
        let ns = 13;
        let x = |k: usize| ((k as f64 * 12.9898).sin() * 43758.5453).fract();
        let part = crate::mfa::Component {
            rotations: (0..ns).map(|i| axis_angle([x(i), x(i + 50), 0.5], 2.0 * x(i + 100))).collect(),
            translations: (0..ns).map(|i| [x(i + 150), x(i + 200), x(i + 250)]).collect(),
            lambda: [0.1; 3],
            variances: vec![1e-4; ns],
            weight: 1.0,
        };
        for trial in 0..40 {
            let h: Vec<[f64; 3]> =
                (0..ns).map(|i| [x(300 + trial * 40 + i), x(900 + trial * 40 + i), x(1700 + trial * 40 + i)]).collect();
            let r = motion_residual(&part, &h);
            for stride in 2..=ns {
                let some: Vec<usize> = (trial % stride..ns).step_by(stride).take(BOUND_SHAPES).collect();
                assert!(motion_residual_bound(&part, &h, &some) <= r * (1.0 + 1e-12), "trial {trial}, shapes {some:?}");
            }
            let all: Vec<usize> = (0..BOUND_SHAPES).collect();
            let first: Vec<[f64; 3]> = h[..BOUND_SHAPES].to_vec();
            let whole = motion_residual(&part, &first);
            assert!((motion_residual_bound(&part, &first, &all) - whole).abs() <= 1e-12 * whole.max(1e-300));
        }
    }
}
