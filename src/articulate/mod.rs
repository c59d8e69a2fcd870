//! Turning a fit into an articulated model: part graph, joints, pose interpolation (Algorithm 2 with the
//! corrections of docs/method.md, items 4, 9 and 10), skinning weights, a skeleton.
//!
//! - [`graph`]: part adjacency from mesh edges, contact triangles, the part tree (strongest-contact or BFS).
//! - [`joints`]: J_pc per training shape and its latent image in each part (eq 23 through Λ).
//! - [`interpolate`]: per-part rigid motions at t (shorter-arc slerp, joint constraint with blended training
//!   offsets so both ends are exact), vertex positions (eq 22/24 rigid, or skinned), keyframe sequences.
//! - [`skin`]: rigid and smooth per-vertex weights, linear and dual-quaternion blending.
//! - [`rig`]: a skinned rig for glTF: rigid, smooth or fitted (SSDR) weights, free or fixed joints.
//! - [`pose`]: new frames onto a finished rig, poses of one's own, the space of poses the population spans.
//! - [`report`]: the figures that check all this on a population (endpoint errors, volume, edge stretch).
//!
//! Everything is in unit-box coordinates, like [`Model`]; [`Articulation::to_original`] converts back.
//!
//! # Choices
//! - **Root** ([`RootRule`]): the default [`RootRule::Anchor`] is the part with the largest surface area
//!   (area of the triangles, each shared equally among its three vertices' parts, averaged over the training
//!   shapes). On an animal that is the trunk: the body then moves on a straight line and every limb swings
//!   from it, whatever the two poses are. The paper's rule ([`RootRule::Paper`], smallest rotation between
//!   the two poses) changes with the pair of poses and often picks a small leg piece, so the whole body
//!   swings about a hoof (docs/method.md, item 9). Both give exact ends with [`Options::exact_ends`].
//! - **Exact ends** ([`Options::exact_ends`], default on): the joint mismatch of each training shape
//!   ([`joints::Joint::offset`]) is blended in t, and the root's centroid (not its b, which depends on the
//!   arbitrary latent origin) moves on a straight line. Off: Algorithm 2 as printed (b_root linear, the child
//!   pinned at the joint), which misses its own end poses (item 9).
//! - **Residual** ([`Options::residual`], default on): eq 24's ε_k^t. With it both ends are the training
//!   shapes; without it, their rigid reconstructions (eq 22).
//! - **Skin** ([`Skin`]): rigid (the paper: each vertex follows its part), or smooth: weights that fall off
//!   over a band on both sides of each part boundary ([`skin::smooth_weights`]), blended by dual quaternions
//!   (default) or linearly. The smooth result is written as a weighted blend of the part motions applied to
//!   the two end shapes, which with one-hot weights is exactly eq 24, and with any weights reproduces both
//!   ends. The two skinned end shapes are then blended edge by edge ([`Options::edge_blend`],
//!   [`skin::edge_blend`]): each edge turns half-way between its two skinned versions and takes the linear
//!   mix of its lengths in the two end shapes. The horse's edges change length by up to 2.5x between poses
//!   at part boundaries; averaging positions there collapses them (p99 boundary stretch 29 % at t = 1/2,
//!   poses 3 -> 8), the edge blend keeps them (15 %). Note that the stretch figure measures deviation from
//!   the very lengths the edge blend aims at: it tells how consistent those lengths and the skinned
//!   directions are, not an independent quality.

pub mod graph;
pub mod interpolate;
pub mod joints;
pub mod pose;
pub mod report;
pub mod rig;
pub mod skeleton_match;
pub mod skin;

use crate::error::{Error, Result};
use crate::geometry::{add, mat_mul, mat_t_vec, mat_vec, scale, transpose, Mat3, Vec3};
use crate::mesh::{Normalization, Population};
use crate::mfa::Model;
use graph::{PartGraph, Tree, TreeRule};
use joints::Joint;
use serde::{Deserialize, Serialize};
use skin::SkinWeights;
use std::collections::BTreeMap;

/// Which part is the root of the tree (the one whose motion is interpolated freely).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum RootRule {
    /// The part with the largest surface area (the trunk of an animal). Default.
    #[default]
    Anchor,
    /// Algorithm 2: the part with the smallest rotation between the two poses.
    Paper,
}

/// How vertices follow the parts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Skin {
    /// Every vertex moves with its own part (eq 22/24). Default.
    #[default]
    Rigid,
    /// Smooth weights across part boundaries ([`skin::smooth_weights`]).
    Smooth,
}

/// How smooth weights blend the part motions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Blend {
    /// Dual-quaternion skinning: no collapse at bent joints. Default.
    #[default]
    DualQuaternion,
    /// Linear blend skinning (what glTF viewers do).
    Linear,
}

/// Interpolation options. Defaults in each field's doc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, rename_all = "camelCase", deny_unknown_fields)]
pub struct Options {
    /// Root rule. Default [`RootRule::Anchor`].
    pub root: RootRule,
    /// Tree rule. Default [`TreeRule::Strongest`].
    pub tree: TreeRule,
    /// Blend the training shapes' joint offsets so both ends are exact. Default true.
    pub exact_ends: bool,
    /// Eq 24's residual ("muscle") blending. Default true.
    pub residual: bool,
    /// Rigid or smooth skinning. Default [`Skin::Rigid`].
    pub skin: Skin,
    /// Blending of smooth weights. Default [`Blend::DualQuaternion`].
    pub blend: Blend,
    /// Smooth skin only: blend the two skinned end shapes edge by edge ([`skin::edge_blend`]) rather than
    /// vertex by vertex. Default true.
    pub edge_blend: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            root: RootRule::Anchor,
            tree: TreeRule::Strongest,
            exact_ends: true,
            residual: true,
            skin: Skin::Rigid,
            blend: Blend::DualQuaternion,
            edge_blend: true,
        }
    }
}

impl Options {
    /// Algorithm 2 as printed (with item 4's Λ and sign): paper root, BFS tree, no offset blending.
    pub fn paper() -> Options {
        Options { root: RootRule::Paper, tree: TreeRule::BreadthFirst, exact_ends: false, ..Options::default() }
    }
}

/// x -> R x + b.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RigidMotion {
    #[serde(with = "crate::geometry::serde_rows")]
    pub rotation: Mat3,
    pub translation: Vec3,
}

impl RigidMotion {
    pub const IDENTITY: RigidMotion = RigidMotion { rotation: crate::geometry::IDENTITY, translation: [0.0; 3] };

    pub fn apply(&self, p: Vec3) -> Vec3 {
        add(mat_vec(&self.rotation, p), self.translation)
    }

    pub fn inverse(&self) -> RigidMotion {
        RigidMotion {
            rotation: transpose(&self.rotation),
            translation: scale(mat_t_vec(&self.rotation, self.translation), -1.0),
        }
    }

    /// self ∘ other (other first).
    pub fn then_after(&self, other: &RigidMotion) -> RigidMotion {
        RigidMotion {
            rotation: mat_mul(&self.rotation, &other.rotation),
            translation: add(mat_vec(&self.rotation, other.translation), self.translation),
        }
    }
}

/// A fit turned into an articulated model (owns copies of what it needs).
#[derive(Debug, Clone)]
pub struct Articulation {
    pub model: Model,
    pub faces: std::sync::Arc<Vec<[u32; 3]>>,
    /// Mesh edges ([`graph::mesh_edges`]).
    pub edges: Vec<[u32; 2]>,
    /// The training shapes (unit box), shared with the population fitted ([`Population`]'s f32 points): a
    /// shape and its rigid reconstruction are made when asked for ([`Articulation::shape`],
    /// [`Articulation::rigid`]). Held in f64, the shapes and their reconstructions took 48 bytes per vertex-pose
    /// for as long as the page's interpolation view was open, and raised a 42 k x 11 population's peak from 57
    /// to 96 bytes per vertex-pose.
    pub population: Population,
    pub normalization: Normalization,
    pub graph: PartGraph,
    /// Joint of every adjacent pair, keyed (smaller, larger).
    pub joints: BTreeMap<(usize, usize), Joint>,
    /// Surface area per part, mean over the training shapes.
    pub part_area: Vec<f64>,
    /// Centroid of each part's latent vertices (its own latent frame).
    pub part_centroid: Vec<Vec3>,
    /// The anchor root ([`RootRule::Anchor`]).
    pub anchor: usize,
    /// One-hot weights (each vertex on its part).
    pub rigid_weights: SkinWeights,
    /// Smooth weights ([`skin::smooth_weights`] with [`skin::DEFAULT_BAND`]).
    pub smooth_weights: SkinWeights,
    /// The smooth weights' band it was built with ([`Articulation::with_band`]).
    pub band: f64,
}

impl Articulation {
    /// Checks that `model` was fitted to `pop` and precomputes graph, joints, weights.
    pub fn new(model: &Model, pop: &Population) -> Result<Articulation> {
        Articulation::with_band(model, pop, skin::DEFAULT_BAND)
    }

    /// Like [`Articulation::new`] with another band width for the smooth weights (see [`skin::smooth_weights`]).
    pub fn with_band(model: &Model, pop: &Population, band: f64) -> Result<Articulation> {
        if model.n_shapes != pop.n_shapes() || model.n_vertices != pop.n_vertices() {
            return Err(Error::Request(format!(
                "the model is for {} shapes x {} vertices but the population has {} x {}",
                model.n_shapes,
                model.n_vertices,
                pop.n_shapes(),
                pop.n_vertices()
            )));
        }
        if model.parts.is_empty() || model.labels.len() != model.n_vertices || model.latent.len() != model.n_vertices {
            return Err(Error::Request(
                "the model has no parts or its labels/latent shape do not match its vertices".into(),
            ));
        }
        if let Some(&l) = model.labels.iter().find(|&&l| l as usize >= model.parts.len()) {
            return Err(Error::Request(format!("label {l} but the model has {} parts", model.parts.len())));
        }
        if !(band.is_finite() && band > 0.0) {
            return Err(Error::Params(format!("the skinning band must be a positive number, got {band}")));
        }
        let n_parts = model.parts.len();
        // the shapes one at a time in f64 (a copy of them all would be 24 bytes per vertex-pose at once)
        let shapes = || pop.shapes().map(|s| s.to_vec());
        // every part's motion from shape 0 (the graph's positions) to each shape: where separate pieces join
        let from_first: Vec<Vec<RigidMotion>> = model
            .parts
            .iter()
            .map(|c| {
                let first = RigidMotion { rotation: c.rotations[0], translation: c.translations[0] }.inverse();
                (0..model.n_shapes)
                    .map(|i| {
                        RigidMotion { rotation: c.rotations[i], translation: c.translations[i] }.then_after(&first)
                    })
                    .collect()
            })
            .collect();
        let graph = PartGraph::new(&model.labels, pop.graph_faces(), n_parts, &pop.shape(0).to_vec(), &from_first);
        let joints = joints::joints(&graph, model, pop.graph_faces(), shapes());
        let mut part_area = vec![0.0; n_parts];
        for s in shapes() {
            for f in pop.faces.iter() {
                let a = graph::triangle_area(s[f[0] as usize], s[f[1] as usize], s[f[2] as usize]) / 3.0;
                for v in f {
                    part_area[model.labels[*v as usize] as usize] += a / pop.n_shapes() as f64;
                }
            }
        }
        let mut part_centroid = vec![[0.0; 3]; n_parts];
        for (v, &l) in model.latent.iter().zip(&model.labels) {
            part_centroid[l as usize] = add(part_centroid[l as usize], *v);
        }
        for k in 0..n_parts {
            part_centroid[k] = scale(part_centroid[k], 1.0 / graph.vertex_count[k].max(1) as f64);
        }
        let anchor = (0..n_parts)
            .filter(|&k| graph.vertex_count[k] > 0)
            .max_by(|&a, &b| part_area[a].total_cmp(&part_area[b]).then(b.cmp(&a)))
            .expect("at least one used part");
        let rigid_weights = SkinWeights::rigid(&model.labels);
        let smooth_weights =
            skin::smooth_weights(&graph, &model.labels, &model.latent, pop.graph_faces(), shapes(), band);
        Ok(Articulation {
            model: model.clone(),
            faces: pop.faces.clone(),
            edges: graph::mesh_edges(&pop.faces),
            population: pop.clone(),
            normalization: pop.normalization,
            graph,
            joints,
            part_area,
            part_centroid,
            anchor,
            rigid_weights,
            smooth_weights,
            band,
        })
    }

    pub fn n_shapes(&self) -> usize {
        self.model.n_shapes
    }

    /// Training shape i (unit box).
    pub fn shape(&self, i: usize) -> Vec<Vec3> {
        self.population.shape(i).to_vec()
    }

    /// Training shape i rebuilt rigidly from the latent shape (eq 22).
    pub fn rigid(&self, i: usize) -> Vec<Vec3> {
        self.model.reconstruct(i)
    }

    pub fn n_vertices(&self) -> usize {
        self.model.n_vertices
    }

    pub fn n_parts(&self) -> usize {
        self.model.parts.len()
    }

    /// Part k's rigid motion in training shape i: latent -> shape (T_k^i = [R_k^i | b_k^i]).
    pub fn training_motion(&self, part: usize, shape: usize) -> RigidMotion {
        let c = &self.model.parts[part];
        RigidMotion { rotation: c.rotations[shape], translation: c.translations[shape] }
    }

    pub fn weights(&self, skin: Skin) -> &SkinWeights {
        match skin {
            Skin::Rigid => &self.rigid_weights,
            Skin::Smooth => &self.smooth_weights,
        }
    }

    /// The joint between two adjacent parts.
    pub fn joint(&self, a: usize, b: usize) -> Option<&Joint> {
        self.joints.get(&if a < b { (a, b) } else { (b, a) })
    }

    /// The root `rule` picks for poses i -> j.
    pub fn root(&self, rule: RootRule, i: usize, j: usize) -> usize {
        match rule {
            RootRule::Anchor => self.anchor,
            RootRule::Paper => {
                let used = self.graph.used_parts();
                *used
                    .iter()
                    .min_by(|&&a, &&b| {
                        self.rotation_angle(a, i, j).total_cmp(&self.rotation_angle(b, i, j)).then(a.cmp(&b))
                    })
                    .expect("at least one used part")
            }
        }
    }

    /// Angle(R_k^i, R_k^j), radians.
    pub fn rotation_angle(&self, part: usize, i: usize, j: usize) -> f64 {
        let c = &self.model.parts[part];
        crate::geometry::rotation::angle_between(&c.rotations[i], &c.rotations[j])
    }

    /// The tree the interpolation i -> j walks with these options.
    pub fn tree(&self, opts: &Options, i: usize, j: usize) -> Tree {
        self.graph.tree(self.root(opts.root, i, j), opts.tree)
    }

    /// Unit box -> the population's original units.
    pub fn to_original(&self, points: &[Vec3]) -> Vec<Vec3> {
        points.iter().map(|&p| self.normalization.to_original(p)).collect()
    }

    pub(crate) fn check_shape(&self, i: usize) -> Result<()> {
        if i < self.n_shapes() {
            Ok(())
        } else {
            Err(Error::Request(format!("no pose {} (0-based): the population has {} poses", i, self.n_shapes())))
        }
    }

    /// The skeleton: one joint per used part arranged as the anchor-rooted tree, each placed at its contact
    /// with its parent (the root at its centroid), in training shape `shape` (unit box).
    pub fn skeleton(&self, shape: usize) -> Result<Skeleton> {
        self.check_shape(shape)?;
        let tree = self.graph.tree(self.anchor, TreeRule::Strongest);
        let mut positions = vec![None; self.n_parts()];
        for &k in &tree.order {
            let motion = self.training_motion(k, shape);
            positions[k] = Some(motion.apply(self.node_offset(&tree, k)));
        }
        Ok(Skeleton { tree, positions })
    }

    /// Where part k's skeleton joint sits in k's latent frame: the joint with its parent, or its centroid
    /// for the root.
    pub fn node_offset(&self, tree: &Tree, k: usize) -> Vec3 {
        match tree.parent[k] {
            None => self.part_centroid[k],
            Some(p) => self.joint(p, k).expect("tree edges are contacts").latent(k),
        }
    }
}

/// Joints of the skeleton.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Skeleton {
    pub tree: Tree,
    /// Position of each part's joint (None for unused parts).
    pub positions: Vec<Option<Vec3>>,
}

/// Linear interpolation of two points.
pub(crate) fn lerp(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    add(scale(a, 1.0 - t), scale(b, t))
}
