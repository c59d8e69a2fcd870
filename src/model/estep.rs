//! E-step: responsibilities γ_kj = P(k | h_j) (eq 12) and the log-likelihood (eq 10), in log space with
//! log-sum-exp (log-densities of different components differ by 1e5-1e8 nats).

use super::component::{Component, PackedShape, Woodbury};
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

/// Per component, the Woodbury constants of the first t shapes (t = 1..n_s), for the early-exit bound:
/// shrink_t[d] = λ_d² / (1 + w_t λ_d²), w_t = Σ_{i<t} 1/s_i.
fn prefix_shrinks(comps: &[Component]) -> Vec<Vec<[f64; 3]>> {
    comps
        .iter()
        .map(|c| {
            let mut w = 0.0;
            c.variances
                .iter()
                .map(|s| {
                    w += 1.0 / s;
                    c.lambda.map(|l| l * l / (1.0 + w * l * l))
                })
                .collect()
        })
        .collect()
}

/// Shapes after which the early-exit bound is checked.
const CHECK_AFTER: [usize; 4] = [1, 2, 4, 8];

/// Vertices per block of the streaming layout: the E-step's kernel runs over one block at a time with the
/// vertices in SIMD lanes (the reduction over shapes then needs no horizontal sums).
pub const LANES: usize = 4;

type Lanes = [f64; LANES];

/// The data vectors regrouped for the E-step: blocks of [`LANES`] vertices that are close in the first shape
/// (Morton order), stored structure-of-arrays, `h[(b * n_s + i) * 3 + c][l]` = coordinate c of vertex
/// `idx[b][l]` in shape i. The last block repeats its last vertex in the unused lanes (`valid[b]` are real).
/// Nearby vertices mostly belong to the same parts, so a block shares its pruning decisions.
#[derive(Debug, Clone)]
pub struct Blocked {
    n_shapes: usize,
    idx: Vec<[u32; LANES]>,
    valid: Vec<u8>,
    h: Vec<Lanes>,
}

impl Blocked {
    pub fn new(data: &Data) -> Blocked {
        let (nv, ns) = (data.n_vertices, data.n_shapes);
        let order = morton_order(data);
        let nb = nv.div_ceil(LANES);
        let mut idx = Vec::with_capacity(nb);
        let mut valid = Vec::with_capacity(nb);
        let mut h = vec![[0.0; LANES]; nb * ns * 3];
        for (b, chunk) in order.chunks(LANES).enumerate() {
            let mut ids = [0u32; LANES];
            for l in 0..LANES {
                let j = chunk[l.min(chunk.len() - 1)];
                ids[l] = j as u32;
                for (i, p) in data.vertex(j).iter().enumerate() {
                    for c in 0..3 {
                        h[(b * ns + i) * 3 + c][l] = p[c];
                    }
                }
            }
            idx.push(ids);
            valid.push(chunk.len() as u8);
        }
        Blocked { n_shapes: ns, idx, valid, h }
    }

    pub fn n_blocks(&self) -> usize {
        self.idx.len()
    }

    /// The block's data: n_s x 3 lane vectors.
    #[inline]
    fn block(&self, b: usize) -> &[Lanes] {
        &self.h[b * self.n_shapes * 3..(b + 1) * self.n_shapes * 3]
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.h.len() * std::mem::size_of::<Lanes>() + self.idx.len() * (std::mem::size_of::<[u32; LANES]>() + 1)
    }
}

/// Vertices sorted along a Z-order curve of their positions in the first shape (10 bits per axis).
fn morton_order(data: &Data) -> Vec<usize> {
    let nv = data.n_vertices;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for j in 0..nv {
        let p = data.vertex(j)[0];
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let spread = |x: u32| -> u64 {
        let mut v = 0u64;
        for bit in 0..10 {
            v |= (((x >> bit) & 1) as u64) << (3 * bit);
        }
        v
    };
    let mut keyed: Vec<(u64, usize)> = (0..nv)
        .map(|j| {
            let p = data.vertex(j)[0];
            let mut key = 0u64;
            for c in 0..3 {
                let w = hi[c] - lo[c];
                let t = if w > 0.0 && p[c].is_finite() { ((p[c] - lo[c]) / w * 1023.0).clamp(0.0, 1023.0) } else { 0.0 };
                key |= spread(t as u32) << c;
            }
            (key, j)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, j)| j).collect()
}

/// y and Σ|x|²/s of one block, accumulated over the shapes `packed` (and the matching `h`, 3 lane vectors per
/// shape): the E-step's kernel, the same arithmetic as [`super::component::project_packed`] with the vertices in lanes.
#[inline(always)]
fn accumulate_block(packed: &[PackedShape], h: &[Lanes], y: &mut [Lanes; 3], sq: &mut Lanes) {
    for (q, hi) in packed.iter().zip(h.chunks_exact(3)) {
        for l in 0..LANES {
            let x0 = hi[0][l] - q[0];
            let x1 = hi[1][l] - q[1];
            let x2 = hi[2][l] - q[2];
            sq[l] += (x0 * x0 + x1 * x1 + x2 * x2) * q[3];
            y[0][l] += q[4] * x0 + q[5] * x1 + q[6] * x2;
            y[1][l] += q[7] * x0 + q[8] * x1 + q[9] * x2;
            y[2][l] += q[10] * x0 + q[11] * x1 + q[12] * x2;
        }
    }
}

/// log_norm - q/2 with q = sq - Σ_d shrink_d y_d², per lane.
#[inline(always)]
fn log_density_lanes(log_norm: f64, shrink: &[f64; 3], y: &[Lanes; 3], sq: &Lanes) -> Lanes {
    let mut out = [0.0; LANES];
    for l in 0..LANES {
        let q = sq[l] - (shrink[0] * y[0][l] * y[0][l] + shrink[1] * y[1][l] * y[1][l] + shrink[2] * y[2][l] * y[2][l]);
        out[l] = log_norm - 0.5 * q;
    }
    out
}

/// Scratch space and layout of the pruned E-step, kept by a fit between iterations (nothing is allocated
/// per vertex or per block).
#[derive(Debug, Clone)]
pub struct EStep {
    blocked: Blocked,
    vals: Vec<Lanes>,
    is_hint: Vec<bool>,
}

impl EStep {
    pub fn new(data: &Data) -> EStep {
        EStep { blocked: Blocked::new(data), vals: Vec::new(), is_hint: Vec::new() }
    }

    pub fn blocked(&self) -> &Blocked {
        &self.blocked
    }

    /// The E-step with exact pruning, a block of [`LANES`] vertices at a time. In each block the components
    /// that were most responsible before (the argmax of each vertex's incoming `gamma` row, when it has the
    /// same number of components; else component 0) are evaluated first; every other component stops as soon
    /// as the bound below proves it more than [`PRUNE_MARGIN`] nats below the best one in every lane.
    ///
    /// The bound: (h-b)^T Σ^-1 (h-b) = min_z Σ_i |x_i - R_i Λ z|² / s_i + |z|², and dropping shapes from the
    /// sum can only lower the minimum, which is again a Woodbury form over the first t shapes. So
    /// log_norm - q_t / 2 bounds the log-density from above for every t.
    ///
    /// The result equals [`e_step`] to rounding. Returns (log-likelihood, shape evaluations done, counting
    /// every lane).
    pub fn run(&mut self, data: &Data, comps: &[Component], gamma: &mut Vec<f64>) -> (f64, usize) {
        let m = comps.len();
        let ns = data.n_shapes;
        debug_assert_eq!(ns, self.blocked.n_shapes);
        let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
        let shrinks = prefix_shrinks(comps);
        let have_hint = gamma.len() == data.n_vertices * m;
        if !have_hint {
            gamma.clear();
            gamma.resize(data.n_vertices * m, 0.0);
        }
        self.vals.clear();
        self.vals.resize(m, [f64::NEG_INFINITY; LANES]);
        self.is_hint.clear();
        self.is_hint.resize(m, false);
        let checks: Vec<usize> = CHECK_AFTER.iter().copied().filter(|&t| t < ns).collect();
        let mut ll = 0.0;
        let mut evals = 0usize;
        for b in 0..self.blocked.n_blocks() {
            let h = self.blocked.block(b);
            let ids = self.blocked.idx[b];
            let nvalid = self.blocked.valid[b] as usize;
            // the previous owners first
            let mut hints = [0usize; LANES];
            let mut n_hints = 0;
            for &j in ids.iter().take(nvalid) {
                let j = j as usize;
                let first = if have_hint {
                    let row = &gamma[j * m..(j + 1) * m];
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
                if !self.is_hint[first] {
                    self.is_hint[first] = true;
                    hints[n_hints] = first;
                    n_hints += 1;
                }
            }
            let mut best = [f64::NEG_INFINITY; LANES];
            for &k in &hints[..n_hints] {
                let mut y = [[0.0; LANES]; 3];
                let mut sq = [0.0; LANES];
                accumulate_block(&wbs[k].packed, h, &mut y, &mut sq);
                let v = log_density_lanes(wbs[k].log_norm, &wbs[k].shrink, &y, &sq);
                for l in 0..LANES {
                    best[l] = best[l].max(v[l]);
                }
                self.vals[k] = v;
                evals += ns * LANES;
            }
            // the others, each stopped early once negligible in every lane
            for k in 0..m {
                if self.is_hint[k] {
                    continue;
                }
                let wb = &wbs[k];
                let mut y = [[0.0; LANES]; 3];
                let mut sq = [0.0; LANES];
                let mut start = 0;
                let mut pruned = false;
                for &t in &checks {
                    accumulate_block(&wb.packed[start..t], &h[3 * start..3 * t], &mut y, &mut sq);
                    start = t;
                    let ub = log_density_lanes(wb.log_norm, &shrinks[k][t - 1], &y, &sq);
                    if (0..LANES).all(|l| ub[l] < best[l] - PRUNE_MARGIN) {
                        pruned = true;
                        break;
                    }
                }
                evals += start * LANES;
                if pruned {
                    self.vals[k] = [f64::NEG_INFINITY; LANES];
                    continue;
                }
                accumulate_block(&wb.packed[start..], &h[3 * start..], &mut y, &mut sq);
                evals += (ns - start) * LANES;
                let v = log_density_lanes(wb.log_norm, &wb.shrink, &y, &sq);
                for l in 0..LANES {
                    best[l] = best[l].max(v[l]);
                }
                self.vals[k] = v;
            }
            for &k in &hints[..n_hints] {
                self.is_hint[k] = false;
            }
            for (l, &j) in ids.iter().enumerate().take(nvalid) {
                let row = &mut gamma[j as usize * m..(j as usize + 1) * m];
                for k in 0..m {
                    row[k] = self.vals[k][l];
                }
                ll += normalise_log_row(row);
            }
        }
        (ll, evals)
    }
}

/// [`EStep::run`] with a fresh layout (tests and one-off calls; a fit keeps its [`EStep`]).
pub fn e_step_pruned(data: &Data, comps: &[Component], gamma: &mut Vec<f64>) -> (f64, usize) {
    EStep::new(data).run(data, comps, gamma)
}

/// Arithmetic rate of a kernel, measured.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct KernelRate {
    pub gflop: f64,
    pub ms: f64,
    pub gflops_per_s: f64,
}

/// The machine's limit for the E-step's arithmetic: the same kernel on the same layout ([`Blocked`], every
/// block x every component x every shape, no pruning, no bookkeeping, no exp), repeated for at least
/// `min_ms`. The real E-step's rate is compared with this.
pub fn kernel_limit(data: &Data, comps: &[Component], min_ms: f64) -> KernelRate {
    let blocked = Blocked::new(data);
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    let ns = data.n_shapes;
    let per_pass = (blocked.n_blocks() * LANES * comps.len()) as f64 * flops_per_pair(ns);
    let mut sink: Lanes = [f64::NEG_INFINITY; LANES];
    let t0 = crate::clock::now_ms();
    let mut passes = 0usize;
    loop {
        for b in 0..blocked.n_blocks() {
            let h = blocked.block(b);
            for wb in &wbs {
                let mut y = [[0.0; LANES]; 3];
                let mut sq = [0.0; LANES];
                accumulate_block(&wb.packed, h, &mut y, &mut sq);
                let v = log_density_lanes(wb.log_norm, &wb.shrink, &y, &sq);
                for l in 0..LANES {
                    sink[l] = sink[l].max(v[l]);
                }
            }
        }
        passes += 1;
        let ms = crate::clock::now_ms() - t0;
        if ms >= min_ms || passes >= 1000 {
            std::hint::black_box(sink);
            let gflop = per_pass * passes as f64 / 1e9;
            return KernelRate { gflop, ms, gflops_per_s: gflop / ms * 1e3 };
        }
    }
}

/// The same arithmetic one vertex at a time on the vertex-major layout ([`project_packed`]), for comparison.
pub fn kernel_rate_vertex_major(data: &Data, comps: &[Component], min_ms: f64) -> KernelRate {
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    let per_pass = (data.n_vertices * comps.len()) as f64 * flops_per_pair(data.n_shapes);
    let mut sink = 0.0f64;
    let t0 = crate::clock::now_ms();
    let mut passes = 0usize;
    loop {
        for j in 0..data.n_vertices {
            let h = data.vertex(j);
            for (c, wb) in comps.iter().zip(&wbs) {
                sink = sink.max(c.log_weighted_density(wb, h));
            }
        }
        passes += 1;
        let ms = crate::clock::now_ms() - t0;
        if ms >= min_ms || passes >= 1000 {
            std::hint::black_box(sink);
            let gflop = per_pass * passes as f64 / 1e9;
            return KernelRate { gflop, ms, gflops_per_s: gflop / ms * 1e3 };
        }
    }
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
