//! The steps both rules take after a final-stage AECM run, which each rule's `next` ([`Pipeline::next_run`])
//! puts together: every vertex labelled by rigid motion and every part made one connected piece ([`Pipeline::tidy`]),
//! the part rule's rule 1 (flesh dissolved, [`Pipeline::dissolve_round`]) and the round's record
//! ([`Pipeline::record_round`]); and, with an exact count asked for, parts split or merged until it holds
//! ([`Pipeline::exact_count`]).

use super::{full_data, FinalRun, PartRound, Pipeline, State};
use crate::error::Result;
use crate::mfa::result::Model;

use crate::parts::labels::compact;

/// Most times [`Pipeline`] makes the part count exact and refits.
pub(super) const COUNT_ROUNDS: usize = 3;

/// Most times [`PartRule::Distinct`] dissolves and merges parts and refits (a refit moves boundaries, which can
/// leave a new sliver of flesh or a new island part).
pub(super) const DECIDE_ROUNDS: usize = 3;

/// What [`Pipeline::exact_count`] leaves to the rule: the model as it is final, or the run that makes the count.
pub(super) enum Tail {
    Final(Model),
    Run(State),
}

impl Pipeline {
    /// After a final-stage run: with `by_motion` (the part rule decides) and before any count was forced, every
    /// vertex labelled by rigid motion ([`super::motion_labels`]); then every part one connected piece of the
    /// mesh ([`super::islands`]: an island becomes a part of its own only after the first final run, later ones
    /// are boundary shifts).
    pub(super) fn tidy(&mut self, model: &mut Model, by_motion: bool) {
        let rounds = self.count_rounds;
        // (not once the count is forced: parts split to meet it can share one motion, and would empty each other)
        if by_motion && rounds == 0 {
            crate::parts::motion_labels::label_by_motion(model, &self.pop);
            crate::parts::motion_labels::drop_empty_parts(model);
        }
        let new_parts = rounds == 0 && self.decide_rounds == 0;
        crate::parts::islands::connect_parts(model, &self.pop, new_parts, self.params.min_part_vertices);
        if by_motion {
            crate::parts::motion_labels::drop_empty_parts(model);
        }
    }

    /// Whether the part rule decides after this run: before any count was forced, at most [`DECIDE_ROUNDS`]
    /// times, and once only with `target_parts` (its later rounds would refit counts the exact part count then
    /// changes anyway).
    pub(super) fn round_due(&self) -> bool {
        let most = if self.params.target_parts.is_some() { 1 } else { DECIDE_ROUNDS };
        self.count_rounds == 0 && self.decide_rounds < most
    }

    /// The parts fitted to the motion labels ([`super::label_fit`]), as the part rule judges them and as a model
    /// that stays as it is keeps them.
    pub(super) fn fit_to_labels(&mut self, model: &mut Model) {
        crate::parts::label_fit::fit_to_labels(model, &full_data(&mut self.full, &self.pop).0, &self.params);
    }

    /// A round of the part rule begins: the parts fitted to their labels, then its rule 1 (flesh between parts
    /// dissolved, [`crate::parts::distinct::dissolve_flesh`]). Returns how many parts were dissolved and how many
    /// are left.
    pub(super) fn dissolve_round(&mut self, model: &mut Model) -> (usize, usize) {
        self.decide_rounds += 1;
        // rule 1 judges each part by the motion of its own labelled vertices (the mixture's component of a
        // short band part leans toward its neighbours' vertices; see label_fit)
        self.fit_to_labels(model);
        let dissolved = crate::parts::distinct::dissolve_flesh(model, &self.pop, self.params.distinct.blend_ratio);
        if dissolved > 0 {
            crate::parts::islands::connect_parts(model, &self.pop, false, self.params.min_part_vertices);
        }
        (dissolved, model.n_parts())
    }

    /// The round's end: its rule 2's labels `merged` and their curve kept, the round recorded. Returns the count
    /// after the merges.
    pub(super) fn record_round(
        &mut self,
        merged: &[u32],
        curve: Vec<crate::parts::distinct::CurvePoint>,
        before: usize,
        dissolved: usize,
    ) -> usize {
        self.part_curve = curve;
        if self.params.target_parts.is_some() {
            self.decided_labels = Some(merged.to_vec());
        }
        let after = merged.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        self.part_rounds.push(PartRound { parts: before + dissolved, dissolved, after });
        if crate::trace::enabled() {
            crate::trace_line!(
                "part rule, round {}: {dissolved} parts dissolved as flesh, merges {before} -> {after} parts",
                self.decide_rounds
            );
        }
        after
    }

    /// The exact part count asked for (`target_parts`), when the model does not have it: parts split or merged
    /// ([`crate::parts::part_count`]) and the final AECM again from those labels (at most [`COUNT_ROUNDS`]
    /// times, in case the AECM drops a part). Otherwise the model is final; with `fit_labels` and before any
    /// count was forced, its parts are first fitted to its motion labels.
    pub(super) fn exact_count(&mut self, mut model: Model, fit_labels: bool) -> Result<Tail> {
        let rounds = self.count_rounds;
        let n = match self.params.target_parts {
            Some(n)
                if !(model.n_parts() == n
                    && compact(&model.labels).iter().max().map_or(0, |&l| l as usize + 1) == n) =>
            {
                n
            }
            _ => {
                if fit_labels && rounds == 0 {
                    self.fit_to_labels(&mut model);
                }
                return Ok(Tail::Final(model));
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
        Ok(Tail::Run(self.refit(FinalRun::Count, &labels)?))
    }

    /// After a round that removed parts, with another count asked for than the round left (`after`): the count
    /// made on the decided labels at once (a refit first would be changed anyway), from `finer` (a partition
    /// with `n` parts the rule has, when `n` is more than decided) or merged from the decided parts. None when
    /// no count is asked for or the round left it.
    pub(super) fn count_after_round(
        &mut self,
        merged: &[u32],
        after: usize,
        finer: impl FnOnce(&Self, usize) -> Option<Vec<u32>>,
    ) -> Result<Option<State>> {
        let Some(n) = self.params.target_parts.filter(|&n| n != after) else { return Ok(None) };
        self.count_rounds += 1;
        let labels = match finer(self, n).filter(|_| n > after) {
            Some(l) => l,
            None => crate::parts::part_count::labels_with_count(&self.pop, merged, n, &self.params)?.0,
        };
        Ok(Some(self.refit(FinalRun::Count, &labels)?))
    }

    /// The model is the fit's: kept, and the data freed before the caller reads the result.
    pub(super) fn done(&mut self, model: Model) -> State {
        self.final_model = Some(model);
        self.full = None;
        State::Done
    }
}
