//! Initialisation (docs/method.md#item-11; the paper's "as in McLachlan et al. 2003" is undefined here):
//! k-means++ on the data vectors h_j with restarts drawn from ONE seeded stream (best by k-means cost),
//! then per cluster: the generalised-Procrustes mean of its points in principal axes (det +1) is the latent
//! shape, R^i is the SO(3) Procrustes fit of that latent shape onto shape i, Λ the latent shape's principal
//! standard deviations, s^i the mean squared residual, b^i the cluster centroid in shape i, π its share.

use super::component::Component;
use super::data::Data;
use crate::geometry::procrustes::best_rotation;
use crate::geometry::{mat_mul, mat_t_vec, mat_vec, sub, Mat3, Vec3};
use crate::mesh::population::widen;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Squared distance between two data vectors (four running sums, so that the loop vectorises).
#[inline]
fn dist2<A: Copy + Into<f64>, B: Copy + Into<f64>>(a: &[A], b: &[B]) -> f64 {
    let mut acc = [0.0; 4];
    let (a4, a_rest) = a.as_chunks::<4>();
    let (b4, b_rest) = b.as_chunks::<4>();
    for (x, y) in a4.iter().zip(b4) {
        for l in 0..4 {
            let d = x[l].into() - y[l].into();
            acc[l] += d * d;
        }
    }
    let rest: f64 = a_rest.iter().zip(b_rest).map(|(&x, &y)| (x.into() - y.into()) * (x.into() - y.into())).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}

/// A uniform index below `n`, the same on every target: rand draws a `usize` range from a `usize`, which is 64
/// bits natively and 32 in wasm32, so `gen_range(0..n)` on `usize` picked other vertices in the page than in the
/// CLI (another k-means++ start, so another fit: horse-poses 32 parts in wasm, 29 natively). Drawn as `u64`.
fn index_below(rng: &mut Pcg64, n: usize) -> usize {
    rng.gen_range(0..n as u64) as usize
}

avx2_fn! {
    /// One k-means++ seeding + Lloyd run. Returns (labels, cost).
    fn kmeans_once(data: &Data, m: usize, rng: &mut Pcg64, lloyd_iters: usize) -> (Vec<u32>, f64) {
        let n = data.n_vertices;
        let dim = data.n_shapes * 3;
        // h_j gathered from the data's layout, as stored (f32), into a reused buffer
        let (mut buf, mut buf2) = (Vec::with_capacity(dim), Vec::with_capacity(dim));
        let mut centres: Vec<f64> = Vec::with_capacity(m * dim);
        let first = index_below(rng, n);
        let c0: Vec<f32> = data.row_into(first, &mut buf).to_vec();
        centres.extend(c0.iter().map(|&v| v as f64));
        let mut d2: Vec<f64> = (0..n).map(|j| dist2(data.row_into(j, &mut buf), &c0)).collect();
        while centres.len() < m * dim {
            let total: f64 = d2.iter().sum();
            let pick = if total > 0.0 {
                let mut t = rng.gen::<f64>() * total;
                let mut p = n - 1;
                for (j, &v) in d2.iter().enumerate() {
                    if t < v {
                        p = j;
                        break;
                    }
                    t -= v;
                }
                p
            } else {
                index_below(rng, n)
            };
            let c: Vec<f64> = data.row_into(pick, &mut buf).iter().map(|&v| v as f64).collect();
            for j in 0..n {
                d2[j] = d2[j].min(dist2(data.row_into(j, &mut buf), &c));
            }
            centres.extend_from_slice(&c);
        }
        let mut labels = vec![0u32; n];
        let mut cost = f64::INFINITY;
        for _ in 0..lloyd_iters {
            // assignment
            let mut new_cost = 0.0;
            let mut changed = false;
            for j in 0..n {
                let r = data.row_into(j, &mut buf);
                let mut best = (f64::INFINITY, 0u32);
                for k in 0..m {
                    let d = dist2(r, &centres[k * dim..(k + 1) * dim]);
                    if d < best.0 {
                        best = (d, k as u32);
                    }
                }
                if labels[j] != best.1 {
                    changed = true;
                }
                labels[j] = best.1;
                new_cost += best.0;
            }
            // update; re-seed empty clusters with the point farthest from its centre
            let mut counts = vec![0usize; m];
            let mut sums = vec![0.0; m * dim];
            for j in 0..n {
                let k = labels[j] as usize;
                counts[k] += 1;
                for (s, &v) in sums[k * dim..(k + 1) * dim].iter_mut().zip(data.row_into(j, &mut buf)) {
                    *s += v as f64;
                }
            }
            for k in 0..m {
                if counts[k] == 0 {
                    let far = (0..n)
                        .max_by(|&a, &b| {
                            let da = dist2(data.row_into(a, &mut buf), &centres[labels[a] as usize * dim..(labels[a] as usize + 1) * dim]);
                            let db = dist2(data.row_into(b, &mut buf2), &centres[labels[b] as usize * dim..(labels[b] as usize + 1) * dim]);
                            da.partial_cmp(&db).unwrap_or(std::cmp::Ordering::Equal)
                        })
                        .unwrap_or(0);
                    for (c, &v) in centres[k * dim..(k + 1) * dim].iter_mut().zip(data.row_into(far, &mut buf)) {
                        *c = v as f64;
                    }
                    labels[far] = k as u32;
                    changed = true;
                } else {
                    for d in 0..dim {
                        centres[k * dim + d] = sums[k * dim + d] / counts[k] as f64;
                    }
                }
            }
            let done = !changed || (cost - new_cost).abs() <= 1e-12 * cost.abs();
            cost = new_cost;
            if done {
                break;
            }
        }
        (labels, cost)
    }
}

/// k-means++ with `restarts` restarts drawn from one stream seeded by `seed`; the lowest cost wins.
pub fn kmeans(data: &Data, m: usize, seed: u64, restarts: usize) -> Vec<u32> {
    let m = m.min(data.n_vertices).max(1);
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut best: Option<(Vec<u32>, f64)> = None;
    for _ in 0..restarts.max(1) {
        let (labels, cost) = kmeans_once(data, m, &mut rng, 50);
        if best.as_ref().is_none_or(|b| cost < b.1) {
            best = Some((labels, cost));
        }
    }
    best.map(|b| b.0).unwrap_or_default()
}

/// Symmetric 3x3 eigen-decomposition: eigenvalues descending, eigenvector matrix with det +1 (columns).
fn principal_axes(cov: &Mat3) -> (Vec3, Mat3) {
    let eig = cov.symmetric_eigen();
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| eig.eigenvalues[b].partial_cmp(&eig.eigenvalues[a]).unwrap_or(std::cmp::Ordering::Equal));
    let mut p = Mat3::zeros();
    let mut vals = [0.0; 3];
    for (col, &e) in idx.iter().enumerate() {
        vals[col] = eig.eigenvalues[e];
        for r in 0..3 {
            p[(r, col)] = eig.eigenvectors[(r, e)];
        }
    }
    if crate::geometry::det(&p) < 0.0 {
        p.column_mut(2).neg_mut();
    }
    (vals, p)
}

/// One component fitted to the vertices `members` by generalised Procrustes analysis.
pub fn component_from_points(data: &Data, members: &[usize], n_total: usize, floor: f64) -> Component {
    let ns = data.n_shapes;
    let n = members.len();
    // the members' points, shape-major, in f32 as the data store them
    let mut xs = vec![[0.0f32; 3]; ns * n];
    for (m, &j) in members.iter().enumerate() {
        for (i, p) in data.vertex(j).iter().enumerate() {
            xs[i * n + m] = crate::mesh::population::narrow(p);
        }
    }
    procrustes_start(ns, n, xs, n_total, floor)
}

/// [`component_from_points`] of `Data::from_population_subset(pop, members)`'s vertices, all of them, without
/// the copy: the same points (each shape centred on the members' centroid, rounded to f32 as `Data` stores
/// them), so the same component bit for bit.
pub fn component_from_population(
    pop: &crate::mesh::Population,
    members: &[usize],
    n_total: usize,
    floor: f64,
) -> Component {
    let offsets = super::data::Data::centroids(pop, members);
    component_from_population_centred(pop, members, &offsets, n_total, floor)
}

/// [`component_from_points`] of `members` of data whose shapes are centred on `offsets` (the data of a
/// population and its offsets, e.g. `Data::from_population(pop)` for `Data::centroids(pop, all vertices)`), read
/// from the population without that copy: the same component bit for bit.
pub fn component_from_population_centred(
    pop: &crate::mesh::Population,
    members: &[usize],
    offsets: &[Vec3],
    n_total: usize,
    floor: f64,
) -> Component {
    let ns = pop.n_shapes();
    let n = members.len();
    let mut xs = vec![[0.0f32; 3]; ns * n];
    for ((i, shape), &offset) in pop.shapes().enumerate().zip(offsets) {
        for (x, &j) in xs[i * n..(i + 1) * n].iter_mut().zip(members) {
            // rounded to f32 as `Data` stores it
            *x = crate::mesh::population::narrow(sub(shape.get(j), offset));
        }
    }
    procrustes_start(ns, n, xs, n_total, floor)
}

avx2_fn! {
    /// Generalised Procrustes on `n` points in each of `ns` shapes, `xs[i * n + m]` = point m in shape i (see the
    /// module doc). Every loop runs shape by shape over the points in order (contiguous reads), with a sum's
    /// accumulators in registers; each sum adds the points in their order.
    fn procrustes_start(ns: usize, n: usize, xs: Vec<[f32; 3]>, n_total: usize, floor: f64) -> Component {
        let nf = n.max(1) as f64;
        let mut centroids = vec![[0.0; 3]; ns];
        for (c, shape) in centroids.iter_mut().zip(xs.chunks_exact(n.max(1))) {
            for &p in shape.iter() {
                let p = widen(p);
                for d in 0..3 {
                    c[d] += p[d] / nf;
                }
            }
        }
        // the points centred on their shape's centroid, computed where they are read (f64, the same values as
        // subtracting once and storing: the points stay f32, half the bytes)
        let shape = |i: usize| {
            let c = centroids[i];
            xs[i * n..(i + 1) * n].iter().map(move |&p| sub(widen(p), c))
        };
        // generalised Procrustes: X_i ≈ R_i mean
        let mut mean: Vec<Vec3> = if ns > 0 { shape(0).collect() } else { vec![[0.0; 3]; n] };
        let mut rots = vec![crate::geometry::IDENTITY; ns];
        for _ in 0..4 {
            for (i, rot) in rots.iter_mut().enumerate() {
                let mut c = [[0.0; 3]; 3];
                for (x, mm) in shape(i).zip(&mean) {
                    for a in 0..3 {
                        for b in 0..3 {
                            c[a][b] += x[a] * mm[b];
                        }
                    }
                }
                *rot = best_rotation(&Mat3::from_fn(|a, b| c[a][b]));
            }
            mean.iter_mut().for_each(|mm| *mm = [0.0; 3]);
            for (i, rot) in rots.iter().enumerate() {
                for (mm, x) in mean.iter_mut().zip(shape(i)) {
                    let v = mat_t_vec(rot, x);
                    for d in 0..3 {
                        mm[d] += v[d] / ns as f64;
                    }
                }
            }
        }
        // principal axes of the mean shape
        let mut cov = Mat3::zeros();
        for mm in &mean {
            for a in 0..3 {
                for b in 0..3 {
                    cov[(a, b)] += mm[a] * mm[b] / nf;
                }
            }
        }
        let (vals, p) = principal_axes(&cov);
        let latent: Vec<Vec3> = mean.iter().map(|&mm| mat_t_vec(&p, mm)).collect();
        let rotations: Vec<Mat3> = rots.iter().map(|r| mat_mul(r, &p)).collect();
        let variances: Vec<f64> = rotations
            .iter()
            .enumerate()
            .map(|(i, rot)| {
                let mut s = 0.0;
                for (x, y) in shape(i).zip(&latent) {
                    let d = sub(x, mat_vec(rot, *y));
                    s += d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                }
                (s / (3.0 * nf)).max(floor)
            })
            .collect();
        Component {
            rotations,
            translations: centroids,
            lambda: vals.map(|v| v.max(0.0).sqrt().max(super::cm::LAMBDA_FLOOR)),
            variances,
            weight: nf / n_total.max(1) as f64,
        }
    }
}

/// Components from a labelling (labels need not be contiguous; empty labels are skipped).
pub fn components_from_labels(data: &Data, labels: &[u32], floor: f64) -> Vec<Component> {
    let m = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let mut members = vec![Vec::new(); m];
    for (j, &l) in labels.iter().enumerate() {
        members[l as usize].push(j);
    }
    members
        .iter()
        .filter(|mem| !mem.is_empty())
        .map(|mem| component_from_points(data, mem, data.n_vertices, floor))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::{angle_between, axis_angle};
    use crate::mesh::Population;

    #[test]
    fn procrustes_start_recovers_a_rigid_cluster() {
        let rest: Vec<Vec3> = (0..30)
            .map(|j| {
                let t = j as f64;
                [0.3 * (t * 0.7).sin(), 0.1 * (t * 1.3).cos(), 0.05 * (t * 0.37).sin()]
            })
            .collect();
        let truth: Vec<Mat3> = (0..4).map(|i| axis_angle([1.0, 0.5, i as f64], 0.4 * i as f64)).collect();
        let shapes: Vec<Vec<Vec3>> = truth.iter().map(|r| rest.iter().map(|&p| mat_vec(r, p)).collect()).collect();
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: (0..4).map(|i| i.to_string()).collect(),
            faces: vec![[0, 1, 2]],
            shapes,
        })
        .unwrap();
        let data = Data::from_population(&pop);
        let comps = components_from_labels(&data, &vec![0; 30], 1e-9);
        assert_eq!(comps.len(), 1);
        let c = &comps[0];
        for i in 1..4 {
            let rel_fit = mat_mul(&c.rotations[i], &crate::geometry::transpose(&c.rotations[0]));
            let rel_true = mat_mul(&truth[i], &crate::geometry::transpose(&truth[0]));
            assert!(angle_between(&rel_fit, &rel_true) < 1e-6);
            assert!((crate::geometry::det(&c.rotations[i]) - 1.0).abs() < 1e-9);
        }
        assert!(c.variances.iter().all(|&s| s < 1e-8), "{:?}", c.variances);
        assert!(c.lambda[0] >= c.lambda[1] && c.lambda[1] >= c.lambda[2]);
    }

    #[test]
    fn kmeans_is_seeded_and_separates_blobs() {
        let shapes: Vec<Vec<Vec3>> = (0..2)
            .map(|i| {
                (0..60)
                    .map(|j| {
                        let c = (j / 20) as f64;
                        [c + 0.01 * (j as f64).sin(), 0.01 * (j as f64 + i as f64).cos(), 0.0]
                    })
                    .collect()
            })
            .collect();
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces: vec![[0, 1, 2]],
            shapes,
        })
        .unwrap();
        let data = Data::from_population(&pop);
        let a = kmeans(&data, 3, 7, 3);
        assert_eq!(a, kmeans(&data, 3, 7, 3));
        for blob in 0..3 {
            let l = a[blob * 20];
            assert!((blob * 20..blob * 20 + 20).all(|j| a[j] == l));
        }
    }
}
