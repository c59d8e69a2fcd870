//! Does the population look articulated? A verdict from figures the fit already has, so that a population the
//! model does not suit (a face making expressions, a bending blob) gets an honest word instead of a list of
//! arbitrary "parts".
//!
//! The figure is how much of the motion the rigid parts explain: with RMSE_1 the error of the best single rigid
//! motion of the whole shape (generalised Procrustes) and RMSE_K the fitted model's, the explained fraction of
//! the non-rigid motion is 1 - (RMSE_K / RMSE_1)². Articulated shapes, whose parts move rigidly up to a little
//! flesh at the joints, measure 0.99 and above (generated creatures 0.999, horse-poses 0.996, horse-gallop 0.990);
//! a smoothly bending blob 0.9 or less, however many parts it is cut into. The verdict is "articulated" from
//! [`MIN_EXPLAINED`] up, with at least two parts.

use super::data::Data;
use super::result::Model;
use crate::mesh::Population;
use serde::Serialize;

/// Least explained fraction of the motion for "articulated".
pub const MIN_EXPLAINED: f64 = 0.975;

/// Below this single-body RMSE (unit-box units) the poses differ by one rigid motion only.
pub const RIGID_RMSE: f64 = 1e-4;

#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Diagnosis {
    pub articulated: bool,
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

/// The verdict for a fitted model of `pop`.
pub fn diagnose(pop: &Population, model: &Model) -> Diagnosis {
    let data = Data::from_population(pop);
    let all: Vec<usize> = (0..data.n_vertices).collect();
    let body = super::init::component_from_points(&data, &all, all.len(), f64::MIN_POSITIVE);
    let sse: f64 = all.iter().map(|&j| super::motion_labels::motion_residual(&body, data.vertex(j))).sum();
    let single = (sse / (data.n_vertices * data.n_shapes).max(1) as f64).sqrt();
    let parts_rmse = model.rmse(pop);
    let parts = model.n_parts();
    let explained = if single > 0.0 { 1.0 - (parts_rmse / single).powi(2) } else { 1.0 };
    let pct = |x: f64| format!("{:.1} %", 100.0 * x);
    let (articulated, reason) = if single < RIGID_RMSE {
        (false, format!("the poses differ by one rigid motion only (RMSE {single:.1e} of the unit box): there is nothing to articulate"))
    } else if parts >= 2 && explained >= MIN_EXPLAINED {
        (
            true,
            format!(
                "{parts} rigid parts explain {} of the motion that one rigid body leaves (RMSE {single:.2e} down to {parts_rmse:.2e})",
                pct(explained)
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
                pct(explained.max(0.0)),
                if parts == 1 { "" } else { "s" },
                pct(MIN_EXPLAINED)
            ),
        )
    };
    Diagnosis { articulated, reason, single_body_rmse: single, parts_rmse, explained, parts }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::hierarchy::fit;
    use crate::model::Params;
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
    fn a_rigidly_moving_population_is_not_articulated() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 500, poses: 4, ..Spec::default() }).unwrap();
        let mut pop = g.population.clone();
        let first = pop.shapes[0].clone();
        for (i, s) in pop.shapes.iter_mut().enumerate() {
            // every pose the first one, turned as a whole
            let r = crate::geometry::rotation::axis_angle([0.2, 1.0, 0.1], 0.3 * i as f64);
            *s = first.iter().map(|&p| crate::geometry::mat_vec(&r, p)).collect();
        }
        let r = fit(&pop, &Params::default(), &mut |_| true).unwrap();
        let d = diagnose(&pop, &r.model);
        assert!(!d.articulated && d.single_body_rmse < RIGID_RMSE, "{d:?}");
        assert!(d.reason.contains("one rigid motion"), "{}", d.reason);
    }
}
