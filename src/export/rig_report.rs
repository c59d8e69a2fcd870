//! How well an exported rig reproduces the training poses, in the skinning literature's own measure,
//! measured on the .glb as written (its `training poses` clip played by linear blend skinning from the
//! file's own numbers, [`super::gltf::play_glb`]), not on the fit.
//!
//! E_RMS (Kavan et al. 2010): 1000 · ||V - V'||_F / sqrt(3 n_v n_poses) / d, with V the training poses, V'
//! the clip's keyframes and d the diagonal of the bounding box of the rest pose (the training pose the rig
//! is bound in, as given: the same d as for any other tool's rig of the same data, whatever bind positions
//! the rig chose). The same for one pose gives the per-pose figure; the overall E_RMS² is their mean square.
//!
//! `e_rms_his_centred_half_diagonal`: the same figure as Hyperspectral Inverse Skinning (Liu et al. 2020)
//! computes it in `recover_poses.py` (CraGL/Hyperspectral-Inverse-Skinning): every pose, the truth's and the
//! rig's, centred on its own vertex mean before the difference is taken, and the error divided by half the
//! rest pose's diagonal, not the whole: 1000 · ||C(V) - C(V')||_F / sqrt(3 n_v n_poses) / (d / 2), C the
//! centring, over the poses other than the rest pose (the script takes the rest pose apart from the folder of
//! poses it measures; with a single pose, that pose). Their published tables are in this measure; it is about
//! twice E_RMS (less whatever the poses' mean offsets and the rest pose carried).

use super::gltf::{GlbPlayback, GltfOptions, Joints, Morphs, Weights};
use crate::articulate::pose::e_rms;
use crate::articulate::Articulation;
use crate::error::{Error, Result};
use crate::geometry::{norm, sub, Vec3};
use crate::mesh::Population;
use serde::Serialize;

/// Error of one training pose.
#[derive(Debug, Clone, Serialize)]
pub struct PoseError {
    pub name: String,
    pub e_rms: f64,
    /// Largest vertex distance, original units.
    pub max_error: f64,
}

/// The rig's error over all training poses.
#[derive(Debug, Clone, Serialize)]
pub struct RigError {
    pub e_rms: f64,
    /// E_RMS as Hyperspectral Inverse Skinning measures it (module doc): every pose but the rest pose, centred,
    /// divided by half the rest pose's diagonal.
    pub e_rms_his_centred_half_diagonal: f64,
    /// Largest vertex distance over all poses, original units.
    pub max_error: f64,
    /// `max_error` / `diagonal`.
    pub max_error_over_diagonal: f64,
    /// Diagonal of the rest pose's bounding box, original units.
    pub diagonal: f64,
    pub poses: Vec<PoseError>,
}

/// Diagonal of the bounding box of `points`.
pub fn bbox_diagonal(points: &[Vec3]) -> f64 {
    let (lo, hi) = crate::geometry::bounds(points);
    norm(sub(hi, lo))
}

/// Compares the clip's keyframes with the population's poses (original units), keyframe i with pose i;
/// `rest` is the training pose the rig is bound in (its bounding box gives d).
pub fn rig_error(pop: &Population, play: &GlbPlayback, rest: usize) -> Result<RigError> {
    check_clip(pop, play.frames.len(), play.rest.len())?;
    let mut sum = ErrorSum::new(pop, rest)?;
    for (i, frame) in play.frames.iter().enumerate() {
        sum.add(i, frame)?;
    }
    Ok(sum.finish())
}

/// A clip of `keys` keyframes of a rig of `vertices` vertices is one of `pop`'s poses each.
fn check_clip(pop: &Population, keys: usize, vertices: usize) -> Result<()> {
    if keys != pop.n_shapes() {
        return Err(Error::Data(format!("the clip has {keys} keyframes for {} training poses", pop.n_shapes())));
    }
    if vertices != pop.n_vertices() {
        return Err(Error::Data(format!("the rig has {vertices} vertices, the population {}", pop.n_vertices())));
    }
    Ok(())
}

/// [`rig_error`] one frame at a time, in pose order (the same sums in the same order).
struct ErrorSum<'a> {
    pop: &'a Population,
    diagonal: f64,
    poses: Vec<PoseError>,
    total: f64,
    /// The rest pose (the one the rig is bound in).
    rest: usize,
    /// Sum over the poses but the rest pose of the squared error after centring both poses (HIS's measure),
    /// and the rest pose's own.
    total_centred: f64,
    rest_centred: f64,
    max_error: f64,
}

impl<'a> ErrorSum<'a> {
    fn new(pop: &'a Population, rest: usize) -> Result<ErrorSum<'a>> {
        if rest >= pop.n_shapes() {
            return Err(Error::Request(format!(
                "rest pose {rest} (0-based): the population has {} poses",
                pop.n_shapes()
            )));
        }
        let rest_pose: Vec<Vec3> = pop.shape(rest).iter().map(|u| pop.normalization.to_original(u)).collect();
        let diagonal = bbox_diagonal(&rest_pose);
        if !(diagonal > 0.0) {
            return Err(Error::Data("the rest pose has an empty bounding box".into()));
        }
        Ok(ErrorSum {
            pop,
            diagonal,
            poses: Vec::with_capacity(pop.n_shapes()),
            total: 0.0,
            rest,
            total_centred: 0.0,
            rest_centred: 0.0,
            max_error: 0.0,
        })
    }

    /// Frame `i` (original units), after frames 0..i.
    fn add(&mut self, i: usize, frame: &[Vec3]) -> Result<()> {
        let pop = self.pop;
        if i != self.poses.len() || i >= pop.n_shapes() {
            return Err(Error::Data(format!("keyframe {i} of a clip for {} training poses", pop.n_shapes())));
        }
        if frame.len() != pop.n_vertices() {
            return Err(Error::Data(format!(
                "keyframe {i} has {} vertices, the population {}",
                frame.len(),
                pop.n_vertices()
            )));
        }
        let mut sq = 0.0;
        let mut worst: f64 = 0.0;
        // the mean difference: centring both poses subtracts it from every vertex's difference
        let mut mean = [0.0; 3];
        for (x, u) in frame.iter().zip(pop.shape(i).iter()) {
            let e = sub(*x, pop.normalization.to_original(u));
            let d = norm(e);
            sq += d * d;
            worst = worst.max(d);
            mean = crate::geometry::add(mean, e);
        }
        let mean = crate::geometry::scale(mean, 1.0 / frame.len().max(1) as f64);
        // Σ|e - ē|², a second pass rather than Σ|e|² - n|ē|² (no cancellation when the offset dominates)
        let mut centred = 0.0;
        for (x, u) in frame.iter().zip(pop.shape(i).iter()) {
            let e = sub(sub(*x, pop.normalization.to_original(u)), mean);
            centred += crate::geometry::dot(e, e);
        }
        self.total += sq;
        if i == self.rest {
            self.rest_centred = centred;
        } else {
            self.total_centred += centred;
        }
        self.max_error = self.max_error.max(worst);
        self.poses.push(PoseError {
            name: pop.names[i].clone(),
            e_rms: e_rms(sq, pop.n_vertices(), self.diagonal),
            max_error: worst,
        });
        Ok(())
    }

    fn finish(self) -> RigError {
        let points = self.pop.n_vertices() * self.pop.n_shapes();
        // HIS measures the poses apart from the rest pose; a population of one pose has only that one
        let his = match self.pop.n_shapes() {
            1 => e_rms(self.rest_centred, points, self.diagonal / 2.0),
            n => e_rms(self.total_centred, self.pop.n_vertices() * (n - 1), self.diagonal / 2.0),
        };
        RigError {
            e_rms: e_rms(self.total, points, self.diagonal),
            e_rms_his_centred_half_diagonal: his,
            max_error: self.max_error,
            max_error_over_diagonal: self.max_error / self.diagonal,
            diagonal: self.diagonal,
            poses: self.poses,
        }
    }
}

/// The pose a rig is bound in by default: the file whose name (without extension) is `reference`, else the
/// first (the CLI and the page alike).
pub fn default_bind_pose(pop: &Population) -> usize {
    pop.names
        .iter()
        .position(|n| std::path::Path::new(n).file_stem().is_some_and(|s| s.eq_ignore_ascii_case("reference")))
        .unwrap_or(0)
}

/// The fit's own error in the rig's measure: E_RMS of the rigid reconstruction of every training pose (eq 22)
/// against the pose, with d the diagonal of [`default_bind_pose`]'s bounding box, so that the fit and any rig
/// of it are compared in one unit (the fit's RMSE is per vertex in the unit box; E_RMS per coordinate, in
/// thousandths of the diagonal). A rig with rigid weights plays exactly these reconstructions.
pub fn fit_e_rms(pop: &Population, model: &crate::mfa::Model) -> f64 {
    let diagonal = bbox_diagonal(&pop.shape(default_bind_pose(pop)).to_vec());
    // the squared error and d both in the unit box, whose scale cancels
    let points = pop.n_vertices() * pop.n_shapes();
    e_rms(model.rmse(pop).powi(2) * points as f64, points, diagonal)
}

/// How a bone moves (fitted weights with free joints; the page's Bones field): rigidly (the default), with a scale
/// along three fixed axes of its own ([`crate::articulate::rig::RigOptions::bone_scale`]), or by any linear map
/// of positive determinant ([`crate::articulate::rig::RigOptions::bone_affine`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoneMotion {
    #[default]
    Rigid,
    Scale,
    Affine,
}

impl BoneMotion {
    /// The bone motion a word names ("rigid", "scale", "affine"), or what is allowed.
    pub fn from_word(word: &str) -> std::result::Result<BoneMotion, String> {
        match word {
            "rigid" => Ok(BoneMotion::Rigid),
            "scale" => Ok(BoneMotion::Scale),
            "affine" => Ok(BoneMotion::Affine),
            other => Err(format!("bone_motion = '{other}': use 'rigid', 'scale' or 'affine'")),
        }
    }

    /// Sets these bones on export options ([`GltfOptions::bone_scale`], [`GltfOptions::bone_affine`]).
    pub fn apply(self, g: &mut GltfOptions) {
        g.bone_scale = self == BoneMotion::Scale;
        g.bone_affine = self == BoneMotion::Affine;
    }
}

/// A rig as asked for by the page (camelCase, unknown fields refused); missing fields take
/// [`GltfOptions`]' defaults, except the bind pose: [`default_bind_pose`].
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(default, rename_all = "camelCase", deny_unknown_fields)]
pub struct RigRequest {
    pub weights: Weights,
    /// 1..=8, default 4.
    pub influences: Option<usize>,
    pub joints: Joints,
    pub morphs: Morphs,
    /// 0-based; default [`default_bind_pose`].
    pub bind_pose: Option<usize>,
    /// Default rigid.
    pub bones: BoneMotion,
}

/// What the rig panel's Influences field allows, in its messages.
pub const INFLUENCES_ALLOWED: &str = "a whole number from 1 to 8 (the most bones that move one vertex)";

impl RigRequest {
    /// The rig panel's fields as typed (`influences`: text), each checked against what it allows: the request,
    /// or one problem per field that cannot be used (its name, what was typed, what is allowed: no parser's
    /// words). An empty field is "empty", not 0.
    pub fn with_fields(
        &self,
        fields: &[(&str, &str)],
    ) -> std::result::Result<RigRequest, Vec<crate::mfa::params::FieldProblem>> {
        let mut r = self.clone();
        let mut problems = Vec::new();
        for &(name, text) in fields {
            let got = match name {
                "influences" => influences_field(text).map(|n| r.influences = Some(n)),
                _ => Err(format!("is not a field of the rig panel (influences is)")),
            };
            if let Err(message) = got {
                let field = if name == "influences" { "influences" } else { "unknown" };
                problems.push(crate::mfa::params::FieldProblem { field, message });
            }
        }
        if problems.is_empty() {
            Ok(r)
        } else {
            Err(problems)
        }
    }

    /// The export options for `pop`, validated.
    pub fn options(&self, pop: &Population) -> Result<GltfOptions> {
        let d = GltfOptions::default();
        let mut g = GltfOptions {
            weights: self.weights,
            influences: self.influences.unwrap_or(d.influences),
            joints: self.joints,
            morphs: self.morphs,
            bind_pose: self.bind_pose.unwrap_or_else(|| default_bind_pose(pop)),
            ..d
        };
        self.bones.apply(&mut g);
        g.rig_options().validate(pop.n_shapes())?;
        Ok(g)
    }
}

/// The Influences field's text as a count: 1 to 8 ([`INFLUENCES_ALLOWED`]), or why not, naming what was typed.
pub fn influences_field(text: &str) -> std::result::Result<usize, String> {
    let t = text.trim();
    let allowed = INFLUENCES_ALLOWED;
    if t.is_empty() {
        return Err(format!("is empty: it must be {allowed}"));
    }
    match t.parse::<f64>() {
        Ok(x) if x.is_finite() && x.fract() == 0.0 && (1.0..=8.0).contains(&x) => Ok(x as usize),
        Ok(x) if x.is_finite() && x.fract() == 0.0 && x < 1.0 => {
            Err(format!("'{t}' is less than 1: it must be {allowed}"))
        }
        Ok(x) if x.is_finite() && x.fract() == 0.0 => Err(format!("'{t}' is more than 8: it must be {allowed}")),
        _ => Err(format!("'{t}' is not a whole number: it must be {allowed}")),
    }
}

/// A written rig and its error measured on the file.
#[derive(Debug, Clone)]
pub struct RigExport {
    pub glb: Vec<u8>,
    pub error: RigError,
    /// Joints of the file's skin.
    pub bones: usize,
    /// The file's animation clips by name: `training poses`, and `interpolated` when the rig moves its parts
    /// by the fit's own motions (rigid or smooth weights with free joints: [`super::gltf`]).
    pub clips: Vec<String>,
    /// Whether the rig was kept in a model file or built now ([`crate::model_file::kept_or_built`]).
    pub source: crate::model_file::RigSource,
    /// Milliseconds: building the rig (weights, bones), writing the .glb, playing and measuring it.
    pub rig_ms: f64,
    pub write_ms: f64,
    pub evaluate_ms: f64,
}

/// Builds the rig of `art` ([`crate::articulate::rig::build`]; `kept`, a model file's rig, when it is that very
/// rig: [`crate::model_file::kept_or_built`]), writes it ([`super::gltf::write_glb`]) and measures the file
/// ([`rig_error`] of [`super::gltf::play_glb`]), bound in `opts.bind_pose`.
pub fn export_rig(
    art: &Articulation,
    pop: &Population,
    opts: &GltfOptions,
    kept: Option<&crate::model_file::SavedRig>,
) -> Result<RigExport> {
    let t = crate::clock::now_ms();
    let (rig, source) = crate::model_file::kept_or_built(kept, art, pop, &opts.rig_options())?;
    let t1 = crate::clock::now_ms();
    let glb = super::gltf::write_glb(art, &rig, opts)?;
    let t2 = crate::clock::now_ms();
    // (played a frame at a time: the whole clip in f64 would be 24 bytes per vertex-pose)
    let mut sum = ErrorSum::new(pop, opts.bind_pose)?;
    let played = super::gltf::play_glb_clip_each(&glb, "training poses", |i, frame, _| sum.add(i, &frame))?;
    check_clip(pop, played.keys, played.rest.len())?;
    let error = sum.finish();
    let t3 = crate::clock::now_ms();
    Ok(RigExport {
        glb,
        error,
        bones: played.joint_parent.len(),
        clips: played.clips,
        source,
        rig_ms: t1 - t,
        write_ms: t2 - t1,
        evaluate_ms: t3 - t2,
    })
}

#[cfg(test)]
mod field_tests {
    use super::*;

    #[test]
    fn influences_field_names_what_was_typed_and_what_is_allowed() {
        assert_eq!(influences_field(" 3 "), Ok(3));
        assert_eq!(influences_field("8"), Ok(8));
        for (text, says) in [
            ("", "is empty"),
            ("0", "less than 1"),
            ("-3", "less than 1"),
            ("99", "more than 8"),
            ("2.5", "not a whole number"),
            ("x", "not a whole number"),
        ] {
            let m = influences_field(text).unwrap_err();
            assert!(m.contains(says) && m.contains("1 to 8"), "{text:?}: {m}");
            assert!(!m.contains("usize") && !m.contains("column"), "{m}");
        }
        let bad = RigRequest::default().with_fields(&[("influences", "")]).unwrap_err();
        assert_eq!(bad[0].field, "influences");
        assert!(!bad[0].message.contains("= 0"), "{}", bad[0].message);
        assert_eq!(RigRequest::default().with_fields(&[("influences", "2")]).unwrap().influences, Some(2));
    }
}

#[cfg(test)]
mod measure_tests {
    use super::*;
    use crate::mesh::Mesh;

    /// Two poses of four vertices; the rest pose's box is 2 x 2 x 1 (diagonal 3). Keyframe 0 (the rest pose) is
    /// off by ±0.2 along y on vertices 2 and 3, keyframe 1 by (1, 1, 1) everywhere plus ±0.4 along x on vertices
    /// 0 and 1.
    #[test]
    fn his_measure_centres_each_pose_and_halves_the_diagonal() {
        let rest = vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]];
        let faces = vec![[0, 1, 2], [0, 1, 3]];
        let named = vec![
            ("p0".to_string(), Mesh { positions: rest.clone(), faces: faces.clone() }),
            ("p1".to_string(), Mesh { positions: rest.clone(), faces }),
        ];
        let pop = Population::new(crate::mesh::population::Sources::Meshes(named)).unwrap();
        let extra = [[0.4, 0.0, 0.0], [-0.4, 0.0, 0.0], [0.0; 3], [0.0; 3]];
        let rest_off: Vec<Vec3> = rest.iter().zip([0.0, 0.0, 0.2, -0.2]).map(|(p, e)| [p[0], p[1] + e, p[2]]).collect();
        let off: Vec<Vec3> =
            rest.iter().zip(extra).map(|(p, e)| [p[0] + 1.0 + e[0], p[1] + 1.0 + e[1], p[2] + 1.0 + e[2]]).collect();
        let play = GlbPlayback {
            rest: rest.clone(),
            frames: vec![rest_off, off],
            joint_positions: vec![vec![], vec![]],
            joint_parent: vec![],
            clips: vec!["training poses".into()],
        };
        let err = rig_error(&pop, &play, 0).unwrap();
        // Kavan: every coordinate of both poses' errors counts; 3 n_v n_poses = 24; d = 3
        let kavan =
            1000.0 * ((2.0 * 0.04 + 1.4f64.powi(2) + 2.0 + 0.6f64.powi(2) + 2.0 + 3.0 + 3.0) / 24.0).sqrt() / 3.0;
        assert!((err.e_rms - kavan).abs() < 1e-6 * kavan, "{} vs {kavan}", err.e_rms);
        // HIS: the rest pose is not measured; the mean offset (1, 1, 1) goes with the centring, ±0.4 is left;
        // 3 n_v n_poses = 12; d / 2 = 1.5
        let his = 1000.0 * (2.0 * 0.16f64 / 12.0).sqrt() / 1.5;
        assert!(
            (err.e_rms_his_centred_half_diagonal - his).abs() < 1e-6 * his,
            "{}",
            err.e_rms_his_centred_half_diagonal
        );
        // a keyframe of the wrong size is an error, not a silent truncation
        let short = GlbPlayback { frames: vec![rest.clone(), rest[..3].to_vec()], ..play };
        assert!(rig_error(&pop, &short, 0).is_err());
    }
}
