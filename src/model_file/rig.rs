//! A rig kept in the model file (format version 2): the skinned rig `export-gltf` and `rig-report` build from
//! the fit, stored with the options and the band it was built with and a fingerprint of the poses it was solved
//! against. A command that would build the same rig from the same poses takes it from the file instead of
//! solving its skin weights again (the fitted weights' SSDR solve is most of what those commands do once the fit
//! is read); any other options, band or poses build it as before. The rig is stored bit for bit (f64), so what a
//! command writes from it is byte for byte what it writes building it.
//!
//! Body arrays: `rigRest` (f64, 3 per vertex: the bind positions), `rigCounts` (u8 per vertex: its influences),
//! `rigBones` and `rigWeights` (the influences in vertex order: bone, weight), `rigMotions` (f64, 12 per pose and
//! bone: rotation rows then translation), `rigJointPoints` (f64, 3 per bone). The header's `rig` holds the rest
//! (docs/formats.md#the-model-file-posemfa).

use super::{bad, floats, Arrays, Body, DAMAGED};
use crate::articulate::graph::Tree;
use crate::articulate::rig::{Joints, Rig, RigOptions};
use crate::articulate::skin::SkinWeights;
use crate::articulate::Articulation;
use crate::articulate::RigidMotion;
use crate::error::Result;
use crate::geometry::{from_rows, rows, Mat3};
use crate::mesh::Population;
use crate::mfa::result::Model;
use serde::{Deserialize, Serialize};

/// A rig built from the model, kept in its file.
#[derive(Debug, Clone)]
pub struct SavedRig {
    /// The articulation's smooth-weight band it was built with ([`Articulation::with_band`]).
    pub band: f64,
    pub options: RigOptions,
    /// [`poses_fingerprint`] of the poses its weights were solved against.
    pub poses: u64,
    pub rig: Rig,
}

impl SavedRig {
    /// Builds the rig of `model` on `pop` with `band` and `options`.
    pub fn build(model: &Model, pop: &Population, band: f64, options: RigOptions) -> Result<SavedRig> {
        if options.bone_scale || options.bone_affine {
            return Err(crate::error::Error::Params(
                "a rig with bone scale or affine bones is not kept in the model file (its motions are not rotations): \
                 build it with export-gltf or rig-report instead"
                    .into(),
            ));
        }
        let art = Articulation::with_band(model, pop, band)?;
        let rig = crate::articulate::rig::build(&art, &options)?;
        Ok(SavedRig { band, options, poses: poses_fingerprint(pop), rig })
    }

    /// The rig, when it is the one `band` and `options` build on `pop`.
    pub fn for_request(&self, pop: &Population, band: f64, options: &RigOptions) -> Option<&Rig> {
        (self.band.to_bits() == band.to_bits() && self.options == *options && self.poses == poses_fingerprint(pop))
            .then_some(&self.rig)
    }
}

/// Where a rig came from ([`kept_or_built`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigSource {
    /// Kept in the model file (`fit --save --with-rig`).
    ModelFile,
    /// Built now from the fit.
    Built,
}

impl RigSource {
    /// "model file" or "built", as the CLI's JSON and the page say it.
    pub fn word(self) -> &'static str {
        match self {
            RigSource::ModelFile => "model file",
            RigSource::Built => "built",
        }
    }
}

/// The rig of `art` (built from `pop`) with `options`: the one kept in a model file (`saved`) when it is that
/// very rig ([`SavedRig::for_request`], with the articulation's band), else built now; and which of the two.
pub fn kept_or_built(
    saved: Option<&SavedRig>,
    art: &Articulation,
    pop: &Population,
    options: &RigOptions,
) -> Result<(Rig, RigSource)> {
    match saved.and_then(|s| s.for_request(pop, art.band, options)) {
        Some(rig) => Ok((rig.clone(), RigSource::ModelFile)),
        None => Ok((crate::articulate::rig::build(art, options)?, RigSource::Built)),
    }
}

/// FNV-1a (64 bits) over the counts and every point's f32 bits, pose after pose: two populations with the same
/// fingerprint hold the same numbers (up to a collision, one in 2^64).
pub fn poses_fingerprint(pop: &Population) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(PRIME);
        }
    };
    eat(&(pop.n_shapes() as u64).to_le_bytes());
    eat(&(pop.n_vertices() as u64).to_le_bytes());
    for i in 0..pop.n_shapes() {
        for p in pop.shape(i).as_f32() {
            for x in p {
                eat(&x.to_bits().to_le_bytes());
            }
        }
    }
    h
}

/// The header's `rig`.
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub(super) struct RigHeader {
    band: f64,
    options: RigOptions,
    /// [`SavedRig::poses`] as 16 hexadecimal digits (a JSON number would lose bits in JavaScript).
    poses: String,
    root: usize,
    order: Vec<usize>,
    parent: Vec<Option<usize>>,
    joints: Joints,
    #[serde(with = "floats")]
    trace: Vec<f64>,
    /// The number of influences over all vertices (the length of `rigBones` and `rigWeights`).
    influences: usize,
}

/// Writes `r`'s arrays into `body` and returns its header.
pub(super) fn write(r: &SavedRig, body: &mut Body) -> RigHeader {
    let rig = &r.rig;
    body.f64s("rigRest", rig.rest.as_flattened());
    let counts: Vec<u8> = rig.weights.influences.iter().map(|v| v.len() as u8).collect();
    body.push("rigCounts", "u8", "raw", counts.len(), &counts);
    let bones: Vec<u32> = rig.weights.influences.iter().flatten().map(|&(b, _)| b).collect();
    let weights: Vec<f64> = rig.weights.influences.iter().flatten().map(|&(_, w)| w).collect();
    body.labels("rigBones", &bones);
    body.f64s("rigWeights", &weights);
    let motions: Vec<f64> =
        rig.bones.iter().flatten().flat_map(|m| rows(&m.rotation).into_iter().flatten().chain(m.translation)).collect();
    body.f64s("rigMotions", &motions);
    body.f64s("rigJointPoints", rig.joint_points.as_flattened());
    RigHeader {
        band: r.band,
        options: r.options,
        poses: format!("{:016x}", r.poses),
        root: rig.tree.root,
        order: rig.tree.order.clone(),
        parent: rig.tree.parent.clone(),
        joints: rig.joints,
        trace: rig.trace.clone(),
        influences: bones.len(),
    }
}

/// Reads the rig of header `h` from the body, for `nv` vertices, `ns` poses and `np` parts, checking every field.
pub(super) fn read(file: &str, h: RigHeader, a: &Arrays, nv: usize, ns: usize, np: usize) -> Result<SavedRig> {
    let field = |name: &str, what: String| bad(file, format!("header field rig.{name}: {what}; {DAMAGED}"));
    if !(h.band.is_finite() && h.band >= 0.0) {
        return Err(field("band", format!("{}", h.band)));
    }
    h.options.validate(ns).map_err(|e| field("options", e.to_string()))?;
    let poses = u64::from_str_radix(&h.poses, 16)
        .ok()
        .filter(|_| h.poses.len() == 16)
        .ok_or_else(|| field("poses", format!("'{}' is not 16 hexadecimal digits", h.poses)))?;
    if h.parent.len() != np {
        return Err(field("parent", format!("{} entries for {np} parts", h.parent.len())));
    }
    // the order: distinct parts, the root first, every other part after its parent, exactly the parts with one
    let mut seen = vec![false; np];
    for (k, &b) in h.order.iter().enumerate() {
        let ok = b < np
            && !seen[b]
            && match h.parent[b] {
                None => k == 0 && b == h.root,
                Some(p) => p < np && seen[p],
            };
        if !ok {
            return Err(field("order", format!("entry {k} (part {b}) is not a part reached after its parent")));
        }
        seen[b] = true;
    }
    if h.order.is_empty() || h.parent.iter().enumerate().any(|(b, p)| p.is_some() != (seen[b] && b != h.root)) {
        return Err(field("parent", "parents that are not those of the parts in the order".into()));
    }
    if h.trace.iter().any(|x| !x.is_finite()) {
        return Err(field("trace", "a value that is not a finite number".into()));
    }
    let rest = a.f64s("rigRest", nv.checked_mul(3).unwrap_or(usize::MAX))?;
    let counts = a.unsigned("rigCounts", nv, 9, "a vertex's influences")?;
    if counts.iter().map(|&c| c as usize).sum::<usize>() != h.influences {
        return Err(field("influences", format!("{} where 'rigCounts' add up to another number", h.influences)));
    }
    if let Some(v) = counts.iter().position(|&c| c == 0 || c as usize > h.options.influences) {
        return Err(bad(
            file,
            format!(
                "array 'rigCounts', vertex {v}: {} influences, the rig allows 1 to {}; {DAMAGED}",
                counts[v], h.options.influences
            ),
        ));
    }
    let bones = a.unsigned("rigBones", h.influences, np, "the parts")?;
    let weights = a.f64s("rigWeights", h.influences)?;
    if let Some(k) = weights.iter().position(|&w| !(w > 0.0 && w <= 1.0 + 1e-9)) {
        return Err(bad(file, format!("array 'rigWeights', element {k}: weight {}; {DAMAGED}", weights[k])));
    }
    let mut influences = Vec::with_capacity(nv);
    let mut at = 0;
    for &c in &counts {
        let c = c as usize;
        influences.push(bones[at..at + c].iter().copied().zip(weights[at..at + c].iter().copied()).collect());
        at += c;
    }
    let flat = a.f64s("rigMotions", ns.checked_mul(np).and_then(|x| x.checked_mul(12)).unwrap_or(usize::MAX))?;
    let mut motions: Vec<RigidMotion> = Vec::with_capacity(ns * np);
    for (k, m) in flat.chunks_exact(12).enumerate() {
        let rotation = from_rows([[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]]);
        if (rotation.transpose() * rotation - Mat3::identity()).abs().max() > 1e-6 || rotation.determinant() < 0.0 {
            return Err(bad(
                file,
                format!("array 'rigMotions': bone {} in pose {} is not a rotation; {DAMAGED}", k % np, k / np + 1),
            ));
        }
        motions.push(RigidMotion { rotation, translation: [m[9], m[10], m[11]] });
    }
    let joint_points = a.f64s("rigJointPoints", np * 3)?;
    let rig = Rig {
        rest: rest.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        weights: SkinWeights { influences },
        bones: motions.chunks_exact(np).map(<[RigidMotion]>::to_vec).collect(),
        tree: Tree { root: h.root, order: h.order, parent: h.parent },
        joint_points: joint_points.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        joints: h.joints,
        trace: h.trace,
        scale: None,
    };
    Ok(SavedRig { band: h.band, options: h.options, poses, rig })
}
