//! E-step: responsibilities γ_kj = P(k | h_j) (eq 12) and the log-likelihood (eq 10), in log space with
//! log-sum-exp (log-densities of different components differ by 1e5-1e8 nats).

use super::component::{project_packed, Component, Woodbury};
use super::data::Data;

/// Floating-point operations of one (vertex, component) log-density with n_s shapes, as counted in
/// [`log_densities`]: per shape 3 (x = h - b) + 6 (|x|²/s) + 18 (y += R^T x / s) + 1, plus 10 per pair.
pub fn flops_per_pair(n_shapes: usize) -> f64 {
    28.0 * n_shapes as f64 + 10.0
}

/// Log of π_k N(h_j | Θ_k) for one vertex and every component, written into `out` (len = comps.len()).
#[inline]
pub fn log_densities(h: &[[f64; 3]], comps: &[Component], wbs: &[Woodbury], out: &mut [f64]) {
    for (k, (c, wb)) in comps.iter().zip(wbs).enumerate() {
        out[k] = c.log_weighted_density(wb, h);
    }
}

/// Responsibilities into `gamma` (`gamma[j * m + k]`), returns the log-likelihood Σ_j log Σ_k π_k N(h_j|Θ_k).
pub fn e_step(data: &Data, comps: &[Component], gamma: &mut Vec<f64>) -> f64 {
    let m = comps.len();
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    gamma.clear();
    gamma.resize(data.n_vertices * m, 0.0);
    let mut ll = 0.0;
    for j in 0..data.n_vertices {
        let row = &mut gamma[j * m..(j + 1) * m];
        log_densities(data.vertex(j), comps, &wbs, row);
        ll += normalise_log_row(row);
    }
    ll
}

/// Components more than this many nats below a vertex's best one contribute less than e^-60 ≈ 1e-26 to
/// its responsibilities: below f64 rounding of their sum, so they are skipped.
pub const PRUNE_MARGIN: f64 = 60.0;

/// Per component, the Woodbury constants of the first t shapes (t = 1..n_s), for the early-exit bound.
struct Prefix {
    /// shrink_t[d] = λ_d² / (1 + w_t λ_d²), w_t = Σ_{i<t} 1/s_i
    shrink: Vec<[f64; 3]>,
    /// 1 / (s_0 + max_d λ_d²): with one shape the quadratic form is Σ_d (R_0^T x)_d² / (s_0 + λ_d²), so
    /// |x_0|² times this bounds it from below without the rotation.
    first_shape_gain: f64,
}

fn prefixes(comps: &[Component]) -> Vec<Prefix> {
    comps
        .iter()
        .map(|c| {
            let mut w = 0.0;
            let shrink = c
                .variances
                .iter()
                .map(|s| {
                    w += 1.0 / s;
                    c.lambda.map(|l| l * l / (1.0 + w * l * l))
                })
                .collect();
            let lmax = c.lambda.iter().fold(0.0f64, |a, &l| a.max(l * l));
            Prefix { shrink, first_shape_gain: 1.0 / (c.variances.first().copied().unwrap_or(1.0) + lmax) }
        })
        .collect()
}

/// Shapes after which the early-exit bound is checked.
const CHECK_AFTER: [usize; 4] = [1, 2, 4, 8]; // 1: the rotation-free check

/// log π_k N(h | Θ_k), or -inf as soon as a bound proves it is more than [`PRUNE_MARGIN`] below `best`.
///
/// The bound: (h-b)^T Σ^-1 (h-b) = min_z Σ_i |x_i - R_i Λ z|² / s_i + |z|², and dropping shapes from the sum
/// can only lower the minimum, which is again a Woodbury form over the first t shapes. So
/// log_norm - q_t / 2 is an upper bound of the log-density for every t; once it falls below best - margin
/// the component cannot matter. Returns (value, shapes evaluated).
#[inline]
fn bounded_log_density(c: &Component, wb: &Woodbury, pre: &Prefix, h: &[[f64; 3]], best: f64) -> (f64, usize) {
    let ns = h.len();
    if ns > 1 {
        // rotation-free check on the first shape (8 flops instead of 28)
        let b = c.translations[0];
        let x = [h[0][0] - b[0], h[0][1] - b[1], h[0][2] - b[2]];
        let q1 = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) * pre.first_shape_gain;
        if wb.log_norm - 0.5 * q1 < best - PRUNE_MARGIN {
            return (f64::NEG_INFINITY, 1);
        }
    }
    // shapes in blocks ending at the check points, each block through the packed kernel
    let mut y = [0.0; 3];
    let mut sq = 0.0;
    let mut start = 0;
    for &t in CHECK_AFTER.iter().skip(1) {
        if t >= ns {
            break;
        }
        let (dy, dsq) = project_packed(&wb.packed[start..t], &h[start..t]);
        y = [y[0] + dy[0], y[1] + dy[1], y[2] + dy[2]];
        sq += dsq;
        start = t;
        let sh = &pre.shrink[t - 1];
        let q = sq - (sh[0] * y[0] * y[0] + sh[1] * y[1] * y[1] + sh[2] * y[2] * y[2]);
        if wb.log_norm - 0.5 * q < best - PRUNE_MARGIN {
            return (f64::NEG_INFINITY, t);
        }
    }
    let (dy, dsq) = project_packed(&wb.packed[start..], &h[start..]);
    y = [y[0] + dy[0], y[1] + dy[1], y[2] + dy[2]];
    sq += dsq;
    let q = sq - (wb.shrink[0] * y[0] * y[0] + wb.shrink[1] * y[1] * y[1] + wb.shrink[2] * y[2] * y[2]);
    (wb.log_norm - 0.5 * q, ns)
}

/// The E-step with exact pruning: per vertex, the component that was most responsible before (the argmax
/// of the incoming `gamma` row, when it has the same number of components) is evaluated first, and every
/// other component stops as soon as the bound of [`bounded_log_density`] proves it negligible. The result
/// equals [`e_step`] to rounding. Returns (log-likelihood, shape evaluations done).
pub fn e_step_pruned(data: &Data, comps: &[Component], gamma: &mut Vec<f64>) -> (f64, usize) {
    let m = comps.len();
    let ns = data.n_shapes;
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    let pre = prefixes(comps);
    let have_hint = gamma.len() == data.n_vertices * m;
    if !have_hint {
        gamma.clear();
        gamma.resize(data.n_vertices * m, 0.0);
    }
    let mut ll = 0.0;
    let mut evals = 0usize;
    for j in 0..data.n_vertices {
        let h = data.vertex(j);
        let row = &mut gamma[j * m..(j + 1) * m];
        let first = if have_hint {
            let mut a = 0;
            for k in 1..m {
                if row[k] > row[a] {
                    a = k;
                }
            }
            a
        } else {
            0
        };
        let best0 = comps[first].log_weighted_density(&wbs[first], h);
        evals += ns;
        let mut best = best0;
        for k in 0..m {
            if k == first {
                continue;
            }
            let (v, n) = bounded_log_density(&comps[k], &wbs[k], &pre[k], h, best);
            evals += n;
            row[k] = v;
            if v > best {
                best = v;
            }
        }
        row[first] = best0;
        ll += normalise_log_row(row);
    }
    (ll, evals)
}

/// Turns a row of log-weights into probabilities in place; returns log Σ exp(row).
#[inline]
pub fn normalise_log_row(row: &mut [f64]) -> f64 {
    let mx = row.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    if !mx.is_finite() {
        // Every component gives zero density (or NaN): share the vertex evenly so nothing divides by zero.
        let u = 1.0 / row.len() as f64;
        row.iter_mut().for_each(|g| *g = u);
        return mx;
    }
    let mut s = 0.0;
    for g in row.iter_mut() {
        // far below the best: exactly 0 after rounding anyway; skipping exp avoids its slow underflow path
        *g = if *g < mx - 2.0 * PRUNE_MARGIN { 0.0 } else { (*g - mx).exp() };
        s += *g;
    }
    let inv = 1.0 / s;
    row.iter_mut().for_each(|g| *g *= inv);
    mx + s.ln()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;
    use crate::mesh::Population;

    #[test]
    fn vectorised_e_step_equals_direct_loop() {
        // three shapes, 40 vertices, 3 components
        let ns = 3;
        let nv = 40;
        let shapes: Vec<Vec<[f64; 3]>> = (0..ns)
            .map(|i| (0..nv).map(|j| {
                let t = j as f64 * 0.1 + i as f64;
                [t.sin(), (1.3 * t).cos(), 0.1 * t]
            }).collect())
            .collect();
        let pop = Population::from_unit_shapes((0..ns).map(|i| format!("{i}")).collect(), vec![[0, 1, 2]], shapes).unwrap();
        let data = Data::from_population(&pop);
        let comps: Vec<Component> = (0..3)
            .map(|k| Component {
                rotations: (0..ns).map(|i| axis_angle([1.0, k as f64, i as f64], 0.3 * (i + k) as f64)).collect(),
                translations: (0..ns).map(|i| [0.1 * k as f64, -0.05 * i as f64, 0.0]).collect(),
                lambda: [0.3, 0.2, 0.1],
                variances: (0..ns).map(|i| 0.01 + 0.01 * (i + k) as f64).collect(),
                weight: [0.2, 0.3, 0.5][k],
            })
            .collect();
        let mut gamma = Vec::new();
        let ll = e_step(&data, &comps, &mut gamma);
        // direct: plain probabilities without log-sum-exp (values are moderate here)
        let mut ll_direct = 0.0;
        for j in 0..nv {
            let h: Vec<[f64; 3]> = (0..ns).map(|i| data.vertex(j)[i]).collect();
            let p: Vec<f64> = comps.iter().map(|c| c.log_weighted_density(&c.woodbury(), &h).exp()).collect();
            let s: f64 = p.iter().sum();
            ll_direct += s.ln();
            for k in 0..3 {
                assert!((gamma[j * 3 + k] - p[k] / s).abs() < 1e-12);
            }
        }
        assert!((ll - ll_direct).abs() < 1e-9 * ll.abs().max(1.0), "{ll} vs {ll_direct}");
    }
}
