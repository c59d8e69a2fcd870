//! USD import (`.usda` text, `.usdc` binary crate files, `.usdz` packages, `.usd` either): the poses of one
//! point-cached mesh. The layer is parsed by the `openusd` crate (pure Rust, all three encodings; its
//! layer-level data only: no composition, so a mesh brought in by a reference or payload from another file is
//! not seen); this module reads the prims.
//!
//! Which mesh: the UsdGeomMesh whose `points` are time-sampled with the most points, or the one named by
//! [`Options::mesh`] (`--object NAME`: the prim's name or path, or its index in the layer's path order). One pose per time sample of its `points`
//! (or [`Options::frames`] of them, evenly spread). Each pose has the mesh's and its ancestors' xformOps
//! applied at that time (translate, scale, rotateX/Y/Z, rotateXYZ and the other orders, orient, transform,
//! `!invert!`, `!resetXformStack!`; time-sampled ops interpolated linearly, held beyond their ends).
//! `faceVertexCounts` / `faceVertexIndices` are fan-triangulated as the OBJ reader does.
//!
//! The stage's `upAxis` Z is turned to Y up (as glTF), and an authored `metersPerUnit` to metres; the source
//! says which. Skinned UsdSkel meshes (points not time-sampled) are refused with a message saying that only
//! point-cached meshes are read. Points that are exact duplicates in the first pose are welded.

use super::fbx::weld;
use super::gltf::{Gltf, Options};
use crate::error::{Error, Result};
use nalgebra::{Matrix4, Point3, Rotation3, UnitQuaternion, Vector3};
use openusd::sdf::{self, AbstractData, Value};
use std::io::Cursor;

type DVec3 = Vector3<f64>;
type DMat4 = Matrix4<f64>;

fn err(file: &str, message: String) -> Error {
    Error::Mesh { format: crate::error::Format::Usd, file: file.to_string(), line: 0, message }
}

fn damaged(file: &str, what: &str, e: impl std::fmt::Display) -> Error {
    err(file, format!("cannot read the {what}: {e:#}; the file is cut or damaged: export it again"))
}

/// A crate layer (a .usdc file, or the crate layer of a .usdz): checked by [`super::usdc_check`] first, which
/// refuses what would make openusd 0.6.0 allocate beyond the file or panic, then read by openusd.
fn crate_layer(file: &str, bytes: &[u8], what: &str) -> Result<Box<dyn AbstractData>> {
    let memory = crate::memory::budget_bytes()?;
    super::usdc_check::check(bytes, memory).map_err(|m| err(file, format!("cannot read the {what}: {m}")))?;
    let data = openusd::usdc::CrateData::open(Cursor::new(bytes.to_vec()), true).map_err(|e| damaged(file, what, e))?;
    Ok(Box::new(data))
}

/// Deepest nesting of brackets a USDA layer may have. A stage nests prims, dictionaries and arrays a few dozen
/// levels at most; openusd's parser descends once per level (about a kilobyte of stack each natively, more of
/// the 1 MiB a wasm module has), so a file of a few thousand opening braces would overflow the stack and abort
/// the process (or trap the page's worker) instead of being refused.
pub const USDA_MAX_NESTING: usize = 128;

/// Deepest nesting of arrays (`[`) a USDA layer may have. Real stages nest arrays two or three deep (an array of
/// tuples); openusd writes an array of arrays in metadata as the escaped text of its elements, so the text
/// doubles with every level: a 654-byte file nesting arrays 40 deep (found by the fuzzer) ran for minutes and
/// took gigabytes. At 16 levels it takes milliseconds.
pub const USDA_MAX_ARRAY_NESTING: usize = 16;

/// Where `text`'s brackets nest too deep ([`usda_too_deep`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct TooDeep {
    line: usize,
    /// "brackets" (all of `{ ( [`) or "arrays" (`[`).
    what: &'static str,
    limit: usize,
}

/// The first place where `text`'s brackets (`{ ( [`) nest deeper than [`USDA_MAX_NESTING`], or its arrays
/// (`[`) deeper than [`USDA_MAX_ARRAY_NESTING`]; None when neither does. Brackets inside strings (`"..."`,
/// `'...'`, triple-quoted), asset paths (`@...@`, `@@@...@@@`) and comments (`#` to the end of the line) do not
/// count.
fn usda_too_deep(text: &str) -> Option<TooDeep> {
    let b = text.as_bytes();
    let (mut i, mut depth, mut arrays, mut line) = (0usize, 0usize, 0usize, 1usize);
    // the end of a quoted run opening at `i` with delimiter `q` (`len` 1 or 3), escapes skipped; lines counted
    let skip = |mut i: usize, q: &[u8], line: &mut usize| -> usize {
        i += q.len();
        while i < b.len() {
            if b[i..].starts_with(q) {
                return i + q.len();
            }
            if b[i] == b'\\' && q.len() == 1 && q[0] != b'@' {
                i += 1;
            } else if b[i] == b'\n' {
                *line += 1;
            }
            i += 1;
        }
        i
    };
    while i < b.len() {
        match b[i] {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            q @ (b'"' | b'\'' | b'@') => {
                let triple = [q; 3];
                let delim: &[u8] = if b[i..].starts_with(&triple) { &triple } else { &triple[..1] };
                i = skip(i, delim, &mut line);
            }
            c @ (b'{' | b'(' | b'[') => {
                depth += 1;
                arrays += usize::from(c == b'[');
                if depth > USDA_MAX_NESTING {
                    return Some(TooDeep { line, what: "brackets", limit: USDA_MAX_NESTING });
                }
                if arrays > USDA_MAX_ARRAY_NESTING {
                    return Some(TooDeep { line, what: "arrays", limit: USDA_MAX_ARRAY_NESTING });
                }
                i += 1;
            }
            c @ (b'}' | b')' | b']') => {
                depth = depth.saturating_sub(1);
                if c == b']' {
                    arrays = arrays.saturating_sub(1);
                }
                i += 1;
            }
            _ => i += 1,
        }
    }
    None
}

/// A USDA layer: its nesting checked ([`usda_too_deep`]), then read by openusd.
fn text_layer(file: &str, text: &str, what: &str) -> Result<Box<dyn AbstractData>> {
    if let Some(TooDeep { line, what: nested, limit }) = usda_too_deep(text) {
        return Err(err(
            file,
            format!(
                "cannot read the {what}: line {line}: its {nested} nest deeper than {limit} levels, \
                 far deeper than a stage nests prims and values; the file is damaged, or not a stage a USD tool \
                 wrote: export it again"
            ),
        ));
    }
    let data = openusd::usda::parse(text).map_err(|e| damaged(file, what, e))?;
    Ok(Box::new(data))
}

/// Which encoding the bytes are in.
fn layer(file: &str, bytes: &[u8]) -> Result<Box<dyn AbstractData>> {
    if bytes.starts_with(b"PXR-USDC") {
        return crate_layer(file, bytes, "USD crate file (usdc)");
    }
    if bytes.starts_with(b"PK\x03\x04") {
        // The package is opened here (not with openusd's usdz::Archive, which hands its layer to openusd
        // unseen) so that a crate layer is checked like a .usdc file. The root layer is the first .usda /
        // .usdc / .usd entry (the USDZ spec), told apart by its extension, a .usd by its first bytes.
        let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| damaged(file, "USDZ package (zip)", e))?;
        let Some(name) = zip
            .file_names()
            .find(|n| n.ends_with(".usdc") || n.ends_with(".usda") || n.ends_with(".usd"))
            .map(String::from)
        else {
            return Err(err(
                file,
                "the USDZ package holds no .usda, .usdc or .usd layer; package the stage again (usdzip)".into(),
            ));
        };
        let what = "first layer of the USDZ package";
        let mut layer_bytes = Vec::new();
        {
            use std::io::Read;
            let mut entry = zip.by_name(&name).map_err(|e| damaged(file, what, e))?;
            entry.read_to_end(&mut layer_bytes).map_err(|e| damaged(file, what, e))?;
        }
        let is_crate = name.ends_with(".usdc") || (!name.ends_with(".usda") && layer_bytes.starts_with(b"PXR-USDC"));
        if is_crate {
            return crate_layer(file, &layer_bytes, what);
        }
        let text = String::from_utf8(layer_bytes)
            .map_err(|e| damaged(file, what, format!("{name} is not UTF-8 text: {e}")))?;
        return text_layer(file, &text, what);
    }
    if bytes.starts_with(b"#usda") {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            err(
                file,
                format!("the USDA text is not UTF-8 (byte {}); the file is damaged: export it again", e.valid_up_to()),
            )
        })?;
        return text_layer(file, text, "USDA text");
    }
    Err(err(
        file,
        "is not a USD file (it starts with neither \"#usda\", \"PXR-USDC\" nor a zip header); the file is damaged or has \
         the wrong extension: export it again as .usda, .usdc or .usdz"
            .into(),
    ))
}

fn field(data: &dyn AbstractData, path: &sdf::Path, name: &str) -> Option<Value> {
    data.try_field(path, name).ok().flatten().map(|c| c.into_owned())
}

fn prop(path: &sdf::Path, name: &str) -> Option<sdf::Path> {
    path.append_property(name).ok()
}

/// A value as f64 numbers (scalars, vectors, matrices, quaternions as w x y z).
fn numbers(v: &Value) -> Option<Vec<f64>> {
    Some(match v {
        Value::Float(x) => vec![f64::from(*x)],
        Value::Double(x) => vec![*x],
        Value::Half(x) => vec![f64::from(x.to_f32())],
        Value::Int(x) => vec![f64::from(*x)],
        Value::Vec3f(v) => vec![v.x.into(), v.y.into(), v.z.into()],
        Value::Vec3d(v) => vec![v.x, v.y, v.z],
        Value::Vec3h(v) => vec![v.x.to_f32().into(), v.y.to_f32().into(), v.z.to_f32().into()],
        Value::Quatf(q) => vec![q.w.into(), q.x.into(), q.y.into(), q.z.into()],
        Value::Quatd(q) => vec![q.w, q.x, q.y, q.z],
        Value::Quath(q) => vec![q.w.to_f32().into(), q.x.to_f32().into(), q.y.to_f32().into(), q.z.to_f32().into()],
        Value::Matrix4d(m) => m.0.to_vec(),
        _ => return None,
    })
}

/// Points of a `points` value.
fn points(v: &Value) -> Option<Vec<DVec3>> {
    Some(match v {
        Value::Vec3fVec(p) => p.iter().map(|v| DVec3::new(v.x.into(), v.y.into(), v.z.into())).collect(),
        Value::Vec3dVec(p) => p.iter().map(|v| DVec3::new(v.x, v.y, v.z)).collect(),
        Value::Vec3hVec(p) => {
            p.iter().map(|v| DVec3::new(v.x.to_f32().into(), v.y.to_f32().into(), v.z.to_f32().into())).collect()
        }
        _ => return None,
    })
}

fn ints(v: &Value) -> Option<Vec<i64>> {
    Some(match v {
        Value::IntVec(p) => p.iter().map(|&x| i64::from(x)).collect(),
        Value::Int64Vec(p) => p.clone(),
        Value::UintVec(p) => p.iter().map(|&x| i64::from(x)).collect(),
        _ => return None,
    })
}

/// An attribute: its default and its time samples (sorted by time).
struct Attr {
    default: Option<Value>,
    samples: Vec<(f64, Value)>,
}

fn attr(data: &dyn AbstractData, prim: &sdf::Path, name: &str) -> Option<Attr> {
    let p = prop(prim, name)?;
    if !data.has_spec(&p) {
        return None;
    }
    let default = field(data, &p, "default").filter(|v| !matches!(v, Value::ValueBlock | Value::None));
    let mut samples = match field(data, &p, "timeSamples") {
        Some(Value::TimeSamples(s)) => {
            s.into_iter().filter(|(t, v)| t.is_finite() && !matches!(v, Value::ValueBlock)).collect()
        }
        _ => Vec::new(),
    };
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    Some(Attr { default, samples })
}

impl Attr {
    /// Numbers at time `t`: linear between samples, held beyond the ends; the default without samples.
    fn numbers_at(&self, t: f64) -> Option<Vec<f64>> {
        if self.samples.is_empty() {
            return self.default.as_ref().and_then(numbers);
        }
        let k = self.samples.partition_point(|(x, _)| *x <= t);
        if k == 0 {
            return numbers(&self.samples[0].1);
        }
        if k >= self.samples.len() {
            return numbers(&self.samples[k - 1].1);
        }
        let (t0, v0) = (&self.samples[k - 1].0, numbers(&self.samples[k - 1].1)?);
        let (t1, v1) = (&self.samples[k].0, numbers(&self.samples[k].1)?);
        if v0.len() != v1.len() || t1 <= t0 {
            return Some(v0);
        }
        let u = (t - t0) / (t1 - t0);
        if v0.len() == 4 && matches!(self.samples[k].1, Value::Quatf(_) | Value::Quatd(_) | Value::Quath(_)) {
            let q0 = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(v0[0], v0[1], v0[2], v0[3]));
            let q1 = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(v1[0], v1[1], v1[2], v1[3]));
            let q = q0.try_slerp(&q1, u, 1e-12).unwrap_or(q0);
            return Some(vec![q.w, q.i, q.j, q.k]);
        }
        Some(v0.iter().zip(&v1).map(|(a, b)| a + (b - a) * u).collect())
    }
}

fn axis_rotation(axis: char, deg: f64) -> Rotation3<f64> {
    let a = match axis {
        'X' => Vector3::x_axis(),
        'Y' => Vector3::y_axis(),
        _ => Vector3::z_axis(),
    };
    Rotation3::from_axis_angle(&a, deg.to_radians())
}

/// The local transform of a prim at time `t` (its xformOpOrder), and whether it resets the parent's.
fn local_transform(file: &str, data: &dyn AbstractData, prim: &sdf::Path, t: f64) -> Result<(DMat4, bool)> {
    let order = match attr(data, prim, "xformOpOrder").and_then(|a| a.default) {
        Some(Value::TokenVec(v)) => v.iter().map(|t| t.as_str().to_string()).collect::<Vec<_>>(),
        _ => return Ok((DMat4::identity(), false)),
    };
    let mut m = DMat4::identity();
    let mut reset = false;
    for op in &order {
        if op == "!resetXformStack!" {
            reset = true;
            m = DMat4::identity();
            continue;
        }
        let (invert, name) = match op.strip_prefix("!invert!") {
            Some(n) => (true, n),
            None => (false, op.as_str()),
        };
        let kind = name.strip_prefix("xformOp:").unwrap_or(name).split(':').next().unwrap_or("");
        let values = attr(data, prim, name).and_then(|a| a.numbers_at(t)).ok_or_else(|| {
            err(
                file,
                format!(
                    "prim {prim}: xformOpOrder names {name}, which has no value; the file is damaged: export it again"
                ),
            )
        })?;
        let bad = || {
            err(file, format!("prim {prim}: {name} holds {} numbers, not what a {kind} op takes; the file is damaged: export it again", values.len()))
        };
        let v3 = || -> Result<DVec3> {
            if values.len() == 3 {
                Ok(DVec3::new(values[0], values[1], values[2]))
            } else {
                Err(bad())
            }
        };
        let one = || -> Result<f64> {
            if values.len() == 1 {
                Ok(values[0])
            } else {
                Err(bad())
            }
        };
        let op_m = match kind {
            "translate" => Matrix4::new_translation(&v3()?),
            "scale" => {
                if values.len() == 1 {
                    Matrix4::new_scaling(values[0])
                } else {
                    Matrix4::new_nonuniform_scaling(&v3()?)
                }
            }
            "rotateX" | "rotateY" | "rotateZ" => axis_rotation(kind.chars().last().unwrap_or('Z'), one()?).to_homogeneous(),
            "orient" => {
                if values.len() != 4 {
                    return Err(bad());
                }
                UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(values[0], values[1], values[2], values[3])).to_homogeneous()
            }
            "transform" => {
                if values.len() != 16 {
                    return Err(bad());
                }
                // USD matrices are row-major for row vectors: the transpose of the column-vector matrix.
                DMat4::from_row_slice(&values).transpose()
            }
            k if k.len() == 9 && k.starts_with("rotate") => {
                let v = v3()?;
                // rotateXYZ: X applied first, so the column-vector matrix is Rz * Ry * Rx.
                let mut r = Rotation3::identity();
                for axis in k[6..].chars() {
                    let deg = match axis {
                        'X' => v.x,
                        'Y' => v.y,
                        _ => v.z,
                    };
                    r = axis_rotation(axis, deg) * r;
                }
                r.to_homogeneous()
            }
            other => {
                return Err(err(
                    file,
                    format!("prim {prim}: xformOp {name} is of the unknown kind `{other}`; export the transforms as translate / rotate / scale / orient / transform ops"),
                ))
            }
        };
        let op_m = if invert { op_m.try_inverse().unwrap_or_else(DMat4::identity) } else { op_m };
        m *= op_m;
    }
    Ok((m, reset))
}

/// The world transform of a prim at time `t`: its ancestors' local transforms, then its own.
fn world_transform(file: &str, data: &dyn AbstractData, prim: &sdf::Path, t: f64) -> Result<DMat4> {
    let mut chain: Vec<sdf::Path> = Vec::new();
    let mut cur = Some(prim.clone());
    while let Some(p) = cur {
        if p.is_abs_root() || p.is_empty() {
            break;
        }
        cur = p.parent();
        chain.push(p);
        if chain.len() > 4096 {
            break;
        }
    }
    let mut m = DMat4::identity();
    for p in chain.iter().rev() {
        let (l, reset) = local_transform(file, data, p, t)?;
        m = if reset { l } else { m * l };
    }
    Ok(m)
}

/// Reads the poses of one point-cached mesh of a USD file.
pub fn read(file: &str, bytes: &[u8], options: &Options) -> Result<Gltf> {
    let data = layer(file, bytes)?;
    let data: &dyn AbstractData = data.as_ref();
    let root = sdf::Path::abs_root();
    let meshes: Vec<sdf::Path> = data
        .spec_paths()
        .into_iter()
        .filter(|p| data.spec_type(p) == Some(sdf::SpecType::Prim))
        .filter(|p| field(data, p, "typeName").as_ref().and_then(Value::as_str) == Some("Mesh"))
        .collect();
    if meshes.is_empty() {
        return Err(err(
            file,
            "the stage holds no Mesh prim (UsdGeomMesh); export the character's mesh (with its points time-sampled)"
                .into(),
        ));
    }
    let name_of = |p: &sdf::Path| p.name().unwrap_or("").to_string();
    let samples_of = |p: &sdf::Path| attr(data, p, "points").map_or(0, |a| a.samples.len());
    let mesh = match &options.mesh {
        Some(w) => meshes
            .iter()
            .enumerate()
            .find(|(i, p)| name_of(p) == *w || p.to_string() == *w || i.to_string() == *w)
            .map(|(_, p)| p.clone())
            .ok_or_else(|| {
                let names: Vec<String> = meshes.iter().map(|p| p.to_string()).collect();
                err(file, format!("no mesh is called or numbered `{w}`; the stage has {}", names.join(", ")))
            })?,
        None => {
            let count = |p: &sdf::Path| {
                let a = attr(data, p, "points");
                a.and_then(|a| a.samples.first().map(|s| s.1.clone()).or(a.default))
                    .and_then(|v| points(&v))
                    .map_or(0, |v| v.len())
            };
            let animated: Vec<&sdf::Path> = meshes.iter().filter(|p| samples_of(p) >= 2).collect();
            let pool: Vec<&sdf::Path> = if animated.is_empty() { meshes.iter().collect() } else { animated };
            let mut best = pool[0];
            for p in &pool {
                if count(p) > count(best) {
                    best = p;
                }
            }
            best.clone()
        }
    };
    let mname = name_of(&mesh);
    let pts = attr(data, &mesh, "points")
        .ok_or_else(|| err(file, format!("mesh {mesh} has no points; export the mesh with its points")))?;
    if pts.samples.len() < 2 {
        let skinned = data.has_spec(&prop(&mesh, "skel:skeleton").unwrap_or_else(|| root.clone()))
            || data.has_spec(&prop(&mesh, "primvars:skel:jointIndices").unwrap_or_else(|| root.clone()));
        let what = if skinned { "is a skinned UsdSkel mesh" } else { "has no time-sampled points" };
        return Err(err(
            file,
            format!(
                "mesh {mesh} {what}; posemfa reads only point-cached meshes from USD (a UsdGeomMesh whose points are \
                 time-sampled, one pose per sample): bake the animation to points (e.g. Blender's USD export of the \
                 evaluated mesh), or export the character as FBX or glTF"
            ),
        ));
    }
    let counts =
        attr(data, &mesh, "faceVertexCounts").and_then(|a| a.default.or(a.samples.into_iter().next().map(|s| s.1)));
    let indices =
        attr(data, &mesh, "faceVertexIndices").and_then(|a| a.default.or(a.samples.into_iter().next().map(|s| s.1)));
    let (Some(counts), Some(indices)) = (counts.as_ref().and_then(ints), indices.as_ref().and_then(ints)) else {
        return Err(err(file, format!("mesh {mesh} has no faceVertexCounts / faceVertexIndices (as int arrays); export the mesh with its faces")));
    };
    let first = points(&pts.samples[0].1).ok_or_else(|| {
        err(
            file,
            format!(
                "mesh {mesh}: points at time {} are not an array of 3-vectors; the file is damaged: export it again",
                pts.samples[0].0
            ),
        )
    })?;
    let n = first.len();
    // (in i128: an int64 or uint array of counts may add up beyond i64)
    let total: i128 = counts.iter().map(|&c| i128::from(c.max(0))).sum();
    if counts.iter().any(|&c| c < 0) || total != indices.len() as i128 {
        return Err(err(
            file,
            format!("mesh {mesh}: faceVertexCounts add up to {total} corners but faceVertexIndices has {}; the file is damaged: export it again", indices.len()),
        ));
    }
    let mut faces = Vec::with_capacity(indices.len());
    let mut at = 0usize;
    for &c in &counts {
        let corners = &indices[at..at + c as usize];
        at += c as usize;
        if let Some((k, &bad)) = corners.iter().enumerate().find(|(_, &i)| i < 0 || i as u64 >= n as u64) {
            return Err(err(
                file,
                format!("mesh {mesh}: faceVertexIndices[{}] names point {bad}, but the mesh has {n}; the file is damaged: export it again", at - c as usize + k),
            ));
        }
        if let Some((&f0, rest)) = corners.split_first() {
            for w in rest.windows(2) {
                faces.push([f0 as u32, w[0] as u32, w[1] as u32]);
            }
        }
    }
    if faces.is_empty() {
        return Err(err(
            file,
            format!("mesh {mesh} has no faces with 3 or more corners; posemfa needs a polygon mesh"),
        ));
    }

    // Stage metadata: up axis, metres per unit, time codes per second.
    let up =
        field(data, &root, "upAxis").as_ref().and_then(Value::as_str).map(str::to_string).unwrap_or_else(|| "Y".into());
    let mpu = field(data, &root, "metersPerUnit")
        .as_ref()
        .and_then(numbers)
        .and_then(|v| v.first().copied())
        .filter(|m| m.is_finite() && *m > 0.0);
    let tcps = field(data, &root, "timeCodesPerSecond")
        .as_ref()
        .and_then(numbers)
        .and_then(|v| v.first().copied())
        .filter(|f| f.is_finite() && *f > 0.0)
        .unwrap_or(24.0);
    let up_m = if up == "Z" {
        Rotation3::from_axis_angle(&Vector3::x_axis(), -std::f64::consts::FRAC_PI_2).to_homogeneous()
    } else {
        DMat4::identity()
    };
    let stage_m = Matrix4::new_scaling(mpu.unwrap_or(1.0)) * up_m;
    let units = match mpu {
        Some(m) if m == 1.0 => "metersPerUnit 1".to_string(),
        Some(m) => format!("metersPerUnit {m} turned to metres"),
        None => "metersPerUnit not stated: lengths as in the file".to_string(),
    };
    let axes = if up == "Z" { "upAxis Z turned to Y up" } else { "upAxis Y" };

    let times: Vec<usize> = match options.frames {
        Some(0) => return Err(err(file, "--frames must be at least 1".into())),
        Some(f) => {
            let last = pts.samples.len() - 1;
            (0..f).map(|i| if f == 1 { 0 } else { (i * last + (f - 1) / 2) / (f - 1) }).collect()
        }
        None => (0..pts.samples.len()).collect(),
    };
    crate::memory::check(n, times.len(), 1, crate::memory::budget_bytes()?)
        .map_err(|e| err(file, format!("mesh {mesh} at {} time samples: {e}; read fewer (--frames N)", times.len())))?;
    let w = times.len().to_string().len();
    let mut poses_raw = Vec::with_capacity(times.len());
    for (i, &k) in times.iter().enumerate() {
        let (t, v) = &pts.samples[k];
        let p = points(v).ok_or_else(|| err(file, format!("mesh {mesh}: points at time {t} are not an array of 3-vectors; the file is damaged: export it again")))?;
        if p.len() != n {
            return Err(err(file, format!("mesh {mesh}: points at time {t} has {} points but {n} at time {}; a point cache keeps its points: export it again", p.len(), pts.samples[0].0)));
        }
        let m = stage_m * world_transform(file, data, &mesh, *t)?;
        let posed: Vec<DVec3> = p.iter().map(|v| m.transform_point(&Point3::from(*v)).coords).collect();
        if posed.iter().any(|v| !v.iter().all(|x| x.is_finite())) {
            return Err(err(file, format!("mesh {mesh} at time {t}: coordinates are not finite numbers (a point or transform holds NaN or infinity); the file is damaged: export it again")));
        }
        poses_raw.push((format!("time {:0w$} ({t})", i + 1), posed));
    }
    let (t0, t1) = (pts.samples[0].0, pts.samples[pts.samples.len() - 1].0);
    let how = match options.frames {
        Some(f) => format!("{f} of its {} time samples", pts.samples.len()),
        None => format!("one per time sample, times {t0} to {t1} at {tcps} per second"),
    };
    let others: Vec<String> = meshes.iter().filter(|p| **p != mesh).map(|p| p.to_string()).collect();
    let more = if others.is_empty() {
        String::new()
    } else {
        format!(" (other meshes: {}; --object NAME picks one)", others.join(", "))
    };
    let description = format!(
        "{} frames of {mname} in {file} (time-sampled points of {mesh}, {how}){more}; {axes}, {units}",
        times.len()
    );
    Ok(weld(file, &first, &faces, poses_raw, description))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nested(levels: usize) -> String {
        let mut s = String::from("#usda 1.0\n");
        (0..levels).for_each(|i| s.push_str(&format!("def Xform \"a{i}\" {{\n")));
        (0..levels).for_each(|_| s.push_str("}\n"));
        s
    }

    #[test]
    fn brackets_nested_past_the_limit_are_refused_by_line_not_by_a_stack_overflow() {
        assert_eq!(usda_too_deep(&nested(USDA_MAX_NESTING)), None);
        let deep = usda_too_deep(&nested(USDA_MAX_NESTING + 1)).unwrap();
        assert_eq!((deep.line, deep.what), (USDA_MAX_NESTING + 2, "brackets"));
        // 100 000 levels: natively several times the main thread's stack if parsed
        let e = match layer("deep.usda", nested(100_000).as_bytes()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("a stage nested 100 000 deep was read"),
        };
        assert!(e.contains("deep.usda") && e.contains("line 130") && e.contains("deeper than 128 levels"), "{e}");
    }

    #[test]
    fn brackets_in_strings_asset_paths_and_comments_do_not_count() {
        let open = "{".repeat(USDA_MAX_NESTING + 1);
        for quoted in [
            format!("\"{open}\""),
            format!("'{open}'"),
            format!("\"\"\"{open}\n\"\"\""),
            format!("@{open}@"),
            format!("@@@{open}@@@"),
            format!("\"\\\"{open}\""),
        ] {
            let text = format!("#usda 1.0\n(\n    doc = {quoted}\n)\n# {open}\ndef Xform \"World\" {{\n}}\n");
            assert_eq!(usda_too_deep(&text), None, "{quoted}");
        }
        let text = format!("#usda 1.0\n(\n    doc = \"a\"\n)\n{open}\n");
        assert_eq!(usda_too_deep(&text).map(|d| d.line), Some(5));
    }

    /// Metadata arrays nested 40 deep: openusd doubles their text per level (minutes and gigabytes before
    /// this limit); 16 deep is read at once.
    #[test]
    fn arrays_nested_past_their_limit_are_refused_before_openusd_formats_them() {
        let stage = |n: usize| {
            format!(
                "#usda 1.0\n\ndef Xform \"World\"\n{{\n    float a = 1 (\n        foo = {}\"x\"{}\n    )\n}}\n",
                "[".repeat(n),
                "]".repeat(n)
            )
        };
        assert_eq!(usda_too_deep(&stage(USDA_MAX_ARRAY_NESTING)), None);
        assert!(layer("ok.usda", stage(USDA_MAX_ARRAY_NESTING).as_bytes()).is_ok());
        let deep = usda_too_deep(&stage(40)).unwrap();
        assert_eq!((deep.line, deep.what, deep.limit), (6, "arrays", USDA_MAX_ARRAY_NESTING));
        let e = match layer("arrays.usda", stage(40).as_bytes()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("arrays nested 40 deep were read"),
        };
        assert!(e.contains("arrays.usda") && e.contains("line 6: its arrays nest deeper than 16 levels"), "{e}");
    }
}
