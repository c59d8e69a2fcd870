//! Skinning weights and blending of part motions per vertex.
//!
//! Rigid parts crease and stretch at joints (docs/method.md, item 9). The smooth weights spread each part
//! boundary over a band: for a vertex j of part p and another part k at mesh distance d (Dijkstra over the
//! edges, each edge as long as its mean length over the training shapes), k gets the raw weight
//! φ(d / h_k) with φ(x) = 1 - 3x² + 2x³ on [0, 1) and 0 beyond, and p itself gets φ(0) = 1; the raw weights
//! are normalised (glTF export keeps the four largest, see [`SkinWeights::capped`]). The band half-width
//! h_k = band · reach_k, where reach_k is the smallest RMS radius (about its centroid, measured on the rigid
//! latent shape) of k and its neighbours: a small part next to k narrows k's band. h depends on k alone, so
//! the weights are continuous across boundaries even where several parts meet. At a boundary both sides
//! weigh about 1/2; the other part's weight falls smoothly to 0 at distance h on each side.
//!
//! The weights are a smooth prior, not fitted: weights fitted by least squares to carry every training
//! shape onto every other (tried during development) did not lower the stretch on the horse, where the data changes edge lengths by up to 2.5x between poses
//! at part boundaries; [`edge_blend`] is what handles that.
//!
//! Blending: dual-quaternion skinning (Kavan et al. 2007: the weighted sum of unit dual quaternions, signs
//! aligned with the heaviest, normalised) or linear blend skinning (the weighted sum of the matrices).

use super::graph::{mesh_edges, PartGraph, VertexNeighbours};
use super::{Blend, RigidMotion};
use crate::geometry::rotation::{from_quat, to_quat};
use crate::geometry::{norm, scale, sub, Mat3, Vec3};
use nalgebra::Quaternion;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Influences per vertex a glTF viewer blends (JOINTS_0 / WEIGHTS_0).
pub const GLTF_INFLUENCES: usize = 4;

/// Default band (half-width of the blend on each side of a boundary, as a fraction of the part's reach).
/// On the horse (poses 3 -> 8, t = 1/2) 0.5 / 1 / 2 / 3 gave p99 boundary stretch 28 / 24 / 23 / 22 % with
/// the position average and about 17 % with the edge blend for 1 to 2; wider bands raise the stretch of the
/// other edges (p99 over all edges 13 % at band 3 on poses 5 -> 6, 7 % at band 1).
pub const DEFAULT_BAND: f64 = 1.0;

/// Per-vertex part weights: (part, weight) pairs, weights positive and summing to 1, the vertex's own part
/// first, then heaviest first.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinWeights {
    pub influences: Vec<Vec<(u32, f64)>>,
}

impl SkinWeights {
    /// One-hot weights: every vertex on its own part.
    pub fn rigid(labels: &[u32]) -> SkinWeights {
        SkinWeights { influences: labels.iter().map(|&l| vec![(l, 1.0)]).collect() }
    }

    pub fn len(&self) -> usize {
        self.influences.len()
    }

    pub fn is_empty(&self) -> bool {
        self.influences.is_empty()
    }

    /// (part, weight) pairs of vertex v.
    pub fn influences(&self, v: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.influences[v].iter().map(|&(k, w)| (k as usize, w))
    }

    /// The `n` heaviest influences of every vertex, renormalised (for glTF's four).
    pub fn capped(&self, n: usize) -> SkinWeights {
        SkinWeights {
            influences: self
                .influences
                .iter()
                .map(|inf| {
                    let mut v = inf.clone();
                    v.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                    v.truncate(n.max(1));
                    let sum: f64 = v.iter().map(|x| x.1).sum();
                    v.iter().map(|&(k, w)| (k, w / sum)).collect()
                })
                .collect(),
        }
    }

    /// Dense n_vertices x n_parts matrix (row-major), for display.
    pub fn dense(&self, n_parts: usize) -> Vec<f64> {
        let mut out = vec![0.0; self.len() * n_parts];
        for v in 0..self.len() {
            for (k, w) in self.influences(v) {
                out[v * n_parts + k] += w;
            }
        }
        out
    }
}

fn phi(x: f64) -> f64 {
    if x >= 1.0 {
        0.0
    } else {
        let x = x.max(0.0);
        1.0 - x * x * (3.0 - 2.0 * x)
    }
}

/// RMS radius of every part about its centroid, from the latent shape.
pub fn part_radii(labels: &[u32], latent: &[Vec3], n_parts: usize) -> Vec<f64> {
    let mut c = vec![[0.0; 3]; n_parts];
    let mut n = vec![0.0; n_parts];
    for (v, &l) in latent.iter().zip(labels) {
        let l = l as usize;
        c[l] = crate::geometry::add(c[l], *v);
        n[l] += 1.0;
    }
    for k in 0..n_parts {
        c[k] = scale(c[k], 1.0 / f64::max(n[k], 1.0));
    }
    let mut r2 = vec![0.0; n_parts];
    for (v, &l) in latent.iter().zip(labels) {
        let d = norm(sub(*v, c[l as usize]));
        r2[l as usize] += d * d;
    }
    (0..n_parts).map(|k| (r2[k] / f64::max(n[k], 1.0)).sqrt()).collect()
}

/// Every edge's length averaged over `shapes`, read one shape at a time.
pub fn mean_edge_lengths<S: AsRef<[Vec3]>>(edges: &[[u32; 2]], shapes: impl IntoIterator<Item = S>) -> Vec<f64> {
    let mut sum = vec![0.0; edges.len()];
    let mut n = 0usize;
    for s in shapes {
        let s = s.as_ref();
        for (e, x) in edges.iter().zip(sum.iter_mut()) {
            *x += norm(sub(s[e[0] as usize], s[e[1] as usize]));
        }
        n += 1;
    }
    sum.iter().map(|x| x / n.max(1) as f64).collect()
}

/// Smooth weights (module doc). `band` scales every blend half-width; `shapes` gives the edge lengths.
pub fn smooth_weights<S: AsRef<[Vec3]>>(
    graph: &PartGraph,
    labels: &[u32],
    latent: &[Vec3],
    faces: &[[u32; 3]],
    shapes: impl IntoIterator<Item = S>,
    band: f64,
) -> SkinWeights {
    let nv = labels.len();
    let n_parts = graph.n_parts;
    let radii = part_radii(labels, latent, n_parts);
    // Every part's reach depends on that part alone, so the raw weights are continuous across boundaries:
    // its own radius, or its smallest neighbour's if smaller (a small part next to it bounds the band).
    let reach: Vec<f64> =
        (0..n_parts).map(|k| graph.neighbors[k].iter().map(|&n| radii[n]).fold(radii[k], f64::min)).collect();
    // CSR adjacency with mean edge lengths.
    let edges = mesh_edges(faces);
    let edge_len = mean_edge_lengths(&edges, shapes);
    let neighbours = VertexNeighbours::new(&edges, nv);
    // raw[v]: (part, raw weight) pairs; the own part first.
    let mut raw: Vec<Vec<(u32, f64)>> = labels.iter().map(|&l| vec![(l, 1.0)]).collect();
    let mut dist = vec![f64::INFINITY; nv];
    let mut touched: Vec<usize> = Vec::new();
    for k in 0..n_parts {
        if graph.vertex_count[k] == 0 || graph.neighbors[k].is_empty() {
            continue;
        }
        let cutoff = band * reach[k];
        if !(cutoff > 0.0) {
            continue;
        }
        let mut heap = BinaryHeap::new();
        for v in 0..nv {
            if labels[v] as usize == k {
                dist[v] = 0.0;
                touched.push(v);
                heap.push(Reverse((0u64, v)));
            }
        }
        while let Some(Reverse((dbits, v))) = heap.pop() {
            let d = f64::from_bits(dbits);
            if d > dist[v] {
                continue;
            }
            for &(u, e) in neighbours.of(v) {
                let u = u as usize;
                let nd = d + edge_len[e];
                if nd < cutoff && nd < dist[u] {
                    if dist[u].is_infinite() {
                        touched.push(u);
                    }
                    dist[u] = nd;
                    heap.push(Reverse((nd.to_bits(), u)));
                }
            }
        }
        for &v in &touched {
            let p = labels[v] as usize;
            if p != k {
                let w = phi(dist[v] / cutoff);
                if w > 0.0 {
                    raw[v].push((k as u32, w));
                }
            }
            dist[v] = f64::INFINITY;
        }
        touched.clear();
    }
    let influences = raw
        .into_iter()
        .map(|mut r| {
            // own part first, then by weight
            r[1..].sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            let sum: f64 = r.iter().map(|x| x.1).sum();
            r.iter().map(|&(k, w)| (k, w / sum)).collect()
        })
        .collect();
    SkinWeights { influences }
}

/// Edge vector at t between a and b: direction by slerp of the unit vectors, length (1-t)|a| + t|b|.
pub fn slerp_vector(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    let (la, lb) = (norm(a), norm(b));
    let mix = |p: Vec3, q: Vec3| crate::geometry::add(scale(p, 1.0 - t), scale(q, t));
    if !(la > 0.0 && lb > 0.0) {
        return mix(a, b);
    }
    let (ua, ub) = (scale(a, 1.0 / la), scale(b, 1.0 / lb));
    // the angle between them as atan2(|a x b|, a . b): accurate near 0 and π, unlike acos of the dot product
    let theta = norm(crate::geometry::cross(ua, ub)).atan2(crate::geometry::dot(ua, ub));
    let dir = if theta < 1e-9 || theta > std::f64::consts::PI - 1e-6 {
        mix(ua, ub)
    } else {
        let s = theta.sin();
        crate::geometry::add(scale(ua, ((1.0 - t) * theta).sin() / s), scale(ub, (t * theta).sin() / s))
    };
    let n = norm(dir);
    if n > 0.0 {
        scale(dir, ((1.0 - t) * la + t * lb) / n)
    } else {
        mix(a, b)
    }
}

/// Anchor weight of [`edge_blend`] (relative to a vertex's edge weights).
pub const EDGE_BLEND_ANCHOR: f64 = 0.01;

/// Solves of [`edge_blend`], each anchored to the one before.
pub const EDGE_BLEND_PASSES: usize = 3;

/// Blends two versions `a`, `b` of the same mesh at t by their edges rather than their positions.
///
/// Averaging positions shortens every edge whose two versions point different ways (by cos(angle / 2)
/// at t = 1/2): at joints, where the data is least rigid, that is where edges collapse. Here every edge
/// (p, q) gets a target vector g_pq = [`slerp_vector`](a_p - a_q, b_p - b_q, t), rescaled to `lengths[k]`
/// (edge k of `edges`) when given, and the positions solve
/// min Σ_pq w_pq |x_p - x_q - g_pq|² + ε Σ_p d_p |x_p - m_p|², with w_pq = 1/|g_pq|² (relative errors),
/// d_p = Σ_q w_pq, m = (1-t) a + t b (which fixes the translation and keeps the shape from drifting) and
/// ε = `anchor`. Solved by Jacobi-preconditioned conjugate gradients from m, [`EDGE_BLEND_PASSES`] times,
/// each pass anchored to the previous result instead of m (so the pull toward the shrunken average fades).
/// When a and b agree (t = 0 or 1 in particular) m is the exact solution and is returned as it is.
pub fn edge_blend(
    a: &[Vec3],
    b: &[Vec3],
    t: f64,
    edges: &[[u32; 2]],
    lengths: Option<&[f64]>,
    anchor: f64,
) -> Vec<Vec3> {
    let n = a.len();
    let m: Vec<Vec3> = a.iter().zip(b).map(|(p, q)| crate::geometry::add(scale(*p, 1.0 - t), scale(*q, t))).collect();
    let g: Vec<Vec3> = edges
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let (p, q) = (e[0] as usize, e[1] as usize);
            let v = slerp_vector(sub(a[p], a[q]), sub(b[p], b[q]), t);
            match lengths {
                Some(l) if norm(v) > 0.0 => scale(v, l[k] / norm(v)),
                _ => v,
            }
        })
        .collect();
    let w: Vec<f64> = g.iter().map(|v| 1.0 / crate::geometry::dot(*v, *v).max(1e-30)).collect();
    let mut diag = vec![0.0; n];
    for (k, e) in edges.iter().enumerate() {
        diag[e[0] as usize] += w[k];
        diag[e[1] as usize] += w[k];
    }
    let eps: Vec<f64> = diag.iter().map(|d| anchor * d.max(1e-300)).collect();
    let mut div: Vec<Vec3> = vec![[0.0; 3]; n];
    for (k, e) in edges.iter().enumerate() {
        let (p, q) = (e[0] as usize, e[1] as usize);
        div[p] = crate::geometry::add(div[p], scale(g[k], w[k]));
        div[q] = sub(div[q], scale(g[k], w[k]));
    }
    // y = A x, into a buffer kept across the iterations (a new one each time cost page faults)
    let apply = |x: &[Vec3], y: &mut [Vec3]| {
        for v in 0..n {
            y[v] = scale(x[v], diag[v] + eps[v]);
        }
        for (k, e) in edges.iter().enumerate() {
            let (p, q) = (e[0] as usize, e[1] as usize);
            y[p] = sub(y[p], scale(x[q], w[k]));
            y[q] = sub(y[q], scale(x[p], w[k]));
        }
    };
    let dot3 = |u: &[Vec3], v: &[Vec3]| {
        let mut s = [0.0; 3];
        for (p, q) in u.iter().zip(v) {
            for d in 0..3 {
                s[d] += p[d] * q[d];
            }
        }
        s
    };
    let pre: Vec<f64> = (0..n).map(|v| 1.0 / (diag[v] + eps[v])).collect();
    // Each pass anchors to the previous pass's result: the pull toward the (shrunken) average fades.
    let mut x = m;
    let mut ap: Vec<Vec3> = vec![[0.0; 3]; n];
    for _ in 0..EDGE_BLEND_PASSES {
        let rhs: Vec<Vec3> = (0..n).map(|v| crate::geometry::add(div[v], scale(x[v], eps[v]))).collect();
        let mut ax: Vec<Vec3> = vec![[0.0; 3]; n];
        apply(&x, &mut ax);
        let mut r: Vec<Vec3> = (0..n).map(|v| sub(rhs[v], ax[v])).collect();
        let scale_rhs = dot3(&rhs, &rhs).map(f64::sqrt);
        let mut z: Vec<Vec3> = (0..n).map(|v| scale(r[v], pre[v])).collect();
        let mut p = z.clone();
        let mut rz = dot3(&r, &z);
        for _ in 0..(4 * n).max(100) {
            let rr = dot3(&r, &r);
            if (0..3).all(|d| rr[d].sqrt() <= 1e-8 * scale_rhs[d].max(1e-300)) {
                break;
            }
            apply(&p, &mut ap);
            let pap = dot3(&p, &ap);
            let alpha = [0, 1, 2].map(|d| if pap[d] > 0.0 { rz[d] / pap[d] } else { 0.0 });
            for v in 0..n {
                for d in 0..3 {
                    x[v][d] += alpha[d] * p[v][d];
                    r[v][d] -= alpha[d] * ap[v][d];
                }
                z[v] = scale(r[v], pre[v]);
            }
            let rz2 = dot3(&r, &z);
            let beta = [0, 1, 2].map(|d| if rz[d] > 0.0 { rz2[d] / rz[d] } else { 0.0 });
            for v in 0..n {
                for d in 0..3 {
                    p[v][d] = z[v][d] + beta[d] * p[v][d];
                }
            }
            rz = rz2;
        }
    }
    x
}

/// A unit dual quaternion q_r + ε q_d for x -> R x + b: q_r = quat(R), q_d = (0, b) q_r / 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualQuat {
    pub real: Quaternion<f64>,
    pub dual: Quaternion<f64>,
}

impl DualQuat {
    pub fn from_motion(m: &RigidMotion) -> DualQuat {
        let real = to_quat(&m.rotation).into_inner();
        let t = Quaternion::new(0.0, m.translation[0], m.translation[1], m.translation[2]);
        DualQuat { real, dual: (t * real) * 0.5 }
    }

    /// Normalised (by the real part's length) and turned back into a rigid motion.
    pub fn to_motion(&self) -> RigidMotion {
        let n = self.real.norm();
        let (r, d) = (self.real * (1.0 / n), self.dual * (1.0 / n));
        let t = (d * r.conjugate()) * 2.0;
        RigidMotion { rotation: from_quat(r), translation: [t.i, t.j, t.k] }
    }
}

fn motion_sum(ms: &[(RigidMotion, f64)]) -> RigidMotion {
    let mut r = Mat3::zeros();
    let mut b = [0.0; 3];
    for (m, w) in ms {
        for a in 0..3 {
            for c in 0..3 {
                r[(a, c)] += w * m.rotation[(a, c)];
            }
            b[a] += w * m.translation[a];
        }
    }
    RigidMotion { rotation: r, translation: b }
}

/// The blended motion of vertex v: Σ_k w_vk M_k (linear: an affine map, not a rigid motion in general) or
/// the dual-quaternion blend. With a single influence it is that part's motion exactly.
pub fn blend_motion(motions: &[RigidMotion], weights: &SkinWeights, v: usize, blend: Blend) -> RigidMotion {
    let mut inf = weights.influences(v);
    let Some((k0, w0)) = inf.next() else { return RigidMotion::IDENTITY };
    let rest: Vec<(usize, f64)> = inf.collect();
    if rest.is_empty() {
        return motions[k0];
    }
    match blend {
        Blend::Linear => {
            let mut all = vec![(motions[k0], w0)];
            all.extend(rest.iter().map(|&(k, w)| (motions[k], w)));
            motion_sum(&all)
        }
        Blend::DualQuaternion => {
            let q0 = DualQuat::from_motion(&motions[k0]);
            let mut real = q0.real * w0;
            let mut dual = q0.dual * w0;
            for (k, w) in rest {
                let q = DualQuat::from_motion(&motions[k]);
                let s = if q.real.dot(&q0.real) < 0.0 { -w } else { w };
                real = real + q.real * s;
                dual = dual + q.dual * s;
            }
            DualQuat { real, dual }.to_motion()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;

    #[test]
    fn dual_quaternion_round_trip_and_blend() {
        let m = RigidMotion { rotation: axis_angle([1.0, 2.0, 0.5], 2.5), translation: [0.3, -1.0, 2.0] };
        let back = DualQuat::from_motion(&m).to_motion();
        let p = [0.7, -0.2, 0.4];
        assert!(norm(sub(back.apply(p), m.apply(p))) < 1e-12);
        // half-way between two rotations about the same axis through the origin = the half rotation
        let a = RigidMotion { rotation: axis_angle([0.0, 0.0, 1.0], 0.0), translation: [0.0; 3] };
        let b = RigidMotion { rotation: axis_angle([0.0, 0.0, 1.0], 1.2), translation: [0.0; 3] };
        let w = SkinWeights { influences: vec![vec![(0, 0.5), (1, 0.5)]] };
        let mid = blend_motion(&[a, b], &w, 0, Blend::DualQuaternion);
        let want = axis_angle([0.0, 0.0, 1.0], 0.6);
        assert!(crate::geometry::rotation::angle_between(&mid.rotation, &want) < 1e-12);
        // linear blending shrinks the same point (candy-wrapper effect): |p| is kept by DQ, not by LBS
        let lin = blend_motion(&[a, b], &w, 0, Blend::Linear);
        let q = [1.0, 0.0, 0.0];
        assert!((norm(mid.apply(q)) - 1.0).abs() < 1e-12);
        assert!(norm(lin.apply(q)) < 0.96);
        // a rotation about a point away from the origin: DQ keeps that point fixed
        let c = [2.0, 1.0, 0.0];
        let r = axis_angle([0.0, 0.0, 1.0], 1.0);
        let about_c = RigidMotion { rotation: r, translation: sub(c, crate::geometry::mat_vec(&r, c)) };
        let id = RigidMotion::IDENTITY;
        let blended = blend_motion(&[id, about_c], &w, 0, Blend::DualQuaternion);
        assert!(norm(sub(blended.apply(c), c)) < 1e-12);
    }

    #[test]
    fn sign_of_quaternions_does_not_matter() {
        // a 350° rotation equals a -10° one; its quaternion has the other sign: blending must go the short way
        let a = RigidMotion { rotation: axis_angle([0.0, 0.0, 1.0], 0.2), translation: [0.0; 3] };
        let b = RigidMotion { rotation: axis_angle([0.0, 0.0, 1.0], (350f64).to_radians()), translation: [0.0; 3] };
        let w = SkinWeights { influences: vec![vec![(0, 0.5), (1, 0.5)]] };
        let mid = blend_motion(&[a, b], &w, 0, Blend::DualQuaternion);
        let want = axis_angle([0.0, 0.0, 1.0], (0.2 - 10f64.to_radians()) / 2.0);
        assert!(crate::geometry::rotation::angle_between(&mid.rotation, &want) < 1e-12);
    }

    #[test]
    fn smooth_weights_on_a_strip() {
        // 21 columns of 2 vertices along x, unit spacing; part 0 = columns 0..=10, part 1 = 11..=20
        let mut pos = Vec::new();
        let mut labels = Vec::new();
        for i in 0..=20 {
            for y in 0..2 {
                pos.push([i as f64, y as f64 * 0.01, 0.0]);
                labels.push(if i <= 10 { 0 } else { 1 });
            }
        }
        let mut faces = Vec::new();
        for i in 0..20u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            faces.push([a, c, b]);
            faces.push([b, c, d]);
        }
        let graph = PartGraph::new(&labels, &faces, 2, &pos, &[]);
        let radii = part_radii(&labels, &pos, 2);
        // RMS radius of 11 (10) unit-spaced columns about their middle: sqrt(10) (sqrt(99 / 12))
        assert!(
            (radii[0] - 10f64.sqrt()).abs() < 1e-3 && (radii[1] - (99.0f64 / 12.0).sqrt()).abs() < 1e-3,
            "{radii:?}"
        );
        let w = smooth_weights(&graph, &labels, &pos, &faces, &[pos.clone()], 1.0);
        let h = radii[0].min(radii[1]);
        for v in 0..pos.len() {
            let sum: f64 = w.influences(v).map(|x| x.1).sum();
            assert!((sum - 1.0).abs() < 1e-12);
            let x = pos[v][0];
            let w1 = w.dense(2)[v * 2 + 1];
            // distance to the other part along x (the diagonals are slightly longer but not shorter)
            let d = if x <= 10.0 { 11.0 - x } else { x - 10.0 };
            let other = phi(d / h);
            let want = if x <= 10.0 { other / (1.0 + other) } else { 1.0 / (1.0 + other) };
            assert!((w1 - want).abs() < 0.02, "x={x}: w1={w1}, want {want}");
        }
        // monotone across the boundary, 0 and 1 far away
        let col = |i: usize| w.dense(2)[(2 * i) * 2 + 1];
        assert_eq!(col(0), 0.0);
        assert_eq!(col(20), 1.0);
        for i in 0..20 {
            assert!(col(i + 1) >= col(i));
        }
    }

    #[test]
    fn edge_blend_turns_edges_instead_of_shortening_them() {
        // a 12 x 12 sheet, and the same sheet turned by 60 degrees about its middle: the position average
        // is 13 % too small (cos 30°); the edge blend is the sheet turned by 30 degrees
        let n = 12u32;
        let a: Vec<Vec3> = (0..n * n).map(|v| [(v % n) as f64, (v / n) as f64, 0.1 * ((v % n) as f64).sin()]).collect();
        let r = crate::geometry::rotation::axis_angle([0.0, 0.0, 1.0], 60f64.to_radians());
        let c = [5.5, 5.5, 0.0];
        let turn = |r: &Mat3, p: Vec3| crate::geometry::add(crate::geometry::mat_vec(r, sub(p, c)), c);
        let b: Vec<Vec3> = a.iter().map(|&p| turn(&r, p)).collect();
        let mut faces = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let v = y * n + x;
                faces.push([v, v + 1, v + n]);
                faces.push([v + 1, v + n + 1, v + n]);
            }
        }
        let edges = mesh_edges(&faces);
        // ends: returned exactly
        assert_eq!(edge_blend(&a, &b, 0.0, &edges, None, EDGE_BLEND_ANCHOR), a);
        assert_eq!(edge_blend(&a, &b, 1.0, &edges, None, EDGE_BLEND_ANCHOR), b);
        let x = edge_blend(&a, &b, 0.5, &edges, None, EDGE_BLEND_ANCHOR);
        let half = crate::geometry::rotation::axis_angle([0.0, 0.0, 1.0], 30f64.to_radians());
        let (mut worst, mut worst_avg, mut mean) = (0.0f64, 0.0f64, 0.0);
        for e in &edges {
            let (p, q) = (e[0] as usize, e[1] as usize);
            let want = crate::geometry::mat_vec(&half, sub(a[p], a[q]));
            let err = norm(sub(sub(x[p], x[q]), want)) / norm(want);
            worst = worst.max(err);
            mean += err / edges.len() as f64;
            let avg = sub(scale(crate::geometry::add(a[p], b[p]), 0.5), scale(crate::geometry::add(a[q], b[q]), 0.5));
            worst_avg = worst_avg.max(norm(sub(avg, want)) / norm(want));
        }
        // (the anchor toward the shrunken average, ε = EDGE_BLEND_ANCHOR, still pulls a little: 1.6 % at worst)
        assert!(worst < 0.03 && mean < 0.015, "edge blend: worst {worst}, mean {mean}");
        assert!(worst_avg > 0.13, "position average: {worst_avg}");
        // target lengths are honoured
        let lengths: Vec<f64> = edges.iter().map(|e| 1.2 * norm(sub(a[e[0] as usize], a[e[1] as usize]))).collect();
        let y = edge_blend(&a, &b, 0.5, &edges, Some(&lengths), EDGE_BLEND_ANCHOR);
        for (k, e) in edges.iter().enumerate() {
            let l = norm(sub(y[e[0] as usize], y[e[1] as usize]));
            assert!((l / lengths[k] - 1.0).abs() < 0.03, "edge {k}: {l} vs {}", lengths[k]);
        }
    }
}
