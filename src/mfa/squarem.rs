//! SQUAREM (Varadhan & Roland 2008, scheme S3) on top of the PX-EM iteration, with a monotonicity safeguard.
//!
//! Let F be one AECM iteration (cycle 1, E-step, cycle 2 with the PX-EM fold, E-step). From θ0, two plain
//! iterations give θ1 = F(θ0) and θ2 = F(θ1); with r = θ1 - θ0 and v = θ2 - 2 θ1 + θ0 (in the coordinates below)
//! the squared extrapolation is
//!
//!   θ' = θ0 - 2 α r + α² v,   α = -max(1, min(|r| / |v|, step_max))
//!
//! (α = -1 gives θ' = θ2 exactly). θ' is kept only when its log-likelihood is at least that of θ2; otherwise the
//! fit stays at θ2 (the plain step), so the log-likelihood never decreases. `step_max` grows by 4 when the
//! longest step is accepted and shrinks by 4 when a step is refused.
//!
//! Coordinates, per component, all taken at θ0 so that every extrapolated point is a valid parameter set:
//! - translations b^i: as they are;
//! - rotations R^i: ω^i = log(R0^iT R^i) (axis x angle); back by R0^i exp(ω^i), always in SO(3);
//! - Λ: log λ_d; back by exp, floored at [`super::cm::LAMBDA_FLOOR`] (always positive);
//! - variances s^i: log s^i; back by exp, floored at the variance floor (always positive);
//! - weights π: log π; back by exp, renormalised to sum 1.
//!
//! The latent axes of a component are defined only up to a proper signed permutation (z -> Q z with Q a
//! signed permutation matrix of det +1 changes R^i to R^i Q and Λ to Q^T Λ Q and leaves the density as it was);
//! the PX-EM fold may pick any of them. Before extrapolating, θ1 is put in the frame closest to θ0's and θ2 in
//! the frame closest to θ1's ([`align_latent_frame`]).
//!
//! The step length |r| / |v| uses a scale-aware norm: a translation step in units of the component's noise
//! standard deviation σ = sqrt(mean s), a rotation step as the displacement it gives at λ_max (ω λ_max / σ), a
//! Λ step as λ_d Δlog λ_d / σ, variance and weight steps in log units; each component weighted by its π0.

use super::cm::LAMBDA_FLOOR;
use super::component::Component;
use crate::geometry::{Mat3, Vec3};
use nalgebra::{Rotation3, Vector3};

/// log of a rotation matrix as axis x angle (the rotation's own angle in [0, π]), through its unit quaternion
/// (w, v): ω = 2 atan2(|v|, w) v / |v| with w >= 0, finite and accurate at every angle (the matrix's own
/// acos of the trace is NaN when rounding puts the trace of a near-identity above 3).
fn log_rotation(r: &Mat3) -> Vec3 {
    let q = crate::geometry::rotation::to_quat(r);
    let (mut w, mut v) = (q.w, [q.i, q.j, q.k]);
    if w < 0.0 {
        w = -w;
        v = v.map(|x| -x);
    }
    let n = crate::geometry::norm(v);
    let f = if n > 1e-300 { 2.0 * n.atan2(w) / n } else { 2.0 / w.max(1e-300) };
    v.map(|x| x * f)
}

fn exp_rotation(w: Vec3) -> Mat3 {
    Rotation3::new(Vector3::new(w[0], w[1], w[2])).into_inner()
}

/// The 24 proper signed permutation matrices (the rotations of the cube).
fn signed_permutations() -> Vec<Mat3> {
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut out = Vec::with_capacity(24);
    for p in perms {
        for signs in 0..8 {
            let mut q = Mat3::zeros();
            for (col, &row) in p.iter().enumerate() {
                q[(row, col)] = if signs >> col & 1 == 1 { -1.0 } else { 1.0 };
            }
            if q.determinant() > 0.0 {
                out.push(q);
            }
        }
    }
    out
}

/// Re-expresses `c` in the latent frame closest to `reference`'s: of the 24 proper signed permutations Q,
/// the one maximising Σ_i trace(R_ref^iT R^i Q), applied as R^i <- R^i Q, Λ <- Q^T Λ Q. The density of every
/// data vector is unchanged (z -> Q^T z keeps N(0, I)).
pub fn align_latent_frame(c: &mut Component, reference: &Component) {
    let qs = signed_permutations();
    let mut best = (f64::NEG_INFINITY, 0);
    for (n, q) in qs.iter().enumerate() {
        let score: f64 =
            c.rotations.iter().zip(&reference.rotations).map(|(r, r0)| (r0.transpose() * r * q).trace()).sum();
        if score > best.0 {
            best = (score, n);
        }
    }
    let q = qs[best.1];
    if q == Mat3::identity() {
        return;
    }
    for r in c.rotations.iter_mut() {
        *r *= q;
    }
    // (Q^T Λ Q)_dd = λ_e where Q's column d has its non-zero in row e
    let l = c.lambda;
    for d in 0..3 {
        let e = (0..3).find(|&e| q[(e, d)] != 0.0).expect("a permutation");
        c.lambda[d] = l[e];
    }
}

/// The coordinates of `c` in the chart at `base` (see the module doc), flat, and the weight of each
/// coordinate in the step-length norm.
fn chart(base: &Component, c: &Component, out: &mut Vec<f64>, weights: Option<&mut Vec<f64>>) {
    let ns = base.rotations.len();
    for i in 0..ns {
        out.extend_from_slice(&[
            c.translations[i][0] - base.translations[i][0],
            c.translations[i][1] - base.translations[i][1],
            c.translations[i][2] - base.translations[i][2],
        ]);
        out.extend_from_slice(&log_rotation(&(base.rotations[i].transpose() * c.rotations[i])));
        out.push((c.variances[i] / base.variances[i]).ln());
    }
    for d in 0..3 {
        out.push((c.lambda[d] / base.lambda[d]).ln());
    }
    out.push((c.weight / base.weight).ln());
    if let Some(w) = weights {
        let var = base.variances.iter().sum::<f64>() / ns.max(1) as f64;
        let lmax = base.lambda.iter().fold(0.0f64, |a, &b| a.max(b));
        let pi = base.weight;
        for _ in 0..ns {
            w.extend_from_slice(&[pi / var; 3]);
            w.extend_from_slice(&[pi * lmax * lmax / var; 3]);
            w.push(pi);
        }
        for d in 0..3 {
            w.push(pi * base.lambda[d] * base.lambda[d] / var);
        }
        w.push(pi);
    }
}

/// The component at coordinates `u` of the chart at `base` (inverse of [`chart`]); the weight is not yet
/// renormalised.
fn unchart(base: &Component, u: &[f64], floor: f64) -> Component {
    let ns = base.rotations.len();
    let mut c = base.clone();
    let mut at = 0;
    for i in 0..ns {
        for d in 0..3 {
            c.translations[i][d] = base.translations[i][d] + u[at + d];
        }
        c.rotations[i] = base.rotations[i] * exp_rotation([u[at + 3], u[at + 4], u[at + 5]]);
        c.variances[i] = (base.variances[i] * u[at + 6].exp()).max(floor);
        at += 7;
    }
    for d in 0..3 {
        c.lambda[d] = (base.lambda[d] * u[at + d].exp()).max(LAMBDA_FLOOR);
    }
    c.weight = base.weight * u[at + 3].exp();
    c
}

/// The extrapolated point of one SQUAREM cycle, or None when there is nothing to gain (α = -1, i.e. θ2 itself)
/// or the inputs do not allow it (different component counts, non-finite coordinates). Returns (θ', |α|).
pub fn extrapolate(
    theta0: &[Component],
    theta1: &[Component],
    theta2: &[Component],
    step_max: f64,
    floor: f64,
) -> Option<(Vec<Component>, f64)> {
    let m = theta0.len();
    if m == 0 || theta1.len() != m || theta2.len() != m {
        return None;
    }
    let mut t1 = theta1.to_vec();
    let mut t2 = theta2.to_vec();
    let (mut u1, mut u2, mut w) = (Vec::new(), Vec::new(), Vec::new());
    let mut spans = Vec::with_capacity(m);
    for k in 0..m {
        if theta0[k].rotations.len() != t1[k].rotations.len() || theta0[k].weight <= 0.0 {
            return None;
        }
        align_latent_frame(&mut t1[k], &theta0[k]);
        align_latent_frame(&mut t2[k], &t1[k]);
        let start = u1.len();
        chart(&theta0[k], &t1[k], &mut u1, Some(&mut w));
        chart(&theta0[k], &t2[k], &mut u2, None);
        spans.push(start..u1.len());
    }
    let (mut rr, mut vv) = (0.0, 0.0);
    for ((a, b), wt) in u1.iter().zip(&u2).zip(&w) {
        let v = b - 2.0 * a;
        rr += wt * a * a;
        vv += wt * v * v;
    }
    if !(rr.is_finite() && vv.is_finite()) || vv <= 0.0 {
        return None;
    }
    let a = (rr / vv).sqrt().min(step_max);
    if !(a > 1.0) {
        return None;
    }
    // θ' = θ0 - 2α r + α² v with α = -a
    let mut out = Vec::with_capacity(m);
    let mut u = Vec::new();
    for (k, span) in spans.into_iter().enumerate() {
        u.clear();
        for n in span {
            let (r, v) = (u1[n], u2[n] - 2.0 * u1[n]);
            u.push(2.0 * a * r + a * a * v);
        }
        if !u.iter().all(|x| x.is_finite()) {
            return None;
        }
        out.push(unchart(&theta0[k], &u, floor));
    }
    let total: f64 = out.iter().map(|c| c.weight).sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    out.iter_mut().for_each(|c| c.weight /= total);
    Some((out, a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;

    fn comp(t: f64) -> Component {
        let ns = 3;
        Component {
            rotations: (0..ns).map(|i| axis_angle([0.2, 1.0, i as f64], 0.3 + 0.1 * i as f64 + t)).collect(),
            translations: (0..ns).map(|i| [0.1 * i as f64 + t, -0.02 * t, 0.05]).collect(),
            lambda: [0.07 * (1.0 + t), 0.03, 0.02 * (1.0 - 0.5 * t)],
            variances: (0..ns).map(|i| 1e-5 * (1.0 + i as f64) * (1.0 + t)).collect(),
            weight: 0.5,
        }
    }

    /// The chart and its inverse are inverse to each other; the extrapolated point of a sequence that moves
    /// along a straight line in the chart (θ_t = θ0 + t d) lands further along that line, a valid parameter set.
    #[test]
    fn chart_round_trips_and_extrapolation_follows_a_line() {
        let base = comp(0.0);
        let c = comp(0.2);
        let mut u = Vec::new();
        chart(&base, &c, &mut u, None);
        let back = unchart(&base, &u, 1e-12);
        for i in 0..3 {
            assert!((back.rotations[i] - c.rotations[i]).norm() < 1e-12);
            assert!((back.variances[i] - c.variances[i]).abs() < 1e-18);
        }
        // a geometric sequence of steps in the chart: d, d/2 (the EM map contracting by 1/2)
        let d: Vec<f64> = u.iter().map(|x| x * 0.1).collect();
        let at = |t: f64| unchart(&base, &d.iter().map(|x| x * t).collect::<Vec<_>>(), 1e-12);
        let (t0, t1, t2) = (vec![at(0.0), at(0.0)], vec![at(1.0), at(1.0)], vec![at(1.5), at(1.5)]);
        let (ext, a) = extrapolate(&t0, &t1, &t2, 100.0, 1e-12).unwrap();
        // |r| / |v| = |d| / |d/2| = 2, and θ' = θ0 + 2·2 d - 4 d/2 = θ0 + 2 d: the fixed point of the sequence
        assert!((a - 2.0).abs() < 1e-9, "{a}");
        let want = at(2.0);
        for i in 0..3 {
            assert!((ext[0].rotations[i] - want.rotations[i]).norm() < 1e-9);
            assert!((crate::geometry::det(&ext[0].rotations[i]) - 1.0).abs() < 1e-12);
            assert!(ext[0].variances[i] > 0.0);
        }
        assert!((ext[0].weight - 0.5).abs() < 1e-12);
    }

    /// The log is finite and inverts exp at every angle, also when rounding puts a near-identity's trace above 3.
    #[test]
    fn log_rotation_is_finite_and_inverts_exp() {
        let mut nearly = Mat3::identity();
        nearly[(0, 0)] = 1.0 + 2e-16;
        nearly[(1, 1)] = 1.0 + 2e-16;
        assert!(log_rotation(&nearly).iter().all(|v| v.is_finite() && v.abs() < 1e-15));
        for angle in [1e-12, 1e-6, 0.3, 2.0, 3.14] {
            let w = [0.3 * angle, -0.5 * angle, 0.81 * angle];
            let n = crate::geometry::norm(w);
            let w = w.map(|x| x * angle / n);
            let back = log_rotation(&exp_rotation(w));
            for d in 0..3 {
                assert!((back[d] - w[d]).abs() < 1e-12, "{angle}: {back:?} vs {w:?}");
            }
        }
    }

    /// Any of the 24 frames of the same component is mapped back to the reference's frame, with the same Λ.
    #[test]
    fn align_latent_frame_undoes_a_signed_permutation() {
        let reference = comp(0.0);
        for q in signed_permutations() {
            let mut c = reference.clone();
            for r in c.rotations.iter_mut() {
                *r *= q;
            }
            let l = Mat3::from_diagonal(&reference.lambda.into());
            let lq = q.transpose() * l * q;
            c.lambda = [lq[(0, 0)], lq[(1, 1)], lq[(2, 2)]];
            align_latent_frame(&mut c, &reference);
            for (a, b) in c.rotations.iter().zip(&reference.rotations) {
                assert!((a - b).norm() < 1e-12);
            }
            assert_eq!(c.lambda, reference.lambda);
        }
    }
}
