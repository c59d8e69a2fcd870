//! How a fitted rig's skeleton compares with an artist's skeleton of the same character over the same clip
//! (`posemfa rig-report --truth CHARACTER.glb`).
//!
//! - **Which artist joints move.** A joint's rotation relative to its parent joint (each world rotation with its
//!   scale removed by the polar factor) is taken at every pose of the clip; the joint *moves* when two poses'
//!   relative rotations differ by at least [`MOVING_DEGREES`] (the largest angle over all pairs of poses: what
//!   the poses show, whatever the bind pose is). A root other than the main one (whose
//!   subtree is dominant on the most vertices) is measured against the main root. Joints that do
//!   not move are merged into their parents (transitively); every vertex's *artist part* is its dominant
//!   joint's (largest skin weight) merged joint. Moving joints that hold no vertex after the merge are left
//!   out (they move nothing).
//! - **Joint distances.** Every moving non-root artist joint is matched to the non-root fitted joint whose
//!   distance to it, over the poses, has the smallest median; its figures are the median and the largest of
//!   that distance over the poses, divided by `diagonal`. The converse matches every non-root fitted joint to
//!   the moving non-root artist joints alike; `fitted_to_any_artist` matches it to every artist joint but the
//!   main root that is dominant on a vertex, moving or not (a fitted joint at a knee that the clip turns 5° is
//!   where the artist put a joint). Roots are left out both ways: a fitted root's joint is its part's
//!   centroid, not a joint between two parts. Summaries: the median and the largest over the joints of their
//!   median distances, and the largest distance at any pose.
//! - **Root placement.** The fitted root part's vertices vote with their dominant artist joint; the winner,
//!   its share, its artist part, and whether that is the *central* artist part (the main root's part, or,
//!   when that holds no vertex, the shallowest part that does, the larger on a tie).
//! - **Parents.** A matched artist joint agrees when the fitted parent of its match is the match of its artist
//!   parent part (the joint its parent merged into; the central part's match is the fitted part that holds
//!   most of its vertices).
//! - **Parts against the skeleton.** The adjusted Rand index of the fitted labels against the artist parts
//!   (vertices without weights one more label).

use super::rig::Rig;
use super::Articulation;
use crate::error::{Error, Result};
use crate::geometry::{norm, sub, Mat3, Vec3};
use serde::Serialize;

/// The least turn (degrees, over the clip, relative to the parent) of a joint that moves, to within
/// [`TURN_ROUNDING`].
pub const MOVING_DEGREES: f64 = 10.0;

/// How far a turn read from a file's f32 rotations can fall short of the turn its animator keyed (degrees): a
/// quaternion component carries an error of about 6e-8, a few millionths of a degree once composed; the Minetest
/// player's head, keyed to turn 10°, reads 9.999997°.
pub const TURN_ROUNDING: f64 = 1e-3;

/// An artist's skeleton over a clip, in the poses' own units.
#[derive(Debug, Clone)]
pub struct ArtistSkeleton {
    pub names: Vec<String>,
    /// Every joint's parent joint (None for a root).
    pub parent: Vec<Option<usize>>,
    /// Per pose, every joint's world rotation (scale removed).
    pub rotations: Vec<Vec<Mat3>>,
    /// Per pose, every joint's world position.
    pub positions: Vec<Vec<Vec3>>,
    /// Per vertex, its dominant joint (largest weight; None for a vertex without weights).
    pub dominant: Vec<Option<usize>>,
}

/// A fitted skeleton over the same clip: joints, their parents, per pose their positions, and every vertex's
/// joint (its part).
#[derive(Debug, Clone)]
pub struct FittedSkeleton {
    pub names: Vec<String>,
    pub parent: Vec<Option<usize>>,
    pub positions: Vec<Vec<Vec3>>,
    pub labels: Vec<usize>,
}

impl ArtistSkeleton {
    /// From a glTF skin read with its poses ([`crate::mesh::gltf::read_with_skin`]).
    pub fn from_skin(file: &str, skin: &crate::mesh::gltf::SkinTrack) -> Result<ArtistSkeleton> {
        let n = skin.names.len();
        let bad = |what: String| Error::Data(format!("{file}: {what}"));
        if n == 0 {
            return Err(bad("the skin has no joints".into()));
        }
        let mut rotations = Vec::with_capacity(skin.world.len());
        let mut positions = Vec::with_capacity(skin.world.len());
        for (i, pose) in skin.world.iter().enumerate() {
            if pose.len() != n {
                return Err(bad(format!("pose {} has {} joint transforms for {n} joints", i + 1, pose.len())));
            }
            if pose.iter().flatten().any(|x| !x.is_finite()) {
                return Err(bad(format!("a joint's transform at pose {} is not finite", i + 1)));
            }
            // column-major 4x4: linear part m[c * 4 + r], translation m[12..15]
            rotations.push(
                pose.iter()
                    .map(|m| {
                        let a = Mat3::from_fn(|r, c| m[c * 4 + r]);
                        crate::geometry::procrustes::best_rotation(&a)
                    })
                    .collect(),
            );
            positions.push(pose.iter().map(|m| [m[12], m[13], m[14]]).collect());
        }
        let dominant = skin
            .influences
            .iter()
            .map(|infl| {
                infl.iter()
                    .filter(|(j, w)| *j < n && *w > 0.0)
                    .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
                    .map(|&(j, _)| j)
            })
            .collect();
        let s =
            ArtistSkeleton { names: skin.names.clone(), parent: skin.parent.clone(), rotations, positions, dominant };
        s.check()?;
        Ok(s)
    }

    fn check(&self) -> Result<()> {
        let n = self.names.len();
        if self.parent.len() != n || self.rotations.iter().any(|p| p.len() != n) {
            return Err(Error::Data("artist skeleton: every joint needs a parent entry and a rotation".into()));
        }
        if self.positions.len() != self.rotations.len() || self.positions.iter().any(|p| p.len() != n) {
            return Err(Error::Data("artist skeleton: every pose needs a position per joint".into()));
        }
        if let Some(j) = self.parent.iter().flatten().find(|&&p| p >= n) {
            return Err(Error::Data(format!("artist skeleton: parent {j} is not a joint ({n} joints)")));
        }
        if let Some(j) = self.dominant.iter().flatten().find(|&&j| j >= n) {
            return Err(Error::Data(format!("artist skeleton: a vertex's joint {j} is not a joint ({n} joints)")));
        }
        if self.order().len() != n {
            return Err(Error::Data("artist skeleton: the joints' parents make a cycle".into()));
        }
        Ok(())
    }

    /// Joints, parents before their children.
    fn order(&self) -> Vec<usize> {
        let n = self.names.len();
        let mut order: Vec<usize> = (0..n).filter(|&j| self.parent[j].is_none()).collect();
        let mut at = 0;
        while at < order.len() {
            let p = order[at];
            order.extend((0..n).filter(|&c| self.parent[c] == Some(p)));
            at += 1;
        }
        order
    }

    /// The main root: of the joints without a parent, the one whose subtree is dominant on the most vertices
    /// (the first on a tie).
    pub fn main_root(&self) -> Option<usize> {
        let mut below = vec![0usize; self.names.len()];
        for j in self.dominant.iter().flatten() {
            below[*j] += 1;
        }
        for &j in self.order().iter().rev() {
            if let Some(p) = self.parent[j] {
                below[p] += below[j];
            }
        }
        (0..self.names.len()).filter(|&j| self.parent[j].is_none()).max_by_key(|&j| (below[j], std::cmp::Reverse(j)))
    }

    /// The joint each joint's turn is measured against: its parent; another root, the main root.
    fn reference(&self, j: usize, main: Option<usize>) -> Option<usize> {
        self.parent[j].or(main.filter(|&r| r != j))
    }

    /// How far each joint turns over the clip against its reference joint, degrees: the largest angle between
    /// two poses' relative rotations (None for the main root).
    pub fn turns(&self) -> Vec<Option<f64>> {
        let main = self.main_root();
        (0..self.names.len())
            .map(|j| {
                let p = self.reference(j, main)?;
                let rel: Vec<Mat3> = self.rotations.iter().map(|r| r[p].transpose() * r[j]).collect();
                let mut worst: f64 = 0.0;
                for (a, ra) in rel.iter().enumerate() {
                    for rb in &rel[a + 1..] {
                        worst = worst.max(crate::geometry::rotation::angle_between(ra, rb));
                    }
                }
                Some(worst.to_degrees())
            })
            .collect()
    }

    /// Every joint's merge target: itself when it moves (or is the main root), else its reference joint's.
    pub fn merged(&self, turns: &[Option<f64>]) -> Vec<usize> {
        let mut kept: Vec<usize> = (0..self.names.len()).collect();
        let main = self.main_root();
        // references before the joints measured against them: the main root, then parents before children
        let mut order = self.order();
        if let Some(r) = main {
            order.retain(|&j| j != r);
            order.insert(0, r);
        }
        for j in order {
            match (self.reference(j, main), turns[j]) {
                (Some(p), Some(t)) if t < MOVING_DEGREES - TURN_ROUNDING => kept[j] = kept[p],
                _ => {}
            }
        }
        kept
    }
}

impl FittedSkeleton {
    /// The rig's skeleton: one joint per part in the tree, at its bone's joint point carried by the bone in
    /// every training pose (where the .glb's joint nodes are), in the poses' original units; the fit's labels.
    pub fn of_rig(art: &Articulation, rig: &Rig) -> FittedSkeleton {
        let n = rig.tree.parent.len();
        let positions = rig
            .bones
            .iter()
            .map(|pose| {
                let local: Vec<Vec3> = (0..n).map(|k| pose[k].apply(rig.joint_points[k])).collect();
                art.to_original(&local)
            })
            .collect();
        FittedSkeleton {
            names: (0..n).map(|k| format!("part {}", k + 1)).collect(),
            parent: rig.tree.parent.clone(),
            positions,
            labels: art.model.labels.iter().map(|&l| l as usize).collect(),
        }
    }

    /// The same joints with the tree rooted at part `r`: the parent relations on the path from `r` to the root
    /// reversed, each contact on it now the joint of the part that became the child (the same point), `r`'s
    /// own joint dropped (a root has none).
    pub fn rerooted(&self, r: usize) -> FittedSkeleton {
        let mut out = self.clone();
        if r >= self.names.len() {
            return out;
        }
        out.parent[r] = None;
        let (mut child, mut at) = (r, self.parent[r]);
        while let Some(p) = at {
            at = self.parent[p];
            out.parent[p] = Some(child);
            for (o, s) in out.positions.iter_mut().zip(&self.positions) {
                o[p] = s[child];
            }
            child = p;
        }
        out
    }

    fn root(&self) -> Option<usize> {
        // the root of the tree: a joint without parent that holds vertices
        let mut held = vec![0usize; self.names.len()];
        for &l in &self.labels {
            if let Some(h) = held.get_mut(l) {
                *h += 1;
            }
        }
        (0..self.names.len()).filter(|&k| self.parent[k].is_none()).max_by_key(|&k| (held[k], std::cmp::Reverse(k)))
    }
}

/// The artist's skeleton of a rigged, animated glTF file whose clip is `pop` (read with the same `options`):
/// refused, naming the file, when it has no skin animating the mesh or when its poses are not `pop`'s (vertex
/// and pose counts, and every vertex of the first pose within 1e-6 of the diagonal).
pub fn read_artist(
    file: &str,
    bytes: &[u8],
    resources: &[(&str, &[u8])],
    options: &crate::mesh::gltf::Options,
    pop: &crate::mesh::Population,
) -> Result<ArtistSkeleton> {
    let (g, skin) = crate::mesh::gltf::read_with_skin(file, bytes, resources, options)?;
    let skin = skin.ok_or_else(|| {
        Error::Data(format!(
            "{file}: the poses read are not a skin's animation (no skinned mesh, or morph targets read): the \
             truth must be a rigged, animated character"
        ))
    })?;
    if g.poses.len() != pop.n_shapes() || skin.influences.len() != pop.n_vertices() {
        return Err(Error::Data(format!(
            "{file}: its clip is {} poses of {} vertices, the poses measured {} of {}: give the truth the same \
             file (and --animation / --frames) the poses were read from",
            g.poses.len(),
            skin.influences.len(),
            pop.n_shapes(),
            pop.n_vertices()
        )));
    }
    let first: Vec<Vec3> = pop.shape(0).iter().map(|u| pop.normalization.to_original(u)).collect();
    let d = crate::export::rig_report::bbox_diagonal(&first);
    if let Some(v) = g.poses[0].1.positions.iter().zip(&first).position(|(p, q)| norm(sub(*p, *q)) > 1e-6 * d) {
        return Err(Error::Data(format!(
            "{file}: vertex {v} of its first pose is not where the poses measured have it: the truth must be \
             the file the poses were read from"
        )));
    }
    ArtistSkeleton::from_skin(file, &skin)
}

/// The rig's skeleton ([`FittedSkeleton::of_rig`]) against `artist` over the training poses, distances divided
/// by the diagonal of the bind pose's bounding box (the rig's E_RMS unit).
pub fn against_rig(artist: &ArtistSkeleton, art: &Articulation, rig: &Rig, bind: usize) -> Result<SkeletonMatch> {
    let pop = &art.population;
    if bind >= pop.n_shapes() {
        return Err(Error::Request(format!("bind pose {bind} (0-based): the population has {} poses", pop.n_shapes())));
    }
    let rest: Vec<Vec3> = pop.shape(bind).iter().map(|u| pop.normalization.to_original(u)).collect();
    compare(artist, &FittedSkeleton::of_rig(art, rig), crate::export::rig_report::bbox_diagonal(&rest))
}

/// One joint's distance to its match, fractions of the diagonal.
#[derive(Debug, Clone, Serialize)]
pub struct JointDistance {
    pub joint: String,
    /// The nearest joint of the other skeleton (smallest median distance over the poses).
    pub nearest: String,
    pub median: f64,
    pub max: f64,
    /// Artist joints: how far it turns over the clip against its parent (degrees).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turn_degrees: Option<f64>,
}

/// Joint distances one way, fractions of the diagonal (None when either side has no joint).
#[derive(Debug, Clone, Serialize)]
pub struct Distances {
    /// Median over the joints of their median distance over the poses.
    pub median: Option<f64>,
    /// Largest over the joints of their median distance over the poses.
    pub max: Option<f64>,
    /// Largest distance of a joint to its match at any pose.
    pub max_any_pose: Option<f64>,
    pub joints: Vec<JointDistance>,
}

/// Where the fitted root is, in the artist's skeleton.
#[derive(Debug, Clone, Serialize)]
pub struct RootPlacement {
    pub fitted_root: String,
    /// The artist joint that is dominant on most of the root part's vertices, and their share.
    pub artist_joint: String,
    pub share: f64,
    /// That joint's artist part (the moving joint it merges into).
    pub artist_part: String,
    /// The artist's central part (its root's part, or the shallowest part holding vertices).
    pub central_part: String,
    pub on_central_part: bool,
}

/// Whether matched joints have the artist's parents.
#[derive(Debug, Clone, Serialize)]
pub struct ParentAgreement {
    pub matched: usize,
    pub agreeing: usize,
    /// agreeing / matched (None without matched joints).
    pub share: Option<f64>,
    /// The artist joints whose match's parent is not their parent's match: (joint, its parent part, the fitted
    /// parent found, the fitted joint expected).
    pub disagreeing: Vec<[String; 4]>,
}

/// One artist joint as measured.
#[derive(Debug, Clone, Serialize)]
pub struct ArtistJoint {
    pub name: String,
    pub parent: Option<String>,
    /// How far it turns over the clip against its parent (None for the main root), degrees.
    pub turn_degrees: Option<f64>,
    /// The joint it merges into (itself when it moves).
    pub part: String,
    /// Vertices whose dominant joint it is.
    pub vertices: usize,
}

/// What the figures would be with the fitted tree rooted on the artist's central part.
#[derive(Debug, Clone, Serialize)]
pub struct Rerooted {
    /// The fitted part that holds most of the central part's vertices.
    pub root: String,
    pub parents: ParentAgreement,
    pub artist_to_fitted_median: Option<f64>,
    pub fitted_to_artist_median: Option<f64>,
}

/// The fitted skeleton against the artist's ([`compare`]).
#[derive(Debug, Clone, Serialize)]
pub struct SkeletonMatch {
    pub rule: String,
    pub diagonal: f64,
    pub artist_joints: usize,
    pub moving_joints: usize,
    pub artist_parts: usize,
    pub fitted_joints: usize,
    pub artist_to_fitted: Distances,
    pub fitted_to_artist: Distances,
    /// The converse against every non-root artist joint that is dominant on at least one vertex, whether the
    /// clip turns it [`MOVING_DEGREES`] or not: a fitted joint at an artist joint that this clip turns a few
    /// degrees (Mr. Fixit's knees in his idle clip) is where the artist put a joint.
    pub fitted_to_any_artist: Distances,
    pub root: RootPlacement,
    pub parents: ParentAgreement,
    /// Adjusted Rand index of the fitted labels against the artist parts.
    pub parts_ari: f64,
    /// Every artist joint, in the skin's order.
    pub artist: Vec<ArtistJoint>,
    /// When the fitted root is not on the central part: the same measure with the fitted tree rooted there
    /// ([`FittedSkeleton::rerooted`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rooted_at_central: Option<Rerooted>,
}

fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 { v[m] } else { 0.5 * (v[m - 1] + v[m]) })
}

/// Every `from` joint to its nearest `to` joint over the poses (see the module doc).
fn nearest(
    from: &[usize],
    from_pos: &[Vec<Vec3>],
    to: &[usize],
    to_pos: &[Vec<Vec3>],
    diagonal: f64,
) -> Vec<(usize, usize, f64, f64)> {
    let mut out = Vec::with_capacity(from.len());
    let mut d = Vec::with_capacity(from_pos.len());
    for &a in from {
        let mut best: Option<(usize, f64, f64)> = None;
        for &b in to {
            d.clear();
            d.extend(from_pos.iter().zip(to_pos).map(|(p, q)| norm(sub(p[a], q[b])) / diagonal));
            let worst = d.iter().copied().fold(0.0, f64::max);
            let m = median(&mut d).unwrap_or(f64::INFINITY);
            if best.is_none_or(|(_, bm, _)| m < bm) {
                best = Some((b, m, worst));
            }
        }
        if let Some((b, m, worst)) = best {
            out.push((a, b, m, worst));
        }
    }
    out
}

fn summary(
    pairs: &[(usize, usize, f64, f64)],
    name_a: &[String],
    name_b: &[String],
    turns: Option<&[Option<f64>]>,
) -> Distances {
    let mut medians: Vec<f64> = pairs.iter().map(|p| p.2).collect();
    Distances {
        median: median(&mut medians),
        max: pairs.iter().map(|p| p.2).reduce(f64::max),
        max_any_pose: pairs.iter().map(|p| p.3).reduce(f64::max),
        joints: pairs
            .iter()
            .map(|&(a, b, m, w)| JointDistance {
                joint: name_a[a].clone(),
                nearest: name_b[b].clone(),
                median: m,
                max: w,
                turn_degrees: turns.and_then(|t| t[a]),
            })
            .collect(),
    }
}

/// Compares `fitted` with `artist` over the same poses (see the module doc); distances divided by `diagonal`.
pub fn compare(artist: &ArtistSkeleton, fitted: &FittedSkeleton, diagonal: f64) -> Result<SkeletonMatch> {
    let mut m = compare_rooted(artist, fitted, diagonal)?;
    if !m.result.root.on_central_part {
        if let Some(r) = m.central_match {
            let again = compare_rooted(artist, &fitted.rerooted(r), diagonal)?;
            m.result.rooted_at_central = Some(Rerooted {
                root: fitted.names[r].clone(),
                parents: again.result.parents,
                artist_to_fitted_median: again.result.artist_to_fitted.median,
                fitted_to_artist_median: again.result.fitted_to_artist.median,
            });
        }
    }
    Ok(m.result)
}

struct Rooted {
    result: SkeletonMatch,
    /// The fitted part that holds most of the central part's vertices.
    central_match: Option<usize>,
}

fn compare_rooted(artist: &ArtistSkeleton, fitted: &FittedSkeleton, diagonal: f64) -> Result<Rooted> {
    artist.check()?;
    let n_poses = artist.positions.len();
    let n_vertices = artist.dominant.len();
    if n_poses == 0 {
        return Err(Error::Data("the artist's clip has no pose".into()));
    }
    if fitted.positions.len() != n_poses {
        return Err(Error::Data(format!(
            "the artist's clip has {n_poses} poses, the fitted rig {}: they must be the same poses",
            fitted.positions.len()
        )));
    }
    if fitted.labels.len() != n_vertices {
        return Err(Error::Data(format!(
            "the artist's skin weights {n_vertices} vertices, the fit labels {}: they must be the same mesh",
            fitted.labels.len()
        )));
    }
    let nf = fitted.names.len();
    if fitted.parent.len() != nf
        || fitted.positions.iter().any(|p| p.len() != nf)
        || fitted.labels.iter().any(|&l| l >= nf)
        || fitted.parent.iter().flatten().any(|&p| p >= nf)
    {
        return Err(Error::Data("fitted skeleton: parents, positions or labels do not fit its joints".into()));
    }
    if !(diagonal > 0.0 && diagonal.is_finite()) {
        return Err(Error::Data(format!("the bounding-box diagonal is {diagonal}: the poses have no extent")));
    }
    let na = artist.names.len();
    let turns = artist.turns();
    let kept = artist.merged(&turns);
    // artist parts: each vertex's dominant joint, merged; vertices without weights one more label
    let part_of: Vec<Option<usize>> = artist.dominant.iter().map(|d| d.map(|j| kept[j])).collect();
    let mut held = vec![0usize; na];
    for p in part_of.iter().flatten() {
        held[*p] += 1;
    }
    let main_root = artist.main_root();
    let moving: Vec<usize> =
        (0..na).filter(|&j| kept[j] == j && held[j] > 0 && Some(j) != main_root && turns[j].is_some()).collect();
    let fitted_joints: Vec<usize> = {
        let mut in_tree = vec![false; nf];
        for &l in &fitted.labels {
            in_tree[l] = true;
        }
        (0..nf).filter(|&k| fitted.parent[k].is_some() && in_tree[k]).collect()
    };
    let forward = nearest(&moving, &artist.positions, &fitted_joints, &fitted.positions, diagonal);
    let backward = nearest(&fitted_joints, &fitted.positions, &moving, &artist.positions, diagonal);
    let holding: Vec<usize> = {
        let mut own = vec![false; na];
        for j in artist.dominant.iter().flatten() {
            own[*j] = true;
        }
        (0..na).filter(|&j| own[j] && Some(j) != main_root).collect()
    };
    let backward_any = nearest(&fitted_joints, &fitted.positions, &holding, &artist.positions, diagonal);

    // the central artist part: the main root's, else the shallowest part holding vertices (larger on a tie)
    let depth = {
        let mut d = vec![0usize; na];
        for j in artist.order() {
            if let Some(p) = artist.parent[j] {
                d[j] = d[p] + 1;
            }
        }
        d
    };
    let central = match main_root.map(|r| kept[r]).filter(|&r| held[r] > 0) {
        Some(r) => r,
        None => (0..na)
            .filter(|&j| held[j] > 0)
            .min_by_key(|&j| (depth[j], std::cmp::Reverse(held[j]), j))
            .ok_or_else(|| Error::Data("no vertex has a skin weight: the skin gives no parts".into()))?,
    };
    // the fitted root's region
    let root = fitted.root().ok_or_else(|| Error::Data("the fitted skeleton has no root".into()))?;
    let mut votes = vec![0usize; na];
    let mut root_size = 0usize;
    for (v, &l) in fitted.labels.iter().enumerate() {
        if l == root {
            root_size += 1;
            if let Some(j) = artist.dominant[v] {
                votes[j] += 1;
            }
        }
    }
    let winner = (0..na).max_by_key(|&j| (votes[j], std::cmp::Reverse(j))).unwrap_or(0);
    let root_placement = RootPlacement {
        fitted_root: fitted.names[root].clone(),
        artist_joint: artist.names[winner].clone(),
        share: if root_size > 0 { votes[winner] as f64 / root_size as f64 } else { 0.0 },
        artist_part: artist.names[kept[winner]].clone(),
        central_part: artist.names[central].clone(),
        on_central_part: kept[winner] == central,
    };

    // parents: the match of every artist part (moving joints by position, the central part by overlap)
    let mut matched: Vec<Option<usize>> = vec![None; na];
    for &(a, b, _, _) in &forward {
        matched[a] = Some(b);
    }
    let mut overlap = vec![0usize; nf];
    for (v, &l) in fitted.labels.iter().enumerate() {
        if part_of[v] == Some(central) {
            overlap[l] += 1;
        }
    }
    let central_match = (0..nf).filter(|&k| overlap[k] > 0).max_by_key(|&k| (overlap[k], std::cmp::Reverse(k)));
    if matched[central].is_none() {
        matched[central] = central_match;
    }
    let mut agreement = ParentAgreement { matched: 0, agreeing: 0, share: None, disagreeing: Vec::new() };
    for &(a, b, _, _) in &forward {
        // (a parent part that holds no vertex, e.g. a root above the hips, has no match to compare)
        let Some(p) = artist.reference(a, main_root).map(|p| kept[p]).filter(|&p| held[p] > 0) else { continue };
        agreement.matched += 1;
        let expected = matched[p];
        if expected.is_some() && fitted.parent[b] == expected {
            agreement.agreeing += 1;
        } else {
            let name = |k: Option<usize>| k.map_or("none".to_string(), |k| fitted.names[k].clone());
            agreement.disagreeing.push([
                artist.names[a].clone(),
                artist.names[p].clone(),
                name(fitted.parent[b]),
                name(expected),
            ]);
        }
    }
    if agreement.matched > 0 {
        agreement.share = Some(agreement.agreeing as f64 / agreement.matched as f64);
    }

    let truth: Vec<u32> = part_of.iter().map(|p| p.map_or(na as u32, |j| j as u32)).collect();
    let labels: Vec<u32> = fitted.labels.iter().map(|&l| l as u32).collect();
    let result = SkeletonMatch {
        rule: format!(
            "artist joints that turn at least {MOVING_DEGREES} degrees against their parent between two poses move; \
             the others are merged into their parents; distances to the nearest joint of the other skeleton \
             (smallest median over the poses), roots left out, as fractions of the diagonal"
        ),
        diagonal,
        artist_joints: na,
        moving_joints: moving.len(),
        artist_parts: (0..na).filter(|&j| held[j] > 0).count(),
        fitted_joints: fitted_joints.len(),
        artist_to_fitted: summary(&forward, &artist.names, &fitted.names, Some(&turns)),
        fitted_to_artist: summary(&backward, &fitted.names, &artist.names, None),
        fitted_to_any_artist: summary(&backward_any, &fitted.names, &artist.names, None),
        root: root_placement,
        parents: agreement,
        parts_ari: crate::metrics::adjusted_rand_index(&labels, &truth),
        artist: (0..na)
            .map(|j| ArtistJoint {
                name: artist.names[j].clone(),
                parent: artist.parent[j].map(|p| artist.names[p].clone()),
                turn_degrees: turns[j],
                part: artist.names[kept[j]].clone(),
                vertices: artist.dominant.iter().filter(|&&d| d == Some(j)).count(),
            })
            .collect(),
        rooted_at_central: None,
    };
    Ok(Rooted { result, central_match })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation::axis_angle;
    use crate::geometry::{add, mat_vec, scale};
    use rand::{Rng, SeedableRng};

    /// A chain of `bends.len()` segments of length 1 along x from the origin, 10 vertices per segment, joint k at
    /// the start of segment k; segment k (k >= 1) bends about z by `bends[k] * sin(phase)` relative to k - 1.
    /// Vertices are rigid on their segment (dominant joint = segment).
    fn chain(bends: &[f64], poses: usize) -> ArtistSkeleton {
        let n = bends.len();
        let (mut rotations, mut positions) = (Vec::new(), Vec::new());
        for i in 0..poses {
            let phase = (i as f64 + 0.5) / poses as f64 * std::f64::consts::TAU;
            let (mut r, mut at) = (Mat3::identity(), [0.0; 3]);
            let (mut rs, mut ps) = (Vec::new(), Vec::new());
            for k in 0..n {
                if k > 0 {
                    at = add(at, mat_vec(&r, [1.0, 0.0, 0.0]));
                    r = r * axis_angle([0.0, 0.0, 1.0], bends[k].to_radians() * phase.sin());
                }
                rs.push(r);
                ps.push(at);
            }
            rotations.push(rs);
            positions.push(ps);
        }
        ArtistSkeleton {
            names: (0..n).map(|k| format!("bone{k}")).collect(),
            parent: (0..n).map(|k| k.checked_sub(1)).collect(),
            rotations,
            positions,
            dominant: (0..n * 10).map(|v| Some(v / 10)).collect(),
        }
    }

    /// The artist's own skeleton as a fit: its joints, parents and dominant joints.
    fn same(a: &ArtistSkeleton) -> FittedSkeleton {
        FittedSkeleton {
            names: (0..a.names.len()).map(|k| format!("part {}", k + 1)).collect(),
            parent: a.parent.clone(),
            positions: a.positions.clone(),
            labels: a.dominant.iter().map(|d| d.unwrap()).collect(),
        }
    }

    #[test]
    fn turns_are_the_largest_angle_between_poses_and_still_joints_merge() {
        // sin over a whole period reaches ±(1 - small): the turn is about 2 x the bend
        let a = chain(&[0.0, 30.0, 4.0, 20.0], 40);
        let t = a.turns();
        assert_eq!(t[0], None);
        for (k, bend) in [(1, 30.0), (2, 4.0), (3, 20.0)] {
            let got = t[k].unwrap();
            assert!((got - 2.0 * bend).abs() < 0.01 * bend, "joint {k}: {got} for a ±{bend} bend");
        }
        // joint 2 turns 8 degrees: merged into joint 1; joint 3 keeps its own part
        assert_eq!(a.merged(&t), vec![0, 1, 1, 3]);
        let m = compare(&a, &same(&a), 4.0).unwrap();
        assert_eq!((m.artist_joints, m.moving_joints, m.artist_parts), (4, 2, 3));
        // the fitted joint at the still joint 2 is one segment (1 / 4 of the diagonal) from the moving ones, and
        // on an artist joint that holds vertices
        assert!((m.fitted_to_artist.max.unwrap() - 0.25).abs() < 1e-9, "{:?}", m.fitted_to_artist.max);
        assert_eq!(m.fitted_to_any_artist.max, Some(0.0));
        assert_eq!(m.fitted_to_any_artist.joints.len(), 3);
    }

    #[test]
    fn a_second_root_turns_against_the_main_root() {
        // bone 2 made a root: its subtree (bones 2-4, 30 vertices) outweighs bone 0's (20), so it is the main
        // root and bone 0 turns against it by bend 1 + bend 2
        let mut a = chain(&[0.0, 20.0, 15.0, 30.0, 25.0], 40);
        a.parent[2] = None;
        assert_eq!(a.main_root(), Some(2));
        let t = a.turns();
        assert_eq!(t[2], None);
        assert!((t[0].unwrap() - 70.0).abs() < 0.7, "{:?}", t[0]);
        assert!((t[1].unwrap() - 40.0).abs() < 0.4, "{:?}", t[1]);
        let m = compare(&a, &same(&a), 5.0).unwrap();
        assert_eq!(m.root.central_part, "bone2");
    }

    #[test]
    fn the_artists_own_skeleton_matches_itself() {
        let a = chain(&[0.0, 40.0, 35.0, 50.0, 25.0], 24);
        let m = compare(&a, &same(&a), 5.0).unwrap();
        assert_eq!(m.artist_to_fitted.median, Some(0.0));
        assert_eq!(m.fitted_to_artist.max_any_pose, Some(0.0));
        assert_eq!(m.parents.share, Some(1.0));
        assert_eq!(m.parents.matched, 4);
        assert!(m.root.on_central_part && m.root.share == 1.0 && m.root.artist_joint == "bone0");
        assert_eq!(m.parts_ari, 1.0);
        let names: Vec<&str> = m.artist_to_fitted.joints.iter().map(|j| j.nearest.as_str()).collect();
        assert_eq!(names, ["part 2", "part 3", "part 4", "part 5"]);
    }

    /// Property: fitted joints moved by known offsets (each joint its own, below half a segment so the match
    /// cannot change) give exactly those distances, the median and largest over the joints, both ways;
    /// renumbering the fitted joints changes nothing but the names.
    #[test]
    fn known_offsets_give_known_distances_whatever_the_numbering() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        for case in 0..20 {
            let n = rng.gen_range(3..8);
            let bends: Vec<f64> = (0..n).map(|k| if k == 0 { 0.0 } else { rng.gen_range(15.0..60.0) }).collect();
            let a = chain(&bends, rng.gen_range(5..30));
            let diagonal = rng.gen_range(1.0..10.0);
            let offsets: Vec<f64> = (0..n).map(|_| rng.gen_range(0.0..0.4)).collect();
            let mut f = same(&a);
            for pose in f.positions.iter_mut() {
                for (k, p) in pose.iter_mut().enumerate() {
                    *p = add(*p, scale([0.0, 1.0, 0.0], offsets[k]));
                }
            }
            // renumber: fitted joint k becomes perm[k]
            let mut perm: Vec<usize> = (0..n).collect();
            for i in (1..n).rev() {
                perm.swap(i, rng.gen_range(0..=i));
            }
            let mut g = f.clone();
            for k in 0..n {
                g.names[perm[k]] = f.names[k].clone();
                g.parent[perm[k]] = f.parent[k].map(|p| perm[p]);
                for (gp, fp) in g.positions.iter_mut().zip(&f.positions) {
                    gp[perm[k]] = fp[k];
                }
            }
            g.labels = f.labels.iter().map(|&l| perm[l]).collect();
            let m = compare(&a, &g, diagonal).unwrap();
            let mut want: Vec<f64> = offsets[1..].iter().map(|o| o / diagonal).collect();
            want.sort_by(f64::total_cmp);
            let close = |x: Option<f64>, y: f64| (x.unwrap() - y).abs() < 1e-12;
            let med = median(&mut want.clone()).unwrap();
            for d in [&m.artist_to_fitted, &m.fitted_to_artist] {
                assert!(close(d.median, med), "case {case}: {:?} vs {med}", d.median);
                assert!(close(d.max, *want.last().unwrap()), "case {case}");
                assert!(close(d.max_any_pose, *want.last().unwrap()), "case {case}");
            }
            for j in &m.artist_to_fitted.joints {
                let k: usize = j.joint.trim_start_matches("bone").parse().unwrap();
                assert_eq!(j.nearest, format!("part {}", k + 1), "case {case}");
            }
            assert_eq!(m.parents.share, Some(1.0), "case {case}");
            assert_eq!(m.parts_ari, 1.0);
        }
    }

    #[test]
    fn a_root_at_the_end_and_wrong_parents_are_reported() {
        // the fitted tree rooted at the chain's last segment: every parent reversed
        let a = chain(&[0.0, 40.0, 35.0, 50.0], 20);
        let mut f = same(&a);
        // part k's joint is where it meets its new parent k + 1: the artist joint k + 1
        f.parent = vec![Some(1), Some(2), Some(3), None];
        for pose in f.positions.iter_mut() {
            let old = pose.clone();
            for k in 0..3 {
                pose[k] = old[k + 1];
            }
            pose[3] = add(old[3], [0.5, 0.0, 0.0]);
        }
        let m = compare(&a, &f, 4.0).unwrap();
        assert_eq!(m.root.fitted_root, "part 4");
        assert_eq!(m.root.artist_joint, "bone3");
        assert!(!m.root.on_central_part);
        assert_eq!(m.root.central_part, "bone0");
        // the joints sit where the artist's are (bone k at part k - 1's joint), but no parent agrees
        assert_eq!(m.artist_to_fitted.max, Some(0.0));
        assert_eq!(m.parents.share, Some(0.0));
        assert_eq!(m.parents.disagreeing.len(), 3);
        assert_eq!(m.parts_ari, 1.0);
        // rooted at the part on the artist's root the tree is the artist's again
        let r = m.rooted_at_central.expect("the root is off the central part");
        assert_eq!(r.root, "part 1");
        assert_eq!(
            (r.parents.share, r.artist_to_fitted_median, r.fitted_to_artist_median),
            (Some(1.0), Some(0.0), Some(0.0))
        );
        // and a tree already rooted there is not measured again
        assert!(compare(&a, &same(&a), 4.0).unwrap().rooted_at_central.is_none());
    }

    #[test]
    fn parts_are_scored_against_the_merged_skeleton() {
        // joint 2 barely turns: the artist has 3 parts; a fit that splits segment 2 off scores below 1, one that
        // keeps it with segment 1 scores 1
        let a = chain(&[0.0, 40.0, 3.0, 50.0], 20);
        let mut f = same(&a);
        let split = compare(&a, &f, 4.0).unwrap();
        assert!(split.parts_ari < 1.0, "{}", split.parts_ari);
        for l in f.labels.iter_mut() {
            if *l == 2 {
                *l = 1;
            }
        }
        f.parent[3] = Some(1);
        let merged = compare(&a, &f, 4.0).unwrap();
        assert_eq!(merged.parts_ari, 1.0);
        assert_eq!(merged.fitted_joints, 2);
    }

    #[test]
    fn mismatched_inputs_are_refused_with_what_differs() {
        let a = chain(&[0.0, 40.0, 30.0], 10);
        let mut f = same(&a);
        f.positions.pop();
        let e = compare(&a, &f, 1.0).unwrap_err().to_string();
        assert!(e.contains("10 poses") && e.contains("9"), "{e}");
        let mut f = same(&a);
        f.labels.pop();
        let e = compare(&a, &f, 1.0).unwrap_err().to_string();
        assert!(e.contains("30 vertices"), "{e}");
        let e = compare(&a, &same(&a), 0.0).unwrap_err().to_string();
        assert!(e.contains("diagonal"), "{e}");
        let mut b = a.clone();
        b.parent = vec![Some(2), Some(0), Some(1)];
        assert!(compare(&b, &same(&a), 1.0).unwrap_err().to_string().contains("cycle"));
    }
}
