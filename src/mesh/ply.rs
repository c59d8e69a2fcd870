//! PLY import (Stanford polygon files): ASCII, binary little endian and binary big endian.
//!
//! - vertex `j` of the [`Mesh`] is the `j`-th element of the `vertex` element; its `x`, `y`, `z` properties
//!   (any numeric type) are kept, every other property (normals, colours, confidence, ...) is skipped.
//! - faces come from the `face` element's list property `vertex_indices` (or `vertex_index`) and are
//!   fan-triangulated as the OBJ reader does (`n` corners give `n - 2` triangles `(0, k, k+1)`); other
//!   properties of faces and every other element (edges, materials, ...) are skipped.
//! - `comment` and `obj_info` lines of the header are ignored; the header itself must be ASCII up to its
//!   names (any 8-bit bytes are accepted in comments).
//!
//! Errors name the file and where: the line for the header and ASCII data, the element and its index plus
//! the byte offset for binary data; they say what is wrong and what to do. Element counts are checked
//! against the bytes actually present before anything is allocated from them, so a header that claims
//! 4 billion vertices in a 1 kB file is refused at once. The reader never panics (no indexing that can
//! fail, no `unwrap` on data).

use super::Mesh;
use crate::error::{Error, Result};

/// Parses one PLY file. `name` is used in error messages.
pub fn parse_ply(name: &str, bytes: &[u8]) -> Result<Mesh> {
    parse(bytes).map_err(|f| Error::Mesh {
        format: crate::error::Format::Ply,
        file: name.to_string(),
        line: f.line,
        message: f.message,
    })
}

/// Whether the bytes start like a PLY file (the magic line `ply`).
pub fn looks_like_ply(bytes: &[u8]) -> bool {
    bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") || bytes.starts_with(b"ply\r")
}

#[derive(Debug)]
struct Fail {
    line: usize,
    message: String,
}

type Res<T> = std::result::Result<T, Fail>;

fn fail<T>(line: usize, message: impl Into<String>) -> Res<T> {
    Err(Fail { line, message: message.into() })
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &[u8]) -> Option<Scalar> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug, Clone)]
enum Property {
    Scalar { ty: Scalar, name: Vec<u8> },
    List { count: Scalar, item: Scalar, name: Vec<u8> },
}

#[derive(Debug, Clone)]
struct Element {
    name: Vec<u8>,
    count: u64,
    /// Header line of the `element` statement (for messages).
    line: usize,
    properties: Vec<Property>,
}

/// What the reader does with an element.
enum Role {
    /// Positions: indices of the x, y, z properties.
    Vertex([usize; 3]),
    /// Faces: index of the vertex-index list.
    Face(usize),
    Skip,
}

fn text(bytes: &[u8]) -> String {
    let t = String::from_utf8_lossy(bytes);
    let mut chars = t.chars();
    let head: String = chars.by_ref().take(40).collect();
    if chars.next().is_some() {
        format!("{head}...")
    } else {
        head
    }
}

/// The header: format, elements, and the offset of the first data byte; `data_line` is the line the data
/// start on (ASCII).
struct Header {
    format: Format,
    elements: Vec<Element>,
    data_start: usize,
    data_line: usize,
}

fn header(bytes: &[u8]) -> Res<Header> {
    if !looks_like_ply(bytes) {
        return fail(
            1,
            "this is not a PLY file: it does not start with the line `ply`; export the mesh again as PLY (or give \
             the file the extension of its real format)",
        );
    }
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let rest = bytes.get(pos..).unwrap_or(&[]);
        if rest.is_empty() {
            return fail(
                line,
                "the header ends without `end_header`: the file is cut or is not a PLY file; export it again",
            );
        }
        let end = memchr::memchr(b'\n', rest).unwrap_or(rest.len());
        let raw = rest.get(..end).unwrap_or(&[]);
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        pos += (end + 1).min(rest.len());
        line += 1;
        let mut words = raw.split(|b| *b == b' ' || *b == b'\t').filter(|w| !w.is_empty());
        let Some(keyword) = words.next() else { continue };
        let words: Vec<&[u8]> = words.collect();
        match keyword {
            b"ply" if line == 1 => {}
            b"comment" | b"obj_info" => {}
            b"format" => {
                let f = match words.first().copied() {
                    Some(b"ascii") => Format::Ascii,
                    Some(b"binary_little_endian") => Format::Little,
                    Some(b"binary_big_endian") => Format::Big,
                    other => {
                        return fail(
                            line,
                            format!(
                                "unknown format `{}`: PLY is `ascii`, `binary_little_endian` or \
                                 `binary_big_endian`; export the file again",
                                text(other.unwrap_or(b""))
                            ),
                        )
                    }
                };
                if words.get(1).is_some_and(|v| *v != b"1.0" && *v != b"1") {
                    return fail(
                        line,
                        format!(
                            "PLY version `{}` is not supported (only 1.0 exists); export the file again",
                            text(words.get(1).copied().unwrap_or(b""))
                        ),
                    );
                }
                format = Some(f);
            }
            b"element" => {
                let (Some(name), Some(count)) = (words.first(), words.get(1)) else {
                    return fail(line, "an `element` line needs a name and a count, as in `element vertex 8431`");
                };
                let count =
                    std::str::from_utf8(count).ok().and_then(|c| c.parse::<u64>().ok()).ok_or_else(|| Fail {
                        line,
                        message: format!(
                            "the count `{}` of element `{}` is not a whole number; the header is damaged: export the \
                         file again",
                            text(count),
                            text(name)
                        ),
                    })?;
                elements.push(Element { name: name.to_vec(), count, line, properties: Vec::new() });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return fail(line, "a `property` line comes before any `element` line; the header is damaged");
                };
                let property =
                    match words.as_slice() {
                        [b"list", count, item, name] => {
                            let (Some(c), Some(i)) = (Scalar::parse(count), Scalar::parse(item)) else {
                                return fail(
                                    line,
                                    format!(
                                    "unknown type in `property list {} {} {}`; PLY types are char uchar short ushort \
                                     int uint float double (or int8 ... float64)",
                                    text(count),
                                    text(item),
                                    text(name)
                                ),
                                );
                            };
                            if c.is_float() {
                                return fail(
                                    line,
                                    format!(
                                        "the count type of list `{}` is a float; it must be an integer type",
                                        text(name)
                                    ),
                                );
                            }
                            Property::List { count: c, item: i, name: name.to_vec() }
                        }
                        [ty, name] => {
                            let Some(t) = Scalar::parse(ty) else {
                                return fail(
                                    line,
                                    format!(
                                    "unknown type `{}` of property `{}`; PLY types are char uchar short ushort int \
                                     uint float double (or int8 ... float64)",
                                    text(ty),
                                    text(name)
                                ),
                                );
                            };
                            Property::Scalar { ty: t, name: name.to_vec() }
                        }
                        _ => return fail(
                            line,
                            "a `property` line is `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME`",
                        ),
                    };
                element.properties.push(property);
            }
            b"end_header" => {
                let Some(format) = format else {
                    return fail(line, "the header has no `format` line; export the file again");
                };
                // (a file that ends on this line has no line after it for the data's messages to name)
                let data_line = if end < rest.len() { line + 1 } else { line };
                return Ok(Header { format, elements, data_start: pos, data_line });
            }
            other => {
                return fail(
                    line,
                    format!(
                        "unknown header line `{}`; a PLY header has format, element, property, comment, obj_info \
                         and end_header lines: the file is damaged or not a PLY file",
                        text(other)
                    ),
                )
            }
        }
    }
}

fn roles(elements: &[Element]) -> Res<Vec<Role>> {
    let mut have_vertex = false;
    let mut out = Vec::with_capacity(elements.len());
    for e in elements {
        let role = match e.name.as_slice() {
            b"vertex" if !have_vertex => {
                have_vertex = true;
                let find = |axis: &[u8]| {
                    e.properties.iter().position(|p| matches!(p, Property::Scalar { name, .. } if name == axis))
                };
                match (find(b"x"), find(b"y"), find(b"z")) {
                    (Some(x), Some(y), Some(z)) => Role::Vertex([x, y, z]),
                    _ => {
                        return fail(
                            e.line,
                            "the `vertex` element has no scalar `x`, `y` and `z` properties; posemfa needs vertex \
                             positions: export them with the mesh",
                        )
                    }
                }
            }
            b"face" => {
                let list = e.properties.iter().position(|p| {
                    matches!(p, Property::List { name, .. } if name == b"vertex_indices" || name == b"vertex_index")
                });
                match list {
                    Some(i) => Role::Face(i),
                    None => {
                        return fail(
                            e.line,
                            "the `face` element has no list property `vertex_indices` (or `vertex_index`); export \
                             the faces as vertex index lists",
                        )
                    }
                }
            }
            _ => Role::Skip,
        };
        out.push(role);
    }
    if !have_vertex {
        return fail(0, "the file has no `vertex` element: there are no vertex positions; export the mesh again");
    }
    Ok(out)
}

fn parse(bytes: &[u8]) -> Res<Mesh> {
    let h = header(bytes)?;
    let roles = roles(&h.elements)?;
    let data = bytes.get(h.data_start..).unwrap_or(&[]);
    let mut mesh = Mesh::default();
    // Face corners, 0-based as written (checked against the vertex count at the end, since the face
    // element may come first).
    let mut face_of_triangle: Vec<u64> = Vec::new();
    match h.format {
        Format::Ascii => {
            let mut r = Ascii { data, pos: 0, line: h.data_line };
            for (e, role) in h.elements.iter().zip(&roles) {
                read_element(&mut r, e, role, &mut mesh, &mut face_of_triangle)?;
            }
        }
        Format::Little | Format::Big => {
            let mut r = Binary { data, pos: 0, big: h.format == Format::Big, offset: h.data_start };
            for (e, role) in h.elements.iter().zip(&roles) {
                read_element(&mut r, e, role, &mut mesh, &mut face_of_triangle)?;
            }
        }
    }
    let n = mesh.positions.len();
    if n == 0 {
        return fail(0, "the `vertex` element is empty (0 vertices); export the mesh again with its vertices");
    }
    for (t, face) in mesh.faces.iter().zip(&face_of_triangle) {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
            return fail(
                0,
                format!(
                    "face {face} refers to vertex {bad} (0-based), but the file has {n} vertices; the file is damaged: \
                     export it again"
                ),
            );
        }
    }
    Ok(mesh)
}

/// Refuses a count that cannot fit in the `left` bytes that follow: every element takes at least `min_bytes`, of
/// which the last may lack `slack`.
fn check_count(e: &Element, min_bytes: u64, left: usize, slack: usize, line: usize) -> Res<()> {
    if min_bytes == 0 {
        return Ok(());
    }
    let fits = (left + slack) as u64 / min_bytes;
    if e.count > fits {
        return fail(
            line,
            format!(
                "the header (line {}) says {} `{}` elements, but only {left} bytes of data follow, room for at most \
                 {fits}: the file is cut or its header is wrong; export it again",
                e.line,
                e.count,
                text(&e.name)
            ),
        );
    }
    Ok(())
}

fn push_fan(mesh: &mut Mesh, face_of_triangle: &mut Vec<u64>, corners: &[u32], face: u64) {
    if let Some((&first, rest)) = corners.split_first() {
        for pair in rest.windows(2) {
            if let [b, c] = *pair {
                mesh.faces.push([first, b, c]);
                face_of_triangle.push(face);
            }
        }
    }
}

fn too_few_corners(face: u64, n: u64) -> String {
    format!(
        "face {face} has {n} vert{}, a face needs at least 3; remove it (or export the mesh again)",
        if n == 1 { "ex" } else { "ices" }
    )
}

// ---------------------------------------------------------------------------------------------- values

/// Why a value could not be read.
enum Bad {
    /// The data ended.
    End,
    /// An ASCII token that is not a number (shown in messages).
    Text(String),
}

/// Where element values come from: ASCII tokens or binary numbers. One element reader
/// ([`read_element`]) serves both; only reading, skipping and saying where differ.
trait Values {
    /// Rows of fixed size can be skipped at once (binary).
    const FIXED: bool;
    /// Bytes of data not read yet.
    fn left(&self) -> usize;
    /// Bytes the data may lack at their end beyond [`Values::value_bytes`] per value (text: the last value
    /// needs no separator after it).
    const SLACK: usize;
    /// The fewest bytes a value of `ty` takes.
    fn value_bytes(ty: Scalar) -> u64;
    /// The fewest bytes an element takes (0: it has no properties).
    fn element_bytes(e: &Element) -> u64;
    /// A cheap mark of the current place, turned into (line, text for messages) by [`Values::place`].
    fn mark(&self) -> usize;
    fn place(&self, mark: usize) -> (usize, String);
    /// The next value of type `ty`.
    fn number(&mut self, ty: Scalar) -> std::result::Result<f64, Bad>;
    /// Skips `n` values of type `ty`; false when the data end first.
    fn skip(&mut self, ty: Scalar, n: u64) -> bool;
}

struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big: bool,
    /// Offset of `data` in the file (for messages).
    offset: usize,
}

impl Binary<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let s = self.data.get(self.pos..self.pos.checked_add(N)?)?;
        let a: [u8; N] = s.try_into().ok()?;
        self.pos += N;
        Some(a)
    }
}

impl Values for Binary<'_> {
    const FIXED: bool = true;
    const SLACK: usize = 0;

    fn left(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    fn value_bytes(ty: Scalar) -> u64 {
        ty.size() as u64
    }

    fn element_bytes(e: &Element) -> u64 {
        e.properties
            .iter()
            .map(|p| match p {
                Property::Scalar { ty, .. } => ty.size() as u64,
                Property::List { count, .. } => count.size() as u64,
            })
            .sum()
    }

    fn mark(&self) -> usize {
        self.pos
    }

    fn place(&self, mark: usize) -> (usize, String) {
        (0, format!(" (at byte {})", self.offset + mark))
    }

    fn number(&mut self, ty: Scalar) -> std::result::Result<f64, Bad> {
        let big = self.big;
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let b = self.take::<$n>().ok_or(Bad::End)?;
                (if big { <$t>::from_be_bytes(b) } else { <$t>::from_le_bytes(b) }) as f64
            }};
        }
        Ok(match ty {
            Scalar::I8 => num!(i8, 1),
            Scalar::U8 => num!(u8, 1),
            Scalar::I16 => num!(i16, 2),
            Scalar::U16 => num!(u16, 2),
            Scalar::I32 => num!(i32, 4),
            Scalar::U32 => num!(u32, 4),
            Scalar::F32 => num!(f32, 4),
            Scalar::F64 => num!(f64, 8),
        })
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> bool {
        let end = usize::try_from(n.saturating_mul(ty.size() as u64)).ok().and_then(|b| self.pos.checked_add(b));
        match end {
            Some(end) if end <= self.data.len() => {
                self.pos = end;
                true
            }
            _ => false,
        }
    }
}

struct Ascii<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Ascii<'a> {
    /// The next whitespace-separated token (counting the lines it passes).
    fn token(&mut self) -> Option<&'a [u8]> {
        let data = self.data;
        while let Some(&b) = data.get(self.pos) {
            match b {
                b'\n' => self.line += 1,
                b'\r' => {
                    if data.get(self.pos + 1) != Some(&b'\n') {
                        self.line += 1;
                    }
                }
                b' ' | b'\t' | 0x0C => {}
                _ => break,
            }
            self.pos += 1;
        }
        let rest = data.get(self.pos..).filter(|r| !r.is_empty())?;
        let len = rest.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(rest.len());
        self.pos += len;
        rest.get(..len)
    }
}

impl Values for Ascii<'_> {
    const FIXED: bool = false;

    const SLACK: usize = 1;

    fn left(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    /// A character and a separator.
    fn value_bytes(_: Scalar) -> u64 {
        2
    }

    fn element_bytes(e: &Element) -> u64 {
        2 * e.properties.len() as u64
    }

    /// The line of the next value (the line the last token ended on, or the data's first line).
    fn mark(&self) -> usize {
        self.line
    }

    fn place(&self, mark: usize) -> (usize, String) {
        (mark, String::new())
    }

    fn number(&mut self, _: Scalar) -> std::result::Result<f64, Bad> {
        let tok = self.token().ok_or(Bad::End)?;
        fast_float2::parse::<f64, _>(tok).map_err(|_| Bad::Text(text(tok)))
    }

    fn skip(&mut self, _: Scalar, n: u64) -> bool {
        (0..n).all(|_| self.token().is_some())
    }
}

/// A whole number (a list length or a vertex index) from a value of any type: floats must have no fraction.
fn whole(x: f64) -> Option<i64> {
    (x.is_finite() && x.fract() == 0.0 && x.abs() <= 9.0e15).then_some(x as i64)
}

/// Reads the `count` rows of one element: vertex positions, face corners (fan-triangulated), or nothing.
fn read_element<V: Values>(
    r: &mut V,
    e: &Element,
    role: &Role,
    mesh: &mut Mesh,
    face_of_triangle: &mut Vec<u64>,
) -> Res<()> {
    let min = V::element_bytes(e);
    if min == 0 {
        return Ok(()); // no properties: nothing to read
    }
    check_count(e, min, r.left(), V::SLACK, r.place(r.mark()).0)?;
    let name = text(&e.name);
    let ended = |r: &V, mark: usize, i: u64| {
        let (line, at) = r.place(mark);
        Fail {
            line,
            message: format!(
                "the file ends inside `{name}` element {i}{at}: the header (line {}) says there are {}; the file is \
                 cut or its header is wrong: export it again",
                e.line, e.count
            ),
        }
    };
    // count * min <= bytes left (checked above), so these reservations are bounded by the file's size.
    match role {
        Role::Vertex(_) => mesh.positions.reserve(usize::try_from(e.count).unwrap_or(0)),
        Role::Face(_) => mesh.faces.reserve(usize::try_from(e.count).unwrap_or(0)),
        Role::Skip => {}
    }
    let all_scalar = e.properties.iter().all(|p| matches!(p, Property::Scalar { .. }));
    if V::FIXED && all_scalar && matches!(role, Role::Skip) {
        // Rows of fixed size: skip them at once (the count was checked against the bytes left).
        let start = r.mark();
        return if r.skip(Scalar::U8, e.count.saturating_mul(min)) { Ok(()) } else { Err(ended(r, start, 0)) };
    }
    let mut corners: Vec<u32> = Vec::new();
    for i in 0..e.count {
        let mut xyz = [0.0f64; 3];
        for (k, p) in e.properties.iter().enumerate() {
            let mark = r.mark();
            match p {
                Property::Scalar { ty, name: pname } => match role {
                    Role::Vertex(axes) if axes.contains(&k) => {
                        let x = match r.number(*ty) {
                            Ok(x) => x,
                            Err(Bad::End) => return Err(ended(r, mark, i)),
                            Err(Bad::Text(t)) => {
                                return fail(
                                    r.place(r.mark()).0,
                                    format!(
                                        "`{t}` is not a valid `{}` value for property `{}` of vertex {i}; write \
                                         decimal numbers such as `1.5` or `-2e-3`",
                                        ty_name(*ty),
                                        text(pname)
                                    ),
                                )
                            }
                        };
                        if !x.is_finite() {
                            let (line, at) = r.place(r.mark());
                            return fail(
                                line,
                                format!(
                                    "vertex {i}{at}: its `{}` is {x}, not a finite number; the exporting tool wrote an \
                                     invalid vertex: fix it there and export again",
                                    text(pname)
                                ),
                            );
                        }
                        for (slot, &axis) in xyz.iter_mut().zip(axes) {
                            if axis == k {
                                *slot = x;
                            }
                        }
                    }
                    _ => {
                        if !r.skip(*ty, 1) {
                            return Err(ended(r, mark, i));
                        }
                    }
                },
                Property::List { count, item, name: pname } => {
                    let n = match r.number(*count) {
                        Ok(x) => whole(x).filter(|n| *n >= 0).ok_or_else(|| x.to_string()),
                        Err(Bad::End) => return Err(ended(r, mark, i)),
                        Err(Bad::Text(t)) => Err(t),
                    };
                    let n = match n {
                        Ok(n) => n as u64,
                        Err(shown) => {
                            let (line, at) = r.place(r.mark());
                            return fail(
                                line,
                                format!(
                                    "`{shown}` is not a valid length for list `{}` of `{name}` element {i}{at}; it \
                                     must be a whole number >= 0: the file is damaged, export it again",
                                    text(pname)
                                ),
                            );
                        }
                    };
                    if n.saturating_mul(V::value_bytes(*item)) > (r.left() + V::SLACK) as u64 {
                        return Err(ended(r, mark, i));
                    }
                    if !matches!(role, Role::Face(l) if *l == k) {
                        if !r.skip(*item, n) {
                            return Err(ended(r, mark, i));
                        }
                        continue;
                    }
                    corners.clear();
                    for _ in 0..n {
                        let at_index = r.mark();
                        let v = match r.number(*item) {
                            Ok(x) => whole(x).ok_or_else(|| x.to_string()),
                            Err(Bad::End) => return Err(ended(r, at_index, i)),
                            Err(Bad::Text(t)) => Err(t),
                        };
                        // where the index is (line, or " (at byte N)") is formatted only for an error: one String per
                        // corner took most of a binary file's reading time
                        let v = v.map_err(|shown| {
                            let (line, at) = r.place(r.mark());
                            Fail {
                                line,
                                message: format!(
                                    "`{shown}` is not a valid vertex index in face {i}{at}; indices are whole numbers \
                                     counted from 0"
                                ),
                            }
                        })?;
                        let v = u32::try_from(v).map_err(|_| {
                            let (line, at) = r.place(r.mark());
                            Fail {
                                line,
                                message: format!(
                                    "face {i}{at} refers to vertex {v}, which is {}; the file is damaged: export it \
                                     again",
                                    if v < 0 { "negative" } else { "beyond 4294967295" }
                                ),
                            }
                        })?;
                        corners.push(v);
                    }
                    if n < 3 {
                        return fail(r.place(r.mark()).0, too_few_corners(i, n));
                    }
                    push_fan(mesh, face_of_triangle, &corners, i);
                }
            }
        }
        if let Role::Vertex(_) = role {
            mesh.positions.push(xyz);
        }
    }
    Ok(())
}

fn ty_name(t: Scalar) -> &'static str {
    match t {
        Scalar::I8 => "char",
        Scalar::U8 => "uchar",
        Scalar::I16 => "short",
        Scalar::U16 => "ushort",
        Scalar::I32 => "int",
        Scalar::U32 => "uint",
        Scalar::F32 => "float",
        Scalar::F64 => "double",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 5\nproperty float x\n\
        property float y\nproperty float z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\n\
        property float quality\nend_header\n0 0 0 255\n1 0 0 0\n1 1 0 0\n0 1 0 0\n0.5 0.5 1e0 7\n4 0 1 2 3 0.5\n3 0 1 4 1\n";

    fn ok(bytes: &[u8]) -> Mesh {
        parse_ply("t.ply", bytes).unwrap_or_else(|e| panic!("expected to load: {e}"))
    }

    fn err(bytes: &[u8]) -> String {
        match parse_ply("t.ply", bytes) {
            Ok(m) => panic!("expected an error, loaded {} vertices", m.positions.len()),
            Err(e) => {
                let s = e.to_string();
                assert!(s.starts_with("file t.ply"), "{s}");
                s
            }
        }
    }

    /// The same mesh as `ASCII`, written in binary with the given byte order.
    fn binary(big: bool) -> Vec<u8> {
        let fmt = if big { "binary_big_endian" } else { "binary_little_endian" };
        let mut b = format!(
            "ply\r\nformat {fmt} 1.0\r\nelement vertex 5\r\nproperty double x\r\nproperty float y\r\nproperty short z\r\n\
             property list uchar float texcoord\r\nelement edge 1\r\nproperty int a\r\nproperty int b\r\n\
             element face 2\r\nproperty list uchar uint vertex_index\r\nend_header\r\n"
        )
        .into_bytes();
        let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.5, 0.5, 1.0]];
        for p in pts {
            let (x, y, z) = (p[0] as f64, p[1] as f32, p[2] as i16);
            if big {
                b.extend(x.to_be_bytes());
                b.extend(y.to_be_bytes());
                b.extend(z.to_be_bytes());
                b.push(2);
                b.extend(0.25f32.to_be_bytes());
                b.extend(0.75f32.to_be_bytes());
            } else {
                b.extend(x.to_le_bytes());
                b.extend(y.to_le_bytes());
                b.extend(z.to_le_bytes());
                b.push(2);
                b.extend(0.25f32.to_le_bytes());
                b.extend(0.75f32.to_le_bytes());
            }
        }
        b.extend([0u8; 8]); // the edge
        for f in [&[0u32, 1, 2, 3][..], &[0, 1, 4]] {
            b.push(f.len() as u8);
            for &i in f {
                b.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
            }
        }
        b
    }

    #[test]
    fn ascii_and_binary_give_the_same_mesh() {
        let a = ok(ASCII.as_bytes());
        assert_eq!(a.positions.len(), 5);
        assert_eq!(a.positions[4], [0.5, 0.5, 1.0]);
        assert_eq!(a.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
        assert_eq!(ok(&binary(false)), a);
        assert_eq!(ok(&binary(true)), a);
    }

    #[test]
    fn counts_are_checked_before_allocating() {
        let mut b = binary(false);
        let at = b.windows(8).position(|w| w == b"vertex 5").unwrap();
        b.splice(at..at + 8, b"vertex 4000000000".iter().copied());
        let m = err(&b);
        assert!(m.contains("4000000000 `vertex` elements") && m.contains("room for at most"), "{m}");
        let text = ASCII.replace("element face 2", "element face 99999999999");
        let m = err(text.as_bytes());
        assert!(m.contains("99999999999 `face` elements"), "{m}");
        // A cut binary file names the element and byte.
        let b = binary(true);
        let m = err(&b[..b.len() - 3]);
        assert!(m.contains("`face` element 1") && m.contains("cut"), "{m}");
    }

    #[test]
    fn errors_name_the_line_and_say_what_to_do() {
        let m = err(ASCII.replace("0.5 0.5 1e0 7", "0.5 zz 1 7").as_bytes());
        assert!(
            m.contains("line 17") && m.contains("`zz` is not a valid `float` value") && m.contains("vertex 4"),
            "{m}"
        );
        let m = err(ASCII.replace("3 0 1 4 1", "3 0 1 9 1").as_bytes());
        assert!(m.contains("face 1 refers to vertex 9") && m.contains("5 vertices"), "{m}");
        let m = err(ASCII.replace("3 0 1 4 1", "2 0 1 1").as_bytes());
        assert!(m.contains("line 19") && m.contains("face 1 has 2 vertices"), "{m}");
        let m = err(ASCII.replace("3 0 1 4 1", "3 0 -1 4 1").as_bytes());
        assert!(m.contains("negative"), "{m}");
        let m = err(ASCII.replace("format ascii", "format ebcdic").as_bytes());
        assert!(m.contains("line 2") && m.contains("unknown format `ebcdic`"), "{m}");
        let m = err(ASCII.replace("property float z\n", "").as_bytes());
        assert!(m.contains("line 4") && m.contains("`x`, `y` and `z`"), "{m}");
        let m = err(ASCII.replace("vertex_indices", "corners").as_bytes());
        assert!(m.contains("vertex_indices"), "{m}");
        let m = err(&ASCII.as_bytes()[..ASCII.len() - 6]);
        assert!(m.contains("ends inside `face` element 1"), "{m}");
        let m = err(ASCII.replace("end_header\n", "").as_bytes());
        assert!(m.contains("end_header") || m.contains("unknown header line"), "{m}");
        let m = err(b"solid cube\nfacet normal 0 0 1\n");
        assert!(m.contains("not a PLY file"), "{m}");
        let m = err(ASCII.replace("1 1 0 0\n", "1 nan 0 0\n").as_bytes());
        assert!(m.contains("not a finite number"), "{m}");
    }

    /// Random mutations never panic and every error names the file.
    #[test]
    fn never_panics_on_mutated_input() {
        let seeds = [ASCII.as_bytes().to_vec(), binary(false), binary(true)];
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (mut loaded, mut rejected) = (0, 0);
        for round in 0..6000 {
            let mut bytes = seeds[round % 3].clone();
            for _ in 0..(1 + next() % 4) {
                let at = (next() % bytes.len() as u64) as usize;
                match next() % 4 {
                    0 => bytes[at] = next() as u8,
                    1 => bytes[at] = b"0123456789 \n-.e"[(next() % 15) as usize],
                    2 => {
                        bytes.truncate(at.max(1));
                    }
                    _ => bytes.insert(at, next() as u8),
                }
            }
            match parse_ply("fuzz.ply", &bytes) {
                Ok(m) => {
                    loaded += 1;
                    assert!(m.faces.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
                }
                Err(e) => {
                    rejected += 1;
                    assert!(e.to_string().starts_with("file fuzz.ply"), "{e}");
                }
            }
        }
        assert!(loaded > 100 && rejected > 100, "{loaded} loaded, {rejected} rejected");
    }

    /// ASCII lengths and indices may be written as floats with no fraction or with a sign; anything else is
    /// refused with the token shown.
    #[test]
    fn ascii_whole_numbers() {
        let m = ok(ASCII.replace("3 0 1 4 1", "3.0 +0 1e0 4.000 1").as_bytes());
        assert_eq!(m.faces.last(), Some(&[0, 1, 4]));
        let m = err(ASCII.replace("3 0 1 4 1", "3 0 1.5 4 1").as_bytes());
        assert!(m.contains("line 19") && m.contains("`1.5` is not a valid vertex index in face 1"), "{m}");
        let m = err(ASCII.replace("3 0 1 4 1", "0x3 0 1 4 1").as_bytes());
        assert!(m.contains("`0x3` is not a valid length for list `vertex_indices` of `face` element 1"), "{m}");
        let m = err(ASCII.replace("3 0 1 4 1", "-3 0 1 4 1").as_bytes());
        assert!(m.contains("`-3` is not a valid length"), "{m}");
    }
}
