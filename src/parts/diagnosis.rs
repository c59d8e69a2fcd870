//! Does the population look articulated? A verdict from figures the fit already has, so that a population the
//! model does not suit (a face making expressions, a bending blob) gets an honest word instead of a list of
//! arbitrary "parts".
//!
//! The figure is how much of the motion the rigid parts explain: with RMSE_1 the error of the best single rigid motion
//! of the whole shape (generalised Procrustes) and RMSE_K the fitted model's, the explained fraction of the non-rigid
//! motion is 1 - (RMSE_K / RMSE_1)². Articulated shapes, whose parts move rigidly up to a little flesh at the joints,
//! measure 0.99 and above at the part rule's count; a smoothly bending blob 0.9 or less, however many parts it is cut
//! into (each population's figure: docs/decisions.md, "Figures behind src/parts"). The verdict is "articulated" from
//! [`MIN_EXPLAINED`] (97.5 %) up, with at least two parts: the one threshold the page, the article and the CLI print
//! (the page and the article read it from the core, wasm `minExplained`).

use super::hierarchy::FitResult;
use crate::mesh::Population;
use crate::mfa::data::Data;
use crate::mfa::result::Model;
use serde::Serialize;

/// Least explained fraction of the motion for "articulated".
pub const MIN_EXPLAINED: f64 = 0.975;

/// `x` (a fraction) as a percentage beside the threshold [`MIN_EXPLAINED`]: one decimal, or as many more (up to
/// four) as it takes for a figure below the threshold not to print as the threshold or above ("97.46 %", not
/// "97.5 %" beside "articulated shapes measure 97.5 % and more").
pub fn percent_against_threshold(x: f64) -> String {
    let x = x.max(0.0);
    let limit = 100.0 * MIN_EXPLAINED;
    for digits in 1..=4 {
        let shown = format!("{:.*}", digits, 100.0 * x);
        if x >= MIN_EXPLAINED || shown.parse::<f64>().is_ok_and(|v| v < limit) {
            return format!("{shown} %");
        }
    }
    // closer than 0.00005 % below: shown truncated, so that it still reads below
    format!("{:.4} %", (1e6 * x).floor() / 1e4)
}

/// Below this single-body RMSE (unit-box units) the poses differ by one rigid motion only.
pub const RIGID_RMSE: f64 = 1e-4;

#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Diagnosis {
    pub articulated: bool,
    /// No verdict: the parts, a count the user fixed with no part rule behind it, explain too little, and too few
    /// parts cannot be told from a population that deforms smoothly (`articulated` is then false).
    pub undecided: bool,
    /// One sentence for people: the verdict, the figures behind it and, when not articulated, what to use instead.
    pub reason: String,
    /// RMSE of the best single rigid motion of the whole shape (unit-box units).
    pub single_body_rmse: f64,
    /// RMSE of the fitted model (unit-box units).
    pub parts_rmse: f64,
    /// 1 - (parts_rmse / single_body_rmse)²: how much of the non-rigid motion the parts explain.
    pub explained: f64,
    pub parts: usize,
}

/// RMSE of the best rigid motion (generalised Procrustes) of each labelled part of `pop`'s data (unit-box
/// units); one label for all vertices gives the single body's. The data as `Data::from_population(pop)` holds
/// them (every shape centred on its centroid, rounded to f32), read from the population without that copy.
fn rigid_rmse(pop: &Population, labels: &[u32]) -> f64 {
    let (nv, ns) = (pop.n_vertices(), pop.n_shapes());
    let all: Vec<usize> = (0..nv).collect();
    let offsets = Data::centroids(pop, &all);
    let m = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let mut members = vec![Vec::new(); m];
    labels.iter().enumerate().for_each(|(j, &l)| members[l as usize].push(j));
    let mut h = vec![[0.0; 3]; ns];
    let sse: f64 = members
        .iter()
        .filter(|v| !v.is_empty())
        .map(|v| {
            let c = crate::mfa::init::component_from_population_centred(pop, v, &offsets, v.len(), f64::MIN_POSITIVE);
            v.iter()
                .map(|&j| {
                    for (i, p) in h.iter_mut().enumerate() {
                        let q = crate::geometry::sub(pop.point(i, j), offsets[i]);
                        *p = crate::mesh::population::widen(crate::mesh::population::narrow(q));
                    }
                    super::motion_labels::motion_residual(&c, &h)
                })
                .sum::<f64>()
        })
        .sum();
    (sse / (nv * ns).max(1) as f64).sqrt()
}

/// The verdict for a fit of `pop`: [`diagnose`] of its model, except with an exact part count (`target_parts`) other
/// than the one the part rule decided. The question is about the population, not the count asked for: a population
/// asked for a few parts is still articulated although those few rigid parts explain less than [`MIN_EXPLAINED`] of its
/// motion (an example: docs/decisions.md, "Figures behind src/parts"), so the verdict is also taken at the part rule's
/// count ([`FitResult::decided_labels`], each part fitted rigidly), and the reason gives both figures. The figures
/// (`parts_rmse`, `explained`, `parts`) stay the asked model's.
pub fn diagnose_fit(pop: &Population, result: &FitResult) -> Diagnosis {
    let asked = diagnose(pop, &result.model);
    if result.count_unjudged && !asked.articulated && asked.single_body_rmse >= RIGID_RMSE {
        let reason = format!(
            "{} rigid part{} (a count the part rule did not judge) explain {} of the motion that one rigid \
             body leaves (RMSE {:.2e} down to {:.2e}), less than the {} that articulated shapes measure: too few \
             parts may be all that is wrong. Fit with the part rule on (\"Refine the parts\" on and \"Parts in the \
             end\" auto, the defaults) for a verdict",
            asked.parts,
            if asked.parts == 1 { "" } else { "s" },
            percent_against_threshold(asked.explained),
            asked.single_body_rmse,
            asked.parts_rmse,
            percent_against_threshold(MIN_EXPLAINED)
        );
        return Diagnosis { undecided: true, reason, ..asked };
    }
    let Some(labels) = result.decided_labels.as_ref() else { return asked };
    let decided = super::labels::compact(labels);
    let n = decided.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    if n == asked.parts || asked.single_body_rmse < RIGID_RMSE {
        return asked;
    }
    let single = asked.single_body_rmse;
    let rmse = rigid_rmse(pop, &decided);
    let explained = 1.0 - (rmse / single).powi(2);
    if asked.articulated || n < 2 || explained < MIN_EXPLAINED {
        return asked;
    }
    // (the count shown leads: the headline reads "Articulated: the 12 parts shown ...", never another count)
    let reason = format!(
        "the {} parts shown (the count asked for) explain {} of the motion that one rigid body leaves (RMSE \
         {single:.2e} down to {:.2e}); the population is articulated all the same: the {n} rigid parts the part \
         rule decided in this fit, before the count was made exact, explain {} (RMSE {rmse:.2e}; articulated \
         shapes measure {} and more)",
        asked.parts,
        percent_against_threshold(asked.explained),
        asked.parts_rmse,
        percent_against_threshold(explained),
        percent_against_threshold(MIN_EXPLAINED)
    );
    Diagnosis { articulated: true, reason, ..asked }
}

/// The verdict for a fit of `pop` that ran to its end ([`diagnose_fit`]); None for a fit stopped early (cancelled):
/// its best state so far may still be the coarse stage's few parts, and a verdict on it would contradict the
/// finished fit's.
pub fn diagnose_finished(pop: &Population, result: &FitResult) -> Option<Diagnosis> {
    result.complete.then(|| diagnose_fit(pop, result))
}

/// What the page and the CLI say instead of a verdict for a fit stopped early.
pub const UNFINISHED: &str = "cancelled: the diagnosis needs a finished fit";

/// The verdict for a fitted model of `pop`.
pub fn diagnose(pop: &Population, model: &Model) -> Diagnosis {
    let single = rigid_rmse(pop, &vec![0; pop.n_vertices()]);
    let parts_rmse = model.rmse(pop);
    let parts = model.n_parts();
    let explained = if single > 0.0 { 1.0 - (parts_rmse / single).powi(2) } else { 1.0 };
    let pct = percent_against_threshold;
    let (articulated, reason) = if single < RIGID_RMSE {
        (false, format!("the poses differ by one rigid motion only (RMSE {single:.1e} of the unit box): there is nothing to articulate"))
    } else if parts >= 2 && explained >= MIN_EXPLAINED {
        (
            true,
            format!(
                "{parts} rigid parts explain {} of the motion that one rigid body leaves (RMSE {single:.2e} down to {parts_rmse:.2e}; \
                 articulated shapes measure {} and more)",
                pct(explained),
                pct(MIN_EXPLAINED)
            ),
        )
    } else {
        (
            false,
            format!(
                "rigid parts explain only {} of the motion that one rigid body leaves ({parts} part{}, RMSE {single:.2e} down to \
                 {parts_rmse:.2e}; articulated shapes measure {} and more): this population deforms smoothly rather than moving \
                 part by part. Use a deformation model instead (e.g. PCA of the vertex positions, or linear blend skinning with \
                 many bones)",
                pct(explained),
                if parts == 1 { "" } else { "s" },
                pct(MIN_EXPLAINED)
            ),
        )
    };
    Diagnosis { articulated, undecided: false, reason, single_body_rmse: single, parts_rmse, explained, parts }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mfa::Params;
    use crate::parts::hierarchy::fit;
    use crate::synth::{generate, Preset, Spec};

    fn verdict(preset: Preset, seed: u64) -> Diagnosis {
        let g = generate(&Spec { preset, vertices: 1500, poses: 8, seed, ..Spec::default() }).unwrap();
        let r = fit(&g.population, &Params { seed, ..Params::default() }, &mut |_| true).unwrap();
        diagnose(&g.population, &r.model)
    }

    #[test]
    fn articulated_creatures_are_articulated_and_the_blob_is_not() {
        for preset in [Preset::Quadruped, Preset::Arm, Preset::Snake] {
            let d = verdict(preset, 0);
            assert!(d.articulated && d.explained > 0.99, "{preset:?}: {d:?}");
        }
        for seed in 0..3 {
            let d = verdict(Preset::Blob, seed);
            assert!(!d.articulated && d.explained < MIN_EXPLAINED, "blob seed {seed}: {d:?}");
            assert!(d.reason.contains("deformation model"), "{}", d.reason);
        }
    }

    #[test]
    fn a_creature_asked_for_few_parts_is_still_articulated_and_the_blob_is_not() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let r = fit(&g.population, &Params { target_parts: Some(3), ..Params::default() }, &mut |_| true).unwrap();
        assert_eq!(r.model.n_parts(), 3);
        // 3 rigid parts leave much of a quadruped's motion unexplained ...
        let asked = diagnose(&g.population, &r.model);
        assert!(!asked.articulated && asked.explained < MIN_EXPLAINED, "{asked:?}");
        // ... but the population is articulated: the part rule's own parts say so, and the reason gives both
        let d = diagnose_fit(&g.population, &r);
        assert!(d.articulated, "{d:?}");
        assert!(
            d.reason.contains("the part rule decided in this fit")
                && d.reason.contains("the 3 parts shown (the count asked for)"),
            "{}",
            d.reason
        );
        assert_eq!((d.parts, d.explained), (3, asked.explained));
        let g = generate(&Spec { preset: Preset::Blob, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let r = fit(&g.population, &Params { target_parts: Some(6), ..Params::default() }, &mut |_| true).unwrap();
        let d = diagnose_fit(&g.population, &r);
        assert!(!d.articulated && d.reason.contains("deformation model"), "{d:?}");
    }

    #[test]
    fn few_parts_the_user_fixed_without_the_part_rule_get_no_verdict() {
        // Algorithm 1's coarse stage alone at m = 4: a quadruped's 4 parts explain too little, and that says
        // nothing about the quadruped
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let r = fit(
            &g.population,
            &Params {
                algorithm1: crate::mfa::Algorithm1Params { parts: 4, ..Default::default() },
                refine: false,
                ..Params::default()
            },
            &mut |_| true,
        )
        .unwrap();
        assert!(r.count_unjudged);
        assert!(!diagnose(&g.population, &r.model).articulated);
        let d = diagnose_fit(&g.population, &r);
        assert!(d.undecided && !d.articulated, "{d:?}");
        assert!(
            d.reason.contains("a count the part rule did not judge") && !d.reason.contains("deformation model"),
            "{}",
            d.reason
        );
        assert!(
            d.reason.contains("of the motion that one rigid body leaves") && !d.reason.contains("  "),
            "{}",
            d.reason
        );
        // enough parts fixed by hand: the verdict stands
        let r = fit(
            &g.population,
            &Params {
                algorithm1: crate::mfa::Algorithm1Params { parts: 40, ..Default::default() },
                refine: false,
                ..Params::default()
            },
            &mut |_| true,
        )
        .unwrap();
        let d = diagnose_fit(&g.population, &r);
        assert!(!d.undecided && d.articulated, "{d:?}");
        // with the part rule on, the verdict is the rule's (no such hedge)
        let r = fit(&g.population, &Params::default(), &mut |_| true).unwrap();
        assert!(!r.count_unjudged && !diagnose_fit(&g.population, &r).undecided);
    }

    #[test]
    fn a_fit_stopped_early_gets_no_verdict() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let mut calls = 0;
        // stopped after the first few iterations of the coarse stage, as the page's Cancel does
        let r = fit(&g.population, &Params::default(), &mut |_| {
            calls += 1;
            calls < 3
        })
        .unwrap();
        assert!(!r.complete);
        assert_eq!(diagnose_finished(&g.population, &r), None);
        let done = fit(&g.population, &Params::default(), &mut |_| true).unwrap();
        assert!(done.complete);
        assert_eq!(diagnose_finished(&g.population, &done), Some(diagnose_fit(&g.population, &done)));
    }

    #[test]
    fn a_rigidly_moving_population_is_not_articulated() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 500, poses: 4, ..Spec::default() }).unwrap();
        let mut pop = g.population.clone();
        let first = pop.shape(0).to_vec();
        let turned: Vec<Vec<[f64; 3]>> = (0..pop.n_shapes())
            .map(|i| {
                // every pose the first one, turned as a whole
                let r = crate::geometry::rotation::axis_angle([0.2, 1.0, 0.1], 0.3 * i as f64);
                first.iter().map(|&p| crate::geometry::mat_vec(&r, p)).collect()
            })
            .collect();
        pop.set_shapes(&turned);
        let r = fit(&pop, &Params::default(), &mut |_| true).unwrap();
        let d = diagnose(&pop, &r.model);
        assert!(!d.articulated && d.single_body_rmse < RIGID_RMSE, "{d:?}");
        assert!(d.reason.contains("one rigid motion"), "{}", d.reason);
    }

    #[test]
    fn a_figure_below_the_threshold_never_prints_as_the_threshold() {
        assert_eq!(percent_against_threshold(MIN_EXPLAINED), "97.5 %");
        assert_eq!(percent_against_threshold(0.97496), "97.496 %");
        assert_eq!(percent_against_threshold(0.9749), "97.49 %");
        assert_eq!(percent_against_threshold(0.9712), "97.1 %");
        assert_eq!(percent_against_threshold(0.99951), "100.0 %");
        assert_eq!(percent_against_threshold(-0.3), "0.0 %");
        let close = percent_against_threshold(MIN_EXPLAINED - 1e-9);
        assert!(close.trim_end_matches(" %").parse::<f64>().unwrap() < 97.5, "{close}");
    }
}
