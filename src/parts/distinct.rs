//! The part rule's two rules, which decide how many parts without any absolute threshold (both rules of a fit
//! use them: [`crate::parts::hierarchy`]). Two ratios, both dimensionless, so the rule is the same for a shape
//! at any scale, mesh resolution or number of poses (README, "A part count without tuning"):
//!
//! 1. **Flesh is not a part** ([`dissolve_flesh`]). A part whose motion is, in every pose, one fixed in-between
//!    of two neighbours' motions (a slice of a skinning blend band) is the joint's flesh: its vertices go to
//!    whichever neighbour moves them best. Test: [`blend_ratio`] < `blend_ratio` (on rotations) or
//!    [`blend_fit_ratio`] < 1 (on positions: the two sides' motions blended per vertex explain the part better
//!    than its own rigid motion), between two neighbours at least the part's own size.
//! 2. **A joint must explain the motion**. Two adjacent parts stay apart only if fitting
//!    them as one rigid body costs their smaller side, per vertex, at least `distinct_ratio` times the variance of
//!    a typical part of this very fit (the vertex-weighted median of the parts' variances, fixed before any
//!    merge). The merge tree's rule reads the count off a merge tree of the fitted parts
//!    ([`crate::parts::merge_tree`]); with Algorithm 1 ([`crate::mfa::params::PartRule::Distinct`]) pairs below
//!    are merged, cheapest first ([`merge_indistinct`]).
//!
//! With Algorithm 1, its refinement runs first without a threshold (it splits while a split lowers the variance
//! by `refine_min_gain`, and keeps a split only when it lowers the variance, or the cut sub-part's squared
//! residuals, `distinct_ratio` times); the final AECM runs on its labels, then 1 and 2, then the final AECM once
//! more if any part went.

use super::labels::{adjacency, compact, weighted_median};
pub use super::merge_tree::CurvePoint;
use super::motion_labels::motion_residual;
use crate::mesh::Population;
use crate::mfa::params::{InFit, RunParams};
use crate::mfa::result::Model;

mod blend;
pub(crate) use blend::rigid_trajectory;
pub use blend::{blend_fit_ratio, blend_ratio, blend_references, is_blend, two_bone_blend, BLEND_REFERENCES};

/// Rule 1: dissolves, smallest first, every part whose [`blend_ratio`] is below `ratio` or whose
/// [`blend_fit_ratio`] is below 1 (both between sides at least its own size); each of its vertices goes
/// to the adjacent part whose motion moves it best ([`motion_residual`]) and takes its latent image under that part
/// (eq 21). The removed part's mixing weight is shared out in proportion. Returns how many parts went.
pub fn dissolve_flesh(model: &mut Model, pop: &Population, ratio: f64) -> usize {
    let mut dissolved = 0;
    let mut h = vec![[0.0; 3]; pop.n_shapes()];
    let refs = blend_references(pop);
    // Both tests are functions of the parts' motions, which this loop never changes, of the sides and (the fit
    // ratio) of the part's vertices: remembered by the parts' first indices, so a dissolution re-tests only the
    // parts it touched.
    let mut ids: Vec<usize> = (0..model.n_parts()).collect();
    let mut rotation_memo: std::collections::HashMap<(usize, Vec<usize>), bool> = Default::default();
    let mut fit_memo: std::collections::HashMap<(usize, Vec<usize>, Vec<usize>), f64> = Default::default();
    loop {
        if model.n_parts() < 3 {
            return dissolved;
        }
        let (adjacent, members) = adjacency(&model.labels, pop.graph_faces(), model.n_parts());
        // the sides a slice of flesh lies between: its neighbours at least its own size (a band slice is thinner
        // than the bodies it joins; a small part of its own, whose rotation a few vertices barely fix, must not
        // make a whole limb look like a blend of it and the next limb)
        // and, through a smaller neighbour, that neighbour's own neighbours at least k's size: a band cut into two
        // slices (a start from small patches leaves such chains; the generated spider's hips at 12 k vertices)
        // has one big side beyond each slice
        let sides: Vec<Vec<usize>> = (0..model.n_parts())
            .map(|k| {
                let big = |a: &usize| members[*a].len() >= members[k].len();
                let mut s: Vec<usize> = adjacent[k].iter().copied().filter(big).collect();
                for &a in adjacent[k].iter().filter(|a| !big(a)) {
                    s.extend(adjacent[a].iter().copied().filter(|&b| b != k && big(&b)));
                }
                s.sort_unstable();
                s.dedup();
                s
            })
            .collect();
        let mut order: Vec<usize> = (0..model.n_parts()).filter(|&k| sides[k].len() >= 2).collect();
        order.sort_by_key(|&k| members[k].len());
        let mut flesh = |k: usize| {
            let side_ids: Vec<usize> = sides[k].iter().map(|&a| ids[a]).collect();
            if *rotation_memo
                .entry((ids[k], side_ids.clone()))
                .or_insert_with(|| is_blend(model, k, &sides[k], &refs, ratio))
            {
                return Some(f64::NAN);
            }
            let f = *fit_memo
                .entry((ids[k], side_ids, members[k].clone()))
                .or_insert_with(|| blend_fit_ratio(model, pop, k, &members[k], &sides[k]));
            (f < 1.0).then_some(f)
        };
        let Some((k, f)) = order.clone().into_iter().find_map(|k| flesh(k).map(|x| (k, x))) else {
            if crate::trace::enabled() {
                for k in (0..model.n_parts()).filter(|&k| members[k].len() < 60) {
                    let r = blend_ratio(model, k, &sides[k], &refs);
                    let f = blend_fit_ratio(model, pop, k, &members[k], &sides[k]);
                    crate::trace_line!(
                        "kept: part {k} ({} vertices) adjacent {:?} sides {:?} blend {r:.3} fit {f:.3}",
                        members[k].len(),
                        adjacent[k],
                        sides[k]
                    );
                }
            }
            return dissolved;
        };
        if crate::trace::enabled() {
            let r = blend_ratio(model, k, &sides[k], &refs);
            crate::trace_line!(
                "flesh: part {k} ({} vertices) dissolved, blend ratio {r:.3}, blend fit {f:.3}",
                members[k].len()
            );
        }
        for &j in &members[k] {
            for (i, s) in pop.shapes().enumerate() {
                h[i] = s.get(j);
            }
            // (each neighbour's residual once; min_by keeps the first of equal ones, as before)
            let to = adjacent[k]
                .iter()
                .map(|&a| (a, motion_residual(&model.parts[a], &h)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("at least two neighbours")
                .0;
            model.labels[j] = to as u32;
            model.latent[j] = model.parts[to].latent_image(&h);
        }
        let gone = model.parts.remove(k).weight;
        ids.remove(k);
        let left = (1.0 - gone).max(f64::MIN_POSITIVE);
        for c in model.parts.iter_mut() {
            c.weight /= left;
        }
        for l in model.labels.iter_mut() {
            if *l as usize > k {
                *l -= 1;
            }
        }
        dissolved += 1;
    }
}

/// Mean variance of the best rigid fit (generalised Procrustes, [`crate::mfa::init::component_from_points`]) of a set of
/// vertices; with multi-resolution, estimated on at most `subset_vertices` evenly spaced ones.
pub fn rigid_variance(pop: &Population, members: &[usize], params: &RunParams) -> f64 {
    let thinned: Vec<usize>;
    let subset = params.algorithm1.subset_vertices;
    let members = if subset > 0 && members.len() > subset {
        let stride = members.len().div_ceil(subset);
        thinned = members.iter().copied().step_by(stride).collect();
        &thinned[..]
    } else {
        members
    };
    crate::mfa::init::component_from_population(pop, members, members.len(), params.floor()).mean_variance()
}

/// Rule 2: merges adjacent parts whose motions are not distinct, cheapest first. The score of a pair (a, b) is
///
///   (n_ab s_ab - n_a s_a - n_b s_b) / (min(n_a, n_b) s_ref),
///
/// the rise in squared error when one rigid motion has to move both, per vertex of the smaller side, over the
/// variance s_ref of a typical part of the fit (vertex-weighted median of the parts' s before any merge; fixed, so
/// that a merge does not make the next one look cheap). s = [`rigid_variance`]. Pairs scoring below
/// `params.distinct_ratio` are merged. Returns compact labels and the curve of decisions.
pub fn merge_indistinct(pop: &Population, labels: &[u32], params: &impl InFit) -> (Vec<u32>, Vec<CurvePoint>) {
    let params = &params.in_fit(|| pop.mean_squared_radius());
    let mut labels = compact(labels);
    let (_, members) = adjacency(&labels, pop.graph_faces(), 0);
    let mut err: Vec<f64> = members.iter().map(|m| rigid_variance(pop, m, params)).collect();
    let sizes: Vec<usize> = members.iter().map(|m| m.len()).collect();
    let s_ref = weighted_median(&err, &sizes).max(params.floor());
    let mut cache: std::collections::HashMap<(u32, u32), (f64, f64)> = std::collections::HashMap::new();
    let mut curve = Vec::new();
    loop {
        let (adjacent, members) = adjacency(&labels, pop.graph_faces(), 0);
        let n_total = labels.len().max(1) as f64;
        let variance = members.iter().zip(&err).map(|(m, e)| m.len() as f64 * e).sum::<f64>() / n_total;
        let mut best: Option<((u32, u32), f64, f64)> = None;
        for (a, adj) in adjacent.iter().enumerate() {
            for &b in adj.iter().filter(|&&b| b > a) {
                let key = (a as u32, b as u32);
                let (score, joint) = *cache.entry(key).or_insert_with(|| {
                    let mut union = members[a].clone();
                    union.extend_from_slice(&members[b]);
                    let joint = rigid_variance(pop, &union, params);
                    let (na, nb) = (members[a].len() as f64, members[b].len() as f64);
                    let rise = union.len() as f64 * joint - na * err[a] - nb * err[b];
                    (rise / (na.min(nb) * s_ref), joint)
                });
                if best.is_none_or(|x| score < x.1) {
                    best = Some((key, score, joint));
                }
            }
        }
        let n_parts = members.len();
        let Some(((a, b), score, joint)) = best else {
            curve.push(CurvePoint { parts: n_parts, score: f64::INFINITY, variance, merged: false });
            break;
        };
        let merged = score < params.distinct.distinct_ratio;
        curve.push(CurvePoint { parts: n_parts, score, variance, merged });
        if !merged {
            break;
        }
        // merge b into a; labels above b shift down, cached pairs with them
        cache = merge_pair(&mut labels, cache, a, b);
        err[a as usize] = joint;
        err.remove(b as usize);
    }
    (labels, curve)
}

/// Merges label b into a (a < b) in compact labels: labels above b shift down, and the cache of pair scores keeps
/// the pairs that touch neither, renumbered. Shared by both part rules' greedy merges.
pub(crate) fn merge_pair<T>(
    labels: &mut [u32],
    cache: std::collections::HashMap<(u32, u32), T>,
    a: u32,
    b: u32,
) -> std::collections::HashMap<(u32, u32), T> {
    for l in labels.iter_mut() {
        if *l == b {
            *l = a;
        } else if *l > b {
            *l -= 1;
        }
    }
    let shift = |x: u32| if x > b { x - 1 } else { x };
    cache
        .into_iter()
        .filter(|((p, q), _)| *p != a && *q != a && *p != b && *q != b)
        .map(|((p, q), e)| ((shift(p), shift(q)), e))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::blend::tests::{model, part};
    use super::*;
    use crate::synth::{generate, Preset, Spec};

    #[test]
    fn a_limb_is_not_flesh_between_its_neighbour_and_a_small_part_beyond_it() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let idx = |name| crate::synth::part_index(Preset::Arm, name).unwrap() as u32;
        let (upper, forearm) = (idx("upper_arm"), idx("forearm"));
        let mut labels = g.part_of_vertex.clone();
        let touches = |j: usize, l: u32| {
            pop.faces.iter().any(|f| f.contains(&(j as u32)) && f.iter().any(|&v| g.part_of_vertex[v as usize] == l))
        };
        // part 3: the forearm's ring at the elbow, a slice of flesh (35 % of the way from the upper arm to the
        // forearm); part 4: the 20 forearm vertices farthest from the elbow, a small part that turns twice as
        // far as the forearm, so the forearm itself lies halfway between the upper arm and it
        let forearm_ids: Vec<usize> = (0..labels.len()).filter(|&j| labels[j] == forearm).collect();
        let ring: Vec<usize> = forearm_ids.iter().copied().filter(|&j| touches(j, upper)).collect();
        assert!(!ring.is_empty() && ring.len() < 200, "{} ring vertices", ring.len());
        let elbow = ring[0];
        let d = |j: usize| {
            let (p, q) = (pop.point(0, j), pop.point(0, elbow));
            (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)
        };
        let mut far = forearm_ids.clone();
        far.sort_by(|&a, &b| d(b).total_cmp(&d(a)));
        ring.iter().for_each(|&j| labels[j] = 3);
        far[..20].iter().for_each(|&j| labels[j] = 4);
        let n = pop.n_shapes();
        let b: Vec<f64> = (0..n).map(|i| 0.1 * i as f64 - 0.3).collect();
        let mut angles = vec![vec![0.0; n]; 5];
        angles[forearm as usize] = b.clone();
        angles[3] = b.iter().map(|x| 0.35 * x).collect();
        angles[4] = b.iter().map(|x| 2.0 * x).collect();
        let mut m = model(angles.iter().map(|a| part(a, [0.0, 0.0, 1.0])).collect());
        m.n_vertices = labels.len();
        m.labels = labels;
        m.latent = vec![[0.0; 3]; m.n_vertices];
        let forearm_size = forearm_ids.len() - ring.len() - 20;
        assert_eq!(
            dissolve_flesh(&mut m, pop, crate::mfa::Params::default().distinct.blend_ratio),
            1,
            "only the slice is flesh"
        );
        assert_eq!(m.n_parts(), 4);
        assert!(m.labels.iter().filter(|&&l| l == forearm).count() >= forearm_size);
    }

    #[test]
    fn a_wide_blend_band_is_flesh_by_positions_and_a_limb_is_not() {
        // the arm with a blend band twice the default: the elbow's band as a part of its own (part 3)
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, joint_band: 0.10, ..Spec::default() })
            .unwrap();
        let pop = &g.population;
        let idx = |name| crate::synth::part_index(Preset::Arm, name).unwrap() as u32;
        let (upper, forearm) = (idx("upper_arm"), idx("forearm"));
        let mut labels = g.part_of_vertex.clone();
        for (j, b) in g.blend.iter().enumerate() {
            let elbow = b.parts.contains(&upper) && b.parts.contains(&forearm);
            if elbow && b.weight > 0.02 && b.weight < 0.98 {
                labels[j] = 3;
            }
        }
        let members: Vec<Vec<usize>> =
            (0..4).map(|k| (0..labels.len()).filter(|&j| labels[j] == k).collect()).collect();
        assert!(members.iter().all(|m| m.len() >= 20), "{:?}", members.iter().map(|m| m.len()).collect::<Vec<_>>());
        let parts = members
            .iter()
            .map(|m| {
                let mut c = crate::mfa::init::component_from_population(pop, m, labels.len(), 1e-12);
                let offsets = crate::mfa::data::Data::centroids(pop, m);
                for (t, o) in c.translations.iter_mut().zip(offsets) {
                    *t = crate::geometry::add(*t, o);
                }
                c
            })
            .collect();
        let mut m = model(parts);
        m.labels = labels;
        let band = blend_fit_ratio(&m, pop, 3, &members[3], &[upper as usize, forearm as usize]);
        assert!(band < 1.0, "the band: {band}");
        let limb = blend_fit_ratio(&m, pop, upper as usize, &members[upper as usize], &[idx("base") as usize, 3]);
        assert!(limb > 4.0, "the upper arm: {limb}");
        assert_eq!(blend_fit_ratio(&m, pop, 3, &members[3], &[upper as usize]), f64::INFINITY);
    }

    #[test]
    fn halves_of_one_rigid_part_merge_and_true_parts_stay_apart() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let pop = &g.population;
        // the true parts, with the forearm (the largest) cut in two across its length by vertex order
        let mut labels = g.part_of_vertex.clone();
        let forearm = crate::synth::part_index(Preset::Arm, "forearm").unwrap() as u32;
        let members: Vec<usize> = (0..labels.len()).filter(|&j| labels[j] == forearm).collect();
        let first = pop.shape(0).to_vec();
        let mid = crate::geometry::bounds(members.iter().map(|&j| &first[j]));
        let axis = (0..3).max_by(|&x, &y| (mid.1[x] - mid.0[x]).total_cmp(&(mid.1[y] - mid.0[y]))).unwrap();
        let cut = 0.5 * (mid.0[axis] + mid.1[axis]);
        for &j in &members {
            if pop.point(0, j)[axis] > cut {
                labels[j] = 3;
            }
        }
        let (merged, curve) = merge_indistinct(pop, &labels, &crate::mfa::Params::default());
        let ari = crate::metrics::adjusted_rand_index(&merged, &g.part_of_vertex);
        assert!(ari > 0.999, "ari {ari}, curve {curve:?}");
        assert_eq!(curve.len(), 2, "{curve:?}");
        assert_eq!((curve[0].parts, curve[1].parts), (4, 3));
        assert!(
            curve[0].score < 1.0 && curve[1].score > crate::mfa::Params::default().distinct.distinct_ratio,
            "{curve:?}"
        );
    }
}
