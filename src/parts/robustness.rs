//! Does the answer depend on the start? The same population fitted at several seeds and as four nuisance
//! variants of itself (poses in reverse order; the first pose dropped; the middle pose dropped; every pose moved
//! by one rigid motion and scaled by 7.3), with the part counts, the pairwise adjusted Rand index of the labels
//! and the times (`posemfa robustness`).
//!
//! Which pose comes first or in the middle is an accident of the file names, so the two dropped poses of the
//! standard variants are a sample of two. [`Variant::leave_each_out`] drops every pose in turn: the part count
//! over those runs says how much the answer hangs on any one pose, which is what a held-out population of the
//! same kind meets (`posemfa robustness --drop-each`).

use crate::geometry::rotation::axis_angle;
use crate::mesh::Population;
use crate::metrics::adjusted_rand_index;
use serde::Serialize;

/// One way of presenting the population again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "camelCase")]
pub enum Variant {
    /// The population as given, fitted with this seed.
    Seed(u64),
    /// The poses in reverse order.
    Reversed,
    /// Without its first pose.
    DropFirst,
    /// Without its middle pose (index n_s / 2).
    DropMiddle,
    /// Every pose turned by one rotation (0.7 rad about (1, 2, 3)), scaled by 7.3 and shifted by (5, -2, 11).
    Moved,
    /// Without pose k (0-based, in the population's order).
    Drop(usize),
}

impl Variant {
    /// Seeds `0..seeds`, then the four nuisance variants.
    pub fn standard(seeds: u64) -> Vec<Variant> {
        let mut v: Vec<Variant> = (0..seeds).map(Variant::Seed).collect();
        v.extend([Variant::Reversed, Variant::DropFirst, Variant::DropMiddle, Variant::Moved]);
        v
    }

    /// Every pose dropped in turn: one variant per pose (none for a population of 2 poses or fewer, where a
    /// dropped pose would leave too few to fit).
    pub fn leave_each_out(n_shapes: usize) -> Vec<Variant> {
        if n_shapes <= 2 {
            return Vec::new();
        }
        (0..n_shapes).map(Variant::Drop).collect()
    }

    pub fn name(&self) -> String {
        match self {
            Variant::Seed(s) => format!("seed {s}"),
            Variant::Reversed => "reversed".into(),
            Variant::DropFirst => "first dropped".into(),
            Variant::DropMiddle => "middle dropped".into(),
            Variant::Moved => "moved x7.3".into(),
            Variant::Drop(k) => format!("pose {} dropped", k + 1),
        }
    }

    /// The seed of the fit (the nuisance variants use seed 0).
    pub fn seed(&self) -> u64 {
        match self {
            Variant::Seed(s) => *s,
            _ => 0,
        }
    }

    /// The population presented this way (the vertices stay the same, so labels compare vertex by vertex).
    pub fn apply(&self, pop: &Population) -> crate::Result<Population> {
        let ns = pop.n_shapes();
        let mut order: Vec<usize> = (0..ns).collect();
        match self {
            Variant::Reversed => order.reverse(),
            Variant::DropFirst if ns > 2 => {
                order.remove(0);
            }
            Variant::DropMiddle if ns > 2 => {
                order.remove(ns / 2);
            }
            Variant::Drop(k) if ns > 2 && *k < ns => {
                order.remove(*k);
            }
            _ => {}
        }
        let moved = matches!(self, Variant::Moved);
        let turn = axis_angle([1.0, 2.0, 3.0], 0.7);
        let shapes: Vec<Vec<[f64; 3]>> = order
            .iter()
            .map(|&i| {
                pop.shape(i)
                    .iter()
                    .map(|p| {
                        let p = pop.normalization.to_original(p);
                        if moved {
                            let r = crate::geometry::mat_vec(&turn, p);
                            [7.3 * r[0] + 5.0, 7.3 * r[1] - 2.0, 7.3 * r[2] + 11.0]
                        } else {
                            p
                        }
                    })
                    .collect()
            })
            .collect();
        // names that keep this order under the natural sort
        let names = (0..shapes.len()).map(|k| format!("pose{k:04}")).collect();
        Population::new(crate::mesh::Sources::UnitShapes { names, faces: pop.faces.to_vec(), shapes })
    }
}

/// One fit of one variant.
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Run {
    pub variant: String,
    pub parts: usize,
    pub rmse: f64,
    pub seconds: f64,
    #[serde(skip)]
    pub labels: Vec<u32>,
}

/// Pairwise agreement of several runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Agreement {
    pub median_ari: f64,
    pub min_ari: f64,
    pub fewest_parts: usize,
    pub most_parts: usize,
}

/// Adjusted Rand index over every pair of runs (median, min) and the spread of their part counts.
pub fn agreement(runs: &[Run]) -> Agreement {
    let mut aris = Vec::new();
    for a in 0..runs.len() {
        for b in a + 1..runs.len() {
            aris.push(adjusted_rand_index(&runs[a].labels, &runs[b].labels));
        }
    }
    aris.sort_by(f64::total_cmp);
    let median = if aris.is_empty() {
        1.0
    } else if aris.len() % 2 == 1 {
        aris[aris.len() / 2]
    } else {
        0.5 * (aris[aris.len() / 2 - 1] + aris[aris.len() / 2])
    };
    Agreement {
        median_ari: median,
        min_ari: aris.first().copied().unwrap_or(1.0),
        fewest_parts: runs.iter().map(|r| r.parts).min().unwrap_or(0),
        most_parts: runs.iter().map(|r| r.parts).max().unwrap_or(0),
    }
}

/// Fits every variant with `params` (the seed set per variant) from `start` (every variant has the same
/// vertices) and returns the runs.
pub fn run_variants(
    pop: &Population,
    params: &crate::mfa::Params,
    start: &crate::mfa::FitStart,
    variants: &[Variant],
    mut each: impl FnMut(&Run),
) -> crate::Result<Vec<Run>> {
    let mut runs = Vec::new();
    for v in variants {
        let p = v.apply(pop)?;
        let params = crate::mfa::Params { seed: v.seed(), ..params.clone() };
        let t0 = crate::clock::now_ms();
        let fit = super::hierarchy::fit_from(&p, &params, start, &mut |_| true)?;
        let seconds = (crate::clock::now_ms() - t0) / 1000.0;
        let run = Run {
            variant: v.name(),
            parts: fit.model.n_parts(),
            rmse: fit.model.rmse(&p),
            seconds,
            labels: fit.model.labels.clone(),
        };
        each(&run);
        runs.push(run);
    }
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{generate, Preset, Spec};

    #[test]
    fn variants_keep_the_vertices_and_change_what_they_say() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 600, poses: 5, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let rev = Variant::Reversed.apply(pop).unwrap();
        assert_eq!(rev.n_vertices(), pop.n_vertices());
        let d = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max);
        // (the coordinates are stored in f32 in the unit box: a round trip through the original units may land
        // on the neighbouring f32, 1.2e-7 away)
        assert!(d(rev.point(0, 7), pop.point(4, 7)) < 1e-6);
        assert_eq!(Variant::DropFirst.apply(pop).unwrap().n_shapes(), 4);
        let mid = Variant::DropMiddle.apply(pop).unwrap();
        let orig = |p: &Population, i: usize, j: usize| p.normalization.to_original(p.point(i, j));
        assert!(d(orig(&mid, 2, 3), orig(pop, 3, 3)) < 1e-6);
        // moved and scaled, then mapped into the unit box again: the same shape up to a rigid motion
        let moved = Variant::Moved.apply(pop).unwrap();
        let len = |s: &[[f64; 3]], a: usize, b: usize| crate::geometry::norm(crate::geometry::sub(s[a], s[b]));
        let ratio = len(&moved.shape(1).to_vec(), 0, 50) / len(&pop.shape(1).to_vec(), 0, 50);
        let ratio2 = len(&moved.shape(3).to_vec(), 10, 400) / len(&pop.shape(3).to_vec(), 10, 400);
        // (f32 coordinates: a length of about 0.1 is known to about 1e-6 of itself)
        assert!((ratio - ratio2).abs() < 1e-5, "{ratio} {ratio2}");
        assert!(d(moved.point(1, 0), pop.point(1, 0)) > 1e-3, "the placement changed");
        // each pose dropped in turn: pose 3 dropped keeps poses 0, 1, 2 and 4, in that order
        let each = Variant::leave_each_out(pop.n_shapes());
        assert_eq!(each.len(), 5);
        let no3 = each[3].apply(pop).unwrap();
        assert_eq!(no3.n_shapes(), 4);
        assert!(d(orig(&no3, 2, 3), orig(pop, 2, 3)) < 1e-6);
        assert!(d(orig(&no3, 3, 3), orig(pop, 4, 3)) < 1e-6);
        assert_eq!(each[3].name(), "pose 4 dropped");
        assert!(Variant::leave_each_out(2).is_empty());
    }

    #[test]
    fn the_variance_floor_follows_the_shape_not_its_box() {
        // turned (a new bounding box) and scaled by 7.3: the floor in the original units scales by 7.3² exactly
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 800, poses: 4, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let moved = Variant::Moved.apply(pop).unwrap();
        let (a, b) = (pop.normalization.scale, moved.normalization.scale);
        assert!(((a / b) / 7.3 - 1.0).abs() > 1e-3, "the turn changes the box: {a} {b}");
        let floor = |p: &Population| crate::mfa::Params::default().for_radius(p.mean_squared_radius()).floor();
        let original = |p: &Population| floor(p) / p.normalization.scale.powi(2);
        let ratio = original(&moved) / original(pop) / (7.3f64 * 7.3);
        assert!((ratio - 1.0).abs() < 1e-5, "{ratio}");
        // scaled once only: parameters scaled already keep their scale
        use crate::mfa::InFit;
        let once = crate::mfa::Params::default().for_radius(0.18);
        assert!((once.in_fit(|| 0.045).floor() - 2e-7).abs() < 1e-18, "{}", once.floor());
    }

    #[test]
    fn agreement_counts_pairs() {
        let run = |labels: Vec<u32>, parts| Run { variant: String::new(), parts, rmse: 0.0, seconds: 0.0, labels };
        let a = agreement(&[run(vec![0, 0, 1, 1], 2), run(vec![1, 1, 0, 0], 2), run(vec![0, 0, 0, 1], 2)]);
        assert_eq!(a.median_ari, 0.0);
        assert_eq!(a.min_ari, 0.0);
        let b = agreement(&[run(vec![0, 0, 1, 1], 2), run(vec![1, 1, 0, 0], 3)]);
        assert_eq!((b.median_ari, b.min_ari, b.fewest_parts, b.most_parts), (1.0, 1.0, 2, 3));
    }
}
