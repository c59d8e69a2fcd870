//! An exact part count (`Params::target_parts`, the CLI's `--bones N`, the page's "Parts: N").
//!
//! Algorithm 1 chooses its own number of parts. A rig is often wanted with a given number of bones, so after
//! Algorithm 1's result the labels are changed one part at a time until there are exactly N, and the final
//! AECM then runs again from them ([`super::hierarchy`]):
//!
//! - **too few**: split the part whose cut lowers the pair-blend residual most
//!   ([`super::pair_blend::Blends::split_drop`]: what a rig blending two bones per vertex, weights fitted, leaves
//!   of the part's and its neighbours' vertices, with the part's motion before and its halves' after). Each part
//!   has up to two candidate cuts, made the way Algorithm 1's refinement cuts a sub-part: 2-means
//!   ([`crate::mfa::init::kmeans`]) once on its vertices' positions over all shapes and once on their residuals
//!   under the part's own rigid motion, each then refined by a 2-component AECM on the part's vertices
//!   (refinement tolerance and cap) started from it. Each half is made one connected piece inside the part
//!   (stray pieces join the half that explains them best, [`super::islands::connect_labels`]).
//! - **too many**: merge the two adjacent parts (sharing a mesh edge) whose merge loses the least.
//!
//! A merge compares the classification log-likelihood Σ_j log(π_k N(h_j; θ_k)) (eq 6 weighted as in eq 12) of
//! the vertices involved. Every part's component (and motion) is fitted to its own vertices in closed form
//! ([`crate::mfa::init::component_from_points`], the start the AECM uses). Splits were once chosen by the
//! log-likelihood gain too, with the 2-means cuts: the drop of the pair-blend residual and the AECM's cuts rig
//! better at many bones (docs/decisions.md, "The 30-bone rig's splits").
//! Every step keeps every part one connected piece: a merge joins two adjacent pieces, a split leaves two
//! connected halves.
//!
//! N cannot be met when N = 0, when N parts of at least `min_part_vertices` vertices do not fit in the mesh
//! ([`check_target`]), when no part can be cut into two connected halves of `min_part_vertices` vertices,
//! or when the parts left touch no other part (a mesh of separate pieces): each gives an error that says
//! what to ask for instead.

use super::islands::connect_labels;
use super::pair_blend::Blends;
use crate::error::{Error, Result};
use crate::mesh::Population;
use crate::mfa::aecm::Fit;
use crate::mfa::component::Component;
use crate::mfa::data::Data;
use crate::mfa::init::{component_from_points, kmeans};
use crate::mfa::params::{InFit, RunParams};
use std::collections::{BTreeSet, HashMap};

/// Checks that `n` parts of at least `min_part_vertices` vertices can exist on `n_vertices` vertices.
pub fn check_target(n: usize, n_vertices: usize, min_part_vertices: usize) -> Result<()> {
    if n == 0 {
        return Err(Error::Params("target_parts = 0: a rig needs at least 1 part (ask for 1 or more, or auto)".into()));
    }
    let most = n_vertices / min_part_vertices.max(1);
    if n > most {
        return Err(Error::Params(format!(
            "target_parts = {n}: the mesh has {n_vertices} vertices and every part needs at least {} (the \
             smallest part a fit keeps), so at most {most} parts are possible; ask for at most {most}",
            min_part_vertices.max(1)
        )));
    }
    Ok(())
}

/// What [`labels_with_count`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CountChange {
    /// Parts in the labels it was given.
    pub from: usize,
    pub splits: usize,
    pub merges: usize,
    /// Change of the classification log-likelihood (nats; negative: the count costs that much).
    pub log_likelihood_change: f64,
}

/// A candidate cut of a part: the vertex lists of both halves, their motions (components fitted to them) and the
/// drop of the pair-blend residual it gives ([`Blends::split_drop`]; NaN until computed and once it changes).
#[derive(Debug, Clone)]
struct Cut {
    halves: [Vec<usize>; 2],
    motions: [Component; 2],
    drop: f64,
}

struct Counter<'a> {
    pop: &'a Population,
    data: &'a Data,
    params: &'a RunParams,
    /// The part count asked for (for the error messages).
    target: usize,
    /// Vertices of every part; None once merged away.
    parts: Vec<Option<Vec<usize>>>,
    /// Classification log-likelihood of every part's vertices under its own component.
    ll: Vec<f64>,
    /// Candidate cuts of a part (empty: it cannot be split), computed when first needed.
    cuts: HashMap<usize, Vec<Cut>>,
    /// The parts' motions and pair-blend residuals, from the first split on.
    blends: Option<Blends<'a>>,
    /// Log-likelihood of the union of two adjacent parts (smaller id first).
    unions: HashMap<(usize, usize), f64>,
}

impl<'a> Counter<'a> {
    /// The component fitted to `members` in closed form.
    fn motion(&self, members: &[usize]) -> Component {
        component_from_points(self.data, members, self.data.n_vertices, self.params.floor())
    }

    /// Σ_j log(π N(h_j; θ)) of `members` under `c`.
    fn score_under(&self, c: &Component, members: &[usize]) -> f64 {
        let wb = c.woodbury();
        let mut h = Vec::new();
        members.iter().map(|&j| c.log_weighted_density(&wb, self.data.vertex_into(j, &mut h))).sum()
    }

    /// Σ_j log(π N(h_j; θ)) of `members` under the component fitted to them.
    fn score(&self, members: &[usize]) -> f64 {
        self.score_under(&self.motion(members), members)
    }

    fn alive(&self) -> usize {
        self.parts.iter().filter(|p| p.is_some()).count()
    }

    /// Current labels (part ids, with gaps where parts were merged away).
    fn labels(&self) -> Vec<u32> {
        let mut labels = vec![0u32; self.data.n_vertices];
        for (k, p) in self.parts.iter().enumerate() {
            for &j in p.iter().flatten() {
                labels[j] = k as u32;
            }
        }
        labels
    }

    /// The candidate cuts of part `k` into two connected halves (module doc), without their drops.
    fn cuts_of(&self, k: usize) -> Vec<Cut> {
        let Some(members) = self.parts[k].as_ref() else { return Vec::new() };
        let least = self.params.min_part_vertices.max(1);
        if members.len() < 2 * least {
            return Vec::new();
        }
        // triangles inside the part, in local ids
        let mut local = vec![u32::MAX; self.data.n_vertices];
        for (l, &j) in members.iter().enumerate() {
            local[j] = l as u32;
        }
        let faces: Vec<[u32; 3]> = self
            .pop
            .graph_faces()
            .iter()
            .filter(|f| f.iter().all(|&v| local[v as usize] != u32::MAX))
            .map(|f| f.map(|v| local[v as usize]))
            .collect();
        let mut sub = Data::from_population_subset(self.pop, members);
        let positions = sub.clone();
        // residuals under the part's own rigid motion: h_j - (R Λ E[z|h_j] + b), as the refinement's second rule
        let whole = component_from_points(
            &positions,
            &(0..members.len()).collect::<Vec<_>>(),
            members.len(),
            self.params.floor(),
        );
        let mut residuals = Vec::with_capacity(sub.n_vertices * sub.n_shapes * 3);
        for l in 0..members.len() {
            let h = positions.vertex(l).to_vec();
            let v = whole.latent_image(&h);
            for (i, p) in h.iter().enumerate() {
                let q = whole.place(i, v);
                residuals.extend_from_slice(&[p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
            }
        }
        // the refinement's AECM runs (Algorithm 1's sub-part fits)
        let refine = self.params.for_refinement();
        let mut cuts: Vec<Cut> = Vec::new();
        for rule in 0..2 {
            if rule == 1 {
                sub = Data::from_f64(sub.n_vertices, sub.n_shapes, &residuals, sub.offsets.clone());
            }
            let seed = self.params.seed.wrapping_add(7919 * k as u64 + rule);
            let start = kmeans(&sub, 2, seed, self.params.restarts);
            // a 2-component AECM on the part's positions from the 2-means cut (kept when it loses a half)
            let mut halves = refine_cut(&positions, &start, &refine).unwrap_or(start);
            // each half one connected piece inside the part: stray pieces go to the half that explains them best
            let comps: Vec<_> = (0..2u32)
                .map(|h| {
                    let mem: Vec<usize> = (0..members.len()).filter(|&l| halves[l] == h).collect();
                    component_from_points(&positions, &mem, members.len(), self.params.floor())
                })
                .collect();
            let wbs: Vec<_> = comps.iter().map(|c| c.woodbury()).collect();
            let score = |l: usize, h: u32| {
                comps[h as usize].log_weighted_density(&wbs[h as usize], &positions.vertex(l).to_vec())
            };
            connect_labels(&mut halves, &faces, &score, None, 1);
            let split: [Vec<usize>; 2] =
                [0u32, 1].map(|h| (0..members.len()).filter(|&l| halves[l] == h).map(|l| members[l]).collect());
            if split.iter().any(|s| s.len() < least) {
                continue;
            }
            // both rules may end at the same cut
            if cuts.iter().any(|c| c.halves.contains(&split[0])) {
                continue;
            }
            let motions = [self.motion(&split[0]), self.motion(&split[1])];
            cuts.push(Cut { halves: split, motions, drop: f64::NAN });
        }
        cuts
    }

    /// Adjacent pairs of live parts (smaller id first).
    fn adjacent_pairs(&self) -> BTreeSet<(usize, usize)> {
        let labels = self.labels();
        let mut pairs = BTreeSet::new();
        for f in self.pop.graph_faces().iter() {
            for e in 0..3 {
                let (a, b) = (labels[f[e] as usize] as usize, labels[f[(e + 1) % 3] as usize] as usize);
                if a != b {
                    pairs.insert((a.min(b), a.max(b)));
                }
            }
        }
        pairs
    }

    fn split_once(&mut self) -> Result<f64> {
        let live: Vec<usize> = (0..self.parts.len()).filter(|&k| self.parts[k].is_some()).collect();
        if self.blends.is_none() {
            let motions = self.parts.iter().map(|p| p.as_ref().map(|m| self.motion(m))).collect();
            self.blends = Some(Blends::new(self.data, self.pop.graph_faces(), self.labels(), motions));
        }
        for &k in &live {
            if !self.cuts.contains_key(&k) {
                let c = self.cuts_of(k);
                self.cuts.insert(k, c);
            }
        }
        let blends = self.blends.as_mut().expect("built above");
        let mut best: Option<(usize, usize, f64)> = None;
        for &k in &live {
            for (c, cut) in self.cuts.get_mut(&k).expect("computed above").iter_mut().enumerate() {
                if cut.drop.is_nan() {
                    cut.drop = blends.split_drop(k, &cut.motions);
                }
                if best.is_none_or(|b| cut.drop > b.2) {
                    best = Some((k, c, cut.drop));
                }
            }
        }
        let Some((k, c, _)) = best else {
            return Err(Error::Data(format!(
                "cannot reach {} parts: none of the {} parts can be cut into two connected pieces of at least {} \
                 vertices each (the smallest part a fit keeps); ask for at most {} parts",
                self.target,
                live.len(),
                self.params.min_part_vertices.max(1),
                live.len()
            )));
        };
        let cut = self.cuts.remove(&k).expect("chosen part has cuts").swap_remove(c);
        let [a, b] = cut.halves;
        let [ma, mb] = cut.motions;
        let (la, lb) = (self.score_under(&ma, &a), self.score_under(&mb, &b));
        let gain = la + lb - self.ll[k];
        self.ll[k] = la;
        self.ll.push(lb);
        let stale = self.blends.as_mut().expect("built above").apply_split(k, &b, [ma, mb]);
        self.parts[k] = Some(a);
        self.parts.push(Some(b));
        let n = self.parts.len() - 1;
        // the drops of the parts near the cut change (their vertices are offered other motions)
        for p in stale {
            for cut in self.cuts.get_mut(&p).into_iter().flatten() {
                cut.drop = f64::NAN;
            }
        }
        self.unions.retain(|&(p, q), _| p != k && q != k);
        self.cuts.remove(&n);
        Ok(gain)
    }

    fn merge_once(&mut self) -> Result<f64> {
        let pairs = self.adjacent_pairs();
        let mut best: Option<((usize, usize), f64, f64)> = None;
        for &(a, b) in &pairs {
            let ll = match self.unions.get(&(a, b)) {
                Some(&x) => x,
                None => {
                    let mut union = self.parts[a].clone().expect("live");
                    union.extend_from_slice(self.parts[b].as_ref().expect("live"));
                    let x = self.score(&union);
                    self.unions.insert((a, b), x);
                    x
                }
            };
            let loss = self.ll[a] + self.ll[b] - ll;
            if best.is_none_or(|x| loss < x.1) {
                best = Some(((a, b), loss, ll));
            }
        }
        let Some(((a, b), loss, ll)) = best else {
            return Err(Error::Data(format!(
                "cannot reach {} parts: the {} parts left share no mesh edge (the mesh has separate pieces, each \
                 needs a part of its own); ask for at least {} parts",
                self.target,
                self.alive(),
                self.alive()
            )));
        };
        let moved = self.parts[b].take().expect("live");
        self.parts[a].as_mut().expect("live").extend(moved);
        self.ll[a] = ll;
        self.ll[b] = 0.0;
        self.unions.retain(|&(p, q), _| p != a && q != a && p != b && q != b);
        self.cuts.remove(&a);
        self.cuts.remove(&b);
        // (built again should a split follow)
        self.blends = None;
        Ok(-loss)
    }
}

/// Labels with exactly `n` parts (renumbered 0..n), from `labels` (Algorithm 1's result; each label one
/// connected piece of the mesh, as [`super::islands::connect_parts`] leaves them), by the splits and merges of
/// the module doc.
pub fn labels_with_count(
    pop: &Population,
    labels: &[u32],
    n: usize,
    params: &impl InFit,
) -> Result<(Vec<u32>, CountChange)> {
    let params = &params.in_fit(|| pop.mean_squared_radius());
    check_target(n, pop.n_vertices(), params.min_part_vertices)?;
    if labels.len() != pop.n_vertices() {
        return Err(Error::Request(format!("{} labels for {} vertices", labels.len(), pop.n_vertices())));
    }
    let data = Data::from_population(pop);
    let m = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let mut members = vec![Vec::new(); m];
    for (j, &l) in labels.iter().enumerate() {
        members[l as usize].push(j);
    }
    members.retain(|p| !p.is_empty());
    let mut c = Counter {
        pop,
        data: &data,
        params,
        target: n,
        parts: Vec::new(),
        ll: Vec::new(),
        cuts: HashMap::new(),
        blends: None,
        unions: HashMap::new(),
    };
    c.ll = members.iter().map(|p| c.score(p)).collect();
    c.parts = members.into_iter().map(Some).collect();
    let mut change = CountChange { from: c.alive(), ..Default::default() };
    while c.alive() < n {
        change.log_likelihood_change += c.split_once()?;
        change.splits += 1;
    }
    while c.alive() > n {
        change.log_likelihood_change += c.merge_once()?;
        change.merges += 1;
    }
    let mut out = vec![0u32; pop.n_vertices()];
    for (k, p) in c.parts.iter().flatten().enumerate() {
        for &j in p {
            out[j] = k as u32;
        }
    }
    Ok((out, change))
}

/// Labels 0 / 1 of a 2-component AECM on `data` (a part's vertices) started from `start`, as Algorithm 1's
/// refinement fits a split sub-part; None when the fit fails or leaves one half empty.
fn refine_cut(data: &Data, start: &[u32], params: &RunParams) -> Option<Vec<u32>> {
    let mut fit = Fit::from_labels(data.clone(), start, params).ok()?;
    fit.run(&mut |_| true);
    let labels = fit.labels();
    (fit.n_parts() == 2 && labels.contains(&0) && labels.contains(&1)).then_some(labels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{generate, part_index, Preset, Spec};

    #[test]
    fn one_split_more_finds_the_joint_inside_a_merged_limb() {
        // the arm's upper arm and forearm given as one part: asked for the true count, the split is the elbow
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let (upper, forearm) =
            (part_index(Preset::Arm, "upper_arm").unwrap() as u32, part_index(Preset::Arm, "forearm").unwrap() as u32);
        let merged: Vec<u32> = g.part_of_vertex.iter().map(|&l| if l == forearm { upper } else { l }).collect();
        let (labels, change) = labels_with_count(&g.population, &merged, 3, &crate::mfa::Params::default()).unwrap();
        assert_eq!((change.from, change.splits, change.merges), (2, 1, 0));
        let ari = crate::metrics::adjusted_rand_index(&labels, &g.part_of_vertex);
        assert!(ari > 0.95, "ari {ari}");
    }

    #[test]
    fn splits_go_to_merged_joints_before_rigid_parts() {
        // a quadruped with two legs' upper and lower parts merged: two splits more cut those legs at their knees
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
        let names = crate::synth::part_names(Preset::Quadruped);
        let idx = |n: &str| part_index(Preset::Quadruped, n).unwrap_or_else(|| panic!("{n} not in {names:?}")) as u32;
        let pairs =
            [(idx("front_left_upper"), idx("front_left_lower")), (idx("hind_right_upper"), idx("hind_right_lower"))];
        let merged: Vec<u32> =
            g.part_of_vertex.iter().map(|&l| pairs.iter().find(|p| p.1 == l).map_or(l, |p| p.0)).collect();
        let n = g.n_parts();
        let (labels, change) = labels_with_count(&g.population, &merged, n, &crate::mfa::Params::default()).unwrap();
        assert_eq!((change.splits, change.merges), (2, 0));
        // each merged leg cut in two: most of its upper part's vertices in one part, most of its lower's in another
        let most = |t: u32| {
            let mut count = HashMap::new();
            g.part_of_vertex
                .iter()
                .zip(&labels)
                .filter(|p| *p.0 == t)
                .for_each(|p| *count.entry(*p.1).or_insert(0usize) += 1);
            count.into_iter().max_by_key(|c| (c.1, c.0)).unwrap().0
        };
        for &(u, l) in &pairs {
            assert_ne!(most(u), most(l), "{} and {} still one part", names[u as usize], names[l as usize]);
        }
        let ari = crate::metrics::adjusted_rand_index(&labels, &g.part_of_vertex);
        assert!(ari > 0.95, "ari {ari}");
    }
}
