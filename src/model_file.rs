//! The model file (`.posemfa`): a finished fit, the parameters it was fitted with and, optionally, the population
//! it was fitted to, in one file that the CLI (`fit --save`, `--model`), the page (a drop, Open, `#src=`) and the
//! embed read back without fitting again.
//!
//! Layout (every number little-endian; the schema, field by field, is in docs/formats.md#the-model-file):
//!
//! ```text
//! bytes 0..8    magic "POSEMFA\0"
//!       8..12   u32 format version (VERSION)
//!      12..16   u32 H: length of the JSON header
//!      16..24   u64 B: length of the binary body
//!      24..     the JSON header (UTF-8, H bytes), zero bytes up to a multiple of 8, then the body (B bytes)
//! ```
//!
//! The header holds everything small (the population's names, source and normalization, the parameters, the
//! fit's counts, statistics, part-rule rounds and merges, the summary figures) and a table of the body's arrays
//! (name, element type, encoding, count, offset, bytes). The body holds everything that grows with the mesh:
//! labels in the narrowest unsigned type that holds them, the triangles delta-coded as zigzag LEB128 varints,
//! the latent shape and the parts' parameters as f64 (bit for bit what the fit produced), and the population's
//! unit-box points as f32 (the very numbers a population holds).
//!
//! Versions: a reader reads its own version and every older one; a file of a newer version is refused by name
//! (which version, which this reader reads, what to do). A change that an older reader would misread raises the
//! version; nothing is ever added to version 1's header without it (its fields are closed: an unknown field is
//! refused as damage). Version 2 adds an optional rig ([`rig`]); a file without one is written as version 1, so
//! that older readers still open it.

use crate::error::{Error, Result};
use crate::geometry::{from_rows, rows, Mat3, Vec3};
use crate::mesh::{Normalization, Population};
use crate::mfa::component::Component;
use crate::mfa::params::Params;
use crate::mfa::result::Model;
use crate::parts::diagnosis::Diagnosis;
use crate::parts::hierarchy::{FitResult, PartRound, RuleReport, StageParts, StageStats};
use crate::parts::merge_tree::{CurvePoint, Merge, MergeTree};
use serde::{Deserialize, Serialize};
use serde::{Deserializer, Serializer};

mod rig;
pub use rig::{kept_or_built, poses_fingerprint, RigSource, SavedRig};

/// The first eight bytes of every model file.
pub const MAGIC: &[u8; 8] = b"POSEMFA\0";
/// The newest format version this posemfa writes and reads (a file without a rig is written as version 1).
pub const VERSION: u32 = 2;
/// The extension the CLI and the page give model files.
pub const EXTENSION: &str = "posemfa";
/// The `format` field of the header.
const FORMAT: &str = "posemfa model";
/// Bytes before the header.
const PREFIX: usize = 24;

/// A fit as a model file holds it: the result, its parameters and its population (the data itself, or when the
/// file was saved without it a stand-in whose poses are the model's reconstructions: [`ModelFile::has_data`]).
#[derive(Debug, Clone)]
pub struct ModelFile {
    pub result: FitResult,
    pub params: Params,
    pub population: Population,
    /// The population holds the fitted data; false: its poses are the model's own reconstructions (eq 22), so
    /// views of the data (reconstruction error, residuals, responsibilities) and fitting again need the data.
    pub has_data: bool,
    /// Figures of the fit measured on the data when it was saved (what the views show without the data).
    pub summary: Summary,
    /// A rig built from the fit, kept so that the commands that would build it take it ([`SavedRig`]).
    pub rig: Option<SavedRig>,
}

/// Figures that need the data, measured when the model was saved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Summary {
    /// RMSE of the fit (unit-box units, [`Model::rmse`]).
    #[serde(with = "float")]
    pub rmse: f64,
    /// The fit's E_RMS ([`crate::export::rig_report::fit_e_rms`]).
    #[serde(with = "float")]
    pub e_rms: f64,
    /// The verdict ([`crate::parts::diagnosis::diagnose_finished`]); null for a fit stopped early.
    #[serde(with = "diagnosis_header")]
    pub diagnosis: Option<Diagnosis>,
}

impl Summary {
    /// The figures of `result` measured on `pop`.
    pub fn measure(pop: &Population, result: &FitResult) -> Summary {
        Summary {
            rmse: result.model.rmse(pop),
            e_rms: crate::export::rig_report::fit_e_rms(pop, &result.model),
            diagnosis: crate::parts::diagnosis::diagnose_finished(pop, result),
        }
    }
}

impl ModelFile {
    /// A finished (or stopped) fit of `pop` with `params`, its summary measured on the data.
    pub fn new(population: Population, result: FitResult, params: Params) -> ModelFile {
        let summary = Summary::measure(&population, &result);
        ModelFile { result, params, population, has_data: true, summary, rig: None }
    }

    /// The file's bytes; with `with_population` (and the data at hand) the population's points too.
    pub fn to_bytes(&self, with_population: bool) -> Vec<u8> {
        let fit = Borrowed {
            result: &self.result,
            params: &self.params,
            population: &self.population,
            summary: &self.summary,
        };
        write(&fit, with_population && self.has_data, self.rig.as_ref())
    }

    /// Reads a model file (`file` names it in errors), checking every field.
    pub fn from_bytes(file: &str, bytes: &[u8]) -> Result<ModelFile> {
        read(file, bytes)
    }

    /// Puts the data of `pop` under a model read without it (or replaces it), after checking that `pop` is the
    /// population the model was fitted to: the same vertex count, pose count and triangles. The figures are
    /// measured again, on these poses.
    pub fn with_population(mut self, file: &str, pop: Population) -> Result<ModelFile> {
        check_same_mesh(file, &self.population, &pop)?;
        self.summary = Summary::measure(&pop, &self.result);
        self.population = pop;
        self.has_data = true;
        Ok(self)
    }
}

/// What a model file is written from, borrowed (the page's model keeps its parts where they are).
pub struct Borrowed<'a> {
    pub result: &'a FitResult,
    pub params: &'a Params,
    pub population: &'a Population,
    pub summary: &'a Summary,
}

impl Borrowed<'_> {
    /// The file's bytes; with `with_points` the population's points too (only when it holds the data).
    pub fn to_bytes(&self, with_points: bool) -> Vec<u8> {
        write(self, with_points, None)
    }
}

/// Refuses `pop` unless it has the vertices, poses and triangles of `saved` (the population of model `file`).
pub fn check_same_mesh(file: &str, saved: &Population, pop: &Population) -> Result<()> {
    let what = if pop.n_vertices() != saved.n_vertices() {
        format!("{} vertices, the model's population {}", pop.n_vertices(), saved.n_vertices())
    } else if pop.n_shapes() != saved.n_shapes() {
        format!("{} poses, the model's population {}", pop.n_shapes(), saved.n_shapes())
    } else if pop.faces.len() != saved.faces.len() {
        format!("{} triangles, the model's population {}", pop.faces.len(), saved.faces.len())
    } else if let Some(k) = pop.faces.iter().zip(saved.faces.iter()).position(|(a, b)| a != b) {
        format!("other triangles (triangle {} differs)", k + 1)
    } else {
        return Ok(());
    };
    Err(Error::ModelFile {
        file: file.to_string(),
        message: format!(
            "the model was fitted to another mesh: these poses ({}) have {what}; give the poses the model was fitted \
             to, or fit these",
            pop.source
        ),
    })
}

// ---------------------------------------------------------------- the header

/// An f64 in the header: a JSON number when finite (written shortest, read back bit for bit), else the string
/// "inf", "-inf" or "nan" (JSON has no such numbers; a part rule's last score is infinite when nothing is left
/// to merge).
mod float {
    use super::*;

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
        if x.is_finite() {
            s.serialize_f64(*x)
        } else if x.is_nan() {
            s.serialize_str("nan")
        } else {
            s.serialize_str(if *x > 0.0 { "inf" } else { "-inf" })
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Either {
            Number(f64),
            Word(String),
        }
        match Either::deserialize(d)? {
            Either::Number(x) => Ok(x),
            Either::Word(w) => match w.as_str() {
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                "nan" => Ok(f64::NAN),
                _ => Err(serde::de::Error::custom(format!("'{w}' is not a number (nor inf, -inf, nan)"))),
            },
        }
    }
}

/// Vec<f64> through [`float`].
mod floats {
    use super::*;

    #[derive(Serialize, Deserialize)]
    #[serde(transparent)]
    struct F(#[serde(with = "float")] f64);

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|&x| F(x)))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Vec<f64>, D::Error> {
        Ok(Vec::<F>::deserialize(d)?.into_iter().map(|f| f.0).collect())
    }
}

/// A [`CurvePoint`] in the header (its floats through [`float`]).
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct CurveHeader {
    parts: usize,
    #[serde(with = "float")]
    score: f64,
    #[serde(with = "float")]
    variance: f64,
    merged: bool,
}

impl From<&CurvePoint> for CurveHeader {
    fn from(c: &CurvePoint) -> Self {
        CurveHeader { parts: c.parts, score: c.score, variance: c.variance, merged: c.merged }
    }
}

impl From<CurveHeader> for CurvePoint {
    fn from(c: CurveHeader) -> Self {
        CurvePoint { parts: c.parts, score: c.score, variance: c.variance, merged: c.merged }
    }
}

/// A [`Merge`] in the header.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MergeHeader {
    a: u32,
    b: u32,
    parts: usize,
    #[serde(with = "float")]
    rise: f64,
    #[serde(with = "float")]
    score: f64,
    #[serde(with = "float")]
    variance: f64,
}

impl From<&Merge> for MergeHeader {
    fn from(m: &Merge) -> Self {
        MergeHeader { a: m.a, b: m.b, parts: m.parts, rise: m.rise, score: m.score, variance: m.variance }
    }
}

impl From<MergeHeader> for Merge {
    fn from(m: MergeHeader) -> Self {
        Merge { a: m.a, b: m.b, parts: m.parts, rise: m.rise, score: m.score, variance: m.variance }
    }
}

/// Option<[`Diagnosis`]> in the header.
mod diagnosis_header {
    use super::*;

    #[derive(Serialize, Deserialize)]
    #[serde(rename_all = "camelCase", deny_unknown_fields)]
    struct D {
        articulated: bool,
        undecided: bool,
        reason: String,
        #[serde(with = "float")]
        single_body_rmse: f64,
        #[serde(with = "float")]
        parts_rmse: f64,
        #[serde(with = "float")]
        explained: f64,
        parts: usize,
    }

    pub fn serialize<S: Serializer>(v: &Option<Diagnosis>, s: S) -> std::result::Result<S::Ok, S::Error> {
        v.as_ref()
            .map(|d| D {
                articulated: d.articulated,
                undecided: d.undecided,
                reason: d.reason.clone(),
                single_body_rmse: d.single_body_rmse,
                parts_rmse: d.parts_rmse,
                explained: d.explained,
                parts: d.parts,
            })
            .serialize(s)
    }

    pub fn deserialize<'de, D2: Deserializer<'de>>(d: D2) -> std::result::Result<Option<Diagnosis>, D2::Error> {
        Ok(Option::<D>::deserialize(d)?.map(|d| Diagnosis {
            articulated: d.articulated,
            undecided: d.undecided,
            reason: d.reason,
            single_body_rmse: d.single_body_rmse,
            parts_rmse: d.parts_rmse,
            explained: d.explained,
            parts: d.parts,
        }))
    }
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct Header {
    format: String,
    version: u32,
    /// The program that wrote the file ("posemfa 0.1.0").
    writer: String,
    population: PopulationHeader,
    params: Params,
    fit: FitHeader,
    summary: Summary,
    /// Version 2: a rig built from the fit ([`rig`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rig: Option<rig::RigHeader>,
    arrays: Vec<ArrayEntry>,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct PopulationHeader {
    vertices: usize,
    shapes: usize,
    triangles: usize,
    names: Vec<String>,
    source: String,
    normalization: Normalization,
    /// A glTF's animations that move its mesh and the one read.
    clips: Option<ClipsHeader>,
    /// The body holds the points (array `points`).
    data: bool,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct ClipsHeader {
    names: Vec<String>,
    read: usize,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct FitHeader {
    parts: usize,
    iterations: usize,
    converged: bool,
    #[serde(with = "floats")]
    log_likelihood: Vec<f64>,
    stages: StageParts,
    stats: Vec<StageStats>,
    complete: bool,
    part_curve: Vec<CurveHeader>,
    part_rounds: Vec<PartRound>,
    start_parts: Option<usize>,
    tree_count: Option<usize>,
    from_merge_tree: bool,
    count_unjudged: bool,
    refined: bool,
    parts_asked: Option<usize>,
    merge_tree: Option<TreeHeader>,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct TreeHeader {
    n_leaves: usize,
    merges: Vec<MergeHeader>,
    #[serde(with = "float")]
    typical: f64,
    #[serde(with = "float")]
    middle: f64,
}

/// One array of the body.
#[derive(Serialize, Deserialize, Clone)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
struct ArrayEntry {
    name: String,
    /// u8, u16, u32, f32 or f64.
    #[serde(rename = "type")]
    kind: String,
    /// raw (little-endian elements) or delta-varint (u32 only: each value minus the one before, zigzag, LEB128).
    encoding: String,
    count: u64,
    offset: u64,
    bytes: u64,
}

// ---------------------------------------------------------------- writing

/// The body as it is written: arrays appended at 8-byte offsets.
#[derive(Default)]
struct Body {
    bytes: Vec<u8>,
    entries: Vec<ArrayEntry>,
}

impl Body {
    fn push(&mut self, name: &str, kind: &str, encoding: &str, count: usize, data: &[u8]) {
        while self.bytes.len() % 8 != 0 {
            self.bytes.push(0);
        }
        self.entries.push(ArrayEntry {
            name: name.into(),
            kind: kind.into(),
            encoding: encoding.into(),
            count: count as u64,
            offset: self.bytes.len() as u64,
            bytes: data.len() as u64,
        });
        self.bytes.extend_from_slice(data);
    }

    /// Labels in the narrowest unsigned type that holds the largest.
    fn labels(&mut self, name: &str, v: &[u32]) {
        let max = v.iter().copied().max().unwrap_or(0);
        if max <= u8::MAX as u32 {
            let b: Vec<u8> = v.iter().map(|&x| x as u8).collect();
            self.push(name, "u8", "raw", v.len(), &b);
        } else if max <= u16::MAX as u32 {
            let b: Vec<u8> = v.iter().flat_map(|&x| (x as u16).to_le_bytes()).collect();
            self.push(name, "u16", "raw", v.len(), &b);
        } else {
            let b: Vec<u8> = v.iter().flat_map(|&x| x.to_le_bytes()).collect();
            self.push(name, "u32", "raw", v.len(), &b);
        }
    }

    fn f64s(&mut self, name: &str, v: &[f64]) {
        let b: Vec<u8> = v.iter().flat_map(|&x| x.to_le_bytes()).collect();
        self.push(name, "f64", "raw", v.len(), &b);
    }
}

/// Each value minus the one before (the first minus 0), zigzag-coded, as LEB128 varints: a mesh's triangles
/// name nearby vertices, so most take one or two bytes instead of four.
fn delta_varint(v: &[u32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(v.len() * 2);
    let mut prev = 0i64;
    for &x in v {
        let d = x as i64 - prev;
        prev = x as i64;
        let mut z = ((d << 1) ^ (d >> 63)) as u64;
        loop {
            let byte = (z & 0x7f) as u8;
            z >>= 7;
            if z == 0 {
                out.push(byte);
                break;
            }
            out.push(byte | 0x80);
        }
    }
    out
}

fn write(m: &Borrowed, with_points: bool, saved_rig: Option<&SavedRig>) -> Vec<u8> {
    let r = m.result;
    let pop = m.population;
    let model = &r.model;
    let mut body = Body::default();
    let flat_faces: Vec<u32> = pop.faces.iter().flatten().copied().collect();
    body.push("faces", "u32", "delta-varint", flat_faces.len(), &delta_varint(&flat_faces));
    body.labels("labels", &model.labels);
    body.labels("coarseLabels", &r.coarse_labels);
    body.labels("refinedLabels", &r.refined_labels);
    if let Some(d) = &r.decided_labels {
        body.labels("decidedLabels", d);
    }
    if let Some(t) = r.merge_tree() {
        body.labels("treeLeaves", &t.leaves);
    }
    if let Some(s) = &r.start_labels {
        body.labels("startLabels", s);
    }
    body.f64s("latent", model.latent.as_flattened());
    let mut parts = Vec::with_capacity(model.parts.len() * (model.n_shapes * 13 + 4));
    for c in &model.parts {
        parts.extend(c.rotations.iter().flat_map(|r| rows(r).into_iter().flatten()));
        parts.extend(c.translations.iter().flatten());
        parts.extend(&c.variances);
        parts.extend(c.lambda);
        parts.push(c.weight);
    }
    body.f64s("parts", &parts);
    if with_points {
        let b: Vec<u8> = (0..pop.n_shapes())
            .flat_map(|i| pop.shape(i).as_f32().iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>())
            .collect();
        body.push("points", "f32", "raw", pop.n_shapes() * pop.n_vertices() * 3, &b);
    }
    let rig = saved_rig.map(|r| rig::write(r, &mut body));
    let version = if rig.is_some() { 2 } else { 1 };
    let params = m.params.clone();
    let header = Header {
        format: FORMAT.into(),
        version,
        writer: format!("posemfa {}", env!("CARGO_PKG_VERSION")),
        population: PopulationHeader {
            vertices: pop.n_vertices(),
            shapes: pop.n_shapes(),
            triangles: pop.faces.len(),
            names: pop.names.clone(),
            source: pop.source.clone(),
            normalization: pop.normalization,
            clips: pop.clips.as_ref().map(|c| ClipsHeader { names: c.names.clone(), read: c.read }),
            data: with_points,
        },
        params,
        fit: FitHeader {
            parts: model.n_parts(),
            iterations: model.iterations,
            converged: model.converged,
            log_likelihood: model.log_likelihood.clone(),
            stages: r.stages,
            stats: r.stats.clone(),
            complete: r.complete,
            part_curve: r.part_curve.iter().map(CurveHeader::from).collect(),
            part_rounds: r.part_rounds.clone(),
            start_parts: r.start_parts(),
            tree_count: r.tree_count(),
            from_merge_tree: r.from_merge_tree(),
            count_unjudged: r.count_unjudged,
            refined: r.refined(),
            parts_asked: r.parts_asked,
            merge_tree: r.merge_tree().map(|t| TreeHeader {
                n_leaves: t.n_leaves,
                merges: t.merges.iter().map(MergeHeader::from).collect(),
                typical: t.typical,
                middle: t.middle_typical(),
            }),
        },
        summary: m.summary.clone(),
        rig,
        arrays: body.entries,
    };
    let json = serde_json::to_vec(&header).expect("the header is plain data");
    let mut out = Vec::with_capacity(PREFIX + json.len() + 8 + body.bytes.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&(body.bytes.len() as u64).to_le_bytes());
    out.extend_from_slice(&json);
    while out.len() % 8 != 0 {
        out.push(0);
    }
    out.extend_from_slice(&body.bytes);
    out
}

// ---------------------------------------------------------------- reading

/// The error for model file `file`: what is wrong and what to do.
fn bad(file: &str, message: impl Into<String>) -> Error {
    Error::ModelFile { file: file.to_string(), message: message.into() }
}

/// "the file is damaged ..." after a damaged field.
const DAMAGED: &str = "the file is damaged or was not written by posemfa; save the model again";

fn read(file: &str, bytes: &[u8]) -> Result<ModelFile> {
    if bytes.len() < PREFIX || &bytes[..8] != MAGIC {
        let hint = if bytes.len() >= 8 && &bytes[..8] == MAGIC {
            format!("it is cut short: {} bytes, fewer than the {PREFIX} of a model file's start", bytes.len())
        } else {
            "it does not start with a posemfa model file's signature (POSEMFA); open a .posemfa file written by \
             `posemfa fit --save` or the page's Save model"
                .to_string()
        };
        return Err(bad(file, format!("not a posemfa model file: {hint}")));
    }
    let u32_at = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = u32_at(8);
    if version == 0 || version > VERSION {
        return Err(bad(
            file,
            format!(
                "format version {version}: this posemfa ({}) reads model files of version 1 to {VERSION}; {}",
                env!("CARGO_PKG_VERSION"),
                if version == 0 {
                    DAMAGED
                } else {
                    "open it with a newer posemfa, or save the model again with this one"
                }
            ),
        ));
    }
    let header_len = u32_at(12) as u64;
    let body_len = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let body_start = (PREFIX as u64 + header_len).div_ceil(8) * 8;
    let expected = body_start.checked_add(body_len);
    if expected != Some(bytes.len() as u64) {
        let what = match expected {
            Some(e) if e > bytes.len() as u64 => {
                format!(
                    "it is cut short: its start promises {e} bytes, the file has {}; get the whole file again",
                    bytes.len()
                )
            }
            Some(e) => format!("{} bytes follow the {e} its start promises; {DAMAGED}", bytes.len() as u64 - e),
            None => format!("its start promises more bytes than any file holds; {DAMAGED}"),
        };
        return Err(bad(file, what));
    }
    let json = &bytes[PREFIX..PREFIX + header_len as usize];
    let body = &bytes[body_start as usize..];
    let de = &mut serde_json::Deserializer::from_slice(json);
    let header: Header = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        if path == "." || path.is_empty() {
            bad(file, format!("its header is not valid: {inner}; {DAMAGED}"))
        } else {
            bad(file, format!("header field {path}: {inner}; {DAMAGED}"))
        }
    })?;
    if header.format != FORMAT {
        return Err(bad(file, format!("header field format: '{}', not '{FORMAT}'; {DAMAGED}", header.format)));
    }
    if header.version != version {
        return Err(bad(
            file,
            format!("header field version: {} but the file's start says {version}; {DAMAGED}", header.version),
        ));
    }
    if header.version == 1 && header.rig.is_some() {
        return Err(bad(file, format!("header field rig: a version 1 file has no rig; {DAMAGED}")));
    }
    decode(file, header, body)
}

/// The arrays of the body by name, each checked against the table once.
struct Arrays<'a> {
    file: &'a str,
    body: &'a [u8],
    entries: Vec<ArrayEntry>,
}

impl<'a> Arrays<'a> {
    fn new(file: &'a str, body: &'a [u8], entries: Vec<ArrayEntry>) -> Result<Arrays<'a>> {
        const KNOWN: &[&str] = &[
            "faces",
            "labels",
            "coarseLabels",
            "refinedLabels",
            "decidedLabels",
            "treeLeaves",
            "startLabels",
            "latent",
            "parts",
            "points",
            "rigRest",
            "rigCounts",
            "rigBones",
            "rigWeights",
            "rigMotions",
            "rigJointPoints",
        ];
        for (k, e) in entries.iter().enumerate() {
            if !KNOWN.contains(&e.name.as_str()) {
                return Err(bad(file, format!("header field arrays[{k}].name: unknown array '{}'; {DAMAGED}", e.name)));
            }
            if entries[..k].iter().any(|o| o.name == e.name) {
                return Err(bad(file, format!("header field arrays[{k}]: array '{}' twice; {DAMAGED}", e.name)));
            }
            let end = e.offset.checked_add(e.bytes);
            if end.is_none_or(|end| end > body.len() as u64) {
                return Err(bad(
                    file,
                    format!(
                        "array '{}' claims bytes {} to {} of a body of {} bytes; {DAMAGED}",
                        e.name,
                        e.offset,
                        e.offset.saturating_add(e.bytes),
                        body.len()
                    ),
                ));
            }
        }
        Ok(Arrays { file, body, entries })
    }

    fn has(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e.name == name)
    }

    /// The entry `name` and its bytes, checked to hold `count` elements of one of `kinds`.
    fn entry(&self, name: &str, count: usize, kinds: &[&str]) -> Result<(&ArrayEntry, &'a [u8])> {
        let e = self.entries.iter().find(|e| e.name == name).ok_or_else(|| {
            bad(self.file, format!("the body has no array '{name}', which this model needs; {DAMAGED}"))
        })?;
        if !kinds.contains(&e.kind.as_str()) {
            return Err(bad(
                self.file,
                format!("array '{name}': type '{}', not one of {}; {DAMAGED}", e.kind, kinds.join(", ")),
            ));
        }
        if e.count != count as u64 {
            return Err(bad(
                self.file,
                format!("array '{name}': {} elements where the header's counts call for {count}; {DAMAGED}", e.count),
            ));
        }
        let width = match e.kind.as_str() {
            "u8" => 1,
            "u16" => 2,
            "u32" | "f32" => 4,
            _ => 8,
        };
        let bytes = &self.body[e.offset as usize..(e.offset + e.bytes) as usize];
        let fits = match e.encoding.as_str() {
            "raw" => e.bytes == e.count * width,
            "delta-varint" if e.kind == "u32" => e.count <= e.bytes,
            other => {
                return Err(bad(
                    self.file,
                    format!("array '{name}': encoding '{other}' (known: raw; delta-varint for u32); {DAMAGED}"),
                ))
            }
        };
        if !fits {
            return Err(bad(
                self.file,
                format!("array '{name}': {} bytes cannot hold {} {} elements; {DAMAGED}", e.bytes, e.count, e.kind),
            ));
        }
        Ok((e, bytes))
    }

    /// Unsigned integers (u8, u16 or u32; raw or delta-varint), each below `limit` (`what` says what they
    /// count).
    fn unsigned(&self, name: &str, count: usize, limit: usize, what: &str) -> Result<Vec<u32>> {
        let (e, b) = self.entry(name, count, &["u8", "u16", "u32"])?;
        let v: Vec<u32> = match (e.kind.as_str(), e.encoding.as_str()) {
            ("u8", _) => b.iter().map(|&x| x as u32).collect(),
            ("u16", _) => b.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]]) as u32).collect(),
            (_, "raw") => b.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
            _ => undelta_varint(b, count).map_err(|m| bad(self.file, format!("array '{name}': {m}; {DAMAGED}")))?,
        };
        if let Some(k) = v.iter().position(|&x| x as usize >= limit) {
            return Err(bad(
                self.file,
                format!("array '{name}', element {k}: {} where {what} go up to {}; {DAMAGED}", v[k], limit - 1),
            ));
        }
        Ok(v)
    }

    /// Finite f64 values.
    fn f64s(&self, name: &str, count: usize) -> Result<Vec<f64>> {
        let (_, b) = self.entry(name, count, &["f64"])?;
        let v: Vec<f64> = b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad(
                self.file,
                format!("array '{name}', element {k}: {} is not a finite number; {DAMAGED}", v[k]),
            ));
        }
        Ok(v)
    }

    /// Finite f32 values, in threes.
    fn points(&self, name: &str, count: usize) -> Result<Vec<[f32; 3]>> {
        let (_, b) = self.entry(name, count * 3, &["f32"])?;
        let v: Vec<[f32; 3]> = b
            .chunks_exact(12)
            .map(|c| {
                let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
                [f(0), f(4), f(8)]
            })
            .collect();
        if let Some(k) = v.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(bad(self.file, format!("array '{name}', point {k}: not finite ({:?}); {DAMAGED}", v[k])));
        }
        Ok(v)
    }
}

/// The inverse of [`delta_varint`]: exactly `count` values from exactly all of `b`.
fn undelta_varint(b: &[u8], count: usize) -> std::result::Result<Vec<u32>, String> {
    let mut out = Vec::with_capacity(count);
    let mut prev = 0i64;
    let mut at = 0;
    while out.len() < count {
        let mut z = 0u64;
        let mut shift = 0;
        loop {
            let Some(&byte) = b.get(at) else {
                return Err(format!("its bytes end inside value {} of {count}", out.len()));
            };
            at += 1;
            if shift > 35 {
                return Err(format!("value {} is longer than a 32-bit delta", out.len()));
            }
            z |= ((byte & 0x7f) as u64) << shift;
            shift += 7;
            if byte & 0x80 == 0 {
                break;
            }
        }
        let d = (z >> 1) as i64 ^ -((z & 1) as i64);
        let x = prev + d;
        if !(0..=u32::MAX as i64).contains(&x) {
            return Err(format!("value {} decodes to {x}, outside 0 to {}", out.len(), u32::MAX));
        }
        prev = x;
        out.push(x as u32);
    }
    if at != b.len() {
        return Err(format!("{} bytes left after its {count} values", b.len() - at));
    }
    Ok(out)
}

fn decode(file: &str, h: Header, body: &[u8]) -> Result<ModelFile> {
    let p = &h.population;
    let (nv, ns, nf, np) = (p.vertices, p.shapes, p.triangles, h.fit.parts);
    let field = |name: &str, what: String| bad(file, format!("header field {name}: {what}; {DAMAGED}"));
    if nv == 0 || nv > u32::MAX as usize {
        return Err(field("population.vertices", format!("{nv} vertices")));
    }
    if ns < 2 {
        return Err(field("population.shapes", format!("{ns} poses, a population has at least 2")));
    }
    if nf == 0 {
        return Err(field("population.triangles", "no triangles".into()));
    }
    if p.names.len() != ns {
        return Err(field("population.names", format!("{} names for {ns} poses", p.names.len())));
    }
    if np == 0 || np > nv {
        return Err(field("fit.parts", format!("{np} parts for {nv} vertices")));
    }
    if h.fit.log_likelihood.len() > h.fit.iterations.saturating_add(1) {
        return Err(field(
            "fit.logLikelihood",
            format!("{} values for {} iterations", h.fit.log_likelihood.len(), h.fit.iterations),
        ));
    }
    if let Some(c) = &p.clips {
        if c.read >= c.names.len() {
            return Err(field("population.clips.read", format!("{} of {} clips", c.read, c.names.len())));
        }
    }
    if !(p.normalization.scale.is_finite() && p.normalization.scale > 0.0)
        || p.normalization.offset.iter().any(|x| !x.is_finite())
    {
        return Err(field("population.normalization", "not a finite offset and a positive scale".into()));
    }
    h.params.validate().map_err(|e| bad(file, format!("header field params: {e}; {DAMAGED}")))?;
    // every array is checked against the body's length before anything the size of the mesh is made
    let a = Arrays::new(file, body, h.arrays)?;
    if p.data && !a.has("points") {
        return Err(bad(
            file,
            format!("the header says it holds the population but the body has no points; {DAMAGED}"),
        ));
    }
    if !p.data && a.has("points") {
        return Err(field("population.data", "false, yet the body has the population's points".into()));
    }
    let faces_flat = a.unsigned("faces", nf.checked_mul(3).unwrap_or(usize::MAX), nv, "the vertices")?;
    let faces: Vec<[u32; 3]> = faces_flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let labels = a.unsigned("labels", nv, np, "the parts")?;
    let coarse_labels = a.unsigned("coarseLabels", nv, nv, "the vertices")?;
    let refined_labels = a.unsigned("refinedLabels", nv, nv, "the vertices")?;
    let decided_labels =
        a.has("decidedLabels").then(|| a.unsigned("decidedLabels", nv, nv, "the vertices")).transpose()?;
    let start_labels = a.has("startLabels").then(|| a.unsigned("startLabels", nv, nv, "the vertices")).transpose()?;
    let latent_flat = a.f64s("latent", nv.checked_mul(3).unwrap_or(usize::MAX))?;
    let latent: Vec<Vec3> = latent_flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    // (after the per-vertex arrays: they bound the vertex count by the body's bytes)
    let merge_tree = match h.fit.merge_tree {
        None if a.has("treeLeaves") => {
            return Err(field("fit.mergeTree", "null, yet the body has the tree's leaves".into()));
        }
        None => None,
        Some(t) => {
            if t.n_leaves == 0 || t.n_leaves > nv || t.merges.len() >= t.n_leaves {
                return Err(field(
                    "fit.mergeTree",
                    format!("{} leaves and {} merges for {nv} vertices", t.n_leaves, t.merges.len()),
                ));
            }
            let mut used = vec![false; t.n_leaves + t.merges.len()];
            for (m, mg) in t.merges.iter().enumerate() {
                let id = t.n_leaves + m;
                for child in [mg.a as usize, mg.b as usize] {
                    if child >= id || used[child] || mg.a == mg.b {
                        return Err(field(
                            &format!("fit.mergeTree.merges[{m}]"),
                            format!("merges nodes {} and {}, not two distinct earlier nodes", mg.a, mg.b),
                        ));
                    }
                    used[child] = true;
                }
            }
            let leaves = a.unsigned("treeLeaves", nv, t.n_leaves, "the tree's leaves")?;
            let merges = t.merges.into_iter().map(Merge::from).collect();
            Some(MergeTree::from_saved(leaves, t.n_leaves, merges, t.typical, t.middle))
        }
    };
    let per_part = ns * 13 + 4;
    let flat = a.f64s("parts", np.checked_mul(per_part).unwrap_or(usize::MAX))?;
    let mut parts = Vec::with_capacity(np);
    for (k, c) in flat.chunks_exact(per_part).enumerate() {
        let rotations: Vec<Mat3> = c[..ns * 9]
            .chunks_exact(9)
            .map(|r| from_rows([[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]]))
            .collect();
        if let Some(i) = rotations
            .iter()
            .position(|r| (r.transpose() * r - Mat3::identity()).abs().max() > 1e-6 || r.determinant() < 0.0)
        {
            return Err(bad(
                file,
                format!("array 'parts': part {} in pose {} is not a rotation; {DAMAGED}", k + 1, i + 1),
            ));
        }
        let translations: Vec<Vec3> = c[ns * 9..ns * 12].chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let variances = c[ns * 12..ns * 13].to_vec();
        if let Some(i) = variances.iter().position(|&s| s <= 0.0) {
            return Err(bad(
                file,
                format!("array 'parts': part {} has variance {} in pose {}; {DAMAGED}", k + 1, variances[i], i + 1),
            ));
        }
        let lambda = [c[ns * 13], c[ns * 13 + 1], c[ns * 13 + 2]];
        let weight = c[ns * 13 + 3];
        if !(weight > 0.0 && weight <= 1.0 + 1e-9) {
            return Err(bad(file, format!("array 'parts': part {} has mixing weight {weight}; {DAMAGED}", k + 1)));
        }
        parts.push(Component { rotations, translations, lambda, variances, weight });
    }
    let model = Model {
        n_shapes: ns,
        n_vertices: nv,
        parts,
        labels,
        latent,
        log_likelihood: h.fit.log_likelihood,
        iterations: h.fit.iterations,
        converged: h.fit.converged,
    };
    let points = if p.data {
        a.points("points", nv.checked_mul(ns).unwrap_or(usize::MAX))?
    } else {
        // the model's reconstruction of every pose stands in for the data
        crate::memory::check(nv, ns, 1, crate::memory::budget_bytes()?)?;
        (0..ns).flat_map(|i| model.reconstruct(i)).map(crate::mesh::population::narrow).collect()
    };
    let mut population = Population::new(crate::mesh::Sources::Saved(crate::mesh::Saved {
        file: file.into(),
        names: p.names.clone(),
        faces,
        points,
        normalization: p.normalization,
        source: p.source.clone(),
    }))?;
    population.clips = p.clips.as_ref().map(|c| crate::mesh::gltf::Clips { names: c.names.clone(), read: c.read });
    let params = h.params;
    // the rule's own report: a file written from a fit has the merge tree's fields only with that rule, and
    // that rule always refines
    let rule = match h.fit.from_merge_tree {
        true if !h.fit.refined => {
            return Err(field(
                "fit.refined",
                "false, yet the parts came from the merge tree, which always refines; save the model again".into(),
            ));
        }
        true => RuleReport::MergeTree { start_parts: h.fit.start_parts, merge_tree, tree_count: h.fit.tree_count },
        false if h.fit.start_parts.is_some() || h.fit.tree_count.is_some() || merge_tree.is_some() => {
            return Err(field(
                "fit.fromMergeTree",
                "false, yet the fit has the merge tree's start, tree or count; save the model again".into(),
            ));
        }
        false => RuleReport::Algorithm1 { refined: h.fit.refined },
    };
    let result = FitResult {
        model,
        coarse_labels,
        refined_labels,
        stages: h.fit.stages,
        stats: h.fit.stats,
        complete: h.fit.complete,
        part_curve: h.fit.part_curve.into_iter().map(CurvePoint::from).collect(),
        part_rounds: h.fit.part_rounds,
        decided_labels,
        count_unjudged: h.fit.count_unjudged,
        parts_asked: h.fit.parts_asked,
        start_labels,
        rule,
    };
    let rig = match h.rig {
        Some(r) => Some(rig::read(file, r, &a, nv, ns, np)?),
        None if a.has("rigRest") => return Err(field("rig", "null, yet the body has a rig's arrays".into())),
        None => None,
    };
    Ok(ModelFile { result, params, population, has_data: p.data, summary: h.summary, rig })
}

/// Whether `bytes` start like a model file (for readers that take any file by its content).
pub fn looks_like(bytes: &[u8]) -> bool {
    bytes.len() >= 8 && &bytes[..8] == MAGIC
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delta_varint_round_trips_and_refuses_damage() {
        let v = vec![0, 1, 2, 5000, 4999, u32::MAX, 0, 7, 7, 128, 127];
        let b = delta_varint(&v);
        assert_eq!(undelta_varint(&b, v.len()).unwrap(), v);
        assert!(undelta_varint(&b[..b.len() - 1], v.len()).is_err());
        assert!(undelta_varint(&b, v.len() - 1).unwrap_err().contains("left after"));
        // a run of continuation bytes is not read past 5 bytes
        assert!(undelta_varint(&[0xff; 20], 1).unwrap_err().contains("longer"));
        // a delta below 0 from the first value
        assert!(undelta_varint(&[1], 1).unwrap_err().contains("outside"));
    }
}
