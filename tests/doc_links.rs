//! Every relative link and image in README.md, CONTRIBUTING.md and docs/**/*.md resolves: the file (or folder)
//! exists, and a `#anchor` matches a heading of the target file by GitHub's slug rules. A failure names the
//! file, the line and the target.
#![cfg(not(target_arch = "wasm32"))]

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

/// A link found in a markdown file: its 1-based line and its target as written.
#[derive(Debug, PartialEq)]
struct Link {
    line: usize,
    target: String,
}

/// Links and images of `text`: inline `[..](target)`, `![..](target)` and reference definitions
/// `[id]: target`, outside fenced code blocks and inline code spans. Titles (`"..."`) and `<...>` are removed.
fn links(text: &str) -> Vec<Link> {
    let mut out = Vec::new();
    let mut fence: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(f) = &fence {
            if trimmed.starts_with(f.as_str()) {
                fence = None;
            }
            continue;
        }
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            fence = Some(trimmed[..3].to_string());
            continue;
        }
        let line_no = i + 1;
        let code_free = without_code_spans(line);
        // Reference definitions: `[id]: target` at the start of a line.
        if let Some(rest) = code_free.trim_start().strip_prefix('[') {
            if let Some(close) = rest.find("]:") {
                if !rest[..close].is_empty() && !rest[..close].contains('[') {
                    let target = clean_target(&rest[close + 2..]);
                    if !target.is_empty() {
                        out.push(Link { line: line_no, target });
                    }
                    continue;
                }
            }
        }
        let b = code_free.as_bytes();
        let mut k = 0;
        while k + 1 < b.len() {
            if b[k] == b']' && b[k + 1] == b'(' {
                // the matching ')' (targets may hold balanced parentheses)
                let start = k + 2;
                let mut depth = 1;
                let mut j = start;
                while j < b.len() {
                    match b[j] {
                        b'(' => depth += 1,
                        b')' => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                    j += 1;
                }
                if j < b.len() {
                    let target = clean_target(&code_free[start..j]);
                    if !target.is_empty() {
                        out.push(Link { line: line_no, target });
                    }
                    k = j;
                }
            }
            k += 1;
        }
    }
    out
}

/// `line` with the content of inline code spans blanked (their backticks and text become spaces).
fn without_code_spans(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '`' {
            out.push(c);
            continue;
        }
        let mut ticks = 1;
        while chars.peek() == Some(&'`') {
            chars.next();
            ticks += 1;
        }
        let rest: String = chars.clone().collect();
        let closing = "`".repeat(ticks);
        match rest.find(&closing) {
            Some(end) => {
                for _ in 0..(ticks * 2 + rest[..end].chars().count()) {
                    out.push(' ');
                }
                for _ in 0..(rest[..end].chars().count() + ticks) {
                    chars.next();
                }
            }
            None => out.push_str(&closing),
        }
    }
    out
}

fn clean_target(raw: &str) -> String {
    let t = raw.trim();
    if let Some(inner) = t.strip_prefix('<') {
        return inner.split('>').next().unwrap_or("").to_string();
    }
    t.split_whitespace().next().unwrap_or("").to_string()
}

/// A target is checked when it is relative: no URL scheme (`https:`, `mailto:`, ...) and not `//host`.
fn is_relative(target: &str) -> bool {
    if target.starts_with("//") {
        return false;
    }
    match target.find(':') {
        Some(colon) => {
            let scheme = &target[..colon];
            let is_scheme = !scheme.is_empty()
                && scheme.chars().next().unwrap().is_ascii_alphabetic()
                && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
            // a colon after a '/', '#' or '?' belongs to the path, not to a scheme
            !is_scheme || scheme.contains(['/', '#', '?'])
        }
        None => true,
    }
}

/// GitHub's anchor for a heading: the rendered text lower-cased, every character that is not a letter, a digit,
/// a space, '-' or '_' removed, spaces turned into '-'. Inline code keeps its text; emphasis markers and link
/// targets are dropped.
fn slug(heading: &str) -> String {
    // [text](url) -> text
    let mut text = String::new();
    let mut rest = heading;
    while let Some(open) = rest.find('[') {
        match rest[open..].find("](").and_then(|m| rest[open + m..].find(')').map(|c| (open + m, open + m + c))) {
            Some((mid, close)) => {
                text.push_str(&rest[..open]);
                text.push_str(&rest[open + 1..mid]);
                rest = &rest[close + 1..];
            }
            None => break,
        }
    }
    text.push_str(rest);
    let mut out = String::new();
    for c in text.trim().chars() {
        if c.is_alphanumeric() || c == '-' || c == '_' {
            out.extend(c.to_lowercase());
        } else if c == ' ' {
            out.push('-');
        }
    }
    out
}

/// The anchors of a markdown file's headings (ATX `#` headings outside code fences); a repeated slug gets
/// `-1`, `-2`, ... as on GitHub.
fn anchors(text: &str) -> Vec<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    let mut in_fence = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("```") || t.starts_with("~~~") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence || !t.starts_with('#') {
            continue;
        }
        let hashes = t.chars().take_while(|&c| c == '#').count();
        if hashes > 6 || !(t.len() == hashes || t[hashes..].starts_with(' ')) {
            continue;
        }
        let title = t[hashes..].trim().trim_end_matches('#').trim();
        let base = slug(title);
        let n = seen.entry(base.clone()).or_insert(0);
        out.push(if *n == 0 { base.clone() } else { format!("{base}-{n}") });
        *n += 1;
    }
    out
}

/// Problems with the relative links of `file` (its text `text`), one line each: `FILE:LINE: TARGET: why`.
fn check_file(file: &Path, text: &str) -> Vec<String> {
    let dir = file.parent().unwrap_or(Path::new("."));
    let mut problems = Vec::new();
    for Link { line, target } in links(text) {
        if !is_relative(&target) {
            continue;
        }
        let (path_part, anchor) = match target.split_once('#') {
            Some((p, a)) => (p, Some(a)),
            None => (target.as_str(), None),
        };
        let path_part = path_part.split('?').next().unwrap_or("");
        let dest: PathBuf = if path_part.is_empty() { file.to_path_buf() } else { dir.join(percent_decode(path_part)) };
        let at = format!("{}:{line}: {target}", file.display());
        if !dest.exists() {
            problems.push(format!("{at}: {} does not exist", dest.display()));
            continue;
        }
        if let Some(anchor) = anchor {
            if dest.is_dir() || dest.extension().is_none_or(|e| e != "md") {
                problems.push(format!("{at}: an anchor into {}, which is not a markdown file", dest.display()));
                continue;
            }
            let dest_text = fs::read_to_string(&dest).unwrap_or_default();
            let known = anchors(&dest_text);
            if !known.iter().any(|a| a == anchor) {
                problems.push(format!(
                    "{at}: no heading of {} has the anchor #{anchor} (its anchors: {})",
                    dest.display(),
                    known.join(", ")
                ));
            }
        }
    }
    problems
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Some(v) = std::str::from_utf8(&b[i + 1..i + 3]).ok().and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn markdown_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![root.join("README.md"), root.join("CONTRIBUTING.md")];
    let mut stack = vec![root.join("docs")];
    while let Some(d) = stack.pop() {
        let Ok(entries) = fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "md") {
                files.push(p);
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_relative_link_in_the_readme_contributing_and_docs_resolves() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = markdown_files(root);
    let mut problems = Vec::new();
    let mut checked = 0;
    for f in &files {
        let text = fs::read_to_string(f).unwrap_or_else(|e| panic!("{}: cannot read it: {e}", f.display()));
        checked += links(&text).iter().filter(|l| is_relative(&l.target)).count();
        let root_prefix = format!("{}/", root.display());
        problems.extend(check_file(f, &text).into_iter().map(|p| p.replace(&root_prefix, "")));
    }
    assert!(files.len() >= 3, "expected README.md, CONTRIBUTING.md and docs/*.md, found {files:?}");
    assert!(checked > 0, "no relative link found in {files:?}: the link scanner is broken");
    assert!(problems.is_empty(), "broken links:\n{}", problems.join("\n"));
}

// The checker itself, on text written here: it must find what is broken.

#[test]
fn the_scanner_finds_inline_links_images_and_references_but_not_code() {
    let text = "see [a](docs/a.md#x) and ![pic](img/p.png \"title\")\n\
                `[not](a link)` and\n\
                ```\n[not](in/a/fence.md)\n```\n\
                [ref]: ../b.md\n\
                [web](https://example.com/x) [paren](f(1).md)\n";
    let found = links(text);
    let found: Vec<(usize, &str)> = found.iter().map(|l| (l.line, l.target.as_str())).collect();
    assert_eq!(
        found,
        vec![(1, "docs/a.md#x"), (1, "img/p.png"), (6, "../b.md"), (7, "https://example.com/x"), (7, "f(1).md")]
    );
    assert!(!is_relative("https://example.com/x"));
    assert!(!is_relative("mailto:a@b.c"));
    assert!(!is_relative("//cdn.example.com/x"));
    assert!(is_relative("docs/a.md#x"));
    assert!(is_relative("#mesh-formats"));
}

#[test]
fn anchors_follow_githubs_slug_rules() {
    assert_eq!(slug("Mesh formats (`src/mesh/`)"), "mesh-formats-srcmesh");
    assert_eq!(
        slug("A part count without tuning (`partRule: \"distinct\"`, the default)"),
        "a-part-count-without-tuning-partrule-distinct-the-default"
    );
    assert_eq!(slug("The CLI (`cargo run --release -- help`)"), "the-cli-cargo-run---release----help");
    assert_eq!(slug("Is it articulated? (`src/parts/diagnosis.rs`)"), "is-it-articulated-srcpartsdiagnosisrs");
    assert_eq!(slug("Speed + Figures"), "speed--figures");
    assert_eq!(slug("part_count and [a link](x.md)"), "part_count-and-a-link");
    assert_eq!(anchors("# A\n## B\n```\n# not\n```\n## B\n#nospace\n### B"), vec!["a", "b", "b-1", "b-2"]);
}

#[test]
fn a_missing_file_and_a_missing_anchor_are_reported_with_file_line_and_target() {
    let dir = std::env::temp_dir().join(format!("posemfa-doc-links-{}", std::process::id()));
    fs::create_dir_all(dir.join("docs")).unwrap();
    fs::write(dir.join("docs/a.md"), "# Title\n## Part two\n").unwrap();
    let readme = dir.join("README.md");
    let text =
        "intro\n[ok](docs/a.md#part-two) [ok too](docs/)\n[gone](docs/missing.md)\n[bad anchor](docs/a.md#part-3)\n\
                [self](#intro) [self ok](#readme)\n# README\n";
    fs::write(&readme, text).unwrap();
    let problems = check_file(&readme, text);
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(problems.len(), 3, "{problems:#?}");
    assert!(
        problems[0].contains("README.md:3: docs/missing.md") && problems[0].contains("does not exist"),
        "{}",
        problems[0]
    );
    assert!(
        problems[1].contains("README.md:4: docs/a.md#part-3") && problems[1].contains("#part-3"),
        "{}",
        problems[1]
    );
    assert!(problems[2].contains("README.md:5: #intro"), "{}", problems[2]);
}
