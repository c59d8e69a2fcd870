//! Rotations: conversion to and from nalgebra's unit quaternions, the rotation angle (accurate near 0 and near
//! π), and shorter-arc slerp.

use super::Mat3;
use nalgebra::{Quaternion, Rotation3, UnitQuaternion};

/// A unit quaternion (w, x, y, z) for a rotation.
pub type Quat = UnitQuaternion<f64>;

/// Rotation of `angle` radians about `axis` (need not be unit length; a zero axis is taken as x), by Rodrigues'
/// formula R = cos θ I + sin θ [a]x + (1 - cos θ) a a^T.
pub fn axis_angle(axis: [f64; 3], angle: f64) -> Mat3 {
    let len = super::norm(axis);
    let [x, y, z] = if len > 0.0 { super::scale(axis, 1.0 / len) } else { [1.0, 0.0, 0.0] };
    let (sin, cos) = angle.sin_cos();
    let omc = 1.0 - cos;
    let (xy, xz, yz) = (x * y * omc, x * z * omc, y * z * omc);
    Mat3::new(
        x * x * omc + cos,
        xy - z * sin,
        xz + y * sin,
        xy + z * sin,
        y * y * omc + cos,
        yz - x * sin,
        xz - y * sin,
        yz + x * sin,
        z * z * omc + cos,
    )
}

/// Unit quaternion of a rotation matrix (which must be a rotation: it is not re-orthogonalised).
pub fn to_quat(m: &Mat3) -> Quat {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*m))
}

/// Rotation matrix of a quaternion (normalised first, so any non-zero quaternion will do).
pub fn from_quat(q: Quaternion<f64>) -> Mat3 {
    UnitQuaternion::from_quaternion(q).to_rotation_matrix().into_inner()
}

/// Rotation angle θ in [0, π] of a rotation matrix R, as atan2(|axis part|, trace part) with
/// axis part = ½ (R32 - R23, R13 - R31, R21 - R12) = sin θ · axis and trace part = ½ (tr R - 1) = cos θ.
///
/// Both parts carry only the rounding of R's entries (about 1e-16 each), and atan2 turns them into θ with that
/// absolute error at every angle. acos of the trace part alone loses half the digits near 0 (cos θ = 1 - θ²/2:
/// a 1e-9 rad rotation has the same trace as the identity) and near π.
pub fn angle(r: &Mat3) -> f64 {
    let axis = [r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]];
    let sin = 0.5 * super::norm(axis);
    let cos = 0.5 * (r[(0, 0)] + r[(1, 1)] + r[(2, 2)] - 1.0);
    sin.atan2(cos)
}

/// Geodesic angle (radians, in [0, π]) of R_b R_a^T: "Angle(R^i, R^j)" of Algorithm 2.
pub fn angle_between(a: &Mat3, b: &Mat3) -> f64 {
    angle(&super::mat_mul(b, &super::transpose(a)))
}

/// Spherical linear interpolation along the SHORTER arc: when the quaternions' dot product is negative,
/// one is negated first (q and -q are the same rotation).
pub fn slerp_quat(a: Quat, b: Quat, t: f64) -> Quat {
    SlerpPath::new(a, b).at(t)
}

pub fn slerp(a: &Mat3, b: &Mat3, t: f64) -> Mat3 {
    SlerpPath::new(to_quat(a), to_quat(b)).matrix_at(t)
}

/// [`slerp_quat`] from `a` to `b` with what does not depend on t (the short-arc sign, the angle) computed once,
/// for many t: `at(t)` is `slerp_quat(a, b, t)` bit for bit.
pub struct SlerpPath {
    qa: Quaternion<f64>,
    qb: Quaternion<f64>,
    theta: f64,
    sin: f64,
}

impl SlerpPath {
    pub fn new(a: Quat, b: Quat) -> SlerpPath {
        let (qa, qb) = (a.into_inner(), b.into_inner());
        let qb = if qa.dot(&qb) < 0.0 { -qb } else { qb };
        // the angle between them by the same atan2 form (|qa - qb| and |qa + qb| are 2 sin and 2 cos of half of it)
        let theta = 2.0 * (qa - qb).norm().atan2((qa + qb).norm());
        SlerpPath { qa, qb, theta, sin: theta.sin() }
    }

    pub fn at(&self, t: f64) -> Quat {
        let (qa, qb, theta) = (self.qa, self.qb, self.theta);
        if theta < 1e-12 {
            return UnitQuaternion::from_quaternion(qa * (1.0 - t) + qb * t);
        }
        let wa = ((1.0 - t) * theta).sin() / self.sin;
        let wb = (t * theta).sin() / self.sin;
        UnitQuaternion::from_quaternion(qa * wa + qb * wb)
    }

    /// [`slerp`] at t: the rotation matrix of [`SlerpPath::at`].
    pub fn matrix_at(&self, t: f64) -> Mat3 {
        from_quat(self.at(t).into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{mat_mul, transpose};

    /// A few rotations to compose with: identity, generic, near π.
    fn bases() -> Vec<Mat3> {
        vec![crate::geometry::IDENTITY, axis_angle([1.0, 2.0, 3.0], 0.4), axis_angle([-0.3, 0.1, 0.9], 3.1)]
    }

    #[test]
    fn slerp_takes_the_short_arc() {
        let a = axis_angle([0.0, 0.0, 1.0], 0.1);
        let b = axis_angle([0.0, 0.0, 1.0], -0.3);
        // force opposite-sign quaternions for b
        let qa = to_quat(&a);
        let qb = UnitQuaternion::new_unchecked(-to_quat(&b).into_inner());
        let mid = from_quat(slerp_quat(qa, qb, 0.5).into_inner());
        let expect = axis_angle([0.0, 0.0, 1.0], -0.1);
        // a few ulp of rounding through quaternions and back: 1e-14 rad is about 45 ulp of 1
        assert!(angle_between(&mid, &expect) < 1e-14, "{}", angle_between(&mid, &expect));
        assert!(angle_between(&slerp(&a, &b, 0.0), &a) < 1e-14);
        assert!(angle_between(&slerp(&a, &b, 1.0), &b) < 1e-14);
        // equal spacing along the arc: a quarter of the way is a quarter of the angle
        let q = slerp(&a, &b, 0.25);
        assert!((angle_between(&a, &q) - 0.1).abs() < 1e-14, "{}", angle_between(&a, &q));
    }

    #[test]
    fn quaternion_round_trip() {
        for r in bases() {
            let back = from_quat(to_quat(&r).into_inner());
            assert!(angle_between(&r, &back) < 1e-15, "{}", angle_between(&r, &back));
        }
    }

    #[test]
    fn angle_is_geodesic() {
        let a = axis_angle([1.0, 2.0, 3.0], 0.4);
        let b = mat_mul(&axis_angle([0.0, 1.0, 0.0], 0.7), &a);
        // two 3x3 products of entries |x| <= 1, each entry within a few ulp: 1e-15 absolute
        assert!((angle_between(&a, &b) - 0.7).abs() < 1e-15, "{}", angle_between(&a, &b) - 0.7);
        assert!((angle_between(&b, &a) - 0.7).abs() < 1e-15);
    }

    #[test]
    fn tiny_angles_are_measured_to_relative_precision() {
        for theta in [1e-15, 1e-12, 1e-9, 1e-6] {
            for axis in [[0.0, 0.0, 1.0], [1.0, -2.0, 0.5]] {
                // directly: the axis part of R is sin θ · axis to a few ulp (1 - cos θ is 0 or tiny), so θ comes
                // back to relative rounding; 1e-13 allows ~500 ulp
                let got = angle(&axis_angle(axis, theta));
                assert!(((got - theta) / theta).abs() < 1e-13, "θ = {theta}: measured {got}");
                // between two rotations: R_b R_a^T is a product of entries |x| <= 1 whose sums of three products
                // each carry up to ~3 ulp (3.3e-16) absolute, so sin θ carries ~1e-15 absolute: relative 1e-6
                // at 1e-9 rad; tolerance 1e-15 absolute + 1e-12 relative
                for a in bases() {
                    let b = mat_mul(&axis_angle(axis, theta), &a);
                    let got = angle_between(&a, &b);
                    assert!((got - theta).abs() < 1e-15 + 1e-12 * theta, "θ = {theta}: measured {got}");
                }
            }
        }
        // a 1e-9 rad rotation to relative 1e-6, where acos of the trace part reads 0 (or 1.5e-8 one ulp away)
        let r = axis_angle([0.3, 0.4, 0.5], 1e-9);
        assert!((angle(&r) / 1e-9 - 1.0).abs() < 1e-6);
        let acos_form = (0.5 * (r.trace() - 1.0)).clamp(-1.0, 1.0).acos();
        assert!((acos_form / 1e-9 - 1.0).abs() > 0.5, "acos of the trace is not accurate near 0: {acos_form}");
    }

    #[test]
    fn angles_near_pi_and_across_the_range() {
        use std::f64::consts::PI;
        for theta in [1e-3, 0.5, 1.0, 2.0, 3.0, PI - 1e-6, PI - 1e-9, PI] {
            for a in bases() {
                let b = mat_mul(&axis_angle([0.2, -0.7, 0.4], theta), &a);
                let got = angle_between(&a, &b);
                // absolute error of the entries, as above; at π the angle is π whatever the rounding sign
                assert!((got - theta).abs() < 2e-15, "θ = {theta}: measured {got} (error {:e})", got - theta);
                assert!((0.0..=PI).contains(&got));
            }
        }
        // R R^T: exactly 0 for a rotation and its own transpose product
        let r = axis_angle([1.0, 1.0, 0.0], 2.0);
        assert!(angle(&mat_mul(&r, &transpose(&r))) < 1e-15);
    }
}
