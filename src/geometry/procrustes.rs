//! Rotation that best aligns two point sets or maximises trace(R^T Q). With det Q > 0 it is Q's orthogonal
//! polar factor (Newton's polar iteration, [`polar_rotation`]); otherwise the SVD with the handedness fix of
//! Lemma 1 (eq 31), i.e. the Kabsch/Umeyama correction: if det(V U^T) < 0, flip the singular direction with
//! the SMALLEST singular value. Every rotation returned has det = +1.

use super::Mat3;

avx2_fn! {
    /// The rotation R in SO(3) maximising trace(R^T C) = Σ R_ab C_ab, for any 3x3 C (a "cross-covariance").
    ///
    /// With C = Σ_j w_j y_j x_j^T this is the R minimising Σ_j w_j |y_j - R x_j|². Returns the identity for C = 0.
    pub fn best_rotation(c: &Mat3) -> Mat3 {
        let m = *c;
        if !m.iter().all(|x| x.is_finite()) || m.iter().all(|x| *x == 0.0) {
            return super::IDENTITY;
        }
        polar_rotation(&m).unwrap_or_else(|| best_rotation_svd(&m))
    }
}

/// One Newton step from the rotation `r` toward [`best_rotation`] of C, for iterations that call it again and
/// again with slowly changing C (generalised Procrustes sweeps): about a fifth of a polar decomposition's work.
///
/// The maximiser R of trace(Rᵀ C) is where X = Rᵀ C is symmetric (and trace(X) I - X positive definite; a
/// linear function on SO(3) has no other local maximum). With X = rᵀ C = S + A (symmetric and skew parts,
/// A = [a]×), turning r by R = r (I + [ω]×) to first order makes the skew part vanish when
/// (trace(S) I - S) ω = 2a; the step applies ω by the Cayley map (an exact rotation, the same fixed point).
/// Where the step is not safe (that matrix not positive definite: far from the maximiser, or C near a
/// reflection) or large (|ω| > 0.5), [`best_rotation`] itself.
pub fn toward_best_rotation(c: &Mat3, r: &Mat3) -> Mat3 {
    let x = r.transpose() * c;
    let s = (x + x.transpose()) * 0.5;
    let a = [(x[(2, 1)] - x[(1, 2)]) * 0.5, (x[(0, 2)] - x[(2, 0)]) * 0.5, (x[(1, 0)] - x[(0, 1)]) * 0.5];
    let h = Mat3::identity() * s.trace() - s;
    // h is symmetric: positive definite when its leading minors are
    let (m1, m2, m3) = (h[(0, 0)], h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(1, 0)], h.determinant());
    let scale = c.norm();
    if !(m1 > 1e-9 * scale && m2 > 1e-9 * scale * scale && m3 > 1e-9 * scale * scale * scale) {
        return best_rotation(c);
    }
    let Some(inv) = h.try_inverse() else { return best_rotation(c) };
    let w = inv * nalgebra::Vector3::new(2.0 * a[0], 2.0 * a[1], 2.0 * a[2]);
    if !(w.norm() <= 0.5) {
        return best_rotation(c);
    }
    // Cayley: the unit quaternion (1, ω/2) normalised
    let (qw, qx, qy, qz) = (1.0, 0.5 * w[0], 0.5 * w[1], 0.5 * w[2]);
    let n2 = qw * qw + qx * qx + qy * qy + qz * qz;
    let k = 2.0 / n2;
    let turn = Mat3::new(
        1.0 - k * (qy * qy + qz * qz),
        k * (qx * qy - qz * qw),
        k * (qx * qz + qy * qw),
        k * (qx * qy + qz * qw),
        1.0 - k * (qx * qx + qz * qz),
        k * (qy * qz - qx * qw),
        k * (qx * qz - qy * qw),
        k * (qy * qz + qx * qw),
        1.0 - k * (qx * qx + qy * qy),
    );
    r * turn
}

/// Smallest det(C) / |C|_F³ for which [`polar_rotation`] is used: below it C is close to singular (or a
/// reflection), where the SVD's explicit handedness fix is the safe way.
const POLAR_MIN_DET: f64 = 1e-9;

/// Most Newton steps of [`polar_rotation`] (from a well-conditioned C it needs 5-8).
const POLAR_MAX_STEPS: usize = 40;

/// The orthogonal polar factor of C (C = R H, H symmetric positive definite) by Higham's scaled Newton
/// iteration X ← (γ X + X^{-T} / γ) / 2, γ = (|X^{-1}|_F / |X|_F)^{1/2}; quadratic once close, about 10x
/// cheaper than a 3x3 SVD, and the CM step calls it once per part and shape. With det C > 0 the polar factor
/// is a rotation and it is the maximiser of trace(R^T C) (C = U D V^T gives R = U V^T). `None` when C is
/// nearly singular or a reflection (det C <= [`POLAR_MIN_DET`] |C|³), or the iteration does not settle.
fn polar_rotation(c: &Mat3) -> Option<Mat3> {
    let norm = c.norm();
    let mut x = *c / norm;
    // |x|_F = 1, so det(x) = det(C) / |C|³
    if !(x.determinant() > POLAR_MIN_DET) {
        return None;
    }
    let mut scaled = true;
    for _ in 0..POLAR_MAX_STEPS {
        // X^{-T} = cof(X) / det X: the cofactor matrix's columns are the cross products of X's columns
        let (a, b, cc) = (x.column(0).into_owned(), x.column(1).into_owned(), x.column(2).into_owned());
        let (ca, cb, ccc) = (b.cross(&cc), cc.cross(&a), a.cross(&b));
        let det = a.dot(&ca);
        if !(det > 0.0) {
            return None;
        }
        let inv_t = Mat3::from_columns(&[ca / det, cb / det, ccc / det]);
        let gamma = if scaled { (inv_t.norm() / x.norm()).sqrt() } else { 1.0 };
        let next = (x * gamma + inv_t / gamma) * 0.5;
        let change = (next - x).norm();
        x = next;
        if change < 1e-3 {
            // near the fixed point the unscaled step converges quadratically
            scaled = false;
        }
        if change < 1e-14 {
            return Some(x);
        }
    }
    None
}

/// [`best_rotation`] by SVD, for any C (also singular ones and reflections).
fn best_rotation_svd(m: &Mat3) -> Mat3 {
    // C = U D V^T  ->  R = U diag(1, 1, det(U V^T)) V^T (largest trace(R^T C) among rotations).
    let svd = m.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else { return super::IDENTITY };
    // nalgebra does not promise sorted singular values: find the smallest one to flip.
    let sv = svd.singular_values;
    let mut smallest = 0;
    for i in 1..3 {
        if sv[i] < sv[smallest] {
            smallest = i;
        }
    }
    let d = (u * v_t).determinant();
    let mut flip = Mat3::identity();
    if d < 0.0 {
        flip[(smallest, smallest)] = -1.0;
    }
    u * flip * v_t
}

/// How many calls of [`best_rotation`] needed the handedness flip (for diagnostics): true if this one did.
pub fn needs_flip(c: &Mat3) -> bool {
    let svd = c.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => (u * v_t).determinant() < 0.0,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{det, mat_vec, orthonormality_error, rotation::axis_angle};

    fn cross_cov(ys: &[[f64; 3]], xs: &[[f64; 3]]) -> Mat3 {
        let mut c = Mat3::zeros();
        for (y, x) in ys.iter().zip(xs) {
            for a in 0..3 {
                for b in 0..3 {
                    c[(a, b)] += y[a] * x[b];
                }
            }
        }
        c
    }

    /// Uniform numbers in [-1, 1) from a xorshift stream.
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// A random C = U D Vᵀ with singular values 1, 10^-a, 10^-b (a, b up to `decades`), the last one negative
    /// when `reflect`, at a random scale; and D's diagonal.
    fn cross_covariance(next: &mut impl FnMut() -> f64, decades: [f64; 2], reflect: bool) -> (Mat3, [f64; 3]) {
        let u = axis_angle([next(), next(), next() + 0.1], 3.0 * next());
        let v = axis_angle([next() + 0.1, next(), next()], 3.0 * next());
        let d = [1.0, 10f64.powf(-decades[0] * next().abs()), 10f64.powf(-decades[1] * next().abs())];
        let sign = if reflect { -1.0 } else { 1.0 };
        (u * Mat3::from_diagonal(&[d[0], d[1], sign * d[2]].into()) * v.transpose() * (1e-3 + next().abs()), d)
    }

    /// The Newton polar path gives the maximiser of trace(R^T C) on cross-covariances of every conditioning it
    /// accepts, and declines the ones it must (reflections, near-singular): best_rotation is then the SVD's.
    #[test]
    fn polar_rotation_equals_the_svd_one() {
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        let (mut used, mut declined) = (0, 0);
        for k in 0..3000 {
            // singular values over 12 decades, sometimes a reflection
            let (c, d) = cross_covariance(&mut next, [3.0, 12.0], k % 7 == 0);
            let svd = best_rotation_svd(&c);
            match polar_rotation(&c) {
                Some(r) => {
                    used += 1;
                    // the maximiser's conditions to rounding: a rotation with R^T C symmetric, and a trace at
                    // least the SVD's (nalgebra's 3x3 SVD leaves R^T C asymmetric by up to 2e-9 |C| when two
                    // singular values nearly coincide; the Newton iterate does not)
                    let (h, scale) = (r.transpose() * c, c.norm());
                    assert!((h - h.transpose()).amax() < 1e-14 * scale, "k {k}: {d:?}");
                    assert!(h.trace() >= (svd.transpose() * c).trace() - 1e-14 * scale, "k {k}: {d:?}");
                    assert!(orthonormality_error(&r) < 1e-13 && (det(&r) - 1.0).abs() < 1e-13, "k {k}");
                    assert!((r - svd).amax() < 1e-7, "k {k}: {d:?}, differ by {:e}", (r - svd).amax());
                }
                None => declined += 1,
            }
            assert!((best_rotation(&c) - polar_rotation(&c).unwrap_or(svd)).amax() == 0.0);
        }
        assert!(used > 1000 && declined > 300, "used {used}, declined {declined}");
    }

    /// Newton steps from a nearby rotation reach best_rotation's maximiser (to rounding) in a few steps, for C of
    /// every conditioning and handedness; from far away the step is best_rotation itself.
    #[test]
    fn steps_toward_the_best_rotation_reach_it() {
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut stepped, mut fell_back) = (0, 0);
        for k in 0..2000 {
            let reflect = k % 5 == 0;
            let (c, d) = cross_covariance(&mut next, [2.0, 6.0], reflect);
            let best = best_rotation(&c);
            // a start up to about 0.3 rad away, then steps
            let mut r = best * axis_angle([next(), next(), next() + 0.1], 0.3 * next());
            for _ in 0..6 {
                let nr = toward_best_rotation(&c, &r);
                if (nr - best).amax() == 0.0 {
                    fell_back += 1;
                } else {
                    stepped += 1;
                }
                r = nr;
            }
            assert!(orthonormality_error(&r) < 1e-12 && (det(&r) - 1.0).abs() < 1e-12, "k {k}");
            let (got, want) = ((r.transpose() * c).trace(), (best.transpose() * c).trace());
            assert!(got >= want - 1e-12 * c.norm(), "k {k}: trace {got} below {want}");
            assert!((r - best).amax() < 1e-6, "k {k}: {d:?} reflect {reflect}, differs by {:e}", (r - best).amax());
        }
        assert!(stepped > 5000 && fell_back > 10, "stepped {stepped}, fell back {fell_back}");
        // from the far side, best_rotation itself
        let c = axis_angle([0.0, 0.0, 1.0], 0.4);
        let far = axis_angle([1.0, 0.0, 0.0], 3.0);
        assert_eq!(toward_best_rotation(&c, &far), best_rotation(&c));
    }

    #[test]
    fn recovers_a_rotation_with_det_plus_one() {
        let r = axis_angle([0.3, -0.5, 0.8], 2.1);
        let xs = [[1.0, 0.2, 0.0], [0.0, 1.0, 0.5], [0.3, 0.0, 1.0], [-1.0, 0.4, 0.2]];
        let ys: Vec<_> = xs.iter().map(|&x| mat_vec(&r, x)).collect();
        let got = best_rotation(&cross_cov(&ys, &xs));
        assert!((got - r).amax() < 1e-10);
        assert!((det(&got) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn reflection_needs_the_flip_and_still_gives_a_rotation() {
        // y = mirror(x): the unconstrained optimum is a reflection; the best rotation keeps det +1
        // and flips the direction of the smallest singular value.
        let mirror = Mat3::from_diagonal(&[1.0, 1.0, -1.0].into());
        let xs = [[3.0, 0.0, 0.1], [-3.0, 0.0, 0.1], [0.0, 2.0, -0.1], [0.0, -2.0, -0.1]];
        let ys: Vec<_> = xs.iter().map(|&x| mat_vec(&mirror, x)).collect();
        let c = cross_cov(&ys, &xs);
        assert!(needs_flip(&c));
        let got = best_rotation(&c);
        assert!((det(&got) - 1.0).abs() < 1e-12, "det {}", det(&got));
        assert!(orthonormality_error(&got) < 1e-12);
        // the planar points (large singular values) are matched exactly, so R = identity here
        assert!((got[(0, 0)] - 1.0).abs() < 1e-9 && (got[(1, 1)] - 1.0).abs() < 1e-9);
        // it beats every other rotation tried
        let score = |r: &Mat3| r.component_mul(&c).sum();
        for k in 0..50 {
            let t = k as f64 * 0.37;
            let other = axis_angle([t.sin(), t.cos(), 0.3], t);
            assert!(score(&got) >= score(&other) - 1e-9);
        }
    }
}
