//! What the part rule does after each final AECM ([`Pipeline::finish`]): every vertex labelled by rigid motion,
//! every part one connected piece, then a round of the rule (flesh dissolved, parts without a distinct motion
//! merged: by the merge tree's cut with [`PartRule::Tree`], pair by pair with [`PartRule::Distinct`]), and with
//! an exact count asked for, parts split or merged until it holds; each round that changed the parts asks the
//! driver for another run.

use super::{full_data, FinalRun, PartRound, Pipeline, State, COUNT_ROUNDS, DECIDE_ROUNDS};
use crate::error::Result;
use crate::mfa::params::PartRule;
use crate::mfa::result::Model;

use crate::parts::labels::compact;

impl Pipeline {
    /// Algorithm 1's model made of connected parts ([`super::islands`]); with `target_parts`, the part count is
    /// then made exact ([`super::part_count`]) and the final AECM runs again from those labels (at most
    /// [`COUNT_ROUNDS`] times, in case the AECM drops a part).
    pub(super) fn finish(&mut self, mut model: Model) -> Result<State> {
        let rounds = self.count_rounds;
        // (not once the count is forced: parts split to meet it can share one motion, and would empty each other)
        // the part rule decides after Algorithm 1's refinement (a run without it is the coarse AECM as it is)
        let distinct = matches!(self.params.part_rule, PartRule::Distinct | PartRule::Tree) && self.params.refine;
        if distinct && rounds == 0 {
            crate::parts::motion_labels::label_by_motion(&mut model, &self.pop);
            crate::parts::motion_labels::drop_empty_parts(&mut model);
        }
        // an island becomes a part of its own only after the first final AECM (later ones are boundary shifts)
        let new_parts = rounds == 0 && self.decide_rounds == 0;
        crate::parts::islands::connect_parts(&mut model, &self.pop, new_parts, self.params.min_part_vertices);
        if distinct {
            crate::parts::motion_labels::drop_empty_parts(&mut model);
        }
        // with `target_parts` the part rule decides once: its later rounds would refit counts the exact part count
        // then changes anyway
        let decide_rounds = if self.params.target_parts.is_some() { 1 } else { DECIDE_ROUNDS };
        // whether the parts were fitted to the motion labels in this call (a model the part rule leaves as it
        // is stays fitted)
        let mut fitted = false;
        if distinct && rounds == 0 && self.decide_rounds == 0 && self.params.start_labels.is_some() {
            // a partition given to start from (the page's Refine) is the user's: the part rule does not change
            // it, but its tree of the fitted parts is made as on any fit (the page's slider, the JSON)
            self.decide_rounds += 1;
            crate::parts::label_fit::fit_to_labels(&mut model, &full_data(&mut self.full, &self.pop).0, &self.params);
            fitted = true;
            let (_, curve) = self.decide_on_tree(&model.labels);
            self.part_curve = curve;
        } else if distinct && rounds == 0 && self.decide_rounds < decide_rounds {
            self.decide_rounds += 1;
            // rule 1 judges each part by the motion of its own labelled vertices (the mixture's component of a
            // short band part leans toward its neighbours' vertices; see label_fit)
            crate::parts::label_fit::fit_to_labels(&mut model, &full_data(&mut self.full, &self.pop).0, &self.params);
            fitted = true;
            let dissolved = crate::parts::distinct::dissolve_flesh(&mut model, &self.pop, self.params.blend_ratio);
            if dissolved > 0 {
                crate::parts::islands::connect_parts(&mut model, &self.pop, false, self.params.min_part_vertices);
            }
            let before = model.n_parts();
            let (merged, curve) = if self.params.part_rule == PartRule::Tree {
                self.decide_on_tree(&model.labels)
            } else {
                crate::parts::distinct::merge_indistinct(&self.pop, &model.labels, &self.params)
            };
            self.part_curve = curve;
            if self.params.target_parts.is_some() {
                self.decided_labels = Some(merged.clone());
            }
            let after = merged.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
            self.part_rounds.push(PartRound { parts: before + dissolved, dissolved, after });
            if crate::trace::enabled() {
                crate::trace_line!(
                    "part rule, round {}: {dissolved} parts dissolved as flesh, merges {before} -> {after} parts",
                    self.decide_rounds
                );
            }
            if dissolved > 0 || after < before {
                self.refined_labels = merged.clone();
                if let Some(n) = self.params.target_parts.filter(|&n| n != after) {
                    // the count is made exact on the decided labels at once (a refit first would be changed anyway)
                    self.count_rounds += 1;
                    // more parts than decided: the tree's finer partition; fewer: merged from the decided parts
                    // (the tree's own 10-part cut of horse-gallop rigged at E_RMS 3.40, the merges at 3.27)
                    let labels = match self.tree_partition(n).filter(|_| n > after) {
                        Some(l) => l,
                        None => crate::parts::part_count::labels_with_count(&self.pop, &merged, n, &self.params)?.0,
                    };
                    return self.refit(FinalRun::Count, &labels);
                }
                if self.fine.is_some() {
                    return self.refit_warm(FinalRun::Round, &merged);
                }
                return self.refit(FinalRun::Round, &merged);
            }
            if self.fine.is_some() && self.params.target_parts.is_none_or(|n| n == model.n_parts()) {
                // nothing to remove, on a coarse mesh: the last run, on all vertices, goes on from these parts
                // (with another count asked for, it is made below, on the coarse mesh)
                return self.finish_on_all_vertices(model);
            }
            if self.loose_start {
                // nothing to remove: the first run goes on at the fit's own tolerance
                return self.go_on(&merged);
            }
        }
        let n = match self.params.target_parts {
            Some(n)
                if !(model.n_parts() == n
                    && compact(&model.labels).iter().max().map_or(0, |&l| l as usize + 1) == n) =>
            {
                n
            }
            _ => {
                // the model is final: with the part rule's motion labels, its parts are fitted to them
                if distinct && rounds == 0 && !fitted {
                    crate::parts::label_fit::fit_to_labels(
                        &mut model,
                        &full_data(&mut self.full, &self.pop).0,
                        &self.params,
                    );
                }
                if self.fine.is_some() {
                    return self.finish_on_all_vertices(model);
                }
                self.final_model = Some(model);
                // the data are not read any more: free them before the caller reads the result
                self.full = None;
                return Ok(State::Done);
            }
        };
        if rounds == COUNT_ROUNDS {
            return Err(crate::error::Error::Data(format!(
                "cannot keep exactly {n} parts: the final AECM dropped parts {rounds} times (each part needs the \
                 weight of at least {} vertices, the smallest part a fit keeps); ask for fewer parts",
                self.params.min_part_vertices
            )));
        }
        self.count_rounds += 1;
        let (labels, _) = crate::parts::part_count::labels_with_count(&self.pop, &model.labels, n, &self.params)?;
        self.refit(FinalRun::Count, &labels)
    }
}
