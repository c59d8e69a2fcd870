//! From a set of files (a drop, a folder, a command line) to the poses of one population, whatever the
//! format: the reader is picked by the file's extension.
//!
//! - `.obj`, `.ply`: one file per pose (OBJ and PLY may be mixed).
//! - `.pc2`, `.mdd`: one point cache whose frames are the poses, plus exactly one base mesh (`.obj`, `.ply`,
//!   `.glb`, `.gltf`) that gives the faces.
//! - `.glb`, `.gltf` (with the `.bin` and image files it names): the poses of one of its meshes, see
//!   [`super::gltf`].
//! - `.fbx` (binary FBX 7.x): the poses of one of its meshes, see [`super::fbx`].
//! - `.usd`, `.usda`, `.usdc`, `.usdz`: the poses of one point-cached mesh, see [`super::usd`].
//! - `.zip`: an archive of any of these, opened as the page opens one ([`super::zip_archive`]): its mesh files
//!   (named `ARCHIVE/PATH`, in natural order) read as if they had been given, what was skipped said in the source.
//! - `.mtl` files (OBJ materials) are ignored; a file with any other extension (or none) is refused by name,
//!   with the list of what posemfa reads ([`formats_read`]), rather than read as OBJ.
//!
//! [`FORMATS`] is the one list of extensions: the readers ([`FileKind::of`]), the folder listing
//! ([`FileKind::is_known_extension`]), the refusal of other files and the command line's help all come from it.
//!
//! Every path says where the poses came from ([`Loaded::source`]), e.g. "11 OBJ files",
//! "48 frames of the point cache gallop.pc2 (frames 0 to 47), faces from reference.obj".

use super::{cache, fbx, gltf, obj, ply, usd, Mesh};
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
    Fbx,
    Usd,
    /// Files a glTF may refer to (`.bin` buffers, images).
    Resource,
    /// Files that come with meshes and are not read (`.mtl`).
    Ignored,
    /// A `.zip` archive of mesh files, opened by [`load_with`] ([`super::zip_archive`]).
    Zip,
    /// Any other extension, or none: refused by name ([`unknown_format`]).
    Unknown,
}

/// One format posemfa reads: its extensions (lower case) and what each file is.
#[derive(Debug, Clone, Copy)]
pub struct Format {
    /// Shown in [`formats_read`] (".glb/.gltf") and picked up from a folder; the first extension is the
    /// format's usual one.
    pub extensions: &'static [(&'static str, FileKind)],
    /// What [`formats_read`] says after the extensions (" with a base mesh"), or "".
    pub note: &'static str,
}

/// Every format posemfa reads, in the order [`formats_read`] lists them. A new reader adds its row here (and
/// its [`FileKind`] to [`load_with`]).
pub const FORMATS: &[Format] = &[
    Format { extensions: &[("obj", FileKind::Obj)], note: "" },
    Format { extensions: &[("ply", FileKind::Ply)], note: "" },
    Format { extensions: &[("glb", FileKind::Glb), ("gltf", FileKind::Gltf)], note: "" },
    Format { extensions: &[("fbx", FileKind::Fbx)], note: "" },
    Format {
        extensions: &[
            ("usd", FileKind::Usd),
            ("usda", FileKind::Usd),
            ("usdc", FileKind::Usd),
            ("usdz", FileKind::Usd),
        ],
        note: "",
    },
    Format { extensions: &[("pc2", FileKind::Pc2), ("mdd", FileKind::Mdd)], note: " with a base mesh" },
];

/// Files read although [`formats_read`] does not list them: a VRM avatar is a .glb; a .gltf's buffers and
/// images; OBJ materials (ignored). `listed`: picked up from a folder (images are not: posemfa reads no
/// texture).
const OTHER_EXTENSIONS: &[(&str, FileKind, bool)] = &[
    ("vrm", FileKind::Glb, true),
    ("bin", FileKind::Resource, true),
    ("png", FileKind::Resource, false),
    ("jpg", FileKind::Resource, false),
    ("jpeg", FileKind::Resource, false),
    ("webp", FileKind::Resource, false),
    ("ktx2", FileKind::Resource, false),
    ("mtl", FileKind::Ignored, false),
    // (not picked up from a folder: a folder's files and an archive of the same poses beside them would be read
    // twice)
    ("zip", FileKind::Zip, false),
];

/// What posemfa reads, for people: ".obj, .ply, .glb/.gltf, .fbx, .usd/.usda/.usdc/.usdz, .pc2/.mdd with a base mesh" (from [`FORMATS`]).
pub fn formats_read() -> String {
    let shown: Vec<String> = FORMATS
        .iter()
        .map(|f| {
            let exts: Vec<String> = f.extensions.iter().map(|(e, _)| format!(".{e}")).collect();
            format!("{}{}", exts.join("/"), f.note)
        })
        .collect();
    shown.join(", ")
}

/// The error for a file whose extension is none of [`FORMATS`]: names the file, lists what posemfa reads and
/// says what to do. E.g. "file cat.blend: posemfa reads .obj, .ply, ...; not .blend: export the poses as one of
/// these".
pub fn unknown_format(name: &str) -> Error {
    let what = match extension(name) {
        Some(ext) => format!("not .{ext}"),
        None => "this file has no extension".to_string(),
    };
    Error::Population {
        file: name.to_string(),
        message: format!(
            "posemfa reads {}; {what}: export the poses as one of these (e.g. glTF from Blender), or leave the \
             file out",
            formats_read()
        ),
    }
}

/// The extension of a file name, lower case, if it has one ("a.OBJ" -> "obj"; "pose1", ".hidden" -> None).
fn extension(name: &str) -> Option<String> {
    let file = name.rsplit(['/', '\\']).next().unwrap_or(name);
    match file.rsplit_once('.') {
        Some((stem, ext)) if !stem.is_empty() && !ext.is_empty() => Some(ext.to_ascii_lowercase()),
        _ => None,
    }
}

impl FileKind {
    /// What a file is, by its extension (any case).
    pub fn of(name: &str) -> FileKind {
        let Some(ext) = extension(name) else { return FileKind::Unknown };
        let read = FORMATS.iter().flat_map(|f| f.extensions).map(|&(e, k)| (e, k));
        let other = OTHER_EXTENSIONS.iter().map(|&(e, k, _)| (e, k));
        read.chain(other).find(|(e, _)| *e == ext).map_or(FileKind::Unknown, |(_, k)| k)
    }

    /// Whether a folder listing should pick the file up: the formats read, .vrm and a .gltf's .bin buffers.
    pub fn is_known_extension(name: &str) -> bool {
        let Some(ext) = extension(name) else { return false };
        FORMATS.iter().flat_map(|f| f.extensions).any(|(e, _)| *e == ext)
            || OTHER_EXTENSIONS.iter().any(|(e, _, listed)| *listed && *e == ext)
    }
}

/// The poses read from a set of files, before they are checked and normalised as a population.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// One (name, mesh) per pose; the names sort in pose order (natural sort).
    pub poses: Vec<(String, Mesh)>,
    /// Where the poses came from, for people ("48 morph targets of mesh 'horse' in horse.glb").
    pub source: String,
    /// A glTF's animations that move its mesh and the one read ([`gltf::Clips`]).
    pub clips: Option<gltf::Clips>,
}

/// Reads one per-pose mesh file by its extension (.obj or .ply; any other is refused by name).
pub fn read_mesh(name: &str, bytes: &[u8]) -> Result<Mesh> {
    match FileKind::of(name) {
        FileKind::Ply => ply::parse_ply(name, bytes),
        FileKind::Obj => obj::parse_obj(name, bytes),
        _ => Err(unknown_format(name)),
    }
}

/// The vertex positions of one OBJ or PLY file that [`read_mesh`] has read without error, as it gives them
/// (OBJ files skip their one-line faces: [`obj::parse_obj_positions`]).
pub fn read_positions(name: &str, bytes: &[u8]) -> Result<Vec<[f64; 3]>> {
    match FileKind::of(name) {
        FileKind::Obj => obj::parse_obj_positions(name, bytes),
        _ => read_mesh(name, bytes).map(|m| m.positions),
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

/// [`load`] with choices for glTF files (which mesh, which animation, how many frames, which poses). A `.zip`
/// among the files is opened ([`super::zip_archive`]; all archives together may unpack to half the memory
/// budget), its mesh files take its place, and the source says which archive they came from and what it
/// skipped.
pub fn load_with(files: Vec<(String, Vec<u8>)>, options: &gltf::Options) -> std::result::Result<Loaded, Vec<Error>> {
    if !files.iter().any(|(n, _)| FileKind::of(n) == FileKind::Zip) {
        return load_files(files, options);
    }
    let mut budget = crate::memory::budget_bytes().map_err(|e| vec![e])? / 2;
    let mut opened = Vec::with_capacity(files.len());
    let mut notes = Vec::new();
    for (name, bytes) in files {
        if FileKind::of(&name) != FileKind::Zip {
            opened.push((name, bytes));
            continue;
        }
        let archive = super::zip_archive::open(&name, &bytes, budget).map_err(|e| vec![e])?;
        budget -= archive.unpacked;
        notes.push(archive.note(&name));
        opened.extend(archive.files);
    }
    opened.sort_by(|a, b| super::population::natural_cmp(&a.0, &b.0));
    let mut loaded = load_files(opened, options)?;
    loaded.source = format!("{}; {}", loaded.source, notes.join("; "));
    Ok(loaded)
}

/// [`load_with`] once the archives are opened.
fn load_files(files: Vec<(String, Vec<u8>)>, options: &gltf::Options) -> std::result::Result<Loaded, Vec<Error>> {
    let kinds: Vec<FileKind> = files.iter().map(|(n, _)| FileKind::of(n)).collect();
    let unknown: Vec<Error> = files
        .iter()
        .zip(&kinds)
        .filter(|(_, k)| **k == FileKind::Unknown)
        .map(|((n, _), _)| unknown_format(n))
        .collect();
    if !unknown.is_empty() {
        return Err(unknown);
    }
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
        return Ok(Loaded { poses, source, clips: None });
    }
    if let Some(l) = load_scene(&files, &kinds, n_gltf + n_mesh, options)? {
        return Ok(l);
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
        return Ok(Loaded { poses: g.poses, source: g.source, clips: g.clips });
    }
    let mut poses = Vec::with_capacity(n_mesh);
    // (each error with its file's place, for the set's first mismatch among the files that read to join them)
    let mut errors = Vec::new();
    let (mut n_obj, mut n_ply) = (0, 0);
    for (at, ((name, bytes), kind)) in files.into_iter().zip(kinds).enumerate() {
        match kind {
            FileKind::Obj => n_obj += 1,
            FileKind::Ply => n_ply += 1,
            _ => continue,
        }
        match read_mesh(&name, &bytes) {
            Ok(m) => poses.push((at, name, m)),
            Err(e) => errors.push((at, e)),
        }
    }
    if !errors.is_empty() {
        // the files that read, in natural order (as the population would check them)
        poses.sort_by(|a, b| super::population::natural_cmp(&a.1, &b.1));
        let mismatch = super::population::first_mismatch(poses.iter().map(|p| (p.1.as_str(), &p.2)));
        errors.extend(mismatch.map(|(k, e)| (poses[k].0, e)));
        errors.sort_by_key(|e| e.0);
        return Err(errors.into_iter().map(|e| e.1).collect());
    }
    let poses = poses.into_iter().map(|(_, name, m)| (name, m)).collect();
    Ok(Loaded { poses, source: mesh_files_source(n_obj, n_ply), clips: None })
}

/// An FBX or USD file (alone): its poses. None when no such file was given.
fn load_scene(
    files: &[(String, Vec<u8>)],
    kinds: &[FileKind],
    n_other_meshes: usize,
    options: &gltf::Options,
) -> std::result::Result<Option<Loaded>, Vec<Error>> {
    let scenes: Vec<&(String, Vec<u8>)> =
        files.iter().zip(kinds).filter(|(_, k)| matches!(k, FileKind::Fbx | FileKind::Usd)).map(|(f, _)| f).collect();
    let Some((name, bytes)) = scenes.first().copied() else { return Ok(None) };
    if scenes.len() > 1 || n_other_meshes > 0 {
        return Err(set_error(
            name,
            format!(
                "was given with {} other mesh file(s): the poses come from one FBX or USD file alone; load it by itself",
                scenes.len() - 1 + n_other_meshes
            ),
        ));
    }
    let g = if FileKind::of(name) == FileKind::Usd {
        usd::read(name, bytes, options)
    } else {
        fbx::read(name, bytes, options)
    };
    let g = g.map_err(|e| vec![e])?;
    Ok(Some(Loaded { poses: g.poses, source: g.source, clips: g.clips }))
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

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: &[u8] = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

    #[test]
    fn the_formats_read_come_from_one_table() {
        assert_eq!(formats_read(), ".obj, .ply, .glb/.gltf, .fbx, .usd/.usda/.usdc/.usdz, .pc2/.mdd with a base mesh");
        for f in FORMATS {
            for (ext, kind) in f.extensions {
                assert_eq!(FileKind::of(&format!("pose.{}", ext.to_ascii_uppercase())), *kind, ".{ext}");
                assert!(FileKind::is_known_extension(&format!("dir/pose.{ext}")), ".{ext}");
            }
        }
        assert_eq!(FileKind::of("avatar.vrm"), FileKind::Glb);
        assert_eq!(FileKind::of("body.mtl"), FileKind::Ignored);
        assert_eq!(FileKind::of("texture.png"), FileKind::Resource);
        assert_eq!(FileKind::of("poses.ZIP"), FileKind::Zip);
        assert!(!FileKind::is_known_extension("poses.zip"), "a folder's .zip is not read beside its files");
        for name in ["notes.txt", "pose1", ".hidden", "scene.blend", "a.obj/readme"] {
            assert_eq!(FileKind::of(name), FileKind::Unknown, "{name}");
            assert!(!FileKind::is_known_extension(name), "{name}");
        }
        assert!(!FileKind::is_known_extension("texture.png") && !FileKind::is_known_extension("body.mtl"));
    }

    /// A .zip given with the files is opened in place: its mesh files join the others in natural order, and
    /// the source says where they came from.
    #[test]
    fn a_zip_among_the_files_is_opened() {
        use std::io::Write;
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        for path in ["p/b10.obj", "p/b2.obj", "notes.txt"] {
            w.start_file(path, zip::write::SimpleFileOptions::default()).unwrap();
            w.write_all(TRI).unwrap();
        }
        let z = w.finish().unwrap().into_inner();
        let l = load(vec![("a1.obj".to_string(), TRI.to_vec()), ("set.zip".to_string(), z)]).unwrap();
        let names: Vec<&str> = l.poses.iter().map(|p| p.0.as_str()).collect();
        assert_eq!(names, ["a1.obj", "set.zip/p/b2.obj", "set.zip/p/b10.obj"]);
        assert_eq!(l.source, "3 OBJ files; read from set.zip (2 mesh files; skipped notes.txt (not a mesh file))");
    }

    /// A file of an extension posemfa does not read is refused by name with the list of what it reads, not
    /// parsed as OBJ; .mtl files next to OBJ files stay ignored.
    #[test]
    fn a_file_of_another_extension_is_refused_by_name() {
        let files = vec![
            ("a.obj".to_string(), TRI.to_vec()),
            ("scene.blend".to_string(), b"BLENDER-v300\0\0binary".to_vec()),
            ("b.obj".to_string(), TRI.to_vec()),
            ("README".to_string(), b"v 0 0 0\n".to_vec()),
        ];
        let errors = load(files).unwrap_err();
        let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
        assert_eq!(
            text,
            [
                "file scene.blend: posemfa reads .obj, .ply, .glb/.gltf, .fbx, .usd/.usda/.usdc/.usdz, .pc2/.mdd with a base mesh; not .blend: \
                 export the poses as one of these (e.g. glTF from Blender), or leave the file out",
                "file README: posemfa reads .obj, .ply, .glb/.gltf, .fbx, .usd/.usda/.usdc/.usdz, .pc2/.mdd with a base mesh; this file has no \
                 extension: export the poses as one of these (e.g. glTF from Blender), or leave the file out",
            ]
        );
        assert_eq!(read_mesh("x.txt", TRI).unwrap_err().to_string(), unknown_format("x.txt").to_string());

        let with_mtl = vec![
            ("a.obj".to_string(), TRI.to_vec()),
            ("a.mtl".to_string(), b"newmtl skin\n".to_vec()),
            ("b.OBJ".to_string(), TRI.to_vec()),
        ];
        let l = load(with_mtl).unwrap();
        assert_eq!(l.poses.len(), 2);
        assert_eq!(l.source, "2 OBJ files");
    }
}
