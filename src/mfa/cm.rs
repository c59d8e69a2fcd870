//! The two CM steps of AECM.
//!
//! Cycle 1 (eqs 13-14): π_k = n_k / n_v, b_k = Σ_j γ_kj h_j / n_k.
//!
//! Cycle 2, in this order, each a conditional maximiser of the expected complete log-likelihood with the
//! E-step statistics E[z|h_j] = M^-1 Λ y_j and E[z z^T|h_j] = M^-1 + E[z]E[z]^T held fixed:
//! - Λ, exact (docs/method.md#item-1): λ_d = Σ_i (1/s_i) (R_i^T C_i)_dd / (w G_d), with
//!   C_i = Σ_j γ_kj x_ji E[z_j]^T, x_ji = v_j^i - b^i, G_d = Σ_j γ_kj E[z_d² | h_j], w = Σ_i 1/s_i;
//!   or the paper's literal eq 18 (Λ = sqrt of the shape-averaged eigenvalues of the per-shape covariances).
//! - R_i (eq 19 with Lemma 1 / eq 31): the rotation maximising trace(R_i^T C_i Λ), by SVD, det +1.
//! - Φ (eq 16 for isotropic per-shape noise, corrected, docs/method.md#item-2):
//!   s_i = (S_i - 2 <R_i, C_i Λ> + Σ_d λ_d² G_d) / (3 n_k), S_i = Σ_j γ_kj |x_ji|², floored.

use super::component::Component;
use super::data::Data;
use super::estep::{Lanes, LANES};
use super::params::LambdaRule;
use crate::geometry::procrustes::best_rotation;
use crate::geometry::{Mat3, Vec3};

/// Responsibilities below this are skipped in the accumulations (their contribution is below rounding).
pub const GAMMA_SKIP: f64 = 1e-14;

/// One (vertex, responsibility) pair of a component, with y = Σ_i R_i^T (h_i - b_i) / s_i from the E-step
/// (so E[z|h] = post_gain y needs no second pass over the shapes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Member {
    pub j: u32,
    pub g: f64,
    pub y: Vec3,
}

/// The responsibilities the CM steps use, sparse: per component, every vertex with γ_kj >= [`GAMMA_SKIP`]
/// (most vertices have one or two). The E-step writes them ([`super::estep::EStep::run`]); the y they carry
/// belong to the parameters of that E-step, which are the ones cycle 2 starts from.
pub type Members = Vec<Vec<Member>>;

/// The dense matrix `gamma[j * m + k]` of sparse responsibilities (entries below [`GAMMA_SKIP`] are 0).
pub fn dense_responsibilities(members: &Members, n_vertices: usize, m: usize) -> Vec<f64> {
    let mut gamma = vec![0.0; n_vertices * m];
    for (k, list) in members.iter().enumerate().take(m) {
        for mb in list {
            gamma[mb.j as usize * m + k] = mb.g;
        }
    }
    gamma
}

/// Smallest λ_d allowed (keeps M invertible and A = RΛ a proper, non-reflecting map).
pub const LAMBDA_FLOOR: f64 = 1e-6;

avx2_fn! {
    /// Cycle 1 CM step. Returns n_k (responsibility mass) per component. Components with no mass keep their b.
    pub fn cycle1(data: &Data, members: &Members, comps: &mut [Component]) -> Vec<f64> {
        let m = comps.len();
        let ns = data.n_shapes;
        let mut mass = vec![0.0; m];
        let mut sums = vec![0.0; m * ns * 3];
        let layout = &*data.layout;
        // per stored shape t and coordinate, one partial sum per lane (summed over the lanes at the end)
        let mut lanes = vec![[0.0; LANES]; ns * 3];
        for (k, list) in members.iter().enumerate().take(m) {
            lanes.iter_mut().for_each(|v| *v = [0.0; LANES]);
            for (b, g, _) in blocks(data, list) {
                for (t, acc) in lanes.chunks_exact_mut(3).enumerate() {
                    let at = (b * ns + t) * 3;
                    for d in 0..3 {
                        let h = &layout.h[at + d];
                        for l in 0..LANES {
                            acc[d][l] += g[l] * h[l] as f64;
                        }
                    }
                }
            }
            mass[k] = list.iter().map(|mb| mb.g).sum();
            let acc = &mut sums[k * ns * 3..(k + 1) * ns * 3];
            for (t, &i) in layout.order.iter().enumerate() {
                for d in 0..3 {
                    acc[i * 3 + d] = lanes[t * 3 + d].iter().sum();
                }
            }
        }
        let nv = data.n_vertices as f64;
        for (k, c) in comps.iter_mut().enumerate() {
            c.weight = mass[k] / nv;
            if mass[k] > 0.0 {
                for i in 0..ns {
                    for d in 0..3 {
                        c.translations[i][d] = sums[(k * ns + i) * 3 + d] / mass[k];
                    }
                }
            }
        }
        mass
    }
}

/// Sufficient statistics of one component for cycle 2.
struct Stats {
    n: f64,
    /// S_i = Σ γ |x_i|²
    sq: Vec<f64>,
    /// C_i = Σ γ x_i E[z]^T
    cross: Vec<Mat3>,
    /// G_d = Σ γ E[z_d²]
    second: Vec3,
    /// Σ γ E[z z^T] (the full matrix; its diagonal is `second`), for the parameter-expanded step
    moment: Mat3,
    /// Σ γ x_i x_i^T (only for the literal eq 18)
    scatter: Vec<Mat3>,
}

/// The blocks of the data that hold members of `list`, each as (block, g, y) with the members'
/// responsibilities `g` and projections `y` in their lanes and 0 in the other lanes, so the sums over the shapes
/// run 4 vertices at a time on the values as they are stored. `list` may come in any order; in layout order
/// (the E-step's and the label fit's) every block comes once.
struct Blocks<'a> {
    data: &'a Data,
    list: &'a [Member],
    at: usize,
}

impl Iterator for Blocks<'_> {
    type Item = (usize, Lanes, [Lanes; 3]);

    #[inline(always)]
    fn next(&mut self) -> Option<Self::Item> {
        let first = self.list.get(self.at)?;
        let (b, _) = self.data.block_lane(first.j as usize);
        let (mut g, mut y) = ([0.0; LANES], [[0.0; LANES]; 3]);
        while let Some(&Member { j, g: gj, y: yj }) = self.list.get(self.at) {
            let (bj, l) = self.data.block_lane(j as usize);
            if bj != b || g[l] != 0.0 {
                break;
            }
            g[l] = gj;
            for e in 0..3 {
                y[e][l] = yj[e];
            }
            self.at += 1;
        }
        Some((b, g, y))
    }
}

fn blocks<'a>(data: &'a Data, list: &'a [Member]) -> Blocks<'a> {
    Blocks { data, list, at: 0 }
}

avx2_fn! {
    fn accumulate(data: &Data, list: &[Member], c: &Component, want_scatter: bool, want_moment: bool) -> Stats {
        let ns = data.n_shapes;
        let wb = c.woodbury();
        let mut st = Stats {
            n: 0.0,
            sq: vec![0.0; ns],
            cross: vec![Mat3::zeros(); ns],
            second: [0.0; 3],
            moment: Mat3::zeros(),
            scatter: if want_scatter { vec![Mat3::zeros(); ns] } else { Vec::new() },
        };
        for &Member { g, y, .. } in list {
            let ez = [wb.post_gain[0] * y[0], wb.post_gain[1] * y[1], wb.post_gain[2] * y[2]];
            st.n += g;
            for d in 0..3 {
                st.second[d] += g * (wb.post_var[d] + ez[d] * ez[d]);
            }
            if want_moment {
                for a in 0..3 {
                    for b in 0..3 {
                        st.moment[(a, b)] += g * ez[a] * ez[b];
                    }
                }
            }
        }
        // S_i and C_i 4 vertices at a time (the lanes of a block), one partial sum per lane, per stored shape t:
        // 1 + 9 values of LANES
        let layout = &*data.layout;
        let mut lanes = vec![[0.0; LANES]; ns * 10];
        for (blk, g, y) in blocks(data, list) {
            let mut q = [[0.0; LANES]; 3];
            for e in 0..3 {
                for l in 0..LANES {
                    q[e][l] = g[l] * wb.post_gain[e] * y[e][l];
                }
            }
            for (t, acc) in lanes.chunks_exact_mut(10).enumerate() {
                let at = (blk * ns + t) * 3;
                let b = c.translations[layout.order[t]];
                let mut x = [[0.0; LANES]; 3];
                for a in 0..3 {
                    for l in 0..LANES {
                        x[a][l] = layout.h[at + a][l] as f64 - b[a];
                    }
                }
                for l in 0..LANES {
                    acc[0][l] += g[l] * (x[0][l] * x[0][l] + x[1][l] * x[1][l] + x[2][l] * x[2][l]);
                }
                for a in 0..3 {
                    for e in 0..3 {
                        for l in 0..LANES {
                            acc[1 + 3 * a + e][l] += x[a][l] * q[e][l];
                        }
                    }
                }
            }
        }
        for (t, &i) in layout.order.iter().enumerate() {
            let acc = &lanes[t * 10..(t + 1) * 10];
            st.sq[i] = acc[0].iter().sum();
            for a in 0..3 {
                for e in 0..3 {
                    st.cross[i][(a, e)] = acc[1 + 3 * a + e].iter().sum();
                }
            }
        }
        if want_scatter {
            for &Member { j, g, .. } in list {
                for i in 0..ns {
                    let (p, b) = (data.point(j as usize, i), c.translations[i]);
                    let x = [p[0] - b[0], p[1] - b[1], p[2] - b[2]];
                    for a in 0..3 {
                        for e in 0..3 {
                            st.scatter[i][(a, e)] += g * x[a] * x[e];
                        }
                    }
                }
            }
        }
        if want_moment {
            for d in 0..3 {
                st.moment[(d, d)] += st.n * wb.post_var[d];
            }
        }
        st
    }
}

/// Cycle 2 CM step (Λ, then R, then Φ, then optionally the parameter-expanded fold of [`px_fold`]) for every
/// component. Returns n_k per component.
pub fn cycle2(
    data: &Data,
    members: &Members,
    comps: &mut [Component],
    rule: LambdaRule,
    floor: f64,
    px: bool,
) -> Vec<f64> {
    let m = comps.len();
    let ns = data.n_shapes;
    let mut masses = Vec::with_capacity(m);
    for k in 0..m {
        let st = accumulate(data, &members[k], &comps[k], rule == LambdaRule::PaperEq18, px);
        masses.push(st.n);
        if st.n <= 0.0 {
            continue;
        }
        let c = &mut comps[k];
        // Λ
        match rule {
            LambdaRule::Exact => {
                let w: f64 = c.variances.iter().map(|s| 1.0 / s).sum();
                for d in 0..3 {
                    let mut num = 0.0;
                    for i in 0..ns {
                        let r = &c.rotations[i];
                        let cr = &st.cross[i];
                        // (R_i^T C_i)_dd = Σ_a R_ad C_ad
                        let rc = r[(0, d)] * cr[(0, d)] + r[(1, d)] * cr[(1, d)] + r[(2, d)] * cr[(2, d)];
                        num += rc / c.variances[i];
                    }
                    let den = w * st.second[d];
                    let l = if den > 0.0 { num / den } else { c.lambda[d] };
                    c.lambda[d] = if l.is_finite() { l.max(LAMBDA_FLOOR) } else { c.lambda[d] };
                }
            }
            LambdaRule::PaperEq18 => {
                let mut eig_sum = [0.0; 3];
                for i in 0..ns {
                    let sc = &st.scatter[i];
                    let cov = sc / st.n;
                    let mut ev: Vec<f64> = cov.symmetric_eigenvalues().iter().cloned().collect();
                    ev.sort_by(|a, b| b.partial_cmp(a).unwrap_or(std::cmp::Ordering::Equal));
                    for d in 0..3 {
                        eig_sum[d] += ev[d].max(0.0);
                    }
                }
                for d in 0..3 {
                    c.lambda[d] = (eig_sum[d] / ns as f64).sqrt().max(LAMBDA_FLOOR);
                }
            }
        }
        // R_i = argmax trace(R^T C_i Λ)
        for i in 0..ns {
            let cr = &st.cross[i];
            let cl = Mat3::from_fn(|a, b| cr[(a, b)] * c.lambda[b]);
            c.rotations[i] = best_rotation(&cl);
            // Φ: s_i
            let r = &c.rotations[i];
            let mut inner = 0.0;
            for a in 0..3 {
                for b in 0..3 {
                    inner += r[(a, b)] * cl[(a, b)];
                }
            }
            let quad: f64 = (0..3).map(|d| c.lambda[d] * c.lambda[d] * st.second[d]).sum();
            let s = (st.sq[i] - 2.0 * inner + quad) / (3.0 * st.n);
            c.variances[i] = if s.is_finite() { s.max(floor) } else { floor };
        }
        if px {
            let sz = st.moment / st.n;
            px_fold(c, &sz);
        }
    }
    masses
}

/// The parameter-expanded step (PX-EM, Liu, Rubin & Wu 1998; docs/method.md#item-12). In the expanded model
/// z ~ N(0, Σ_z); the CM steps above are its CM steps for A* = RΛ and Φ, and its maximiser for Σ_z is the
/// average posterior second moment Σ_z = Σ_j γ_j E[z z^T | h_j] / n_k. Reducing back to z ~ N(0, I) gives
/// A = A* Σ_z^{1/2}, and A A^T = R (Λ Σ_z Λ) R^T. With Λ Σ_z Λ = U D U^T (U a proper rotation), A = (R U) D^{1/2}
/// up to a rotation of z, which leaves the density unchanged: R_i ← R_i U and Λ ← D^{1/2}. Each AECM iteration
/// still cannot lower the likelihood (it is an ECM iteration of the expanded model), and the latent frame no
/// longer has to creep towards the principal axes one small step at a time.
pub fn px_fold(c: &mut Component, sigma_z: &Mat3) {
    let l = c.lambda;
    let m = Mat3::from_fn(|a, b| l[a] * sigma_z[(a, b)] * l[b]);
    if !m.iter().all(|v| v.is_finite()) {
        return;
    }
    let mut u = m.symmetric_eigen().eigenvectors;
    if u.determinant() < 0.0 {
        u.column_mut(2).neg_mut();
    }
    // Each column's own Rayleigh quotient, so that D always pairs with U's columns; and U must diagonalise M
    // (else the fold is skipped: the plain CM step is still a proper one).
    let d = [0, 1, 2].map(|i| u.column(i).dot(&(m * u.column(i))));
    let recon = u * Mat3::from_diagonal(&d.into()) * u.transpose();
    if !((recon - m).norm() <= 1e-9 * m.norm()) {
        return;
    }
    let new_lambda = d.map(|v| v.max(0.0).sqrt().max(LAMBDA_FLOOR));
    if !new_lambda.iter().all(|v| v.is_finite()) {
        return;
    }
    for r in c.rotations.iter_mut() {
        *r *= u;
    }
    c.lambda = new_lambda;
}

#[cfg(test)]
mod px_tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;

    fn component(lambda: Vec3) -> Component {
        let ns = 4;
        Component {
            rotations: (0..ns).map(|i| axis_angle([0.3, 1.0, i as f64], 0.2 + i as f64)).collect(),
            translations: (0..ns).map(|i| [0.1 * i as f64, 0.0, -0.05]).collect(),
            lambda,
            variances: vec![1e-4, 2e-4, 3e-4, 1e-6],
            weight: 0.5,
        }
    }

    /// With Σ_z = I the fold only relabels or flips latent axes: every log-density stays.
    #[test]
    fn px_fold_with_identity_keeps_every_density() {
        for lambda in [[0.07, 0.02, 0.034], [0.0789, 0.0369, 0.0221], [0.0726, 0.0203, 0.0341]] {
            let mut c = component(lambda);
            let hs: Vec<Vec<Vec3>> = (0..20)
                .map(|j| {
                    (0..4)
                        .map(|i| [0.01 * j as f64, 0.02 * i as f64 - 0.01 * j as f64, 0.003 * (j * i) as f64])
                        .collect()
                })
                .collect();
            let before: Vec<f64> = hs.iter().map(|h| c.log_weighted_density(&c.woodbury(), h)).collect();
            px_fold(&mut c, &Mat3::new(1.0, 1e-15, 0.0, 1e-15, 1.0, -2e-15, 0.0, -2e-15, 1.0));
            for (h, b) in hs.iter().zip(&before) {
                let a = c.log_weighted_density(&c.woodbury(), h);
                assert!((a - b).abs() < 1e-9 * b.abs().max(1.0), "{b} -> {a}, lambda {lambda:?} -> {:?}", c.lambda);
            }
        }
    }

    /// R_i Λ Σ_z Λ R_i^T before the fold equals R_i' Λ'² R_i'^T after it, for every shape; R_i' are rotations.
    #[test]
    fn px_fold_moves_the_latent_covariance_into_lambda_and_r() {
        let sz = Mat3::new(0.54, -0.03, 0.02, -0.03, 0.94, 0.006, 0.02, 0.006, 1.2);
        let eye = Mat3::identity();
        for lambda in [[0.07, 0.02, 0.034], [0.0789, 0.0369, 0.0221], [0.05, 0.05, 0.01]] {
            let mut c = component(lambda);
            let cov = |c: &Component, i: usize, mid: &Mat3| {
                let (r, l) = (c.rotations[i], Mat3::from_diagonal(&c.lambda.into()));
                r * l * mid * l * r.transpose()
            };
            let before: Vec<_> = (0..4).map(|i| cov(&c, i, &sz)).collect();
            px_fold(&mut c, &sz);
            for (i, b) in before.iter().enumerate() {
                assert!((cov(&c, i, &eye) - b).norm() < 1e-12, "shape {i}, lambda {lambda:?}");
                assert!((crate::geometry::det(&c.rotations[i]) - 1.0).abs() < 1e-12);
            }
        }
    }
}

#[cfg(test)]
mod sum_tests {
    use super::*;
    use crate::synth::{generate, Preset, Spec};

    /// The sums by blocks of 4 lanes equal the member-by-member ones, for member lists in layout order, in
    /// reverse and in a scattered order (blocks visited piecewise), with blocks partly filled.
    #[test]
    fn the_sums_by_blocks_equal_the_sums_by_members() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 400, poses: 5, seed: 1, ..Spec::default() }).unwrap();
        let data = Data::from_population(&g.population);
        let comps = crate::mfa::init::components_from_labels(&data, &g.part_of_vertex, 1e-8);
        let mut members: Members = Vec::new();
        crate::mfa::estep::EStep::new(&data).run(&data, &comps, &mut members);
        let ns = data.n_shapes;
        let k = (0..comps.len()).max_by_key(|&k| members[k].len()).unwrap();
        let c = &comps[k];
        let wb = c.woodbury();
        let in_layout = members[k].clone();
        assert!(in_layout.len() > 50 && in_layout.len() < data.n_vertices, "{} members", in_layout.len());
        let reversed: Vec<Member> = in_layout.iter().rev().copied().collect();
        let scattered: Vec<Member> = (0..7).flat_map(|r| in_layout.iter().skip(r).step_by(7).copied()).collect();
        let scale = |m: &Mat3| m.amax().max(1e-300);
        for list in [&in_layout, &reversed, &scattered] {
            let st = accumulate(&data, list, c, false, false);
            for i in 0..ns {
                let (mut sq, mut cross) = (0.0, Mat3::zeros());
                for &Member { j, g, y } in list {
                    let (p, b) = (data.point(j as usize, i), c.translations[i]);
                    let x = [p[0] - b[0], p[1] - b[1], p[2] - b[2]];
                    sq += g * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
                    for a in 0..3 {
                        for e in 0..3 {
                            cross[(a, e)] += x[a] * g * wb.post_gain[e] * y[e];
                        }
                    }
                }
                assert!((st.sq[i] - sq).abs() <= 1e-12 * sq, "shape {i}: S {} against {sq}", st.sq[i]);
                assert!(
                    (st.cross[i] - cross).amax() <= 1e-12 * scale(&cross),
                    "shape {i}: C {} against {cross}",
                    st.cross[i]
                );
            }
            let mut sums = comps.clone();
            let one: Members = (0..comps.len()).map(|q| if q == k { list.clone() } else { Vec::new() }).collect();
            let mass = cycle1(&data, &one, &mut sums);
            let n: f64 = list.iter().map(|m| m.g).sum();
            assert!((mass[k] - n).abs() <= 1e-12 * n);
            for i in 0..ns {
                for d in 0..3 {
                    let b: f64 = list.iter().map(|m| m.g * data.point(m.j as usize, i)[d]).sum::<f64>() / n;
                    assert!(
                        (sums[k].translations[i][d] - b).abs() <= 1e-12,
                        "b {} against {b}",
                        sums[k].translations[i][d]
                    );
                }
            }
        }
    }
}
