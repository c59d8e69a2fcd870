//! The two rooms: `src/mfa/` (the constrained mixture and its fit) never names `crate::parts`;
//! `src/parts/` (how the partition is decided) calls into `mfa`; `src/mesh/`, `src/geometry/` and
//! `src/memory.rs` name neither; and inside `parts/` every module uses only the modules listed before it in
//! `parts/mod.rs`, so there is no import circle. Comments and `#[cfg(test)]` modules are not looked at: a unit
//! test may build a whole fit.

use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The code of a Rust file without its comments, string literals' contents and `#[cfg(test)]` items.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if b[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if b[i] == b'"' {
            out.push('"');
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            out.push('"');
            i += 1;
        } else {
            let c = text[i..].chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    strip_cfg_test(&out)
}

/// `code` without every `#[cfg(test)]` item (an attribute, then an item ending at its matching `}` or `;`).
fn strip_cfg_test(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        let mut depth = 0usize;
        let mut end = after.len();
        for (k, c) in after.char_indices().skip("#[cfg(test)]".len()) {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// Every `crate::ROOM::NAME` and `super::NAME` this code names, as (room or "super", name).
fn paths_named(code: &str) -> Vec<(String, String)> {
    let mut found = Vec::new();
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    for (prefix, room) in [("crate::mfa::", "mfa"), ("crate::parts::", "parts"), ("crate::memory", "memory")] {
        for (at, _) in code.match_indices(prefix) {
            let name = ident(&code[at + prefix.len()..]);
            found.push((room.to_string(), name));
        }
    }
    for (at, _) in code.match_indices("super::") {
        let after = &code[at + "super::".len()..];
        if let Some(list) = after.strip_prefix('{') {
            let list = &list[..list.find('}').unwrap_or(list.len())];
            for item in list.split(',') {
                found.push(("super".into(), ident(item.trim())));
            }
        } else {
            found.push(("super".into(), ident(after)));
        }
    }
    found
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    files.sort();
    files
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn the_parser_ignores_comments_strings_and_unit_tests() {
    let text =
        "use super::data::Data; // crate::parts::hierarchy\n/* crate::parts::x */ let s = \"crate::parts::y\";\n\
                #[cfg(test)]\nmod tests { use crate::parts::hierarchy::fit; fn f() { if true { } } }\n\
                fn g() { crate::mfa::aecm::run(); }\nuse super::{cm, estep::EStep};";
    let named = paths_named(&code_only(text));
    let want: Vec<(String, String)> = [("mfa", "aecm"), ("super", "data"), ("super", "cm"), ("super", "estep")]
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(named, want);
    // and code that does name the other room is seen
    assert!(paths_named(&code_only("fn f() { crate::parts::hierarchy::fit(); }"))
        .contains(&("parts".into(), "hierarchy".into())));
}

#[test]
fn mfa_never_names_parts() {
    for f in rust_files(&src().join("mfa")) {
        for (room, name) in paths_named(&code_only(&read(&f))) {
            assert_ne!(
                room,
                "parts",
                "{} names crate::parts::{name}: the MFA must not depend on the part decisions",
                f.display()
            );
        }
    }
}

#[test]
fn mesh_and_geometry_name_neither_room() {
    let mut files = rust_files(&src().join("mesh"));
    files.extend(rust_files(&src().join("geometry")));
    files.push(src().join("memory.rs"));
    for f in files {
        for (room, name) in paths_named(&code_only(&read(&f))) {
            assert!(room != "parts" && room != "mfa", "{} names crate::{room}::{name}", f.display());
        }
    }
}

#[test]
fn parts_modules_import_only_earlier_ones() {
    let dir = src().join("parts");
    let order: Vec<String> = code_only(&read(&dir.join("mod.rs")))
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod ")?.strip_suffix(';').map(str::to_string))
        .collect();
    assert!(order.len() >= 10, "parts/mod.rs lists {order:?}");
    // a module's own child modules (parts/NAME/*.rs) are that module: their `super::` is it
    let mut files: Vec<(PathBuf, bool)> = rust_files(&dir).into_iter().map(|f| (f, false)).collect();
    for m in &order {
        if dir.join(m).is_dir() {
            files.extend(rust_files(&dir.join(m)).into_iter().map(|f| (f, true)));
        }
    }
    for (f, child) in files {
        let me = if child {
            f.parent().unwrap().file_name().unwrap().to_string_lossy().to_string()
        } else {
            f.file_stem().unwrap().to_string_lossy().to_string()
        };
        if me == "mod" {
            continue;
        }
        let mine = order.iter().position(|m| *m == me).unwrap_or_else(|| panic!("{me}.rs is not in parts/mod.rs"));
        for (room, name) in paths_named(&code_only(&read(&f))) {
            if room != "super" && room != "parts" || (child && room == "super") {
                continue;
            }
            if let Some(theirs) = order.iter().position(|m| *m == name) {
                assert!(
                    theirs < mine,
                    "parts/{me}.rs uses parts::{name}, listed after it in parts/mod.rs: an import circle or a wrong order"
                );
            } else {
                assert!(
                    room == "parts" || name == "super",
                    "parts/{me}.rs names super::{name}, not a module of parts/"
                );
            }
        }
    }
}

/// The core never prints: what a fit has to say goes through its observer or the trace (`crate::trace`), which
/// the CLI prints with `--trace`; a page has no stderr to read.
#[test]
fn the_model_and_the_part_rooms_do_not_print() {
    for room in ["mfa", "parts"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(src().join(room))
            .expect("the room exists")
            .map(|e| e.expect("a directory entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "rs"))
            .collect();
        files.sort();
        for f in files {
            let code = code_only(&std::fs::read_to_string(&f).expect("readable"));
            for word in ["eprintln!", "println!", "eprint!", "print!(", "dbg!"] {
                assert!(
                    !code.contains(word),
                    "{} uses {word}: hand the line to crate::trace_line! instead",
                    f.display()
                );
            }
        }
    }
}
