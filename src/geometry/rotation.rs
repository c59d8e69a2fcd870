//! Rotations as quaternions (glam's `DQuat`): conversion, geodesic angle, shorter-arc slerp.

use super::Mat3;
use glam::{DMat3, DQuat, DVec3};

/// Rotation of `angle` radians about `axis` (need not be unit length).
pub fn axis_angle(axis: [f64; 3], angle: f64) -> Mat3 {
    let a = DVec3::from(axis);
    let a = if a.length_squared() > 0.0 { a.normalize() } else { DVec3::X };
    from_glam(DMat3::from_axis_angle(a, angle))
}

/// Row-major [`Mat3`] from glam's column-major matrix.
pub fn from_glam(m: DMat3) -> Mat3 {
    let c = m.to_cols_array_2d();
    [[c[0][0], c[1][0], c[2][0]], [c[0][1], c[1][1], c[2][1]], [c[0][2], c[1][2], c[2][2]]]
}

pub fn to_glam(m: &Mat3) -> DMat3 {
    DMat3::from_cols_array_2d(&[[m[0][0], m[1][0], m[2][0]], [m[0][1], m[1][1], m[2][1]], [m[0][2], m[1][2], m[2][2]]])
}

/// Unit quaternion of a rotation matrix.
pub fn to_quat(m: &Mat3) -> DQuat {
    DQuat::from_mat3(&to_glam(m)).normalize()
}

pub fn from_quat(q: DQuat) -> Mat3 {
    from_glam(DMat3::from_quat(q.normalize()))
}

/// Geodesic angle (radians, in [0, π]) of R_b R_a^T: "Angle(R^i, R^j)" of Algorithm 2.
pub fn angle_between(a: &Mat3, b: &Mat3) -> f64 {
    let rel = super::mat_mul(b, &super::transpose(a));
    let tr = rel[0][0] + rel[1][1] + rel[2][2];
    ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
}

/// Spherical linear interpolation along the SHORTER arc: when the quaternions' dot product is negative,
/// one is negated first (q and -q are the same rotation).
pub fn slerp_quat(a: DQuat, b: DQuat, t: f64) -> DQuat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let d = a.dot(b).clamp(-1.0, 1.0);
    if d > 1.0 - 1e-12 {
        return (a * (1.0 - t) + b * t).normalize();
    }
    let theta = d.acos();
    let s = theta.sin();
    let wa = ((1.0 - t) * theta).sin() / s;
    let wb = (t * theta).sin() / s;
    (a * wa + b * wb).normalize()
}

pub fn slerp(a: &Mat3, b: &Mat3, t: f64) -> Mat3 {
    from_quat(slerp_quat(to_quat(a), to_quat(b), t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slerp_takes_the_short_arc() {
        let a = axis_angle([0.0, 0.0, 1.0], 0.1);
        let b = axis_angle([0.0, 0.0, 1.0], -0.3);
        // force opposite-sign quaternions for b
        let qa = to_quat(&a);
        let qb = -to_quat(&b);
        let mid = from_quat(slerp_quat(qa, qb, 0.5));
        let expect = axis_angle([0.0, 0.0, 1.0], -0.1);
        assert!(angle_between(&mid, &expect) < 1e-9, "{}", angle_between(&mid, &expect));
        assert!(angle_between(&slerp(&a, &b, 0.0), &a) < 1e-9);
        assert!(angle_between(&slerp(&a, &b, 1.0), &b) < 1e-9);
    }

    #[test]
    fn angle_is_geodesic() {
        let a = axis_angle([1.0, 2.0, 3.0], 0.4);
        let b = super::super::mat_mul(&axis_angle([0.0, 1.0, 0.0], 0.7), &a);
        assert!((angle_between(&a, &b) - 0.7).abs() < 1e-10);
    }
}
