//! glTF 2.0 import (`.glb`, and `.gltf` with data-URI buffers or its `.bin` files given alongside): the poses
//! of one mesh.
//!
//! The document is parsed and validated by the `gltf` crate (every index it holds names an existing object);
//! the GLB container is split here and every accessor is read here with its bounds checked against its
//! buffer view and buffer in 64-bit arithmetic *before* anything is allocated, so a file that claims 4 G
//! vertices is refused at once.
//!
//! Which mesh: the one with the most vertices (all its triangle primitives, in order), together with every
//! other mesh bound to the same skin (a character's head, body and clothes, read as one mesh), or the one
//! named by [`Options::mesh`] alone. Which poses, in this order of preference ([`Options::source`] to choose):
//! - **animation**: an animation that moves the mesh (its morph weights, or the joints of its skin), sampled
//!   at its keyframe times, or at [`Options::frames`] evenly spaced times. Skinned meshes are posed by linear
//!   blend skinning over the node hierarchy (JOINTS_0/WEIGHTS_0 and JOINTS_1/WEIGHTS_1: 4 or 8 influences);
//!   morph weights are applied first. LINEAR, STEP and CUBICSPLINE samplers. Several animations: the one with
//!   the most keyframes, or [`Options::animation`].
//! - **morph targets**: the base mesh and then the base plus each target (weight 1, the others 0).
//!
//! Exporters split vertices along normal and UV seams (Blender writes one vertex per face corner unless
//! normals are shared); such exact duplicates of a position in the base pose are welded back into one vertex
//! (the first), so that the part graph sees the real surface. [`Gltf::source`] says which mesh, which poses
//! and both vertex counts.
//!
//! Accessors are read as the spec lays them out: interleaved (a buffer view's byteStride), normalised
//! integers, and sparse (substitutions over a buffer view, or over zeros when there is none).
//!
//! Errors name the file and the accessor / buffer view / animation at fault and say what to do: an index
//! out of range, an accessor (or its sparse indices and values) past its buffer view, a view past its buffer,
//! a stride shorter than an element, a skin without inverse bind matrices, an animation without keyframes, a
//! missing `.bin`.
//!
//! [`read_skinned`] reads a skinned mesh with its skin, node tree and clips through the same checked
//! accessors: the one glTF reader of a user's rig (`posemfa pose`, the rig checks).

use super::Mesh;
use crate::error::{Error, Result};
use nalgebra::{Matrix4, Point3, Quaternion, UnitQuaternion, Vector3};

type DVec3 = Vector3<f64>;
type DQuat = UnitQuaternion<f64>;
type DMat4 = Matrix4<f64>;

/// A unit quaternion from glTF's (x, y, z, w) order.
fn quat(x: f64, y: f64, z: f64, w: f64) -> DQuat {
    let q = Quaternion::new(w, x, y, z);
    if q.norm() > 0.0 && q.norm().is_finite() {
        UnitQuaternion::from_quaternion(q)
    } else {
        UnitQuaternion::identity()
    }
}

/// (x, y, z, w) of a unit quaternion.
fn xyzw(q: &DQuat) -> Vec<f64> {
    let c = q.coords;
    vec![c.x, c.y, c.z, c.w]
}

/// Shorter-arc slerp that never panics (nearly equal or opposite quaternions fall back to the nearer end).
fn slerp(a: &DQuat, b: &DQuat, t: f64) -> DQuat {
    let b = if a.coords.dot(&b.coords) < 0.0 { UnitQuaternion::new_unchecked(-b.into_inner()) } else { *b };
    a.try_slerp(&b, t, 1e-12).unwrap_or(if t < 0.5 { *a } else { b })
}

fn trs(t: DVec3, r: DQuat, s: DVec3) -> DMat4 {
    Matrix4::new_translation(&t) * r.to_homogeneous() * Matrix4::new_nonuniform_scaling(&s)
}

fn apply(m: &DMat4, p: &DVec3) -> DVec3 {
    m.transform_point(&Point3::from(*p)).coords
}
use std::collections::HashMap;

/// Where the poses come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PoseSource {
    /// The animation if one moves the mesh, else the morph targets.
    #[default]
    Auto,
    Animation,
    MorphTargets,
}

/// Choices for reading a glTF file.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Mesh name or index (default: the mesh with the most vertices).
    pub mesh: Option<String>,
    /// Animation name or index (default: the one with the most keyframes that moves the mesh).
    pub animation: Option<String>,
    /// Sample the animation at this many evenly spaced times instead of at its keyframes.
    pub frames: Option<usize>,
    pub source: PoseSource,
}

/// The poses read from a glTF file.
#[derive(Debug, Clone)]
pub struct Gltf {
    /// The glTF file's name.
    pub file: String,
    /// One (name, mesh) per pose, names in pose order.
    pub poses: Vec<(String, Mesh)>,
    /// For people: "49 frames of animation 'Gallop' (keyframes, 24 fps) of mesh 'horse' in horse.glb;
    /// 50528 vertices welded to 8431".
    pub source: String,
    /// Vertices as stored in the file, and after welding.
    pub vertices_in_file: usize,
    pub vertices_welded: usize,
    /// The animations that move the mesh, when the poses came from one of them ([`Clips`]).
    pub clips: Option<Clips>,
}

/// The animations of a file that move its mesh, each by what [`Options::animation`] takes (its name, else its
/// index), and the one the poses came from: what a page offers to read another.
#[derive(Debug, Clone, PartialEq)]
pub struct Clips {
    pub names: Vec<String>,
    /// Index in `names` of the one read.
    pub read: usize,
}

/// Reads the glTF file in `files` (the one `.glb`/`.gltf`), taking external buffers from the other files.
pub fn load_files(files: &[(String, Vec<u8>)], options: &Options) -> std::result::Result<Gltf, Vec<Error>> {
    let is_gltf = |n: &str| {
        let l = n.to_ascii_lowercase();
        l.ends_with(".glb") || l.ends_with(".gltf") || l.ends_with(".vrm")
    };
    let Some((name, bytes)) = files.iter().find(|(n, _)| is_gltf(n)) else {
        return Err(vec![Error::Io("no .glb or .gltf file was given".into())]);
    };
    let resources: Vec<(&str, &[u8])> =
        files.iter().filter(|(n, _)| n != name).map(|(n, b)| (n.as_str(), b.as_slice())).collect();
    read(name, bytes, &resources, options).map_err(|e| vec![e])
}

/// An error in glTF file `file` (what is wrong and what to do).
pub(crate) fn error(file: &str, message: String) -> Error {
    err(file, message)
}

fn err(file: &str, message: String) -> Error {
    Error::Mesh { format: crate::error::Format::Gltf, file: file.to_string(), line: 0, message }
}

/// Splits a GLB container into its JSON and BIN chunks, checking every length against the bytes present.
fn split_glb(file: &str, bytes: &[u8]) -> Result<(Vec<u8>, Option<Vec<u8>>)> {
    let u32_at = |at: usize| -> Option<u32> { Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?)) };
    let bad = |what: String| err(file, format!("{what}; the .glb file is cut or damaged: export it again"));
    let version = u32_at(4).ok_or_else(|| bad("the GLB header is shorter than 12 bytes".into()))?;
    if version != 2 {
        return Err(err(file, format!("GLB version {version} is not supported; export the file as glTF 2.0")));
    }
    let total = u32_at(8).unwrap_or(0) as usize;
    if total < 12 || total > bytes.len() {
        return Err(bad(format!("the GLB header says {total} bytes but the file has {}", bytes.len())));
    }
    let body = bytes.get(..total).unwrap_or(bytes);
    let mut at = 12usize;
    let mut json = None;
    let mut bin = None;
    while at + 8 <= body.len() {
        let len = u32::from_le_bytes(body.get(at..at + 4).and_then(|s| s.try_into().ok()).unwrap_or([0; 4])) as usize;
        let kind = body.get(at + 4..at + 8).unwrap_or(&[]);
        let data = body
            .get(at + 8..)
            .and_then(|rest| rest.get(..len))
            .ok_or_else(|| bad(format!("the chunk at byte {at} claims {len} bytes, past the end of the file")))?;
        match kind {
            b"JSON" if json.is_none() => json = Some(data.to_vec()),
            b"BIN\0" if bin.is_none() => bin = Some(data.to_vec()),
            _ => {} // unknown chunks are skipped (glTF 2.0, GLB)
        }
        at = at + 8 + len;
        at = (at + 3) & !3;
    }
    let json = json.ok_or_else(|| bad("the GLB file has no JSON chunk".into()))?;
    Ok((json, bin))
}

/// Checks what the `gltf` crate leaves unchecked: byte counts and element counts must fit this build's
/// `usize` (the crate converts them with `as usize`, which would silently wrap in wasm32 where `usize` is
/// 32 bits), and animation channel targets must be valid (the crate does not validate them).
fn check_sizes(file: &str, doc: &gltf::Document) -> Result<()> {
    let json = doc.as_json();
    let too_big = |what: String, v: u64| {
        err(file, format!("{what} is {v}, more than this build can address ({}); the file is damaged", usize::MAX))
    };
    let fits = |v: u64| usize::try_from(v).is_ok();
    for (i, a) in json.accessors.iter().enumerate() {
        if !fits(a.count.0) {
            return Err(too_big(format!("the count of accessor {i}"), a.count.0));
        }
        if let Some(o) = a.byte_offset.filter(|o| !fits(o.0)) {
            return Err(too_big(format!("the byte offset of accessor {i}"), o.0));
        }
        if let Some(s) = &a.sparse {
            for (what, v) in [
                ("sparse count", s.count.0),
                ("sparse indices' byte offset", s.indices.byte_offset.0),
                ("sparse values' byte offset", s.values.byte_offset.0),
            ] {
                if !fits(v) {
                    return Err(too_big(format!("the {what} of accessor {i}"), v));
                }
            }
        }
    }
    for (i, v) in json.buffer_views.iter().enumerate() {
        if !fits(v.byte_length.0) {
            return Err(too_big(format!("the length of buffer view {i}"), v.byte_length.0));
        }
        if let Some(o) = v.byte_offset.filter(|o| !fits(o.0)) {
            return Err(too_big(format!("the byte offset of buffer view {i}"), o.0));
        }
    }
    for (i, b) in json.buffers.iter().enumerate() {
        if !fits(b.byte_length.0) {
            return Err(too_big(format!("the length of buffer {i}"), b.byte_length.0));
        }
    }
    // The `gltf` crate (1.4) does not validate animation channel targets, and unwraps them when asked:
    // a target naming a missing node, or an unknown path (such as KHR_animation_pointer's "pointer"), would
    // panic there. Checked here with the crate's own validation of a target.
    use gltf::json::validation::Validate;
    for (a, anim) in json.animations.iter().enumerate() {
        for (c, channel) in anim.channels.iter().enumerate() {
            let mut problems = Vec::new();
            channel
                .target
                .validate(json, gltf::json::Path::new, &mut |path, e| problems.push(format!("{} ({e})", path())));
            if !problems.is_empty() {
                return Err(err(
                    file,
                    format!(
                        "channel {c} of animation {a} has an invalid target: {}; the node must exist and the path be \
                         translation, rotation, scale or weights: export the animation again",
                        problems.join(", ")
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The bytes of every buffer: GLB's BIN chunk, data URIs, or files given alongside.
fn buffers(
    file: &str,
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    resources: &[(&str, &[u8])],
) -> Result<Vec<Vec<u8>>> {
    use base64::Engine as _;
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                err(
                    file,
                    format!("buffer {} is the GLB's binary chunk, but the file has none; export it again", b.index()),
                )
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let Some((_, payload)) = uri.split_once(";base64,") else {
                    return Err(err(
                        file,
                        format!(
                            "buffer {}: only base64 data URIs are supported; export with embedded buffers",
                            b.index()
                        ),
                    ));
                };
                base64::engine::general_purpose::STANDARD.decode(payload).map_err(|e| {
                    err(file, format!("buffer {}: its data URI is not valid base64 ({e}); export it again", b.index()))
                })?
            }
            gltf::buffer::Source::Uri(uri) => {
                let wanted = percent_decode(uri.rsplit('/').next().unwrap_or(uri));
                let found =
                    resources.iter().find(|(n, _)| n.rsplit('/').next() == Some(wanted.as_str())).or_else(|| {
                        resources
                            .iter()
                            .find(|(n, _)| n.rsplit('/').next().is_some_and(|n| n.eq_ignore_ascii_case(&wanted)))
                    });
                match found {
                    Some((_, bytes)) => bytes.to_vec(),
                    None => {
                        return Err(err(
                            file,
                            format!(
                            "buffer {} is stored in the separate file `{uri}`, which was not given; drop or pass it \
                                 together with the .gltf file (or export a single .glb)",
                            b.index()
                        ),
                        ))
                    }
                }
            }
        };
        if data.len() < b.length() {
            return Err(err(
                file,
                format!(
                    "buffer {} should hold {} bytes but has {}; the file (or its .bin) is cut: export it again",
                    b.index(),
                    b.length(),
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while let Some(&c) = b.get(i) {
        if c == b'%' {
            if let Some(v) = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
            {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(c);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Reads accessors with their bounds checked.
struct Data<'a> {
    file: &'a str,
    buffers: &'a [Vec<u8>],
}

/// Where an accessor's values are: its dense part (bytes from its first element to the end of its buffer
/// view, and the stride) if it has a buffer view, and its sparse part if it has one, all bounds checked.
struct Located<'b> {
    dense: Option<(&'b [u8], usize)>,
    /// Sparse substitution: count, the index bytes and their size, the value bytes (tightly packed).
    sparse: Option<(usize, &'b [u8], usize, &'b [u8])>,
}

/// `count` elements of `dims` components of type `data_type` from `bytes` (element i at `i * stride`), as f64,
/// normalised integers mapped to [0, 1] / [-1, 1]. The caller checked that the bytes hold them.
fn decode(
    bytes: &[u8],
    stride: usize,
    count: usize,
    dims: usize,
    data_type: gltf::accessor::DataType,
    norm: bool,
    mut bad: impl FnMut(usize) -> Error,
) -> Result<Vec<f64>> {
    use gltf::accessor::DataType;
    let comp = data_type.size();
    let mut out = Vec::with_capacity(count.saturating_mul(dims));
    for i in 0..count {
        let base = i * stride;
        for c in 0..dims {
            let at = base + c * comp;
            let s = bytes.get(at..at + comp).unwrap_or(&[]);
            let v = match (data_type, s) {
                (DataType::F32, &[a, b, c, d]) => f64::from(f32::from_le_bytes([a, b, c, d])),
                (DataType::U32, &[a, b, c, d]) => f64::from(u32::from_le_bytes([a, b, c, d])),
                (DataType::U16, &[a, b]) => {
                    let v = f64::from(u16::from_le_bytes([a, b]));
                    if norm {
                        v / 65535.0
                    } else {
                        v
                    }
                }
                (DataType::I16, &[a, b]) => {
                    let v = f64::from(i16::from_le_bytes([a, b]));
                    if norm {
                        (v / 32767.0).max(-1.0)
                    } else {
                        v
                    }
                }
                (DataType::U8, &[a]) => {
                    let v = f64::from(a);
                    if norm {
                        v / 255.0
                    } else {
                        v
                    }
                }
                (DataType::I8, &[a]) => {
                    let v = f64::from(a as i8);
                    if norm {
                        (v / 127.0).max(-1.0)
                    } else {
                        v
                    }
                }
                _ => f64::NAN, // not reached: the bounds were checked; refused below if it were
            };
            if !v.is_finite() {
                return Err(bad(i));
            }
            out.push(v);
        }
    }
    Ok(out)
}

impl<'a> Data<'a> {
    /// Every element of an accessor as f64 components (`dims` per element), normalised integers mapped to
    /// [0, 1] / [-1, 1], sparse substitutions applied. `what` says what the accessor is for, in messages.
    fn read(&self, a: &gltf::Accessor, what: &str) -> Result<Vec<f64>> {
        let located = self.locate(a, what)?;
        let (dims, count, idx) = (a.dimensions().multiplicity(), a.count(), a.index());
        let file = self.file;
        let not_finite = |i: usize| {
            err(file, format!("accessor {idx} ({what}): element {i} is not a finite number; export the file again"))
        };
        let mut out = match located.dense {
            Some((bytes, stride)) => decode(bytes, stride, count, dims, a.data_type(), a.normalized(), not_finite)?,
            // No buffer view: zeros, then the sparse values (`locate` bounded the count by the memory budget).
            None => vec![0.0; count * dims],
        };
        if let Some((n, index_bytes, index_size, value_bytes)) = located.sparse {
            use gltf::accessor::DataType;
            let index_type = match index_size {
                1 => DataType::U8,
                2 => DataType::U16,
                _ => DataType::U32,
            };
            let indices = decode(index_bytes, index_size, n, 1, index_type, false, not_finite)?;
            let sparse_bad = |i: usize| {
                err(
                    file,
                    format!("accessor {idx} ({what}): sparse value {i} is not a finite number; export the file again"),
                )
            };
            let values =
                decode(value_bytes, dims * a.data_type().size(), n, dims, a.data_type(), a.normalized(), sparse_bad)?;
            let mut previous = None;
            for (k, &i) in indices.iter().enumerate() {
                let i = i as usize;
                if i >= count || previous.is_some_and(|p| i <= p) {
                    return Err(err(
                        file,
                        format!(
                            "accessor {idx} ({what}): sparse index {k} is {i}, but the indices must increase and stay \
                             below the accessor's {count} elements; the file is damaged: export it again"
                        ),
                    ));
                }
                previous = Some(i);
                out[i * dims..(i + 1) * dims].copy_from_slice(&values[k * dims..(k + 1) * dims]);
            }
        }
        Ok(out)
    }

    /// The bytes of a buffer view, after checking that it lies inside its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&'a [u8]> {
        let data = self.buffers.get(view.buffer().index()).map(Vec::as_slice).unwrap_or(&[]);
        // 64-bit sums of the document's numbers, saturating: a huge offset is refused, never wrapped.
        let view_end = (view.offset() as u64).saturating_add(view.length() as u64);
        if view_end > data.len() as u64 {
            return Err(err(
                self.file,
                format!(
                    "buffer view {} (bytes {}..{view_end}) runs past the end of buffer {} ({} bytes); the file is \
                     damaged: export it again",
                    view.index(),
                    view.offset(),
                    view.buffer().index(),
                    data.len()
                ),
            ));
        }
        Ok(data.get(view.offset()..view_end as usize).unwrap_or(&[]))
    }

    /// Where an accessor's values are ([`Located`]), after checking that every element (dense and sparse) lies
    /// inside its buffer view and the view inside its buffer; an accessor of zeros (no buffer view) only when
    /// its size fits the memory budget.
    fn locate(&self, a: &gltf::Accessor, what: &str) -> Result<Located<'a>> {
        let file = self.file;
        let idx = a.index();
        let dims = a.dimensions().multiplicity();
        let comp = a.data_type().size();
        let count = a.count();
        let elem = (dims * comp) as u64;
        let dense = match a.view() {
            Some(view) => {
                let stride = view.stride().map_or(elem, |s| s as u64);
                let bytes = self.view_bytes(&view)?;
                let need = if count == 0 {
                    0
                } else {
                    (a.offset() as u64).saturating_add(stride.saturating_mul(count as u64 - 1)).saturating_add(elem)
                };
                if stride < elem {
                    return Err(err(
                        file,
                        format!(
                            "accessor {idx} ({what}): its buffer view {} has a byteStride of {stride} bytes, shorter \
                             than one element ({elem} bytes), so elements would overlap; the file is damaged: \
                             export it again",
                            view.index()
                        ),
                    ));
                }
                if need > view.length() as u64 {
                    return Err(err(
                        file,
                        format!(
                            "accessor {idx} ({what}: {count} elements of {elem} bytes, stride {stride}, from byte {}) \
                             reads past the end of its buffer view {} ({} bytes); the file is damaged or cut: export \
                             it again",
                            a.offset(),
                            view.index(),
                            view.length()
                        ),
                    ));
                }
                Some((bytes.get(a.offset()..).unwrap_or(&[]), stride as usize))
            }
            None if a.sparse().is_none() => {
                return Err(err(
                    file,
                    format!(
                        "accessor {idx} ({what}) has neither a buffer view nor sparse values; the file is damaged: \
                         export it again"
                    ),
                ))
            }
            None => {
                // All zeros but the sparse values (glTF 2.0, 3.6.2.3): the count has no bytes behind it, so
                // the zeros are bounded by the memory budget before they are allocated.
                let need = (count as u64).saturating_mul(dims as u64).saturating_mul(8);
                let budget = crate::memory::budget_bytes()?;
                if need > budget {
                    return Err(err(
                        file,
                        format!(
                            "accessor {idx} ({what}) has no buffer view and {count} elements, which take {} to hold, \
                             more than the memory budget of {}; the file is damaged",
                            crate::memory::show_bytes(need),
                            crate::memory::show_bytes(budget)
                        ),
                    ));
                }
                None
            }
        };
        let sparse = match a.sparse() {
            None => None,
            Some(s) => {
                let n = s.count();
                let index_size = match s.indices().index_type() {
                    gltf::accessor::sparse::IndexType::U8 => 1usize,
                    gltf::accessor::sparse::IndexType::U16 => 2,
                    gltf::accessor::sparse::IndexType::U32 => 4,
                };
                let part = |view: gltf::buffer::View, offset: usize, size: u64, which: &str| -> Result<&'a [u8]> {
                    let bytes = self.view_bytes(&view)?;
                    let need = (offset as u64).saturating_add((n as u64).saturating_mul(size));
                    if need > view.length() as u64 {
                        return Err(err(
                            file,
                            format!(
                                "accessor {idx} ({what}): its {n} sparse {which} of {size} bytes from byte {offset} \
                                 run past the end of buffer view {} ({} bytes); the file is damaged or cut: export \
                                 it again",
                                view.index(),
                                view.length()
                            ),
                        ));
                    }
                    Ok(bytes.get(offset..).unwrap_or(&[]))
                };
                if n as u64 > count as u64 {
                    return Err(err(
                        file,
                        format!(
                            "accessor {idx} ({what}) has {n} sparse values for {count} elements; the file is damaged: \
                             export it again"
                        ),
                    ));
                }
                let indices = part(s.indices().view(), s.indices().offset(), index_size as u64, "indices")?;
                let values = part(s.values().view(), s.values().offset(), elem, "values")?;
                Some((n, indices, index_size, values))
            }
        };
        Ok(Located { dense, sparse })
    }

    fn read_vec3(&self, a: &gltf::Accessor, what: &str) -> Result<Vec<DVec3>> {
        self.expect(a, what, 3)?;
        Ok(self.read(a, what)?.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect())
    }

    fn expect(&self, a: &gltf::Accessor, what: &str, dims: usize) -> Result<()> {
        if a.dimensions().multiplicity() != dims {
            return Err(err(
                self.file,
                format!(
                    "accessor {} ({what}) has {} components per element, expected {dims}; the file is damaged",
                    a.index(),
                    a.dimensions().multiplicity()
                ),
            ));
        }
        Ok(())
    }
}

/// One mesh's vertices, as stored (all triangle primitives, concatenated).
struct MeshData {
    positions: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
    /// targets[k][j]: position delta of vertex j in morph target k.
    targets: Vec<Vec<DVec3>>,
    /// Up to 8 (joint, weight) per vertex.
    influences: Vec<Vec<(usize, f64)>>,
}

/// How many JOINTS_n / WEIGHTS_n sets a primitive has (n = 0, 1, ... while both are present): 4 influences
/// per set.
fn joint_sets(p: &gltf::Primitive) -> u32 {
    (0..)
        .find(|&n| p.get(&gltf::Semantic::Joints(n)).is_none() || p.get(&gltf::Semantic::Weights(n)).is_none())
        .unwrap_or(0)
}

fn mesh_vertex_count(mesh: &gltf::Mesh) -> u64 {
    mesh.primitives()
        .filter_map(|p| p.get(&gltf::Semantic::Positions))
        .fold(0u64, |n, a| n.saturating_add(a.count() as u64))
}

fn name_of(name: Option<&str>, kind: &str, index: usize) -> String {
    match name {
        Some(n) if !n.is_empty() => format!("{kind} '{n}'"),
        _ => format!("{kind} {index}"),
    }
}

fn pick<'a, T>(
    items: Vec<T>,
    wanted: &str,
    name: impl Fn(&T) -> Option<&'a str>,
    index: impl Fn(&T) -> usize,
) -> Option<T> {
    let by_index = wanted.parse::<usize>().ok();
    items.into_iter().find(|t| name(t) == Some(wanted) || Some(index(t)) == by_index)
}

/// Refuses, before anything is read, a mesh whose vertices (with its morph targets and skin weights) and
/// indices would take more memory than the budget. The counts come from the document (a primitive may reuse
/// another's accessor, so small files can name huge meshes); each accessor was checked against its bytes
/// only when it is read.
fn check_read_size(data: &Data, mesh: &gltf::Mesh, mname: &str, budget: u64) -> Result<()> {
    let file = data.file;
    // Each accessor against its bytes first (the more precise message).
    for (pi, p) in mesh.primitives().enumerate() {
        let what = |w: &str| format!("{w} of primitive {pi} of {mname}");
        if let Some(a) = p.get(&gltf::Semantic::Positions) {
            data.locate(&a, &what("POSITION"))?;
        }
        if let Some(a) = p.indices() {
            data.locate(&a, &what("indices"))?;
        }
        for (k, t) in p.morph_targets().enumerate() {
            if let Some(a) = t.positions() {
                data.locate(&a, &what(&format!("morph target {k}")))?;
            }
        }
    }
    let vertices = mesh_vertex_count(mesh);
    let targets = mesh.primitives().map(|p| p.morph_targets().len() as u64).max().unwrap_or(0);
    let indices = mesh.primitives().fold(0u64, |n, p| {
        let count = p.indices().map(|a| a.count() as u64);
        n.saturating_add(count.or_else(|| p.get(&gltf::Semantic::Positions).map(|a| a.count() as u64)).unwrap_or(0))
    });
    // Per vertex: position and one delta per target (24 bytes each), skin influences as read (per set of
    // 4 joints and 4 weights, 64 bytes as f64) and kept (4 pairs of 16 bytes plus a share of the list's 24),
    // 152 per set, counted for at least two sets.
    // Per index: the f64 read, the u64 kept and a third of a triangle (4 bytes).
    let sets = mesh.primitives().map(|p| u64::from(joint_sets(&p))).max().unwrap_or(0).max(2);
    let per_vertex = 24u64.saturating_mul(targets.saturating_add(1)).saturating_add(152 * sets);
    let need = vertices.saturating_mul(per_vertex).saturating_add(indices.saturating_mul(20));
    if need > budget {
        let show = crate::memory::show_bytes;
        return Err(err(
            file,
            format!(
                "{mname} has {vertices} vertices{} and {indices} indices in its primitives, which take about {} to \
                 read, more than the memory budget of {}; the file is damaged or far larger than a pose population \
                 needs (decimate the mesh before exporting it)",
                if targets > 0 { format!(" with {targets} morph targets") } else { String::new() },
                show(need),
                show(budget)
            ),
        ));
    }
    Ok(())
}

fn read_mesh(data: &Data, mesh: &gltf::Mesh) -> Result<MeshData> {
    use gltf::mesh::Mode;
    let file = data.file;
    let mname = name_of(mesh.name(), "mesh", mesh.index());
    let mut md = MeshData { positions: Vec::new(), faces: Vec::new(), targets: Vec::new(), influences: Vec::new() };
    let n_targets = mesh.primitives().map(|p| p.morph_targets().len()).max().unwrap_or(0);
    md.targets = vec![Vec::new(); n_targets];
    for (pi, p) in mesh.primitives().enumerate() {
        if p.mode() != Mode::Triangles && p.mode() != Mode::TriangleStrip && p.mode() != Mode::TriangleFan {
            continue; // points and lines: no surface
        }
        let Some(pos) = p.get(&gltf::Semantic::Positions) else { continue };
        let offset = md.positions.len();
        let what = format!("POSITION of primitive {pi} of {mname}");
        let positions = data.read_vec3(&pos, &what)?;
        let n = positions.len();
        md.positions.extend(positions);
        let indices: Vec<u64> = match p.indices() {
            Some(a) => {
                data.expect(&a, "indices", 1)?;
                if a.data_type() == gltf::accessor::DataType::F32 {
                    return Err(err(
                        file,
                        format!("accessor {} (indices of primitive {pi} of {mname}) holds floats; indices are unsigned integers: the file is damaged", a.index()),
                    ));
                }
                data.read(&a, &format!("indices of primitive {pi} of {mname}"))?.into_iter().map(|v| v as u64).collect()
            }
            None => (0..n as u64).collect(),
        };
        if let Some((k, &bad)) = indices.iter().enumerate().find(|(_, &i)| i >= n as u64) {
            return Err(err(
                file,
                format!(
                    "index {k} of primitive {pi} of {mname} (accessor {}) is {bad}, but the primitive has {n} vertices; \
                     the file is damaged: export it again",
                    p.indices().map_or(0, |a| a.index())
                ),
            ));
        }
        let v = |i: u64| (i as usize + offset) as u32;
        match p.mode() {
            Mode::Triangles => {
                for t in indices.chunks_exact(3) {
                    md.faces.push([v(t[0]), v(t[1]), v(t[2])]);
                }
            }
            Mode::TriangleStrip => {
                for (k, w) in indices.windows(3).enumerate() {
                    md.faces.push(if k % 2 == 0 { [v(w[0]), v(w[1]), v(w[2])] } else { [v(w[1]), v(w[0]), v(w[2])] });
                }
            }
            _ => {
                if let Some((&first, rest)) = indices.split_first() {
                    for w in rest.windows(2) {
                        md.faces.push([v(first), v(w[0]), v(w[1])]);
                    }
                }
            }
        }
        let targets: Vec<_> = p.morph_targets().collect();
        for (k, slot) in md.targets.iter_mut().enumerate() {
            match targets.get(k).and_then(|t| t.positions()) {
                Some(a) => {
                    let d = data.read_vec3(&a, &format!("morph target {k} of primitive {pi} of {mname}"))?;
                    if d.len() != n {
                        return Err(err(
                            file,
                            format!(
                                "morph target {k} of primitive {pi} of {mname} (accessor {}) has {} positions for {n} \
                                 vertices; the file is damaged",
                                a.index(),
                                d.len()
                            ),
                        ));
                    }
                    slot.extend(d);
                }
                None => slot.extend(std::iter::repeat(DVec3::zeros()).take(n)),
            }
        }
        let mut infl = vec![Vec::new(); n];
        for set in 0..joint_sets(&p) {
            let (Some(j), Some(w)) = (p.get(&gltf::Semantic::Joints(set)), p.get(&gltf::Semantic::Weights(set))) else {
                continue;
            };
            data.expect(&j, "JOINTS", 4)?;
            data.expect(&w, "WEIGHTS", 4)?;
            let jv = data.read(&j, &format!("JOINTS_{set} of primitive {pi} of {mname}"))?;
            let wv = data.read(&w, &format!("WEIGHTS_{set} of primitive {pi} of {mname}"))?;
            if jv.len() != 4 * n || wv.len() != 4 * n {
                return Err(err(
                    file,
                    format!("JOINTS_{set}/WEIGHTS_{set} of primitive {pi} of {mname} do not have one entry per vertex"),
                ));
            }
            for (i, slot) in infl.iter_mut().enumerate() {
                for c in 0..4 {
                    let (jj, ww) = (jv[4 * i + c], wv[4 * i + c]);
                    if ww != 0.0 {
                        slot.push((jj as usize, ww));
                    }
                }
            }
        }
        md.influences.extend(infl);
    }
    if md.positions.is_empty() || md.faces.is_empty() {
        return Err(err(file, format!("{mname} has no triangles; posemfa needs a triangle mesh")));
    }
    if md.positions.len() > u32::MAX as usize {
        return Err(err(file, format!("{mname} has more than 4294967295 vertices")));
    }
    Ok(md)
}

/// The local transform of every node at rest.
fn rest_transforms(doc: &gltf::Document) -> Vec<(DVec3, DQuat, DVec3)> {
    doc.nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            (
                DVec3::new(t[0].into(), t[1].into(), t[2].into()),
                quat(r[0].into(), r[1].into(), r[2].into(), r[3].into()),
                DVec3::new(s[0].into(), s[1].into(), s[2].into()),
            )
        })
        .collect()
}

/// Global transforms from local ones over the node hierarchy (roots have no parent). Linear in the number
/// of nodes however deep the hierarchy; a cycle (which a valid file cannot have) is cut where it closes.
fn globals(parents: &[Option<usize>], local: &[(DVec3, DQuat, DVec3)]) -> Vec<DMat4> {
    let n = local.len();
    let mut out: Vec<Option<DMat4>> = vec![None; n];
    let mut on_path = vec![false; n];
    let mut chain = Vec::new();
    for start in 0..n {
        // Walk up to a computed ancestor (or a root, or a node already on this walk).
        chain.clear();
        let mut cur = Some(start);
        while let Some(c) = cur {
            if out.get(c).is_none_or(Option::is_some) || on_path.get(c).copied().unwrap_or(true) {
                break;
            }
            if let Some(flag) = on_path.get_mut(c) {
                *flag = true;
            }
            chain.push(c);
            cur = parents.get(c).copied().flatten();
        }
        for &i in chain.iter().rev() {
            let (t, r, s) = local.get(i).copied().unwrap_or((DVec3::zeros(), DQuat::identity(), DVec3::repeat(1.0)));
            let m = trs(t, r, s);
            let parent = parents.get(i).copied().flatten().and_then(|p| out.get(p).copied().flatten());
            if let Some(slot) = out.get_mut(i) {
                *slot = Some(parent.map_or(m, |pm| pm * m));
            }
            if let Some(flag) = on_path.get_mut(i) {
                *flag = false;
            }
        }
    }
    out.into_iter().map(|m| m.unwrap_or_else(DMat4::identity)).collect()
}

/// Marks every node that is a joint of `joints` or an ancestor of one (each node visited once).
fn joint_ancestors(parents: &[Option<usize>], joints: &[usize]) -> Vec<bool> {
    let mut marked = vec![false; parents.len()];
    for &j in joints {
        let mut cur = Some(j);
        while let Some(c) = cur {
            match marked.get_mut(c) {
                Some(m) if !*m => *m = true,
                _ => break,
            }
            cur = parents.get(c).copied().flatten();
        }
    }
    marked
}

/// One animation channel, read.
struct Channel {
    node: usize,
    property: gltf::animation::Property,
    interpolation: gltf::animation::Interpolation,
    times: Vec<f64>,
    /// `values[k]`: the output of key k (CUBICSPLINE: in-tangent, value, out-tangent).
    values: Vec<Vec<f64>>,
}

impl Channel {
    fn sample(&self, t: f64) -> Vec<f64> {
        use gltf::animation::Interpolation::*;
        let cubic = self.interpolation == CubicSpline;
        let value = |k: usize| -> Vec<f64> {
            let v = self.values.get(k).cloned().unwrap_or_default();
            if cubic {
                let w = v.len() / 3;
                v.get(w..2 * w).map(<[f64]>::to_vec).unwrap_or_default()
            } else {
                v
            }
        };
        let n = self.times.len();
        let (Some(&first), Some(&last)) = (self.times.first(), self.times.last()) else { return Vec::new() };
        if t <= first {
            return value(0);
        }
        if t >= last {
            return value(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t).saturating_sub(1).min(n.saturating_sub(2));
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let u = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
        match self.interpolation {
            Step => value(k),
            Linear => {
                let (a, b) = (value(k), value(k + 1));
                if self.property == gltf::animation::Property::Rotation && a.len() == 4 && b.len() == 4 {
                    let q = slerp(&quat(a[0], a[1], a[2], a[3]), &quat(b[0], b[1], b[2], b[3]), u);
                    xyzw(&q)
                } else {
                    a.iter().zip(&b).map(|(x, y)| x + (y - x) * u).collect()
                }
            }
            CubicSpline => {
                let (va, vb) = (
                    self.values.get(k).cloned().unwrap_or_default(),
                    self.values.get(k + 1).cloned().unwrap_or_default(),
                );
                let w = va.len() / 3;
                let (u2, u3) = (u * u, u * u * u);
                let out: Vec<f64> = (0..w)
                    .map(|c| {
                        let p0 = va.get(w + c).copied().unwrap_or(0.0);
                        let m0 = va.get(2 * w + c).copied().unwrap_or(0.0) * dt;
                        let p1 = vb.get(w + c).copied().unwrap_or(0.0);
                        let m1 = vb.get(c).copied().unwrap_or(0.0) * dt;
                        (2.0 * u3 - 3.0 * u2 + 1.0) * p0
                            + (u3 - 2.0 * u2 + u) * m0
                            + (-2.0 * u3 + 3.0 * u2) * p1
                            + (u3 - u2) * m1
                    })
                    .collect();
                if self.property == gltf::animation::Property::Rotation && out.len() == 4 {
                    xyzw(&quat(out[0], out[1], out[2], out[3]))
                } else {
                    out
                }
            }
        }
    }
}

fn read_channels(data: &Data, anim: &gltf::Animation, aname: &str) -> Result<Vec<Channel>> {
    let mut out = Vec::new();
    for (ci, ch) in anim.channels().enumerate() {
        let s = ch.sampler();
        let input = s.input();
        let output = s.output();
        let times = data.read(&input, &format!("keyframe times of channel {ci} of {aname}"))?;
        if times.is_empty() {
            return Err(err(
                data.file,
                format!("channel {ci} of {aname} has no keyframes (accessor {} is empty); export the animation again with its keys", input.index()),
            ));
        }
        if times.windows(2).any(|w| w[1] < w[0]) {
            return Err(err(data.file, format!("the keyframe times of channel {ci} of {aname} (accessor {}) are not increasing; the file is damaged", input.index())));
        }
        let flat = data.read(&output, &format!("keyframe values of channel {ci} of {aname}"))?;
        let per_key_parts = if s.interpolation() == gltf::animation::Interpolation::CubicSpline { 3 } else { 1 };
        let per_key = flat.len() / times.len();
        if per_key == 0 || flat.len() % times.len() != 0 || per_key % per_key_parts != 0 {
            return Err(err(
                data.file,
                format!(
                    "channel {ci} of {aname}: {} output values for {} keyframes (accessor {}); the file is damaged",
                    flat.len(),
                    times.len(),
                    output.index()
                ),
            ));
        }
        let values = flat.chunks_exact(per_key).map(<[f64]>::to_vec).collect();
        out.push(Channel {
            node: ch.target().node().index(),
            property: ch.target().property(),
            interpolation: s.interpolation(),
            times,
            values,
        });
    }
    if out.is_empty() {
        return Err(err(
            data.file,
            format!("{aname} has no channels: no keyframes to sample; export the animation again"),
        ));
    }
    Ok(out)
}

/// The document of a `.glb` or `.gltf` file, validated by the `gltf` crate and [`check_sizes`], and the bytes
/// of its buffers (checked by [`buffers`]).
fn open(file: &str, bytes: &[u8], resources: &[(&str, &[u8])]) -> Result<(gltf::Document, Vec<Vec<u8>>)> {
    let (json, blob) = if bytes.starts_with(b"glTF") { split_glb(file, bytes)? } else { (bytes.to_vec(), None) };
    if blob.is_none() && json.iter().find(|b| !b.is_ascii_whitespace()) != Some(&b'{') {
        // (an OBJ, a PLY, an image given where a glTF belongs: "expected value at line 1" would say nothing)
        return Err(err(
            file,
            "not a .glb or .gltf file: it neither starts with a .glb's signature (glTF) nor is a JSON document; \
             give a glTF 2.0 file (for `posemfa pose`, the .glb `posemfa export-gltf` wrote)"
                .into(),
        ));
    }
    let invalid =
        |e: gltf::Error| err(file, format!("not a valid glTF 2.0 document: {e}; export the file again as glTF 2.0"));
    let root = gltf::Gltf::from_slice_without_validation(&json).map_err(invalid)?.document.into_json();
    // The crate's validation indexes `accessors` with a primitive's POSITION index unchecked (gltf-json 1.4,
    // mesh.rs): an index out of range would panic inside it, so those are checked first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &primitive.attributes {
                if index.value() >= root.accessors.len() {
                    return Err(err(
                        file,
                        format!(
                            "attribute {semantic:?} of primitive {p} of mesh {m} names accessor {}, but the file has {}; \
                             the file is damaged: export it again",
                            index.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let doc = gltf::Document::from_json(root).map_err(invalid)?;
    check_sizes(file, &doc)?;
    let buffers = buffers(file, &doc, blob, resources)?;
    Ok((doc, buffers))
}

/// Reads the poses of one glTF file.
pub fn read(file: &str, bytes: &[u8], resources: &[(&str, &[u8])], options: &Options) -> Result<Gltf> {
    read_poses(file, bytes, resources, options, false).map(|(g, _)| g)
}

/// The skeleton a skinned mesh's poses were played from ([`read_with_skin`]).
#[derive(Debug, Clone)]
pub struct SkinTrack {
    /// Every joint of the skin: its node's name, else `node N`.
    pub names: Vec<String>,
    /// Every joint's nearest ancestor that is a joint of the skin.
    pub parent: Vec<Option<usize>>,
    /// Every joint's world transform in the bind pose (the inverse of its inverse bind matrix), column-major.
    pub bind: Vec<[f64; 16]>,
    /// Per pose, every joint's world transform (column-major), in the frame the posed vertices are in.
    pub world: Vec<Vec<[f64; 16]>>,
    /// Per vertex as welded in the poses: every (joint, weight) of the file.
    pub influences: Vec<Vec<(usize, f64)>>,
}

/// [`read`], and when the poses are the animation of a skinned mesh, its skeleton at every pose.
pub fn read_with_skin(
    file: &str,
    bytes: &[u8],
    resources: &[(&str, &[u8])],
    options: &Options,
) -> Result<(Gltf, Option<SkinTrack>)> {
    read_poses(file, bytes, resources, options, true)
}

fn read_poses(
    file: &str,
    bytes: &[u8],
    resources: &[(&str, &[u8])],
    options: &Options,
    keep_skin: bool,
) -> Result<(Gltf, Option<SkinTrack>)> {
    let (doc, buffers) = open(file, bytes, resources)?;
    let data = Data { file, buffers: &buffers };

    // The mesh, and the node that shows it (for its skin and morph weights).
    let meshes: Vec<gltf::Mesh> = doc.meshes().collect();
    if meshes.is_empty() {
        return Err(err(file, "the file holds no mesh; export the model with its mesh".into()));
    }
    let mesh = match &options.mesh {
        Some(w) => pick(meshes.clone(), w, |m| m.name(), |m| m.index()).ok_or_else(|| {
            let names: Vec<String> = meshes.iter().map(|m| name_of(m.name(), "mesh", m.index())).collect();
            err(file, format!("no mesh is called or numbered `{w}`; the file has {}", names.join(", ")))
        })?,
        None => meshes
            .iter()
            .max_by_key(|m| (mesh_vertex_count(m), std::cmp::Reverse(m.index())))
            .cloned()
            .ok_or_else(|| err(file, "no mesh".into()))?,
    };
    let mname = name_of(mesh.name(), "mesh", mesh.index());
    let node = doc.nodes().find(|n| n.mesh().is_some_and(|m| m.index() == mesh.index()));
    let budget = crate::memory::budget_bytes()?;
    check_read_size(&data, &mesh, &mname, budget)?;
    let mut md = read_mesh(&data, &mesh)?;
    // A character is often several meshes (head, body, clothes) bound to one skin: unless a mesh was asked
    // for, every mesh that skin moves is read with the largest, as one mesh (each node of a skinned mesh
    // ignores its own transform, so their vertices are in one frame already).
    let mut joined = vec![mname.clone()];
    let skin_index = node.as_ref().and_then(|n| n.skin()).map(|s| s.index());
    if let (None, Some(si), true) = (&options.mesh, skin_index, md.targets.is_empty()) {
        let mut seen = vec![mesh.index()];
        for n in doc.nodes() {
            let (Some(m), Some(s)) = (n.mesh(), n.skin()) else { continue };
            let no_targets = m.primitives().all(|p| p.morph_targets().len() == 0);
            let surface = m.primitives().any(|p| {
                use gltf::mesh::Mode::*;
                matches!(p.mode(), Triangles | TriangleStrip | TriangleFan)
            });
            if s.index() != si || seen.contains(&m.index()) || !no_targets || !surface {
                continue;
            }
            seen.push(m.index());
            let name = name_of(m.name(), "mesh", m.index());
            check_read_size(&data, &m, &name, budget)?;
            let more = read_mesh(&data, &m)?;
            let offset = md.positions.len() as u32;
            md.faces.extend(more.faces.iter().map(|f| f.map(|v| v + offset)));
            md.positions.extend(more.positions);
            md.influences.extend(more.influences);
            joined.push(name);
        }
    }
    let others = meshes.len() - joined.len();
    let shown = match joined.as_slice() {
        [one] => one.clone(),
        [first @ .., last] => format!(
            "meshes {} and {} (one skin moves them; read as one mesh)",
            first.iter().map(|n| n.trim_start_matches("mesh ")).collect::<Vec<_>>().join(", "),
            last.trim_start_matches("mesh ")
        ),
        [] => mname.clone(),
    };
    let n_file = md.positions.len();

    let mut parents = vec![None; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            if let Some(slot) = parents.get_mut(c.index()) {
                *slot = Some(n.index());
            }
        }
    }
    let rest = rest_transforms(&doc);
    let skin = node.as_ref().and_then(|n| n.skin());
    let default_weights: Vec<f64> = node
        .as_ref()
        .and_then(|n| n.weights())
        .or_else(|| mesh.weights())
        .map(|w| w.iter().map(|&x| f64::from(x)).collect())
        .unwrap_or_else(|| vec![0.0; md.targets.len()]);

    // Skinning data: joints and inverse bind matrices.
    let skinning = match &skin {
        Some(s) => {
            let Some(ibm) = s.inverse_bind_matrices() else {
                return Err(err(
                    file,
                    format!(
                        "skin {} of {mname} has no inverse bind matrices, so its rest pose is unknown; export the skin \
                         with them (every exporter that writes skins can)",
                        s.index()
                    ),
                ));
            };
            data.expect(&ibm, "inverse bind matrices", 16)?;
            let m = data.read(&ibm, &format!("inverse bind matrices of skin {}", s.index()))?;
            let joints: Vec<usize> = s.joints().map(|j| j.index()).collect();
            if m.len() != 16 * joints.len() {
                return Err(err(
                    file,
                    format!(
                        "skin {} has {} joints but {} inverse bind matrices (accessor {})",
                        s.index(),
                        joints.len(),
                        m.len() / 16,
                        ibm.index()
                    ),
                ));
            }
            let ibms: Vec<DMat4> = m.chunks_exact(16).map(|c| DMat4::from_column_slice(c)).collect();
            if let Some((j, _)) = md.influences.iter().flatten().find(|(j, _)| *j >= joints.len()) {
                return Err(err(
                    file,
                    format!(
                        "a vertex of {mname} is bound to joint {j}, but skin {} has {} joints; the file is damaged",
                        s.index(),
                        joints.len()
                    ),
                ));
            }
            Some((joints, ibms))
        }
        None => None,
    };

    // Which animation moves this mesh: one with morph weights on its node, or one moving a joint of its skin.
    let moves_joint = skinning.as_ref().map_or_else(Vec::new, |(joints, _)| joint_ancestors(&parents, joints));
    let moves_mesh = |a: &gltf::Animation| {
        a.channels().any(|c| {
            let t = c.target();
            let n = t.node().index();
            (t.property() == gltf::animation::Property::MorphTargetWeights
                && node.as_ref().is_some_and(|x| x.index() == n))
                || moves_joint.get(n).copied().unwrap_or(false)
        })
    };
    let animations: Vec<gltf::Animation> = doc.animations().filter(|a| moves_mesh(a)).collect();
    let use_animation = match options.source {
        PoseSource::Animation => true,
        PoseSource::MorphTargets => false,
        PoseSource::Auto => !animations.is_empty() || options.animation.is_some(),
    };

    let mut poses_raw: Vec<(String, Vec<DVec3>)> = Vec::new();
    let mut joint_world: Vec<Vec<[f64; 16]>> = Vec::new();
    let description;
    let mut clips = String::new();
    let mut clip_list = None;
    if use_animation {
        let all: Vec<gltf::Animation> = doc.animations().collect();
        let anim = match &options.animation {
            Some(w) => pick(all.clone(), w, |a| a.name(), |a| a.index()).ok_or_else(|| {
                let names: Vec<String> = all.iter().map(|a| name_of(a.name(), "animation", a.index())).collect();
                err(
                    file,
                    format!(
                        "no animation is called or numbered `{w}`; the file has {}",
                        if names.is_empty() { "none".into() } else { names.join(", ") }
                    ),
                )
            })?,
            None => {
                let mut best = None;
                let mut best_keys = 0usize;
                for a in &animations {
                    let keys = a.channels().map(|c| c.sampler().input().count()).max().unwrap_or(0);
                    if best.is_none() || keys > best_keys {
                        best = Some(a.clone());
                        best_keys = keys;
                    }
                }
                best.ok_or_else(|| {
                    err(file, format!("no animation moves {mname} (its morph weights or the joints of its skin); read its morph targets instead, or export the animation"))
                })?
            }
        };
        let aname = name_of(anim.name(), "animation", anim.index());
        let key =
            |a: &gltf::Animation| a.name().filter(|n| !n.is_empty()).map_or(a.index().to_string(), str::to_string);
        let names: Vec<String> = animations.iter().map(key).collect();
        clip_list = animations.iter().position(|a| a.index() == anim.index()).map(|read| Clips { names, read });
        let channels = read_channels(&data, &anim, &aname)?;
        let mut keys: Vec<f64> = channels.iter().flat_map(|c| c.times.iter().copied()).collect();
        keys.sort_by(f64::total_cmp);
        keys.dedup_by(|a, b| (*a - *b).abs() <= 1e-6);
        let (lo, hi) = (keys.first().copied().unwrap_or(0.0), keys.last().copied().unwrap_or(0.0));
        let n_times = match options.frames {
            Some(0) => return Err(err(file, "--frames must be at least 1".into())),
            Some(f) => f,
            None => keys.len(),
        };
        // The poses must fit in the memory budget: refuse before computing them.
        crate::memory::check(n_file, n_times, 1, crate::memory::budget_bytes()?).map_err(|e| {
            err(file, format!("{aname} sampled at {n_times} times: {e}; sample it at fewer times (--frames N)"))
        })?;
        let times: Vec<f64> = match options.frames {
            Some(f) => (0..f).map(|i| if f == 1 { lo } else { lo + (hi - lo) * i as f64 / (f - 1) as f64 }).collect(),
            None => keys.clone(),
        };
        let how = match options.frames {
            Some(f) => format!("sampled at {f} evenly spaced times"),
            None => {
                let steps: Vec<f64> = keys.windows(2).map(|w| w[1] - w[0]).collect();
                let even = steps.first().is_some_and(|&d| d > 0.0 && steps.iter().all(|s| (s - d).abs() <= 1e-3 * d));
                match steps.first() {
                    Some(&d) if even => {
                        format!("sampled at its keyframes, {:.3} fps", 1.0 / d).replace(".000 fps", " fps")
                    }
                    _ => "sampled at its keyframes".into(),
                }
            }
        };
        // the others a user may have meant, each as --animation takes it, and how to read one of them
        if let Some(c) = clip_list.as_ref().filter(|c| options.animation.is_none() && c.names.len() > 1) {
            let names: Vec<String> = c.names.iter().map(|n| format!("'{n}'")).collect();
            clips = format!(
                "; of the {} animations that move it ({}) the one with the most keyframes is read (the page's \
                 Animation list or the CLI's --animation NAME reads another)",
                names.len(),
                names.join(", ")
            );
        }
        description = format!("{} frames of {aname} ({how}) of {shown}", times.len());
        for (fi, &t) in times.iter().enumerate() {
            let mut local = rest.clone();
            let mut weights = default_weights.clone();
            for c in &channels {
                let v = c.sample(t);
                use gltf::animation::Property::*;
                match (c.property, v.as_slice()) {
                    (Translation, &[x, y, z]) => {
                        if let Some(l) = local.get_mut(c.node) {
                            l.0 = DVec3::new(x, y, z)
                        }
                    }
                    (Rotation, &[x, y, z, w]) => {
                        if let Some(l) = local.get_mut(c.node) {
                            l.1 = quat(x, y, z, w)
                        }
                    }
                    (Scale, &[x, y, z]) => {
                        if let Some(l) = local.get_mut(c.node) {
                            l.2 = DVec3::new(x, y, z)
                        }
                    }
                    (MorphTargetWeights, w) if node.as_ref().is_some_and(|n| n.index() == c.node) => {
                        for (slot, &x) in weights.iter_mut().zip(w) {
                            *slot = x;
                        }
                    }
                    _ => {}
                }
            }
            let g = globals(&parents, &local);
            if let (true, Some((joints, _))) = (keep_skin, &skinning) {
                let at = |j: usize| g.get(j).copied().unwrap_or_else(DMat4::identity);
                joint_world.push(joints.iter().map(|&j| std::array::from_fn(|i| at(j)[i])).collect());
            }
            let morphed = morph(&md, &weights);
            let posed = match &skinning {
                Some((joints, ibms)) => {
                    let mats: Vec<DMat4> = joints
                        .iter()
                        .zip(ibms)
                        .map(|(&j, ibm)| g.get(j).copied().unwrap_or_else(DMat4::identity) * *ibm)
                        .collect();
                    skin_positions(&morphed, &md.influences, &mats)
                }
                None => {
                    let m = node.as_ref().and_then(|n| g.get(n.index()).copied()).unwrap_or_else(DMat4::identity);
                    morphed.iter().map(|p| apply(&m, p)).collect()
                }
            };
            poses_raw.push((format!("frame {:0w$}", fi + 1, w = times.len().to_string().len()), posed));
        }
    } else {
        if md.targets.is_empty() {
            return Err(err(
                file,
                format!(
                    "{mname} has no morph targets and no animation moves it, so the file holds one pose; export the poses \
                     as shape keys / morph targets or as an animation"
                ),
            ));
        }
        let names: Vec<String> = mesh
            .extras()
            .as_ref()
            .and_then(|e| serde_json::from_str::<serde_json::Value>(e.get()).ok())
            .and_then(|v| v.get("targetNames").and_then(|t| t.as_array().cloned()))
            .map(|a| a.iter().map(|v| v.as_str().unwrap_or("").to_string()).collect())
            .unwrap_or_default();
        crate::memory::check(n_file, md.targets.len() + 1, 1, crate::memory::budget_bytes()?)
            .map_err(|e| err(file, format!("{} morph targets of {mname}, each one pose: {e}", md.targets.len())))?;
        description = format!("{} morph targets of {mname}, plus the base (the first pose)", md.targets.len());
        let w = md.targets.len().to_string().len();
        poses_raw.push((format!("target {:0w$} base", 0), md.positions.clone()));
        for k in 0..md.targets.len() {
            let mut weights = vec![0.0; md.targets.len()];
            weights[k] = 1.0;
            let label = names.get(k).filter(|n| !n.is_empty()).map(|n| format!(" {n}")).unwrap_or_default();
            poses_raw.push((format!("target {:0w$}{label}", k + 1), morph(&md, &weights)));
        }
    }

    // Weld exact duplicates of the base positions.
    let weld = Weld::new(&md.positions, &md.faces);
    let n_welded = weld.kept.len();
    let weld_note = if n_welded == n_file {
        format!("{n_file} vertices")
    } else {
        format!("{n_file} vertices welded to {n_welded} (seams split by the exporter)")
    };
    let more = match (others, joined.len()) {
        (0, _) => String::new(),
        (o, 1) if options.mesh.is_some() => format!(" (one of {} meshes)", o + 1),
        (o, 1) => format!(" (the largest of {} meshes)", o + 1),
        (1, _) => " (1 other mesh not read)".to_string(),
        (o, _) => format!(" ({o} other meshes not read)"),
    };
    let source = format!("{description} in {file}{more}; {weld_note}{clips}");
    let poses = poses_raw
        .into_iter()
        .map(|(name, pos)| (format!("{file} {name}"), Mesh { positions: weld.keep(&pos), faces: weld.faces.clone() }))
        .collect();
    let skin_track = match skinning {
        Some((joints, ibms)) if keep_skin && use_animation => {
            let slot: HashMap<usize, usize> = joints.iter().enumerate().map(|(k, &n)| (n, k)).collect();
            let parent = joints
                .iter()
                .map(|&n| {
                    let mut a = parents.get(n).copied().flatten();
                    // (the hierarchy was walked above: no cycle reaches here unbounded)
                    for _ in 0..parents.len() {
                        match a {
                            Some(p) if !slot.contains_key(&p) => a = parents.get(p).copied().flatten(),
                            _ => break,
                        }
                    }
                    a.and_then(|p| slot.get(&p).copied())
                })
                .collect();
            let names = joints
                .iter()
                .map(|&n| {
                    doc.nodes().nth(n).and_then(|x| x.name().map(str::to_string)).unwrap_or_else(|| format!("node {n}"))
                })
                .collect();
            let bind = ibms
                .iter()
                .map(|m| {
                    let b = m.try_inverse().unwrap_or_else(DMat4::identity);
                    std::array::from_fn(|i| b[i])
                })
                .collect();
            let influences = weld.kept.iter().map(|&j| md.influences.get(j).cloned().unwrap_or_default()).collect();
            Some(SkinTrack { names, parent, bind, world: joint_world, influences })
        }
        _ => None,
    };
    Ok((
        Gltf {
            file: file.to_string(),
            poses,
            source,
            vertices_in_file: n_file,
            vertices_welded: n_welded,
            clips: clip_list,
        },
        skin_track,
    ))
}

/// A node's local transform as stored in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Local {
    /// A 4x4 matrix, column-major (glTF's order).
    Matrix([f64; 16]),
    /// Translation, rotation (x, y, z, w) and scale.
    Trs([f64; 3], [f64; 4], [f64; 3]),
}

/// What an animation channel moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    Translation,
    Rotation,
    Scale,
    /// The morph target weights of the node's mesh.
    Weights,
}

/// One channel of a clip at its keyframes ([`Skinned::clip`]).
#[derive(Debug, Clone, PartialEq)]
pub struct KeyChannel {
    pub node: usize,
    pub path: Path,
    pub times: Vec<f64>,
    /// The value at each keyframe (3 numbers for translation and scale, 4 for a rotation, one per morph target
    /// for weights; of a CUBICSPLINE channel the value, without its tangents).
    pub values: Vec<Vec<f64>>,
}

/// A skinned mesh, its skin and its node tree, read from a `.glb` / `.gltf` with every accessor checked as for
/// [`read`]: what a rig is posed and played from (`posemfa pose`, the rig checks). The mesh is the one of the
/// first node that has both a mesh and a skin (all its triangle primitives, in order; no welding: vertex j is
/// the file's vertex j); the skin is that node's.
#[derive(Debug, Clone)]
pub struct Skinned {
    file: String,
    document: gltf::Document,
    buffers: Vec<Vec<u8>>,
    /// Index of the mesh, of the node that shows it and of its skin.
    pub mesh: usize,
    pub mesh_node: usize,
    pub skin: usize,
    /// Bind positions (POSITION).
    pub positions: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Per morph target, the position delta of every vertex.
    pub targets: Vec<Vec<[f64; 3]>>,
    /// The morph weights of the node (else the mesh), one per target.
    pub default_weights: Vec<f64>,
    /// Per vertex: every (joint slot, weight) with a non-zero weight, from all JOINTS_n / WEIGHTS_n sets; every
    /// slot is a joint of the skin and every weight finite and positive.
    pub influences: Vec<Vec<(usize, f64)>>,
    /// The node of every joint slot.
    pub joints: Vec<usize>,
    /// The inverse bind matrix of every joint slot, column-major (identity when the skin has none).
    pub inverse_bind: Vec<[f64; 16]>,
    /// Every node's parent: the node tree is checked (no node has two parents, no cycle).
    pub parent: Vec<Option<usize>>,
    /// Every node, parents before their children.
    pub order: Vec<usize>,
    /// Every node's local transform at rest.
    pub local: Vec<Local>,
    /// Every node's name, if it has one.
    pub node_names: Vec<Option<String>>,
    /// Every animation's name, if it has one.
    pub clips: Vec<Option<String>>,
}

/// Reads a skinned mesh ([`Skinned`]) from a glTF file; `resources` are the files a `.gltf` names.
pub fn read_skinned(file: &str, bytes: &[u8], resources: &[(&str, &[u8])]) -> Result<Skinned> {
    let (doc, buffers) = open(file, bytes, resources)?;
    let data = Data { file, buffers: &buffers };
    let Some((node, mesh, skin)) = doc.nodes().find_map(|n| Some((n.index(), n.mesh()?, n.skin()?))) else {
        return Err(err(
            file,
            "no node has both a mesh and a skin: the file holds no skinned mesh (a rig); export the mesh with its \
             armature"
                .into(),
        ));
    };
    let mname = name_of(mesh.name(), "mesh", mesh.index());
    check_read_size(&data, &mesh, &mname, crate::memory::budget_bytes()?)?;
    let md = read_mesh(&data, &mesh)?;
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    if joints.is_empty() {
        return Err(err(file, format!("skin {} has no joints; export the mesh with its armature", skin.index())));
    }
    let inverse_bind: Vec<[f64; 16]> = match skin.inverse_bind_matrices() {
        Some(a) => {
            data.expect(&a, "inverse bind matrices", 16)?;
            let m = data.read(&a, &format!("inverse bind matrices of skin {}", skin.index()))?;
            if m.len() != 16 * joints.len() {
                return Err(err(
                    file,
                    format!(
                        "skin {} has {} joints but {} inverse bind matrices (accessor {}); the file is damaged: \
                         export it again",
                        skin.index(),
                        joints.len(),
                        m.len() / 16,
                        a.index()
                    ),
                ));
            }
            m.chunks_exact(16).map(|c| std::array::from_fn(|i| c[i])).collect()
        }
        None => vec![std::array::from_fn(|i| if i % 5 == 0 { 1.0 } else { 0.0 }); joints.len()],
    };
    for (v, infl) in md.influences.iter().enumerate() {
        if let Some(&(j, _)) = infl.iter().find(|&&(j, _)| j >= joints.len()) {
            return Err(err(
                file,
                format!(
                    "vertex {v} of {mname} is bound to joint {j}, but skin {} has {} joints; the file is damaged: \
                     export it again",
                    skin.index(),
                    joints.len()
                ),
            ));
        }
        if let Some(&(j, w)) = infl.iter().find(|&&(_, w)| !(w > 0.0)) {
            return Err(err(
                file,
                format!(
                    "vertex {v} of {mname} has the negative weight {w} for joint {j}; skin weights are 0 to 1: the \
                     file is damaged, export it again"
                ),
            ));
        }
    }
    // The node tree: one parent per node, no cycle; parents ordered before their children.
    let n_nodes = doc.nodes().len();
    let mut parent = vec![None; n_nodes];
    for n in doc.nodes() {
        for c in n.children() {
            match parent.get_mut(c.index()) {
                Some(slot @ None) => *slot = Some(n.index()),
                Some(Some(first)) => {
                    return Err(err(
                        file,
                        format!(
                            "node {} is a child of nodes {first} and {}; a node has one parent: the file is damaged",
                            c.index(),
                            n.index()
                        ),
                    ))
                }
                None => {}
            }
        }
    }
    let mut children = vec![Vec::new(); n_nodes];
    for (c, p) in parent.iter().enumerate() {
        if let Some(p) = *p {
            children[p].push(c);
        }
    }
    let mut order: Vec<usize> = (0..n_nodes).filter(|&n| parent[n].is_none()).collect();
    let mut at = 0;
    while let Some(&n) = order.get(at) {
        order.extend(children[n].iter().copied());
        at += 1;
    }
    if order.len() != n_nodes {
        let stuck = (0..n_nodes).find(|n| !order.contains(n)).unwrap_or(0);
        return Err(err(
            file,
            format!("node {stuck} is its own ancestor: the node hierarchy has a cycle; the file is damaged"),
        ));
    }
    let local = doc
        .nodes()
        .map(|n| match n.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                Local::Matrix(std::array::from_fn(|i| f64::from(matrix[i / 4][i % 4])))
            }
            gltf::scene::Transform::Decomposed { translation: t, rotation: r, scale: s } => {
                Local::Trs(t.map(f64::from), r.map(f64::from), s.map(f64::from))
            }
        })
        .collect::<Vec<_>>();
    if let Some(n) = local.iter().position(|l| match l {
        Local::Matrix(m) => m.iter().any(|x| !x.is_finite()),
        Local::Trs(t, r, s) => t.iter().chain(r).chain(s).any(|x| !x.is_finite()),
    }) {
        return Err(err(file, format!("node {n}'s transform has a number that is not finite; the file is damaged")));
    }
    let node_ref = doc.nodes().nth(node);
    let default_weights: Vec<f64> = node_ref
        .as_ref()
        .and_then(|n| n.weights())
        .or_else(|| mesh.weights())
        .map(|w| w.iter().map(|&x| f64::from(x)).collect())
        .unwrap_or_default();
    let mut default_weights = default_weights;
    default_weights.resize(md.targets.len(), 0.0);
    let v3 = |p: &DVec3| [p.x, p.y, p.z];
    Ok(Skinned {
        file: file.to_string(),
        mesh: mesh.index(),
        mesh_node: node,
        skin: skin.index(),
        positions: md.positions.iter().map(v3).collect(),
        faces: md.faces,
        targets: md.targets.iter().map(|t| t.iter().map(v3).collect()).collect(),
        default_weights,
        influences: md.influences,
        joints,
        inverse_bind,
        parent,
        order,
        local,
        node_names: doc.nodes().map(|n| n.name().map(str::to_string)).collect(),
        clips: doc.animations().map(|a| a.name().map(str::to_string)).collect(),
        document: doc,
        buffers,
    })
}

impl Skinned {
    /// The glTF document as read (to write it again with more in it).
    pub fn json(&self) -> &gltf::json::Root {
        self.document.as_json()
    }

    /// The GLB's binary chunk, when the first buffer is one (a `.glb`).
    pub fn glb_bin(&self) -> Option<&[u8]> {
        let first = self.document.buffers().next()?;
        matches!(first.source(), gltf::buffer::Source::Bin).then(|| self.buffers[0].as_slice())
    }

    /// The channels of the animation called `name`, each at its keyframes, with every accessor checked and
    /// every value's length checked against what it moves.
    pub fn clip(&self, name: &str) -> Result<Vec<KeyChannel>> {
        let file = self.file.as_str();
        let data = Data { file, buffers: &self.buffers };
        let Some(anim) = self.document.animations().find(|a| a.name() == Some(name)) else {
            let names: Vec<String> =
                self.document.animations().map(|a| name_of(a.name(), "animation", a.index())).collect();
            return Err(err(
                file,
                format!(
                    "no animation is called '{name}'; the file has {}",
                    if names.is_empty() { "none".into() } else { names.join(", ") }
                ),
            ));
        };
        let aname = name_of(anim.name(), "animation", anim.index());
        let channels = read_channels(&data, &anim, &aname)?;
        let mut out = Vec::with_capacity(channels.len());
        for (ci, c) in channels.into_iter().enumerate() {
            use gltf::animation::Property;
            let (path, dims) = match c.property {
                Property::Translation => (Path::Translation, 3),
                Property::Rotation => (Path::Rotation, 4),
                Property::Scale => (Path::Scale, 3),
                Property::MorphTargetWeights => (
                    Path::Weights,
                    self.document
                        .nodes()
                        .nth(c.node)
                        .and_then(|n| n.mesh())
                        .map_or(0, |m| m.primitives().map(|p| p.morph_targets().len()).max().unwrap_or(0)),
                ),
            };
            let cubic = c.interpolation == gltf::animation::Interpolation::CubicSpline;
            let parts = if cubic { 3 } else { 1 };
            if c.values.first().map_or(0, Vec::len) != parts * dims || dims == 0 {
                return Err(err(
                    file,
                    format!(
                        "channel {ci} of {aname} moves {path:?} of node {} with {} numbers per keyframe, expected {}; \
                         the file is damaged: export the animation again",
                        c.node,
                        c.values.first().map_or(0, Vec::len),
                        parts * dims
                    ),
                ));
            }
            let values = c.values.into_iter().map(|v| if cubic { v[dims..2 * dims].to_vec() } else { v }).collect();
            out.push(KeyChannel { node: c.node, path, times: c.times, values });
        }
        Ok(out)
    }
}

fn morph(md: &MeshData, weights: &[f64]) -> Vec<DVec3> {
    let mut out = md.positions.clone();
    for (t, &w) in md.targets.iter().zip(weights) {
        if w != 0.0 {
            for (p, d) in out.iter_mut().zip(t) {
                *p += *d * w;
            }
        }
    }
    out
}

fn skin_positions(positions: &[DVec3], influences: &[Vec<(usize, f64)>], mats: &[DMat4]) -> Vec<DVec3> {
    positions
        .iter()
        .zip(influences)
        .map(|(&p, infl)| {
            let total: f64 = infl.iter().map(|(_, w)| w).sum();
            if infl.is_empty() || total <= 0.0 {
                return p;
            }
            infl.iter().map(|&(j, w)| mats.get(j).map_or(p, |m| apply(m, &p)) * (w / total)).sum()
        })
        .collect()
}

/// Points that are exact duplicates in the first pose (the exporter split them at seams or per face corner),
/// welded: the first of each kept. The glTF and FBX readers share it.
pub(super) struct Weld {
    pub(super) n_file: usize,
    /// The kept points, in order.
    pub(super) kept: Vec<usize>,
    /// The faces on the kept points.
    pub(super) faces: Vec<[u32; 3]>,
}

impl Weld {
    pub(super) fn new(base: &[DVec3], faces: &[[u32; 3]]) -> Weld {
        let n_file = base.len();
        let mut first_of: HashMap<[u64; 3], u32> = HashMap::with_capacity(n_file);
        let mut map = Vec::with_capacity(n_file);
        let mut kept: Vec<usize> = Vec::new();
        for (j, p) in base.iter().enumerate() {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let next = kept.len() as u32;
            let w = *first_of.entry(key).or_insert(next);
            if w == next {
                kept.push(j);
            }
            map.push(w);
        }
        let faces = faces.iter().map(|f| f.map(|v| map.get(v as usize).copied().unwrap_or(0))).collect();
        Weld { n_file, kept, faces }
    }

    /// Whether every point is kept (no duplicates): a pose needs no copy.
    pub(super) fn is_identity(&self) -> bool {
        self.kept.len() == self.n_file
    }

    /// The kept points of a pose.
    pub(super) fn keep<P: Copy + Into<[f64; 3]>>(&self, pose: &[P]) -> Vec<[f64; 3]> {
        self.kept.iter().map(|&j| pose.get(j).map_or([0.0; 3], |&p| p.into())).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use base64::Engine as _;
    use serde_json::json;

    /// A quad split along a seam (vertex 4 = vertex 0), two morph targets, two joints, as a .gltf with a
    /// data-URI buffer. `edit` changes the JSON before it is written.
    fn quad(edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
        let mut bin: Vec<u8> = Vec::new();
        let f32s = |bin: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
        // 0: positions (5 x vec3) at 0
        f32s(&mut bin, &[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0., 0., 0., 0.]);
        // 60: target 0 (vertex 1 up), 120: target 1 (vertex 3 up)
        f32s(&mut bin, &[0., 0., 0., 0., 0., 1., 0., 0., 0., 0., 0., 0., 0., 0., 0.]);
        f32s(&mut bin, &[0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 1., 0., 0., 0.]);
        // 180: indices (6 x u16) + 4 bytes padding
        for i in [0u16, 1, 2, 4, 2, 3] {
            bin.extend(i.to_le_bytes());
        }
        bin.extend([0u8; 4]);
        // 196: joints (5 x 4 u8), 216: weights (5 x vec4 f32)
        for j in [0u8, 0, 1, 1, 0] {
            bin.extend([j, 0, 0, 0]);
        }
        for _ in 0..5 {
            f32s(&mut bin, &[1., 0., 0., 0.]);
        }
        // 296: times (3 f32), 308: weights output (6 f32), 332: rotations (3 x vec4), 380: 2 identity matrices
        f32s(&mut bin, &[0., 1., 2.]);
        f32s(&mut bin, &[0., 0., 1., 0., 0., 1.]);
        let h = std::f32::consts::FRAC_1_SQRT_2;
        f32s(&mut bin, &[0., 0., 0., 1., 0., 0., h, h, 0., 0., 0., 1.]);
        for _ in 0..2 {
            f32s(&mut bin, &[1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]);
        }
        let uri =
            format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
        let view = |o: usize, l: usize| json!({"buffer": 0, "byteOffset": o, "byteLength": l});
        let acc =
            |v: usize, ct: u32, n: usize, t: &str| json!({"bufferView": v, "componentType": ct, "count": n, "type": t});
        let mut pos = acc(0, 5126, 5, "VEC3");
        pos["min"] = json!([0, 0, 0]);
        pos["max"] = json!([1, 1, 0]);
        let mut v = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": bin.len(), "uri": uri}],
            "bufferViews": [view(0, 60), view(60, 60), view(120, 60), view(180, 12), view(196, 20), view(216, 80),
                            view(296, 12), view(308, 24), view(332, 48), view(380, 128)],
            "accessors": [pos, acc(1, 5126, 5, "VEC3"), acc(2, 5126, 5, "VEC3"), acc(3, 5123, 6, "SCALAR"),
                          acc(4, 5121, 5, "VEC4"), acc(5, 5126, 5, "VEC4"), acc(6, 5126, 3, "SCALAR"),
                          acc(7, 5126, 6, "SCALAR"), acc(8, 5126, 3, "VEC4"), acc(9, 5126, 2, "MAT4")],
            "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0}, "indices": 3,
                        "targets": [{"POSITION": 1}, {"POSITION": 2}]}]}],
            "nodes": [{"name": "body", "mesh": 0}],
            "scenes": [{"nodes": [0]}],
            "animations": [{"name": "Walk", "samplers": [{"input": 6, "output": 7}],
                            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}]
        });
        edit(&mut v);
        serde_json::to_vec(&v).unwrap()
    }

    /// The quad with a skin instead of morph targets: vertices 2, 3 follow joint 1, which turns 90 degrees
    /// about z at t = 1.
    fn skinned(v: &mut serde_json::Value) {
        v["meshes"][0]["primitives"][0] =
            json!({"attributes": {"POSITION": 0, "JOINTS_0": 4, "WEIGHTS_0": 5}, "indices": 3});
        v["nodes"] =
            json!([{"name": "body", "mesh": 0, "skin": 0}, {"name": "root", "children": [2]}, {"name": "arm"}]);
        v["scenes"] = json!([{"nodes": [0, 1]}]);
        v["skins"] = json!([{"joints": [1, 2], "inverseBindMatrices": 9}]);
        v["animations"] = json!([{"name": "Bend", "samplers": [{"input": 6, "output": 8}],
                                  "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]}]);
    }

    fn load(bytes: &[u8], options: &Options) -> Result<Gltf> {
        read("t.gltf", bytes, &[], options)
    }

    fn error(bytes: &[u8]) -> String {
        let e = load(bytes, &Options::default()).unwrap_err().to_string();
        assert!(e.starts_with("file t.gltf"), "{e}");
        e
    }

    #[test]
    fn morph_targets_and_weight_animation_give_the_poses_welded() {
        let g = load(&quad(|_| {}), &Options { source: PoseSource::MorphTargets, ..Options::default() }).unwrap();
        assert_eq!((g.vertices_in_file, g.vertices_welded), (5, 4));
        assert_eq!(g.poses.len(), 3);
        assert_eq!(g.poses[0].1.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(g.poses[1].1.positions[1], [1.0, 0.0, 1.0]);
        assert_eq!(g.poses[2].1.positions[3], [0.0, 1.0, 1.0]);
        assert!(g.source.starts_with("2 morph targets of mesh 'quad', plus the base"), "{}", g.source);
        assert!(g.source.contains("5 vertices welded to 4"), "{}", g.source);
        // Auto prefers the animation: frame k shows target k.
        let a = load(&quad(|_| {}), &Options::default()).unwrap();
        assert!(
            a.source
                .starts_with("3 frames of animation 'Walk' (sampled at its keyframes, 1 fps) of mesh 'quad' in t.gltf"),
            "{}",
            a.source
        );
        for k in 0..3 {
            assert_eq!(a.poses[k].1.positions, g.poses[k].1.positions);
        }
        // --frames 5: halfway between keys is half of each target.
        let f = load(&quad(|_| {}), &Options { frames: Some(5), ..Options::default() }).unwrap();
        assert_eq!(f.poses.len(), 5);
        assert_eq!(f.poses[1].1.positions[1], [1.0, 0.0, 0.5]);
    }

    #[test]
    fn several_animations_that_move_the_mesh_are_named_with_the_one_read() {
        let two = |v: &mut serde_json::Value| {
            let walk = v["animations"][0].clone();
            let mut idle = walk.clone();
            idle["name"] = json!("Idle");
            v["animations"] = json!([walk, idle]);
        };
        let g = load(&quad(two), &Options::default()).unwrap();
        assert!(g.source.starts_with("3 frames of animation 'Walk'"), "{}", g.source);
        assert!(
            g.source.ends_with(
                "; of the 2 animations that move it ('Walk', 'Idle') the one with the most keyframes is read (the \
                 page's Animation list or the CLI's --animation NAME reads another)"
            ),
            "{}",
            g.source
        );
        // asked for by name: the one read, and no list
        let names = vec!["Walk".to_string(), "Idle".to_string()];
        assert_eq!(g.clips, Some(Clips { names: names.clone(), read: 0 }));
        let idle = load(&quad(two), &Options { animation: Some("Idle".into()), ..Options::default() }).unwrap();
        assert!(idle.source.starts_with("3 frames of animation 'Idle'"), "{}", idle.source);
        assert_eq!(idle.clips, Some(Clips { names, read: 1 }));
        assert!(!idle.source.contains("animations that move it"), "{}", idle.source);
        // one animation: no list; morph targets: no clips
        let one = load(&quad(|_| {}), &Options::default()).unwrap();
        assert!(!one.source.contains("animations that move it"));
        assert_eq!(one.clips, Some(Clips { names: vec!["Walk".into()], read: 0 }));
        let targets = Options { source: PoseSource::MorphTargets, ..Options::default() };
        assert_eq!(load(&quad(|_| {}), &targets).unwrap().clips, None);
    }

    #[test]
    fn skinned_animation_is_posed_by_the_joints() {
        let g = load(&quad(skinned), &Options::default()).unwrap();
        assert_eq!(g.poses.len(), 3);
        assert!(g.source.starts_with("3 frames of animation 'Bend'"), "{}", g.source);
        let p = &g.poses[1].1.positions;
        // vertex 2 = (1, 1, 0) turned 90 degrees about z by joint 1 -> (-1, 1, 0); vertex 1 stays.
        assert!((p[2][0] + 1.0).abs() < 1e-6 && (p[2][1] - 1.0).abs() < 1e-6, "{:?}", p[2]);
        assert_eq!(p[1], [1.0, 0.0, 0.0]);
        assert_eq!(g.poses[0].1.positions, g.poses[2].1.positions);
    }

    #[test]
    fn meshes_of_one_skin_are_read_as_one() {
        // the quad's mesh twice more: "hat" bound to the same skin, "prop" not skinned
        let three = |v: &mut serde_json::Value| {
            skinned(v);
            let prim = v["meshes"][0]["primitives"][0].clone();
            let meshes = v["meshes"].as_array_mut().unwrap();
            meshes.push(json!({"name": "hat", "primitives": [prim]}));
            meshes.push(json!({"name": "prop", "primitives": [{"attributes": {"POSITION": 0}, "indices": 3}]}));
            let nodes = v["nodes"].as_array_mut().unwrap();
            nodes.push(json!({"name": "hat", "mesh": 1, "skin": 0}));
            nodes.push(json!({"name": "prop", "mesh": 2}));
            v["scenes"] = json!([{"nodes": [0, 1, 3, 4]}]);
        };
        let g = load(&quad(three), &Options::default()).unwrap();
        assert_eq!(g.vertices_in_file, 10, "{}", g.source);
        assert!(
            g.source.contains(
                "of meshes 'quad' and 'hat' (one skin moves them; read as one mesh) in t.gltf (1 other mesh not read)"
            ),
            "{}",
            g.source
        );
        // the hat follows the same joints: its copy of vertex 2 turns with the quad's, so both weld to one
        assert_eq!(g.vertices_welded, 4);
        let p = &g.poses[1].1.positions;
        assert!((p[2][0] + 1.0).abs() < 1e-6 && (p[2][1] - 1.0).abs() < 1e-6, "{:?}", p[2]);
        assert_eq!(g.poses[1].1.faces.len(), 4);
        // one mesh asked for: that one alone
        let one = load(&quad(three), &Options { mesh: Some("hat".into()), ..Options::default() }).unwrap();
        assert_eq!(one.vertices_in_file, 5);
        assert!(one.source.contains("of mesh 'hat' in t.gltf (one of 3 meshes)"), "{}", one.source);
    }

    #[test]
    fn errors_name_the_accessor_and_say_what_to_do() {
        let e = error(&quad(|v| {
            v["accessors"][1].as_object_mut().unwrap().remove("bufferView");
        }));
        assert!(e.contains("accessors[1].bufferView: Missing data"), "{e}");
        let e = error(&quad(|v| v["accessors"][0]["count"] = json!(4_000_000_000u64)));
        assert!(e.contains("accessor 0") && e.contains("past the end of its buffer view 0"), "{e}");
        let e = error(&quad(|v| v["bufferViews"][0]["byteLength"] = json!(100_000)));
        assert!(e.contains("buffer view 0") && e.contains("past the end of buffer 0"), "{e}");
        let e = error(&quad(|v| v["accessors"][0]["count"] = json!(4)));
        assert!(
            e.contains("index 3 of primitive 0 of mesh 'quad' (accessor 3) is 4") && e.contains("4 vertices"),
            "{e}"
        );
        let e = error(&quad(|v| v["meshes"][0]["primitives"][0]["indices"] = json!(6)));
        assert!(e.contains("accessor 6") && e.contains("unsigned integers"), "{e}");
        let e = error(&quad(|v| {
            skinned(v);
            v["skins"][0].as_object_mut().unwrap().remove("inverseBindMatrices");
        }));
        assert!(e.contains("skin 0") && e.contains("inverse bind matrices"), "{e}");
        let e = error(&quad(|v| {
            v["bufferViews"][6]["byteLength"] = json!(0);
            v["accessors"][6]["count"] = json!(0);
        }));
        assert!(e.contains("no keyframes") || e.contains("not a valid glTF"), "{e}");
        let e = error(&quad(|v| {
            v["meshes"][0]["primitives"][0]["targets"] = json!([]);
            v.as_object_mut().unwrap().remove("animations");
        }));
        assert!(e.contains("no morph targets and no animation"), "{e}");
        let e = error(&quad(|v| v["buffers"][0]["uri"] = json!("quad.bin")));
        assert!(e.contains("`quad.bin`, which was not given"), "{e}");
    }

    /// Sparse accessors (glTF 2.0, 3.6.2.3) are read with their substitutions: on a buffer view (POSITION's
    /// vertex 1 moved to (0, 0, 1)) and without one (morph target 0 as zeros plus its one non-zero delta, which
    /// reads as the dense target did). Sparse index 1 is the u16 at byte 2 of the index view, its value the
    /// vec3 at byte 12 of target 0's view.
    #[test]
    fn sparse_accessors_are_read_with_their_substitutions() {
        let one = json!({"count": 1, "indices": {"bufferView": 3, "byteOffset": 2, "componentType": 5123},
                         "values": {"bufferView": 1, "byteOffset": 12}});
        let dense = load(&quad(|_| {}), &Options::default()).unwrap();
        let sparse_target = load(
            &quad(|v| {
                v["accessors"][1].as_object_mut().unwrap().remove("bufferView");
                v["accessors"][1]["sparse"] = one.clone();
            }),
            &Options::default(),
        )
        .unwrap();
        assert_eq!(sparse_target.poses.len(), dense.poses.len());
        for ((_, a), (_, b)) in sparse_target.poses.iter().zip(&dense.poses) {
            assert_eq!(a.positions, b.positions);
        }
        let moved = load(&quad(|v| v["accessors"][0]["sparse"] = one.clone()), &Options::default()).unwrap();
        let base = &moved.poses[0].1.positions;
        assert_eq!(base[1], [0.0, 0.0, 1.0]);
        assert_eq!(base[2], dense.poses[0].1.positions[2]);
        // indices that do not increase, or run past the accessor
        let e = error(&quad(|v| {
            v["accessors"][0]["sparse"] = json!({"count": 2, "indices": {"bufferView": 3, "byteOffset": 6,
                "componentType": 5123}, "values": {"bufferView": 1}});
        }));
        assert!(e.contains("accessor 0") && e.contains("sparse index 1 is 2") && e.contains("must increase"), "{e}");
        // byte 14 of the rotations' view is 0x80 (of 1.0f32): index 128 of 5 vertices
        let e = error(&quad(|v| {
            v["accessors"][0]["sparse"] = json!({"count": 1, "indices": {"bufferView": 8, "byteOffset": 14,
                "componentType": 5121}, "values": {"bufferView": 1}});
        }));
        assert!(e.contains("sparse index 0 is 128") && e.contains("below the accessor's 5 elements"), "{e}");
        let e = error(&quad(|v| {
            v["accessors"][0]["sparse"] = json!({"count": 5, "indices": {"bufferView": 3, "byteOffset": 4,
                "componentType": 5123}, "values": {"bufferView": 1}});
        }));
        assert!(e.contains("5 sparse indices of 2 bytes from byte 4 run past the end of buffer view 3"), "{e}");
    }

    #[test]
    fn glb_container_lengths_are_checked() {
        let json = quad(|_| {});
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        let total = 12 + 8 + json.len().div_ceil(4) * 4;
        glb.extend((total as u32).to_le_bytes());
        glb.extend((json.len().div_ceil(4) as u32 * 4).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(&json);
        while glb.len() < total {
            glb.push(b' ');
        }
        let g = read("t.glb", &glb, &[], &Options::default()).unwrap();
        assert_eq!(g.poses.len(), 3);
        let mut bad = glb.clone();
        bad[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = read("t.glb", &bad, &[], &Options::default()).unwrap_err().to_string();
        assert!(e.contains("GLB header says 4294967295 bytes"), "{e}");
        let mut bad = glb.clone();
        bad[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = read("t.glb", &bad, &[], &Options::default()).unwrap_err().to_string();
        assert!(e.contains("past the end of the file"), "{e}");
        for n in 0..20 {
            let _ = read("t.glb", &glb[..n], &[], &Options::default());
        }
    }

    /// A primitive may reuse another's accessors: 1000 primitives over the quad's 5 vertices name 5000
    /// vertices (with 2 morph targets each). The size is checked from the document before anything is read.
    #[test]
    fn reused_accessors_are_counted_before_reading() {
        let bytes = quad(|v| {
            let p = v["meshes"][0]["primitives"][0].clone();
            v["meshes"][0]["primitives"] = json!(vec![p; 1000]);
        });
        let doc = gltf::Gltf::from_slice(&bytes).unwrap().document;
        let bufs = buffers("t.gltf", &doc, None, &[]).unwrap();
        let data = Data { file: "t.gltf", buffers: &bufs };
        let mesh = doc.meshes().next().unwrap();
        // 5000 vertices x (24 x 3 + 304) + 6000 indices x 20 = 1_880_000 + 120_000 bytes.
        assert!(check_read_size(&data, &mesh, "mesh 'quad'", 2_000_000).is_ok());
        let e = check_read_size(&data, &mesh, "mesh 'quad'", 1_999_999).unwrap_err().to_string();
        assert!(e.contains("mesh 'quad' has 5000 vertices with 2 morph targets and 6000 indices"), "{e}");
        assert!(e.contains("more than the memory budget of 1.9 MiB"), "{e}");
        // Each accessor's own bounds come first.
        let bytes = quad(|v| {
            v["accessors"][1]["count"] = json!(1_000_000);
        });
        let doc = gltf::Gltf::from_slice(&bytes).unwrap().document;
        let bufs = buffers("t.gltf", &doc, None, &[]).unwrap();
        let data = Data { file: "t.gltf", buffers: &bufs };
        let e = check_read_size(&data, &doc.meshes().next().unwrap(), "mesh 'quad'", 1).unwrap_err().to_string();
        assert!(
            e.contains("accessor 1 (morph target 0 of primitive 0 of mesh 'quad'") && e.contains("past the end"),
            "{e}"
        );
    }

    /// Offsets and lengths near 2^64 are refused, not wrapped (the sums saturate).
    #[test]
    fn huge_offsets_are_refused() {
        let e = error(&quad(|v| {
            v["bufferViews"][0]["byteOffset"] = json!(u64::MAX - 10);
        }));
        assert!(e.contains("buffer view 0") && e.contains("past the end of buffer 0"), "{e}");
        let e = error(&quad(|v| {
            v["accessors"][0]["byteOffset"] = json!(u64::MAX - 2);
        }));
        assert!(e.contains("accessor 0") && e.contains("past the end of its buffer view 0"), "{e}");
    }

    /// Global transforms over a deep chain equal the product of the locals; a cycle (invalid, but possible in
    /// a damaged file) ends.
    #[test]
    fn globals_of_chains_and_cycles() {
        let n = 5000;
        let parents: Vec<Option<usize>> = (0..n).map(|i| if i == 0 { None } else { Some(i - 1) }).collect();
        let step = (DVec3::new(1.0, 0.0, 0.0), DQuat::identity(), DVec3::repeat(1.0));
        let g = globals(&parents, &vec![step; n]);
        assert_eq!(g[n - 1].column(3)[0], (n - 1 + 1) as f64);
        // Reverse order of computation (leaf first) gives the same.
        let rev: Vec<Option<usize>> = (0..n).map(|i| if i == n - 1 { None } else { Some(i + 1) }).collect();
        let g = globals(&rev, &vec![step; n]);
        assert_eq!(g[0].column(3)[0], n as f64);
        let cycle = vec![Some(2), Some(0), Some(1)];
        let g = globals(&cycle, &vec![step; 3]);
        assert!(g.iter().all(|m| m.iter().all(|x| x.is_finite())));
        assert_eq!(joint_ancestors(&cycle, &[0]), vec![true, true, true]);
        assert_eq!(joint_ancestors(&parents[..4], &[2]), vec![true, true, true, false]);
    }

    /// The `gltf` crate does not validate animation channel targets (and panics on reading an invalid one):
    /// an unknown path or a missing node is an error naming the channel.
    #[test]
    fn invalid_channel_targets_are_refused() {
        for (path, node) in [("pointer", 0), ("tranSlation", 0), ("weights", 9)] {
            let e = error(&quad(|v| {
                v["animations"][0]["channels"][0]["target"] = json!({"node": node, "path": path});
            }));
            assert!(e.contains("channel 0 of animation 0 has an invalid target"), "{e}");
        }
    }

    /// The `gltf` crate's validation indexes the accessors with a POSITION index unchecked; such a file is
    /// refused before it gets there (found by the gltf_read fuzz target).
    #[test]
    fn attribute_accessor_out_of_range_is_refused() {
        let e = error(&quad(|v| v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99)));
        assert!(e.contains("names accessor 99, but the file has 10"), "{e}");
    }
}
