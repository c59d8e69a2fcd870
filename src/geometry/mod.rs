//! Small fixed-size geometry: 3x3 matrices, SO(3) Procrustes, quaternions and slerp.
//!
//! One representation for the maths: nalgebra. A 3x3 matrix is `Mat3` = `nalgebra::Matrix3<f64>` (indexed
//! `m[(row, col)]`), a rotation's quaternion `rotation::Quat` = `nalgebra::UnitQuaternion<f64>`, and the SVD and
//! symmetric eigen-decompositions work on `Mat3` directly. Points and vectors are `[f64; 3]`, the storage of
//! meshes and populations (one contiguous buffer, passed to JS as is); [`mat_vec`] and friends apply a `Mat3`
//! to them. The products below are written out term by term in a fixed order, so results do not depend on how
//! nalgebra orders its sums.

pub mod procrustes;
pub mod rotation;
pub mod surface_distance;

pub type Vec3 = [f64; 3];
pub type Mat3 = nalgebra::Matrix3<f64>;

pub const IDENTITY: Mat3 = Mat3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);

/// A matrix's nine numbers row by row (as JSON and the page read a rotation).
#[inline]
pub fn row_major(m: &Mat3) -> [f64; 9] {
    [m[(0, 0)], m[(0, 1)], m[(0, 2)], m[(1, 0)], m[(1, 1)], m[(1, 2)], m[(2, 0)], m[(2, 1)], m[(2, 2)]]
}

/// A matrix from its rows.
#[inline]
pub fn from_rows(r: [[f64; 3]; 3]) -> Mat3 {
    Mat3::new(r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2])
}

/// Its rows.
#[inline]
pub fn rows(m: &Mat3) -> [[f64; 3]; 3] {
    [[m[(0, 0)], m[(0, 1)], m[(0, 2)]], [m[(1, 0)], m[(1, 1)], m[(1, 2)]], [m[(2, 0)], m[(2, 1)], m[(2, 2)]]]
}

#[inline]
pub fn mat_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[(0, 0)] * v[0] + m[(0, 1)] * v[1] + m[(0, 2)] * v[2],
        m[(1, 0)] * v[0] + m[(1, 1)] * v[1] + m[(1, 2)] * v[2],
        m[(2, 0)] * v[0] + m[(2, 1)] * v[1] + m[(2, 2)] * v[2],
    ]
}

/// m^T v
#[inline]
pub fn mat_t_vec(m: &Mat3, v: Vec3) -> Vec3 {
    [
        m[(0, 0)] * v[0] + m[(1, 0)] * v[1] + m[(2, 0)] * v[2],
        m[(0, 1)] * v[0] + m[(1, 1)] * v[1] + m[(2, 1)] * v[2],
        m[(0, 2)] * v[0] + m[(1, 2)] * v[1] + m[(2, 2)] * v[2],
    ]
}

pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    Mat3::from_fn(|i, j| a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)])
}

pub fn transpose(a: &Mat3) -> Mat3 {
    a.transpose()
}

/// Determinant by the first row's cofactors.
pub fn det(a: &Mat3) -> f64 {
    a[(0, 0)] * (a[(1, 1)] * a[(2, 2)] - a[(1, 2)] * a[(2, 1)])
        - a[(0, 1)] * (a[(1, 0)] * a[(2, 2)] - a[(1, 2)] * a[(2, 0)])
        + a[(0, 2)] * (a[(1, 0)] * a[(2, 1)] - a[(1, 1)] * a[(2, 0)])
}

/// serde for a `Mat3` as its rows (`[[r00, r01, r02], ...]`), the layout of the JSON export.
pub mod serde_rows {
    use super::Mat3;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(m: &Mat3, s: S) -> Result<S::Ok, S::Error> {
        super::rows(m).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Mat3, D::Error> {
        Ok(super::from_rows(<[[f64; 3]; 3]>::deserialize(d)?))
    }

    /// The same for a list of matrices.
    pub mod vec {
        use super::super::{from_rows, rows, Mat3};
        use serde::{Deserialize, Deserializer, Serialize, Serializer};

        pub fn serialize<S: Serializer>(ms: &[Mat3], s: S) -> Result<S::Ok, S::Error> {
            ms.iter().map(rows).collect::<Vec<_>>().serialize(s)
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Mat3>, D::Error> {
            Ok(Vec::<[[f64; 3]; 3]>::deserialize(d)?.into_iter().map(from_rows).collect())
        }
    }
}

#[inline]
pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
pub fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

/// Smallest and largest coordinates of `points` (an empty set gives +inf / -inf).
pub fn bounds<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> (Vec3, Vec3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

/// |a_j - b_j| for every pair of points (`a` and `b` of the same length).
pub fn distances(a: &[Vec3], b: &[Vec3]) -> Vec<f64> {
    a.iter().zip(b).map(|(&p, &q)| norm(sub(p, q))).collect()
}

/// Where every point lies along the longest side of the points' bounding box: 0 at its low end, 1 at its high
/// end (all 0 when the box has no extent). The page's first figure colours a population's poses by it.
pub fn along_longest_axis(points: &[Vec3]) -> Vec<f64> {
    let (lo, hi) = bounds(points);
    let axis = (0..3).fold(0, |best, d| if hi[d] - lo[d] > hi[best] - lo[best] { d } else { best });
    let extent = hi[axis] - lo[axis];
    if !(extent > 0.0) {
        return vec![0.0; points.len()];
    }
    points.iter().map(|p| (p[axis] - lo[axis]) / extent).collect()
}

#[cfg(test)]
mod point_tests {
    use super::*;

    #[test]
    fn distances_and_position_along_the_longest_axis() {
        let a = [[0.0, 0.0, 0.0], [1.0, 2.0, 2.0]];
        let b = [[3.0, 4.0, 0.0], [1.0, 2.0, 2.0]];
        assert_eq!(distances(&a, &b), vec![5.0, 0.0]);
        // the box is 4 long in y, 1 in x, 0.5 in z: y decides
        let pts = [[0.0, -1.0, 0.0], [1.0, 3.0, 0.5], [0.5, 0.0, 0.25]];
        assert_eq!(along_longest_axis(&pts), vec![0.0, 1.0, 0.25]);
        assert_eq!(along_longest_axis(&[[2.0, 2.0, 2.0]; 3]), vec![0.0; 3]);
        assert!(along_longest_axis(&[]).is_empty());
    }
}

/// Largest deviation of R^T R from I, and det R: for checking rotations.
pub fn orthonormality_error(r: &Mat3) -> f64 {
    (mat_mul(&transpose(r), r) - IDENTITY).amax()
}
