//! Rotation that best aligns two point sets or maximises trace(R^T Q): SVD with the handedness fix of
//! Lemma 1 (eq 31), i.e. the Kabsch/Umeyama correction: if det(V U^T) < 0, flip the singular direction with
//! the SMALLEST singular value. Every rotation returned has det = +1.

use super::Mat3;

/// The rotation R in SO(3) maximising trace(R^T C) = Σ R_ab C_ab, for any 3x3 C (a "cross-covariance").
///
/// With C = Σ_j w_j y_j x_j^T this is the R minimising Σ_j w_j |y_j - R x_j|². Returns the identity for C = 0.
pub fn best_rotation(c: &Mat3) -> Mat3 {
    let m = *c;
    if !m.iter().all(|x| x.is_finite()) || m.iter().all(|x| *x == 0.0) {
        return super::IDENTITY;
    }
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
