//! The OBJ importer against real third-party files.
//!
//! - `objcorpus` of the shared data folder (`POSEMFA_SHARED`, default `../shared` next to the crate): every
//!   `.obj` listed in its `MANIFEST.tsv` must give the outcome the manifest states ("loads: V=.. vertices,
//!   F=.. triangles" or "should be rejected: ..."), without panicking.
//! - `data/horse-poses` there: the horse population must load with 8431 vertices / 16843 triangles per file and
//!   one common face list.
//!
//! Positions are also checked against a naive reading of the `v` lines (file order) and against the
//! positions-only reading (`parse_obj_positions`), and triangles against tobj, an independent OBJ reader (same
//! corners, same order).
//!
//! When a folder is missing, the tests that need it are counted as skipped, and fail under CI=true
//! (`common::shared_dir`): the data are not part of the repository.

use posemfa::error::Error;
use posemfa::mesh::obj::{parse_obj, parse_obj_positions};
use posemfa::mesh::Mesh;
use std::path::{Path, PathBuf};

mod common;

fn corpus_dir(test: &str) -> Option<PathBuf> {
    common::shared_dir("objcorpus", test)
}

fn horse_dir(test: &str) -> Option<PathBuf> {
    common::shared_dir("data/horse-poses", test)
}

/// What the manifest allows for one file.
#[derive(Debug, Clone, PartialEq)]
enum Expect {
    /// Must load with exactly these counts.
    Loads { vertices: usize, triangles: usize },
    /// Must be an error naming the file (and a line, when a line is at fault); `empty_ok`: a mesh with no
    /// vertices and no faces is also acceptable.
    Rejected { needs_line: bool, empty_ok: bool },
    /// Either loads with these counts or is an error naming the file and a line.
    Either { vertices: usize, triangles: usize },
}

/// The number right after `key` in `text` (e.g. `V=` in "loads: V=8 vertices").
fn number_after(text: &str, key: &str) -> Option<usize> {
    let start = text.find(key)? + key.len();
    let digits: String = text[start..].chars().take_while(|c| c.is_ascii_digit()).collect();
    digits.parse().ok()
}

fn counts(text: &str) -> Option<(usize, usize)> {
    let v = number_after(text, "V=")?;
    let after_v = &text[text.find("V=")?..];
    let f = number_after(after_v, "F=")?;
    Some((v, f))
}

/// Reads the expected outcome of a manifest entry. `None` for entries that are not OBJ inputs (MTL).
fn expectation(file: &str, outcome: &str) -> Option<Expect> {
    let outcome = outcome.trim();
    if outcome.starts_with("n/a") {
        return None;
    }
    let bad = || -> (usize, usize) { panic!("{file}: cannot read the expected outcome {outcome:?}") };
    if let Some(rest) = outcome.strip_prefix("loads:") {
        let (vertices, triangles) = counts(rest).unwrap_or_else(bad);
        return Some(Expect::Loads { vertices, triangles });
    }
    if let Some(rest) = outcome.strip_prefix("should be rejected:") {
        // The reason comes before the notes on lenient loaders ("|") and the checker's tags ("[").
        let reason = rest.split(['|', '[']).next().unwrap_or(rest).to_ascii_lowercase();
        let whole_file = reason.contains("empty file") || reason.contains("no geometry");
        let empty_ok = reason.contains("empty mesh") && reason.contains("acceptable");
        return Some(Expect::Rejected { needs_line: !whole_file, empty_ok });
    }
    if outcome.starts_with("AMBIGUOUS") {
        // e.g. "... expects it to load as V=3 vertices, F=1 triangle ...; strict spec joining gives ... -> reject".
        let (vertices, triangles) = counts(outcome).unwrap_or_else(bad);
        return Some(Expect::Either { vertices, triangles });
    }
    panic!("{file}: cannot read the expected outcome {outcome:?}")
}

/// (file, expectation) for every OBJ entry of MANIFEST.tsv, columns found by their header names.
fn manifest(dir: &Path) -> Vec<(String, Expect)> {
    let text = std::fs::read_to_string(dir.join("MANIFEST.tsv")).expect("read MANIFEST.tsv");
    let mut rows = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<&str> = rows.next().expect("MANIFEST.tsv has a header").split('\t').collect();
    let col = |name: &str| {
        header.iter().position(|h| h.trim() == name).unwrap_or_else(|| panic!("no column {name:?} in MANIFEST.tsv"))
    };
    let (file_col, outcome_col) = (col("file"), col("expected outcome"));
    rows.filter_map(|row| {
        let cells: Vec<&str> = row.split('\t').collect();
        let file = cells.get(file_col).expect("file cell").trim().to_string();
        let outcome = cells.get(outcome_col).unwrap_or_else(|| panic!("{file}: no expected outcome"));
        expectation(&file, outcome).map(|e| (file, e))
    })
    .collect()
}

/// Number of lines of a file, with LF, CRLF and lone CR as line ends.
fn line_count(bytes: &[u8]) -> usize {
    let mut n = 1;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n')) {
            n += 1;
        }
    }
    n
}

/// Parses inside catch_unwind: a panic is a test failure of its own.
fn parse_caught(name: &str, bytes: &[u8]) -> Result<posemfa::Result<Mesh>, String> {
    std::panic::catch_unwind(|| parse_obj(name, bytes)).map_err(|p| {
        let what = p.downcast_ref::<String>().cloned().or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()));
        format!("PANICKED: {}", what.unwrap_or_default())
    })
}

/// Checks an error against what the manifest requires of it; returns a complaint or None.
fn check_error(name: &str, bytes: &[u8], e: &Error, needs_line: bool) -> Option<String> {
    let shown = e.to_string();
    let Error::Obj { file, line, .. } = e else { return Some(format!("not an OBJ error: {shown}")) };
    if file != name || !shown.contains(name) {
        return Some(format!("message does not name the file: {shown}"));
    }
    if needs_line && *line == 0 {
        return Some(format!("message names no line: {shown}"));
    }
    if *line > 0 && (!shown.contains(&format!("line {line}")) || *line > line_count(bytes)) {
        return Some(format!("line {line} is not shown or not in the file ({} lines): {shown}", line_count(bytes)));
    }
    None
}

fn check(name: &str, bytes: &[u8], expect: &Expect) -> Result<String, String> {
    let result = parse_caught(name, bytes)?;
    match (expect, &result) {
        (Expect::Loads { vertices, triangles } | Expect::Either { vertices, triangles }, Ok(m)) => {
            if (m.positions.len(), m.faces.len()) == (*vertices, *triangles) {
                Ok(format!("loads V={vertices} F={triangles}"))
            } else {
                Err(format!("loaded V={} F={}, expected V={vertices} F={triangles}", m.positions.len(), m.faces.len()))
            }
        }
        (Expect::Loads { .. }, Err(e)) => Err(format!("rejected, expected to load: {e}")),
        (Expect::Either { .. }, Err(e)) => {
            check_error(name, bytes, e, true).map_or(Ok(format!("rejected (allowed): {e}")), Err)
        }
        (Expect::Rejected { needs_line, .. }, Err(e)) => {
            check_error(name, bytes, e, *needs_line).map_or(Ok(format!("rejected: {e}")), Err)
        }
        (Expect::Rejected { empty_ok: true, .. }, Ok(m)) if m.positions.is_empty() && m.faces.is_empty() => {
            Ok("empty mesh (allowed)".into())
        }
        (Expect::Rejected { .. }, Ok(m)) => {
            Err(format!("loaded V={} F={}, expected a rejection", m.positions.len(), m.faces.len()))
        }
    }
}

#[test]
fn manifest_outcomes() {
    let Some(dir) = corpus_dir("manifest_outcomes") else { return };
    let not_found = std::fs::read_to_string(dir.join("NOT_FOUND.txt")).unwrap_or_default();
    if let Some(first) = not_found.lines().next() {
        println!("NOT_FOUND.txt: {first}");
    }
    let entries = manifest(&dir);
    assert!(!entries.is_empty(), "{}: MANIFEST.tsv lists no OBJ file", dir.display());
    let mut listed: Vec<&str> = entries.iter().map(|(f, _)| f.as_str()).collect();
    listed.sort_unstable();
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .expect("read corpus folder")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.to_ascii_lowercase().ends_with(".obj"))
        .collect();
    on_disk.sort_unstable();
    assert_eq!(listed, on_disk, "the .obj files of {} and the OBJ entries of MANIFEST.tsv differ", dir.display());

    let mut failures = Vec::new();
    let (mut loads, mut rejects) = (0, 0);
    for (file, expect) in &entries {
        let bytes = std::fs::read(dir.join(file)).expect("read corpus file");
        // the second reading of a large population reads only the positions: the same ones
        if let Ok(m) = parse_obj(file, &bytes) {
            if parse_obj_positions(file, &bytes).as_ref() != Ok(&m.positions) {
                failures.push(format!("{file}: the positions-only reading differs from the full one"));
            }
        }
        match check(file, &bytes, expect) {
            Ok(how) => {
                if how.starts_with("loads") {
                    loads += 1;
                } else {
                    rejects += 1;
                }
                println!("ok   {file}: {how}");
            }
            Err(why) => {
                println!("FAIL {file}: {why}");
                failures.push(format!("{file}: {why}"));
            }
        }
    }
    println!("{} OBJ files: {loads} loaded, {rejects} rejected as expected, {} wrong", entries.len(), failures.len());
    assert!(failures.is_empty(), "{} corpus files give the wrong outcome:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn manifest_reader() {
    assert_eq!(
        expectation("a.obj", "loads: V=76 vertices, F=36 triangles; closed triangle mesh: no"),
        Some(Expect::Loads { vertices: 76, triangles: 36 })
    );
    assert_eq!(
        expectation(
            "a.obj",
            "should be rejected: empty file (0 bytes); an empty mesh is also acceptable [count.py: x]"
        ),
        Some(Expect::Rejected { needs_line: false, empty_ok: true })
    );
    assert_eq!(
        expectation("a.obj", "should be rejected: index 0 in every face | lenient loaders: V=4, F=0; an empty mesh"),
        Some(Expect::Rejected { needs_line: true, empty_ok: false })
    );
    assert_eq!(
        expectation(
            "a.obj",
            "AMBIGUOUS: x expects it to load as V=3 vertices, F=1 triangle with ...; strict ... -> reject"
        ),
        Some(Expect::Either { vertices: 3, triangles: 1 })
    );
    assert_eq!(expectation("a.mtl", "n/a (MTL file, not an OBJ)"), None);
    assert_eq!(line_count(b"a\r\nb\rc\n"), 4);
}

/// x y z of every `v` line, read as naively as possible (no continuation lines).
fn naive_positions(bytes: &[u8]) -> Vec<[f64; 3]> {
    let text = std::str::from_utf8(bytes).expect("utf-8");
    text.lines()
        .filter_map(|l| l.strip_prefix("v ").or_else(|| l.strip_prefix("v\t")))
        .map(|rest| {
            let mut it = rest.split_whitespace().map(|t| t.parse::<f64>().expect("number"));
            [it.next().expect("x"), it.next().expect("y"), it.next().expect("z")]
        })
        .collect()
}

/// The loadable files whose lines are plain (no continuation), from the corpus and the horse population; `None`
/// (skipped) when either is absent.
fn plain_loadable_files(test: &str) -> Option<Vec<(String, Vec<u8>)>> {
    let (corpus, horse) = (corpus_dir(test)?, horse_dir(test)?);
    let mut out = Vec::new();
    {
        let dir = corpus;
        for (file, expect) in manifest(&dir) {
            if matches!(expect, Expect::Loads { .. }) {
                let bytes = std::fs::read(dir.join(&file)).expect("read");
                let continued = bytes.windows(2).any(|w| w == b"\\\n" || w == b"\\\r");
                if !continued {
                    out.push((file, bytes));
                }
            }
        }
    }
    for name in ["1.obj", "reference.obj"] {
        let bytes = std::fs::read(horse.join(name)).unwrap_or_else(|e| panic!("{}: {e}", horse.join(name).display()));
        out.push((format!("horse-poses/{name}"), bytes));
    }
    Some(out)
}

#[test]
fn positions_are_the_v_lines_in_file_order() {
    let Some(files) = plain_loadable_files("positions_are_the_v_lines_in_file_order") else { return };
    for (name, bytes) in &files {
        let mesh = parse_obj(name, bytes).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.positions, naive_positions(bytes), "{name}: positions differ from the v lines");
    }
    println!("{} files: positions equal the v lines in order", files.len());
}

/// Triangles as corner positions, from tobj (all models in order; lines and points ignored).
fn tobj_triangles(bytes: &[u8]) -> Option<Vec<[[f32; 3]; 3]>> {
    // `..Default::default()` keeps this compiling if tobj features add fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj_buf(&mut std::io::BufReader::new(bytes), &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .ok()?;
    let mut out = Vec::new();
    for m in &models {
        let p = &m.mesh.positions;
        let corner = |i: u32| -> Option<[f32; 3]> {
            let i = i as usize * 3;
            Some([*p.get(i)?, *p.get(i + 1)?, *p.get(i + 2)?])
        };
        for t in m.mesh.indices.chunks(3) {
            if let [a, b, c] = *t {
                out.push([corner(a)?, corner(b)?, corner(c)?]);
            }
        }
    }
    Some(out)
}

#[test]
fn triangles_agree_with_tobj() {
    let mut compared = 0;
    let Some(files) = plain_loadable_files("triangles_agree_with_tobj") else { return };
    for (name, bytes) in files {
        // tobj turns `l` polylines of 3+ vertices into triangles and divides x y z by `w`: not comparable.
        let text = String::from_utf8_lossy(&bytes);
        let has_polyline_or_w = text.lines().any(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            (t.first() == Some(&"l") && t.len() > 3)
                || (t.first() == Some(&"v") && t.len() == 5 && t[4].parse::<f64>() != Ok(1.0))
        });
        let Some(theirs) = tobj_triangles(&bytes) else {
            println!("{name}: tobj cannot read it, not compared");
            continue;
        };
        if has_polyline_or_w {
            println!("{name}: has polylines or w != 1, not compared");
            continue;
        }
        let mesh = parse_obj(&name, &bytes).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.faces.len(), theirs.len(), "{name}: triangle count differs from tobj");
        for (k, (f, t)) in mesh.faces.iter().zip(&theirs).enumerate() {
            for (corner, expected) in f.iter().zip(t) {
                let ours = mesh.positions[*corner as usize];
                for (a, b) in ours.iter().zip(expected) {
                    let tol = 1e-6 * a.abs().max(1.0);
                    assert!(
                        (a - *b as f64).abs() <= tol,
                        "{name}: triangle {k} differs from tobj: {f:?} -> {ours:?} vs {t:?}"
                    );
                }
            }
        }
        compared += 1;
    }
    println!("{compared} files: triangles equal tobj's");
    assert!(compared > 0, "no file was compared with tobj");
}

#[test]
fn horse_poses_share_size_and_faces() {
    let Some(dir) = horse_dir("horse_poses_share_size_and_faces") else { return };
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("read horse folder")
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 11, "expected the 11 horse files in {}", dir.display());
    let mut faces: Option<Vec<[u32; 3]>> = None;
    for path in &names {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("?");
        let bytes = std::fs::read(path).expect("read horse file");
        let started = std::time::Instant::now();
        let mesh =
            parse_caught(name, &bytes).unwrap_or_else(|p| panic!("{name}: {p}")).unwrap_or_else(|e| panic!("{e}"));
        let took = started.elapsed();
        println!(
            "{name}: V={} F={} in {:.1} ms (test profile)",
            mesh.positions.len(),
            mesh.faces.len(),
            took.as_secs_f64() * 1e3
        );
        assert_eq!((mesh.positions.len(), mesh.faces.len()), (8431, 16843), "{name}");
        match &faces {
            None => faces = Some(mesh.faces),
            Some(f) => assert!(*f == mesh.faces, "{name}: faces differ from the first file's"),
        }
    }
}
