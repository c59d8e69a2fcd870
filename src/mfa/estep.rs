//! E-step: responsibilities γ_kj = P(k | h_j) (eq 12) and the log-likelihood (eq 10), in log space with
//! log-sum-exp (log-densities of different components differ by 1e5-1e8 nats).

use super::cm::{Member, Members, GAMMA_SKIP};
use super::component::{Component, Woodbury};
use super::data::{Data, Layout};

/// Floating-point operations per (vertex, shape) of the kernel: 3 (x = h - b) + 6 (|x|²/s) + 18
/// (y += R^T x / s) + 1.
pub const FLOPS_PER_SHAPE: usize = 28;
/// Per vertex, one log-density from y and Σ|x|²/s (6 + 2 + 1 + 2), a bound or a final value.
pub const FLOPS_PER_BOUND: usize = 11;
/// Per vertex, one check of the f32 screen (8 for the Woodbury term, 4 for the lower bound, 3 for the threshold).
pub const FLOPS_PER_SCREEN_CHECK: usize = 15;

/// Floating-point operations of one (vertex, component) log-density with n_s shapes.
pub fn flops_per_pair(n_shapes: usize) -> f64 {
    (FLOPS_PER_SHAPE * n_shapes + FLOPS_PER_BOUND) as f64
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
    let mut h = Vec::new();
    for j in 0..data.n_vertices {
        let row = &mut gamma[j * m..(j + 1) * m];
        log_densities(data.vertex_into(j, &mut h), comps, &wbs, row);
        ll += normalise_log_row(row);
    }
    ll
}

/// Components more than this many nats below a vertex's best one contribute less than e^-60 ≈ 1e-26 to
/// its responsibilities: below f64 rounding of their sum, so they are skipped.
pub const PRUNE_MARGIN: f64 = 60.0;

/// Per component, the Woodbury constants of the first t shapes in `order` (t = 1..n_s), for the early-exit
/// bound: shrink_t[d] = λ_d² / (1 + w_t λ_d²), w_t = Σ_{i<t} 1/s_order[i].
fn prefix_shrinks(comps: &[Component], order: &[usize]) -> Vec<Vec<[f64; 3]>> {
    comps
        .iter()
        .map(|c| {
            let mut w = 0.0;
            order
                .iter()
                .map(|&i| {
                    w += 1.0 / c.variances[i];
                    c.lambda.map(|l| l * l / (1.0 + w * l * l))
                })
                .collect()
        })
        .collect()
}

/// Woodbury constants with the packed per-shape constants in the order `order` (that of [`Blocked`]).
pub(crate) fn ordered_woodbury(comps: &[Component], order: &[usize]) -> Vec<Woodbury> {
    comps
        .iter()
        .map(|c| {
            let mut wb = c.woodbury();
            wb.packed = order.iter().map(|&i| wb.packed[i]).collect();
            wb
        })
        .collect()
}

/// Shapes after which the early-exit bound is checked in f64 (after the f32 screen).
pub(crate) const CHECK_AFTER: [usize; 2] = [4, 8];

/// Shapes of the first early-exit check, done in f32 (twice the SIMD lanes of f64) with a rigorous slack.
const SCREEN_SHAPES: usize = 2;

/// Relative error allowed for the f32 screen's quadratic form (f32 rounds at 6e-8; about 20 operations per
/// value), and its absolute error per shape from rounding coordinates near 1 to f32, times s_min (see
/// [`EStep::run`]).
const SCREEN_REL: f32 = 1e-4;
const SCREEN_ABS_S: f64 = 5e-8;

/// Blocks per group of the group bound ([`EStep::run`]): 16 vertices close in the first shape.
const GROUP_BLOCKS: usize = 4;
/// Shapes the group bound looks at (the first ones of the farthest-first order).
const GROUP_SHAPES: usize = 8;

/// Vertices per block of the streaming layout: the E-step's kernel runs over one block at a time with the
/// vertices in SIMD lanes (the reduction over shapes then needs no horizontal sums).
pub const LANES: usize = 4;

pub type Lanes = [f64; LANES];

/// What the E-step needs besides the data's own [`Layout`] (which it shares: the data are stored once, in
/// that layout): the shapes the f32 screen reads (the first ones of every block, as stored) and the group
/// bound's centres and radii.
#[derive(Debug, Clone)]
pub struct Blocked {
    n_shapes: usize,
    layout: std::sync::Arc<Layout>,
    /// Shapes the f32 screen reads: the first ones of every block.
    screen: usize,
    /// Groups of [`GROUP_BLOCKS`] consecutive blocks: per group, the centre of its vertices in each of the
    /// first `group_shapes` shapes (in `order`), `centres[g * group_shapes + t]`, and the squared radius of the
    /// group around it in that shape, `radii2[g * group_shapes + t]` (largest over the group's vertices).
    centres: Vec<[f64; 3]>,
    radii2: Vec<f64>,
    group_shapes: usize,
}

impl Blocked {
    pub fn new(data: &Data) -> Blocked {
        let ns = data.n_shapes;
        let layout = data.layout.clone();
        let h = &layout.h;
        let nb = layout.n_blocks();
        let screen = if ns > SCREEN_SHAPES { SCREEN_SHAPES } else { 0 };
        let group_shapes = ns.min(GROUP_SHAPES);
        let ng = nb.div_ceil(GROUP_BLOCKS);
        let mut centres = vec![[0.0; 3]; ng * group_shapes];
        let mut radii2 = vec![0.0; ng * group_shapes];
        for g in 0..ng {
            let blocks = g * GROUP_BLOCKS..((g + 1) * GROUP_BLOCKS).min(nb);
            for t in 0..group_shapes {
                let lanes = || blocks.clone().flat_map(|b| (0..LANES).map(move |l| (b, l)));
                let mut c = [0.0; 3];
                let n = (blocks.len() * LANES) as f64;
                for (b, l) in lanes() {
                    for d in 0..3 {
                        c[d] += h[(b * ns + t) * 3 + d][l] as f64 / n;
                    }
                }
                let mut r2 = 0.0f64;
                for (b, l) in lanes() {
                    let e: f64 = (0..3).map(|d| (h[(b * ns + t) * 3 + d][l] as f64 - c[d]).powi(2)).sum();
                    r2 = r2.max(e);
                }
                centres[g * group_shapes + t] = c;
                radii2[g * group_shapes + t] = r2;
            }
        }
        Blocked { n_shapes: ns, layout, screen, centres, radii2, group_shapes }
    }

    pub fn n_blocks(&self) -> usize {
        self.layout.n_blocks()
    }

    /// The block's data: n_s x 3 lane vectors.
    #[inline]
    fn block(&self, b: usize) -> &[[f32; LANES]] {
        &self.layout.h[b * self.n_shapes * 3..(b + 1) * self.n_shapes * 3]
    }

    /// The block's first [`Blocked::screen`] shapes.
    #[inline]
    fn block32(&self, b: usize) -> &[[f32; LANES]] {
        &self.layout.h[b * self.n_shapes * 3..b * self.n_shapes * 3 + self.screen * 3]
    }
}

/// The arithmetic of the kernel: f64, and f32 for the screening pass.
pub trait Real:
    Copy + std::ops::Add<Output = Self> + std::ops::Sub<Output = Self> + std::ops::Mul<Output = Self> + std::ops::AddAssign
{
}
impl Real for f64 {}
impl Real for f32 {}

/// y and Σ|x|²/s of one block, accumulated over the shapes `packed` (and the matching `h`, 3 lane vectors per
/// shape, f32 widened to `T`): the E-step's kernel, the same arithmetic as [`super::component::project_packed`]
/// with the vertices in lanes.
#[inline(always)]
fn accumulate_block<T: Real + From<f32>>(
    packed: &[[T; 13]],
    h: &[[f32; LANES]],
    y: &mut [[T; LANES]; 3],
    sq: &mut [T; LANES],
) {
    for (q, hi) in packed.iter().zip(h.chunks_exact(3)) {
        for l in 0..LANES {
            let x0 = T::from(hi[0][l]) - q[0];
            let x1 = T::from(hi[1][l]) - q[1];
            let x2 = T::from(hi[2][l]) - q[2];
            sq[l] += (x0 * x0 + x1 * x1 + x2 * x2) * q[3];
            y[0][l] += q[4] * x0 + q[5] * x1 + q[6] * x2;
            y[1][l] += q[7] * x0 + q[8] * x1 + q[9] * x2;
            y[2][l] += q[10] * x0 + q[11] * x1 + q[12] * x2;
        }
    }
}

avx2_fn! {
    /// [`accumulate_block`] in f64, as a function of its own: the E-step calls it for every evaluation it keeps
    /// (the owners', the f64 checks' and the survivors' shapes). Kept out of [`EStep::run`]'s body so that it is
    /// compiled as the small loop it is (in wasm the engine allocates its registers as in [`kernel_pass`], the
    /// limit it is compared with, instead of within the whole E-step).
    #[inline(never)]
    pub(crate) fn accumulate_block_f64(packed: &[[f64; 13]], h: &[[f32; LANES]], y: &mut [Lanes; 3], sq: &mut Lanes) {
        accumulate_block(packed, h, y, sq);
    }
}

/// The smallest lane by comparisons (`f64::min` is a call to `fmax`/`fmin` in wasm); the best values it is
/// used on are never NaN (they start at -inf and only grow by `>`).
#[inline(always)]
fn lanes_min(v: &Lanes) -> f64 {
    let mut a = f64::INFINITY;
    for &x in v {
        if x < a {
            a = x;
        }
    }
    a
}

/// log_norm - q/2 with q = sq - Σ_d shrink_d y_d², per lane.
#[inline(always)]
pub(crate) fn log_density_lanes(log_norm: f64, shrink: &[f64; 3], y: &[Lanes; 3], sq: &Lanes) -> Lanes {
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
    /// y = Σ_i R_i^T x_i / s_i per component and lane (E[z|h] = post_gain y), kept for cycle 2.
    ys: Vec<[Lanes; 3]>,
    is_hint: Vec<bool>,
    alive: Vec<usize>,
    /// Per component, the packed constants of the screened shapes in f32, and the screen's constants.
    packed32: Vec<[f32; 13]>,
    screen: Vec<Screen>,
    /// Per component, an upper bound of its log-density over the current group of blocks.
    group_bound: Vec<f64>,
    /// The group bound's constants with the components in lanes ([`GroupConsts`]).
    group_consts: Vec<GroupConsts>,
    /// Floating-point operations of the last run: in f64 (shape evaluations, bounds and final densities) and
    /// in f32 (the screen and its checks).
    pub flops_f64: f64,
    pub flops_f32: f64,
    /// Most responsible component of every vertex after the last run, for `owner_parts` components.
    owner: Vec<u32>,
    owner_parts: usize,
}

impl EStep {
    pub fn new(data: &Data) -> EStep {
        EStep::with_layout(Blocked::new(data))
    }

    /// An E-step on data already laid out (`Blocked::new` of the same data: it depends on nothing else, so one
    /// layout serves every run on the same vertices).
    pub fn with_layout(blocked: Blocked) -> EStep {
        EStep {
            blocked,
            vals: Vec::new(),
            ys: Vec::new(),
            is_hint: Vec::new(),
            alive: Vec::new(),
            packed32: Vec::new(),
            screen: Vec::new(),
            group_bound: Vec::new(),
            group_consts: Vec::new(),
            flops_f64: 0.0,
            flops_f32: 0.0,
            owner: Vec::new(),
            owner_parts: 0,
        }
    }

    /// The layout it runs on.
    pub fn into_layout(self) -> Blocked {
        self.blocked
    }

    /// Forgets the previous owners (the components were renumbered).
    pub fn forget_owners(&mut self) {
        self.owner_parts = 0;
    }

    /// Takes `labels` (one per vertex, each below `m`) as the owners to evaluate first.
    pub fn set_owner_labels(&mut self, labels: &[u32], m: usize) {
        if m == 0 || labels.iter().any(|&l| l as usize >= m) {
            return;
        }
        self.owner = labels.to_vec();
        self.owner_parts = m;
    }

    /// Takes each vertex's most responsible component in a dense matrix `gamma[j * m + k]` as its owner.
    pub fn set_owners(&mut self, gamma: &[f64], m: usize) {
        if m == 0 || gamma.len() % m != 0 {
            return;
        }
        self.owner = gamma.chunks_exact(m).map(|row| argmax(row) as u32).collect();
        self.owner_parts = m;
    }

    /// The E-step with exact pruning, a block of [`LANES`] vertices at a time. In each block the components
    /// that were most responsible before (each vertex's previous owner: from the last run, else the argmax of
    /// its incoming `gamma` row when that has the same number of components, else component 0) are evaluated
    /// first; every other component stops as soon as the bound below proves it more than [`PRUNE_MARGIN`]
    /// nats below the best one in every lane.
    ///
    /// The bound: (h-b)^T Σ^-1 (h-b) = min_z Σ_i |x_i - R_i Λ z|² / s_i + |z|², and dropping shapes from the
    /// sum can only lower the minimum, which is again a Woodbury form over the first t shapes. So
    /// log_norm - q_t / 2 bounds the log-density from above for every t.
    ///
    /// Writes the responsibilities into `members`, sparsely (every γ >= [`GAMMA_SKIP`]; the rest are below
    /// rounding of the CM sums). The result equals [`e_step`] to rounding. Returns (log-likelihood, shape
    /// evaluations done, counting every lane).
    pub fn run(&mut self, data: &Data, comps: &[Component], members: &mut Members) -> (f64, usize) {
        let m = comps.len();
        let ns = data.n_shapes;
        let nv = data.n_vertices;
        debug_assert_eq!(ns, self.blocked.n_shapes);
        if m == 0 {
            members.clear();
            return (f64::NEG_INFINITY, 0);
        }
        let wbs = ordered_woodbury(comps, &self.blocked.layout.order);
        let shrinks = prefix_shrinks(comps, &self.blocked.layout.order);
        if self.owner_parts != m || self.owner.len() != nv {
            self.owner.clear();
            self.owner.resize(nv, 0);
        }
        members.resize_with(m, Vec::new);
        members.truncate(m);
        members.iter_mut().for_each(|l| l.clear());
        self.vals.clear();
        self.vals.resize(m, [f64::NEG_INFINITY; LANES]);
        self.ys.clear();
        self.ys.resize(m, [[0.0; LANES]; 3]);
        self.is_hint.clear();
        self.is_hint.resize(m, false);
        let checks: Vec<usize> = CHECK_AFTER.iter().copied().filter(|&t| t < ns).collect();
        let ts = self.blocked.screen;
        self.packed32.clear();
        self.screen.clear();
        if ts > 0 {
            for (k, wb) in wbs.iter().enumerate() {
                self.packed32.extend(wb.packed[..ts].iter().map(|q| q.map(|v| v as f32)));
                let s_min = self.blocked.layout.order[..ts]
                    .iter()
                    .map(|&i| comps[k].variances[i])
                    .fold(f64::INFINITY, f64::min);
                self.screen.push(Screen {
                    shrink: shrinks[k][ts - 1].map(|v| v as f32),
                    abs: (ts as f64 * (1.0 + SCREEN_ABS_S / s_min)) as f32,
                    thr_base: 2.0 * (wb.log_norm + PRUNE_MARGIN),
                });
            }
        }
        let mut ll = 0.0;
        let mut evals = 0usize;
        let mut screen_evals = 0usize;
        let mut bounds = 0usize; // lanes x log-density evaluations (checks and final values), f64
        let mut screens = 0usize; // lanes x screen checks, f32
        let gs = self.blocked.group_shapes;
        self.group_bound.clear();
        self.group_bound.resize(m.next_multiple_of(LANES), f64::INFINITY);
        self.group_consts.clear();
        if gs > 0 {
            self.group_consts.extend(
                (0..m).step_by(LANES).map(|k0| GroupConsts::new(&wbs[k0..(k0 + LANES).min(m)], &shrinks[k0..], gs)),
            );
        }
        for b in 0..self.blocked.n_blocks() {
            if b % GROUP_BLOCKS == 0 && gs > 0 {
                // the group bound of every component for the next GROUP_BLOCKS blocks
                let g = b / GROUP_BLOCKS;
                let centre = &self.blocked.centres[g * gs..(g + 1) * gs];
                let radii2 = &self.blocked.radii2[g * gs..(g + 1) * gs];
                for (gc, out) in self.group_consts.iter().zip(self.group_bound.chunks_exact_mut(LANES)) {
                    out.copy_from_slice(&group_upper_bounds(gc, centre, radii2));
                }
                evals += gs * m;
                bounds += m;
            }
            let h = self.blocked.block(b);
            let h32 = self.blocked.block32(b);
            let ids = self.blocked.layout.idx[b];
            let nvalid = self.blocked.layout.valid[b] as usize;
            self.alive.clear();
            // the previous owners first
            let mut best = [f64::NEG_INFINITY; LANES];
            for &j in ids.iter().take(nvalid) {
                let k = (self.owner[j as usize] as usize).min(m - 1);
                if self.is_hint[k] {
                    continue;
                }
                self.is_hint[k] = true;
                self.alive.push(k);
                let mut y = [[0.0; LANES]; 3];
                let mut sq = [0.0; LANES];
                accumulate_block_f64(&wbs[k].packed, h, &mut y, &mut sq);
                let v = log_density_lanes(wbs[k].log_norm, &wbs[k].shrink, &y, &sq);
                bounds += LANES;
                for l in 0..LANES {
                    if v[l] > best[l] {
                        best[l] = v[l];
                    }
                }
                self.vals[k] = v;
                self.ys[k] = y;
                evals += ns * LANES;
            }
            // the others, each stopped early once negligible in every lane
            let mut best_min = lanes_min(&best);
            for k in 0..m {
                if self.is_hint[k] {
                    continue;
                }
                // the whole group is far from this component (NaN never prunes)
                if self.group_bound[k] < best_min - PRUNE_MARGIN {
                    continue;
                }
                let wb = &wbs[k];
                if ts > 0 {
                    evals += ts * LANES;
                    screen_evals += ts * LANES;
                    screens += LANES;
                    if screened_out(
                        &self.packed32[k * ts..(k + 1) * ts],
                        h32,
                        &self.screen[k],
                        threshold(&self.screen[k], best_min),
                    ) {
                        continue;
                    }
                }
                let mut y = [[0.0; LANES]; 3];
                let mut sq = [0.0; LANES];
                let mut start = 0;
                let mut pruned = false;
                for &t in &checks {
                    accumulate_block_f64(&wb.packed[start..t], &h[3 * start..3 * t], &mut y, &mut sq);
                    start = t;
                    let ub = log_density_lanes(wb.log_norm, &shrinks[k][t - 1], &y, &sq);
                    bounds += LANES;
                    if (0..LANES).all(|l| ub[l] < best[l] - PRUNE_MARGIN) {
                        pruned = true;
                        break;
                    }
                }
                evals += start * LANES;
                if pruned {
                    continue;
                }
                accumulate_block_f64(&wb.packed[start..], &h[3 * start..], &mut y, &mut sq);
                evals += (ns - start) * LANES;
                let v = log_density_lanes(wb.log_norm, &wb.shrink, &y, &sq);
                bounds += LANES;
                for l in 0..LANES {
                    if v[l] > best[l] {
                        best[l] = v[l];
                    }
                }
                best_min = lanes_min(&best);
                self.vals[k] = v;
                self.ys[k] = y;
                self.alive.push(k);
            }
            for &k in &self.alive {
                self.is_hint[k] = false;
            }
            // normalise over the components still alive (the pruned ones are exactly 0 after rounding)
            for (l, &j) in ids.iter().enumerate().take(nvalid) {
                let j = j as usize;
                let mx = best[l];
                if !mx.is_finite() {
                    // no component gives this vertex a density (or NaN): share it evenly, nothing divides by 0
                    let u = 1.0 / m as f64;
                    for (c, list) in comps.iter().zip(members.iter_mut()) {
                        let (y, _) = super::component::project_packed(&c.woodbury().packed, &data.vertex(j).to_vec());
                        list.push(Member { j: j as u32, g: u, y });
                    }
                    self.owner[j] = 0;
                    ll += mx;
                    continue;
                }
                let mut s = 0.0;
                let mut top = self.alive[0];
                for &k in &self.alive {
                    let v = self.vals[k][l];
                    // exp(0) = 1 exactly, and far below the best is 0 after rounding: only the rest need exp
                    let e = if v == mx {
                        1.0
                    } else if v < mx - 2.0 * PRUNE_MARGIN {
                        0.0
                    } else {
                        (v - mx).exp()
                    };
                    self.vals[k][l] = e;
                    s += e;
                    if v == mx {
                        top = k;
                    }
                }
                let inv = 1.0 / s;
                for &k in &self.alive {
                    let g = self.vals[k][l] * inv;
                    if g >= GAMMA_SKIP {
                        let y = &self.ys[k];
                        members[k].push(Member { j: j as u32, g, y: [y[0][l], y[1][l], y[2][l]] });
                    }
                }
                self.owner[j] = top as u32;
                ll += if s == 1.0 { mx } else { mx + s.ln() };
            }
            for &k in &self.alive {
                self.vals[k] = [f64::NEG_INFINITY; LANES];
            }
        }
        self.owner_parts = m;
        self.flops_f64 = (FLOPS_PER_SHAPE * (evals - screen_evals) + FLOPS_PER_BOUND * bounds) as f64;
        self.flops_f32 = (FLOPS_PER_SHAPE * screen_evals + FLOPS_PER_SCREEN_CHECK * screens) as f64;
        (ll, evals)
    }
}

/// An upper bound of a component's log-density over every vertex of a group (a ball of radius ρ_t around the
/// centre c_t in each of the first T shapes), from one evaluation at the centre.
///
/// With x = h - b over the first T shapes, the prefix quadratic form q_T(h) = x^T P x, P = D - D A (I + A^T D A)^-1
/// A^T D with D = diag(1/s_t) (the Woodbury form over T shapes, see [`EStep::run`]), is the square of a seminorm,
/// and P <= D. So for every h of the group, by the triangle inequality,
/// sqrt q_T(h) >= sqrt q_T(c) - |h - c|_P >= sqrt q_T(c) - R,  R² = Σ_t ρ_t² / s_t,
/// and log π N(h) <= log_norm - q_T(h) / 2 <= log_norm - max(0, sqrt q_T(c) - R)² / 2. Rounding: q_T(c) is a
/// difference of two sums of at most sq = Σ |x_t|²/s_t, each rounded at 1e-16 relative; 1e-12 sq is taken off
/// it and R is taken 1e-12 larger.
#[cfg(test)]
fn group_upper_bound(wb: &Woodbury, shrink: &[f64; 3], centre: &[[f64; 3]], radii2: &[f64]) -> f64 {
    let t = centre.len();
    let (y, sq) = super::component::project_packed(&wb.packed[..t], centre);
    let q = sq - (shrink[0] * y[0] * y[0] + shrink[1] * y[1] * y[1] + shrink[2] * y[2] * y[2]);
    let q_low = (q - 1e-12 * sq).max(0.0);
    let r2: f64 = wb.packed[..t].iter().zip(radii2).map(|(p, r2)| r2 * p[3]).sum();
    let gap = (q_low.sqrt() - r2.sqrt() * (1.0 + 1e-12)).max(0.0);
    wb.log_norm - 0.5 * gap * gap
}

/// The constants of [`group_upper_bound`] for [`LANES`] components at once, one component per lane (the last
/// component repeated in unused lanes), so that the group bound runs with the components in SIMD lanes.
#[derive(Debug, Clone)]
struct GroupConsts {
    /// Per shape of the group bound, the packed constants ([`super::component::PackedShape`]) by lane.
    packed: Vec<[Lanes; 13]>,
    shrink: [Lanes; 3],
    log_norm: Lanes,
}

impl GroupConsts {
    /// `wbs` (1 to [`LANES`] components) and their prefix shrinks; `gs` shapes.
    fn new(wbs: &[Woodbury], shrinks: &[Vec<[f64; 3]>], gs: usize) -> GroupConsts {
        let k = |l: usize| l.min(wbs.len() - 1);
        GroupConsts {
            packed: (0..gs).map(|t| std::array::from_fn(|e| std::array::from_fn(|l| wbs[k(l)].packed[t][e]))).collect(),
            shrink: std::array::from_fn(|d| std::array::from_fn(|l| shrinks[k(l)][gs - 1][d])),
            log_norm: std::array::from_fn(|l| wbs[k(l)].log_norm),
        }
    }
}

/// [`group_upper_bound`] for the components of `gc`, one per lane: the same arithmetic in the same order, so
/// the same values.
#[inline]
fn group_upper_bounds(gc: &GroupConsts, centre: &[[f64; 3]], radii2: &[f64]) -> Lanes {
    let mut y = [[0.0; LANES]; 3];
    let mut sq = [0.0; LANES];
    let mut r2 = [0.0; LANES];
    for (q, (p, &rr)) in gc.packed.iter().zip(centre.iter().zip(radii2)) {
        for l in 0..LANES {
            let x0 = p[0] - q[0][l];
            let x1 = p[1] - q[1][l];
            let x2 = p[2] - q[2][l];
            sq[l] += (x0 * x0 + x1 * x1 + x2 * x2) * q[3][l];
            y[0][l] += q[4][l] * x0 + q[5][l] * x1 + q[6][l] * x2;
            y[1][l] += q[7][l] * x0 + q[8][l] * x1 + q[9][l] * x2;
            y[2][l] += q[10][l] * x0 + q[11][l] * x1 + q[12][l] * x2;
            r2[l] += rr * q[3][l];
        }
    }
    let mut out = [0.0; LANES];
    for l in 0..LANES {
        let sh = [gc.shrink[0][l], gc.shrink[1][l], gc.shrink[2][l]];
        let q = sq[l] - (sh[0] * y[0][l] * y[0][l] + sh[1] * y[1][l] * y[1][l] + sh[2] * y[2][l] * y[2][l]);
        let q_low = (q - 1e-12 * sq[l]).max(0.0);
        let gap = (q_low.sqrt() - r2[l].sqrt() * (1.0 + 1e-12)).max(0.0);
        out[l] = gc.log_norm[l] - 0.5 * gap * gap;
    }
    out
}

/// Per component, what the f32 screen needs.
#[derive(Debug, Clone, Copy)]
struct Screen {
    /// shrink_t of the screened shapes (the prefix bound's Woodbury correction).
    shrink: [f32; 3],
    /// Absolute error allowed per block value: per shape 1 + SCREEN_ABS_S / s_min.
    abs: f32,
    /// 2 (log_norm + margin): the screen's threshold is this minus twice the block's smallest best.
    thr_base: f64,
}

/// The first early-exit check in f32: true when, in every lane, even a lower bound of the prefix quadratic
/// form q_t puts the component more than [`PRUNE_MARGIN`] below the best.
///
/// Error of the f32 value: every input (coordinates within the unit box, constants) rounds to f32 with
/// relative error 6e-8, so a coordinate difference x carries an absolute error δ below 1.2e-7 per axis, and
/// |x+δ|²/s - |x|²/s = (2x·δ + |δ|²)/s is below 1e-5 |x|²/s + |δ|²/(1e-5 s) <= 1e-5 |x|²/s + 5e-8/s per shape;
/// the Woodbury term behaves the same by Cauchy-Schwarz, and the ~20 f32 operations per value add about
/// 1e-6 relative. So q_t >= sq (1 - 1e-4) - r (1 + 1e-4) - t (1 + 5e-8/s_min), with sq and r the f32 values
/// of Σ|x|²/s and Σ shrink y²: that lower bound is what is compared (NaN never prunes).
#[inline(never)]
fn screened_out(packed: &[[f32; 13]], h32: &[[f32; LANES]], sc: &Screen, thr32: f32) -> bool {
    let mut y = [[0.0f32; LANES]; 3];
    let mut sq = [0.0f32; LANES];
    accumulate_block(packed, h32, &mut y, &mut sq);
    let mut out = true;
    for l in 0..LANES {
        let r = sc.shrink[0] * y[0][l] * y[0][l] + sc.shrink[1] * y[1][l] * y[1][l] + sc.shrink[2] * y[2][l] * y[2][l];
        let q_low = sq[l] * (1.0 - SCREEN_REL) - r * (1.0 + SCREEN_REL) - sc.abs;
        out &= q_low > thr32;
    }
    out
}

/// A component's screen threshold for the block (`best_min` the smallest best log-density of its lanes):
/// log_norm - q_low / 2 < best - margin in every lane follows from q_low > 2 (log_norm + margin) - 2 min(best).
/// Rounded up to f32: the conversion errs by at most half an f32 ulp (6e-8 relative), so 2.4e-7 relative is
/// added first (NaN stays NaN and never prunes).
#[inline(always)]
fn threshold(sc: &Screen, best_min: f64) -> f32 {
    let thr = sc.thr_base - 2.0 * best_min;
    (thr + thr.abs() * 2.4e-7) as f32
}

fn argmax(row: &[f64]) -> usize {
    let mut a = 0;
    for k in 1..row.len() {
        if row[k] > row[a] {
            a = k;
        }
    }
    a
}

/// [`EStep::run`] with a fresh layout and dense responsibilities (tests and one-off calls; a fit keeps its
/// [`EStep`]): an incoming `gamma` of the right size gives the owners to try first.
pub fn e_step_pruned(data: &Data, comps: &[Component], gamma: &mut Vec<f64>) -> (f64, usize) {
    let mut estep = EStep::new(data);
    if gamma.len() == data.n_vertices * comps.len() {
        estep.set_owners(gamma, comps.len());
    }
    let mut members = Members::new();
    let out = estep.run(data, comps, &mut members);
    *gamma = super::cm::dense_responsibilities(&members, data.n_vertices, comps.len());
    out
}

/// Arithmetic rate of a kernel, measured.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "camelCase")]
pub struct KernelRate {
    pub gflop: f64,
    pub ms: f64,
    pub gflops_per_s: f64,
}

/// The machine's limit for the E-step's arithmetic: the same kernel on the same layout ([`Blocked`], every
/// block x every component x every shape, no pruning, no bookkeeping, no exp), repeated for at least
/// `min_ms` (and at least 5 passes: in wasm, engines compile a function with their optimising tier only
/// after it has run a while, and a pass is one call). The real E-step's rate is compared with this.
pub fn kernel_limit(data: &Data, comps: &[Component], min_ms: f64) -> KernelRate {
    kernel_limit_on(&Blocked::new(data), comps, min_ms)
}

/// [`kernel_limit`] on data already laid out.
pub fn kernel_limit_on(blocked: &Blocked, comps: &[Component], min_ms: f64) -> KernelRate {
    let wbs = ordered_woodbury(comps, &blocked.layout.order);
    let packed: Vec<Vec<[f64; 13]>> = wbs.iter().map(|wb| wb.packed.clone()).collect();
    let per_pass = (blocked.n_blocks() * LANES * comps.len()) as f64 * flops_per_pair(blocked.n_shapes);
    measure(per_pass, min_ms, || kernel_pass(&blocked.layout.h, blocked.n_shapes, &packed))
}

/// The same for the f32 screen: every block x every component, the first [`SCREEN_SHAPES`] shapes in f32 and
/// the check's arithmetic (as [`screened_out`] does it), no branches. This is the limit of the screened part of
/// the E-step's work, which comes in short pieces of 2 shapes.
pub fn kernel_limit_f32(data: &Data, comps: &[Component], min_ms: f64) -> KernelRate {
    kernel_limit_f32_on(&Blocked::new(data), comps, min_ms)
}

/// [`kernel_limit_f32`] on data already laid out.
pub fn kernel_limit_f32_on(blocked: &Blocked, comps: &[Component], min_ms: f64) -> KernelRate {
    let ts = blocked.screen;
    if ts == 0 {
        return KernelRate { gflop: 0.0, ms: 0.0, gflops_per_s: f64::INFINITY };
    }
    let wbs = ordered_woodbury(comps, &blocked.layout.order);
    let packed: Vec<[f32; 13]> =
        wbs.iter().flat_map(|wb| wb.packed[..ts].iter().map(|q| q.map(|v| v as f32))).collect();
    let m = comps.len();
    let per_pass = (blocked.n_blocks() * LANES * m * (FLOPS_PER_SHAPE * ts + FLOPS_PER_SCREEN_CHECK)) as f64;
    measure(per_pass, min_ms, || screen_pass(blocked, &packed, m, ts) as f64)
}

#[inline(never)]
fn screen_pass(blocked: &Blocked, packed: &[[f32; 13]], m: usize, ts: usize) -> f32 {
    let mut sink = [0.0f32; LANES];
    let shrink = [0.5f32, 0.25, 0.125];
    for b in 0..blocked.n_blocks() {
        let h32 = blocked.block32(b);
        for k in 0..m {
            let mut y = [[0.0f32; LANES]; 3];
            let mut sq = [0.0f32; LANES];
            accumulate_block(&packed[k * ts..(k + 1) * ts], h32, &mut y, &mut sq);
            let thr = k as f32;
            for l in 0..LANES {
                let r = shrink[0] * y[0][l] * y[0][l] + shrink[1] * y[1][l] * y[1][l] + shrink[2] * y[2][l] * y[2][l];
                let q_low = sq[l] * (1.0 - SCREEN_REL) - r * (1.0 + SCREEN_REL) - 1.0;
                if q_low > thr {
                    sink[l] += q_low;
                }
            }
        }
    }
    sink.iter().sum()
}

#[inline(never)]
fn kernel_pass<T: Real + PartialOrd + From<f32>>(h: &[[f32; LANES]], ns: usize, packed: &[Vec<[T; 13]>]) -> T {
    let zero = T::from(0.0);
    let mut sink = [zero; LANES];
    for hb in h.chunks_exact(ns * 3) {
        for p in packed {
            let mut y = [[zero; LANES]; 3];
            let mut sq = [zero; LANES];
            accumulate_block(p, hb, &mut y, &mut sq);
            // q = sq - y·y (the Woodbury correction's arithmetic), kept so nothing is optimised away
            for l in 0..LANES {
                let q = sq[l] - (y[0][l] * y[0][l] + y[1][l] * y[1][l] + y[2][l] * y[2][l]);
                if q > sink[l] {
                    sink[l] = q;
                }
            }
        }
    }
    // every lane feeds the result, so no lane's arithmetic can be dropped as dead code
    let mut total = zero;
    for v in sink {
        total += v;
    }
    total
}

/// The same arithmetic one vertex at a time on the vertex-major layout
/// ([`super::component::project_packed`]), for comparison.
pub fn kernel_rate_vertex_major(data: &Data, comps: &[Component], min_ms: f64) -> KernelRate {
    let wbs: Vec<Woodbury> = comps.iter().map(|c| c.woodbury()).collect();
    let per_pass = (data.n_vertices * comps.len()) as f64 * flops_per_pair(data.n_shapes);
    measure(per_pass, min_ms, || vertex_major_pass(data, comps, &wbs))
}

#[inline(never)]
fn vertex_major_pass(data: &Data, comps: &[Component], wbs: &[Woodbury]) -> f64 {
    let mut sink = f64::NEG_INFINITY;
    let mut buf = Vec::new();
    for j in 0..data.n_vertices {
        let h = data.vertex_into(j, &mut buf);
        for (c, wb) in comps.iter().zip(wbs) {
            sink = sink.max(c.log_weighted_density(wb, h));
        }
    }
    sink
}

/// Runs `pass` (which does `flops_per_pass` flops) until `min_ms` have passed and at least 5 passes ran,
/// after an untimed warm-up of at least 2 passes and `min_ms / 3` (time for a wasm engine's optimising tier).
fn measure(flops_per_pass: f64, min_ms: f64, mut pass: impl FnMut() -> f64) -> KernelRate {
    let w0 = crate::clock::now_ms();
    let mut warm = 0;
    while warm < 2 || (crate::clock::now_ms() - w0 < min_ms / 3.0 && warm < 100_000) {
        std::hint::black_box(pass());
        warm += 1;
    }
    let t0 = crate::clock::now_ms();
    let mut passes = 0usize;
    loop {
        std::hint::black_box(pass());
        passes += 1;
        let ms = crate::clock::now_ms() - t0;
        if (ms >= min_ms && passes >= 5) || passes >= 100_000 {
            let gflop = flops_per_pass * passes as f64 / 1e9;
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

    /// The group bound with the components in lanes gives every component's scalar bound, bit for bit (5
    /// components: a full chunk and a padded one).
    #[test]
    fn group_bounds_in_lanes_equal_the_scalar_ones() {
        let ns = 9;
        let gs = 8;
        let comps: Vec<Component> = (0..5)
            .map(|k| Component {
                rotations: (0..ns).map(|i| axis_angle([1.0, k as f64, i as f64], 0.3 * (i + k) as f64)).collect(),
                translations: (0..ns).map(|i| [0.1 * k as f64, -0.05 * i as f64, 0.02]).collect(),
                lambda: [0.3, 0.2 / (k + 1) as f64, 0.1],
                variances: (0..ns).map(|i| 1e-4 + 1e-3 * (i + k) as f64).collect(),
                weight: 0.2,
            })
            .collect();
        let order: Vec<usize> = (0..ns).rev().collect();
        let wbs = ordered_woodbury(&comps, &order);
        let shrinks = prefix_shrinks(&comps, &order);
        let centre: Vec<[f64; 3]> = (0..gs).map(|t| [0.05 * t as f64, 0.3, -0.1 * t as f64]).collect();
        let radii2: Vec<f64> = (0..gs).map(|t| 1e-4 * (t + 1) as f64).collect();
        for k0 in [0, 4] {
            let gc = GroupConsts::new(&wbs[k0..(k0 + LANES).min(5)], &shrinks[k0..], gs);
            let lanes = group_upper_bounds(&gc, &centre, &radii2);
            for k in k0..(k0 + LANES).min(5) {
                let one = group_upper_bound(&wbs[k], &shrinks[k][gs - 1], &centre, &radii2);
                assert_eq!(lanes[k - k0].to_bits(), one.to_bits(), "component {k}: {} vs {one}", lanes[k - k0]);
            }
        }
    }

    #[test]
    fn vectorised_e_step_equals_direct_loop() {
        // three shapes, 40 vertices, 3 components
        let ns = 3;
        let nv = 40;
        let shapes: Vec<Vec<[f64; 3]>> = (0..ns)
            .map(|i| {
                (0..nv)
                    .map(|j| {
                        let t = j as f64 * 0.1 + i as f64;
                        [t.sin(), (1.3 * t).cos(), 0.1 * t]
                    })
                    .collect()
            })
            .collect();
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: (0..ns).map(|i| format!("{i}")).collect(),
            faces: vec![[0, 1, 2]],
            shapes,
        })
        .unwrap();
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
            let h: Vec<[f64; 3]> = (0..ns).map(|i| data.point(j, i)).collect();
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
