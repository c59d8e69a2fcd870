//! A `.zip` of mesh files, opened as the page opens one: `posemfa fit poses.zip` reads what the
//! page reads when the same archive is dropped on it (`www/drop.js` unzips with fflate, and hands the entries
//! to the same [`super::load`]).
//!
//! - Entries are named `ARCHIVE/PATH` (`poses.zip/walk/pose01.obj`), as the page names them, and come in
//!   natural order of those names, as a folder's files do: nested folders sort by their path, `pose2` before
//!   `pose10`.
//! - Read: the entries a folder listing picks up ([`FileKind::is_known_extension`]: the mesh formats, `.vrm`,
//!   a `.gltf`'s `.bin`). Skipped, each named with why in [`Archive::note`]: folders, `__MACOSX/` (macOS
//!   resource forks), hidden files (a path part starting with `.`), archives inside the archive (not opened),
//!   anything else (README, images, `.mtl`).
//! - Refused, by name: an archive that does not open (cut, damaged, not a zip), an encrypted entry, an entry
//!   in a compression method other than stored and deflate, an entry that does not unpack (corrupt data, CRC
//!   mismatch), and zip bombs: the mesh entries may unpack to at most `budget` bytes together (the caller
//!   gives half the memory budget, [`crate::memory::budget_bytes`]). The sizes the archive declares are added
//!   up first, so an honest bomb is refused before anything is unpacked; each entry is then unpacked at most
//!   to the size it declares (one byte more is an error), so a lying one is cut off there, and no more than
//!   the budget is ever allocated.

use super::load::FileKind;
use super::population::natural_cmp;
use crate::error::{Error, Result};
use crate::memory::show_bytes;
use std::io::Read;

/// The mesh files of an archive and what was skipped.
#[derive(Debug)]
pub struct Archive {
    /// `(ARCHIVE/PATH, bytes)`, in natural order of the names.
    pub files: Vec<(String, Vec<u8>)>,
    /// Entries not read (folders aside): `(PATH, why)`, in the archive's order.
    pub skipped: Vec<(String, &'static str)>,
    /// Bytes the mesh files unpacked to, together.
    pub unpacked: u64,
}

fn err(file: &str, message: String) -> Error {
    Error::Population { file: file.to_string(), message }
}

/// Whether `path` names a model file (`.posemfa`): the page opens one from an archive ([`open_with`]).
fn is_model(path: &str) -> bool {
    path.to_ascii_lowercase().ends_with(&format!(".{}", crate::model_file::EXTENSION))
}

/// Why an entry is not read, or None when it is a file posemfa reads (`models`: model files too).
fn skip_reason(path: &str, models: bool) -> Option<&'static str> {
    let parts: Vec<&str> = path.split('/').filter(|p| !p.is_empty()).collect();
    if parts.first() == Some(&"__MACOSX") {
        return Some("macOS resource fork");
    }
    if parts.iter().any(|p| p.starts_with('.')) {
        return Some("hidden file");
    }
    let file = parts.last().copied().unwrap_or("");
    if file.to_ascii_lowercase().ends_with(".zip") {
        return Some("an archive inside the archive, not opened");
    }
    if !(FileKind::is_known_extension(file) || models && is_model(file)) {
        return Some("not a mesh file");
    }
    None
}

/// Whether the archive holds a model file (`.posemfa`) that [`open_with`] would read, from its listing alone
/// (nothing unpacked); false for an archive that does not open (opening it says why).
pub fn holds_model(bytes: &[u8]) -> bool {
    let Ok(zip) = zip::ZipArchive::new(std::io::Cursor::new(bytes)) else { return false };
    let holds = zip.file_names().any(|path| is_model(path) && skip_reason(&path.replace('\\', "/"), true).is_none());
    holds
}

/// Opens the zip archive `name` (its `bytes`), unpacking at most `budget` bytes of mesh files.
pub fn open(name: &str, bytes: &[u8], budget: u64) -> Result<Archive> {
    open_with(name, bytes, budget, false)
}

/// [`open`]; with `models`, model files (`.posemfa`) are read too, as the page reads them beside pose files (a
/// paper's demo serving one .zip of its model and its poses).
pub fn open_with(name: &str, bytes: &[u8], budget: u64, models: bool) -> Result<Archive> {
    let damaged = |what: String| err(name, format!("{what}; the archive is cut or damaged: zip the files again"));
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| damaged(format!("cannot open the zip archive ({e})")))?;
    // Which entries to read, and the sizes they declare.
    let mut wanted: Vec<(usize, String, u64)> = Vec::new();
    let mut skipped = Vec::new();
    let mut declared: u64 = 0;
    for i in 0..zip.len() {
        let entry =
            zip.by_index_raw(i).map_err(|e| damaged(format!("cannot read entry {} of the archive ({e})", i + 1)))?;
        let path = entry.name().replace('\\', "/");
        if entry.is_dir() {
            continue;
        }
        if let Some(why) = skip_reason(&path, models) {
            skipped.push((path, why));
            continue;
        }
        if entry.encrypted() {
            return Err(err(
                name,
                format!("entry {path} is encrypted; posemfa reads archives without a password: zip the files again without one"),
            ));
        }
        declared = declared.saturating_add(entry.size());
        wanted.push((i, path, entry.size()));
    }
    if wanted.is_empty() {
        let held = if skipped.is_empty() {
            "it holds no files".to_string()
        } else {
            format!("it holds only {}", list(&skipped))
        };
        return Err(err(
            name,
            format!(
                "the zip archive holds no mesh files ({held}); posemfa reads {}{}: zip the pose files themselves",
                super::load::formats_read(),
                if models { " and model files (.posemfa)" } else { "" }
            ),
        ));
    }
    if declared > budget {
        return Err(err(
            name,
            format!(
                "its mesh files unpack to {} (as the archive declares), more than the {} a zip archive may unpack \
                 to (half the memory budget); the archive is a zip bomb, or far larger than a pose population: \
                 unzip it and give the folder instead",
                show_bytes(declared),
                show_bytes(budget)
            ),
        ));
    }
    let mut files = Vec::with_capacity(wanted.len());
    let mut unpacked: u64 = 0;
    for (i, path, size) in wanted {
        let entry = zip.by_index(i).map_err(|e| match e {
            e @ (zip::result::ZipError::UnsupportedArchive(_) | zip::result::ZipError::CompressionMethodNotSupported(_)) => err(
                name,
                format!("entry {path} cannot be unpacked here ({e}); posemfa reads stored and deflated entries: zip the files again (any zip tool's default)"),
            ),
            e => damaged(format!("cannot unpack entry {path} ({e})")),
        })?;
        // (the declared sizes add up to at most the budget, and no entry unpacks past its own)
        let mut data = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
        entry
            .take(size.saturating_add(1))
            .read_to_end(&mut data)
            .map_err(|e| damaged(format!("cannot unpack entry {path} ({e})")))?;
        if data.len() as u64 > size {
            return Err(err(
                name,
                format!(
                    "entry {path} unpacks past the {size} bytes the archive declares for it; the archive is damaged \
                     (or a zip bomb): zip the files again"
                ),
            ));
        }
        unpacked += data.len() as u64;
        files.push((format!("{name}/{path}"), data));
    }
    files.sort_by(|a, b| natural_cmp(&a.0, &b.0));
    Ok(Archive { files, skipped, unpacked })
}

/// Up to five entries with why, then how many more: "README.txt (not a mesh file), ... and 3 more".
fn list(entries: &[(String, &'static str)]) -> String {
    let shown: Vec<String> = entries.iter().take(5).map(|(p, why)| format!("{p} ({why})")).collect();
    let more = entries.len().saturating_sub(5);
    if more > 0 {
        format!("{} and {more} more", shown.join(", "))
    } else {
        shown.join(", ")
    }
}

impl Archive {
    /// What the source line says of archive `name`: "read from poses.zip (12 mesh files; skipped README.txt (not
    /// a mesh file))".
    pub fn note(&self, name: &str) -> String {
        let n = self.files.len();
        let files = format!("{n} mesh file{}", if n == 1 { "" } else { "s" });
        if self.skipped.is_empty() {
            format!("read from {name} ({files})")
        } else {
            format!("read from {name} ({files}; skipped {})", list(&self.skipped))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_are_read_or_skipped_by_their_path() {
        for p in ["pose1.obj", "walk/pose10.PLY", "a/b/c/horse.glb", "scene.gltf", "scene.bin", "walk.usdz"] {
            assert_eq!(skip_reason(p, false), None, "{p}");
        }
        assert_eq!(skip_reason("__MACOSX/walk/._pose1.obj", false), Some("macOS resource fork"));
        assert_eq!(skip_reason("walk/._pose1.obj", false), Some("hidden file"));
        assert_eq!(skip_reason(".git/config.obj", false), Some("hidden file"));
        assert_eq!(skip_reason("old/more.zip", false), Some("an archive inside the archive, not opened"));
        for p in ["README", "notes.txt", "skin.png", "body.mtl"] {
            assert_eq!(skip_reason(p, false), Some("not a mesh file"), "{p}");
        }
        // a model file: read when asked for (the page), skipped otherwise (the CLI opens one with --model)
        assert_eq!(skip_reason("demo/horse.posemfa", true), None);
        assert_eq!(skip_reason("demo/horse.posemfa", false), Some("not a mesh file"));
        assert_eq!(skip_reason("__MACOSX/._horse.posemfa", true), Some("macOS resource fork"));
    }

    #[test]
    fn a_model_file_in_an_archive_is_seen_from_the_listing_and_read_when_asked() {
        let with = zip_of(&[("demo/horse.posemfa", b"POSEMFA\0 not unpacked by the listing"), ("demo/p1.obj", TRI)]);
        let without = zip_of(&[("demo/p1.obj", TRI), ("__MACOSX/._x.posemfa", b"fork")]);
        assert!(holds_model(&with));
        assert!(!holds_model(&without), "a resource fork named .posemfa is no model file");
        assert!(!holds_model(b"not a zip"));
        let page = open_with("d.zip", &with, 1 << 20, true).unwrap();
        let names: Vec<&str> = page.files.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["d.zip/demo/horse.posemfa", "d.zip/demo/p1.obj"]);
        let cli = open("d.zip", &with, 1 << 20).unwrap();
        assert_eq!(cli.files.len(), 1);
        assert_eq!(cli.skipped, [("demo/horse.posemfa".to_string(), "not a mesh file")]);
        let e = open_with("e.zip", &zip_of(&[("notes.txt", b"hi")]), 1 << 20, true).unwrap_err().to_string();
        assert!(e.contains("and model files (.posemfa)"), "{e}");
    }

    const TRI: &[u8] = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

    /// A zip of `entries` (path, bytes), deflated.
    fn zip_of(entries: &[(&str, &[u8])]) -> Vec<u8> {
        use std::io::Write;
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        for (path, bytes) in entries {
            let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
            w.start_file(*path, options).unwrap();
            w.write_all(bytes).unwrap();
        }
        w.finish().unwrap().into_inner()
    }

    /// Offsets of the local headers (PK\x03\x04) and central directory headers (PK\x01\x02) of a zip.
    fn headers(z: &[u8], sig: &[u8; 4]) -> Vec<usize> {
        z.windows(4).enumerate().filter(|(_, w)| w == sig).map(|(i, _)| i).collect()
    }

    fn error(z: &[u8], budget: u64) -> String {
        open("a.zip", z, budget).unwrap_err().to_string()
    }

    #[test]
    fn an_archive_reads_in_natural_order_and_skips_what_is_not_a_mesh() {
        let z = zip_of(&[
            ("walk/pose10.obj", TRI),
            ("README.txt", b"poses of a walk"),
            ("walk/pose2.obj", TRI),
            ("__MACOSX/walk/._pose2.obj", b"\0\x05\x16\x07"),
            ("run/pose1.obj", TRI),
            ("old.zip", b"PK"),
        ]);
        let a = open("a.zip", &z, 1 << 20).unwrap();
        let names: Vec<&str> = a.files.iter().map(|f| f.0.as_str()).collect();
        assert_eq!(names, ["a.zip/run/pose1.obj", "a.zip/walk/pose2.obj", "a.zip/walk/pose10.obj"]);
        assert!(a.files.iter().all(|f| f.1 == TRI));
        assert_eq!(a.unpacked, 3 * TRI.len() as u64);
        assert_eq!(
            a.note("a.zip"),
            "read from a.zip (3 mesh files; skipped README.txt (not a mesh file), __MACOSX/walk/._pose2.obj (macOS \
             resource fork), old.zip (an archive inside the archive, not opened))"
        );
    }

    /// Hostile and broken archives: each refused by name, with what to do, before any large allocation.
    #[test]
    fn hostile_archives_are_refused_by_name() {
        let z = zip_of(&[("pose1.obj", TRI), ("pose2.obj", TRI)]);
        // not a zip, and a cut one (its central directory is at the end)
        assert!(error(b"PK\x03\x04 nothing", 1 << 20).starts_with("file a.zip: cannot open the zip archive ("));
        let e = error(&z[..z.len() - 30], 1 << 20);
        assert!(
            e.starts_with("file a.zip: cannot open the zip archive (")
                && e.ends_with("); the archive is cut or damaged: zip the files again"),
            "{e}"
        );
        // no mesh file in it
        assert_eq!(
            error(&zip_of(&[("notes.txt", b"x"), ("dir/", b"")]), 1 << 20),
            format!(
                "file a.zip: the zip archive holds no mesh files (it holds only notes.txt (not a mesh file)); posemfa \
                 reads {}: zip the pose files themselves",
                crate::mesh::load::formats_read()
            )
        );
        // a bomb that declares its size: 2 x 64 MiB of spaces in 2 x 65 kB, refused before anything is unpacked
        let spaces = vec![b' '; 64 << 20];
        let bomb = zip_of(&[("pose1.obj", &spaces), ("pose2.obj", &spaces)]);
        assert!(bomb.len() < 300_000, "{}", bomb.len());
        assert_eq!(
            error(&bomb, 100 << 20),
            "file a.zip: its mesh files unpack to 128.0 MiB (as the archive declares), more than the 100.0 MiB a zip \
             archive may unpack to (half the memory budget); the archive is a zip bomb, or far larger than a pose \
             population: unzip it and give the folder instead"
        );
        // a bomb that lies: each entry declares 10 bytes (central directory and local header alike) and is cut
        // off after 11
        let mut liar = zip_of(&[("pose1.obj", &spaces[..1 << 20])]);
        for at in headers(&liar, b"PK\x03\x04") {
            liar[at + 22..at + 26].copy_from_slice(&10u32.to_le_bytes());
        }
        for at in headers(&liar, b"PK\x01\x02") {
            liar[at + 24..at + 28].copy_from_slice(&10u32.to_le_bytes());
        }
        assert_eq!(
            error(&liar, 100 << 20),
            "file a.zip: entry pose1.obj unpacks past the 10 bytes the archive declares for it; the archive is damaged \
             (or a zip bomb): zip the files again"
        );
        // corrupt deflate data
        let mut corrupt = z.clone();
        let data = headers(&corrupt, b"PK\x03\x04")[0] + 30 + "pose1.obj".len();
        corrupt[data] ^= 0xff;
        corrupt[data + 1] ^= 0xff;
        let e = error(&corrupt, 1 << 20);
        assert!(e.starts_with("file a.zip: cannot unpack entry pose1.obj ("), "{e}");
        // an encrypted entry
        use zip::unstable::write::FileOptionsExt;
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        w.start_file("pose1.obj", zip::write::SimpleFileOptions::default().with_deprecated_encryption(b"pw").unwrap())
            .unwrap();
        std::io::Write::write_all(&mut w, TRI).unwrap();
        let locked = w.finish().unwrap().into_inner();
        assert_eq!(
            error(&locked, 1 << 20),
            "file a.zip: entry pose1.obj is encrypted; posemfa reads archives without a password: zip the files again \
             without one"
        );
        // a compression method posemfa does not unpack (12: bzip2), in both headers
        let mut bzip = z.clone();
        for at in headers(&bzip, b"PK\x03\x04") {
            bzip[at + 8] = 12;
        }
        for at in headers(&bzip, b"PK\x01\x02") {
            bzip[at + 10] = 12;
        }
        let e = error(&bzip, 1 << 20);
        assert!(e.starts_with("file a.zip: entry pose1.obj cannot be unpacked here ("), "{e}");
        assert!(
            e.ends_with("); posemfa reads stored and deflated entries: zip the files again (any zip tool's default)"),
            "{e}"
        );
    }

    #[test]
    fn the_note_lists_five_skipped_entries_then_counts() {
        let a = Archive {
            files: vec![("a.zip/p.obj".into(), vec![])],
            skipped: (1..=7).map(|k| (format!("r{k}.txt"), "not a mesh file")).collect(),
            unpacked: 0,
        };
        assert_eq!(
            a.note("a.zip"),
            "read from a.zip (1 mesh file; skipped r1.txt (not a mesh file), r2.txt (not a mesh file), r3.txt (not a mesh \
             file), r4.txt (not a mesh file), r5.txt (not a mesh file) and 2 more)"
        );
    }
}
