//! The parts as one merge tree, a function of the population alone: no random start, so the same creature
//! comes out of any seed, any pose order and any rigid placement or scale of the whole population.
//!
//! 1. **Patches** ([`super::patches`]): the mesh is cut into many small, compact pieces by farthest-point sampling
//!    with geodesic distances along the mesh's edges (each edge's length averaged over the poses), every vertex
//!    to its nearest seed. Only the connectivity and the poses' edge lengths enter, so the patches do not depend
//!    on the order of the poses nor on where the population stands.
//! 2. **Merges** ([`MergeTree::build`]): adjacent nodes are merged greedily, cheapest first, by the part rule's
//!    score: the rise in squared error when one rigid motion moves both (generalised Procrustes over the poses),
//!    per vertex of the smaller side. Each node keeps additive sufficient statistics (its vertex count, per pose
//!    the sum of its points and, per pair of poses, Σ_j x_j^i x_j^kᵀ), so the rigid fit of a union is solved on
//!    3x3 blocks without touching the vertices again (`rigid_stats`). Every merge is recorded: the tree gives
//!    a partition for every count, at once ([`MergeTree::labels_at`]).
//! 3. **The count** ([`MergeTree::decided_count`]): read off the tree by the part rule: merges go on while the
//!    next one costs the smaller side, per vertex, less than `distinct_ratio` times the variance of a typical
//!    part of that partition (the vertex-weighted median of its nodes' rigid-fit variances).
//!
//! The model's AECM then runs from that partition ([`super::hierarchy`]) and the part rule's flesh test and
//! merges ([`super::distinct`]) judge the fitted parts.

use super::patches::{patch_count, patches, spread_poses};
use crate::geometry::procrustes::best_rotation;
use crate::geometry::{Mat3, IDENTITY};
use crate::mesh::Population;
use rigid_stats::{rigid_sse, Stats};
use serde::Serialize;
use std::cmp::Ordering;
use std::collections::{BTreeSet, BinaryHeap};

mod rigid_stats;

/// Most poses the tree's rigid fits look at: with more, a well-spread subset ([`spread_poses`]). The statistics
/// grow with the square of the poses.
pub const TREE_POSES: usize = 16;

/// More nodes than a body has parts: [`MergeTree::merge_yardstick`] averages the merges above this many nodes.
pub const PART_NODES: usize = 100;
/// One merge: nodes `a` and `b` became node `n_leaves + index`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Merge {
    pub a: u32,
    pub b: u32,
    /// Parts before this merge.
    pub parts: usize,
    /// The rise in squared error of one rigid motion for both, per vertex of the smaller side, per coordinate
    /// and pose (unit-box units²).
    pub rise: f64,
    /// `rise / typical` with `typical` the tree's ([`MergeTree::typical`]): the part rule's score.
    pub score: f64,
    /// The vertex-weighted mean variance of the rigid fits of the `parts` nodes before the merge.
    pub variance: f64,
}

/// The merge tree of a population.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MergeTree {
    /// The patch (leaf) of every vertex.
    pub leaves: Vec<u32>,
    pub n_leaves: usize,
    /// In order; merge m makes node `n_leaves + m`.
    pub merges: Vec<Merge>,
    /// What the scores are divided by: when the tree is built, the vertex-weighted median variance of the
    /// leaves' rigid fits (at least the variance floor), fixed before any merge (a merge's larger variance must
    /// not make the next merge look cheap); [`MergeTree::rescore`] sets another (the start's
    /// [`MergeTree::merge_yardstick`], the decision's [`MergeTree::middle_typical`]).
    pub typical: f64,
    /// The geometric mean of the leaves' variances over their middle vertices (between the [`MIDDLE_BAND`] and
    /// 1 - [`MIDDLE_BAND`] quantiles by vertex; at least the variance floor): the part rule's yardstick on the
    /// fitted parts' tree ([`MergeTree::middle_typical`]).
    #[serde(skip)]
    middle: f64,
}

#[derive(PartialEq)]
struct Candidate {
    score: f64,
    a: u32,
    b: u32,
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Candidate {
    // a min-heap on the score, then the node ids
    fn cmp(&self, o: &Self) -> Ordering {
        o.score.total_cmp(&self.score).then(o.a.cmp(&self.a)).then(o.b.cmp(&self.b))
    }
}

/// The rigid fit of a candidate merge: the rise it scores, its squared error and rotations.
struct Fit {
    rise: f64,
    /// sse - the two sides' sse (not clamped at 0).
    raw: f64,
    sse: f64,
    rot: Vec<Mat3>,
}

/// A candidate merge in the heap: its fit once made; before that only a lower bound of its raw rise
/// (`sse(a ∪ b) - sse(a) - sse(b)`, see [`MergeTree::from_leaves`]).
struct Pending {
    raw_lower: f64,
    fit: Option<Fit>,
}

struct Node {
    stats: Stats,
    rot: Vec<Mat3>,
    sse: f64,
    size: usize,
}

impl Node {
    fn variance(&self) -> f64 {
        self.sse / (3.0 * self.stats.n.max(1.0) * self.rot.len().max(1) as f64)
    }
}

/// How many of a tree's `m` first merges [`MergeTree::merge_yardstick`] averages.
fn yardstick_merges(m: usize) -> usize {
    (3 * m / 4).min(m.saturating_sub(PART_NODES).max(m / 2))
}

/// Where the middle of the leaves' variances starts and ends, as quantiles by vertex ([`MergeTree::middle`]).
pub const MIDDLE_BAND: f64 = 0.3;

/// The vertex-weighted median of the nodes' variances, and their geometric mean over the middle band of
/// vertices ([`MIDDLE_BAND`]).
fn typical_variances(nodes: &[Option<Node>]) -> (f64, f64) {
    let (values, sizes): (Vec<f64>, Vec<usize>) = nodes.iter().flatten().map(|n| (n.variance(), n.size)).unzip();
    let middle = super::labels::weighted_log_mean_between(&values, &sizes, MIDDLE_BAND, 1.0 - MIDDLE_BAND);
    (super::labels::weighted_median(&values, &sizes), middle)
}

impl MergeTree {
    /// Builds the tree of `pop` from [`patches`] of [`patch_count`] pieces. `floor` (the variance floor) keeps
    /// the typical variance of exactly rigid data away from 0.
    pub fn build(pop: &Population, floor: f64) -> MergeTree {
        let leaves = patches(pop, patch_count(pop.n_vertices()));
        MergeTree::from_leaves(pop, leaves, floor)
    }

    /// Builds the tree from given leaves (compact labels: 0..n_leaves).
    pub fn from_leaves(pop: &Population, leaves: Vec<u32>, floor: f64) -> MergeTree {
        let poses = spread_poses(pop, TREE_POSES);
        let q = poses.len();
        let n_leaves = leaves.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        let mut stats = vec![Stats::empty(q); n_leaves];
        let mut size = vec![0usize; n_leaves];
        let mut x = vec![[0.0; 3]; q];
        for (j, &l) in leaves.iter().enumerate() {
            for (t, &i) in poses.iter().enumerate() {
                x[t] = pop.point(i, j);
            }
            stats[l as usize].add_point(&x);
            size[l as usize] += 1;
        }
        let mut nodes: Vec<Option<Node>> = stats
            .into_iter()
            .zip(size)
            .map(|(st, size)| {
                // start: each pose onto the first
                let c = st.centred();
                let mut rot: Vec<Mat3> =
                    (0..q).map(|i| if i == 0 { IDENTITY } else { best_rotation(&c[i * q]) }).collect();
                let sse = rigid_sse(&st, &mut rot);
                Some(Node { stats: st, rot, sse, size })
            })
            .collect();
        // node adjacency: mesh edges between patches, and every other connected piece of the mesh linked to
        // its nearest one (so the tree ends in one node)
        let mut adjacent: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); n_leaves];
        for f in pop.graph_faces().iter() {
            for s in 0..3 {
                let (a, b) = (leaves[f[s] as usize], leaves[f[(s + 1) % 3] as usize]);
                if a != b {
                    adjacent[a as usize].insert(b);
                    adjacent[b as usize].insert(a);
                }
            }
        }
        link_pieces(pop, &leaves, &mut adjacent);
        // the statistics of a and b together, the larger side first (the rotations start from its fit)
        fn joined(nodes: &[Option<Node>], a: u32, b: u32) -> (Stats, usize, usize, &[Mat3]) {
            let (na, nb) = (nodes[a as usize].as_ref().expect("live"), nodes[b as usize].as_ref().expect("live"));
            let (big, small) = if na.size >= nb.size { (na, nb) } else { (nb, na) };
            (big.stats.plus(&small.stats), na.size + nb.size, small.size, &big.rot[..])
        }
        // a candidate merge's rigid fit, kept until the merge is made or a side is gone
        let pair = |nodes: &[Option<Node>], a: u32, b: u32| -> Fit {
            let (st, _, small, start) = joined(nodes, a, b);
            let mut rot = start.to_vec();
            let sse = rigid_sse(&st, &mut rot);
            let (na, nb) = (nodes[a as usize].as_ref().expect("live"), nodes[b as usize].as_ref().expect("live"));
            let raw = sse - na.sse - nb.sse;
            Fit { rise: raw.max(0.0) / (3.0 * q as f64 * small.max(1) as f64), raw, sse, rot }
        };
        let size_of = |nodes: &[Option<Node>], a: u32| nodes[a as usize].as_ref().expect("live").size;
        let (typical, middle) = typical_variances(&nodes);
        let (typical, middle) = (typical.max(floor), middle.max(floor));
        // Lazy candidates. Every adjacent pair is in the heap once, keyed by its rise or by a lower bound of it:
        // a bound that reaches the top gets its rigid fit and goes back in with its exact rise, an exact one on
        // top is the cheapest merge. Bounds only postpone fits, so the merges are the eager greedy's, in order
        // (the tree of every real population was checked equal: docs/speed.md). The bound after a and b merged
        // into ab, for a neighbour c: the rigid error of a union is at least the sum of its pieces' (each piece
        // fitted on its own does at least as well), so sse(c∪a∪b) >= sse(c∪a) + sse(b), i.e.
        // raw(c, ab) >= raw(c, a) - raw(a, b), and the same with b; less a slack of 1e-9 of the points' spread
        // for the fits' own convergence tolerance.
        let mut heap = BinaryHeap::new();
        let mut pending: std::collections::HashMap<(u32, u32), Pending> = Default::default();
        for a in 0..n_leaves {
            for &b in adjacent[a].iter().filter(|&&b| b as usize > a) {
                heap.push(Candidate { score: 0.0, a: a as u32, b });
                pending.insert((a as u32, b), Pending { raw_lower: 0.0, fit: None });
            }
        }
        let key = |x: u32, y: u32| (x.min(y), x.max(y));
        let mut merges = Vec::with_capacity(n_leaves.saturating_sub(1));
        let mut live = n_leaves;
        let mut total_sse: f64 = nodes.iter().flatten().map(|n| n.sse).sum();
        let per_variance = 1.0 / (3.0 * q.max(1) as f64 * leaves.len().max(1) as f64);
        while let Some(Candidate { a, b, .. }) = heap.pop() {
            let Some(entry) = pending.get_mut(&(a, b)) else { continue };
            let Some(fit) = entry.fit.take() else {
                let fit = pair(&nodes, a, b);
                heap.push(Candidate { score: fit.rise, a, b });
                entry.raw_lower = fit.raw;
                entry.fit = Some(fit);
                continue;
            };
            pending.remove(&(a, b));
            let (stats, size, _, _) = joined(&nodes, a, b);
            let spread = stats.spread();
            let Fit { rise, raw, sse, rot } = fit;
            let node = Node { stats, rot, sse, size };
            let id = nodes.len() as u32;
            let variance = total_sse * per_variance;
            total_sse += node.sse
                - nodes[a as usize].as_ref().map_or(0.0, |n| n.sse)
                - nodes[b as usize].as_ref().map_or(0.0, |n| n.sse);
            merges.push(Merge { a, b, parts: live, rise, score: rise / typical, variance });
            nodes[a as usize] = None;
            nodes[b as usize] = None;
            nodes.push(Some(node));
            live -= 1;
            let mut around: BTreeSet<u32> = adjacent[a as usize].union(&adjacent[b as usize]).copied().collect();
            around.remove(&a);
            around.remove(&b);
            for &c in &around {
                adjacent[c as usize].remove(&a);
                adjacent[c as usize].remove(&b);
                adjacent[c as usize].insert(id);
                let lower =
                    [a, b].iter().filter_map(|&x| pending.remove(&key(c, x))).map(|p| p.raw_lower).fold(0.0, f64::max);
                let slack = 1e-9 * (spread + nodes[c as usize].as_ref().expect("live").stats.spread());
                let raw_lower = (lower - raw.max(0.0) - slack).max(0.0);
                let small = size_of(&nodes, c).min(size);
                heap.push(Candidate { score: raw_lower / (3.0 * q as f64 * small.max(1) as f64), a: c, b: id });
                pending.insert((c, id), Pending { raw_lower, fit: None });
            }
            adjacent.push(around);
            adjacent[a as usize].clear();
            adjacent[b as usize].clear();
        }
        MergeTree { leaves, n_leaves, merges, typical, middle }
    }

    /// What merging two pieces of one part typically costs: the mean rise of the tree's cheapest merges, from the
    /// patches down to a quarter of them (on a mesh of a few tens of parts these join pieces of one part); on a tree of
    /// fewer than 400 patches, down to [`PART_NODES`] nodes or half of the merges, whichever takes more (the same count
    /// at 400). The same quantity as the scores, averaged over hundreds of merges, so a cut against it moves little
    /// with the data (less than the patches' median variance, [`MergeTree::typical`], with a pose dropped). Why not a
    /// quarter on every tree: a smaller tree's patches are larger against its parts, and its third quarter of merges
    /// joins parts across their joints, which lifts the mean far above its median and leaves the start, and the fit,
    /// with too few parts (the figures of both: docs/decisions.md, "Figures behind src/parts").
    pub fn merge_yardstick(&self) -> f64 {
        let k = yardstick_merges(self.merges.len());
        if k == 0 {
            return self.typical;
        }
        self.merges[..k].iter().map(|x| x.rise).sum::<f64>() / k as f64
    }

    /// A tree as a model file stored it ([`crate::model_file`], which checks every merge joins two earlier nodes).
    pub fn from_saved(leaves: Vec<u32>, n_leaves: usize, merges: Vec<Merge>, typical: f64, middle: f64) -> MergeTree {
        MergeTree { leaves, n_leaves, merges, typical, middle }
    }

    /// The part rule's yardstick on the tree of a fit's parts: [`MergeTree::middle`]. The median
    /// ([`MergeTree::typical`]) falls where the parts' variances climb steeply, so a small change of the data moves it
    /// far, and the count with it. The mean of the logs over the middle 40 % of vertices averages across that climb
    /// (the counts with a pose dropped, both ways: docs/decisions.md, "Figures behind src/parts"). Its level is the
    /// median's where the logs are spread evenly around it.
    pub fn middle_typical(&self) -> f64 {
        self.middle
    }

    /// Scores the merges against another typical variance.
    pub fn rescore(&mut self, typical: f64) {
        self.typical = typical;
        for m in self.merges.iter_mut() {
            m.score = m.rise / typical;
        }
    }

    /// The most parts the tree has (its leaves) and the fewest (after every merge).
    pub fn counts(&self) -> (usize, usize) {
        (self.n_leaves, self.n_leaves - self.merges.len())
    }

    /// Compact labels of the partition with `count` parts (clamped to the tree's counts), numbered in the order
    /// of their first vertex.
    pub fn labels_at(&self, count: usize) -> Vec<u32> {
        let (most, fewest) = self.counts();
        let count = count.clamp(fewest, most);
        let done = most - count;
        // the node every leaf ends in after `done` merges
        let mut up: Vec<u32> = (0..(self.n_leaves + done) as u32).collect();
        for (m, mg) in self.merges[..done].iter().enumerate() {
            let id = (self.n_leaves + m) as u32;
            up[mg.a as usize] = id;
            up[mg.b as usize] = id;
        }
        let root = |mut x: u32| {
            while up[x as usize] != x {
                x = up[x as usize];
            }
            x
        };
        let mut number = std::collections::HashMap::new();
        self.leaves
            .iter()
            .map(|&l| {
                let r = root(l);
                let next = number.len() as u32;
                *number.entry(r).or_insert(next)
            })
            .collect()
    }

    /// The merges as the part rule's curve of decisions, from the most parts down to `count` and the first merge
    /// that was not made (as [`super::distinct::merge_indistinct`] reports them).
    pub fn curve(&self, count: usize) -> Vec<CurvePoint> {
        self.merges
            .iter()
            .take_while(|m| m.parts > count)
            .map(|m| CurvePoint { parts: m.parts, score: m.score, variance: m.variance, merged: true })
            .chain(self.merges.iter().find(|m| m.parts == count).map(|m| CurvePoint {
                parts: m.parts,
                score: m.score,
                variance: m.variance,
                merged: false,
            }))
            .collect()
    }

    /// The count the part rule reads off the tree: merges go on while they score below `ratio` (the rise per
    /// vertex of the smaller side over the leaves' typical variance); the count before the first merge that
    /// does not.
    pub fn decided_count(&self, ratio: f64) -> usize {
        self.merges.iter().find(|m| m.score >= ratio).map_or(self.counts().1, |m| m.parts)
    }
}

/// The partitions a fit offers by its merge tree, one for every count (the page's "Parts in the merge tree"
/// slider): the tree's cut, except at the count the part rule read off it, where the fit's own labels are
/// (the fit was refitted from that cut, so its parts can differ from it). Held apart from its fit, so that the
/// partitions of the fit a Refine started from stay in reach once the refined fit has replaced it.
#[derive(Debug, Clone)]
pub struct TreeCuts {
    tree: MergeTree,
    decided: Option<usize>,
    /// The fit's labels when it has the decided count.
    fitted: Option<Vec<u32>>,
}

impl TreeCuts {
    /// `fitted`: the fit's labels, used at `decided` when they have that many parts.
    pub fn new(tree: MergeTree, decided: Option<usize>, fitted: &[u32]) -> TreeCuts {
        let parts = fitted.iter().collect::<BTreeSet<_>>().len();
        let fitted = (decided == Some(parts)).then(|| fitted.to_vec());
        TreeCuts { tree, decided, fitted }
    }

    /// The most and the fewest parts (see [`MergeTree::counts`]).
    pub fn counts(&self) -> (usize, usize) {
        self.tree.counts()
    }

    /// The count the part rule read off the tree (none with a count asked for).
    pub fn decided(&self) -> Option<usize> {
        self.decided
    }

    /// One label per vertex for `count` parts (clamped to the tree's counts).
    pub fn labels(&self, count: usize) -> Vec<u32> {
        match &self.fitted {
            Some(f) if self.decided == Some(count) => f.clone(),
            _ => self.tree.labels_at(count),
        }
    }
}

/// Links every connected piece of the patch graph but the largest to the piece holding the vertex nearest to it
/// (mean shape, on at most 64 of its vertices), so that merges can reach every node.
fn link_pieces(pop: &Population, leaves: &[u32], adjacent: &mut [BTreeSet<u32>]) {
    let n = adjacent.len();
    let mut piece = vec![u32::MAX; n];
    let mut pieces = 0u32;
    for s in 0..n {
        if piece[s] != u32::MAX {
            continue;
        }
        let mut stack = vec![s as u32];
        piece[s] = pieces;
        while let Some(v) = stack.pop() {
            for &u in &adjacent[v as usize] {
                if piece[u as usize] == u32::MAX {
                    piece[u as usize] = pieces;
                    stack.push(u);
                }
            }
        }
        pieces += 1;
    }
    if pieces <= 1 {
        return;
    }
    let ns = pop.n_shapes() as f64;
    let mean: Vec<[f64; 3]> = (0..pop.n_vertices())
        .map(|j| {
            let mut m = [0.0; 3];
            for s in pop.shapes() {
                let p = s.get(j);
                for c in 0..3 {
                    m[c] += p[c] / ns;
                }
            }
            m
        })
        .collect();
    let piece_of = |j: usize| piece[leaves[j] as usize];
    let mut size = vec![0usize; pieces as usize];
    for j in 0..leaves.len() {
        size[piece_of(j) as usize] += 1;
    }
    let largest = (0..pieces as usize).max_by(|&x, &y| size[x].cmp(&size[y]).then(y.cmp(&x))).expect("pieces");
    for p in (0..pieces).filter(|&p| p as usize != largest) {
        let inside: Vec<usize> = (0..leaves.len()).filter(|&j| piece_of(j) == p).collect();
        let stride = inside.len().div_ceil(64).max(1);
        let mut best: Option<(f64, usize, usize)> = None;
        for &j in inside.iter().step_by(stride) {
            for k in (0..leaves.len()).filter(|&k| piece_of(k) != p) {
                let d: f64 = (0..3).map(|c| (mean[j][c] - mean[k][c]).powi(2)).sum();
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, j, k));
                }
            }
        }
        if let Some((_, j, k)) = best {
            let (a, b) = (leaves[j], leaves[k]);
            adjacent[a as usize].insert(b);
            adjacent[b as usize].insert(a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{generate, Preset, Spec};

    /// The lazily evaluated merges are the eager greedy's: replaying the tree, every merge it made was the
    /// cheapest of all adjacent live pairs at that moment, each pair's rise computed afresh.
    #[test]
    fn every_merge_is_the_cheapest_adjacent_pair() {
        let g =
            generate(&Spec { preset: Preset::Quadruped, vertices: 700, poses: 9, seed: 3, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let tree = MergeTree::build(pop, 1e-14);
        let poses = spread_poses(pop, TREE_POSES);
        let q = poses.len();
        let mut stats: Vec<Option<Stats>> = vec![Some(Stats::empty(q)); tree.n_leaves];
        for (j, &l) in tree.leaves.iter().enumerate() {
            let x: Vec<[f64; 3]> = poses.iter().map(|&i| pop.point(i, j)).collect();
            stats[l as usize].as_mut().unwrap().add_point(&x);
        }
        let sse = |st: &Stats| {
            let c = st.centred();
            let mut rot: Vec<Mat3> = (0..q).map(|i| if i == 0 { IDENTITY } else { best_rotation(&c[i * q]) }).collect();
            rigid_sse(st, &mut rot)
        };
        let mut edges: BTreeSet<(u32, u32)> = BTreeSet::new();
        for f in pop.faces.iter() {
            for s in 0..3 {
                let (a, b) = (tree.leaves[f[s] as usize], tree.leaves[f[(s + 1) % 3] as usize]);
                if a != b {
                    edges.insert((a.min(b), a.max(b)));
                }
            }
        }
        let mut own: Vec<f64> = stats.iter().map(|s| sse(s.as_ref().unwrap())).collect();
        let rise = |stats: &[Option<Stats>], own: &[f64], a: u32, b: u32| {
            let (sa, sb) = (stats[a as usize].as_ref().unwrap(), stats[b as usize].as_ref().unwrap());
            (sse(&sa.plus(sb)) - own[a as usize] - own[b as usize]).max(0.0) / (3.0 * q as f64 * sa.n.min(sb.n))
        };
        assert!(tree.merges.len() > 60, "{} merges", tree.merges.len());
        for (m, mg) in tree.merges.iter().enumerate() {
            let cheapest = edges.iter().map(|&(a, b)| rise(&stats, &own, a, b)).fold(f64::INFINITY, f64::min);
            assert!(edges.contains(&(mg.a.min(mg.b), mg.a.max(mg.b))), "merge {m} joins no adjacent pair");
            assert!(
                mg.rise <= cheapest * (1.0 + 1e-6) + 1e-15,
                "merge {m}: rise {} but a pair rises {cheapest}",
                mg.rise
            );
            let id = (tree.n_leaves + m) as u32;
            let joined = stats[mg.a as usize].as_ref().unwrap().plus(stats[mg.b as usize].as_ref().unwrap());
            own.push(sse(&joined));
            stats.push(Some(joined));
            stats[mg.a as usize] = None;
            stats[mg.b as usize] = None;
            edges = edges
                .into_iter()
                .filter(|&e| e != (mg.a.min(mg.b), mg.a.max(mg.b)))
                .map(|(a, b)| {
                    let up = |x: u32| if x == mg.a || x == mg.b { id } else { x };
                    (up(a).min(up(b)), up(a).max(up(b)))
                })
                .collect();
        }
    }

    #[test]
    fn the_yardstick_averages_three_quarters_from_400_patches_and_half_or_more_below() {
        // from 400 patches (every mesh of 2 400 vertices or more) the same merges as three quarters
        for m in [399, 400, 450, 1000] {
            assert_eq!(yardstick_merges(m), 3 * m / 4, "{m}");
        }
        // below: down to 100 nodes or half of the merges, whichever takes more
        assert_eq!(yardstick_merges(114), 57);
        assert_eq!(yardstick_merges(250), 150);
        assert_eq!(yardstick_merges(300), 200);
        assert_eq!(yardstick_merges(1), 0);
    }

    #[test]
    fn the_yardsticks_merges_join_pieces_of_one_part_on_a_small_mesh() {
        // a small mesh: fewer than 400 patches for 18 parts. Down to a quarter of the patches the merges
        // cross joints; the yardstick must average only merges within one part
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 700, poses: 10, ..Spec::default() }).unwrap();
        let tree = MergeTree::build(&g.population, 1e-14);
        let n_parts = g.part_of_vertex.iter().map(|&p| p as usize + 1).max().unwrap();
        // every node's vertex count per true part, leaves first, then one node per merge
        let mut counts: Vec<Vec<usize>> = vec![vec![0; n_parts]; tree.n_leaves];
        for (j, &l) in tree.leaves.iter().enumerate() {
            counts[l as usize][g.part_of_vertex[j] as usize] += 1;
        }
        let major = |c: &[usize]| (0..c.len()).max_by_key(|&p| c[p]).unwrap();
        let k = yardstick_merges(tree.merges.len());
        let mut crossing = 0;
        for (m, mg) in tree.merges.iter().enumerate() {
            let (a, b) = (counts[mg.a as usize].clone(), counts[mg.b as usize].clone());
            if m < k && major(&a) != major(&b) {
                crossing += 1;
            }
            counts.push(a.iter().zip(&b).map(|(x, y)| x + y).collect());
        }
        assert_eq!(crossing, 0, "{crossing} of the {k} merges the yardstick averages join two parts");
    }

    #[test]
    fn the_tree_finds_the_arm_and_ignores_pose_order() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let tree = MergeTree::build(pop, 1e-14);
        let (most, fewest) = tree.counts();
        assert!(most > 3 && fewest == 1, "{most} {fewest}");
        // every count's partition has that many parts
        for n in [1, 2, 3, most / 2, most] {
            let l = tree.labels_at(n);
            assert_eq!(l.iter().copied().collect::<std::collections::BTreeSet<u32>>().len(), n);
        }
        // the last two merges join the three bones: the 3-part cut is the arm's parts (up to the blend bands)
        let ari = crate::metrics::adjusted_rand_index(&tree.labels_at(3), &g.part_of_vertex);
        assert!(ari > 0.9, "ari {ari}");
        // the same population with its poses in reverse order gives the same tree
        let rev = super::super::robustness::Variant::Reversed.apply(pop).unwrap();
        let again = MergeTree::build(&rev, 1e-14);
        assert_eq!(again.leaves, tree.leaves);
        assert_eq!(again.labels_at(3), tree.labels_at(3));
    }

    #[test]
    fn the_cuts_give_the_fitted_labels_at_the_decided_count_only() {
        let g = generate(&Spec { preset: Preset::Arm, vertices: 600, poses: 6, ..Spec::default() }).unwrap();
        let tree = MergeTree::build(&g.population, 1e-14);
        // labels of 3 parts that are not the tree's 3-part cut (vertex 0's part grows by one vertex)
        let mut fitted = tree.labels_at(3);
        let other = fitted.iter().position(|&l| l != fitted[0]).unwrap();
        fitted[other] = fitted[0];
        assert_ne!(fitted, tree.labels_at(3));
        let cuts = TreeCuts::new(tree.clone(), Some(3), &fitted);
        assert_eq!(cuts.labels(3), fitted);
        assert_eq!(cuts.labels(2), tree.labels_at(2));
        assert_eq!(cuts.counts(), tree.counts());
        // labels of another count than the decided one are not used for it
        let cuts = TreeCuts::new(tree.clone(), Some(4), &fitted);
        assert_eq!(cuts.labels(4), tree.labels_at(4));
        assert_eq!(cuts.labels(3), tree.labels_at(3));
        assert_eq!(cuts.decided(), Some(4));
    }
}

/// One merge decision of [`merge_indistinct`]: with `parts` parts, the cheapest adjacent pair scored `score`
/// (merged when below `distinct_ratio`); `variance` is the vertex-weighted mean variance of the rigid fits of
/// the `parts` parts (unit-box units²). The last entry is the first pair that was not merged (or the count
/// reached 1): the reason the fit stopped where it did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct CurvePoint {
    pub parts: usize,
    pub score: f64,
    pub variance: f64,
    /// The pair was merged (score below `distinct_ratio`).
    pub merged: bool,
}
