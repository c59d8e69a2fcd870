//! One constrained factor analyser: h = R Λ z + b + ε (eq 4 with A = R Λ, eq 15 corrected).
//!
//! Because every R_i^T R_i = I, A^T Φ^-1 A = w Λ² with w = Σ_i 1/s_i, so M = I + w Λ² is diagonal and the
//! Woodbury identity gives the log-density (eq 6) and the posterior of z (eq 8) in O(n_s):
//!
//! - y = Σ_i R_i^T (x_i - b_i) / s_i,   E[z|h] = M^-1 Λ y,   Cov[z|h] = M^-1
//! - (h-b)^T Σ^-1 (h-b) = Σ_i |x_i - b_i|² / s_i - Σ_d λ_d² y_d² / (1 + w λ_d²)
//! - log|Σ| = 3 Σ_i log s_i + Σ_d log(1 + w λ_d²)
//!
//! No 3n_s x 3n_s matrix is ever formed.

use crate::geometry::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

pub const LN_2PI: f64 = 1.837_877_066_409_345_3;

/// One component (a rigid part): its per-shape rotation R^i and translation b^i, scales Λ, per-shape
/// isotropic variances s^i and mixing weight π.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Component {
    /// R_k^i, one per shape (serialised as rows).
    #[serde(with = "crate::geometry::serde_rows::vec")]
    pub rotations: Vec<Mat3>,
    /// b_k^i, one per shape.
    pub translations: Vec<Vec3>,
    /// diag(Λ_k).
    pub lambda: Vec3,
    /// s_k^i, one per shape.
    pub variances: Vec<f64>,
    /// π_k.
    pub weight: f64,
}

/// Per shape, packed for streaming: [b_x, b_y, b_z, 1/s, (R^T/s) row-major (9)].
pub type PackedShape = [f64; 13];

/// Per-component constants of the Woodbury form, computed once per E-step.
#[derive(Debug, Clone)]
pub struct Woodbury {
    /// Everything the inner loop reads per shape, contiguous (see [`PackedShape`]).
    pub packed: Vec<PackedShape>,
    /// λ_d² / (1 + w λ_d²): the Woodbury correction of the quadratic form.
    pub shrink: Vec3,
    /// λ_d / (1 + w λ_d²): E[z|h]_d = post_gain_d * y_d.
    pub post_gain: Vec3,
    /// 1 / (1 + w λ_d²): Cov[z|h] = diag(post_var).
    pub post_var: Vec3,
    /// log π - (3 n_s log 2π + log|Σ|) / 2.
    pub log_norm: f64,
}

impl Component {
    pub fn n_shapes(&self) -> usize {
        self.rotations.len()
    }

    /// Mean of the per-shape variances s_k^i.
    pub fn mean_variance(&self) -> f64 {
        self.variances.iter().sum::<f64>() / self.variances.len().max(1) as f64
    }

    pub fn woodbury(&self) -> Woodbury {
        let ns = self.n_shapes();
        let inv_s: Vec<f64> = self.variances.iter().map(|s| 1.0 / s).collect();
        let w: f64 = inv_s.iter().sum();
        let mut shrink = [0.0; 3];
        let mut post_gain = [0.0; 3];
        let mut post_var = [0.0; 3];
        let mut log_det = 3.0 * self.variances.iter().map(|s| s.ln()).sum::<f64>();
        for d in 0..3 {
            let l = self.lambda[d];
            let m = 1.0 + w * l * l;
            shrink[d] = l * l / m;
            post_gain[d] = l / m;
            post_var[d] = 1.0 / m;
            log_det += m.ln();
        }
        let rt_over_s: Vec<Mat3> = (0..ns).map(|i| self.rotations[i].transpose() * inv_s[i]).collect();
        let log_norm = self.weight.ln() - 0.5 * (3.0 * ns as f64 * LN_2PI + log_det);
        let packed = (0..ns)
            .map(|i| {
                let (b, r): (&Vec3, &Mat3) = (&self.translations[i], &rt_over_s[i]);
                [
                    b[0],
                    b[1],
                    b[2],
                    inv_s[i],
                    r[(0, 0)],
                    r[(0, 1)],
                    r[(0, 2)],
                    r[(1, 0)],
                    r[(1, 1)],
                    r[(1, 2)],
                    r[(2, 0)],
                    r[(2, 1)],
                    r[(2, 2)],
                ]
            })
            .collect();
        Woodbury { packed, shrink, post_gain, post_var, log_norm }
    }

    /// y = Σ_i R_i^T (h_i - b_i) / s_i and Σ_i |h_i - b_i|² / s_i for one data vector h (one point per shape).
    pub fn project(&self, wb: &Woodbury, h: &[Vec3]) -> (Vec3, f64) {
        project_packed(&wb.packed, h)
    }

    /// log(π_k N(h; b_k, A A^T + Φ)) by the Woodbury identity (eq 6, weighted by π as in eq 12's numerator).
    pub fn log_weighted_density(&self, wb: &Woodbury, h: &[Vec3]) -> f64 {
        let (y, sq) = self.project(wb, h);
        let quad = sq - (wb.shrink[0] * y[0] * y[0] + wb.shrink[1] * y[1] * y[1] + wb.shrink[2] * y[2] * y[2]);
        wb.log_norm - 0.5 * quad
    }

    /// E[z | h] under this component (eq 8).
    pub fn posterior_mean(&self, wb: &Woodbury, h: &[Vec3]) -> Vec3 {
        let (y, _) = self.project(wb, h);
        [wb.post_gain[0] * y[0], wb.post_gain[1] * y[1], wb.post_gain[2] * y[2]]
    }

    /// The latent image Λ E[z | h] of a data vector (eq 21 for a vertex; eq 23's E^p(z|J) mapped by Λ).
    pub fn latent_image(&self, h: &[Vec3]) -> Vec3 {
        let wb = self.woodbury();
        let e = self.posterior_mean(&wb, h);
        [self.lambda[0] * e[0], self.lambda[1] * e[1], self.lambda[2] * e[2]]
    }

    /// R^i v + b^i (eq 22 for one point).
    pub fn place(&self, shape: usize, v: Vec3) -> Vec3 {
        let r = &self.rotations[shape];
        let b = self.translations[shape];
        [
            r[(0, 0)] * v[0] + r[(0, 1)] * v[1] + r[(0, 2)] * v[2] + b[0],
            r[(1, 0)] * v[0] + r[(1, 1)] * v[1] + r[(1, 2)] * v[2] + b[1],
            r[(2, 0)] * v[0] + r[(2, 1)] * v[1] + r[(2, 2)] * v[2] + b[2],
        ]
    }

    /// (R^i)^T (p - b^i): the inverse of [`Component::place`], a point of shape `shape` brought back to the
    /// part's frame.
    pub fn unplace(&self, shape: usize, p: Vec3) -> Vec3 {
        let r = &self.rotations[shape];
        let b = self.translations[shape];
        let d = [p[0] - b[0], p[1] - b[1], p[2] - b[2]];
        [
            r[(0, 0)] * d[0] + r[(1, 0)] * d[1] + r[(2, 0)] * d[2],
            r[(0, 1)] * d[0] + r[(1, 1)] * d[1] + r[(2, 1)] * d[2],
            r[(0, 2)] * d[0] + r[(1, 2)] * d[1] + r[(2, 2)] * d[2],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;
    use nalgebra::{DMatrix, DVector};

    fn sample_component(ns: usize, seed: u64) -> Component {
        let mut st = seed;
        let mut rnd = || {
            st = st.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((st >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        Component {
            rotations: (0..ns).map(|_| axis_angle([rnd(), rnd(), rnd()], 3.0 * rnd())).collect(),
            translations: (0..ns).map(|_| [rnd(), rnd(), rnd()]).collect(),
            lambda: [0.3 + rnd().abs(), 0.2 + rnd().abs(), 0.05 + 0.1 * rnd().abs()],
            variances: (0..ns).map(|_| 1e-3 + 1e-2 * rnd().abs()).collect(),
            weight: 0.25,
        }
    }

    /// The dense 3n_s-dimensional Gaussian, formed explicitly.
    fn dense_log_density(c: &Component, h: &[Vec3]) -> (f64, DVector<f64>) {
        let ns = c.n_shapes();
        let n = 3 * ns;
        let mut a = DMatrix::zeros(n, 3);
        let mut phi = DMatrix::zeros(n, n);
        let mut x = DVector::zeros(n);
        for i in 0..ns {
            for r in 0..3 {
                for d in 0..3 {
                    a[(3 * i + r, d)] = c.rotations[i][(r, d)] * c.lambda[d];
                }
                phi[(3 * i + r, 3 * i + r)] = c.variances[i];
                x[3 * i + r] = h[i][r] - c.translations[i][r];
            }
        }
        let sigma = &a * a.transpose() + &phi;
        let chol = sigma.clone().cholesky().unwrap();
        let log_det = 2.0 * chol.l().diagonal().iter().map(|v| v.ln()).sum::<f64>();
        let sol = chol.solve(&x);
        let quad = x.dot(&sol);
        let beta = a.transpose() * sigma.try_inverse().unwrap();
        let ez = &beta * &x;
        (c.weight.ln() - 0.5 * (n as f64 * LN_2PI + log_det + quad), ez)
    }

    #[test]
    fn woodbury_equals_dense_gaussian() {
        for (ns, seed) in [(2, 1), (3, 2), (5, 3), (11, 4)] {
            let c = sample_component(ns, seed);
            let wb = c.woodbury();
            let h: Vec<Vec3> = (0..ns)
                .map(|i| {
                    let t = i as f64;
                    [0.1 * t.sin(), 0.2 * t.cos(), 0.05 * t]
                })
                .collect();
            let fast = c.log_weighted_density(&wb, &h);
            let (dense, ez_dense) = dense_log_density(&c, &h);
            assert!((fast - dense).abs() < 1e-8 * dense.abs().max(1.0), "ns={ns}: {fast} vs {dense}");
            let ez = c.posterior_mean(&wb, &h);
            for d in 0..3 {
                assert!((ez[d] - ez_dense[d]).abs() < 1e-8, "E[z] {d}: {} vs {}", ez[d], ez_dense[d]);
            }
        }
    }
}

/// y = Σ_i (R_i^T / s_i)(h_i - b_i) and Σ_i |h_i - b_i|² / s_i over packed shapes (the E-step's kernel).
#[inline(always)]
pub fn project_packed(packed: &[PackedShape], h: &[Vec3]) -> (Vec3, f64) {
    let (mut y0, mut y1, mut y2, mut sq) = (0.0, 0.0, 0.0, 0.0);
    for (p, q) in h.iter().zip(packed) {
        let x0 = p[0] - q[0];
        let x1 = p[1] - q[1];
        let x2 = p[2] - q[2];
        sq += (x0 * x0 + x1 * x1 + x2 * x2) * q[3];
        y0 += q[4] * x0 + q[5] * x1 + q[6] * x2;
        y1 += q[7] * x0 + q[8] * x1 + q[9] * x2;
        y2 += q[10] * x0 + q[11] * x1 + q[12] * x2;
    }
    ([y0, y1, y2], sq)
}
