//! The node tree of a binary FBX 7.x file (the low-level part of [`super::fbx`]).
//!
//! Layout (FBX 7.0-7.7, little endian): a 27-byte header (`Kaydara FBX Binary  \0`, 0x1A 0x00, the version as
//! u32), then node records. A record is: end offset, property count, property list length (u32 each, u64 from
//! version 7500 on), a name length (u8) and the name, the properties, then the nested records closed by a null
//! record. A property is a type code and a value: `Y` i16, `C` bool, `I` i32, `F` f32, `D` f64, `L` i64,
//! `S` string and `R` raw bytes (u32 length first), and arrays `f d l i b` (u32 element count, u32 encoding,
//! u32 byte length; encoding 1 is zlib).
//!
//! Every length, count and offset is checked against the bytes present, in 64-bit arithmetic, before anything
//! is allocated; a compressed array may not claim more than deflate can produce from its bytes, must inflate
//! to exactly the size it declares (inflating stops at that size), and all arrays together must fit the memory
//! budget. Nesting deeper than [`MAX_DEPTH`] is refused (no recursion on the stack beyond that).

use crate::error::{Error, Result};

/// FBX files nest a handful of levels (Objects > Geometry > LayerElementNormal > Normals); more is damage.
pub const MAX_DEPTH: usize = 64;
/// The most deflate can expand: 1032 output bytes per input byte, plus slack for headers.
const MAX_INFLATE_RATIO: u64 = 1032;
const MAGIC: &[u8] = b"Kaydara FBX Binary  \0";

/// One property of a node.
#[derive(Debug, Clone, PartialEq)]
pub enum Prop {
    Int(i64),
    Float(f64),
    Bool(bool),
    Str(String),
    /// Raw bytes are not used by the reader: only their length is kept.
    Raw(usize),
    F32s(Vec<f32>),
    F64s(Vec<f64>),
    I32s(Vec<i32>),
    I64s(Vec<i64>),
    Bools(Vec<bool>),
}

impl Prop {
    pub fn as_i64(&self) -> Option<i64> {
        match self {
            Prop::Int(v) => Some(*v),
            Prop::Float(v) if v.fract() == 0.0 && v.abs() < 9.0e18 => Some(*v as i64),
            Prop::Bool(b) => Some(*b as i64),
            _ => None,
        }
    }
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Prop::Int(v) => Some(*v as f64),
            Prop::Float(v) => Some(*v),
            Prop::Bool(b) => Some(f64::from(u8::from(*b))),
            _ => None,
        }
    }
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Prop::Str(s) => Some(s),
            _ => None,
        }
    }
    /// A numeric array as f64 (any element type).
    pub fn to_f64s(&self) -> Option<Vec<f64>> {
        Some(match self {
            Prop::F32s(v) => v.iter().map(|&x| f64::from(x)).collect(),
            Prop::F64s(v) => v.clone(),
            Prop::I32s(v) => v.iter().map(|&x| f64::from(x)).collect(),
            Prop::I64s(v) => v.iter().map(|&x| x as f64).collect(),
            _ => return None,
        })
    }
    /// An integer array as i64 (i32 or i64 elements).
    pub fn to_i64s(&self) -> Option<Vec<i64>> {
        Some(match self {
            Prop::I32s(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Prop::I64s(v) => v.clone(),
            _ => return None,
        })
    }
}

/// A node: its name, properties and children, and where its record starts (for messages).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Node {
    pub name: String,
    pub props: Vec<Prop>,
    pub children: Vec<Node>,
    pub offset: u64,
}

impl Node {
    pub fn child(&self, name: &str) -> Option<&Node> {
        self.children.iter().find(|c| c.name == name)
    }
    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Node> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
    /// The first property of the child `name`.
    pub fn child_prop(&self, name: &str) -> Option<&Prop> {
        self.child(name).and_then(|c| c.props.first())
    }
}

/// The parsed file: its version (7400 = FBX 7.4) and top-level nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct Tree {
    pub version: u32,
    pub nodes: Vec<Node>,
}

impl Tree {
    pub fn node(&self, name: &str) -> Option<&Node> {
        self.nodes.iter().find(|n| n.name == name)
    }
}

fn err(file: &str, message: String) -> Error {
    Error::Obj { file: file.to_string(), line: 0, message }
}

/// Whether the bytes look like an ASCII FBX file (a `; FBX` comment header or an `FBXHeaderExtension:` node).
pub fn is_ascii_fbx(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(4096)];
    let text = String::from_utf8_lossy(head);
    let t = text.trim_start_matches('\u{feff}').trim_start();
    t.starts_with("; FBX") || t.contains("FBXHeaderExtension:")
}

struct Reader<'a> {
    file: &'a str,
    bytes: &'a [u8],
    wide: bool,
    /// Bytes still allowed for decoded arrays.
    budget: u64,
    /// Names of nodes whose arrays are not decoded (kept as [`Prop::Raw`] of their stored length).
    skip: &'a [&'a str],
}

impl<'a> Reader<'a> {
    fn cut(&self, what: &str, at: u64) -> Error {
        err(
            self.file,
            format!(
                "{what} at byte {at} runs past the end of the file ({} bytes); the file is cut or damaged: export it again",
                self.bytes.len()
            ),
        )
    }

    fn slice(&self, at: u64, len: u64, what: &str) -> Result<&'a [u8]> {
        let end = at.checked_add(len).filter(|&e| e <= self.bytes.len() as u64).ok_or_else(|| self.cut(what, at))?;
        Ok(&self.bytes[at as usize..end as usize])
    }

    fn u32_at(&self, at: u64, what: &str) -> Result<u32> {
        let s = self.slice(at, 4, what)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }

    fn u64_at(&self, at: u64, what: &str) -> Result<u64> {
        let s = self.slice(at, 8, what)?;
        let mut b = [0u8; 8];
        b.copy_from_slice(s);
        Ok(u64::from_le_bytes(b))
    }

    /// The records from `at` until a null record (or `end`); returns them and the offset after the null record.
    fn records(&mut self, mut at: u64, end: u64, depth: usize, parent: &str) -> Result<(Vec<Node>, u64)> {
        if depth > MAX_DEPTH {
            return Err(err(
                self.file,
                format!("nodes nest deeper than {MAX_DEPTH} levels under node '{parent}' at byte {at}; the file is damaged: export it again"),
            ));
        }
        let header = if self.wide { 25 } else { 13 };
        let mut nodes = Vec::new();
        while at < end {
            let (node_end, n_props, props_len, name_len) = if self.wide {
                (self.u64_at(at, "a node record")?, self.u64_at(at + 8, "a node record")?, self.u64_at(at + 16, "a node record")?, self.slice(at + 24, 1, "a node record")?[0])
            } else {
                (
                    u64::from(self.u32_at(at, "a node record")?),
                    u64::from(self.u32_at(at + 4, "a node record")?),
                    u64::from(self.u32_at(at + 8, "a node record")?),
                    self.slice(at + 12, 1, "a node record")?[0],
                )
            };
            if node_end == 0 {
                // A null record closes the list.
                return Ok((nodes, at + header));
            }
            let name_bytes = self.slice(at + header, u64::from(name_len), "a node name")?;
            let name = String::from_utf8_lossy(name_bytes).into_owned();
            let props_at = at + header + u64::from(name_len);
            let children_at = props_at.checked_add(props_len).ok_or_else(|| self.cut("a property list", props_at))?;
            if node_end > end {
                let outer = if depth == 0 { "the file".to_string() } else { format!("its parent '{parent}'") };
                return Err(err(
                    self.file,
                    format!(
                        "node '{name}' at byte {at} says it ends at byte {node_end}, past the end of {outer} (byte {end}); \
                         the file is cut or damaged: export it again"
                    ),
                ));
            }
            if node_end < children_at {
                return Err(err(
                    self.file,
                    format!(
                        "node '{name}' at byte {at} says it ends at byte {node_end}, before its own properties end (byte \
                         {children_at}); the file is damaged: export it again"
                    ),
                ));
            }
            // Every property takes at least 2 bytes: a count above that is damage (and would allocate).
            if n_props > props_len / 2 + 1 {
                return Err(err(
                    self.file,
                    format!("node '{name}' at byte {at} claims {n_props} properties in {props_len} bytes; the file is damaged: export it again"),
                ));
            }
            let mut props = Vec::with_capacity(n_props as usize);
            let mut p = props_at;
            for k in 0..n_props {
                let (prop, next) = self.prop(p, children_at, &name, k)?;
                props.push(prop);
                p = next;
            }
            let children = if children_at < node_end {
                let (children, after) = self.records(children_at, node_end, depth + 1, &name)?;
                if after > node_end {
                    return Err(self.cut(&format!("the children of node '{name}'"), children_at));
                }
                children
            } else {
                Vec::new()
            };
            nodes.push(Node { name, props, children, offset: at });
            at = node_end;
        }
        Ok((nodes, at))
    }

    fn prop(&mut self, at: u64, end: u64, node: &str, k: u64) -> Result<(Prop, u64)> {
        let what = format!("property {k} of node '{node}'");
        let code = *self.slice(at, 1, &what)?.first().unwrap_or(&0);
        let v = at + 1;
        let fixed = |r: &Self, n: u64| -> Result<&'a [u8]> {
            if v + n > end {
                return Err(r.cut(&what, at));
            }
            r.slice(v, n, &what)
        };
        let prop = match code {
            b'Y' => {
                let s = fixed(self, 2)?;
                (Prop::Int(i64::from(i16::from_le_bytes([s[0], s[1]]))), v + 2)
            }
            b'C' => (Prop::Bool(fixed(self, 1)?[0] != 0), v + 1),
            b'I' => {
                let s = fixed(self, 4)?;
                (Prop::Int(i64::from(i32::from_le_bytes([s[0], s[1], s[2], s[3]]))), v + 4)
            }
            b'F' => {
                let s = fixed(self, 4)?;
                (Prop::Float(f64::from(f32::from_le_bytes([s[0], s[1], s[2], s[3]]))), v + 4)
            }
            b'D' | b'L' => {
                let s = fixed(self, 8)?;
                let mut b = [0u8; 8];
                b.copy_from_slice(s);
                let p = if code == b'D' { Prop::Float(f64::from_le_bytes(b)) } else { Prop::Int(i64::from_le_bytes(b)) };
                (p, v + 8)
            }
            b'S' | b'R' => {
                let len = u64::from(self.u32_at(v, &what)?);
                if v + 4 + len > end {
                    return Err(self.cut(&format!("{what} ({len} bytes)"), at));
                }
                let s = self.slice(v + 4, len, &what)?;
                let p = if code == b'S' { Prop::Str(String::from_utf8_lossy(s).into_owned()) } else { Prop::Raw(s.len()) };
                (p, v + 4 + len)
            }
            b'f' | b'd' | b'l' | b'i' | b'b' if self.skip.contains(&node) => {
                let stored = u64::from(self.u32_at(v + 8, &what)?);
                if v + 12 + stored > end {
                    return Err(self.cut(&format!("{what} ({stored} bytes of array data)"), at));
                }
                (Prop::Raw(stored as usize), v + 12 + stored)
            }
            b'f' | b'd' | b'l' | b'i' | b'b' => self.array(code, at, end, &what)?,
            other => {
                return Err(err(
                    self.file,
                    format!(
                        "{what} at byte {at} has the unknown type code 0x{other:02x}; the file is damaged or not a binary \
                         FBX 7.x file: export it again"
                    ),
                ))
            }
        };
        Ok(prop)
    }

    fn array(&mut self, code: u8, at: u64, end: u64, what: &str) -> Result<(Prop, u64)> {
        let v = at + 1;
        let count = u64::from(self.u32_at(v, what)?);
        let encoding = self.u32_at(v + 4, what)?;
        let stored = u64::from(self.u32_at(v + 8, what)?);
        let data_at = v + 12;
        if data_at + stored > end {
            return Err(self.cut(&format!("{what} ({stored} bytes of array data)"), at));
        }
        let data = self.slice(data_at, stored, what)?;
        let size: u64 = match code {
            b'd' | b'l' => 8,
            b'f' | b'i' => 4,
            _ => 1,
        };
        let bytes_needed = count * size; // at most 2^32 * 8: no overflow in u64
        if bytes_needed > self.budget {
            return Err(err(
                self.file,
                format!(
                    "{what} at byte {at} asks for {count} elements ({bytes_needed} bytes), more than the memory budget \
                     left for this file ({} bytes); the file is damaged, or too large for this build: raise \
                     POSEMFA_MEMORY_BUDGET (natively) or export fewer objects",
                    self.budget
                ),
            ));
        }
        let raw: std::borrow::Cow<'a, [u8]> = match encoding {
            0 => {
                if stored != bytes_needed {
                    return Err(err(
                        self.file,
                        format!(
                            "{what} at byte {at} declares {count} elements ({bytes_needed} bytes) but stores {stored} \
                             bytes; the file is damaged: export it again"
                        ),
                    ));
                }
                std::borrow::Cow::Borrowed(data)
            }
            1 => {
                if bytes_needed > stored.saturating_mul(MAX_INFLATE_RATIO) + 64 {
                    return Err(err(
                        self.file,
                        format!(
                            "{what} at byte {at} declares {count} elements ({bytes_needed} bytes) from {stored} compressed \
                             bytes, more than zlib can hold; the file is damaged: export it again"
                        ),
                    ));
                }
                // Inflated into a buffer of exactly the declared size (bounded above): no regrowth, and a
                // stream that goes on past it stops there.
                let mut out = vec![0u8; bytes_needed as usize];
                let n = miniz_oxide::inflate::decompress_slice_iter_to_slice(&mut out, std::iter::once(data), true, false)
                    .map_err(|status| {
                        let why = match status {
                            miniz_oxide::inflate::TINFLStatus::HasMoreOutput => {
                                format!("inflates past the {bytes_needed} bytes it declares")
                            }
                            _ => format!("is not valid zlib data ({status:?})"),
                        };
                        err(self.file, format!("{what} at byte {at} {why}; the file is damaged: export it again"))
                    })?;
                out.truncate(n);
                if out.len() as u64 != bytes_needed {
                    return Err(err(
                        self.file,
                        format!(
                            "{what} at byte {at} inflates to {} bytes but declares {count} elements ({bytes_needed} bytes); \
                             the file is damaged: export it again",
                            out.len()
                        ),
                    ));
                }
                std::borrow::Cow::Owned(out)
            }
            e => {
                return Err(err(
                    self.file,
                    format!("{what} at byte {at} has the unknown array encoding {e} (0: plain, 1: zlib); the file is damaged: export it again"),
                ))
            }
        };
        self.budget -= bytes_needed;
        let r = &raw[..];
        let prop = match code {
            b'd' => Prop::F64s(r.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect()),
            b'l' => Prop::I64s(r.chunks_exact(8).map(|c| i64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect()),
            b'f' => Prop::F32s(r.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap_or([0; 4]))).collect()),
            b'i' => Prop::I32s(r.chunks_exact(4).map(|c| i32::from_le_bytes(c.try_into().unwrap_or([0; 4]))).collect()),
            _ => Prop::Bools(r.iter().map(|&b| b != 0).collect()),
        };
        Ok((prop, data_at + stored))
    }
}

/// Parses a binary FBX file into its node tree. `budget` bounds the bytes of all decoded arrays.
pub fn parse(file: &str, bytes: &[u8], budget: u64) -> Result<Tree> {
    parse_skipping(file, bytes, budget, &[])
}

/// [`parse`], leaving the arrays of the nodes named in `skip` undecoded ([`Prop::Raw`] of their stored
/// length; their bounds are still checked): a reader that needs no normals or UVs does not inflate them.
pub fn parse_skipping(file: &str, bytes: &[u8], budget: u64, skip: &[&str]) -> Result<Tree> {
    if !bytes.starts_with(MAGIC) {
        if is_ascii_fbx(bytes) {
            return Err(err(
                file,
                "is an ASCII FBX file; posemfa reads binary FBX 7.x: export it again as binary FBX (Blender always \
                 writes binary; in Maya, 3ds Max and MotionBuilder choose File Format: Binary in the FBX export options)"
                    .into(),
            ));
        }
        return Err(err(
            file,
            "is not a binary FBX file (it does not start with \"Kaydara FBX Binary\"); the file is damaged or has the \
             wrong extension: export it again as binary FBX 7.x"
                .into(),
        ));
    }
    if bytes.len() < 27 {
        return Err(err(file, format!("the FBX header is cut ({} of 27 bytes); the file is cut: export it again", bytes.len())));
    }
    let version = u32::from_le_bytes([bytes[23], bytes[24], bytes[25], bytes[26]]);
    if !(7000..8000).contains(&version) {
        return Err(err(
            file,
            format!(
                "is FBX version {}.{} ({version}); posemfa reads binary FBX 7.x (7.0 to 7.7): export it again as FBX \
                 2011 or newer",
                version / 1000,
                version % 1000 / 100
            ),
        ));
    }
    let mut r = Reader { file, bytes, wide: version >= 7500, budget, skip };
    let (nodes, _) = r.records(27, bytes.len() as u64, 0, "(top level)")?;
    Ok(Tree { version, nodes })
}

/// Writes a binary FBX 7.4 node tree (plain arrays, or zlib arrays when `compress`): for tests and fuzz seeds.
pub fn write(nodes: &[Node], compress: bool) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[0x1A, 0x00]);
    out.extend_from_slice(&7400u32.to_le_bytes());
    for n in nodes {
        write_node(&mut out, n, compress);
    }
    out.extend_from_slice(&[0u8; 13]);
    out.extend_from_slice(&[0u8; 160]); // footer (not read)
    out
}

fn write_node(out: &mut Vec<u8>, n: &Node, compress: bool) {
    let start = out.len();
    out.extend_from_slice(&[0u8; 12]);
    out.push(n.name.len() as u8);
    out.extend_from_slice(n.name.as_bytes());
    let props_start = out.len();
    for p in &n.props {
        write_prop(out, p, compress);
    }
    let props_len = (out.len() - props_start) as u32;
    for c in &n.children {
        write_node(out, c, compress);
    }
    if !n.children.is_empty() {
        out.extend_from_slice(&[0u8; 13]);
    }
    let end = out.len() as u32;
    out[start..start + 4].copy_from_slice(&end.to_le_bytes());
    out[start + 4..start + 8].copy_from_slice(&(n.props.len() as u32).to_le_bytes());
    out[start + 8..start + 12].copy_from_slice(&props_len.to_le_bytes());
}

fn write_prop(out: &mut Vec<u8>, p: &Prop, compress: bool) {
    let array = |out: &mut Vec<u8>, code: u8, count: usize, raw: Vec<u8>| {
        out.push(code);
        out.extend_from_slice(&(count as u32).to_le_bytes());
        let data = if compress { miniz_oxide::deflate::compress_to_vec_zlib(&raw, 6) } else { raw };
        out.extend_from_slice(&u32::from(compress).to_le_bytes());
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(&data);
    };
    match p {
        Prop::Int(v) => {
            out.push(b'L');
            out.extend_from_slice(&v.to_le_bytes());
        }
        Prop::Float(v) => {
            out.push(b'D');
            out.extend_from_slice(&v.to_le_bytes());
        }
        Prop::Bool(b) => {
            out.push(b'C');
            out.push(u8::from(*b));
        }
        Prop::Str(s) => {
            out.push(b'S');
            out.extend_from_slice(&(s.len() as u32).to_le_bytes());
            out.extend_from_slice(s.as_bytes());
        }
        Prop::Raw(n) => {
            out.push(b'R');
            out.extend_from_slice(&(*n as u32).to_le_bytes());
            out.extend(std::iter::repeat(0u8).take(*n));
        }
        Prop::F32s(v) => array(out, b'f', v.len(), v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Prop::F64s(v) => array(out, b'd', v.len(), v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Prop::I32s(v) => array(out, b'i', v.len(), v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Prop::I64s(v) => array(out, b'l', v.len(), v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Prop::Bools(v) => array(out, b'b', v.len(), v.iter().map(|&b| u8::from(b)).collect()),
    }
}
