//! A rig .glb this project wrote ([`super::gltf::write_glb`]), read back for posing, and written again with a
//! clip of new poses (`posemfa pose`, the page's pose export).
//!
//! Reading ([`read_rig`], through the checked reader [`crate::mesh::gltf::read_skinned`]: strides, sparse
//! accessors and every bound): the mesh of the first node with a mesh and a skin (its triangle primitives;
//! POSITION, all JOINTS_n / WEIGHTS_n), that skin (joints, inverse bind matrices) and the node tree. Bone k is skin joint k; its motion in a pose is its skin
//! matrix S_k = W_k · IBM_k (W_k the joint node's world matrix), the map from the bind positions (POSITION) to the
//! posed mesh in scene coordinates, so the rig's skinning is v = Σ_k w_k S_k u exactly as a glTF player does it.
//! Bone k's parent is the nearest ancestor node that is a joint; its joint point is the joint node's origin in
//! the rest state, taken back to bind coordinates.
//!
//! Writing ([`GlbRig::with_clip`]): the whole document is kept (mesh, skin, other clips) and one animation is
//! added (replacing one of the same name): per joint a translation and a rotation channel, keyframe f at f s,
//! linear, with W_k = M_k · IBM_k⁻¹ and the local transform W_parent⁻¹ W_k (the parent node's rest world when it
//! is not a joint); morph weights 0 when the mesh has morph targets (no residual for a new pose).
//! Everything is in scene coordinates (the population's original units for this project's rigs).

use super::gltf::{glb_container, Bin, Channels};
use crate::articulate::pose::{PoseSpace, SkinnedRig};
use crate::articulate::skin::SkinWeights;
use crate::articulate::RigidMotion;
use crate::error::{Error, Result};
use crate::geometry::procrustes::best_rotation;
use crate::geometry::rotation::{from_quat, to_quat};
use crate::geometry::{add, mat_mul, mat_vec, sub, Mat3, Vec3};
use gltf_json as json;
use json::validation::USize64;

/// x -> A x + c.
type Affine = (Mat3, Vec3);

fn compose(a: &Affine, b: &Affine) -> Affine {
    (mat_mul(&a.0, &b.0), add(mat_vec(&a.0, b.1), a.1))
}

fn invert(a: &Affine) -> Option<Affine> {
    let inv = a.0.try_inverse()?;
    Some((inv, mat_vec(&inv, a.1).map(|x| -x)))
}

/// A rig read from a .glb (module doc).
#[derive(Debug, Clone)]
pub struct GlbRig {
    root: json::Root,
    bin: Vec<u8>,
    /// The skinned mesh (index in the document).
    mesh: usize,
    /// Bind positions, weights, skeleton, joint points: scene coordinates.
    pub rig: SkinnedRig,
    /// Node of every bone (skin joint).
    pub joint_nodes: Vec<usize>,
    /// Name of every bone's node.
    pub names: Vec<String>,
    /// Names of the clips in the file.
    pub clips: Vec<String>,
    /// The mesh's triangles.
    pub faces: Vec<[u32; 3]>,
    ibm: Vec<Affine>,
    node_parent: Vec<Option<usize>>,
    /// Rest-state world matrix of every node.
    rest_world: Vec<Affine>,
}

/// Reads a rig .glb (module doc) with the checked glTF reader ([`crate::mesh::gltf::read_skinned`]: every
/// accessor's bounds, strides and sparse values); `file` names it in errors ("file F: what is wrong").
pub fn read_rig(file: &str, glb: &[u8]) -> Result<GlbRig> {
    let s = crate::mesh::gltf::read_skinned(file, glb, &[])?;
    let bad = |m: String| crate::mesh::gltf::error(file, m);
    let bin = s
        .glb_bin()
        .ok_or_else(|| {
            bad("its first buffer is not a .glb's binary chunk: posemfa poses binary .glb rigs (export the rig as \
                 .glb)"
                .into())
        })?
        .to_vec();
    let root = s.json().clone();
    let nv = s.positions.len();
    let rest: Vec<Vec3> = s.positions.clone();
    let faces = s.faces.clone();
    let n_joints = s.joints.len();
    if s.influences.iter().all(Vec::is_empty) {
        return Err(bad(format!(
            "mesh {} has no JOINTS_0 / WEIGHTS_0: it is not skinned, so it is no rig; weight the mesh to the \
             armature and export it again",
            s.mesh
        )));
    }
    let mut influences: Vec<Vec<(u32, f64)>> =
        s.influences.iter().map(|inf| inf.iter().map(|&(k, w)| (k as u32, w)).collect()).collect();
    for (v, inf) in influences.iter_mut().enumerate() {
        let sum: f64 = inf.iter().map(|x| x.1).sum();
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(bad(format!(
                "vertex {v} of its {nv} has no joint weight (JOINTS_n / WEIGHTS_n): every vertex of a rig follows \
                 a joint; weight the mesh to the armature and export it again"
            )));
        }
        inf.iter_mut().for_each(|x| x.1 /= sum);
        inf.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    }
    let ibm: Vec<Affine> = s
        .inverse_bind
        .iter()
        .map(|m| (Mat3::new(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]), [m[12], m[13], m[14]]))
        .collect();
    let n_nodes = s.local.len();
    let node_parent = s.parent.clone();
    let local_of = |l: &crate::mesh::gltf::Local| -> Affine {
        match *l {
            crate::mesh::gltf::Local::Matrix(m) => {
                (Mat3::new(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]), [m[12], m[13], m[14]])
            }
            crate::mesh::gltf::Local::Trs(t, q, sc) => {
                let r = from_quat(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]));
                (Mat3::from_fn(|a, b| r[(a, b)] * sc[b]), t)
            }
        }
    };
    // parents before children (the reader's order)
    let mut rest_world: Vec<Affine> = vec![(Mat3::identity(), [0.0; 3]); n_nodes];
    for &n in &s.order {
        let l = local_of(&s.local[n]);
        rest_world[n] = match node_parent[n] {
            Some(p) => compose(&rest_world[p], &l),
            None => l,
        };
    }
    let joint_nodes: Vec<usize> = s.joints.clone();
    if let Some(&n) = joint_nodes.iter().find(|&&n| matches!(s.local[n], crate::mesh::gltf::Local::Matrix(_))) {
        return Err(bad(format!(
            "joint node {n} has a matrix: a joint a clip moves needs translation / rotation / scale; export the rig \
             again"
        )));
    }
    let slot_of_node: std::collections::HashMap<usize, usize> =
        joint_nodes.iter().enumerate().map(|(s, &n)| (n, s)).collect();
    let parent: Vec<Option<usize>> = joint_nodes
        .iter()
        .map(|&n| {
            let mut p = node_parent[n];
            while let Some(q) = p {
                if let Some(&s) = slot_of_node.get(&q) {
                    return Some(s);
                }
                p = node_parent[q];
            }
            None
        })
        .collect();
    // skeleton order: parents first (depth, then skin order)
    let depth = |mut k: usize| {
        let mut d = 0;
        while let Some(p) = parent[k] {
            k = p;
            d += 1;
            if d > n_joints {
                break;
            }
        }
        d
    };
    let mut order: Vec<usize> = (0..n_joints).collect();
    order.sort_by_key(|&k| (depth(k), k));
    let joint_points: Vec<Vec3> = (0..n_joints)
        .map(|k| {
            let w = rest_world[joint_nodes[k]];
            let s = compose(&w, &ibm[k]);
            invert(&s).map_or(w.1, |si| add(mat_vec(&si.0, w.1), si.1))
        })
        .collect();
    let names = joint_nodes.iter().map(|&n| s.node_names[n].clone().unwrap_or_else(|| format!("node {n}"))).collect();
    let clips = s.clips.iter().map(|c| c.clone().unwrap_or_default()).collect();
    let rig = SkinnedRig { rest, weights: SkinWeights { influences }, parent, order, joint_points };
    rig.validate().map_err(|e| bad(format!("its skin is not a rig posemfa can pose: {e}")))?;
    Ok(GlbRig { root, bin, mesh: s.mesh, rig, joint_nodes, names, clips, faces, ibm, node_parent, rest_world })
}

impl GlbRig {
    /// The motions of the rest state (the skin matrices W_k · IBM_k; the identity for this project's rigs).
    pub fn rest_bones(&self) -> Vec<RigidMotion> {
        (0..self.joint_nodes.len())
            .map(|k| {
                let s = compose(&self.rest_world[self.joint_nodes[k]], &self.ibm[k]);
                RigidMotion { rotation: best_rotation(&s.0), translation: s.1 }
            })
            .collect()
    }

    /// The .glb with clip `name` added (module doc): keyframe f at f seconds is `frames[f]` (one motion per bone).
    pub fn with_clip(&self, name: &str, frames: &[Vec<RigidMotion>]) -> Result<Vec<u8>> {
        let nb = self.joint_nodes.len();
        if frames.is_empty() {
            return Err(Error::Request("no frames to write".into()));
        }
        if let Some(f) = frames.iter().position(|f| f.len() != nb) {
            return Err(Error::Request(format!("frame {} has {} bone motions for {nb} bones", f + 1, frames[f].len())));
        }
        let ibm_inv: Vec<Affine> = self
            .ibm
            .iter()
            .enumerate()
            .map(|(k, m)| {
                invert(m).ok_or_else(|| Error::Data(format!("joint {k}: its inverse bind matrix is singular")))
            })
            .collect::<Result<_>>()?;
        let slot_of_node: std::collections::HashMap<usize, usize> =
            self.joint_nodes.iter().enumerate().map(|(s, &n)| (n, s)).collect();
        let mut root = self.root.clone();
        root.animations.retain(|a| a.name.as_deref() != Some(name));
        let mut bin = Bin {
            data: self.bin.clone(),
            views: std::mem::take(&mut root.buffer_views),
            accessors: std::mem::take(&mut root.accessors),
        };
        let n = frames.len();
        let times: Vec<f32> = (0..n).map(|f| f as f32).collect();
        let input = bin.floats(&times, json::accessor::Type::Scalar, 1, true, None, &format!("{name}: time"));
        // per bone and frame: the local (translation, rotation xyzw)
        let mut tr = vec![Vec::with_capacity(3 * n); nb];
        let mut rot = vec![Vec::with_capacity(4 * n); nb];
        let mut prev: Vec<Option<[f64; 4]>> = vec![None; nb];
        for (f, bones) in frames.iter().enumerate() {
            let world: Vec<Affine> =
                (0..nb).map(|k| compose(&(bones[k].rotation, bones[k].translation), &ibm_inv[k])).collect();
            for k in 0..nb {
                let node = self.joint_nodes[k];
                let parent_world = match self.node_parent[node] {
                    None => None,
                    Some(p) => Some(match slot_of_node.get(&p) {
                        Some(&s) => world[s],
                        None => self.rest_world[p],
                    }),
                };
                let local = match parent_world {
                    None => world[k],
                    Some(pw) => compose(
                        &invert(&pw)
                            .ok_or_else(|| Error::Data(format!("the parent of joint {k} has a singular transform")))?,
                        &world[k],
                    ),
                };
                let det = local.0.determinant();
                let s = det.cbrt();
                let r = best_rotation(&local.0);
                let off = (local.0 - r * s).norm();
                if !(det > 0.0) || (s - 1.0).abs() > 1e-3 || off > 1e-3 {
                    return Err(Error::Data(format!(
                        "frame {}, joint {k} ({}): its local transform is not a rotation (scale {s:.6}, off by {off:.2e}); \
                         posemfa writes translation and rotation channels only",
                        f + 1,
                        self.names[k]
                    )));
                }
                let q = to_quat(&r);
                let mut q = [q.i, q.j, q.k, q.w];
                if let Some(p) = prev[k] {
                    if p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3] < 0.0 {
                        q = q.map(|c| -c);
                    }
                }
                prev[k] = Some(q);
                tr[k].extend(local.1.map(|c| c as f32));
                rot[k].extend(q.map(|c| c as f32));
            }
        }
        let mut clip = Channels::new(input);
        for k in 0..nb {
            let t = bin.floats(
                &tr[k],
                json::accessor::Type::Vec3,
                3,
                false,
                None,
                &format!("{name}: {} translation", self.names[k]),
            );
            clip.add(t, self.joint_nodes[k] as u32, json::animation::Property::Translation);
            let r = bin.floats(
                &rot[k],
                json::accessor::Type::Vec4,
                4,
                false,
                None,
                &format!("{name}: {} rotation", self.names[k]),
            );
            clip.add(r, self.joint_nodes[k] as u32, json::animation::Property::Rotation);
        }
        // morph targets: weights 0 (a new pose has no residual); on every node that shows the mesh
        let n_targets = root
            .meshes
            .get(self.mesh)
            .map_or(0, |m| m.primitives.iter().map(|p| p.targets.as_ref().map_or(0, |t| t.len())).max().unwrap_or(0));
        if n_targets > 0 {
            let zeros = vec![0f32; n_targets * n];
            let w = bin.floats(&zeros, json::accessor::Type::Scalar, 1, false, None, &format!("{name}: morph weights"));
            let mesh_nodes: Vec<usize> = root
                .nodes
                .iter()
                .enumerate()
                .filter(|(_, nd)| nd.mesh.map(|m| m.value()) == Some(self.mesh))
                .map(|(i, _)| i)
                .collect();
            for node in mesh_nodes {
                clip.add(w, node as u32, json::animation::Property::MorphTargetWeights);
            }
        }
        root.animations.push(json::Animation {
            extensions: Default::default(),
            extras: Default::default(),
            channels: clip.channels,
            name: Some(name.to_string()),
            samplers: clip.samplers,
        });
        while bin.data.len() % 4 != 0 {
            bin.data.push(0);
        }
        root.buffer_views = bin.views;
        root.accessors = bin.accessors;
        match root.buffers.first_mut() {
            Some(b) if b.uri.is_none() => b.byte_length = USize64(bin.data.len() as u64),
            _ => return Err(Error::Data("the rig's first buffer is not the GLB's BIN chunk".into())),
        }
        let text = json::serialize::to_vec(&root).map_err(|e| Error::Data(format!("glTF JSON: {e}")))?;
        Ok(glb_container(text, bin.data))
    }
}

/// The rig as the frames' mesh has it: [`GlbRig::on_frames`].
#[derive(Debug, Clone)]
pub struct RigOnFrames {
    /// The rig whose vertices are the frames' (the file's own, or its points welded).
    pub rig: SkinnedRig,
    /// When welded: for each of the frames' vertices, one of the file's vertices at that point (the first), so
    /// that a pose played from the file is read at the frames' vertices. None: the file's vertices are the frames'.
    pub file_vertex: Option<Vec<usize>>,
}

impl RigOnFrames {
    /// A pose of the file's vertices (a player's output) at the frames' vertices.
    pub fn at_frames(&self, played: &[Vec3]) -> Vec<Vec3> {
        match &self.file_vertex {
            None => played.to_vec(),
            Some(first) => first.iter().map(|&v| played[v]).collect(),
        }
    }
}

impl GlbRig {
    /// The file's vertices grouped into points: vertices with the same bind position and the same joint weights
    /// (bit for bit) are one point, numbered in the order of their first vertex. Exporters write a vertex once per
    /// normal or UV it has (a flat-shaded mesh: once per face corner), which is this.
    fn welded_points(&self) -> (Vec<usize>, Vec<usize>) {
        let mut index: std::collections::HashMap<Vec<u64>, usize> = std::collections::HashMap::new();
        let mut of_vertex = Vec::with_capacity(self.rig.rest.len());
        let mut first = Vec::new();
        for (v, p) in self.rig.rest.iter().enumerate() {
            let mut key: Vec<u64> = p.iter().map(|c| c.to_bits()).collect();
            for (k, w) in self.rig.weights.influences(v) {
                key.push(k as u64);
                key.push(w.to_bits());
            }
            let next = first.len();
            let point = *index.entry(key).or_insert(next);
            if point == next {
                first.push(v);
            }
            of_vertex.push(point);
        }
        (of_vertex, first)
    }

    /// The rig on frames of `frame_vertices` vertices and triangles `frame_faces` (the first frame's): the rig
    /// itself when the counts agree. A rig saved again by a tool that splits vertices along seams or per face
    /// (Blender's glTF exporter on a flat-shaded mesh) has more vertices than the frames; when its points
    /// ([`Self::welded_points`]) are as many as the frames' vertices and its triangles over those points are
    /// exactly the frames' triangles, it is that mesh, and the rig on its points is returned. Otherwise the
    /// frames are refused by name (`frame_name`), saying what the rig's vertices are.
    pub fn on_frames(
        &self,
        rig_file: &str,
        frame_name: &str,
        frame_vertices: usize,
        frame_faces: &[[u32; 3]],
    ) -> Result<RigOnFrames> {
        let nv = self.rig.n_vertices();
        if frame_vertices == nv {
            return Ok(RigOnFrames { rig: self.rig.clone(), file_vertex: None });
        }
        let (of_vertex, first) = self.welded_points();
        let refuse = |why: String| Error::Population {
            file: frame_name.to_string(),
            message: format!(
                "has {frame_vertices} vertices but the rig {rig_file} has {nv}{why}: add frames of the fitted mesh \
                 (the same vertices in the same order, as the training poses)"
            ),
        };
        if first.len() == nv {
            return Err(refuse(String::new()));
        }
        let split = format!(" ({} points, some written more than once, as exporters do along seams)", first.len());
        if first.len() != frame_vertices {
            return Err(refuse(split));
        }
        let canonical = |f: [usize; 3]| {
            let mut f = f;
            f.sort_unstable();
            f
        };
        let mut ours: Vec<[usize; 3]> = self
            .faces
            .iter()
            .map(|f| f.map(|v| of_vertex[v as usize]))
            .filter(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2])
            .map(canonical)
            .collect();
        let mut theirs: Vec<[usize; 3]> = frame_faces.iter().map(|f| canonical(f.map(|v| v as usize))).collect();
        ours.sort_unstable();
        theirs.sort_unstable();
        if ours != theirs {
            return Err(refuse(format!(
                "{split}; its {} points are as many as the frames' vertices, but its triangles over them are not the \
                 frames' (the tool that saved the rig changed the vertex order)",
                first.len()
            )));
        }
        let rest = first.iter().map(|&v| self.rig.rest[v]).collect();
        let influences = first.iter().map(|&v| self.rig.weights.influences[v].clone()).collect();
        let rig = SkinnedRig {
            rest,
            weights: SkinWeights { influences },
            parent: self.rig.parent.clone(),
            order: self.rig.order.clone(),
            joint_points: self.rig.joint_points.clone(),
        };
        rig.validate()?;
        Ok(RigOnFrames { rig, file_vertex: Some(first) })
    }
}

/// The rig's skinning of one pose, scene coordinates (shorthand for [`SkinnedRig::skin`]).
pub fn posed(rig: &GlbRig, bones: &[RigidMotion]) -> Vec<Vec3> {
    rig.rig.skin(bones)
}

/// Distance between two point lists, largest.
pub fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| crate::geometry::norm(sub(*x, *y))).fold(0.0, f64::max)
}

/// Pose mode (the page): a fitted model's rig written as a .glb and read back ([`read_rig`], so everything is in
/// the population's original units, as in the file people take away), its training poses solved onto it
/// ([`crate::articulate::pose::solve_frames`]), their [`PoseSpace`], and the pose being made.
#[derive(Debug, Clone)]
pub struct Poser {
    pub rig: GlbRig,
    /// Bind -> pose motions of every training pose (original units).
    pub training: Vec<Vec<RigidMotion>>,
    pub space: PoseSpace,
    /// The pose being made (starts at the rest pose: every bone the identity).
    pub current: Vec<RigidMotion>,
    /// Each vertex's heaviest bone (what a click on it picks).
    pub bone_of_vertex: Vec<u32>,
    /// The diagonal of the bind positions' bounding box (original units).
    pub diagonal: f64,
    /// The population's unit box (the page shows unit-box coordinates): [`Poser::to_unit`].
    pub normalization: crate::mesh::Normalization,
}

impl Poser {
    /// From a fitted model's articulation: the rig of `opts` ([`super::gltf::write_glb`]; `kept`, a model file's
    /// rig, when it is that very rig) and the population.
    pub fn new(
        art: &crate::articulate::Articulation,
        pop: &crate::mesh::Population,
        opts: &super::gltf::GltfOptions,
        kept: Option<&crate::model_file::SavedRig>,
    ) -> Result<Poser> {
        let (rig, _) = crate::model_file::kept_or_built(kept, art, pop, &opts.rig_options())?;
        let glb = super::gltf::write_glb(art, &rig, opts)?;
        // (the training poses in original units one at a time, into the frame solve's own copy)
        let mut p = Poser::from_glb("rig.glb", &glb, pop.shapes().map(|s| art.to_original(&s.to_vec())))?;
        p.normalization = pop.normalization;
        Ok(p)
    }

    /// Original units -> the population's unit box.
    pub fn to_unit(&self, points: &[Vec3]) -> Vec<Vec3> {
        points.iter().map(|&p| self.normalization.to_unit(p)).collect()
    }

    /// From a rig .glb and the training poses (original units; read once, in order: [`solve_frames`]).
    ///
    /// [`solve_frames`]: crate::articulate::pose::solve_frames
    pub fn from_glb<F: AsRef<[Vec3]>>(
        file: &str,
        glb: &[u8],
        poses: impl IntoIterator<Item = F, IntoIter: ExactSizeIterator>,
    ) -> Result<Poser> {
        let rig = read_rig(file, glb)?;
        let solved = crate::articulate::pose::solve_frames(&rig.rig, poses)?;
        let space = PoseSpace::new(&rig.rig, &solved.bones)?;
        let current = rig.rest_bones();
        let bone_of_vertex = rig.rig.weights.influences.iter().map(|inf| inf[0].0).collect();
        let diagonal = rig.rig.diagonal();
        Ok(Poser {
            rig,
            training: solved.bones,
            space,
            current,
            bone_of_vertex,
            diagonal,
            normalization: crate::mesh::Normalization::IDENTITY,
        })
    }

    /// The mesh of the current pose.
    pub fn positions(&self) -> Vec<Vec3> {
        self.rig.rig.skin(&self.current)
    }

    /// Turns bone k's subtree ([`crate::articulate::pose::turn`]).
    pub fn turn(&mut self, k: usize, axis: Vec3, angle: f64) -> Result<()> {
        self.current = crate::articulate::pose::turn(&self.rig.rig, &self.current, k, axis, angle)?;
        Ok(())
    }

    /// Every bone's angle from the rest pose (degrees): of its rotation relative to its parent's (the root's own).
    pub fn angles(&self) -> Vec<f64> {
        self.angles_of(&self.current)
    }

    fn angles_of(&self, bones: &[RigidMotion]) -> Vec<f64> {
        crate::articulate::pose::local_rotations(&self.rig.rig, bones)
            .iter()
            .map(|q| crate::geometry::rotation::angle(q).to_degrees())
            .collect()
    }

    /// Every bone's largest angle from the rest pose over the training poses (degrees, as [`Poser::angles`]): how
    /// far the poses it was learnt from turn it, against which a pose made by hand can be read.
    pub fn training_angles(&self) -> Vec<f64> {
        let mut most = vec![0.0f64; self.rig.rig.n_bones()];
        for pose in &self.training {
            for (m, a) in most.iter_mut().zip(self.angles_of(pose)) {
                *m = m.max(a);
            }
        }
        most
    }

    /// Bone k in every training pose, degrees from the rest pose: at its joint (its rotation relative to its
    /// parent's, what [`Poser::angles`] and [`Poser::training_angles`] give; the root's own) and as a whole (its
    /// own rotation, which includes every turn of the bones that carry it, the whole body's too).
    pub fn training_angles_of(&self, k: usize) -> Result<(Vec<f64>, Vec<f64>)> {
        if k >= self.rig.rig.n_bones() {
            return Err(Error::Request(format!("no bone {k} ({} bones)", self.rig.rig.n_bones())));
        }
        let joint = self.training.iter().map(|pose| self.angles_of(pose)[k]).collect();
        let whole =
            self.training.iter().map(|pose| crate::geometry::rotation::angle(&pose[k].rotation).to_degrees()).collect();
        Ok((joint, whole))
    }

    /// Where bone k's joint is in the current pose (its parent carries it; the root's: itself).
    pub fn joint_position(&self, k: usize) -> Result<Vec3> {
        let r = &self.rig.rig;
        if k >= r.n_bones() {
            return Err(Error::Request(format!("no bone {k} ({} bones)", r.n_bones())));
        }
        Ok(self.current[r.parent[k].unwrap_or(k)].apply(r.joint_points[k]))
    }

    /// The pose of mode coefficients ([`PoseSpace::pose`]), the root where it is now.
    pub fn set_modes(&mut self, coeffs: &[f64]) -> Result<()> {
        if coeffs.len() > self.space.n_modes() || !coeffs.iter().all(|c| c.is_finite()) {
            return Err(Error::Request(format!(
                "{} mode coefficients for {} modes (numbers)",
                coeffs.len(),
                self.space.n_modes()
            )));
        }
        let root = self.rig.rig.order[0];
        let locals = self.space.locals(self.rig.rig.n_bones(), &self.space.vector(coeffs));
        self.current = crate::articulate::pose::pose_from_locals(&self.rig.rig, self.current[root], &locals);
        Ok(())
    }

    /// The current pose's pose vector and its coordinates along the modes.
    pub fn vector(&self) -> Vec<f64> {
        let q = crate::articulate::pose::local_rotations(&self.rig.rig, &self.current);
        self.space.bones.iter().flat_map(|&k| crate::articulate::pose::log_map(&q[k])).collect()
    }

    /// Sets training pose i (its solved bones).
    pub fn set_training(&mut self, i: usize) -> Result<()> {
        self.current = self.training.get(i).cloned().ok_or_else(|| Error::Request(format!("no training pose {i}")))?;
        Ok(())
    }

    /// The rig .glb with the current pose as a one-frame clip `pose`.
    pub fn pose_glb(&self) -> Result<Vec<u8>> {
        self.rig.with_clip("pose", std::slice::from_ref(&self.current))
    }

    /// New frames of the same mesh (original units) solved onto the rig: the solve, each frame's E_RMS (diagonal:
    /// the bind positions'), and the rig .glb with clip `frames`.
    pub fn add_frames(&self, frames: &[Vec<Vec3>]) -> Result<(crate::articulate::pose::FrameSolve, Vec<f64>, Vec<u8>)> {
        let solved = crate::articulate::pose::solve_frames(&self.rig.rig, frames)?;
        let nv = self.rig.rig.n_vertices();
        let e = solved.sse.iter().map(|&s| crate::articulate::pose::e_rms(s, nv, self.diagonal)).collect();
        let glb = self.rig.with_clip("frames", &solved.bones)?;
        Ok((solved, e, glb))
    }

    /// The bones as 12 numbers each ([R row-major | t]), for undo ([`flat_bones`]).
    pub fn bones_flat(&self) -> Vec<f64> {
        flat_bones(&self.current)
    }

    /// Restores bones from [`Poser::bones_flat`] (rotations re-orthonormalised).
    pub fn set_bones_flat(&mut self, flat: &[f64]) -> Result<()> {
        let nb = self.rig.rig.n_bones();
        if flat.len() != 12 * nb || !flat.iter().all(|x| x.is_finite()) {
            return Err(Error::Request(format!("{} numbers for {nb} bones (12 each)", flat.len())));
        }
        self.current = flat
            .chunks_exact(12)
            .map(|c| RigidMotion {
                rotation: best_rotation(&Mat3::from_row_slice(&c[..9])),
                translation: [c[9], c[10], c[11]],
            })
            .collect();
        Ok(())
    }

    /// Per vertex: whether any of its weights is on bone k or below it (what a turn of k may move).
    pub fn touches(&self, k: usize) -> Result<Vec<bool>> {
        let r = &self.rig.rig;
        if k >= r.n_bones() {
            return Err(Error::Request(format!("no bone {k} ({} bones)", r.n_bones())));
        }
        Ok((0..r.n_vertices()).map(|v| r.weights.influences(v).any(|(b, _)| r.in_subtree(k, b))).collect())
    }

    /// Back to the rest pose.
    pub fn reset(&mut self) {
        self.current = self.rig.rest_bones();
    }
}

/// Bones as 12 numbers each ([R row-major | t]): what [`Poser::set_bones_flat`] takes.
pub fn flat_bones(bones: &[RigidMotion]) -> Vec<f64> {
    bones.iter().flat_map(|m| crate::geometry::row_major(&m.rotation).into_iter().chain(m.translation)).collect()
}
