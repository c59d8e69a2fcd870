//! OBJ import.
//!
//! A strict, line-by-line reader of Wavefront OBJ meshes, written for posemfa's needs rather than for
//! rendering:
//!
//! - vertex `j` of the [`Mesh`] is the `j`-th `v` line of the file, always: across `o`/`g` objects and
//!   including vertices no face uses. The method relies on vertex correspondence between files.
//! - faces (`f`, and the old `fo`) are fan-triangulated (a face of `n` vertices gives `n - 2` triangles,
//!   `(1, k, k+1)`), degenerate ones included; `l`, `p`, `vt`, `vn` and every other statement are ignored,
//!   but every index written in `f`, `l` and `p` is checked (a reference to a missing `vt`/`vn` means the
//!   file is damaged or cut).
//! - a line that starts with neither a keyword (letters) nor `#` is an error: it is damage, and skipping it
//!   would blame a later line or another file (a vertex line overwritten leaves a face out of range, or the
//!   file a vertex short of the others).
//! - `v x y z`, `v x y z w` and `v x y z r g b` are accepted; only x y z are kept (`w` is not a divisor
//!   for polygon vertices).
//! - a trailing backslash continues a line (OBJ spec), comments included; a comment whose backslash
//!   would swallow a following `v`/`f`/... statement is reported instead of silently hiding it.
//! - LF, CRLF and lone CR line ends; a UTF-8 byte-order mark and a final Ctrl-Z are skipped.
//! - the text is read as bytes: only the numbers and indices must be ASCII. Names, comments and material
//!   names in any 8-bit encoding load (3ds Max writes Latin-1 `usemtl` and `o` names).
//!
//! Everything else is an error that names the file and the (first physical) line, says what is wrong and
//! what to do: UTF-16, NUL and other control bytes (binary data), numbers that do not parse or are not
//! finite (`nan`, `inf`, `1.#IND`, exponents that overflow), `3.1+e2` and such, indices that are 0 or out of
//! range (positive ones must refer to lines above the face, negative ones count back from the latest), faces
//! with fewer than 3 vertices, and a file without any vertex.
//!
//! Speed: a one-line `v x y z` or `f` of in-range references (what exporters write) is read straight
//! from the text up to its line end; every other line is found with `memchr` and read token by token.
//! Numbers are parsed from the bytes in place by `fast-float2` (Eisel-Lemire; the maintained fork of
//! `fast-float`), so no line is copied or validated as UTF-8 first; the binary-data check is one
//! branch-free pass over the file.
//!
//! Why not tobj: tobj (kept in Cargo.toml) re-indexes the vertices of each model in order of first use by
//! a face and drops the vertices no face uses, so the `v` order cannot be recovered from its output; it also
//! reports no line numbers, accepts `nan`/`inf`, divides x y z by `w`, turns `f 1`/`f 1 2` and `l` polylines
//! into triangles and does not join continued lines. It is used by the tests as an independent oracle for
//! index resolution and triangulation, not here.
//!
//! The reader never panics: no indexing that can fail, no `unwrap` on data, and no allocation sized by a
//! number read from the file.

use super::Mesh;
use crate::error::{Error, Result};

/// Parses one OBJ file. `name` is used in error messages.
pub fn parse_obj(name: &str, bytes: &[u8]) -> Result<Mesh> {
    parse(bytes, false).map_err(|f| Error::Obj { file: name.to_string(), line: f.line, message: f.message })
}

/// The vertex positions of an OBJ file, as [`parse_obj`] gives them, read faster: one-line `f` statements are
/// skipped to their line end instead of read (a statement continued by a backslash still goes through the
/// full reader). For a file [`parse_obj`] has already accepted: a face this skips is not checked (the second
/// reading of a large population, [`crate::mesh::Sources::MeshFiles`]).
pub fn parse_obj_positions(name: &str, bytes: &[u8]) -> Result<Vec<[f64; 3]>> {
    parse(bytes, true).map(|m| m.positions).map_err(|f| Error::Obj {
        file: name.to_string(),
        line: f.line,
        message: f.message,
    })
}

/// An error before the file name is attached. `line` is 1-based, 0 for the whole file.
#[derive(Debug)]
struct Fail {
    line: usize,
    message: String,
}

fn fail<T>(line: usize, message: String) -> std::result::Result<T, Fail> {
    Err(Fail { line, message })
}

type Res<T> = std::result::Result<T, Fail>;

/// `skip_faces`: one-line `f` statements are passed over unread ([`parse_obj_positions`]).
fn parse(bytes: &[u8], skip_faces: bool) -> Res<Mesh> {
    let text = decode(bytes)?;
    parse_text(text, skip_faces).map_err(|f| on_cut_last_line(text, f))
}

/// An error on the file's last line when the file ends without a line end: what a copy, download or export
/// that stopped leaves (`v 0.12` or `f 5438 5` torn mid-number), so the message says so.
fn on_cut_last_line(text: &[u8], mut fail: Fail) -> Fail {
    let ends_mid_line = text.last().is_some_and(|&b| b != b'\n' && b != b'\r');
    if ends_mid_line && fail.line == line_and_column(text, text.len()).0 {
        fail.message.push_str(
            " (this is the file's last line and the file ends in it, without a line end: it looks cut short, as an \
             interrupted copy, download or export leaves it; copy or export it again)",
        );
    }
    fail
}

fn parse_text(text: &[u8], skip_faces: bool) -> Res<Mesh> {
    let mut reader = Reader { skip_faces, ..Reader::default() };
    // A capacity guess from the file's size (bounded by the bytes present, never by a number in the file):
    // pages reserved but never written cost nothing, and growing a vector copies it.
    reader.mesh.positions.reserve(text.len() / 64);
    if !skip_faces {
        reader.mesh.faces.reserve(text.len() / 32);
    }
    let mut lines = PhysicalLines { rest: text, done: false };
    let mut joined: Vec<u8> = Vec::new();
    let mut lineno = 0usize;
    loop {
        // The common one-line `v` and `f` statements are read straight from the text, line end included;
        // any other line (and any line the fast path does not take whole) goes through `statement`.
        if !lines.done {
            if let Some(after) = reader.line_fast(lines.rest) {
                lines.rest = after;
                lineno += 1;
                continue;
            }
        }
        let Some(first) = lines.next() else { break };
        lineno += 1;
        let start = lineno;
        let (head, mut continued) = split_continuation(first);
        if !continued {
            reader.statement(first, start, start)?;
            continue;
        }
        // A continued statement: join the physical lines with a space, reusing one buffer.
        // Once a comment has started, the continuation makes the next lines part of it.
        let mut in_comment = has_comment(head);
        joined.clear();
        joined.extend_from_slice(head);
        while continued {
            let Some(next) = lines.next() else { break };
            lineno += 1;
            if in_comment {
                if let Some(kw) = tokens(next).next().filter(|k| is_element_keyword(k)) {
                    return fail(
                        lineno - 1,
                        format!(
                            "this comment ends with a backslash, which in OBJ continues it onto line {lineno} and so \
                             hides the `{}` statement there; remove the trailing backslash (or end the comment with \
                             another character)",
                            shown(kw)
                        ),
                    );
                }
            }
            let (part, more) = split_continuation(next);
            in_comment = in_comment || has_comment(part);
            joined.push(b' ');
            joined.extend_from_slice(part);
            continued = more;
        }
        reader.statement(&joined, start, lineno)?;
    }
    reader.finish()
}

/// Separators between tokens (what `str::split_ascii_whitespace` splits on).
fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\r' | 0x0C)
}

/// The whitespace-separated tokens of a line.
fn tokens(line: &[u8]) -> Tokens<'_> {
    Tokens { rest: line }
}

struct Tokens<'a> {
    rest: &'a [u8],
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];
    fn next(&mut self) -> Option<&'a [u8]> {
        let start = self.rest.iter().position(|&b| !is_space(b))?;
        let rest = self.rest.get(start..).unwrap_or(&[]);
        let len = rest.iter().position(|&b| is_space(b)).unwrap_or(rest.len());
        let (token, after) = rest.split_at(len.min(rest.len()));
        self.rest = after;
        Some(token)
    }
}

/// `bytes` without its leading separators other than line ends (tab, space, form feed).
fn skip_blank(bytes: &[u8]) -> &[u8] {
    let n = bytes.iter().position(|&b| !matches!(b, b' ' | b'\t' | 0x0C)).unwrap_or(bytes.len());
    bytes.get(n..).unwrap_or(&[])
}

/// What follows a line end (LF, CRLF or a lone CR) at the start of `bytes`; `None` when none is there.
fn after_line_end(bytes: &[u8]) -> Option<&[u8]> {
    match bytes {
        [b'\r', b'\n', after @ ..] | [b'\n' | b'\r', after @ ..] => Some(after),
        _ => None,
    }
}

/// Three finite numbers (`x y z` after a `v`), each ended by a separator, a line end or the end of `text`,
/// and the text after the third.
fn leading_xyz(text: &[u8]) -> Option<([f64; 3], &[u8])> {
    let mut rest = text;
    let mut xyz = [0.0f64; 3];
    for slot in &mut xyz {
        rest = skip_blank(rest);
        let (x, n) = fast_float2::parse_partial::<f64, _>(rest).ok()?;
        rest = rest.get(n..)?;
        if !x.is_finite() || !at_token_end(rest) {
            return None;
        }
        *slot = x;
    }
    Some((xyz, rest))
}

/// `bytes` without its leading separators.
fn skip_space(bytes: &[u8]) -> &[u8] {
    let n = bytes.iter().position(|&b| !is_space(b)).unwrap_or(bytes.len());
    bytes.get(n..).unwrap_or(&[])
}

/// Whether a token ends here: end of line or a separator.
fn at_token_end(bytes: &[u8]) -> bool {
    bytes.first().is_none_or(|&b| is_space(b))
}

/// An optionally signed decimal integer of at most 18 digits at the start of `bytes`, and the bytes after it.
fn leading_int(bytes: &[u8]) -> Option<(i64, &[u8])> {
    let (negative, digits) = match bytes {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, bytes),
    };
    // One pass: the value of the first 18 digits, and whether a 19th follows (then None).
    let mut value = 0i64;
    let mut n = 0usize;
    while let Some(&d) = digits.get(n) {
        if !d.is_ascii_digit() || n == 18 {
            break;
        }
        value = value * 10 + i64::from(d - b'0');
        n += 1;
    }
    if n == 0 || digits.get(n).is_some_and(u8::is_ascii_digit) {
        return None;
    }
    let after = digits.get(n..).unwrap_or(&[]);
    Some((if negative { -value } else { value }, after))
}

/// Resolves a 1-based or negative OBJ index against `count` items read so far; `None` when out of range
/// (the slow path then says why).
fn resolve_fast(index: i64, count: usize) -> Option<usize> {
    let count = i64::try_from(count).ok()?;
    let resolved = if index > 0 { index - 1 } else { count + index };
    if index != 0 && (0..count).contains(&resolved) {
        usize::try_from(resolved).ok()
    } else {
        None
    }
}

/// Whether a line holds a comment (a token starting with '#').
fn has_comment(line: &[u8]) -> bool {
    tokens(line).any(|t| t.first() == Some(&b'#'))
}

/// Statements whose loss would change the mesh or the numbering of its references.
fn is_element_keyword(k: &[u8]) -> bool {
    matches!(k, b"v" | b"vt" | b"vn" | b"vp" | b"f" | b"fo" | b"l" | b"p")
}

/// Removes a trailing backslash (spaces or tabs after it allowed). Returns the line without it and whether
/// the line continues.
fn split_continuation(line: &[u8]) -> (&[u8], bool) {
    let mut t = line;
    while let [rest @ .., b' ' | b'\t'] = t {
        t = rest;
    }
    match t {
        [head @ .., b'\\'] => (head, true),
        _ => (line, false),
    }
}

/// The text after the physical line that starts `text`, when that line has a line end and is not continued by
/// a backslash (what [`PhysicalLines`] and [`split_continuation`] would find).
fn skip_line(text: &[u8]) -> Option<&[u8]> {
    let i = memchr::memchr2(b'\n', b'\r', text)?;
    let (line, end) = text.split_at(i);
    if split_continuation(line).1 {
        return None;
    }
    after_line_end(end)
}

/// Physical lines ended by LF, CRLF or a lone CR.
struct PhysicalLines<'a> {
    rest: &'a [u8],
    done: bool,
}

impl<'a> Iterator for PhysicalLines<'a> {
    type Item = &'a [u8];
    fn next(&mut self) -> Option<&'a [u8]> {
        if self.done {
            return None;
        }
        let bytes = self.rest;
        match memchr::memchr2(b'\n', b'\r', bytes) {
            Some(i) => {
                let end = if bytes.get(i) == Some(&b'\r') && bytes.get(i + 1) == Some(&b'\n') { i + 2 } else { i + 1 };
                let line = bytes.get(..i).unwrap_or(&[]);
                self.rest = bytes.get(end..).unwrap_or(&[]);
                Some(line)
            }
            None => {
                self.done = true;
                Some(bytes)
            }
        }
    }
}

/// A byte that marks binary data: C0 controls other than tab, LF, CR and form feed, and DEL.
fn is_binary(b: u8) -> bool {
    (b < 0x20 && b != b'\t' && b != b'\n' && b != b'\r' && b != 0x0C) || b == 0x7F
}

/// Position of the first binary byte. Whole 64-byte chunks are tested branch-free (vectorised), so it costs
/// a few milliseconds on tens of megabytes; the chunk with a hit and the tail are then searched bytewise.
fn first_binary(bytes: &[u8]) -> Option<usize> {
    let mut base = 0;
    for chunk in bytes.chunks_exact(64) {
        if chunk.iter().fold(0u8, |acc, &b| acc | u8::from(is_binary(b))) != 0 {
            break;
        }
        base += 64;
    }
    bytes.get(base..).and_then(|rest| rest.iter().position(|&b| is_binary(b))).map(|i| base + i)
}

/// Checks that the bytes are OBJ text (no UTF-16, no binary control bytes) and returns the body without
/// a UTF-8 byte-order mark and DOS end-of-file markers. Other bytes >= 0x80 are left to the statements:
/// only numbers must be ASCII.
fn decode(bytes: &[u8]) -> Res<&[u8]> {
    if bytes.is_empty() {
        return fail(0, "the file is empty (0 bytes); export the mesh again as a Wavefront OBJ".into());
    }
    if bytes.starts_with(&[0xFE, 0xFF]) || bytes.starts_with(&[0xFF, 0xFE]) {
        return fail(
            1,
            "the file is UTF-16 text (it starts with a UTF-16 byte-order mark), not an OBJ text file; \
             save or export it again as UTF-8 or ASCII"
                .into(),
        );
    }
    let bom = if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) { 3 } else { 0 };
    let mut end = bytes.len();
    while end > bom && bytes.get(end - 1) == Some(&0x1A) {
        end -= 1; // DOS end-of-file marker
    }
    let body = bytes.get(bom..end).unwrap_or(&[]);
    if let Some(at) = first_binary(body) {
        let (line, col) = line_and_column(body, at);
        let byte = body.get(at).copied().unwrap_or(0);
        let what = if byte == 0 { "a NUL byte (0x00)".to_string() } else { format!("the control byte 0x{byte:02X}") };
        return fail(
            line,
            format!(
                "{what} at column {col}: this is binary data (or UTF-16 text), not an OBJ text file; \
                 export the mesh again as a text Wavefront OBJ (ASCII or UTF-8)"
            ),
        );
    }
    Ok(body)
}

/// 1-based line and column (in bytes) of byte `at`, with the same line ends as [`PhysicalLines`].
fn line_and_column(bytes: &[u8], at: usize) -> (usize, usize) {
    let before = bytes.get(..at).unwrap_or(bytes);
    let mut line = 1;
    let mut line_start = 0;
    let mut i = 0;
    while let Some(&b) = before.get(i) {
        if b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n')) {
            line += 1;
            line_start = i + 1;
        }
        i += 1;
    }
    (line, at.saturating_sub(line_start) + 1)
}

/// A token for an error message: at most 40 characters; bytes that are not UTF-8 are shown as U+FFFD.
fn shown(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    let mut chars = text.chars();
    let head: String = chars.by_ref().take(40).collect();
    if chars.next().is_some() {
        format!("{head}...")
    } else {
        head
    }
}

/// What an index refers to.
#[derive(Clone, Copy)]
enum Target {
    Position,
    TexCoord,
    Normal,
}

/// An element that refers to vertices.
#[derive(Clone, Copy, PartialEq)]
enum Element {
    Face,
    Line,
    Point,
}

impl Element {
    fn name(self) -> &'static str {
        match self {
            Element::Face => "face",
            Element::Line => "line element (`l`)",
            Element::Point => "point element (`p`)",
        }
    }
    fn min_vertices(self) -> usize {
        match self {
            Element::Face => 3,
            Element::Line => 2,
            Element::Point => 1,
        }
    }
}

#[derive(Default)]
struct Reader {
    mesh: Mesh,
    texcoords: usize,
    normals: usize,
    /// Position indices of the element being read (reused: no allocation per line).
    corners: Vec<u32>,
    /// One-line `f` statements are skipped, not read ([`parse_obj_positions`]).
    skip_faces: bool,
}

impl Reader {
    fn statement(&mut self, line: &[u8], start: usize, end: usize) -> Res<()> {
        let mut tokens = tokens(line);
        let Some(keyword) = tokens.next() else { return Ok(()) };
        let rest = tokens.rest;
        // A comment runs from a token that starts with '#' to the end of the line.
        let tokens = tokens.take_while(|t| t.first() != Some(&b'#'));
        let r = match keyword {
            // The common forms are read straight from the bytes; anything else (and every error) goes
            // through the token-by-token path, which names the problem.
            b"v" if self.vertex_fast(rest) => Ok(()),
            b"f" if self.face_fast(rest) => Ok(()),
            b"v" => self.vertex(tokens),
            b"vt" => {
                self.texcoords += 1;
                Ok(())
            }
            b"vn" => {
                self.normals += 1;
                Ok(())
            }
            b"f" | b"fo" => self.element(Element::Face, tokens),
            b"l" => self.element(Element::Line, tokens),
            b"p" => self.element(Element::Point, tokens),
            // A statement starts with a keyword (letters; `#` starts a comment): a line that starts with
            // anything else is damage (a vertex line overwritten, a number torn from its statement), and
            // skipping it would move the blame to a later line or another file.
            _ if !(keyword[0].is_ascii_alphabetic() || keyword[0] == b'#') => Err(format!(
                "`{}` is not an OBJ statement (a statement starts with a keyword such as v, vt, vn or f; # starts \
                 a comment): the line is damaged: export the file again",
                shown(keyword)
            )),
            // Comments, groups, objects, materials, smoothing groups, free-form geometry, vendor
            // extensions (`vw`, `t`, ...): nothing posemfa uses.
            _ => Ok(()),
        };
        r.map_err(|message| {
            let message = if end > start {
                format!(
                    "{message} (this statement is continued with trailing backslashes over lines {start}-{end}; \
                     a continuation ends at the first line without one, even an empty line)"
                )
            } else {
                message
            };
            Fail { line: start, message }
        })
    }

    /// A whole line at the start of `text`, `v x y z` or a face of in-range references, ended by a line end
    /// (no comment, no continuation): stores it and returns the text after the line end. `None` (with
    /// nothing stored) for anything else, which [`Reader::statement`] then reads; it stores the same for
    /// the lines taken here.
    fn line_fast<'t>(&mut self, text: &'t [u8]) -> Option<&'t [u8]> {
        match text {
            [b'v', b' ' | b'\t' | 0x0C, rest @ ..] => {
                let (xyz, rest) = leading_xyz(rest)?;
                let after = after_line_end(skip_blank(rest))?;
                self.push_vertex(xyz).then_some(after)
            }
            [b'f', b' ' | b'\t' | 0x0C, rest @ ..] if self.skip_faces => skip_line(rest),
            [b'f', b' ' | b'\t' | 0x0C, rest @ ..] => {
                let after = after_line_end(self.corners_fast(rest)?)?;
                self.push_fan().then_some(after)
            }
            _ => None,
        }
    }

    /// `x y z` (then a comment or nothing): true when read and stored.
    fn vertex_fast(&mut self, line: &[u8]) -> bool {
        let Some((xyz, rest)) = leading_xyz(line) else { return false };
        let rest = skip_space(rest);
        (rest.is_empty() || rest.first() == Some(&b'#')) && self.push_vertex(xyz)
    }

    /// Stores a vertex unless there are already u32::MAX of them (the slow path then says so).
    fn push_vertex(&mut self, xyz: [f64; 3]) -> bool {
        if self.mesh.positions.len() >= u32::MAX as usize {
            return false;
        }
        self.mesh.positions.push(xyz);
        true
    }

    /// A face of `v`, `v/vt`, `v//vn` or `v/vt/vn` references, all in range: true when read and stored.
    fn face_fast(&mut self, line: &[u8]) -> bool {
        self.corners_fast(line).is_some() && self.push_fan()
    }

    /// Reads `v`, `v/vt`, `v//vn` or `v/vt/vn` references, all in range, into `corners`, up to a comment, a
    /// line end or the end of `text`, and returns the text from there.
    fn corners_fast<'t>(&mut self, text: &'t [u8]) -> Option<&'t [u8]> {
        self.corners.clear();
        let mut rest = skip_blank(text);
        while let Some(&first) = rest.first() {
            if matches!(first, b'#' | b'\n' | b'\r') {
                break;
            }
            let (v, after) = leading_int(rest)?;
            let v = resolve_fast(v, self.mesh.positions.len()).and_then(|v| u32::try_from(v).ok())?;
            rest = after;
            if let [b'/', after @ ..] = rest {
                rest = after;
                if let Some((t, after)) = leading_int(rest) {
                    resolve_fast(t, self.texcoords)?;
                    rest = after;
                }
                if let [b'/', after @ ..] = rest {
                    let (n, after) = leading_int(after)?;
                    resolve_fast(n, self.normals)?;
                    rest = after;
                }
            }
            if !at_token_end(rest) {
                return None;
            }
            self.corners.push(v);
            rest = skip_blank(rest);
        }
        Some(rest)
    }

    /// Stores the face in `corners` as a fan of triangles when it has at least 3 corners.
    fn push_fan(&mut self) -> bool {
        if self.corners.len() < 3 {
            return false;
        }
        if let Some((&first, others)) = self.corners.split_first() {
            for pair in others.windows(2) {
                if let [b, c] = *pair {
                    self.mesh.faces.push([first, b, c]);
                }
            }
        }
        true
    }

    fn vertex<'a>(&mut self, tokens: impl Iterator<Item = &'a [u8]>) -> std::result::Result<(), String> {
        let mut xyz = [0.0f64; 3];
        let mut count = 0usize;
        for token in tokens {
            let value = number(token, count)?;
            if let Some(slot) = xyz.get_mut(count) {
                *slot = value;
            }
            count += 1;
        }
        match count {
            3 | 4 | 6 => {}
            0..=2 => {
                return Err(format!(
                    "vertex has {count} coordinate{}, it needs 3: write `v x y z` (optionally followed by w, or \
                     by r g b)",
                    if count == 1 { "" } else { "s" }
                ))
            }
            _ => {
                return Err(format!(
                    "vertex has {count} numbers; expected 3 (`v x y z`), 4 (`v x y z w`) or 6 (`v x y z r g b`); \
                     remove the extra values"
                ))
            }
        }
        if self.mesh.positions.len() >= u32::MAX as usize {
            return Err("too many vertices (more than 4294967295); split the mesh".into());
        }
        self.mesh.positions.push(xyz);
        Ok(())
    }

    fn element<'a>(
        &mut self,
        kind: Element,
        tokens: impl Iterator<Item = &'a [u8]>,
    ) -> std::result::Result<(), String> {
        self.corners.clear();
        for token in tokens {
            let index = self.reference(kind, token)?;
            self.corners.push(index);
        }
        let n = self.corners.len();
        if n < kind.min_vertices() {
            return Err(match kind {
                Element::Face => format!(
                    "face has {n} vert{}, a face needs at least 3; remove it (or write it as `l` for a line, `p` \
                     for a point)",
                    if n == 1 { "ex" } else { "ices" }
                ),
                _ => format!(
                    "{} has {n} vert{}, it needs at least {}; remove it",
                    kind.name(),
                    if n == 1 { "ex" } else { "ices" },
                    kind.min_vertices()
                ),
            });
        }
        if kind == Element::Face {
            if let Some((&first, rest)) = self.corners.split_first() {
                for pair in rest.windows(2) {
                    if let [b, c] = *pair {
                        self.mesh.faces.push([first, b, c]);
                    }
                }
            }
        }
        Ok(())
    }

    /// Checks one `v`, `v/vt`, `v//vn` or `v/vt/vn` reference and returns the 0-based position index.
    fn reference(&self, kind: Element, token: &[u8]) -> std::result::Result<u32, String> {
        let bad = || {
            format!(
                "`{}` is not a valid {} vertex: write an integer index as in `7`, `7/2`, `7//3` or `7/2/3` \
                 (1 = the first `v` line, -1 = the latest one)",
                shown(token),
                kind.name()
            )
        };
        let mut parts = token.split(|&b| b == b'/');
        let position = parts.next().unwrap_or(&[]);
        let texcoord = parts.next().unwrap_or(&[]);
        let normal = parts.next().unwrap_or(&[]);
        if parts.next().is_some() || position.is_empty() {
            return Err(bad());
        }
        let v = self.resolve(kind, Target::Position, position).ok_or_else(bad)??;
        if !texcoord.is_empty() {
            self.resolve(kind, Target::TexCoord, texcoord).ok_or_else(bad)??;
        }
        if !normal.is_empty() {
            self.resolve(kind, Target::Normal, normal).ok_or_else(bad)??;
        }
        // Positions never exceed u32::MAX (checked when they are read).
        u32::try_from(v).map_err(|_| bad())
    }

    /// Resolves a 1-based or negative (relative) index against what has been read so far.
    /// `None` when the text is not an integer at all.
    fn resolve(&self, kind: Element, target: Target, text: &[u8]) -> Option<std::result::Result<usize, String>> {
        let (negative, digits) = match text {
            [b'-', rest @ ..] => (true, rest),
            [b'+', rest @ ..] => (false, rest),
            _ => (false, text),
        };
        if digits.is_empty() || !digits.iter().all(u8::is_ascii_digit) {
            return None;
        }
        let count = match target {
            Target::Position => self.mesh.positions.len(),
            Target::TexCoord => self.texcoords,
            Target::Normal => self.normals,
        };
        // The digits as a number; None when it does not fit in 64 bits.
        let magnitude = digits.iter().try_fold(0i64, |acc, &d| acc.checked_mul(10)?.checked_add(i64::from(d - b'0')));
        let count_i = i64::try_from(count).unwrap_or(i64::MAX);
        if let Some(m) = magnitude {
            // The common case, without building any message.
            let resolved = if negative { count_i - m } else { m - 1 };
            if m != 0 && resolved >= 0 && resolved < count_i {
                return Some(
                    usize::try_from(resolved)
                        .map_err(|_| self.index_error(kind, target, negative, &shown(text), count)),
                );
            }
            if m == 0 {
                let (what, ..) = describe(target);
                return Some(Err(format!(
                    "{} {what} 0 is invalid: OBJ indices start at 1 (1 = the first line of its kind, -1 = the \
                     latest one); fix the index or export the file again",
                    kind.name()
                )));
            }
            let signed = if negative { -m } else { m };
            return Some(Err(self.index_error(kind, target, negative, &signed.to_string(), count)));
        }
        // Only digits with an optional sign: the number is too large for 64 bits.
        Some(Err(self.index_error(kind, target, negative, &shown(text), count)))
    }

    fn index_error(&self, kind: Element, target: Target, negative: bool, shown_index: &str, count: usize) -> String {
        let (what, lines, advice) = describe(target);
        let element = kind.name();
        let lines = if count == 1 { singular(lines) } else { lines.to_string() };
        if negative {
            format!(
                "{element} {what} {shown_index} is out of range: negative indices count back from the latest \
                 one, and the file has {count} {lines} so far{advice}"
            )
        } else {
            format!(
                "{element} {what} {shown_index} is out of range (the file has {count} {lines} so far); OBJ \
                 indices are 1-based and refer to lines above the {element}{}",
                if advice.is_empty() { "; the file is damaged or cut: export it again" } else { advice }
            )
        }
    }

    fn finish(self) -> Res<Mesh> {
        if self.mesh.positions.is_empty() {
            return fail(
                0,
                "no vertices: the file has no `v` lines (it is empty or holds only comments or other statements); \
                 export the mesh again as a Wavefront OBJ with its vertices"
                    .into(),
            );
        }
        Ok(self.mesh)
    }
}

/// How an index target is named in messages: (what, lines, advice).
fn describe(target: Target) -> (&'static str, &'static str, &'static str) {
    match target {
        Target::Position => ("index", "vertices", ""),
        Target::TexCoord => (
            "texture-coordinate index",
            "texture coordinates (`vt` lines)",
            "; texture coordinates are not used here, but a reference to a missing one means the file is \
             damaged or cut: export it again (or without texture coordinates)",
        ),
        Target::Normal => (
            "normal index",
            "normals (`vn` lines)",
            "; normals are not used here, but a reference to a missing one means the file is damaged or cut: \
             export it again (or without normals)",
        ),
    }
}

/// "vertices" -> "vertex", "normals (`vn` lines)" -> "normal (`vn` line)", ...
fn singular(plural: &str) -> String {
    plural
        .replacen("vertices", "vertex", 1)
        .replacen("coordinates", "coordinate", 1)
        .replacen("normals", "normal", 1)
        .replacen("lines", "line", 1)
}

/// Parses the `k`-th (0-based) number of a `v` line; it must be a finite decimal number.
fn number(token: &[u8], k: usize) -> std::result::Result<f64, String> {
    let parsed = fast_float2::parse::<f64, _>(token);
    if let Ok(x) = parsed {
        if x.is_finite() {
            return Ok(x);
        }
    }
    // Only errors from here on (so building the message allocates on errors only).
    let which = match k {
        0 => "x coordinate".to_string(),
        1 => "y coordinate".to_string(),
        2 => "z coordinate".to_string(),
        _ => format!("value {} of this vertex", k + 1),
    };
    match parsed {
        Ok(x) => {
            let looks_numeric = token.iter().any(u8::is_ascii_digit);
            Err(if looks_numeric {
                format!(
                    "{which} `{}` overflows (beyond 1.8e308, read as {x}); fix this vertex in the tool that wrote \
                     the file and export again",
                    shown(token)
                )
            } else {
                format!(
                    "{which} is `{}`, which is not a finite number; the exporting tool wrote an invalid vertex: fix \
                     it there and export again",
                    shown(token)
                )
            })
        }
        Err(_) if token.contains(&b'#') => Err(format!(
            "{which} is `{}`, Microsoft's notation for NaN or infinity, not a finite number; the exporting tool \
             wrote an invalid vertex: fix it there and export again",
            shown(token)
        )),
        Err(_) => match token.iter().find(|&&b| b >= 0x80) {
            Some(b) => Err(format!(
                "{which} `{}` holds the byte 0x{b:02X}, which is not ASCII: numbers must be written with ASCII \
                 digits; this is binary data or text in another encoding (UTF-16?), so export the mesh again",
                shown(token)
            )),
            None => Err(format!(
                "{which} `{}` is not a number; write decimal numbers such as `1.5`, `-2`, `.5` or `3.1e2`",
                shown(token)
            )),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(text: &str) -> Mesh {
        match parse_obj("t.obj", text.as_bytes()) {
            Ok(m) => m,
            Err(e) => panic!("expected to load, got: {e}"),
        }
    }

    /// Parses bytes that must fail; returns (line, message) after checking the Display form.
    fn err_bytes(bytes: &[u8]) -> (usize, String) {
        match parse_obj("t.obj", bytes) {
            Ok(m) => panic!("expected an error, loaded {} vertices / {} faces", m.positions.len(), m.faces.len()),
            Err(e @ Error::Obj { .. }) => {
                let shown = e.to_string();
                let Error::Obj { line, message, file } = e else { unreachable!() };
                assert_eq!(file, "t.obj");
                if line > 0 {
                    assert!(shown.starts_with(&format!("file t.obj, line {line}: ")), "{shown}");
                } else {
                    assert!(shown.starts_with("file t.obj: "), "{shown}");
                }
                (line, message)
            }
            Err(e) => panic!("wrong error kind: {e:?}"),
        }
    }

    fn err(text: &str) -> (usize, String) {
        err_bytes(text.as_bytes())
    }

    fn assert_err(text: &str, line: usize, needles: &[&str]) {
        let (l, m) = err(text);
        assert_eq!(l, line, "wrong line for {text:?}: {m}");
        for n in needles {
            assert!(m.contains(n), "message {m:?} lacks {n:?}");
        }
    }

    #[test]
    fn a_line_that_starts_with_no_keyword_is_damage() {
        assert_err(
            "v 0 0 0\nv 1 0 0\n%%%% garbage $$$\nv 0 1 0\nf 1 2 3\n",
            3,
            &["`%%%%` is not an OBJ statement", "export the file again"],
        );
        assert_err("v 0 0 0\n1.000000\n", 2, &["`1.000000` is not an OBJ statement"]);
        // keywords posemfa does not use (vendor extensions, free-form geometry) and comments are skipped
        let m = ok("# c\n#MRGB 00ff\nvw 1 0 1.0\nt crease 2 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        assert_eq!((m.positions.len(), m.faces.len()), (3, 1));
    }

    #[test]
    fn keeps_v_order_with_unreferenced_vertices_and_objects() {
        let m = ok("o a\nv 0 0 0\nv 1 0 0\nv 9 9 9\nv 0 1 0\nf 4 2 1\ng b\nv 5 5 5\no c\nv 2 0 0\nv 2 1 0\nf 1 6 7\n");
        assert_eq!(
            m.positions,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [9.0, 9.0, 9.0],
                [0.0, 1.0, 0.0],
                [5.0, 5.0, 5.0],
                [2.0, 0.0, 0.0],
                [2.0, 1.0, 0.0]
            ]
        );
        assert_eq!(m.faces, vec![[3, 1, 0], [0, 5, 6]]);
    }

    #[test]
    fn negative_indices_are_relative_to_the_latest_vertex() {
        let m = ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -1 -2 1\nvt 0 0\nvn 0 0 1\nf -4/-1/-1 2 3\n");
        assert_eq!(m.faces, vec![[0, 1, 2], [3, 2, 0], [0, 1, 2]]);
    }

    #[test]
    fn quads_and_ngons_are_fans() {
        let m = ok("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\nv -1 0 0\nf 1 2 3 4\nf 1 2 3 4 5 6\n");
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);
        // Degenerate faces are kept: the topology is the file's.
        assert_eq!(ok("v 0 0 0\nv 1 0 0\nf 2 2 2\nf 1 2 2\n").faces, vec![[1, 1, 1], [0, 1, 1]]);
    }

    #[test]
    fn face_vertex_forms_and_ignored_elements() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n\
                    f 1/1 2/2 3/1\nf 1//1 2//1 3//1\nf 1/1/1 2/2/1 3/1/1\nf 1/1/ 2/2/ 3/1/\nf +1 2 3\n\
                    l 1 2 3\nl 1/-2 2/-1\np 1 2 3\ns off\nusemtl x\nvw 1 0 1.0\nt crease 2/1/0 1 2 5.0\n";
        let m = ok(text);
        assert_eq!(m.positions.len(), 3);
        assert_eq!(m.faces, vec![[0, 1, 2]; 5]);
    }

    #[test]
    fn vertex_colours_and_w_keep_xyz() {
        let m = ok("v 1 2 3 0.5 0.25 1\nv 4 5 6 2.0\nv .5 -.7e+2 2.e01 \nv +1 1E2 -0\nf 1 2 3\n");
        assert_eq!(m.positions, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [0.5, -70.0, 20.0], [1.0, 100.0, -0.0]]);
    }

    #[test]
    fn line_ends_comments_and_whitespace() {
        let crlf = ok("# c\r\nv 0 0 0\r\nv 1 0 0 # inline\r\nv\t0  1\t0\r\n\r\nf 1 2 3 # tri\r\n");
        assert_eq!(crlf.positions.len(), 3);
        assert_eq!(crlf.faces, vec![[0, 1, 2]]);
        // Old Mac line ends (lone CR) are line ends too, not spaces that would merge two vertices.
        let cr = ok("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3");
        assert_eq!(cr.positions.len(), 3);
        assert_err("v 0 0 0\rv 1 0 0\rv 0 1\rf 1 2 3", 3, &["2 coordinates"]);
        assert_err("v 0 0 0\r\nv 1 0 0\r\n\r\nf 1 2 4\r\n", 4, &["index 4 is out of range"]);
        // A UTF-8 byte-order mark and a DOS end-of-file marker are skipped.
        let mut b = vec![0xEF, 0xBB, 0xBF];
        b.extend_from_slice(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\x1A");
        assert_eq!(parse_obj("t.obj", &b).map(|m| m.faces.len()), Ok(1));
    }

    #[test]
    fn line_continuation() {
        let m = ok("v -1 \\\n 0 1\nv 1 0 \\  \n1\nv 0 \\\n\\\n1 0\nf 1 \\\n2 3\n");
        assert_eq!(m.positions, vec![[-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.0]]);
        assert_eq!(m.faces, vec![[0, 1, 2]]);
        // Comments continue too (so ASCII art ending in '\' stays a comment) ...
        let m = ok("#   / \\\n#  /   \\\n# \\\n www.\\\nblender.\\\norg\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        assert_eq!(m.positions.len(), 3);
        // ... but not over a statement: that would silently drop a vertex.
        assert_err("v 0 0 0\n# note \\\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 2, &["backslash", "line 3", "`v`"]);
        assert_err("v 0 0 0 # note \\\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 1, &["backslash", "line 2", "`v`"]);
        assert_err("v 0 0 \\\n0 # note \\\nf 1 1 1\n", 2, &["backslash", "line 3", "`f`"]);
        // A continuation that reaches an empty line ends there: the error names the first line and the span.
        assert_err("# x\nv -1 \\\n 0 \\\n\n 1\nv 1 0 0\n", 2, &["2 coordinates", "lines 2-4"]);
    }

    /// The positions-only reading gives the full reading's positions, whatever the faces and line ends look
    /// like, continued `f` statements and comments included.
    #[test]
    fn positions_only_reading_gives_the_same_positions() {
        let texts = [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\r\nv 1 0 0\r\nf 1 2 -1\r\nv 0 1 0\r\nvt 0 0\r\nvt 1 0\r\nvt 0 1\r\nf 1/1 2/2 3/3\r\n",
            "v 0 0 0\rv 1 0 0\rv 0 1 0\rvn 0 0 1\rf 1//1 2//1 3//1\rv 5 5 5",
            // a face continued onto the next line, one whose comment ends in a backslash, one at the end
            "v -1 \\\n 0 1\nv 1 0 0\nv 0 1 0\nf 1 \\\n2 3\nv 2 2 2\nf 1 2 4 # c \\\n\nv 3 3 3\nf 1 2 3",
            // a face line ending in blanks, a tab after f, a quad, vt / vn lines, objects and groups
            "o a\nv 0 0 0\nv 1 0 0\nvt 0 0\nvn 0 0 1\nv 1 1 0\nv 0 1 0\nf\t1 2 3 4  \t\ng b\nf 1/1/1 2/1/1 3/1/1\nv 9 9 9\n",
        ];
        for t in texts {
            let full = parse_obj("t.obj", t.as_bytes()).unwrap_or_else(|e| panic!("{t:?}: {e}"));
            assert!(!full.faces.is_empty());
            assert_eq!(parse_obj_positions("t.obj", t.as_bytes()).unwrap(), full.positions, "{t:?}");
        }
        // (it skips the faces it does not read: a face the full reading refuses passes unread)
        assert!(parse_obj("t.obj", b"v 0 0 0\nf 1 2 3\n").is_err());
        assert_eq!(parse_obj_positions("t.obj", b"v 0 0 0\nf 1 2 3\n").unwrap(), vec![[0.0; 3]]);
    }

    #[test]
    fn an_error_where_the_file_stops_mid_line_says_it_looks_cut_short() {
        let cut = "looks cut short";
        // torn in a vertex and in a face: the last line, no line end
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1", 3, &["2 coordinates", cut]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1", 5, &["face has 1 vertex,", cut]);
        // the same errors in a whole file (a line end after them, or lines after them) are not called cut
        for whole in ["v 0 0 0\nv 1 0 0\nv 0 1\n", "v 0 0 0\nv 1 0 0\nv 0 1\nv 1 1 1"] {
            let (line, message) = err(whole);
            assert_eq!(line, 3);
            assert!(!message.contains(cut), "{message}");
        }
    }

    #[test]
    fn errors_name_the_line() {
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 0\n", 5, &["index 0 is invalid", "start at 1"]);
        assert_err(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 9 3\n",
            5,
            &["face index 9 is out of range", "3 vertices so far", "1-based"],
        );
        assert_err("f -4 -3 -2", 1, &["index -4 is out of range", "0 vertices so far"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4, &["-4 is out of range", "count back"]);
        assert_err("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", 3, &["index 3 is out of range", "2 vertices so far"]);
        assert_err(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 99999999999999999999999 3\n",
            4,
            &["99999999999999999999999 is out of range"],
        );
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", 4, &["face has 2 vertices", "at least 3"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1\n", 4, &["face has 1 vertex,"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf\n", 4, &["face has 0 vertices"]);
        assert_err(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            5,
            &["texture-coordinate index 2 is out of range", "1 texture"],
        );
        assert_err(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n",
            4,
            &["normal index 1 is out of range", "0 normals"],
        );
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//0 2//1 3//1\n", 5, &["normal index 0 is invalid"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n", 4, &["`1/2/3/4` is not a valid face vertex"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf a b c\n", 4, &["`a` is not a valid face vertex"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1.0 2 3\n", 4, &["`1.0` is not a valid"]);
        assert_err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf //1 2 3\n", 4, &["`//1` is not a valid"]);
        assert_err("v 0 0 0\np 2\n", 2, &["point element (`p`) index 2 is out of range"]);
        assert_err("v 0 0 0\nv 1 0 0\nl 1\n", 3, &["line element (`l`) has 1 vertex,"]);
        assert_err("v 0 0 0\nv 1 0 0\nl 1 bleh\n", 3, &["`bleh` is not a valid line element"]);
    }

    #[test]
    fn bad_numbers_name_the_line() {
        assert_err("v 0 0 0\nv 1 2 3.1+e2\n", 2, &["z coordinate `3.1+e2` is not a number"]);
        assert_err("v 0 0 0\nv 1 bleh 2\n", 2, &["y coordinate `bleh` is not a number"]);
        assert_err("v 0 0 0\n\nv nan 0 0\n", 3, &["x coordinate is `nan`", "not a finite number"]);
        assert_err("v 0 0 0\nv 0 -inf 0\n", 2, &["`-inf`", "not a finite number"]);
        assert_err("v 0 0 0\nv 0 0 1.#IND\n", 2, &["`1.#IND`", "NaN or infinity"]);
        assert_err("v 0 0 0\nv -1.#INF 0 0\n", 2, &["`-1.#INF`"]);
        assert_err("v 3E4570711268 0 0\n", 1, &["`3E4570711268` overflows"]);
        assert_err("v 0 0 0\nv 1 2\n", 2, &["vertex has 2 coordinates", "needs 3"]);
        assert_err("v\n", 1, &["vertex has 0 coordinates"]);
        assert_err("v 1 2 3 4 5\n", 1, &["vertex has 5 numbers"]);
        assert_err("v 1 2 3 4 5 6 7\n", 1, &["vertex has 7 numbers"]);
        assert_err("v 1 2 3 1 nan 1\n", 1, &["value 5 of this vertex"]);
        // Long tokens are shortened in messages.
        let long = format!("v 1 2 {}x\n", "9".repeat(200));
        let (_, m) = err(&long);
        assert!(m.len() < 300, "{m}");
    }

    #[test]
    fn encodings_and_binary_data() {
        let (l, m) = err_bytes(b"");
        assert_eq!(l, 0);
        assert!(m.contains("empty"), "{m}");
        for text in ["# only a comment\n", "\n\n", "g x\nvt 0 0\n"] {
            let (l, m) = err(text);
            assert_eq!(l, 0);
            assert!(m.contains("no vertices"), "{m}");
        }
        let (l, m) = err_bytes(b"\xFE\xFF\x00v\x00 \x001");
        assert_eq!(l, 1);
        assert!(m.contains("UTF-16"), "{m}");
        // Latin-1 (3ds Max) names and comments load; only numbers must be ASCII.
        let latin1 = b"# caf\xE9\nmtllib m\xFC.mtl\no Fl\xFCgel\nv 0 0 0\nv 1 0 0\r\nusemtl \xC9t\xE9\nv 0 1 0\nf 1 2 3 # \xA9\n";
        assert_eq!(parse_obj("t.obj", latin1).map(|m| (m.positions.len(), m.faces.len())), Ok((3, 1)));
        let (l, m) = err_bytes(b"v 0 0 0\nv 1 0 0\r\nv 0 1\xE9 0\n");
        assert_eq!(l, 3);
        assert!(m.contains("0xE9") && m.contains("y coordinate") && m.contains("ASCII"), "{m}");
        let (l, m) = err_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \xB3\n");
        assert_eq!(l, 4);
        assert!(m.contains("not a valid face vertex"), "{m}");
        let (l, m) = err_bytes(b"v 0 0 0\nv 1 0\x00 0\n");
        assert_eq!(l, 2);
        assert!(m.contains("NUL") && m.contains("column 6") && m.contains("binary"), "{m}");
        let (l, m) = err_bytes(b"v 0 0 0\n\nv 1 0 0\x01\n");
        assert_eq!(l, 3);
        assert!(m.contains("0x01"), "{m}");
        // The earliest problem wins.
        assert_eq!(err_bytes(b"v 0 0 0\n\x00\n\xFF\n").0, 2);
        assert_eq!(err_bytes(b"v 0 0 0\n\xFF\n\x00\n").0, 3);
        // UTF-16 without a byte-order mark is NUL bytes.
        assert_eq!(err_bytes(b"v\x00 \x000\x00").0, 1);
    }

    #[test]
    fn fast_and_token_paths_agree() {
        // Every line once as it is (whole lines such as these are read straight from the text) and once with
        // a comment after it (read token by token): the same mesh, with each kind of line end.
        let lines = [
            "v 0.1 -2.5e3 7",
            "v\t1 2 3 ",
            "v -0 .5 5.",
            "v\x0c+1e-300 1E2 -0.022739015899999999",
            "f 1 2 3",
            "f 3/1 2/1 1/1",
            "f 1//1 2//1 3//1 4//1",
            "f -1 -2 -3\t",
            "f 1/1/1 +2/1/-1 3/-1/1 4 1",
        ];
        for end in ["\n", "\r\n", "\r"] {
            let text = |suffix: &str| {
                let mut t = format!("vt 0 0{end}vn 0 0 1{end}");
                for l in lines {
                    t.push_str(&format!("{l}{suffix}{end}"));
                }
                t
            };
            let (fast, slow) = (ok(&text("")), ok(&text(" # note")));
            assert_eq!(fast.positions.len(), 4);
            assert_eq!(fast.faces.len(), 1 + 1 + 2 + 1 + 3);
            assert_eq!((fast.positions, fast.faces), (slow.positions, slow.faces));
        }
    }

    #[test]
    fn vertices_without_faces_load() {
        let m = ok("v 0 0 0\nv 1 0 0\nl 1 2\np 1\n");
        assert_eq!((m.positions.len(), m.faces.len()), (2, 0));
    }

    /// A small deterministic fuzz: random bytes and mutated OBJ text never panic, and every error names the file.
    #[test]
    fn never_panics_on_mutated_input() {
        let seed_text = b"v 0 0 0\r\nv 1 0 0 \\\n\nv 0 1 0 1 1 1\nvt 0 0\nvn 0 0 1\nf 1/1/1 2//1 -1\nf 1 2 3 1\nl 1 2\np 3\n# c \\\n#x\n";
        let alphabet = b"vfnlpt0123456789-+./# \\\r\n\t\x00\xFFeE#IND";
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        assert_eq!(parse_obj("seed.obj", seed_text).map(|m| (m.positions.len(), m.faces.len())), Ok((3, 3)));
        let (mut loaded, mut rejected) = (0, 0);
        for round in 0..4000 {
            let mut bytes = seed_text.to_vec();
            if round % 4 == 0 {
                bytes = (0..next() % 64).map(|_| next() as u8).collect();
            }
            for _ in 0..(next() % 6) {
                let len = bytes.len() as u64 + 1;
                let at = (next() % len) as usize;
                let c = alphabet[(next() % alphabet.len() as u64) as usize];
                match next() % 3 {
                    0 => bytes.insert(at, c),
                    1 if at < bytes.len() => {
                        bytes.remove(at);
                    }
                    _ if at < bytes.len() => bytes[at] = c,
                    _ => {}
                }
            }
            match parse_obj("fuzz.obj", &bytes) {
                Ok(m) => {
                    loaded += 1;
                    let n = m.positions.len() as u32;
                    assert!(m.faces.iter().flatten().all(|&i| i < n));
                }
                Err(e) => {
                    rejected += 1;
                    assert!(e.to_string().starts_with("file fuzz.obj"), "{e}");
                }
            }
        }
        // Both paths were exercised.
        assert!(loaded > 200 && rejected > 200, "{loaded} loaded, {rejected} rejected");
    }
}
