//! The rigid fit of a set of vertices from additive statistics: each node of the merge tree keeps its vertex
//! count, per pose the sum of its points and, per pair of poses, the sum of their outer products, so a union's
//! statistics are the sum of its sides' and its rigid fit (generalised Procrustes over the poses) is solved on
//! 3x3 blocks without reading the vertices again.

use crate::geometry::procrustes::{best_rotation, toward_best_rotation};
use crate::geometry::Mat3;

/// Additive statistics of a node over the tree's poses.
#[derive(Clone)]
pub(super) struct Stats {
    pub(super) n: f64,
    /// Per pose: Σ_j x_j^i.
    pub(super) sum: Vec<[f64; 3]>,
    /// Per pair of poses i <= k (row-major upper triangle): Σ_j x_j^i x_j^kᵀ, row-major 3x3.
    cross: Vec<[f64; 9]>,
}

fn upper_index(q: usize, i: usize, k: usize) -> usize {
    debug_assert!(i <= k && k < q);
    i * (2 * q - i + 1) / 2 + (k - i)
}

impl Stats {
    pub(super) fn empty(q: usize) -> Stats {
        Stats { n: 0.0, sum: vec![[0.0; 3]; q], cross: vec![[0.0; 9]; q * (q + 1) / 2] }
    }

    pub(super) fn add_point(&mut self, x: &[[f64; 3]]) {
        let q = x.len();
        self.n += 1.0;
        for i in 0..q {
            for c in 0..3 {
                self.sum[i][c] += x[i][c];
            }
            let base = upper_index(q, i, i);
            for k in i..q {
                let m = &mut self.cross[base + k - i];
                for r in 0..3 {
                    for c in 0..3 {
                        m[3 * r + c] += x[i][r] * x[k][c];
                    }
                }
            }
        }
    }

    pub(super) fn plus(&self, o: &Stats) -> Stats {
        let mut s = self.clone();
        s.n += o.n;
        for (a, b) in s.sum.iter_mut().zip(&o.sum) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        for (a, b) in s.cross.iter_mut().zip(&o.cross) {
            for c in 0..9 {
                a[c] += b[c];
            }
        }
        s
    }

    /// Σ_i tr(C_ii): the spread of the node's points about their mean, summed over the poses.
    pub(super) fn spread(&self) -> f64 {
        let q = self.sum.len();
        let inv = if self.n > 0.0 { 1.0 / self.n } else { 0.0 };
        (0..q)
            .map(|i| {
                let m = &self.cross[upper_index(q, i, i)];
                let s = &self.sum[i];
                m[0] + m[4] + m[8] - (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) * inv
            })
            .sum()
    }

    /// The centred cross-covariances C_ik = Σ_j (x_j^i - x̄^i)(x_j^k - x̄^k)ᵀ for all i, k (q x q blocks).
    pub(super) fn centred(&self) -> Vec<Mat3> {
        let q = self.sum.len();
        let mut c = vec![Mat3::zeros(); q * q];
        let inv = if self.n > 0.0 { 1.0 / self.n } else { 0.0 };
        for i in 0..q {
            for k in i..q {
                let m = &self.cross[upper_index(q, i, k)];
                let mut b = Mat3::zeros();
                for r in 0..3 {
                    for col in 0..3 {
                        b[(r, col)] = m[3 * r + col] - self.sum[i][r] * self.sum[k][col] * inv;
                    }
                }
                c[i * q + k] = b;
                c[k * q + i] = b.transpose();
            }
        }
        c
    }
}

/// Generalised Procrustes on the statistics: rotations R_i (warm-started from `rot`) maximising
/// Σ_{i,k} tr(R_iᵀ C_ik R_k); returns the squared error Σ_i Σ_j |R_iᵀ (x_j^i - x̄^i) - y_j|² about the mean
/// shape y, and leaves the rotations in `rot`. Each sweep updates R_i by one Newton step toward the maximiser
/// of its own term ([`toward_best_rotation`]): the sweeps converge to the same rotations as with the exact
/// maximiser each time, at a fifth of its cost.
pub(super) fn rigid_sse(st: &Stats, rot: &mut [Mat3]) -> f64 {
    let q = st.sum.len();
    let c = st.centred();
    let total: f64 = (0..q).map(|i| c[i * q + i].trace()).sum();
    if total <= 0.0 || q < 2 {
        return 0.0;
    }
    // Σ_{i,k} tr(R_iᵀ C_ik R_k) = Σ_i tr(C_ii) + 2 Σ_{i<k} <R_i, C_ik R_k> (C_ki = C_ikᵀ)
    let objective = |rot: &[Mat3]| {
        let mut g = total;
        for i in 0..q {
            for k in i + 1..q {
                g += 2.0 * rot[i].dot(&(c[i * q + k] * rot[k]));
            }
        }
        g
    };
    let mut last = objective(rot);
    for _ in 0..50 {
        for i in 0..q {
            let mut m = Mat3::zeros();
            for k in (0..q).filter(|&k| k != i) {
                m += c[i * q + k] * rot[k];
            }
            rot[i] = toward_best_rotation(&m, &rot[i]);
        }
        let g = objective(rot);
        let done = (g - last).abs() <= 1e-12 * total;
        last = g;
        if done {
            break;
        }
    }
    // the rotations start the next fit of an overlapping set: rounding drift from the turns is not carried on
    // (the nearest rotation of a rotation up to rounding is its polar factor, a step or two from there)
    rot.iter_mut().for_each(|r| *r = best_rotation(r));
    (total - last / q as f64).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upper_triangle_indices_are_dense() {
        let q = 5;
        let mut seen = vec![false; q * (q + 1) / 2];
        for i in 0..q {
            for k in i..q {
                let x = upper_index(q, i, k);
                assert!(!seen[x]);
                seen[x] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }
}
