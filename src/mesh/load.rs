//! From a set of files (a drop, a folder, a command line) to the poses of one population, whatever the
//! format: the reader is picked by the file's extension.
//!
//! - `.obj`, `.ply`: one file per pose (OBJ and PLY may be mixed).
//! - `.pc2`, `.mdd`: one point cache whose frames are the poses, plus exactly one base mesh (`.obj`, `.ply`,
//!   `.glb`, `.gltf`) that gives the faces.
//! - `.glb`, `.gltf` (with the `.bin` and image files it names): the poses of one of its meshes, see
//!   [`super::gltf`].
//! - `.mtl` files (OBJ materials) are ignored; a file with any other extension is read as OBJ.
//!
//! Every path says where the poses came from ([`Loaded::source`]), e.g. "11 OBJ files",
//! "48 frames of the point cache gallop.pc2 (frames 0 to 47), faces from reference.obj".

use super::{cache, gltf, obj, ply, Mesh};
use crate::error::{Error, Result};

/// What a file is, by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    Obj,
    Ply,
    Gltf,
    Glb,
    Pc2,
    Mdd,
    /// Files a glTF may refer to (`.bin` buffers, images).
    Resource,
    /// Files that come with meshes and are not read (`.mtl`).
    Ignored,
}

impl FileKind {
    pub fn of(name: &str) -> FileKind {
        let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
        match ext.as_str() {
            "ply" => FileKind::Ply,
            "gltf" => FileKind::Gltf,
            "glb" | "vrm" => FileKind::Glb,
            "pc2" => FileKind::Pc2,
            "mdd" => FileKind::Mdd,
            "bin" | "png" | "jpg" | "jpeg" | "webp" | "ktx2" => FileKind::Resource,
            "mtl" => FileKind::Ignored,
            _ => FileKind::Obj,
        }
    }

    /// Whether a folder listing should pick the file up.
    pub fn is_known_extension(name: &str) -> bool {
        let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
        matches!(ext.as_str(), "obj" | "ply" | "gltf" | "glb" | "pc2" | "mdd" | "bin")
    }
}

/// The poses read from a set of files, before they are checked and normalised as a population.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// One (name, mesh) per pose; the names sort in pose order (natural sort).
    pub poses: Vec<(String, Mesh)>,
    /// Where the poses came from, for people ("48 morph targets of mesh 'horse' in horse.glb").
    pub source: String,
}

/// Reads one per-pose mesh file by its extension.
pub fn read_mesh(name: &str, bytes: &[u8]) -> Result<Mesh> {
    match FileKind::of(name) {
        FileKind::Ply => ply::parse_ply(name, bytes),
        _ => obj::parse_obj(name, bytes),
    }
}

fn set_error(file: &str, message: String) -> Vec<Error> {
    vec![Error::Population { file: file.to_string(), message }]
}

/// Reads a set of files into poses. Errors: every file's error (per-pose files), or the one that stops the
/// set (a cache without a base mesh, two glTF files, ...).
pub fn load(files: Vec<(String, Vec<u8>)>) -> std::result::Result<Loaded, Vec<Error>> {
    load_with(files, &gltf::Options::default())
}

/// [`load`] with choices for glTF files (which mesh, which animation, how many frames, which poses).
pub fn load_with(files: Vec<(String, Vec<u8>)>, options: &gltf::Options) -> std::result::Result<Loaded, Vec<Error>> {
    let kinds: Vec<FileKind> = files.iter().map(|(n, _)| FileKind::of(n)).collect();
    let count = |k: &[FileKind]| kinds.iter().filter(|x| k.contains(x)).count();
    let n_cache = count(&[FileKind::Pc2, FileKind::Mdd]);
    let n_gltf = count(&[FileKind::Gltf, FileKind::Glb]);
    let n_mesh = count(&[FileKind::Obj, FileKind::Ply]);
    let first_of = |k: &[FileKind]| files.iter().zip(&kinds).find(|(_, x)| k.contains(x)).map(|(f, _)| f);

    if n_cache > 0 {
        let Some((cache_name, cache_bytes)) = first_of(&[FileKind::Pc2, FileKind::Mdd]) else { return Err(vec![]) };
        if n_cache > 1 {
            return Err(set_error(
                cache_name,
                format!("{n_cache} point caches were given; load one point cache (with its base mesh) at a time"),
            ));
        }
        if n_gltf + n_mesh != 1 {
            return Err(set_error(
                cache_name,
                format!(
                    "a point cache holds only positions: give it exactly one base mesh (.obj, .ply, .glb or .gltf) \
                     with the same vertices, which gives the faces; got {} mesh files",
                    n_gltf + n_mesh
                ),
            ));
        }
        let cache = match FileKind::of(cache_name) {
            FileKind::Pc2 => cache::parse_pc2(cache_name, cache_bytes),
            _ => cache::parse_mdd(cache_name, cache_bytes),
        }
        .map_err(|e| vec![e])?;
        let (base_name, base) = if n_gltf == 1 {
            let g = gltf::load_files(&files, options)?;
            let base = g.poses.into_iter().next().map(|(_, m)| m).ok_or_else(Vec::new)?;
            (g.file, base)
        } else {
            let Some((name, bytes)) = first_of(&[FileKind::Obj, FileKind::Ply]) else { return Err(vec![]) };
            (name.clone(), read_mesh(name, bytes).map_err(|e| vec![e])?)
        };
        if cache.points != base.positions.len() {
            return Err(set_error(
                cache_name,
                format!(
                    "has {} vertices per frame but the base mesh {base_name} has {}; the cache must be written \
                     from that very mesh (same vertices, same order)",
                    cache.points,
                    base.positions.len()
                ),
            ));
        }
        let source = format!("{}, faces from {base_name}", cache.describe(cache_name));
        let width = cache.frames.len().to_string().len();
        let poses = cache
            .frames
            .into_iter()
            .enumerate()
            .map(|(f, positions)| {
                (format!("{cache_name} frame {:0width$}", f + 1), Mesh { positions, faces: base.faces.clone() })
            })
            .collect();
        return Ok(Loaded { poses, source });
    }
    if n_gltf > 0 {
        if n_mesh > 0 {
            let name = first_of(&[FileKind::Obj, FileKind::Ply]).map(|f| f.0.as_str()).unwrap_or("");
            return Err(set_error(
                name,
                "was given with a glTF file: the poses come either from one glTF file or from one mesh file per \
                 pose; load them separately"
                    .into(),
            ));
        }
        let g = gltf::load_files(&files, options)?;
        return Ok(Loaded { poses: g.poses, source: g.source });
    }
    let mut poses = Vec::with_capacity(n_mesh);
    let mut errors = Vec::new();
    let (mut n_obj, mut n_ply) = (0, 0);
    for ((name, bytes), kind) in files.into_iter().zip(kinds) {
        match kind {
            FileKind::Obj => n_obj += 1,
            FileKind::Ply => n_ply += 1,
            _ => continue,
        }
        match read_mesh(&name, &bytes) {
            Ok(m) => poses.push((name, m)),
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(Loaded { poses, source: mesh_files_source(n_obj, n_ply) })
}

/// Where poses read from one mesh file each came from: "11 OBJ files", "1 OBJ and 2 PLY files".
pub(super) fn mesh_files_source(n_obj: usize, n_ply: usize) -> String {
    let plural = |n: usize, what: &str| format!("{n} {what} file{}", if n == 1 { "" } else { "s" });
    match (n_obj, n_ply) {
        (o, 0) => plural(o, "OBJ"),
        (0, p) => plural(p, "PLY"),
        (o, p) => format!("{o} OBJ and {}", plural(p, "PLY")),
    }
}
