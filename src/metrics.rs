//! Accuracy against ground truth: the adjusted Rand index of two labellings, and rotation errors of fitted
//! parts.

use crate::error::{Error, Result};
use crate::geometry::rotation::angle_between;
use crate::geometry::{mat_mul, transpose, Mat3};
use serde::Serialize;
use std::collections::HashMap;

/// Maps arbitrary label values to 0..k in order of first appearance, and k.
fn compact(labels: &[u32]) -> (Vec<usize>, usize) {
    let out: Vec<usize> = crate::parts::labels::compact(labels).into_iter().map(|l| l as usize).collect();
    let k = out.iter().max().map_or(0, |&l| l + 1);
    (out, k)
}

fn pairs(x: u64) -> u128 {
    let x = x as u128;
    x * x.saturating_sub(1) / 2
}

/// Adjusted Rand index (Hubert and Arabie 1985) of two labellings of the same items:
///
/// ARI = (I - E) / (M - E), with I = sum_ij C(n_ij, 2) over the contingency table, A = sum_i C(a_i, 2),
/// B = sum_j C(b_j, 2), E = A B / C(n, 2) and M = (A + B) / 2.
///
/// Label values are arbitrary (only the partitions matter). 1 for identical partitions up to relabelling,
/// about 0 for independent ones, negative for worse than chance. The one case where M = E (both labellings
/// put everything in one cluster, or both put every item alone, or fewer than 2 items) means identical
/// partitions and returns 1, never NaN. Computed in exact integer arithmetic up to the final division.
///
/// Panics if the two slices differ in length.
pub fn adjusted_rand_index(a: &[u32], b: &[u32]) -> f64 {
    assert_eq!(a.len(), b.len(), "adjusted_rand_index: the labellings have {} and {} items", a.len(), b.len());
    let n = a.len();
    if n < 2 {
        return 1.0;
    }
    let (ca, ka) = compact(a);
    let (cb, kb) = compact(b);
    let mut rows = vec![0u64; ka];
    let mut cols = vec![0u64; kb];
    let mut cells: HashMap<(usize, usize), u64> = HashMap::new();
    for (&i, &j) in ca.iter().zip(&cb) {
        rows[i] += 1;
        cols[j] += 1;
        *cells.entry((i, j)).or_insert(0) += 1;
    }
    let index: u128 = cells.values().map(|&c| pairs(c)).sum();
    let sa: u128 = rows.iter().map(|&c| pairs(c)).sum();
    let sb: u128 = cols.iter().map(|&c| pairs(c)).sum();
    let total = pairs(n as u64);
    // multiply (I - AB/N) and ((A+B)/2 - AB/N) by 2N: exact integers
    let num = 2 * total as i128 * index as i128 - 2 * (sa * sb) as i128;
    let den = (sa + sb) as i128 * total as i128 - 2 * (sa * sb) as i128;
    if den == 0 {
        return 1.0;
    }
    num as f64 / den as f64
}

/// How well one ground-truth part's motion was recovered.
#[derive(Debug, Clone, PartialEq)]
pub struct PartRotationError {
    /// Index of the ground-truth part.
    pub truth_part: usize,
    /// The fitted part compared with it (see [`rotation_errors`] for how it is chosen).
    pub fitted_part: usize,
    /// Whether that fitted part's vertices are mostly in `truth_part` (false: the truth part has no fitted
    /// part of its own and was compared with the fitted part holding most of its vertices).
    pub owned: bool,
    /// Vertices of the truth part, and how many of them carry the fitted part's label.
    pub truth_vertices: usize,
    pub shared_vertices: usize,
    /// Angle in degrees for shapes 1..n_s (shape 0 is the reference, always 0).
    pub angles_deg: Vec<f64>,
}

impl PartRotationError {
    pub fn mean_deg(&self) -> f64 {
        if self.angles_deg.is_empty() {
            0.0
        } else {
            self.angles_deg.iter().sum::<f64>() / self.angles_deg.len() as f64
        }
    }

    pub fn max_deg(&self) -> f64 {
        self.angles_deg.iter().cloned().fold(0.0, f64::max)
    }
}

/// Rotation error of every ground-truth part that has vertices.
///
/// - `fitted_rotations[k][i]`: rotation of fitted part k in shape i (as in `Model::parts[k].rotations`);
///   `fitted_labels[j]` is the fitted part of vertex j.
/// - `truth_rotations[i][g]`: rotation of ground-truth part g in shape i (as in
///   [`crate::synth::Generated::rotations`]); `truth_labels[j]` is the true part of vertex j.
///
/// Matching: each fitted part k is mapped to the ground-truth part holding most of its vertices. Ground-truth
/// part g is compared with the fitted part mapped to g that holds the most of g's vertices; if no fitted part
/// maps to g (g was merged into a part that is mostly something else), with the fitted part holding most of
/// g's vertices (`owned = false`; its error then shows the merge).
///
/// What is compared: RELATIVE rotations to shape 0, because a fitted part's latent frame is arbitrary (its
/// rotations are the truth's up to a constant factor on the right, R_fit^i = R_true^i Q): for every shape
/// i >= 1, the geodesic angle ([`angle_between`]) between R_fit^i (R_fit^0)^T and R_true^i (R_true^0)^T,
/// in degrees.
pub fn rotation_errors(
    fitted_rotations: &[Vec<Mat3>],
    fitted_labels: &[u32],
    truth_rotations: &[Vec<Mat3>],
    truth_labels: &[u32],
) -> Result<Vec<PartRotationError>> {
    if fitted_labels.len() != truth_labels.len() {
        return Err(Error::Request(format!(
            "rotation_errors: {} fitted labels but {} true labels; both must label the same vertices",
            fitted_labels.len(),
            truth_labels.len()
        )));
    }
    let ns = truth_rotations.len();
    if let Some((k, r)) = fitted_rotations.iter().enumerate().find(|(_, r)| r.len() != ns) {
        return Err(Error::Request(format!(
            "rotation_errors: fitted part {k} has {} rotations but the truth has {ns} shapes",
            r.len()
        )));
    }
    let ng = truth_rotations.first().map_or(0, |r| r.len());
    if let Some(i) = truth_rotations.iter().position(|r| r.len() != ng) {
        return Err(Error::Request(format!("rotation_errors: truth shape {i} has a different number of parts")));
    }
    let nf = fitted_rotations.len();
    if let Some(&l) = fitted_labels.iter().find(|&&l| l as usize >= nf) {
        return Err(Error::Request(format!("rotation_errors: fitted label {l} but only {nf} fitted parts")));
    }
    if let Some(&l) = truth_labels.iter().find(|&&l| l as usize >= ng) {
        return Err(Error::Request(format!("rotation_errors: true label {l} but only {ng} true parts")));
    }
    // overlap[k][g]: vertices with fitted label k and true label g
    let mut overlap = vec![vec![0usize; ng]; nf];
    for (&f, &t) in fitted_labels.iter().zip(truth_labels) {
        overlap[f as usize][t as usize] += 1;
    }
    let argmax = |v: &[usize]| -> usize { (0..v.len()).fold(0, |b, k| if v[k] > v[b] { k } else { b }) };
    let owner: Vec<Option<usize>> =
        overlap.iter().map(|row| if row.iter().any(|&c| c > 0) { Some(argmax(row)) } else { None }).collect();
    let mut out = Vec::new();
    for g in 0..ng {
        let column: Vec<usize> = (0..nf).map(|k| overlap[k][g]).collect();
        let truth_vertices: usize = column.iter().sum();
        if truth_vertices == 0 {
            continue;
        }
        let own: Vec<usize> = (0..nf).filter(|&k| owner[k] == Some(g)).collect();
        let (k, owned) = match own.iter().max_by_key(|&&k| (column[k], std::cmp::Reverse(k))) {
            Some(&k) => (k, true),
            None => (argmax(&column), false),
        };
        let truth: Vec<Mat3> = truth_rotations.iter().map(|pose| pose[g]).collect();
        let angles_deg = relative_angles_deg(&fitted_rotations[k], &truth);
        out.push(PartRotationError {
            truth_part: g,
            fitted_part: k,
            owned,
            truth_vertices,
            shared_vertices: column[k],
            angles_deg,
        });
    }
    Ok(out)
}

/// One number per ground-truth part with vertices (in part order): the mean over shapes 1..n_s of the angle
/// described in [`rotation_errors`], in degrees. Take the median or the max of the list for a summary.
pub fn rotation_errors_deg(
    fitted_rotations: &[Vec<Mat3>],
    fitted_labels: &[u32],
    truth_rotations: &[Vec<Mat3>],
    truth_labels: &[u32],
) -> Result<Vec<f64>> {
    Ok(rotation_errors(fitted_rotations, fitted_labels, truth_rotations, truth_labels)?
        .iter()
        .map(|e| e.mean_deg())
        .collect())
}

/// Median of a list (mean of the two middle values for an even length; 0 for an empty list).
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// A fit's accuracy against a generated population's ground truth: the one payload that both the CLI (`fit` of
/// a `synth:` population) and the page (`Synthetic.groundTruth`) print.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct GroundTruthAccuracy {
    /// Adjusted Rand index of the fitted labels against the true parts.
    pub ari: f64,
    /// Median over the true parts of their mean rotation error (degrees, relative to pose 1).
    pub rotation_error_deg: f64,
    /// The worst true part's mean rotation error (degrees).
    pub rotation_error_deg_max: f64,
    /// Every true part's mean rotation error (degrees), in part order ([`rotation_errors_deg`]).
    pub rotation_errors_deg: Vec<f64>,
    /// Number of true parts.
    pub true_parts: usize,
    /// The parts the generator moved alike ([`crate::synth::Spec::tied`]), each pair as the fit saw it.
    pub tied: Vec<TiedParts>,
}

/// Two true parts the generator moved alike in every pose (one takes the other's joint rotation), as the fit
/// saw them: the fitted part that holds most of each one's vertices, and how far apart those parts' motions
/// are against how far the true parts turn. Motion cannot tell such parts apart: the fit either gives them
/// one motion or joins them.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct TiedParts {
    /// The two true parts' names.
    pub names: [String; 2],
    /// The fitted part holding most of each true part's vertices (equal when the fit joined them).
    pub fitted: [u32; 2],
    /// RMS over the poses of the angle between the two fitted parts' motions, each relative to pose 1
    /// (R_a^i R_a^1ᵀ against R_b^i R_b^1ᵀ), in degrees.
    pub motion_gap_deg: f64,
    /// RMS over the poses of the first true part's own turn relative to pose 1, in degrees: how far the tied
    /// parts move.
    pub turn_deg: f64,
}

/// The angle between two rotation sequences in poses 2..n, each taken relative to its pose 1 (R_a^i R_a^1ᵀ
/// against R_b^i R_b^1ᵀ: free of either's latent frame), in degrees.
fn relative_angles_deg(a: &[Mat3], b: &[Mat3]) -> Vec<f64> {
    let (Some(a0), Some(b0)) = (a.first(), b.first()) else { return Vec::new() };
    let (a0, b0) = (transpose(a0), transpose(b0));
    a.iter().zip(b).skip(1).map(|(x, y)| angle_between(&mat_mul(x, &a0), &mat_mul(y, &b0)).to_degrees()).collect()
}

/// RMS over all the poses of [`relative_angles_deg`] (pose 1's is 0), in degrees.
fn relative_gap_deg(a: &[Mat3], b: &[Mat3]) -> f64 {
    let sq: f64 = relative_angles_deg(a, b).iter().map(|d| d * d).sum();
    (sq / a.len().max(1) as f64).sqrt()
}

/// [`TiedParts`] of every pair of `truth.spec.tied` that has vertices.
fn tied_parts(model: &crate::mfa::Model, truth: &crate::synth::Generated) -> Vec<TiedParts> {
    let majority = |part: usize| -> Option<u32> {
        let mut count: HashMap<u32, usize> = HashMap::new();
        for (&l, _) in model.labels.iter().zip(&truth.part_of_vertex).filter(|(_, &t)| t as usize == part) {
            *count.entry(l).or_default() += 1;
        }
        // ties to the lower part number
        count.into_iter().max_by(|x, y| x.1.cmp(&y.1).then(y.0.cmp(&x.0))).map(|(l, _)| l)
    };
    let sequence = |part: usize| -> Vec<Mat3> { truth.rotations.iter().map(|pose| pose[part]).collect() };
    truth
        .spec
        .tied
        .iter()
        .filter_map(|&(a, b)| {
            let (fa, fb) = (majority(a)?, majority(b)?);
            let identity = vec![Mat3::identity(); truth.rotations.len()];
            Some(TiedParts {
                names: [truth.part_names[a].clone(), truth.part_names[b].clone()],
                fitted: [fa, fb],
                motion_gap_deg: relative_gap_deg(
                    &model.parts[fa as usize].rotations,
                    &model.parts[fb as usize].rotations,
                ),
                turn_deg: relative_gap_deg(&sequence(a), &identity),
            })
        })
        .collect()
}

/// [`GroundTruthAccuracy`] of a model fitted to a generated population.
pub fn ground_truth_accuracy(
    model: &crate::mfa::Model,
    truth: &crate::synth::Generated,
) -> Result<GroundTruthAccuracy> {
    if model.labels.len() != truth.part_of_vertex.len() {
        return Err(Error::Request(format!(
            "the model has {} vertices, the ground truth {}",
            model.labels.len(),
            truth.part_of_vertex.len()
        )));
    }
    let fitted: Vec<Vec<Mat3>> = model.parts.iter().map(|p| p.rotations.clone()).collect();
    let errs = rotation_errors_deg(&fitted, &model.labels, &truth.rotations, &truth.part_of_vertex)?;
    Ok(GroundTruthAccuracy {
        ari: adjusted_rand_index(&model.labels, &truth.part_of_vertex),
        rotation_error_deg: median(&errs),
        rotation_error_deg_max: errs.iter().cloned().fold(0.0, f64::max),
        rotation_errors_deg: errs,
        true_parts: truth.n_parts(),
        tied: tied_parts(model, truth),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;

    #[test]
    fn the_gap_of_two_motions_is_their_rms_angle_relative_to_pose_one() {
        let z = [0.0, 0.0, 1.0];
        let a: Vec<Mat3> = (0..5).map(|i| axis_angle([1.0, 0.0, 0.0], 0.2 * i as f64)).collect();
        // b: a's motion from another latent frame (no gap), then turned 3 degrees more about z in poses 2..5
        let frame = axis_angle([0.3, 0.5, 0.1], 1.1);
        let b: Vec<Mat3> = a.iter().map(|r| r * frame).collect();
        assert!(relative_gap_deg(&a, &b) < 1e-9);
        let off = axis_angle(z, 3f64.to_radians());
        let c: Vec<Mat3> = b.iter().enumerate().map(|(i, r)| if i == 0 { *r } else { off * r }).collect();
        let want = 3.0 * (4.0f64 / 5.0).sqrt();
        assert!((relative_gap_deg(&a, &c) - want).abs() < 1e-9, "{}", relative_gap_deg(&a, &c));
    }

    #[test]
    fn ari_known_values() {
        // hand computed: contingency [[2,1,0],[0,1,2]]: I = 2, A = 6, B = 3, C(6,2) = 15,
        // E = 18/15 = 1.2, M = 4.5 -> (2 - 1.2) / (4.5 - 1.2) = 8/33
        let a = [0, 0, 0, 1, 1, 1];
        let b = [0, 0, 1, 1, 2, 2];
        assert!((adjusted_rand_index(&a, &b) - 8.0 / 33.0).abs() < 1e-15);
        assert!((adjusted_rand_index(&b, &a) - 8.0 / 33.0).abs() < 1e-15);
        // values from scikit-learn's documentation of adjusted_rand_score
        assert!((adjusted_rand_index(&[0, 0, 1, 2], &[0, 0, 1, 1]) - 4.0 / 7.0).abs() < 1e-15);
        assert_eq!(adjusted_rand_index(&[0, 0, 0, 0], &[0, 1, 2, 3]), 0.0);
        assert!((adjusted_rand_index(&[0, 0, 1, 1], &[0, 1, 0, 1]) + 0.5).abs() < 1e-15);
        assert_eq!(adjusted_rand_index(&[0, 0, 1, 1], &[1, 1, 0, 0]), 1.0);
    }

    #[test]
    fn ari_is_invariant_to_relabelling_and_order() {
        let a: Vec<u32> = (0..200).map(|i| (i * 7 % 5) as u32).collect();
        let b: Vec<u32> = (0..200).map(|i| ((i * 3 + i / 17) % 4) as u32).collect();
        let base = adjusted_rand_index(&a, &b);
        assert!(base.abs() < 0.5 && base != 0.0);
        let relabel: Vec<u32> = a.iter().map(|&l| [90, 3, 1_000_000, 7, 42][l as usize]).collect();
        assert!((adjusted_rand_index(&relabel, &b) - base).abs() < 1e-15);
        // the same permutation of the items in both labellings
        let perm: Vec<usize> = (0..200).map(|i| (i * 37) % 200).collect();
        let pa: Vec<u32> = perm.iter().map(|&i| a[i]).collect();
        let pb: Vec<u32> = perm.iter().map(|&i| b[i]).collect();
        assert!((adjusted_rand_index(&pa, &pb) - base).abs() < 1e-15);
        assert_eq!(adjusted_rand_index(&a, &relabel), 1.0);
    }

    #[test]
    fn ari_degenerate_cases_are_not_nan() {
        assert_eq!(adjusted_rand_index(&[5, 5, 5], &[1, 1, 1]), 1.0);
        assert_eq!(adjusted_rand_index(&[0, 1, 2], &[2, 0, 1]), 1.0);
        assert_eq!(adjusted_rand_index(&[], &[]), 1.0);
        assert_eq!(adjusted_rand_index(&[3], &[4]), 1.0);
        assert_eq!(adjusted_rand_index(&[1, 1, 1, 1], &[0, 0, 1, 1]), 0.0);
        assert_eq!(adjusted_rand_index(&[0, 1, 2, 3], &[0, 0, 0, 0]), 0.0);
    }

    fn truth(ns: usize, ng: usize) -> Vec<Vec<Mat3>> {
        (0..ns)
            .map(|i| (0..ng).map(|g| axis_angle([1.0, g as f64, 0.5], 0.2 * i as f64 + 0.1 * g as f64)).collect())
            .collect()
    }

    #[test]
    fn perfect_fit_in_any_latent_frame_has_zero_error() {
        let (ns, ng) = (5, 3);
        let tr = truth(ns, ng);
        let tl: Vec<u32> = (0..30).map(|j| (j / 10) as u32).collect();
        // fitted parts in another order, each in its own latent frame: R_fit^i = R_true^i Q_k
        let order = [2usize, 0, 1];
        let fitted: Vec<Vec<Mat3>> = order
            .iter()
            .enumerate()
            .map(|(k, &g)| {
                let q = axis_angle([0.3, -1.0, k as f64], 1.0 + k as f64);
                (0..ns).map(|i| mat_mul(&tr[i][g], &q)).collect()
            })
            .collect();
        let fl: Vec<u32> = tl.iter().map(|&g| order.iter().position(|&o| o == g as usize).unwrap() as u32).collect();
        let errs = rotation_errors(&fitted, &fl, &tr, &tl).unwrap();
        assert_eq!(errs.len(), 3);
        for e in &errs {
            assert!(e.owned && e.truth_vertices == 10 && e.shared_vertices == 10);
            assert_eq!(e.angles_deg.len(), ns - 1);
            // exact up to rounding: a few 3x3 products of entries |x| <= 1 leave ~1e-15 rad (6e-14 degrees), and
            // angle_between keeps that absolute precision near 0 (geometry::rotation::angle)
            assert!(e.max_deg() < 1e-12, "{e:?}");
            assert_eq!(order[e.fitted_part], e.truth_part);
        }
    }

    #[test]
    fn known_error_and_merged_parts() {
        let (ns, ng) = (4, 2);
        let tr = truth(ns, ng);
        let tl: Vec<u32> = (0..20).map(|j| (j / 10) as u32).collect();
        // fitted part 0 = truth part 0 with an extra 3 degrees about z in every shape after the first
        let extra = axis_angle([0.0, 0.0, 1.0], 3f64.to_radians());
        let f0: Vec<Mat3> = (0..ns).map(|i| if i == 0 { tr[0][0] } else { mat_mul(&extra, &tr[i][0]) }).collect();
        let errs = rotation_errors(std::slice::from_ref(&f0), &[0; 20], &tr, &tl).unwrap();
        // one fitted part holding everything: truth 0 owns it (tie 10/10 goes to the lower index)
        assert!(errs[0].owned && !errs[1].owned);
        for a in &errs[0].angles_deg {
            assert!((a - 3.0).abs() < 1e-9, "{a}");
        }
        // truth part 1 is compared with the merged part: its error is the relative motion of the two parts
        assert!(errs[1].mean_deg() > 3.0);
        let means = rotation_errors_deg(&[f0], &[0; 20], &tr, &tl).unwrap();
        assert_eq!(means.len(), 2);
        assert!((means[0] - 3.0).abs() < 1e-9);
        assert!(rotation_errors(&[vec![tr[0][0]; 3]], &[0; 20], &tr, &tl).is_err());
        assert!(rotation_errors(&[vec![tr[0][0]; 4]], &[1; 20], &tr, &tl).is_err());
        assert!(rotation_errors(&[vec![tr[0][0]; 4]], &[0; 19], &tr, &tl).is_err());
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
