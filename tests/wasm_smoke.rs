//! The library's public API, checked natively (`cargo test`) AND in wasm (`cargo test --target
//! wasm32-unknown-unknown`, in Node and in headless Chromium): every test is written once with [`dual_test!`].
//!
//! The references here are computed independently of the library (own rotation formula, own dense Cholesky),
//! so a wrong result on either target fails.

#[macro_use]
mod common;

use posemfa::geometry::procrustes::{best_rotation, needs_flip};
use posemfa::geometry::{from_rows, rows};
use posemfa::mesh::population::natural_cmp;
use posemfa::mesh::{Mesh, Population};
use posemfa::mfa::component::LN_2PI;
use posemfa::mfa::Component;

/// The test's own 3x3 matrices: rows, with its own products (the library's `Mat3` only at its API, through
/// `from_rows` / `rows`).
type Mat3 = [[f64; 3]; 3];

/// Rotation of `angle` about `axis` (Rodrigues), row-major: the test's own, not the library's.
fn rodrigues(axis: [f64; 3], angle: f64) -> Mat3 {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = [axis[0] / n, axis[1] / n, axis[2] / n];
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                c[i][j] += a[i][k] * b[k][j];
            }
        }
    }
    c
}

fn tr(a: &Mat3) -> Mat3 {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = a[j][i];
        }
    }
    t
}

fn det3(a: &Mat3) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

fn max_abs_diff(a: &Mat3, b: &Mat3) -> f64 {
    (0..9).map(|k| (a[k / 3][k % 3] - b[k / 3][k % 3]).abs()).fold(0.0, f64::max)
}

/// trace(R^T C): what best_rotation maximises.
fn score(r: &Mat3, c: &Mat3) -> f64 {
    (0..9).map(|k| r[k / 3][k % 3] * c[k / 3][k % 3]).sum()
}

fn square(offset: f64, scale: f64) -> Mesh {
    Mesh {
        positions: vec![
            [offset, 0.0, 0.0],
            [offset + scale, 0.0, 0.0],
            [offset + scale, scale, 0.0],
            [offset, scale, 0.5 * scale],
        ],
        faces: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Dense Cholesky log-density of N(x; 0, S) (S symmetric positive definite, n x n) and S^-1 x.
fn dense_gaussian(s: &[Vec<f64>], x: &[f64]) -> (f64, Vec<f64>) {
    let n = x.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let sum: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                let d = s[i][i] - sum;
                assert!(d > 0.0, "covariance not positive definite");
                l[i][i] = d.sqrt();
            } else {
                l[i][j] = (s[i][j] - sum) / l[j][j];
            }
        }
    }
    // L y = x, L^T u = y  ->  u = S^-1 x
    let mut y = vec![0.0; n];
    for i in 0..n {
        y[i] = (x[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut u = vec![0.0; n];
    for i in (0..n).rev() {
        u[i] = (y[i] - (i + 1..n).map(|k| l[k][i] * u[k]).sum::<f64>()) / l[i][i];
    }
    let log_det: f64 = 2.0 * (0..n).map(|i| l[i][i].ln()).sum::<f64>();
    let quad: f64 = y.iter().map(|v| v * v).sum();
    (-0.5 * (n as f64 * LN_2PI + log_det + quad), u)
}

fn component(ns: usize) -> Component {
    Component {
        rotations: (0..ns).map(|i| from_rows(rodrigues([1.0, 0.3 * i as f64, -0.7], 0.4 + 0.9 * i as f64))).collect(),
        translations: (0..ns).map(|i| [0.1 * i as f64, -0.05 * i as f64, 0.2]).collect(),
        lambda: [0.45, 0.3, 0.08],
        variances: (0..ns).map(|i| 2e-3 + 1e-3 * i as f64).collect(),
        weight: 0.3,
    }
}

dual_test! {
    fn natural_order_of_names() {
        let mut v = vec!["pose10.obj", "pose2.obj", "Pose1.obj", "pose02b.obj", "a.obj", "pose2.obj.bak"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, vec!["a.obj", "Pose1.obj", "pose2.obj", "pose2.obj.bak", "pose02b.obj", "pose10.obj"]);
        assert_eq!(natural_cmp("x9", "x10"), std::cmp::Ordering::Less);
        assert_eq!(natural_cmp("x010", "x9"), std::cmp::Ordering::Greater);
        assert_eq!(natural_cmp("same", "same"), std::cmp::Ordering::Equal);
    }

    fn population_sorts_and_normalises_with_one_scale() {
        let named = vec![
            ("10.obj".to_string(), square(4.0, 2.0)),
            ("2.obj".to_string(), square(0.0, 2.0)),
            ("1.obj".to_string(), square(-1.0, 2.0)),
        ];
        let p = Population::new(posemfa::mesh::Sources::Meshes(named)).unwrap();
        assert_eq!(p.names, vec!["1.obj", "2.obj", "10.obj"]);
        assert_eq!((p.n_shapes(), p.n_vertices(), p.faces.len()), (3, 4, 2));
        // x spans [-1, 6]: one common scale 1/7 and offset at the minimum corner for every shape
        let n = p.normalization;
        assert!((n.scale - 1.0 / 7.0).abs() < 1e-12, "scale {}", n.scale);
        assert_eq!(n.offset, [-1.0, 0.0, 0.0]);
        for shape in &p.unit_shapes() {
            for v in shape {
                assert!(v.iter().all(|c| (-1e-12..=1.0 + 1e-12).contains(c)), "{v:?} outside the unit box");
            }
        }
        // shape "10.obj" vertex 1 was (6, 0, 0): the far corner of the box, and it maps back
        assert!((p.unit_shapes()[2][1][0] - 1.0).abs() < 1e-12);
        let back = n.to_original(p.unit_shapes()[2][1]);
        assert!((back[0] - 6.0).abs() < 1e-12 && back[1].abs() < 1e-12);
    }

    fn population_rejects_a_mismatched_shape_and_names_it() {
        let mut bad = square(0.0, 1.0);
        bad.faces[1] = [0, 3, 2];
        let e = Population::new(posemfa::mesh::Sources::Meshes(vec![("a.obj".into(), square(0.0, 1.0)), ("b.obj".into(), bad)])).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("b.obj") && msg.contains("triangle 2"), "{msg}");
        let e = Population::new(posemfa::mesh::Sources::Meshes(vec![("only.obj".into(), square(0.0, 1.0))])).unwrap_err();
        assert!(e.to_string().contains("at least 2"), "{e}");
    }

    fn best_rotation_recovers_a_rotation() {
        let r = rodrigues([0.3, -0.5, 0.8], 2.1);
        let xs = [[1.0, 0.2, 0.0], [0.0, 1.0, 0.5], [0.3, 0.0, 1.0], [-1.0, 0.4, 0.2]];
        let mut c = [[0.0; 3]; 3];
        for x in &xs {
            let y = [0, 1, 2].map(|a| r[a][0] * x[0] + r[a][1] * x[1] + r[a][2] * x[2]);
            for a in 0..3 {
                for b in 0..3 {
                    c[a][b] += y[a] * x[b];
                }
            }
        }
        assert!(!needs_flip(&from_rows(c)));
        let got = rows(&best_rotation(&from_rows(c)));
        assert!(max_abs_diff(&got, &r) < 1e-10, "{got:?} vs {r:?}");
    }

    fn best_rotation_flips_handedness_on_the_smallest_singular_value() {
        // C = Q diag(3, 2, -1) P^T: its SVD has det(U V^T) = -1. The best ROTATION keeps the two large
        // singular directions and gives up the smallest: R = Q P^T (score 3 + 2 - 1 = 4), while the
        // unconstrained optimum Q diag(1, 1, -1) P^T (score 6) is a reflection.
        let q = rodrigues([0.2, 1.0, -0.4], 1.3);
        let p = rodrigues([-0.6, 0.1, 0.9], -2.4);
        let d = [[3.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, -1.0]];
        let c = mul(&mul(&q, &d), &tr(&p));
        assert!(needs_flip(&from_rows(c)));
        let got = rows(&best_rotation(&from_rows(c)));
        let want = mul(&q, &tr(&p));
        assert!(max_abs_diff(&got, &want) < 1e-9, "{got:?} vs {want:?}");
        assert!((det3(&got) - 1.0).abs() < 1e-12, "det {}", det3(&got));
        assert!((score(&got, &c) - 4.0).abs() < 1e-9);
        for k in 0..200 {
            let t = k as f64 * 0.173;
            let other = mul(&rodrigues([t.sin(), t.cos(), 0.5 - t.sin() * t.cos()], 3.0 * t.cos()), &want);
            assert!(score(&got, &c) >= score(&other, &c) - 1e-9);
        }
    }

    fn woodbury_log_density_equals_the_dense_gaussian() {
        for ns in [2usize, 3, 6] {
            let comp = component(ns);
            let wb = comp.woodbury();
            let h: Vec<[f64; 3]> = (0..ns).map(|i| {
                let t = i as f64;
                [0.3 * t.cos(), 0.1 - 0.2 * t.sin(), 0.05 * t]
            }).collect();
            // Σ = A A^T + Φ with A = [R_i Λ], x = h - b, all 3 ns dimensional
            let n = 3 * ns;
            let a: Vec<[f64; 3]> = (0..n).map(|row| {
                let (i, r) = (row / 3, row % 3);
                [0, 1, 2].map(|d| comp.rotations[i][(r, d)] * comp.lambda[d])
            }).collect();
            let sigma: Vec<Vec<f64>> = (0..n).map(|r| (0..n).map(|s| {
                let aa: f64 = (0..3).map(|d| a[r][d] * a[s][d]).sum();
                aa + if r == s { comp.variances[r / 3] } else { 0.0 }
            }).collect()).collect();
            let x: Vec<f64> = (0..n).map(|row| h[row / 3][row % 3] - comp.translations[row / 3][row % 3]).collect();
            let (log_n, sinv_x) = dense_gaussian(&sigma, &x);
            let dense = comp.weight.ln() + log_n;
            let fast = comp.log_weighted_density(&wb, &h);
            assert!((fast - dense).abs() < 1e-9 * dense.abs().max(1.0), "ns={ns}: {fast} vs {dense}");
            // E[z | h] = A^T Σ^-1 x
            let ez = comp.posterior_mean(&wb, &h);
            for d in 0..3 {
                let want: f64 = (0..n).map(|r| a[r][d] * sinv_x[r]).sum();
                assert!((ez[d] - want).abs() < 1e-9, "ns={ns} E[z]_{d}: {} vs {want}", ez[d]);
            }
        }
    }
}
