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
    parse(bytes).map_err(|f| Error::Obj { file: name.to_string(), line: f.line, message: f.message })
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
                let count = std::str::from_utf8(count).ok().and_then(|c| c.parse::<u64>().ok()).ok_or_else(|| Fail {
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
                let property = match words.as_slice() {
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
                                format!("the count type of list `{}` is a float; it must be an integer type", text(name)),
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
                    _ => {
                        return fail(
                            line,
                            "a `property` line is `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME`",
                        )
                    }
                };
                element.properties.push(property);
            }
            b"end_header" => {
                let Some(format) = format else {
                    return fail(line, "the header has no `format` line; export the file again");
                };
                return Ok(Header { format, elements, data_start: pos, data_line: line + 1 });
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
                read_ascii_element(&mut r, e, role, &mut mesh, &mut face_of_triangle)?;
            }
        }
        Format::Little | Format::Big => {
            let mut r = Binary { data, pos: 0, big: h.format == Format::Big, offset: h.data_start };
            for (e, role) in h.elements.iter().zip(&roles) {
                read_binary_element(&mut r, e, role, &mut mesh, &mut face_of_triangle)?;
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

/// Refuses a count that cannot fit in the bytes left: every element takes at least `min_bytes`.
fn check_count(e: &Element, min_bytes: u64, left: usize, line: usize) -> Res<()> {
    if min_bytes == 0 {
        return Ok(());
    }
    let fits = left as u64 / min_bytes;
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

// ---------------------------------------------------------------------------------------------- binary

struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big: bool,
    /// Offset of `data` in the file (for messages).
    offset: usize,
}

impl Binary<'_> {
    fn left(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let s = self.data.get(self.pos..self.pos.checked_add(N)?)?;
        let a: [u8; N] = s.try_into().ok()?;
        self.pos += N;
        Some(a)
    }

    fn skip(&mut self, n: u64) -> Option<()> {
        let n = usize::try_from(n).ok()?;
        let end = self.pos.checked_add(n)?;
        if end > self.data.len() {
            return None;
        }
        self.pos = end;
        Some(())
    }

    fn float(&mut self, ty: Scalar) -> Option<f64> {
        let big = self.big;
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let b = self.take::<$n>()?;
                (if big { <$t>::from_be_bytes(b) } else { <$t>::from_le_bytes(b) }) as f64
            }};
        }
        Some(match ty {
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

    /// An integer property; `Err(value)` when a float type holds a value that is not a whole number.
    fn int(&mut self, ty: Scalar) -> Option<std::result::Result<i64, f64>> {
        let x = self.float(ty)?;
        if ty.is_float() && (x.fract() != 0.0 || !x.is_finite() || x.abs() > 9.0e15) {
            return Some(Err(x));
        }
        Some(Ok(x as i64))
    }
}

fn read_binary_element(
    r: &mut Binary,
    e: &Element,
    role: &Role,
    mesh: &mut Mesh,
    face_of_triangle: &mut Vec<u64>,
) -> Res<()> {
    let min: u64 = e
        .properties
        .iter()
        .map(|p| match p {
            Property::Scalar { ty, .. } => ty.size() as u64,
            Property::List { count, .. } => count.size() as u64,
        })
        .sum();
    check_count(e, min, r.left(), 0)?;
    if min == 0 {
        return Ok(()); // no properties: nothing to read
    }
    let name = text(&e.name);
    let cut = |r: &Binary, i: u64| Fail {
        line: 0,
        message: format!(
            "`{name}` element {i} (at byte {}) is cut: the file ends inside it; the file is cut or its header is \
             wrong: export it again",
            r.offset + r.pos
        ),
    };
    let mut corners: Vec<u32> = Vec::new();
    match role {
        Role::Vertex(_) => {
            // count * min <= bytes left (checked above), so this reservation is bounded by the file's size.
            mesh.positions.reserve(usize::try_from(e.count).unwrap_or(0));
        }
        Role::Face(_) => mesh.faces.reserve(usize::try_from(e.count).unwrap_or(0)),
        Role::Skip => {}
    }
    let all_scalar = e.properties.iter().all(|p| matches!(p, Property::Scalar { .. }));
    if let (Role::Skip, true) = (role, all_scalar) {
        // Fixed-size rows: skip them at once (the count was checked against the bytes left).
        return r.skip(e.count.saturating_mul(min)).ok_or_else(|| cut(r, 0));
    }
    for i in 0..e.count {
        let mut xyz = [0.0f64; 3];
        for (k, p) in e.properties.iter().enumerate() {
            match p {
                Property::Scalar { ty, .. } => match role {
                    Role::Vertex(axes) if axes.contains(&k) => {
                        let x = r.float(*ty).ok_or_else(|| cut(r, i))?;
                        for (slot, &axis) in xyz.iter_mut().zip(axes) {
                            if axis == k {
                                *slot = x;
                            }
                        }
                    }
                    _ => r.skip(ty.size() as u64).ok_or_else(|| cut(r, i))?,
                },
                Property::List { count, item, name: pname } => {
                    let at = r.offset + r.pos;
                    let n = match r.int(*count).ok_or_else(|| cut(r, i))? {
                        Ok(n) if n >= 0 => n as u64,
                        Ok(n) => {
                            return fail(
                                0,
                                format!(
                                    "`{name}` element {i} (at byte {at}): list `{}` has a negative length {n}; the \
                                     file is damaged: export it again",
                                    text(pname)
                                ),
                            )
                        }
                        Err(x) => return fail(0, format!("`{name}` element {i}: list length {x} is not a whole number")),
                    };
                    if matches!(role, Role::Face(l) if *l == k) {
                        if n.saturating_mul(item.size() as u64) > r.left() as u64 {
                            return Err(cut(r, i));
                        }
                        corners.clear();
                        for _ in 0..n {
                            let at = r.offset + r.pos;
                            let v = match r.int(*item).ok_or_else(|| cut(r, i))? {
                                Ok(v) => v,
                                Err(x) => {
                                    return fail(
                                        0,
                                        format!("face {i} (at byte {at}): vertex index {x} is not a whole number"),
                                    )
                                }
                            };
                            let v = u32::try_from(v).map_err(|_| Fail {
                                line: 0,
                                message: format!(
                                    "face {i} (at byte {at}) refers to vertex {v}, which is {}; the file is \
                                     damaged: export it again",
                                    if v < 0 { "negative" } else { "beyond 4294967295" }
                                ),
                            })?;
                            corners.push(v);
                        }
                        if n < 3 {
                            return fail(0, too_few_corners(i, n));
                        }
                        push_fan(mesh, face_of_triangle, &corners, i);
                    } else {
                        r.skip(n.saturating_mul(item.size() as u64)).ok_or_else(|| cut(r, i))?;
                    }
                }
            }
        }
        if let Role::Vertex(_) = role {
            if let Some(bad) = xyz.iter().position(|c| !c.is_finite()) {
                return fail(
                    0,
                    format!(
                        "vertex {i}: its {} coordinate is not a finite number; the exporting tool wrote an invalid \
                         vertex: fix it there and export again",
                        ["x", "y", "z"].get(bad).copied().unwrap_or("")
                    ),
                );
            }
            mesh.positions.push(xyz);
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------- ASCII

struct Ascii<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Ascii<'a> {
    /// The next whitespace-separated token and its line.
    fn token(&mut self) -> Option<(&'a [u8], usize)> {
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
        let start = self.pos;
        let rest = data.get(start..)?;
        if rest.is_empty() {
            return None;
        }
        let len = rest.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(rest.len());
        self.pos = start + len;
        Some((rest.get(..len)?, self.line))
    }
}

fn read_ascii_element(
    r: &mut Ascii,
    e: &Element,
    role: &Role,
    mesh: &mut Mesh,
    face_of_triangle: &mut Vec<u64>,
) -> Res<()> {
    if e.properties.is_empty() {
        return Ok(());
    }
    // Every property takes at least one character and one separator.
    check_count(e, 2 * e.properties.len() as u64 - 1, r.data.len().saturating_sub(r.pos) + 1, r.line)?;
    let name = text(&e.name);
    let ended = |line: usize, i: u64| Fail {
        line,
        message: format!(
            "the file ends inside `{name}` element {i}: the header (line {}) says there are {}; the file is cut or its \
             header is wrong: export it again",
            e.line, e.count
        ),
    };
    match role {
        Role::Vertex(_) => mesh.positions.reserve(usize::try_from(e.count).unwrap_or(0)),
        Role::Face(_) => mesh.faces.reserve(usize::try_from(e.count).unwrap_or(0)),
        Role::Skip => {}
    }
    let mut corners: Vec<u32> = Vec::new();
    for i in 0..e.count {
        let mut xyz = [0.0f64; 3];
        for (k, p) in e.properties.iter().enumerate() {
            match p {
                Property::Scalar { ty, name: pname } => {
                    let line = r.line;
                    let (tok, line) = r.token().ok_or_else(|| ended(line, i))?;
                    if let Role::Vertex(axes) = role {
                        if axes.contains(&k) {
                            let x = ascii_number(tok, *ty).ok_or_else(|| Fail {
                                line,
                                message: format!(
                                    "`{}` is not a valid `{}` value for property `{}` of vertex {i}; write decimal \
                                     numbers such as `1.5` or `-2e-3`",
                                    text(tok),
                                    ty_name(*ty),
                                    text(pname)
                                ),
                            })?;
                            if !x.is_finite() {
                                return fail(
                                    line,
                                    format!(
                                        "vertex {i}: `{}` is not a finite number; the exporting tool wrote an \
                                         invalid vertex: fix it there and export again",
                                        text(tok)
                                    ),
                                );
                            }
                            for (slot, &axis) in xyz.iter_mut().zip(axes) {
                                if axis == k {
                                    *slot = x;
                                }
                            }
                        }
                    }
                }
                Property::List { name: pname, .. } => {
                    let line = r.line;
                    let (tok, line) = r.token().ok_or_else(|| ended(line, i))?;
                    let n = ascii_int(tok).filter(|n| *n >= 0).ok_or_else(|| Fail {
                        line,
                        message: format!(
                            "`{}` is not a valid length for list `{}` of `{name}` element {i}; it must be a whole \
                             number >= 0",
                            text(tok),
                            text(pname)
                        ),
                    })? as u64;
                    let is_face = matches!(role, Role::Face(l) if *l == k);
                    if is_face {
                        corners.clear();
                    }
                    for _ in 0..n {
                        let before = r.line;
                        let (tok, line) = r.token().ok_or_else(|| ended(before, i))?;
                        if is_face {
                            let v = ascii_int(tok).ok_or_else(|| Fail {
                                line,
                                message: format!(
                                    "`{}` is not a valid vertex index in face {i}; indices are whole numbers \
                                     counted from 0",
                                    text(tok)
                                ),
                            })?;
                            let v = u32::try_from(v).map_err(|_| Fail {
                                line,
                                message: format!(
                                    "face {i} refers to vertex {v}, which is {}; the file is damaged: export it again",
                                    if v < 0 { "negative" } else { "beyond 4294967295" }
                                ),
                            })?;
                            corners.push(v);
                        }
                    }
                    if is_face {
                        if n < 3 {
                            return fail(line, too_few_corners(i, n));
                        }
                        push_fan(mesh, face_of_triangle, &corners, i);
                    }
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

fn ascii_number(tok: &[u8], _ty: Scalar) -> Option<f64> {
    fast_float2::parse::<f64, _>(tok).ok()
}

/// A whole number written as digits (optionally signed), or as a float with no fraction (`3.0`).
fn ascii_int(tok: &[u8]) -> Option<i64> {
    if let Some(v) = std::str::from_utf8(tok).ok().and_then(|t| t.parse::<i64>().ok()) {
        return Some(v);
    }
    let x = fast_float2::parse::<f64, _>(tok).ok()?;
    (x.is_finite() && x.fract() == 0.0 && x.abs() <= 9.0e15).then_some(x as i64)
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
        assert!(m.contains("line 17") && m.contains("`zz` is not a valid `float` value") && m.contains("vertex 4"), "{m}");
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
}
