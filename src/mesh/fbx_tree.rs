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
    Error::Mesh { format: crate::error::Format::Fbx, file: file.to_string(), line: 0, message }
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
    /// The zlib inflater, made at the first compressed array and reset for each next one.
    inflater: Option<zlib_rs::Inflate>,
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
                (
                    self.u64_at(at, "a node record")?,
                    self.u64_at(at + 8, "a node record")?,
                    self.u64_at(at + 16, "a node record")?,
                    self.slice(at + 24, 1, "a node record")?[0],
                )
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
                let p =
                    if code == b'D' { Prop::Float(f64::from_le_bytes(b)) } else { Prop::Int(i64::from_le_bytes(b)) };
                (p, v + 8)
            }
            b'S' | b'R' => {
                let len = u64::from(self.u32_at(v, &what)?);
                if v + 4 + len > end {
                    return Err(self.cut(&format!("{what} ({len} bytes)"), at));
                }
                let s = self.slice(v + 4, len, &what)?;
                let p =
                    if code == b'S' { Prop::Str(String::from_utf8_lossy(s).into_owned()) } else { Prop::Raw(s.len()) };
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
        if encoding > 1 {
            return Err(err(
                self.file,
                format!("{what} at byte {at} has the unknown array encoding {encoding} (0: plain, 1: zlib); the file is damaged: export it again"),
            ));
        }
        if encoding == 0 && stored != bytes_needed {
            return Err(err(
                self.file,
                format!(
                    "{what} at byte {at} declares {count} elements ({bytes_needed} bytes) but stores {stored} \
                     bytes; the file is damaged: export it again"
                ),
            ));
        }
        if encoding == 1 && bytes_needed > stored.saturating_mul(MAX_INFLATE_RATIO) + 64 {
            return Err(err(
                self.file,
                format!(
                    "{what} at byte {at} declares {count} elements ({bytes_needed} bytes) from {stored} compressed \
                     bytes, more than zlib can hold; the file is damaged: export it again"
                ),
            ));
        }
        self.budget -= bytes_needed;
        // The elements are written straight into their typed buffer (its bytes, little endian as in the file):
        // plain arrays copied, zlib arrays inflated into exactly the declared size.
        let n = count as usize;
        let prop = match code {
            b'd' => Prop::F64s(self.fill(vec![0f64; n], data, encoding, at, what)?),
            b'l' => Prop::I64s(self.fill(vec![0i64; n], data, encoding, at, what)?),
            b'f' => Prop::F32s(self.fill(vec![0f32; n], data, encoding, at, what)?),
            b'i' => Prop::I32s(self.fill(vec![0i32; n], data, encoding, at, what)?),
            _ => Prop::Bools(self.fill(vec![0u8; n], data, encoding, at, what)?.into_iter().map(|b| b != 0).collect()),
        };
        Ok((prop, data_at + stored))
    }

    /// Fills `out` (the declared number of elements) from an array's stored bytes: copied when `encoding` is 0,
    /// inflated when it is 1 (zlib, its Adler-32 checked; the stream must fill `out` exactly).
    fn fill<T: LittleEndian>(
        &mut self,
        mut out: Vec<T>,
        data: &[u8],
        encoding: u32,
        at: u64,
        what: &str,
    ) -> Result<Vec<T>> {
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out[..]);
        let declared = bytes.len();
        if encoding == 0 {
            bytes.copy_from_slice(data);
        } else {
            let inflater = self.inflater.get_or_insert_with(|| zlib_rs::Inflate::new(true, 15));
            inflater.reset(true);
            let status = inflater.decompress(data, bytes, zlib_rs::InflateFlush::Finish);
            let (read, written) = (inflater.total_in(), inflater.total_out());
            let why = match status {
                Ok(zlib_rs::Status::StreamEnd) if written == declared as u64 => None,
                Ok(zlib_rs::Status::StreamEnd) => Some(format!(
                    "inflates to {written} bytes but declares {} elements ({declared} bytes)",
                    declared / std::mem::size_of::<T>()
                )),
                // Output full and input left: the stream goes on past the declared size (inflating stops there).
                Ok(_) if written == declared as u64 && read < data.len() as u64 => {
                    Some(format!("inflates past the {declared} bytes it declares"))
                }
                Ok(_) => Some("is not valid zlib data (its stream stops before its end)".to_string()),
                Err(e) => Some(format!("is not valid zlib data ({})", e.as_str())),
            };
            if let Some(why) = why {
                return Err(err(self.file, format!("{what} at byte {at} {why}; the file is damaged: export it again")));
            }
        }
        if cfg!(target_endian = "big") {
            out.iter_mut().for_each(LittleEndian::from_le);
        }
        Ok(out)
    }
}

/// Array elements stored little endian: turned to the machine's order in place (a no-op on little-endian
/// machines, which is every target posemfa ships for).
trait LittleEndian: bytemuck::Pod {
    fn from_le(&mut self);
}

macro_rules! little_endian {
    ($($t:ty),*) => {$(
        impl LittleEndian for $t {
            fn from_le(&mut self) {
                *self = <$t>::from_le_bytes(self.to_ne_bytes());
            }
        }
    )*};
}
little_endian!(f64, i64, f32, i32, u8);

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
        return Err(err(
            file,
            format!("the FBX header is cut ({} of 27 bytes); the file is cut: export it again", bytes.len()),
        ));
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
    let mut r = Reader { file, bytes, wide: version >= 7500, budget, skip, inflater: None };
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
        let data = if compress {
            let mut z = vec![0u8; zlib_rs::compress_bound(raw.len())];
            let (done, rc) = zlib_rs::compress_slice(&mut z, &raw, zlib_rs::DeflateConfig::new(6));
            assert_eq!(rc, zlib_rs::ReturnCode::Ok, "deflate into its bound cannot fail");
            done.to_vec()
        } else {
            raw
        };
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of one node `V` holding one zlib f64 array: its bytes and where the array's zlib stream starts.
    fn one_array(values: &[f64]) -> (Vec<u8>, usize) {
        let node = Node { name: "V".into(), props: vec![Prop::F64s(values.to_vec())], children: vec![], offset: 0 };
        let bytes = write(&[node], true);
        // header 27, record header 13, name 1, type code 1, count 4, encoding 4, length 4
        (bytes, 27 + 13 + 1 + 1 + 12)
    }

    fn error(bytes: &[u8]) -> String {
        parse("t.fbx", bytes, 1 << 30).unwrap_err().to_string()
    }

    #[test]
    fn zlib_arrays_inflate_into_their_elements() {
        let values: Vec<f64> = (0..1000).map(|i| (i as f64).sin()).collect();
        for v in [&values[..], &[][..]] {
            let (bytes, _) = one_array(v);
            let tree = parse("t.fbx", &bytes, 1 << 30).unwrap();
            assert_eq!(tree.nodes[0].props[0], Prop::F64s(v.to_vec()));
        }
    }

    #[test]
    fn damaged_zlib_arrays_are_refused() {
        let (bytes, data) = one_array(&[1.5, 2.5, 3.5]);
        let len = u32::from_le_bytes(bytes[data - 4..data].try_into().unwrap()) as usize;
        let at = 27 + 13 + 1;
        let tail = "the file is damaged: export it again";
        // The Adler-32 of the inflated bytes (the stream's last 4 bytes) does not match.
        let mut bad = bytes.clone();
        bad[data + len - 1] ^= 1;
        assert_eq!(
            error(&bad),
            format!("file t.fbx: property 0 of node 'V' at byte {at} is not valid zlib data (data error); {tail}")
        );
        // The stream stops before its end (its checksum cut off; the stored length says so).
        let mut cut = bytes.clone();
        cut[data - 4..data].copy_from_slice(&(len as u32 - 4).to_le_bytes());
        assert_eq!(
            error(&cut),
            format!("file t.fbx: property 0 of node 'V' at byte {at} is not valid zlib data (its stream stops before its end); {tail}")
        );
        // Not zlib at all (a wrong header).
        let mut junk = bytes.clone();
        junk[data] = 0;
        assert_eq!(
            error(&junk),
            format!("file t.fbx: property 0 of node 'V' at byte {at} is not valid zlib data (data error); {tail}")
        );
        // It declares more elements than the stream holds, or fewer (zero among them).
        for (count, message) in [
            (4u32, format!("inflates to 24 bytes but declares 4 elements (32 bytes)")),
            (2, format!("inflates past the 16 bytes it declares")),
            (0, format!("inflates past the 0 bytes it declares")),
        ] {
            let mut lying = bytes.clone();
            lying[data - 12..data - 8].copy_from_slice(&count.to_le_bytes());
            assert_eq!(error(&lying), format!("file t.fbx: property 0 of node 'V' at byte {at} {message}; {tail}"));
        }
    }
}
