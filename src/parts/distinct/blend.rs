//! How far a part's motion is a fixed blend of two neighbours' motions, the flesh test of the part rule's
//! rule 1 ([`super::dissolve_flesh`]): on rotations ([`blend_ratio`], against every reference pose as the bind
//! pose) and on positions ([`blend_fit_ratio`], the two sides' rigid motions blended per vertex).

use crate::geometry::rotation::{angle_between, to_quat};
use crate::geometry::Mat3;
use crate::mesh::Population;
use crate::mfa::result::Model;
use crate::parts::motion_labels::motion_residual;

/// Motion of a part relative to pose r, per pose: R^i (R^r)^T (free of the part's latent frame).
fn relative_motion(rotations: &[Mat3], r: usize) -> Vec<Mat3> {
    let rt = rotations[r].transpose();
    rotations.iter().map(|m| m * rt).collect()
}

/// Most reference poses [`blend_ratio`] tries (with more poses, a spread subset of them).
pub const BLEND_REFERENCES: usize = 24;

/// The poses [`blend_ratio`] takes as the bind pose in turn: every pose, or up to [`BLEND_REFERENCES`] spread
/// ones ([`crate::parts::patches::spread_poses`]). Independent of the poses' order.
pub fn blend_references(pop: &Population) -> Vec<usize> {
    crate::parts::patches::spread_poses(pop, BLEND_REFERENCES)
}

/// How far part k's motion is from a fixed in-between of two of its neighbours' motions, as a fraction of how far
/// those two are apart: the minimum over neighbour pairs (a, b), t in [0, 1] (steps of 1/20) and reference poses
/// r in `refs` of RMS_i ∠(M_k^i, slerp(M_a^i, M_b^i, t)) / RMS_i ∠(M_a^i, M_b^i), with M^i = R^i (R^r)^T. Skinned
/// flesh is a fixed blend of its sides' motions relative to the bind pose, which is not known: each reference
/// pose is tried as the bind pose (so the ratio does not depend on which pose comes first). A slice of a blend
/// band moves as one fixed blend of its two sides: near 0. A part with a joint of its own turns independently:
/// large. Infinity without two neighbours that move apart (more than 1e-3 rad RMS).
pub fn blend_ratio(model: &Model, k: usize, adjacent: &[usize], refs: &[usize]) -> f64 {
    let mut ratios: Vec<f64> =
        refs.iter().map(|&r| blend_ratio_from(model, k, adjacent, r, f64::NEG_INFINITY)).collect();
    if ratios.is_empty() {
        return f64::INFINITY;
    }
    ratios.sort_by(f64::total_cmp);
    ratios[(ratios.len() - 1) / 2]
}

/// Whether [`blend_ratio`] is below `ratio`, with only the work that decides it: the median is below once more
/// than half the reference poses are, each of those known below at its first in-between under `ratio`, and not
/// once half of them (rounded up) are not.
pub fn is_blend(model: &Model, k: usize, adjacent: &[usize], refs: &[usize], ratio: f64) -> bool {
    // the median of n sorted values is the ((n - 1) / 2)-th: below `ratio` when at least `need` values are
    let need = (refs.len().max(1) - 1) / 2 + 1;
    let (mut below, mut above) = (0, 0);
    for &r in refs {
        if blend_ratio_from(model, k, adjacent, r, ratio) < ratio {
            below += 1;
        } else {
            above += 1;
        }
        if below >= need {
            return true;
        }
        if above > refs.len() - need {
            return false;
        }
    }
    false
}

/// [`blend_ratio`] with pose `r` as the bind pose; returns as soon as the ratio is known below `stop` (a value
/// below `stop`, not always the minimum).
///
/// Done in quaternions: with p_a = q_k^* q_a and p_b = q_k^* q_b (q_b on q_a's side of the 4-sphere, Ω the angle
/// between them), k's motion seen from slerp(q_a, q_b, t) is q_k^* slerp_t = (sin((1-t)Ω) p_a + sin(tΩ) p_b) / sin Ω,
/// linear in the two fixed products, and its rotation angle is 2 atan2(|vector part|, |scalar part|), which does
/// not depend on the scale. So each pose costs 21 sines per pair (one table read both ways) and one atan2 per t,
/// instead of a slerp, a matrix product and an atan2 per t. Equal to the matrix form to rounding (a test below).
fn blend_ratio_from(model: &Model, k: usize, adjacent: &[usize], r: usize, stop: f64) -> f64 {
    let ns = model.n_shapes;
    let mk = relative_motion(&model.parts[k].rotations, r);
    let ms: Vec<Vec<Mat3>> = adjacent.iter().map(|&a| relative_motion(&model.parts[a].rotations, r)).collect();
    let qk: Vec<[f64; 4]> = mk.iter().map(quat4).collect();
    let qs: Vec<Vec<[f64; 4]>> = ms.iter().map(|m| m.iter().map(quat4).collect()).collect();
    let rms = |f: &mut dyn FnMut(usize) -> f64| ((0..ns).map(|i| f(i).powi(2)).sum::<f64>() / ns as f64).sqrt();
    let mut best = f64::INFINITY;
    // per pose: p_a, p_b, and sin(sΩ/20) for s = 0..=20 (sin((1-t)Ω) is the same table read backwards)
    let mut ends = vec![([0.0; 4], [0.0; 4]); ns];
    let mut sines = vec![[0.0; SLERP_STEPS + 1]; ns];
    // the in-between's products p per pose, formed once for the bound and kept for the exact angles
    let mut ps = vec![[0.0; 4]; ns];
    for x in 0..ms.len() {
        for y in x + 1..ms.len() {
            let (ma, mb) = (&ms[x], &ms[y]);
            let apart = rms(&mut |i| angle_between(&ma[i], &mb[i]));
            if apart < 1e-3 {
                continue;
            }
            for i in 0..ns {
                let (qa, mut qb) = (qs[x][i], qs[y][i]);
                if dot4(&qa, &qb) < 0.0 {
                    qb = qb.map(|c| -c);
                }
                let omega = 2.0 * norm4(&sub4(&qa, &qb)).atan2(norm4(&add4(&qa, &qb)));
                let kc = conj4(&qk[i]);
                ends[i] = (mul4(&kc, &qa), mul4(&kc, &qb));
                for (s, v) in sines[i].iter_mut().enumerate() {
                    let t = s as f64 / SLERP_STEPS as f64;
                    // below 1e-12 rad slerp is the straight line (SlerpPath does the same)
                    *v = if omega < 1e-12 { t } else { (t * omega).sin() };
                }
            }
            // an in-between matters only below `stop` (deciding) or below the best so far (measuring)
            let matters = if stop > f64::NEG_INFINITY { stop } else { best };
            for step in 0..=SLERP_STEPS {
                // a lower bound first, without the atan2: the angle θ = 2 atan2(|v|, |w|) of p = (w, v) is at
                // least 2 sin(θ/2) = 2 |v| / |p| (sin x <= x), with a margin for rounding
                let mut low = 0.0;
                for (i, ((pa, pb), p)) in ends.iter().zip(ps.iter_mut()).enumerate() {
                    let (wa, wb) = (sines[i][SLERP_STEPS - step], sines[i][step]);
                    *p = std::array::from_fn(|c| wa * pa[c] + wb * pb[c]);
                    let v2 = p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
                    let n2 = v2 + p[0] * p[0];
                    if n2 > 0.0 {
                        low += 4.0 * v2 / n2;
                    }
                }
                if (low / ns as f64).sqrt() * (1.0 - 1e-9) / apart >= matters.min(best) {
                    continue;
                }
                let e = rms(&mut |i| {
                    let p = &ps[i];
                    2.0 * (p[1] * p[1] + p[2] * p[2] + p[3] * p[3]).sqrt().atan2(p[0].abs())
                });
                best = best.min(e / apart);
                if best < stop {
                    return best;
                }
            }
        }
    }
    best
}

/// Steps of t in [0, 1] at which [`blend_ratio`] tries the in-between (t = s / 20).
const SLERP_STEPS: usize = 20;

/// (w, x, y, z) of a rotation matrix.
fn quat4(m: &Mat3) -> [f64; 4] {
    let q = to_quat(m);
    [q.w, q.i, q.j, q.k]
}

fn conj4(q: &[f64; 4]) -> [f64; 4] {
    [q[0], -q[1], -q[2], -q[3]]
}

/// Hamilton product a b of (w, x, y, z) quaternions.
fn mul4(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn dot4(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}

fn add4(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    std::array::from_fn(|c| a[c] + b[c])
}

fn sub4(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    std::array::from_fn(|c| a[c] - b[c])
}

fn norm4(a: &[f64; 4]) -> f64 {
    dot4(a, a).sqrt()
}

/// The least of Σ_i |e_a^i - w d^i|² over w in [0, 1], from its parabola's coefficients aa = Σ|e_a|²,
/// ab = Σ e_a·d and bb = Σ|d|² (e_a = h - T_a, d = T_b - T_a): what a blend (1 - w) T_a + w T_b of two rigid
/// trajectories leaves of a vertex's points h (w = 0 when T_a = T_b).
pub fn two_bone_blend(aa: f64, ab: f64, bb: f64) -> f64 {
    let w = if bb > 0.0 { (ab / bb).clamp(0.0, 1.0) } else { 0.0 };
    (aa - 2.0 * w * ab + w * w * bb).max(0.0)
}

/// The best rigid trajectory of a vertex (`h`, one point per shape) under a part's motion: the mean of its points
/// brought back by the part's inverse motions, placed again in every shape (what [`motion_residual`] measures
/// against).
pub(crate) fn rigid_trajectory(part: &crate::mfa::Component, h: &[[f64; 3]], out: &mut [[f64; 3]]) {
    let ns = h.len();
    let mut mean = [0.0; 3];
    for (i, &p) in h.iter().enumerate() {
        let y = part.unplace(i, p);
        for a in 0..3 {
            mean[a] += y[a] / ns as f64;
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = part.place(i, mean);
    }
}

/// Most vertices of a part [`blend_fit_ratio`] looks at (evenly spaced; the ratio is a mean over vertices).
const BLEND_FIT_SAMPLE: usize = 256;

/// How well two neighbours' motions, blended per vertex, explain part k's vertices, against k's own rigid motion:
/// min over pairs (a, b) of `sides` of Σ_j min_{w in [0,1]} Σ_i |h_j^i - ((1-w) T_a(j)^i + w T_b(j)^i)|² over
/// Σ_j r_k(j), with T the vertex's best rigid trajectory under a part ([`rigid_trajectory`]) and r_k its
/// [`motion_residual`] (on at most [`BLEND_FIT_SAMPLE`] of k's vertices), each per the residual degrees of freedom
/// its own fit leaves: times (1 - 2/n - 1/n_s) / (1 - 1/(3 n_s)) for a part of n vertices and n_s shapes (the own
/// fit's motion and latent points against the blend's weight; about 1/2 at 4 vertices, 0.98 at 100 with many
/// shapes). Flesh of a skinning blend band is a fixed blend of its sides per vertex: below 1 (its own rigid motion
/// explains it worse than the blend: a wide band's slice measures 0.17-0.33 on the generated spider, band 0.10). A part with a joint of its own: far above
/// (12.7 and more on the generated creatures). Infinity without two sides.
pub fn blend_fit_ratio(model: &Model, pop: &Population, k: usize, members: &[usize], sides: &[usize]) -> f64 {
    let ns = pop.n_shapes();
    let stride = members.len().div_ceil(BLEND_FIT_SAMPLE).max(1);
    let sample: Vec<usize> = members.iter().copied().step_by(stride).collect();
    let points: Vec<Vec<[f64; 3]>> = sample.iter().map(|&j| pop.track(j)).collect();
    let own: f64 = points.iter().map(|h| motion_residual(&model.parts[k], h)).sum();
    let (mut ta, mut tb) = (vec![[0.0; 3]; ns], vec![[0.0; 3]; ns]);
    let mut best = f64::INFINITY;
    for x in 0..sides.len() {
        for y in x + 1..sides.len() {
            let (pa, pb) = (&model.parts[sides[x]], &model.parts[sides[y]]);
            let mut blend = 0.0;
            for h in &points {
                rigid_trajectory(pa, h, &mut ta);
                rigid_trajectory(pb, h, &mut tb);
                // Σ_i |h - T_a - w (T_b - T_a)|² is a parabola in w
                let (mut aa, mut ab, mut bb) = (0.0, 0.0, 0.0);
                for i in 0..ns {
                    for c in 0..3 {
                        let (e, d) = (h[i][c] - ta[i][c], tb[i][c] - ta[i][c]);
                        aa += e * e;
                        ab += e * d;
                        bb += d * d;
                    }
                }
                blend += two_bone_blend(aa, ab, bb);
            }
            best = best.min(blend);
        }
    }
    if best.is_infinite() {
        return best;
    }
    // per residual degree of freedom: the part's own fit spends 6 numbers per pose on its motion (2 / n of each
    // vertex's 3 coordinates per pose) and 3 per vertex on its latent point, the blend one weight per vertex. A
    // part of a few vertices otherwise wins by fitting its own noise: a 4-vertex ring where three or four bones
    // share the skinning weights measured 1.2-1.6 and stayed a part
    let n = members.len().max(1) as f64;
    let own_dof = (1.0 - 2.0 / n - 1.0 / ns as f64).max(1e-3);
    let blend_dof = 1.0 - 1.0 / (3.0 * ns as f64);
    best / own.max(f64::MIN_POSITIVE) * own_dof / blend_dof
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;
    use crate::mfa::Component;

    pub(crate) fn part(angles: &[f64], axis: [f64; 3]) -> Component {
        Component {
            rotations: angles.iter().map(|&a| axis_angle(axis, a)).collect(),
            translations: vec![[0.0; 3]; angles.len()],
            lambda: [0.1; 3],
            variances: vec![1e-6; angles.len()],
            weight: 1.0 / 3.0,
        }
    }

    pub(crate) fn model(parts: Vec<Component>) -> Model {
        Model {
            n_shapes: parts[0].rotations.len(),
            n_vertices: 0,
            parts,
            labels: Vec::new(),
            latent: Vec::new(),
            log_likelihood: Vec::new(),
            iterations: 0,
            converged: true,
        }
    }

    /// The matrix form [`blend_ratio_from`] replaced: slerp, matrix, angle at every t.
    fn blend_ratio_from_matrices(model: &Model, k: usize, adjacent: &[usize], r: usize) -> f64 {
        let mk = relative_motion(&model.parts[k].rotations, r);
        let ms: Vec<Vec<Mat3>> = adjacent.iter().map(|&a| relative_motion(&model.parts[a].rotations, r)).collect();
        // the neighbours' motions as quaternions once (slerp converts both ends at every t otherwise)
        let qs: Vec<Vec<crate::geometry::rotation::Quat>> =
            ms.iter().map(|m| m.iter().map(to_quat).collect()).collect();
        let rms =
            |f: &dyn Fn(usize) -> f64| ((0..mk.len()).map(|i| f(i).powi(2)).sum::<f64>() / mk.len() as f64).sqrt();
        let mut best = f64::INFINITY;
        for x in 0..ms.len() {
            for y in x + 1..ms.len() {
                let (ma, mb) = (&ms[x], &ms[y]);
                let apart = rms(&|i| angle_between(&ma[i], &mb[i]));
                if apart < 1e-3 {
                    continue;
                }
                // slerp(ma[i], mb[i], t) = paths[i].matrix_at(t), bit for bit
                let paths: Vec<crate::geometry::rotation::SlerpPath> =
                    qs[x].iter().zip(&qs[y]).map(|(&a, &b)| crate::geometry::rotation::SlerpPath::new(a, b)).collect();
                for step in 0..=20 {
                    let t = step as f64 / 20.0;
                    let e = rms(&|i| angle_between(&mk[i], &paths[i].matrix_at(t)));
                    best = best.min(e / apart);
                }
            }
        }
        best
    }

    #[test]
    fn the_quaternion_blend_ratio_equals_the_matrix_one() {
        // random parts (some near a blend of two others, some not), every reference pose
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let ns = 9;
        let mut u = || rng.gen::<f64>();
        let mut seen = [0; 2];
        for trial in 0..40 {
            let mut axis = || [u() - 0.5, u() - 0.5, u() - 0.5];
            let (ax, bx, cx) = (axis(), axis(), axis());
            let a: Vec<Mat3> = (0..ns).map(|_| axis_angle(ax, 3.0 * (u() - 0.5))).collect();
            let b: Vec<Mat3> = (0..ns).map(|_| axis_angle(bx, 3.0 * (u() - 0.5))).collect();
            let t = u();
            let noise = if trial % 2 == 0 { 0.02 } else { 1.0 };
            let k: Vec<Mat3> = (0..ns)
                .map(|i| {
                    let blend = crate::geometry::rotation::slerp(&a[i], &b[i], t);
                    axis_angle(cx, noise * (u() - 0.5)) * blend
                })
                .collect();
            let d = part(&vec![0.0; ns], ax);
            let comp = |r: Vec<Mat3>| Component { rotations: r, ..d.clone() };
            let other: Vec<Mat3> = (0..ns).map(|_| axis_angle(cx, 2.0 * (u() - 0.5))).collect();
            let m = model(vec![comp(a), comp(b), comp(k), comp(other)]);
            for r in 0..ns {
                let (new, old) = (
                    blend_ratio_from(&m, 2, &[0, 1, 3], r, f64::NEG_INFINITY),
                    blend_ratio_from_matrices(&m, 2, &[0, 1, 3], r),
                );
                assert!((new - old).abs() <= 1e-9 * old.max(1e-3), "trial {trial} ref {r}: {new} against {old}");
            }
            // the early-stopping decision is the full ratio's, for every threshold and reference set around it
            let refs: Vec<usize> = (0..ns).collect();
            for cut in [0.05, 0.1, 0.2, 0.4, 0.8] {
                for n in [1, 2, 5, ns] {
                    let full = blend_ratio(&m, 2, &[0, 1, 3], &refs[..n]);
                    assert_eq!(
                        is_blend(&m, 2, &[0, 1, 3], &refs[..n], cut),
                        full < cut,
                        "trial {trial}: {full} against {cut}, {n} references"
                    );
                    seen[(full < cut) as usize] += 1;
                }
            }
        }
        assert!(seen[0] > 100 && seen[1] > 100, "decisions either way: {seen:?}");
    }

    #[test]
    fn a_fixed_blend_of_two_neighbours_is_flesh_and_an_own_joint_is_not() {
        let a: Vec<f64> = vec![0.0; 6];
        let b: Vec<f64> = (0..6).map(|i| 0.15 * i as f64 - 0.3).collect();
        // 35 % of the way from a to b in every pose
        let flesh: Vec<f64> = b.iter().map(|x| 0.35 * x).collect();
        let m = model(vec![part(&a, [0.0, 0.0, 1.0]), part(&b, [0.0, 0.0, 1.0]), part(&flesh, [0.0, 0.0, 1.0])]);
        assert!(blend_ratio(&m, 2, &[0, 1], &[0]) < 0.01, "{}", blend_ratio(&m, 2, &[0, 1], &[0]));
        // the same angles in another order: a joint of its own, not a blend
        let own: Vec<f64> = [0.2, -0.3, 0.1, 0.4, -0.1, 0.0].to_vec();
        let m = model(vec![part(&a, [0.0, 0.0, 1.0]), part(&b, [0.0, 0.0, 1.0]), part(&own, [1.0, 0.0, 0.0])]);
        assert!(blend_ratio(&m, 2, &[0, 1], &[0]) > 0.5, "{}", blend_ratio(&m, 2, &[0, 1], &[0]));
        // neighbours that move together give no in-between to test
        let m = model(vec![part(&a, [0.0, 0.0, 1.0]), part(&a, [0.0, 0.0, 1.0]), part(&own, [1.0, 0.0, 0.0])]);
        assert_eq!(blend_ratio(&m, 2, &[0, 1], &[0]), f64::INFINITY);
        assert_eq!(blend_ratio(&m, 2, &[0], &[0]), f64::INFINITY);
    }
}
