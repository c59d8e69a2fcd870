//! Binary glTF 2.0 (.glb) of an articulated model: the mesh, a skeleton of one joint per part, the skin and
//! two animation clips. The document is built with the `gltf-json` crate; the GLB container (12-byte
//! header, JSON chunk, BIN chunk) is written here.
//!
//! Layout:
//! - node 0 `mesh`: the skinned mesh (a root node without transform, as glTF wants);
//! - node 1 `skeleton`: carries the unit box -> original units map (scale 1/s, translation = offset);
//! - nodes 2..: one joint per used part, arranged as the rig's part tree ([`crate::articulate::rig::Rig::tree`]:
//!   the anchor-rooted tree, or with fitted weights and free joints the same tree rooted on the central part).
//!   Part k's joint sits, in k's latent frame, at its joint point with its parent (its centroid for the root;
//!   [`crate::articulate::rig::Rig::joint_points`]): world matrix
//!   G_k^i = [R_k^i | R_k^i o_k + b_k^i] in pose i. Animation channels hold the local transforms
//!   G_p^-1 G_k (rotation + translation).
//! - inverse bind matrices (G_k^bind)^-1 x (unit box <- original units), so that joint world x inverse
//!   bind = T_k^i (T_k^bind)^-1: part k's rigid motion from the bind pose to pose i.
//! - the mesh is bound in pose `bind_pose`: its rigid reconstruction (eq 22) with rigid weights, so that the
//!   clip reproduces every training pose's rigid reconstruction exactly; the training shape itself with
//!   smooth weights (glTF blends linearly: at other poses the result is linear blend skinning of it).
//! - with bone scale ([`RigOptions::bone_scale`]): after the joints, one leaf node `part k scale` per joint, its
//!   child, with the fixed rotation Rb_kᵀ Q_k (Rb_k the joint's bind rotation, Q_k the bone's scale axes) and the
//!   scale S_k^i animated; the leaves are the skin's joints (inverse bind matrices (Q_k at the joint point)^-1),
//!   so a bone's skin matrix is the joint's rigid motion after Q S Qᵀ about the joint point, and no scale
//!   reaches a child joint;
//! - with affine bones ([`RigOptions::bone_affine`]): the axes Q_k^i turn from pose to pose, so two leaves per
//!   joint: `part k stretch` (the joint's child) with the animated rotation Rb_kᵀ Q_k^i and scale S_k^i, and
//!   under it `part k skin` with the animated rotation Q_k^iᵀ Rb_k, whose product is Rb_kᵀ Q S Qᵀ Rb_k; the
//!   `part k skin` leaves are the skin's joints (inverse bind matrices those of the joints: the bind pose's
//!   bones are the identity);
//! - clip `training poses`: keyframe i at time i s (0-based), one per training shape;
//!   clip `interpolated`: the articulation's own interpolation (anchor root, exact ends) through the poses in
//!   order, `samples_per_second` samples per second.
//!
//! Positions are in the population's original units. [`check_glb`] reads a .glb back and evaluates its
//! training clip at every keyframe from the stored numbers.

use crate::articulate::graph::Tree;
use crate::articulate::rig::{Rig, RigOptions};
use crate::articulate::{Articulation, Options, RigidMotion};
use crate::error::{Error, Result};
use crate::geometry::rotation::to_quat;
use crate::geometry::{mat_mul, mat_vec, sub, Mat3, Vec3};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use serde::Serialize;

pub use crate::articulate::rig::Joints;
/// Which skinning weights the file carries (rigid, smooth, or fitted: [`crate::articulate::rig`]).
pub use crate::articulate::rig::RigWeights as Weights;

/// Morph targets of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Morphs {
    /// The pure rig. Default.
    #[default]
    None,
    /// One morph target per training pose, driven by the `training poses` clip's `weights` channel (1 at its
    /// own keyframe, 0 elsewhere): what linear blend skinning leaves of that pose, so the clip reproduces
    /// every training pose.
    Residual,
}

/// Export options. Defaults in each field's doc.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, rename_all = "camelCase")]
pub struct GltfOptions {
    /// Default [`Weights::Rigid`].
    pub weights: Weights,
    /// Most joints per vertex, 1..=8 (JOINTS_0/WEIGHTS_0, and JOINTS_1/WEIGHTS_1 past 4). Default 4.
    pub influences: usize,
    /// Default [`Joints::Free`].
    pub joints: Joints,
    /// Default [`Morphs::None`].
    pub morphs: Morphs,
    /// Training shape the mesh is bound in (0-based). Default 0.
    pub bind_pose: usize,
    /// Samples per second (per pair of consecutive poses) of the `interpolated` clip, at least 1. Default 10.
    pub samples_per_second: usize,
    /// Interpolation options of the `interpolated` clip (skin and residual do not apply: glTF moves joints).
    pub interpolation: Options,
    /// Fitted weights, free joints: scale channels per bone ([`RigOptions::bone_scale`]). Default false.
    pub bone_scale: bool,
    /// Fitted weights, free joints: affine bones ([`RigOptions::bone_affine`]). Default false.
    pub bone_affine: bool,
    /// Fitted weights: most alternations ([`RigOptions::iterations`]). Default 30.
    pub iterations: usize,
    /// Fitted weights: the alternations' relative tolerance ([`RigOptions::tol`]). Default 1e-2.
    pub tol: f64,
    /// Fitted weights: rings of the part graph that give a vertex's candidate bones, 1..=3
    /// ([`RigOptions::rings`]). Default 1.
    pub rings: usize,
}

impl Default for GltfOptions {
    fn default() -> GltfOptions {
        GltfOptions {
            weights: Weights::Rigid,
            influences: 4,
            joints: Joints::Free,
            morphs: Morphs::None,
            bind_pose: 0,
            samples_per_second: 10,
            interpolation: Options::default(),
            bone_scale: false,
            bone_affine: false,
            iterations: RigOptions::default().iterations,
            tol: RigOptions::default().tol,
            rings: 1,
        }
    }
}

impl GltfOptions {
    /// The rig these options ask for.
    pub fn rig_options(&self) -> RigOptions {
        RigOptions {
            weights: self.weights,
            influences: self.influences,
            joints: self.joints,
            bind_pose: self.bind_pose,
            bone_scale: self.bone_scale,
            bone_affine: self.bone_affine,
            iterations: self.iterations,
            tol: self.tol,
            rings: self.rings,
            ..RigOptions::default()
        }
    }
}

const GLB_MAGIC: u32 = 0x4654_6C67;
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Column-major 4x4 of an affine map x -> A x + c (A row-major 3x3).
fn mat4(a: &Mat3, c: Vec3) -> [f64; 16] {
    [
        a[(0, 0)],
        a[(1, 0)],
        a[(2, 0)],
        0.0,
        a[(0, 1)],
        a[(1, 1)],
        a[(2, 1)],
        0.0,
        a[(0, 2)],
        a[(1, 2)],
        a[(2, 2)],
        0.0,
        c[0],
        c[1],
        c[2],
        1.0,
    ]
}

pub(crate) struct Bin {
    pub(crate) data: Vec<u8>,
    pub(crate) views: Vec<json::buffer::View>,
    pub(crate) accessors: Vec<json::Accessor>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: Option<json::buffer::Target>) -> json::Index<json::buffer::View> {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        let offset = self.data.len();
        self.data.extend_from_slice(bytes);
        self.views.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: Default::default(),
            extras: Default::default(),
        });
        json::Index::new(self.views.len() as u32 - 1)
    }

    #[allow(clippy::too_many_arguments)]
    fn accessor(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
        count: usize,
        component: json::accessor::ComponentType,
        type_: json::accessor::Type,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
        name: &str,
    ) -> json::Index<json::Accessor> {
        let view = self.view(bytes, target);
        let (min, max) = match bounds {
            Some((lo, hi)) => (Some(serde_json::json!(lo)), Some(serde_json::json!(hi))),
            None => (None, None),
        };
        self.accessors.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(count as u64),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: Default::default(),
            extras: Default::default(),
            type_: Valid(type_),
            min,
            max,
            name: Some(name.to_string()),
            normalized: false,
            sparse: None,
        });
        json::Index::new(self.accessors.len() as u32 - 1)
    }

    pub(crate) fn floats(
        &mut self,
        values: &[f32],
        type_: json::accessor::Type,
        per: usize,
        bounds: bool,
        target: Option<json::buffer::Target>,
        name: &str,
    ) -> json::Index<json::Accessor> {
        let b = bounds.then(|| {
            let mut lo = vec![f32::INFINITY; per];
            let mut hi = vec![f32::NEG_INFINITY; per];
            for c in values.chunks(per) {
                for d in 0..per {
                    lo[d] = lo[d].min(c[d]);
                    hi[d] = hi[d].max(c[d]);
                }
            }
            (lo, hi)
        });
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, target, values.len() / per, json::accessor::ComponentType::F32, type_, b, name)
    }
}

/// Quaternion `q` (x, y, z, w) or its negative, whichever is on the side of the previous key's (`prev`, then
/// updated to it), so that a clip's keys interpolate the short way.
fn same_side(mut q: [f64; 4], prev: &mut Option<[f64; 4]>) -> [f64; 4] {
    if let Some(p) = prev {
        if p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3] < 0.0 {
            q = q.map(|c| -c);
        }
    }
    *prev = Some(q);
    q
}

/// A rotation matrix's quaternion (x, y, z, w).
fn quat_xyzw(r: &Mat3) -> [f64; 4] {
    let u = to_quat(r);
    [u.i, u.j, u.k, u.w]
}

/// Local transforms (translation, rotation quaternion xyzw) of every joint of `tree` from world joint
/// motions `world` (joint frame -> unit box): the root relative to the `skeleton` node, every other joint
/// relative to its parent joint.
fn locals(tree: &Tree, world: &[RigidMotion]) -> Vec<(Vec3, [f64; 4])> {
    tree.order
        .iter()
        .map(|&k| {
            let local = match tree.parent[k] {
                None => world[k],
                Some(p) => world[p].inverse().then_after(&world[k]),
            };
            (local.translation, quat_xyzw(&local.rotation))
        })
        .collect()
}

/// The .glb bytes (module doc): builds the rig ([`crate::articulate::rig::build`]) and writes it.
pub fn to_glb(art: &Articulation, opts: &GltfOptions) -> Result<Vec<u8>> {
    let rig = crate::articulate::rig::build(art, &opts.rig_options())?;
    write_glb(art, &rig, opts)
}

/// Joint placement in the bind pose of every part: rotation of the part's MFA motion into the bind pose,
/// origin at the rig's joint point.
fn bind_placements(art: &Articulation, rig: &Rig, bind: usize) -> Vec<RigidMotion> {
    (0..art.n_parts())
        .map(|k| RigidMotion { rotation: art.training_motion(k, bind).rotation, translation: rig.joint_points[k] })
        .collect()
}

/// Writes a rig built from `art` (its bind pose, weights and bones) as a .glb (module doc).
pub fn write_glb(art: &Articulation, rig: &Rig, opts: &GltfOptions) -> Result<Vec<u8>> {
    let ns = art.n_shapes();
    opts.rig_options().validate(ns)?;
    if opts.samples_per_second == 0 {
        return Err(Error::Params("samples per second must be at least 1".into()));
    }
    let tree = &rig.tree;
    let n_joints = tree.order.len();
    let mut joint_of_part = vec![u32::MAX; art.n_parts()];
    for (slot, &k) in tree.order.iter().enumerate() {
        joint_of_part[k] = slot as u32;
    }
    let norm = art.normalization;
    let mut bin = Bin { data: Vec::new(), views: Vec::new(), accessors: Vec::new() };

    // Mesh.
    let positions: Vec<f32> = art.to_original(&rig.rest).iter().flat_map(|p| p.map(|c| c as f32)).collect();
    let pos_acc = bin.floats(
        &positions,
        json::accessor::Type::Vec3,
        3,
        true,
        Some(json::buffer::Target::ArrayBuffer),
        "POSITION",
    );
    let indices: Vec<u8> = art.faces.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let idx_acc = bin.accessor(
        &indices,
        Some(json::buffer::Target::ElementArrayBuffer),
        art.faces.len() * 3,
        json::accessor::ComponentType::U32,
        json::accessor::Type::Scalar,
        None,
        "indices",
    );
    let weights = rig.weights.capped(opts.influences);
    let sets = opts.influences.div_ceil(4);
    let slots_per_vertex = 4 * sets;
    let mut joint_idx: Vec<u16> = Vec::with_capacity(art.n_vertices() * slots_per_vertex);
    let mut joint_w: Vec<f32> = Vec::with_capacity(art.n_vertices() * slots_per_vertex);
    for v in 0..art.n_vertices() {
        if weights.influences(v).any(|(k, _)| joint_of_part[k] == u32::MAX) {
            return Err(Error::Data(format!("vertex {v} is weighted to a part outside the skeleton")));
        }
        let mut slots: Vec<(u16, f32)> =
            weights.influences(v).map(|(k, w)| (joint_of_part[k] as u16, w as f32)).collect();
        // normalise in f32: the heaviest takes the rounding
        let rest: f32 = slots[1..].iter().map(|s| s.1).sum();
        slots[0].1 = 1.0 - rest;
        slots.resize(slots_per_vertex, (0, 0.0));
        for (j, w) in slots {
            joint_idx.push(j);
            joint_w.push(w);
        }
    }
    let mut skin_attrs = Vec::new();
    for set in 0..sets {
        let pick = |v: usize, s: usize| v * slots_per_vertex + 4 * set + s;
        let idx: Vec<u16> = (0..art.n_vertices())
            .flat_map(|v| (0..4).map(move |s| (v, s)))
            .map(|(v, s)| joint_idx[pick(v, s)])
            .collect();
        let wts: Vec<f32> =
            (0..art.n_vertices()).flat_map(|v| (0..4).map(move |s| (v, s))).map(|(v, s)| joint_w[pick(v, s)]).collect();
        let (joints_bytes, joints_type) = if n_joints <= 256 {
            (idx.iter().map(|&j| j as u8).collect::<Vec<u8>>(), json::accessor::ComponentType::U8)
        } else {
            (idx.iter().flat_map(|j| j.to_le_bytes()).collect(), json::accessor::ComponentType::U16)
        };
        let joints_acc = bin.accessor(
            &joints_bytes,
            Some(json::buffer::Target::ArrayBuffer),
            art.n_vertices(),
            joints_type,
            json::accessor::Type::Vec4,
            None,
            &format!("JOINTS_{set}"),
        );
        let weights_acc = bin.floats(
            &wts,
            json::accessor::Type::Vec4,
            4,
            false,
            Some(json::buffer::Target::ArrayBuffer),
            &format!("WEIGHTS_{set}"),
        );
        skin_attrs.push((set as u32, joints_acc, weights_acc));
    }

    // Morph targets: per training pose the bind-space displacement that linear blend skinning carries onto
    // the pose exactly: d = L⁻¹ (v - c) - u with L, c the vertex's blended linear part and translation.
    let mut targets = Vec::new();
    if opts.morphs == Morphs::Residual {
        for i in 0..ns {
            let mut d: Vec<f32> = Vec::with_capacity(3 * art.n_vertices());
            let shape = art.shape(i);
            for v in 0..art.n_vertices() {
                let mut l = crate::geometry::Mat3::zeros();
                let mut c = [0.0; 3];
                for (k, w) in weights.influences(v) {
                    let m = &rig.bones[i][k];
                    l += m.rotation * w;
                    for a in 0..3 {
                        c[a] += w * m.translation[a];
                    }
                }
                let want = sub(shape[v], c);
                let x = solve3(&l, want).ok_or_else(|| {
                    Error::Data(format!(
                        "pose {i}, vertex {v}: the blended bone motion is singular, no morph target can fix it"
                    ))
                })?;
                let disp = sub(x, rig.rest[v]);
                d.extend(disp.map(|c| (c / norm.scale) as f32));
            }
            let acc = bin.floats(
                &d,
                json::accessor::Type::Vec3,
                3,
                true,
                Some(json::buffer::Target::ArrayBuffer),
                &format!("morph target: pose {i}"),
            );
            targets.push(json::mesh::MorphTarget { positions: Some(acc), normals: None, tangents: None });
        }
    }

    // Inverse bind matrices: (B_k)^-1 x (x -> (x - offset) * scale).
    let placements = bind_placements(art, rig, opts.bind_pose);
    let scaled = rig.scale.as_ref();
    let turning = scaled.is_some_and(|sc| sc.turning.is_some());
    let mut ibm: Vec<f32> = Vec::with_capacity(16 * n_joints);
    for &k in &tree.order {
        // with scale channels the skin's joint is the bone's leaf node (its scale axes Q_k at the joint point)
        let gi = match scaled {
            Some(sc) if !turning => {
                RigidMotion { rotation: sc.axes[k], translation: placements[k].translation }.inverse()
            }
            _ => placements[k].inverse(),
        };
        let s = norm.scale;
        let a = gi.rotation.map(|x| x * s);
        let c = sub(gi.translation, mat_vec(&a, norm.offset));
        ibm.extend(mat4(&a, c).iter().map(|&x| x as f32));
    }
    let ibm_acc = bin.floats(&ibm, json::accessor::Type::Mat4, 16, false, None, "inverse bind matrices");

    // Animations: world joint motions W_k = M_k ∘ B_k per frame.
    let world = |bones: &[RigidMotion]| -> Vec<RigidMotion> {
        (0..art.n_parts()).map(|k| bones[k].then_after(&placements[k])).collect()
    };
    let mut animations = Vec::new();
    let keys: Vec<usize> = (0..ns).collect();
    let mut clips: Vec<(&str, Vec<f64>, Vec<Vec<RigidMotion>>)> = Vec::new();
    // With scale channels a bone's skin motion x -> A x + b, A = R Q S Qᵀ, is its joint's rigid motion after the
    // leaf's scaling about the joint point p: x -> R (p + Q S Qᵀ (x - p)) + t', so t' = b - R (p - Q S Qᵀ p).
    let rigid_bones = |i: usize| -> Vec<RigidMotion> {
        match scaled {
            None => rig.bones[i].clone(),
            Some(sc) => (0..art.n_parts())
                .map(|k| {
                    let m = &rig.bones[i][k];
                    let r = m.rotation * sc.stretch_inverse(i, k);
                    let p = placements[k].translation;
                    let moved = mat_vec(&sc.stretch(i, k), p);
                    RigidMotion { rotation: r, translation: sub(m.translation, mat_vec(&r, sub(p, moved))) }
                })
                .collect(),
        }
    };
    clips.push((
        "training poses",
        (0..ns).map(|i| i as f64).collect(),
        (0..ns).map(|i| world(&rigid_bones(i))).collect(),
    ));
    let mfa_motions = opts.weights != Weights::Fitted && opts.joints == Joints::Free;
    if mfa_motions {
        let steps = (ns - 1) * opts.samples_per_second;
        let mut times = Vec::with_capacity(steps + 1);
        let mut frames = Vec::with_capacity(steps + 1);
        for s in 0..=steps {
            let time = s as f64 / opts.samples_per_second as f64;
            times.push(time);
            // the articulation's part motions T_k(t), as bind -> t motions T_k(t) (T_k^bind)^-1
            let parts = art.keyframe_motions(&keys, time, &opts.interpolation)?;
            let bones: Vec<RigidMotion> = (0..art.n_parts())
                .map(|k| parts[k].then_after(&art.training_motion(k, opts.bind_pose).inverse()))
                .collect();
            frames.push(world(&bones));
        }
        clips.push(("interpolated", times, frames));
    }
    for (name, times, frames) in clips {
        if times.len() < 2 {
            continue; // a single pose: nothing to animate
        }
        let t32: Vec<f32> = times.iter().map(|&t| t as f32).collect();
        let input = bin.floats(&t32, json::accessor::Type::Scalar, 1, true, None, &format!("{name}: time"));
        let per_frame: Vec<Vec<(Vec3, [f64; 4])>> = frames.iter().map(|w| locals(tree, w)).collect();
        let mut clip = Channels::new(input);
        for (slot, &k) in tree.order.iter().enumerate() {
            let mut tr: Vec<f32> = Vec::with_capacity(3 * frames.len());
            let mut rot: Vec<f32> = Vec::with_capacity(4 * frames.len());
            let mut prev: Option<[f64; 4]> = None;
            for f in &per_frame {
                let (t, q) = f[slot];
                tr.extend(t.map(|c| c as f32));
                rot.extend(same_side(q, &mut prev).map(|c| c as f32));
            }
            // with fixed joints only the root's translation moves: the others keep their rest translation
            if opts.joints == Joints::Free || tree.parent[k].is_none() {
                let out = bin.floats(
                    &tr,
                    json::accessor::Type::Vec3,
                    3,
                    false,
                    None,
                    &format!("{name}: part {k} translation"),
                );
                clip.add(out, 2 + slot as u32, json::animation::Property::Translation);
            }
            let out =
                bin.floats(&rot, json::accessor::Type::Vec4, 4, false, None, &format!("{name}: part {k} rotation"));
            clip.add(out, 2 + slot as u32, json::animation::Property::Rotation);
            if let (Some(sc), "training poses") = (scaled, name) {
                let sv: Vec<f32> = sc.factors.iter().flat_map(|f| f[k].map(|c| c as f32)).collect();
                let out =
                    bin.floats(&sv, json::accessor::Type::Vec3, 3, false, None, &format!("{name}: part {k} scale"));
                clip.add(out, (2 + n_joints + slot) as u32, json::animation::Property::Scale);
                if turning {
                    // the stretch leaf turns to the pose's axes, the skin leaf back
                    let rb = placements[k].rotation;
                    let mut there: Vec<f32> = Vec::with_capacity(4 * ns);
                    let mut back: Vec<f32> = Vec::with_capacity(4 * ns);
                    let (mut p0, mut p1): (Option<[f64; 4]>, Option<[f64; 4]>) = (None, None);
                    for i in 0..ns {
                        let q = rb.transpose() * sc.axes_of(i, k);
                        there.extend(same_side(quat_xyzw(&q), &mut p0).map(|c| c as f32));
                        back.extend(same_side(quat_xyzw(&q.transpose()), &mut p1).map(|c| c as f32));
                    }
                    for (values, node, what) in
                        [(there, 2 + n_joints + slot, "stretch"), (back, 2 + 2 * n_joints + slot, "skin")]
                    {
                        let out = bin.floats(
                            &values,
                            json::accessor::Type::Vec4,
                            4,
                            false,
                            None,
                            &format!("{name}: part {k} {what} rotation"),
                        );
                        clip.add(out, node as u32, json::animation::Property::Rotation);
                    }
                }
            }
        }
        if name == "training poses" && !targets.is_empty() {
            let mut w = vec![0f32; ns * ns];
            for i in 0..ns {
                w[i * ns + i] = 1.0;
            }
            let out = bin.floats(&w, json::accessor::Type::Scalar, 1, false, None, "training poses: morph weights");
            clip.add(out, 0, json::animation::Property::MorphTargetWeights);
        }
        animations.push(json::Animation {
            extensions: Default::default(),
            extras: Default::default(),
            channels: clip.channels,
            name: Some(name.to_string()),
            samplers: clip.samplers,
        });
    }

    // Nodes: mesh, skeleton wrapper, joints (rest state = the bind pose).
    let rest = locals(tree, &placements);
    let mut nodes = vec![
        json::Node {
            mesh: Some(json::Index::new(0)),
            skin: Some(json::Index::new(0)),
            name: Some("mesh".into()),
            ..Default::default()
        },
        json::Node {
            children: Some(vec![json::Index::new(2)]),
            name: Some("skeleton".into()),
            scale: Some([(1.0 / norm.scale) as f32; 3]),
            translation: Some(norm.offset.map(|c| c as f32)),
            ..Default::default()
        },
    ];
    for (slot, &k) in tree.order.iter().enumerate() {
        let children: Vec<json::Index<json::Node>> = tree
            .order
            .iter()
            .enumerate()
            .filter(|(_, &c)| tree.parent[c] == Some(k))
            .map(|(s, _)| json::Index::new(2 + s as u32))
            .chain(scaled.map(|_| json::Index::new((2 + n_joints + slot) as u32)))
            .collect();
        let (t, q) = rest[slot];
        nodes.push(json::Node {
            children: if children.is_empty() { None } else { Some(children) },
            name: Some(format!("part {}", k + 1)),
            translation: Some(t.map(|c| c as f32)),
            rotation: Some(json::scene::UnitQuaternion(q.map(|c| c as f32))),
            ..Default::default()
        });
    }
    if let Some(sc) = scaled {
        // one leaf per bone: a fixed rotation to its scale axes (Q'_k = Rb_kᵀ Q_k, Rb_k the joint's bind
        // rotation), the scale animated; the skin's joints. Affine bones: the bind pose's axes, and under each
        // a second leaf turning back (the skin's joints)
        let b = opts.bind_pose;
        for (slot, &k) in tree.order.iter().enumerate() {
            let q = quat_xyzw(&(placements[k].rotation.transpose() * sc.axes_of(b, k)));
            let f = sc.factors[b][k];
            nodes.push(json::Node {
                name: Some(format!("part {} {}", k + 1, if turning { "stretch" } else { "scale" })),
                rotation: Some(json::scene::UnitQuaternion(q.map(|c| c as f32))),
                scale: Some(f.map(|c| c as f32)),
                children: turning.then(|| vec![json::Index::new((2 + 2 * n_joints + slot) as u32)]),
                ..Default::default()
            });
        }
        if turning {
            for &k in &tree.order {
                let q = quat_xyzw(&(sc.axes_of(b, k).transpose() * placements[k].rotation));
                nodes.push(json::Node {
                    name: Some(format!("part {} skin", k + 1)),
                    rotation: Some(json::scene::UnitQuaternion(q.map(|c| c as f32))),
                    ..Default::default()
                });
            }
        }
    }
    let skin_joint0 = match scaled {
        None => 2,
        Some(_) if turning => 2 + 2 * n_joints,
        Some(_) => 2 + n_joints,
    };
    while bin.data.len() % 4 != 0 {
        bin.data.push(0);
    }
    let mut attributes = std::collections::BTreeMap::new();
    attributes.insert(Valid(json::mesh::Semantic::Positions), pos_acc);
    for (set, j, w) in skin_attrs {
        attributes.insert(Valid(json::mesh::Semantic::Joints(set)), j);
        attributes.insert(Valid(json::mesh::Semantic::Weights(set)), w);
    }
    let n_targets = targets.len();
    let root = json::Root {
        asset: json::Asset {
            generator: Some(format!(
                "posemfa {} (export::gltf, {:?} weights, {} influences, {:?} joints, {:?} morphs)",
                env!("CARGO_PKG_VERSION"),
                opts.weights,
                opts.influences,
                opts.joints,
                opts.morphs
            )),
            ..Default::default()
        },
        accessors: bin.accessors,
        buffer_views: bin.views,
        buffers: vec![json::Buffer {
            byte_length: USize64(bin.data.len() as u64),
            name: None,
            uri: None,
            extensions: Default::default(),
            extras: Default::default(),
        }],
        meshes: vec![json::Mesh {
            extensions: Default::default(),
            extras: Default::default(),
            name: Some("posemfa".into()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: Default::default(),
                extras: Default::default(),
                indices: Some(idx_acc),
                material: None,
                mode: Valid(json::mesh::Mode::Triangles),
                targets: if n_targets > 0 { Some(targets) } else { None },
            }],
            weights: if n_targets > 0 { Some(vec![0.0; n_targets]) } else { None },
        }],
        skins: vec![json::Skin {
            extensions: Default::default(),
            extras: Default::default(),
            inverse_bind_matrices: Some(ibm_acc),
            joints: (0..n_joints).map(|s| json::Index::new((skin_joint0 + s) as u32)).collect(),
            name: Some("parts".into()),
            skeleton: Some(json::Index::new(2)),
        }],
        nodes,
        scenes: vec![json::Scene {
            extensions: Default::default(),
            extras: Default::default(),
            name: Some("posemfa".into()),
            nodes: vec![json::Index::new(0), json::Index::new(1)],
        }],
        scene: Some(json::Index::new(0)),
        animations,
        ..Default::default()
    };
    let text = json::serialize::to_vec(&root).map_err(|e| Error::Data(format!("glTF JSON: {e}")))?;
    Ok(glb_container(text, bin.data))
}

/// Solves L x = b for a 3x3 L; None when (nearly) singular.
fn solve3(l: &crate::geometry::Mat3, b: Vec3) -> Option<Vec3> {
    let scale = l.iter().map(|x| x.abs()).fold(0.0, f64::max);
    if !(l.determinant().abs() > 1e-12 * scale * scale * scale) {
        return None;
    }
    let x = l.lu().solve(&nalgebra::Vector3::new(b[0], b[1], b[2]))?;
    Some([x[0], x[1], x[2]])
}

/// GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
pub(crate) fn glb_container(mut text: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend(GLB_MAGIC.to_le_bytes());
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(CHUNK_JSON.to_le_bytes());
    out.extend(text);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(CHUNK_BIN.to_le_bytes());
        out.extend(bin);
    }
    out
}

/// Splits a .glb into its JSON document and BIN chunk.
pub fn parse_glb(glb: &[u8]) -> Result<(json::Root, Vec<u8>)> {
    let bad = |m: &str| Error::Data(format!("not a valid .glb: {m}"));
    let word = |o: usize| -> Result<u32> {
        glb.get(o..o + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).ok_or_else(|| bad("truncated"))
    };
    if word(0)? != GLB_MAGIC || word(4)? != 2 || word(8)? as usize != glb.len() {
        return Err(bad("header"));
    }
    let jlen = word(12)? as usize;
    if word(16)? != CHUNK_JSON {
        return Err(bad("first chunk is not JSON"));
    }
    let o = 20usize.checked_add(jlen).filter(|&o| o <= glb.len()).ok_or_else(|| bad("JSON chunk"))?;
    let text = &glb[20..o];
    let root: json::Root = json::deserialize::from_slice(text).map_err(|e| bad(&e.to_string()))?;
    let mut bin = Vec::new();
    if o < glb.len() {
        let blen = word(o)? as usize;
        if word(o + 4)? != CHUNK_BIN {
            return Err(bad("second chunk is not BIN"));
        }
        bin =
            o.checked_add(8).and_then(|start| glb.get(start..)?.get(..blen)).ok_or_else(|| bad("BIN chunk"))?.to_vec();
    }
    Ok((root, bin))
}

/// What [`check_glb`] found.
#[derive(Debug, Clone, Serialize)]
pub struct GlbCheck {
    pub joints: usize,
    pub clips: Vec<String>,
    /// Per training pose: the largest distance (unit box) between the skinned mesh of clip `training poses`
    /// at time i and the rigid reconstruction of pose i.
    pub frame_error: Vec<f64>,
    pub max_frame_error: f64,
}

type Affine = (Mat3, Vec3);

fn affine_mul(a: &Affine, b: &Affine) -> Affine {
    (mat_mul(&a.0, &b.0), crate::geometry::add(mat_vec(&a.0, b.1), a.1))
}

fn trs(t: Vec3, q: [f64; 4], s: Vec3) -> Affine {
    // glTF stores (x, y, z, w); nalgebra's Quaternion::new takes w first
    let r = crate::geometry::rotation::from_quat(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]));
    (Mat3::from_fn(|a, b| r[(a, b)] * s[b]), t)
}

/// The `training poses` clip of a .glb written by [`to_glb`], played at every keyframe from the file's own
/// numbers, as a glTF viewer does: node hierarchy and TRS, the clip's channels (translation, rotation, morph
/// weights), morph targets, inverse bind matrices, JOINTS_n / WEIGHTS_n and linear blend skinning.
#[derive(Debug, Clone)]
pub struct GlbPlayback {
    /// Bind positions (the mesh's POSITION), original units.
    pub rest: Vec<Vec3>,
    /// Per keyframe: skinned positions, original units.
    pub frames: Vec<Vec<Vec3>>,
    /// Per keyframe: world position of every skin joint (in skin order), original units.
    pub joint_positions: Vec<Vec<Vec3>>,
    /// Parent of every skin joint (index in skin order), None for the skeleton's root.
    pub joint_parent: Vec<Option<usize>>,
    pub clips: Vec<String>,
}

/// Plays the `training poses` clip of a .glb (see [`GlbPlayback`]).
pub fn play_glb(glb: &[u8]) -> Result<GlbPlayback> {
    play_glb_clip(glb, "training poses")
}

/// Plays the clip named `clip` of a .glb at every keyframe, as [`play_glb`] does (e.g. `frames`,
/// [`super::pose_glb`]).
pub fn play_glb_clip(glb: &[u8], clip: &str) -> Result<GlbPlayback> {
    let (mut frames, mut joint_positions) = (Vec::new(), Vec::new());
    let rig = play_glb_clip_each(glb, clip, |_, frame, joints| {
        frames.push(frame);
        joint_positions.push(joints);
        Ok(())
    })?;
    Ok(GlbPlayback { rest: rig.rest, frames, joint_positions, joint_parent: rig.joint_parent, clips: rig.clips })
}

/// What [`play_glb_clip_each`] returns besides the frames it hands over.
#[derive(Debug, Clone)]
pub struct GlbRig {
    /// Bind positions (the mesh's POSITION), original units.
    pub rest: Vec<Vec3>,
    /// Parent of every skin joint (index in skin order), None for the skeleton's root.
    pub joint_parent: Vec<Option<usize>>,
    pub clips: Vec<String>,
    /// Keyframes of the clip played.
    pub keys: usize,
}

/// [`play_glb_clip`] one keyframe at a time: `each(key, skinned positions, joint positions)` as each is played,
/// so that no more than one frame is held (a whole clip in f64 is 24 bytes per vertex and keyframe).
pub fn play_glb_clip_each(
    glb: &[u8],
    clip: &str,
    mut each: impl FnMut(usize, Vec<Vec3>, Vec<Vec3>) -> Result<()>,
) -> Result<GlbRig> {
    use crate::mesh::gltf::{Local, Path};
    const FILE: &str = "the .glb";
    let s = crate::mesh::gltf::read_skinned(FILE, glb, &[])?;
    let err = |m: String| crate::mesh::gltf::error(FILE, format!("glb playback: {m}"));
    let joint_parent: Vec<Option<usize>> = {
        let slot_of_node: std::collections::HashMap<usize, usize> =
            s.joints.iter().enumerate().map(|(k, &n)| (n, k)).collect();
        s.joints.iter().map(|&n| s.parent[n].and_then(|p| slot_of_node.get(&p).copied())).collect()
    };
    let channels = s.clip(clip)?;
    let n_keys = channels.first().map_or(0, |c| c.times.len());
    if let Some(c) = channels.iter().find(|c| c.times.len() != n_keys) {
        return Err(err(format!(
            "channels with different keyframe counts ({} and {n_keys}, node {}): played at its keyframes, a clip's \
             channels share them",
            c.times.len(),
            c.node
        )));
    }
    let n_targets = s.targets.len();
    // morph weights of other nodes (another node showing the same mesh) do not move the skinned one
    let channels: Vec<_> = channels.into_iter().filter(|c| c.path != Path::Weights || c.node == s.mesh_node).collect();
    let rest_local: Vec<(Vec3, [f64; 4], Vec3)> = s
        .local
        .iter()
        .map(|l| match *l {
            Local::Trs(t, r, sc) => Ok((t, r, sc)),
            Local::Matrix(m) => {
                let (t, r, sc) = decompose(&m).ok_or_else(|| {
                    err("a node's matrix is not translation, rotation \
                     and scale"
                        .into())
                })?;
                Ok((t, r, sc))
            }
        })
        .collect::<Result<_>>()?;
    for key in 0..n_keys {
        let mut local = rest_local.clone();
        let mut morph_w = s.default_weights.clone();
        for c in &channels {
            let v = &c.values[key];
            match c.path {
                Path::Translation => local[c.node].0 = [v[0], v[1], v[2]],
                Path::Rotation => local[c.node].1 = [v[0], v[1], v[2], v[3]],
                Path::Scale => local[c.node].2 = [v[0], v[1], v[2]],
                Path::Weights => morph_w.copy_from_slice(&v[..n_targets]),
            }
        }
        let mut world: Vec<Affine> = vec![(Mat3::identity(), [0.0; 3]); local.len()];
        for &n in &s.order {
            let l = trs(local[n].0, local[n].1, local[n].2);
            world[n] = match s.parent[n] {
                Some(p) => affine_mul(&world[p], &l),
                None => l,
            };
        }
        let mut jpos = Vec::with_capacity(s.joints.len());
        let joint_mats: Vec<Affine> = s
            .joints
            .iter()
            .zip(&s.inverse_bind)
            .map(|(&n, m)| {
                let w = world[n];
                jpos.push(w.1);
                // glTF matrices are column-major, like nalgebra's storage
                let b: Affine =
                    (Mat3::new(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]), [m[12], m[13], m[14]]);
                affine_mul(&w, &b)
            })
            .collect();
        let mut out = Vec::with_capacity(s.positions.len());
        for (v, (&rest, infl)) in s.positions.iter().zip(&s.influences).enumerate() {
            let mut p = rest;
            for (t, w) in s.targets.iter().zip(&morph_w) {
                if *w != 0.0 {
                    for d in 0..3 {
                        p[d] += w * t[v][d];
                    }
                }
            }
            let mut x = [0.0; 3];
            for &(k, w) in infl {
                let m = &joint_mats[k];
                let y = crate::geometry::add(mat_vec(&m.0, p), m.1);
                for d in 0..3 {
                    x[d] += w * y[d];
                }
            }
            out.push(x);
        }
        each(key, out, jpos)?;
    }
    Ok(GlbRig { rest: s.positions, joint_parent, clips: s.clips.into_iter().flatten().collect(), keys: n_keys })
}

/// Translation, rotation (x, y, z, w) and scale of a column-major 4x4 matrix without shear or projection.
fn decompose(m: &[f64; 16]) -> Option<(Vec3, [f64; 4], Vec3)> {
    let a = Mat3::new(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]);
    let sc = [a.column(0).norm(), a.column(1).norm(), a.column(2).norm()];
    if sc.iter().any(|x| !(*x > 0.0)) || m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0 {
        return None;
    }
    let mut r = a;
    for (c, s) in sc.iter().enumerate() {
        r.set_column(c, &(a.column(c) / *s));
    }
    if (r.transpose() * r - Mat3::identity()).norm() > 1e-4 || r.determinant() < 0.0 {
        return None;
    }
    Some(([m[12], m[13], m[14]], quat_xyzw(&r), sc))
}

/// Evaluates the `training poses` clip of a .glb written by [`to_glb`] at every keyframe ([`play_glb`]) and
/// compares with the rigid reconstructions of `art`, one keyframe at a time ([`play_glb_clip_each`]).
pub fn check_glb(art: &Articulation, glb: &[u8]) -> Result<GlbCheck> {
    let ns = art.n_shapes();
    let mut frame_error = Vec::with_capacity(ns);
    let rig = play_glb_clip_each(glb, "training poses", |i, frame, _| {
        if i >= ns {
            return Ok(()); // (counted: the error below)
        }
        let rigid = art.rigid(i);
        frame_error.push(
            frame
                .iter()
                .zip(&rigid)
                .map(|(x, r)| crate::geometry::norm(sub(art.normalization.to_unit(*x), *r)))
                .fold(0.0, f64::max),
        );
        Ok(())
    })?;
    if rig.keys != ns {
        return Err(Error::Data(format!("glb check: {} keyframes for {ns} poses", rig.keys)));
    }
    let (root, _) = parse_glb(glb)?;
    let joints = root.skins.first().map_or(0, |s| s.joints.len());
    Ok(GlbCheck {
        joints,
        clips: rig.clips,
        max_frame_error: frame_error.iter().cloned().fold(0.0, f64::max),
        frame_error,
    })
}

/// The samplers and channels of one glTF animation clip whose keyframes all share the times `input`, linear.
pub(crate) struct Channels {
    input: json::Index<json::Accessor>,
    pub samplers: Vec<json::animation::Sampler>,
    pub channels: Vec<json::animation::Channel>,
}

impl Channels {
    pub fn new(input: json::Index<json::Accessor>) -> Self {
        Channels { input, samplers: Vec::new(), channels: Vec::new() }
    }

    /// A channel moving `path` of node `node` through the values of accessor `output`.
    pub fn add(&mut self, output: json::Index<json::Accessor>, node: u32, path: json::animation::Property) {
        self.samplers.push(json::animation::Sampler {
            extensions: Default::default(),
            extras: Default::default(),
            input: self.input,
            interpolation: Valid(json::animation::Interpolation::Linear),
            output,
        });
        self.channels.push(json::animation::Channel {
            sampler: json::Index::new(self.samplers.len() as u32 - 1),
            target: json::animation::Target {
                extensions: Default::default(),
                extras: Default::default(),
                node: json::Index::new(node),
                path: Valid(path),
            },
            extensions: Default::default(),
            extras: Default::default(),
        });
    }
}
