//! An exact part count (`Params::target_parts`, the CLI's `--bones N`, the page's "Parts: N").
//!
//! Algorithm 1 chooses its own number of parts. A rig is often wanted with a given number of bones, so after
//! Algorithm 1's result the labels are changed one part at a time until there are exactly N, and the final
//! AECM then runs again from them ([`super::hierarchy`]):
//!
//! - **too few**: split the part whose split gains the most log-likelihood. Each part is cut in two the way
//!   the refinement cuts a sub-part (2-means, [`crate::mfa::init::kmeans`]), once on its vertices' positions over
//!   all shapes and once on their residuals under the part's own rigid motion; the better of the two is
//!   its candidate. Each half is made one connected piece inside the part (stray pieces join the half that
//!   explains them best, [`super::islands::connect_labels`]).
//! - **too many**: merge the two adjacent parts (sharing a mesh edge) whose merge loses the least.
//!
//! Both compare the classification log-likelihood Σ_j log(π_k N(h_j; θ_k)) (eq 6 weighted as in eq 12) of the
//! vertices involved, every part's component fitted to its own vertices in closed form
//! ([`crate::mfa::init::component_from_points`], the start the AECM uses), so a split and a merge are scored the
//! same way and the N - 1 and N + 1 decisions agree. Every step keeps every part one connected piece: a merge
//! joins two adjacent pieces, a split leaves two connected halves.
//!
//! N cannot be met when N = 0, when N parts of at least `min_part_vertices` vertices do not fit in the mesh
//! ([`check_target`]), when no part can be cut into two connected halves of `min_part_vertices` vertices,
//! or when the parts left touch no other part (a mesh of separate pieces): each gives an error that says
//! what to ask for instead.

use crate::mfa::data::Data;
use crate::mfa::init::{component_from_points, kmeans};
use super::islands::connect_labels;
use crate::mfa::params::Params;
use crate::error::{Error, Result};
use crate::mesh::Population;
use std::collections::{BTreeSet, HashMap};

/// Checks that `n` parts of at least `min_part_vertices` vertices can exist on `n_vertices` vertices.
pub fn check_target(n: usize, n_vertices: usize, min_part_vertices: usize) -> Result<()> {
    if n == 0 {
        return Err(Error::Params("target_parts = 0: a rig needs at least 1 part (ask for 1 or more, or auto)".into()));
    }
    let most = n_vertices / min_part_vertices.max(1);
    if n > most {
        return Err(Error::Params(format!(
            "target_parts = {n}: the mesh has {n_vertices} vertices and every part needs at least {} \
             (min_part_vertices), so at most {most} parts are possible; ask for at most {most}",
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

/// A part split in two: the vertex lists of both halves and the gain in log-likelihood.
#[derive(Debug, Clone)]
struct Split {
    halves: [Vec<usize>; 2],
    gain: f64,
}

struct Counter<'a> {
    pop: &'a Population,
    data: Data,
    params: &'a Params,
    /// The part count asked for (for the error messages).
    target: usize,
    /// Vertices of every part; None once merged away.
    parts: Vec<Option<Vec<usize>>>,
    /// Classification log-likelihood of every part's vertices under its own component.
    ll: Vec<f64>,
    /// Best split of a part (None: it cannot be split), computed when first needed.
    splits: HashMap<usize, Option<Split>>,
    /// Log-likelihood of the union of two adjacent parts (smaller id first).
    unions: HashMap<(usize, usize), f64>,
}

impl<'a> Counter<'a> {
    /// Σ_j log(π N(h_j; θ)) of `members` under the component fitted to them.
    fn score(&self, members: &[usize]) -> f64 {
        let c = component_from_points(&self.data, members, self.data.n_vertices, self.params.variance_floor);
        let wb = c.woodbury();
        let mut h = Vec::new();
        members.iter().map(|&j| c.log_weighted_density(&wb, self.data.vertex_into(j, &mut h))).sum()
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

    /// The best way to cut part `k` in two connected halves (module doc), or None.
    fn best_split(&self, k: usize) -> Option<Split> {
        let members = self.parts[k].as_ref()?;
        let least = self.params.min_part_vertices.max(1);
        if members.len() < 2 * least {
            return None;
        }
        // triangles inside the part, in local ids
        let mut local = vec![u32::MAX; self.data.n_vertices];
        for (l, &j) in members.iter().enumerate() {
            local[j] = l as u32;
        }
        let faces: Vec<[u32; 3]> = self
            .pop
            .faces
            .iter()
            .filter(|f| f.iter().all(|&v| local[v as usize] != u32::MAX))
            .map(|f| f.map(|v| local[v as usize]))
            .collect();
        let mut sub = Data::from_population_subset(self.pop, members);
        let positions = sub.clone();
        // residuals under the part's own rigid motion: h_j - (R Λ E[z|h_j] + b), as the refinement's second rule
        let whole = component_from_points(&positions, &(0..members.len()).collect::<Vec<_>>(), members.len(), self.params.variance_floor);
        let mut residuals = Vec::with_capacity(sub.n_vertices * sub.n_shapes * 3);
        for l in 0..members.len() {
            let h = positions.vertex(l).to_vec();
            let v = whole.latent_image(&h);
            for (i, p) in h.iter().enumerate() {
                let q = whole.place(i, v);
                residuals.extend_from_slice(&[p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
            }
        }
        let mut best: Option<Split> = None;
        for rule in 0..2 {
            if rule == 1 {
                sub = Data::from_f64(sub.n_vertices, sub.n_shapes, &residuals, sub.offsets.clone());
            }
            let seed = self.params.seed.wrapping_add(7919 * k as u64 + rule);
            let mut halves = kmeans(&sub, 2, seed, self.params.restarts);
            // each half one connected piece inside the part: stray pieces go to the half that explains them best
            let comps: Vec<_> = (0..2u32)
                .map(|h| {
                    let mem: Vec<usize> = (0..members.len()).filter(|&l| halves[l] == h).collect();
                    component_from_points(&positions, &mem, members.len(), self.params.variance_floor)
                })
                .collect();
            let wbs: Vec<_> = comps.iter().map(|c| c.woodbury()).collect();
            let score = |l: usize, h: u32| comps[h as usize].log_weighted_density(&wbs[h as usize], &positions.vertex(l).to_vec());
            connect_labels(&mut halves, &faces, &score, None, 1);
            let split: [Vec<usize>; 2] =
                [0u32, 1].map(|h| (0..members.len()).filter(|&l| halves[l] == h).map(|l| members[l]).collect());
            if split.iter().any(|s| s.len() < least) {
                continue;
            }
            let gain = self.score(&split[0]) + self.score(&split[1]) - self.ll[k];
            if best.as_ref().is_none_or(|b| gain > b.gain) {
                best = Some(Split { halves: split, gain });
            }
        }
        best
    }

    /// Adjacent pairs of live parts (smaller id first).
    fn adjacent_pairs(&self) -> BTreeSet<(usize, usize)> {
        let labels = self.labels();
        let mut pairs = BTreeSet::new();
        for f in &self.pop.faces {
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
        for &k in &live {
            if !self.splits.contains_key(&k) {
                let s = self.best_split(k);
                self.splits.insert(k, s);
            }
        }
        let best = live
            .iter()
            .filter_map(|&k| self.splits[&k].as_ref().map(|s| (k, s.gain)))
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
        let Some((k, gain)) = best else {
            return Err(Error::Data(format!(
                "cannot reach {} parts: none of the {} parts can be cut into two connected pieces of at least {} \
                 vertices (min_part_vertices); ask for fewer parts or lower min_part_vertices",
                self.target,
                live.len(),
                self.params.min_part_vertices.max(1)
            )));
        };
        let split = self.splits.remove(&k).flatten().expect("chosen split exists");
        let [a, b] = split.halves;
        self.ll[k] = self.score(&a);
        let lb = self.score(&b);
        self.parts[k] = Some(a);
        self.parts.push(Some(b));
        self.ll.push(lb);
        let n = self.parts.len() - 1;
        self.unions.retain(|&(p, q), _| p != k && q != k);
        self.splits.remove(&n);
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
        self.splits.remove(&a);
        self.splits.remove(&b);
        Ok(-loss)
    }
}

/// Labels with exactly `n` parts (renumbered 0..n), from `labels` (Algorithm 1's result; each label one
/// connected piece of the mesh, as [`super::islands::connect_parts`] leaves them), by the splits and merges of
/// the module doc.
pub fn labels_with_count(pop: &Population, labels: &[u32], n: usize, params: &Params) -> Result<(Vec<u32>, CountChange)> {
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
        data,
        params,
        target: n,
        parts: Vec::new(),
        ll: Vec::new(),
        splits: HashMap::new(),
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
