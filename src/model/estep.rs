//! E-step: responsibilities γ_kj = P(k | h_j) (eq 12) and the log-likelihood (eq 10), in log space with
//! log-sum-exp (log-densities of different components differ by 1e5-1e8 nats).

use super::component::{Component, Woodbury};
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
/// its responsibilities: below f64 rounding of the sum. They are skipped until the next full E-step.
pub const ACTIVE_MARGIN: f64 = 60.0;

/// For every vertex, the components within [`ACTIVE_MARGIN`] nats of its best one at the last full E-step
/// (compressed rows: `idx[ptr[j]..ptr[j+1]]`).
#[derive(Debug, Clone, Default)]
pub struct ActiveSets {
    pub ptr: Vec<u32>,
    pub idx: Vec<u32>,
}

impl ActiveSets {
    pub fn pairs(&self) -> usize {
        self.idx.len()
    }
}

/// Full E-step that also records, per vertex, which components are within the margin.
pub fn e_step_full(data: &Data, comps: &[Component], gamma: &mut Vec<f64>, active: &mut ActiveSets) -> f64 {
    let m = comps.len();
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    gamma.clear();
    gamma.resize(data.n_vertices * m, 0.0);
    active.ptr.clear();
    active.idx.clear();
    active.ptr.push(0);
    let mut ll = 0.0;
    for j in 0..data.n_vertices {
        let row = &mut gamma[j * m..(j + 1) * m];
        log_densities(data.vertex(j), comps, &wbs, row);
        let mx = row.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        for (k, &v) in row.iter().enumerate() {
            if v >= mx - ACTIVE_MARGIN || !mx.is_finite() {
                active.idx.push(k as u32);
            }
        }
        active.ptr.push(active.idx.len() as u32);
        ll += normalise_log_row(row);
    }
    ll
}

/// E-step over the active sets only (the other responsibilities are set to 0).
pub fn e_step_active(data: &Data, comps: &[Component], gamma: &mut [f64], active: &ActiveSets) -> f64 {
    let m = comps.len();
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    let mut buf = vec![0.0; m];
    let mut ll = 0.0;
    for j in 0..data.n_vertices {
        let ks = &active.idx[active.ptr[j] as usize..active.ptr[j + 1] as usize];
        let h = data.vertex(j);
        let b = &mut buf[..ks.len()];
        for (slot, &k) in b.iter_mut().zip(ks) {
            let k = k as usize;
            *slot = comps[k].log_weighted_density(&wbs[k], h);
        }
        ll += normalise_log_row(b);
        let row = &mut gamma[j * m..(j + 1) * m];
        row.iter_mut().for_each(|g| *g = 0.0);
        for (&g, &k) in b.iter().zip(ks) {
            row[k as usize] = g;
        }
    }
    ll
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
        *g = if *g < mx - 2.0 * ACTIVE_MARGIN { 0.0 } else { (*g - mx).exp() };
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
