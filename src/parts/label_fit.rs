//! The parts' parameters given their labels: the classification fit that ends the distinct part rule.
//!
//! The part rule labels every vertex by least-squares rigid motion ([`super::motion_labels`]), but the final
//! AECM's components were fitted with the mixture's own responsibilities, which differ where no part moves a
//! vertex rigidly (the flesh around a joint). There a component with large per-shape variances s_k^i (a short
//! part that is mostly blend band, such as a neck) explains the neighbours' band vertices better than their own
//! tight components do: a Gaussian mixture's widest component collects what the others fit badly, and its
//! rotations turn toward them (the generated quadruped's neck: 200 vertices of trunk and head band in its
//! responsibilities, its rotations 4-7 degrees off the bone's, against 1-3 for the same labels fitted alone).
//!
//! So the parameters reported with the labels are fitted to the labels: with the labels l_j known, the model
//! is one factor analyser per part and the classification log-likelihood
//!
//!   L_c = Σ_j [log π_{l_j} + log N(h_j; b_{l_j}, A_{l_j} A_{l_j}^T + Φ_{l_j})],   π_k = n_k / n,
//!
//! is maximised by the same two CM cycles as AECM with γ_kj = 1[l_j = k] in place of the E-step's
//! responsibilities (an ECM of that model: L_c never decreases), from the AECM's parameters, to the AECM's
//! tolerance on |ΔL_c| / n_v.

use crate::mfa::cm::{self, Member, Members};
use crate::mfa::data::Data;
use crate::mfa::estep::LANES;
use crate::mfa::{InFit, Model};

/// The responsibilities of the labels (γ = 1 for each vertex's own part) with y under `comps`, written into
/// `members` (emptied first, its lists' capacity kept), and L_c of the labels under `comps` from the same
/// projections (log N = log_norm - (Σ|x|²/s - Σ shrink y²) / 2, as [`crate::mfa::Component::log_weighted_density`]).
/// Block by block in the data's layout, as the E-step: the 4 vertices of a block are projected together under
/// each part that labels one of them (one part for most blocks), so the members come in layout order.
fn label_members(data: &Data, labels: &[u32], comps: &[crate::mfa::Component], members: &mut Members) -> f64 {
    let layout = &*data.layout;
    let wbs = crate::mfa::estep::ordered_woodbury(comps, &layout.order);
    members.resize_with(comps.len(), Vec::new);
    members.iter_mut().for_each(|list| list.clear());
    let ns = data.n_shapes;
    // (the sum as f64's Sum adds: in order from -0.0)
    let mut ll = -0.0;
    for (b, (ids, &valid)) in layout.idx.iter().zip(&layout.valid).enumerate() {
        let ids = &ids[..valid as usize];
        let h = &layout.h[b * ns * 3..(b + 1) * ns * 3];
        let mut done = [false; LANES];
        for first in 0..ids.len() {
            if done[first] {
                continue;
            }
            let k = labels[ids[first] as usize] as usize;
            let wb = &wbs[k];
            let (mut y, mut sq) = ([[0.0; LANES]; 3], [0.0; LANES]);
            crate::mfa::estep::accumulate_block_f64(&wb.packed, h, &mut y, &mut sq);
            let density = crate::mfa::estep::log_density_lanes(wb.log_norm, &wb.shrink, &y, &sq);
            for (l, &j) in ids.iter().enumerate().skip(first) {
                if done[l] || labels[j as usize] as usize != k {
                    continue;
                }
                done[l] = true;
                ll += density[l];
                members[k].push(Member { j, g: 1.0, y: [y[0][l], y[1][l], y[2][l]] });
            }
        }
    }
    ll
}

/// Refits `model.parts` to `model.labels` (see the module documentation) and recomputes the latent shape;
/// the labels are kept. Returns the classification log-likelihood after every iteration (never decreasing).
/// Every part must have at least one vertex.
pub fn fit_to_labels(model: &mut Model, data: &Data, params: &impl InFit) -> Vec<f64> {
    let m = model.n_parts();
    if m == 0 || model.labels.len() != data.n_vertices || model.labels.iter().any(|&l| l as usize >= m) {
        return Vec::new();
    }
    // the model's translations are in unit-box coordinates, the data centred per shape
    let mut comps = crate::mfa::data::to_frame(data, &model.parts);
    let labels = model.labels.clone();
    let mut trace = Vec::new();
    // `members` always holds the projections under the current `comps`: the pass that gives L_c after cycle 2
    // also gives the next cycle 1 its members
    let mut members = Members::new();
    let mut prev = label_members(data, &labels, &comps, &mut members);
    let params = &crate::mfa::aecm::floor_for(data, params);
    let floor = params.floor();
    for it in 0..params.max_iter {
        // With the labels fixed, cycle 1 reads only the members (γ = 1, in layout order) and the data: from the
        // second iteration on it writes the same π and b again, bit for bit (cycle 2 changes neither), and the
        // projections under those parameters are the ones the last pass computed. So it runs once.
        if it == 0 {
            cm::cycle1(data, &members, &mut comps);
            label_members(data, &labels, &comps, &mut members);
        }
        cm::cycle2(data, &members, &mut comps, params.lambda_rule, floor, params.px_em);
        let ll = label_members(data, &labels, &comps, &mut members);
        trace.push(ll);
        let done = ((ll - prev) / data.n_vertices as f64).abs() < params.tol;
        prev = ll;
        if done {
            break;
        }
    }
    // the latent shape under the new parameters (eq 21: Λ E[z|h] with E[z|h] = post_gain y, y of the last pass),
    // then the translations back to unit-box coordinates
    for (c, list) in comps.iter().zip(&members) {
        let wb = c.woodbury();
        for mb in list {
            let e = [wb.post_gain[0] * mb.y[0], wb.post_gain[1] * mb.y[1], wb.post_gain[2] * mb.y[2]];
            model.latent[mb.j as usize] = [c.lambda[0] * e[0], c.lambda[1] * e[1], c.lambda[2] * e[2]];
        }
    }
    model.parts = crate::mfa::data::from_frame(data, &comps);
    trace
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mfa::Params;
    use crate::synth::{generate, Preset, Spec};

    fn fitted(spec: &Spec) -> (crate::synth::Generated, Model) {
        let g = generate(spec).unwrap();
        let mut params = Params { refine: false, ..Params::default() };
        params.algorithm1.parts = g.n_parts();
        let r = super::super::hierarchy::fit(&g.population, &params, &mut |_| true).unwrap();
        (g, r.model)
    }

    #[test]
    fn the_classification_log_likelihood_never_decreases_and_the_labels_stay() {
        let spec = Spec { preset: Preset::Arm, vertices: 1500, poses: 8, seed: 2, ..Spec::default() };
        let (g, mut model) = fitted(&spec);
        let labels = model.labels.clone();
        let data = Data::from_population(&g.population);
        let centred = crate::mfa::data::to_frame(&data, &model.parts);
        let before = label_members(&data, &labels, &centred, &mut Members::new());
        let trace = fit_to_labels(&mut model, &data, &Params::default());
        assert!(!trace.is_empty());
        assert_eq!(model.labels, labels);
        let mut last = before;
        for &ll in &trace {
            assert!(ll >= last - 1e-9 * last.abs(), "L_c fell from {last} to {ll}");
            last = ll;
        }
    }

    /// What lets [`fit_to_labels`] run cycle 1 once: with the labels' members, cycle 1 gives the same π and b
    /// bit for bit each time, and cycle 2 does not touch them.
    #[test]
    fn with_fixed_labels_cycle_one_is_idempotent_and_cycle_two_keeps_its_output() {
        let spec = Spec { preset: Preset::Quadruped, vertices: 1500, poses: 6, seed: 4, ..Spec::default() };
        let (g, model) = fitted(&spec);
        let data = Data::from_population(&g.population);
        let mut comps = crate::mfa::data::to_frame(&data, &model.parts);
        let mut members = Members::new();
        label_members(&data, &model.labels, &comps, &mut members);
        cm::cycle1(&data, &members, &mut comps);
        let once: Vec<_> = comps.iter().map(|c| (c.weight, c.translations.clone())).collect();
        label_members(&data, &model.labels, &comps, &mut members);
        let p = Params::default();
        cm::cycle2(&data, &members, &mut comps, p.lambda_rule, p.variance_floor, p.px_em);
        assert_eq!(comps.iter().map(|c| (c.weight, c.translations.clone())).collect::<Vec<_>>(), once);
        label_members(&data, &model.labels, &comps, &mut members);
        cm::cycle1(&data, &members, &mut comps);
        assert_eq!(comps.iter().map(|c| (c.weight, c.translations.clone())).collect::<Vec<_>>(), once);
    }

    #[test]
    fn parts_fitted_to_the_true_labels_move_as_the_true_parts_do() {
        // the mixture's own responsibilities give a short, mostly-blend part its neighbours' band vertices; refitted
        // to the true labels, the worst part's rotation comes closer to the bone's
        let spec = Spec { preset: Preset::Quadruped, vertices: 6000, poses: 10, seed: 1, ..Spec::default() };
        let g = generate(&spec).unwrap();
        let params = Params::default();
        let mut fit =
            crate::mfa::aecm::Fit::from_labels(Data::from_population(&g.population), &g.part_of_vertex, &params)
                .unwrap();
        fit.run(&mut |_| true);
        let mut model = fit.model();
        assert_eq!(model.n_parts(), g.n_parts());
        model.labels = g.part_of_vertex.clone();
        let worst = |model: &Model| crate::metrics::ground_truth_accuracy(model, &g).unwrap().rotation_error_deg_max;
        let before = worst(&model);
        fit_to_labels(&mut model, &Data::from_population(&g.population), &params);
        let after = worst(&model);
        assert!(after < before, "worst rotation {before:.2} -> {after:.2} degrees");
    }
}
