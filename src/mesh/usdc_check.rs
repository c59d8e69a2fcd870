//! A structural check of USD crate files (`.usdc`) before they are handed to `openusd` 0.6.0.
//!
//! openusd trusts the counts and sizes it reads: it sizes buffers from them (`vec![0; n]` with `n` straight
//! from the file), indexes its tables with indices from the file, and has `todo!()`s for old crate versions
//! and chunked LZ4. A damaged or hostile file would then abort the process (an allocation failure is an abort,
//! not a panic; in the browser the wasm instance dies) or panic. This module walks the file as openusd will
//! and refuses, with a message saying what is wrong, anything that would:
//!
//! - the bootstrap header: magic, a crate version openusd reads (0.4.0 to 0.12.x), the TOC inside the file;
//! - the TOC: 1 to 63 sections, each inside the file;
//! - the sections read at open (TOKENS, STRINGS, FIELDS, FIELDSETS, PATHS, SPECS): every count and compressed
//!   size against the bytes left in its section, every LZ4 block walked (its decompressed size is exact, so
//!   no buffer is sized beyond what its compressed bytes expand to), the integer codings long enough for their
//!   counts, string table entries naming tokens, and the path tree walked as openusd builds it (indices in
//!   range, no entry visited twice);
//! - the values read later (the ValueReps of the FIELDS section): every array's count against the bytes after
//!   it (by element size; a compressed integer array against the codes its LZ4 block really decodes to, 2 bits
//!   per integer, not against an LZ4 ratio, which USD's integer coding outdoes), openusd's allocations for all
//!   the arrays together within the memory budget, every token / string / path index in range, dictionaries and
//!   time samples followed (their jumps inside the file, at most [`MAX_DEPTH`] levels deep, so a value that
//!   contains itself is refused), and the flag combinations on which openusd's debug assertions fire; values
//!   already checked are not walked again, and the whole walk is bounded (about 1000 elements per byte of
//!   file), so many values over the same data cannot make the check itself slow.
//!
//! Nothing here refuses a file that Pixar's writer makes, except an empty string / asset array (payload 0),
//! which openusd 0.6.0 would misread as a count from the file header. The format (integer coding, ValueRep
//! layout, LZ4 block format) is from Pixar's `crateFile.cpp` / `integerCoding.cpp` and the LZ4 block spec;
//! the code is our own.

use std::collections::HashMap;

/// The oldest and newest crate versions openusd 0.6.0 reads (older ones hit its `todo!()`s).
const OLDEST: (u8, u8, u8) = (0, 4, 0);
const NEWEST_MINOR: u8 = 12;

/// How deep dictionaries and time samples may nest (openusd reads them recursively, one stack frame each).
pub const MAX_DEPTH: u32 = 32;

const DAMAGED: &str = "the file is cut or damaged: export it again";

type Check<T> = std::result::Result<T, String>;

fn damaged<T>(what: String) -> Check<T> {
    Err(format!("{what}; {DAMAGED}"))
}

/// Checks a crate file (starting with `PXR-USDC`); `Err` is the message (what is wrong and what to do).
/// `memory` bounds what openusd may allocate to decode the file's arrays, all of them together (the memory
/// budget, [`crate::memory::budget_bytes`]).
pub fn check(bytes: &[u8], memory: u64) -> Check<()> {
    let mut c = Crate::new(bytes, (0, 0, 0));
    c.memory_budget = memory;
    c.run()
}

/// A read position inside `[.., end)` of the file.
#[derive(Clone)]
struct Cur<'a> {
    b: &'a [u8],
    pos: u64,
    end: u64,
    what: &'a str,
}

impl<'a> Cur<'a> {
    fn left(&self) -> u64 {
        self.end.saturating_sub(self.pos)
    }
    fn take(&mut self, n: u64, item: &str) -> Check<&'a [u8]> {
        if self.pos > self.end || n > self.left() {
            return damaged(format!(
                "{} ends inside {item} (byte {}, {n} bytes wanted, {} left)",
                self.what,
                self.pos,
                self.left()
            ));
        }
        let s = &self.b[self.pos as usize..(self.pos + n) as usize];
        self.pos += n;
        Ok(s)
    }
    fn u8(&mut self, item: &str) -> Check<u8> {
        Ok(self.take(1, item)?[0])
    }
    fn u32(&mut self, item: &str) -> Check<u32> {
        Ok(u32::from_le_bytes(self.take(4, item)?.try_into().expect("4 bytes")))
    }
    fn u64(&mut self, item: &str) -> Check<u64> {
        Ok(u64::from_le_bytes(self.take(8, item)?.try_into().expect("8 bytes")))
    }
    /// `count` elements of `size` bytes must fit in what is left.
    fn fits(&self, count: u64, size: u64, item: &str) -> Check<()> {
        if count.checked_mul(size).is_none_or(|n| n > self.left()) {
            return damaged(format!(
                "{} claims {count} {item} at byte {} ({size} bytes each), but only {} bytes follow",
                self.what,
                self.pos,
                self.left()
            ));
        }
        Ok(())
    }
    /// A `u32` index that must be below `limit`.
    fn index(&mut self, limit: u64, table: &str) -> Check<()> {
        let at = self.pos;
        let i = self.u32(table)?;
        if u64::from(i) >= limit {
            return damaged(format!("{} names {table} {i} at byte {at}, but the file has {limit}", self.what));
        }
        Ok(())
    }
    /// openusd's recursive offset: an `i64` at the position, relative to it, to jump to.
    fn jump(&mut self) -> Check<()> {
        let at = self.pos;
        let off = self.u64("a value offset")? as i64;
        let to = i128::from(at) + i128::from(off);
        if off < i64::MIN + 8 || to < 0 || to > self.b.len() as i128 {
            return damaged(format!("{} jumps from byte {at} by {off}, outside the file", self.what));
        }
        self.pos = to as u64;
        self.end = self.b.len() as u64;
        Ok(())
    }
}

/// Decompressed size of an LZ4 block (`src`, no frame), or why it is not one. With `out`, the bytes too.
/// Refused when it would expand beyond `limit` bytes (openusd's output buffer).
fn lz4(src: &[u8], limit: u64, mut out: Option<&mut Vec<u8>>, what: &str) -> Check<u64> {
    let bad = |why: &str| damaged(format!("{what}: the LZ4 data is corrupt ({why})"));
    let over =
        |n: u64| damaged(format!("{what}: the LZ4 data expands beyond the {limit} bytes expected (to {n} at least)"));
    let mut n: u64 = 0;
    let mut i = 0usize;
    if src.is_empty() {
        return Ok(0);
    }
    let length = |i: &mut usize, mut l: u64| -> Option<u64> {
        loop {
            let b = *src.get(*i)?;
            *i += 1;
            l += u64::from(b);
            if b != 255 {
                return Some(l);
            }
        }
    };
    loop {
        let Some(&token) = src.get(i) else { return bad("a sequence is cut") };
        i += 1;
        let mut lit = u64::from(token >> 4);
        if lit == 15 {
            lit = match length(&mut i, lit) {
                Some(l) => l,
                None => return bad("a literal length is cut"),
            };
        }
        if lit > (src.len() - i) as u64 {
            return bad("literals run past the end");
        }
        if n + lit > limit {
            return over(n + lit);
        }
        if let Some(o) = out.as_deref_mut() {
            o.extend_from_slice(&src[i..i + lit as usize]);
        }
        i += lit as usize;
        n += lit;
        if i == src.len() {
            return Ok(n);
        }
        if src.len() - i < 2 {
            return bad("an offset is cut");
        }
        let offset = u64::from(u16::from_le_bytes([src[i], src[i + 1]]));
        i += 2;
        if offset == 0 || offset > n {
            return bad("a match points before the start");
        }
        let mut m = u64::from(token & 15);
        if m == 15 {
            m = match length(&mut i, m) {
                Some(l) => l,
                None => return bad("a match length is cut"),
            };
        }
        m += 4;
        if n + m > limit {
            return over(n + m);
        }
        if let Some(o) = out.as_deref_mut() {
            let from = o.len() - offset as usize;
            for k in 0..m as usize {
                let b = o[from + k];
                o.push(b);
            }
        }
        n += m;
    }
}

/// LZ4 expands at most about 255:1 (a match of 255 bytes per length byte). This bounds what a block can
/// really decode to; it does not bound openusd's buffer for integers, which is sized from the element count
/// (about 4.25 bytes per integer) while USD's integer coding stores a run of equal steps in 2 bits per
/// integer before LZ4 shrinks those code bytes 255:1: an all-triangle mesh's `faceVertexCounts` (14 410
/// threes) is 33 compressed bytes for a 61 247-byte buffer. So integer counts are bounded by the decoded size
/// (2 bits per integer at least, see [`Crate::ints`]) and by the memory budget, not by this ratio.
fn lz4_cap(compressed: u64) -> u64 {
    compressed.saturating_mul(255).saturating_add(16)
}

/// Summary of a checked value: element count (arrays) and nesting height.
#[derive(Clone, Copy)]
struct Info {
    count: u64,
    height: u32,
}

const LEAF: Info = Info { count: 0, height: 0 };

struct Crate<'a> {
    b: &'a [u8],
    version: (u8, u8, u8),
    tokens: u64,
    strings: u64,
    paths: u64,
    /// Values already checked (ValueRep -> its summary), so shared values are walked once.
    heights: HashMap<u64, Info>,
    /// Elements and compressed bytes walked so far, and how many the file may make us walk: distinct
    /// ValueReps pointing at the same large array would otherwise make the check quadratic.
    work: std::cell::Cell<u64>,
    budget: u64,
    /// Bytes openusd allocates to decode the arrays checked so far (its buffers and its output vectors,
    /// each value counted once), and how many it may: every array of the file decoded at once must fit in the
    /// memory budget. A file claims a large array only with the data to back it (see [`Crate::ints`]), so what
    /// this refuses is a file whose data really decodes to more than the budget, or many values over the
    /// same data.
    memory: std::cell::Cell<u64>,
    memory_budget: u64,
}

/// The integer width openusd decodes an integer array with.
#[derive(Clone, Copy, PartialEq)]
enum Width {
    W32,
    W64,
}

impl<'a> Crate<'a> {
    fn new(b: &'a [u8], version: (u8, u8, u8)) -> Self {
        // Generous: a constant array of a million floats codes to about 1 kB (LZ4 of integer codes), so a valid
        // file can hold about 1000 elements per byte.
        let budget = (b.len() as u64).saturating_mul(1024).saturating_add(1 << 24);
        Crate {
            b,
            version,
            tokens: 0,
            strings: 0,
            paths: 0,
            heights: HashMap::new(),
            work: Default::default(),
            budget,
            memory: Default::default(),
            memory_budget: crate::memory::NATIVE_BUDGET_BYTES,
        }
    }

    /// openusd will allocate `bytes` to decode `what` (at byte `at`): refused when the file's arrays then
    /// take more than the memory budget.
    fn allocates(&self, bytes: u64, what: &str, at: u64) -> Check<()> {
        use crate::memory::show_bytes;
        let total = self.memory.get().saturating_add(bytes);
        self.memory.set(total);
        if total > self.memory_budget {
            let knob = if cfg!(target_arch = "wasm32") {
                "; the command-line program has a budget of 8 GiB (POSEMFA_MEMORY_BUDGET changes it)"
            } else {
                ", or raise the budget with POSEMFA_MEMORY_BUDGET (e.g. 32G) if this machine has the memory"
            };
            return Err(format!(
                "{what} at byte {at} takes {} to decode, which brings the file's arrays to {}, more than the memory \
                 budget of {}; the file is damaged, or far larger than a pose population: export only the animated \
                 mesh{knob}",
                show_bytes(bytes),
                show_bytes(total),
                show_bytes(self.memory_budget)
            ));
        }
        Ok(())
    }

    fn spend(&self, n: u64) -> Check<()> {
        let w = self.work.get().saturating_add(n);
        self.work.set(w);
        if w > self.budget {
            return damaged(format!(
                "its values make the reader walk more than {} elements for a file of {} bytes (many values over the same data)",
                self.budget,
                self.b.len()
            ));
        }
        Ok(())
    }

    fn at(&self, pos: u64, what: &'a str) -> Cur<'a> {
        Cur { b: self.b, pos, end: self.b.len() as u64, what }
    }

    fn run(&mut self) -> Check<()> {
        let len = self.b.len() as u64;
        let mut h = self.at(0, "the header");
        let magic = h.take(8, "the magic")?;
        if magic != b"PXR-USDC" {
            return damaged("the header does not start with PXR-USDC".into());
        }
        let v = h.take(8, "the version")?;
        self.version = (v[0], v[1], v[2]);
        let (ma, mi, pa) = self.version;
        if self.version < OLDEST || ma != 0 || mi > NEWEST_MINOR {
            let why = if self.version < OLDEST { "older than 0.4.0" } else { "newer than 0.12" };
            return Err(format!(
                "it is crate version {ma}.{mi}.{pa}, {why}; the reader (openusd 0.6.0) reads crate versions 0.4.0 to \
                 0.12.x: save the stage again with a current USD (e.g. usdcat in.usdc -o out.usdc)"
            ));
        }
        let toc = h.u64("the TOC offset")?;
        if toc == 0 || toc > len.saturating_sub(8) {
            return damaged(format!("the table of contents is at byte {toc}, outside the file of {len} bytes"));
        }
        let mut t = self.at(toc, "the table of contents");
        let n = t.u64("the section count")?;
        if n == 0 || n >= 64 {
            return damaged(format!("the table of contents lists {n} sections (1 to 63 expected)"));
        }
        t.fits(n, 32, "sections")?;
        let mut sections: Vec<(String, u64, u64)> = Vec::new();
        for k in 0..n {
            let raw = t.take(16, "a section name")?;
            let name = raw
                .split(|&c| c == 0)
                .next()
                .filter(|_| raw.contains(&0))
                .and_then(|s| std::str::from_utf8(s).ok())
                .unwrap_or("");
            let (start, size) = (t.u64("a section start")?, t.u64("a section size")?);
            if start.checked_add(size).is_none_or(|e| e > len) {
                return damaged(format!(
                    "section {k} ({}) spans bytes {start} to {}, past the end of the file ({len} bytes)",
                    if name.is_empty() { "unnamed" } else { name },
                    start as u128 + size as u128
                ));
            }
            sections.push((name.to_string(), start, size));
        }
        // openusd reads the first section of each name.
        let find = |name: &'static str| -> Option<Cur<'a>> {
            sections.iter().find(|s| s.0 == name).map(|&(_, start, size)| Cur {
                b: self.b,
                pos: start,
                end: start + size,
                what: name,
            })
        };
        if let Some(mut s) = find("TOKENS") {
            self.tokens = self.read_tokens(&mut s)?;
        }
        if let Some(mut s) = find("STRINGS") {
            let count = s.u64("the string count")?;
            s.fits(count, 4, "strings")?;
            for _ in 0..count {
                s.index(self.tokens, "token")?;
            }
            self.strings = count;
        }
        let mut reps = Vec::new();
        if let Some(mut s) = find("FIELDS") {
            let count = s.u64("the field count")?;
            self.ints(&mut s, count, Width::W32, false)?;
            let (_, bytes) = self.block(&mut s, count.checked_mul(8), true, true, "field values")?;
            if bytes.len() as u64 != count * 8 {
                return damaged(format!("FIELDS claims {count} fields but holds {} bytes of values", bytes.len()));
            }
            reps = bytes.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        }
        if let Some(mut s) = find("FIELDSETS") {
            let count = s.u64("the fieldset count")?;
            self.ints(&mut s, count, Width::W32, false)?;
        }
        if let Some(mut s) = find("PATHS") {
            self.read_paths(&mut s)?;
        }
        if let Some(mut s) = find("SPECS") {
            let count = s.u64("the spec count")?;
            for _ in 0..3 {
                self.ints(&mut s, count, Width::W32, false)?;
            }
        }
        for (k, &rep) in reps.iter().enumerate() {
            self.value(rep, 0).map_err(|e| format!("field {k}: {e}"))?;
        }
        Ok(())
    }

    /// A compressed block: `u64` size, a chunk count byte (0: one LZ4 block), the block. Its decompressed size
    /// must not exceed `limit` (openusd's buffer; `None`: beyond what any file can hold). With `exact`, the
    /// block must decompress to `limit` bytes, so a limit beyond what LZ4 can expand the block to is refused
    /// before it is walked; otherwise `limit` is only an upper bound (openusd's estimate for integers). Gives
    /// the decompressed size, and with `keep` the bytes.
    fn block(&self, s: &mut Cur<'a>, limit: Option<u64>, exact: bool, keep: bool, item: &str) -> Check<(u64, Vec<u8>)> {
        let at = s.pos;
        let size = s.u64("a compressed size")?;
        if size > s.left() {
            return damaged(format!(
                "{} claims {size} compressed bytes of {item} at byte {at}, but only {} bytes follow",
                s.what,
                s.left()
            ));
        }
        let data = s.take(size, item)?;
        self.spend(size)?;
        let Some((&chunks, block)) = data.split_first() else {
            return damaged(format!("{}: the compressed {item} at byte {at} are empty", s.what));
        };
        if chunks != 0 {
            return damaged(format!(
                "{}: the compressed {item} at byte {at} are in {chunks} LZ4 chunks (made only for data over 2 GB), which the reader cannot read",
                s.what
            ));
        }
        let Some(limit) = limit.filter(|&l| !exact || l <= lz4_cap(size)) else {
            return damaged(format!(
                "{} claims {} bytes of {item} at byte {at}, more than its {size} compressed bytes can hold",
                s.what,
                limit.map_or("too many".to_string(), |l| l.to_string())
            ));
        };
        let what = format!("{} ({item} at byte {at})", s.what);
        let mut out = Vec::new();
        let n = lz4(block, limit, keep.then_some(&mut out), &what)?;
        Ok((n, out))
    }

    /// `read_encoded_ints` of openusd: `count` integers coded (common value, 2-bit codes, deltas) in a
    /// compressed block. With `decode`, the integers (as i64, to be cast to the width's type).
    fn ints(&self, s: &mut Cur<'a>, count: u64, width: Width, decode: bool) -> Check<Vec<i64>> {
        let at = s.pos;
        let w: u64 = if width == Width::W64 { 8 } else { 4 };
        // (a size beyond the section is refused by block() below, with its own message)
        let size = s.clone().u64("a compressed size")?.min(s.left().saturating_sub(8));
        // The coding needs the common value and a code byte per 4 integers, so a count beyond 4 x what the
        // block can expand to cannot be right; this also keeps openusd's size arithmetic from overflowing.
        if count > lz4_cap(size).saturating_mul(4) {
            let what = s.what;
            return damaged(format!(
                "{what} claims {count} integers at byte {at}, more than its {size} compressed bytes can hold"
            ));
        }
        let codes = (count * 2).div_ceil(8);
        // openusd sizes its buffer for 32-bit integers, whatever the width.
        let estimate = if count == 0 { 0 } else { 4 + codes + 4 * count };
        // The block is walked (without keeping its bytes unless they are decoded here): its true decoded size
        // bounds the count (2 bits of code per integer), then openusd's buffer and output are what the file's
        // data backs, and they count against the memory budget.
        let (n, data) = self.block(s, Some(estimate), false, decode, "integers")?;
        if count == 0 {
            return Ok(Vec::new());
        }
        if n < w + codes {
            return damaged(format!(
                "{}: {count} integers at byte {at} need {} bytes of codes, the block holds {n}",
                s.what,
                w + codes
            ));
        }
        self.allocates(estimate.saturating_add(count.saturating_mul(w)), &format!("{}: {count} integers", s.what), at)?;
        if !decode {
            return Ok(Vec::new());
        }
        let mut d = Cur { b: &data, pos: 0, end: n, what: s.what };
        let common = if width == Width::W64 { d.u64("integers")? as i64 } else { i64::from(d.u32("integers")? as i32) };
        let mut v = Cur { b: &data, pos: w + codes, end: n, what: s.what };
        self.spend(count)?;
        let mut out = Vec::with_capacity(count as usize);
        let mut prev = 0i64;
        'all: for k in 0..codes {
            let code = data[(w + k) as usize];
            for j in 0..4 {
                if out.len() as u64 == count {
                    break 'all;
                }
                let delta = match ((code >> (2 * j)) & 3, width) {
                    (0, _) => common,
                    (1, Width::W32) => i64::from(v.take(1, "integers")?[0] as i8),
                    (1, Width::W64) | (2, Width::W32) => {
                        i64::from(i16::from_le_bytes(v.take(2, "integers")?.try_into().expect("2")))
                    }
                    (2, Width::W64) | (3, Width::W32) => i64::from(v.u32("integers")? as i32),
                    _ => v.u64("integers")? as i64,
                };
                prev = prev.wrapping_add(delta);
                out.push(prev);
            }
        }
        Ok(out)
    }

    fn read_tokens(&self, s: &mut Cur<'a>) -> Check<u64> {
        let count = s.u64("the token count")?;
        let size = s.u64("the token bytes' size")?;
        let at = s.pos;
        let (n, _) = self.block(s, Some(size), true, false, "tokens")?;
        if n != size {
            return damaged(format!("TOKENS claims {size} bytes of tokens at byte {at} but its data expands to {n}"));
        }
        if count > n {
            return damaged(format!("TOKENS claims {count} tokens but holds only {n} bytes of them"));
        }
        Ok(count)
    }

    /// PATHS: the path count, then the tree as three integer arrays (path index, element token, jump), walked
    /// here as openusd walks it.
    fn read_paths(&mut self, s: &mut Cur<'a>) -> Check<()> {
        let paths = s.u64("the path count")?;
        let count = s.u64("the encoded path count")?;
        if paths > count {
            return damaged(format!("PATHS claims {paths} paths but encodes only {count}"));
        }
        let index = self.ints(s, count, Width::W32, true)?;
        let token = self.ints(s, count, Width::W32, true)?;
        let jump = self.ints(s, count, Width::W32, true)?;
        self.paths = paths;
        if count == 0 {
            return Ok(());
        }
        let bad = |why: String| damaged(format!("PATHS: {why}"));
        let mut filled = vec![false; paths as usize];
        // (next entry, whether the parent path is still empty)
        let mut pending = vec![(0u64, true)];
        let mut visits = 0u64;
        while let Some((mut i, mut root)) = pending.pop() {
            loop {
                visits += 1;
                if visits > count {
                    return bad(format!("the tree visits more than its {count} entries (its jumps loop)"));
                }
                if i >= count {
                    return bad(format!("the tree runs to entry {i} of {count}"));
                }
                let k = i as usize;
                let slot = index[k] as u32 as u64;
                if root {
                    if i >= paths {
                        return bad(format!("the root is entry {i} of {paths} paths"));
                    }
                    filled[k] = true;
                    root = false;
                } else {
                    let t = u64::from((token[k] as i32).unsigned_abs());
                    if t >= self.tokens {
                        return bad(format!("entry {i} names token {t}, but the file has {}", self.tokens));
                    }
                    if slot >= paths {
                        return bad(format!("entry {i} names path {slot}, but the file has {paths}"));
                    }
                    filled[slot as usize] = true;
                }
                let j = jump[k] as i32;
                let (child, sibling) = (j > 0 || j == -1, j >= 0);
                if child {
                    if sibling {
                        pending.push((i + j as u64, root));
                    }
                    if slot >= paths {
                        return bad(format!("entry {i} names path {slot}, but the file has {paths}"));
                    }
                    root = !filled[slot as usize];
                }
                if !child && !sibling {
                    break;
                }
                i += 1;
            }
        }
        Ok(())
    }

    /// The element count of an array value (openusd's `unpack_array_len`) and whether it is compressed, with
    /// the position after the count; `kind`: 0 plain, 1 integers, 2 floats.
    fn array(&self, rep: u64, kind: u8) -> Check<(u64, bool, Cur<'a>)> {
        let p = rep & ((1 << 48) - 1);
        if rep & INLINED != 0 {
            return damaged(format!("an array value is marked inlined (ValueRep {rep:#x})"));
        }
        if kind == 0 && rep & COMPRESSED != 0 {
            return damaged(format!(
                "an array of type {} is marked compressed (ValueRep {rep:#x})",
                (rep >> 48) & 0xff
            ));
        }
        let mut c = self.at(p, "an array value");
        if p == 0 {
            return Ok((0, false, c));
        }
        if self.version < (0, 5, 0) {
            c.u32("an array shape")?;
        }
        let count =
            if self.version < (0, 7, 0) { u64::from(c.u32("an array count")?) } else { c.u64("an array count")? };
        let compressed = rep & COMPRESSED != 0
            && count >= 4
            && match kind {
                1 => self.version >= (0, 5, 0),
                2 => self.version >= (0, 6, 0),
                _ => false,
            };
        Ok((count, compressed, c))
    }

    /// A count-prefixed array of `u32` indices below `limit` at `c` (openusd's `read_indexed_vec`).
    fn indexed(&self, c: &mut Cur<'a>, limit: u64, table: &str) -> Check<u64> {
        let count = c.u64("a count")?;
        c.fits(count, 4, &format!("{table} indices"))?;
        self.spend(count)?;
        for _ in 0..count {
            c.index(limit, table)?;
        }
        Ok(count)
    }

    /// A count-prefixed array of `size`-byte values at `c`.
    fn pods(&self, c: &mut Cur<'a>, size: u64) -> Check<()> {
        let count = c.u64("a count")?;
        c.fits(count, size, "values")?;
        c.take(count * size, "values")?;
        Ok(())
    }

    /// A dictionary at `c` (openusd's `read_custom_data`), leaving `c` where openusd leaves its reader.
    fn dictionary(&mut self, c: &mut Cur<'a>, depth: u32) -> Check<u32> {
        let count = c.u64("a dictionary size")?;
        // Each entry is at least a key (4 bytes), a jump (8) and a ValueRep (8), one after the other.
        c.fits(count, 20, "dictionary entries")?;
        self.spend(count)?;
        let mut height = 0;
        for _ in 0..count {
            c.index(self.strings, "string")?;
            c.jump()?;
            let rep = c.u64("a dictionary value")?;
            if (rep >> 48) & 0xff == 0 {
                // openusd stops with an error here.
                return Ok(height);
            }
            height = height.max(self.value(rep, depth + 1)?.height);
        }
        Ok(height)
    }

    /// Checks a value as openusd's `CrateFile::value` would read it.
    fn value(&mut self, rep: u64, depth: u32) -> Check<Info> {
        if depth > MAX_DEPTH {
            return damaged(format!(
                "values nest more than {MAX_DEPTH} levels deep (a dictionary or time samples holding itself?)"
            ));
        }
        if let Some(&info) = self.heights.get(&rep) {
            if depth + info.height > MAX_DEPTH {
                return damaged(format!(
                    "values nest more than {MAX_DEPTH} levels deep (a dictionary or time samples holding itself?)"
                ));
            }
            return Ok(info);
        }
        let info = self.value_uncached(rep, depth)?;
        self.heights.insert(rep, info);
        Ok(info)
    }

    fn value_uncached(&mut self, rep: u64, depth: u32) -> Check<Info> {
        let ty = (rep >> 48) & 0xff;
        let (array, inlined, compressed) = (rep & ARRAY != 0, rep & INLINED != 0, rep & COMPRESSED != 0);
        let p = rep & ((1 << 48) - 1);
        let (tokens, strings, paths) = (self.tokens, self.strings, self.paths);
        let count = |n: u64| Ok(Info { count: n, height: 0 });
        let small = |i: u64, limit: u64, table: &str| {
            if i >= limit {
                damaged(format!("a value names {table} {i}, but the file has {limit}"))
            } else {
                Ok(LEAF)
            }
        };
        // Element sizes of the plain arrays (types 1-30 except the integer, float, string and token ones).
        let plain = |t: u64| -> Option<u64> {
            Some(match t {
                1 | 2 => 1,
                13 => 32,
                14 => 72,
                15 => 128,
                16 => 32,
                17 => 16,
                18 => 8,
                19 => 16,
                20 => 8,
                21 => 4,
                22 => 8,
                23 => 24,
                24 => 12,
                25 => 6,
                26 => 12,
                27 => 32,
                28 => 16,
                29 => 8,
                30 => 16,
                _ => return None,
            })
        };
        match ty {
            t if array && plain(t).is_some() => {
                let (n, _, c) = self.array(rep, 0)?;
                let size = plain(t).unwrap_or(1);
                c.fits(n, size, "array elements")?;
                self.allocates(n * size, &format!("an array of {n} elements"), c.pos)?;
                count(n)
            }
            3..=6 if array => {
                let (n, packed, mut c) = self.array(rep, 1)?;
                let width = if ty >= 5 { Width::W64 } else { Width::W32 };
                if packed {
                    self.ints(&mut c, n, width, false)?;
                } else if n > 0 {
                    let size = if ty >= 5 { 8 } else { 4 };
                    c.fits(n, size, "integers")?;
                    self.allocates(n * size, &format!("an array of {n} integers"), c.pos)?;
                }
                count(n)
            }
            7..=9 | 48 | 56 if array || ty == 48 => {
                if inlined {
                    return Ok(LEAF);
                }
                let size = match ty {
                    7 => 2,
                    8 => 4,
                    _ => 8,
                };
                let (n, packed, mut c) = self.array(rep, 2)?;
                if !packed {
                    c.fits(n, size, "numbers")?;
                    self.allocates(n * size, &format!("an array of {n} numbers"), c.pos)?;
                    return count(n);
                }
                // (the integers and the lookup table are counted where they are checked)
                let at = c.pos;
                match c.u8("a float array code")? {
                    b'i' => {
                        self.ints(&mut c, n, Width::W32, false)?;
                    }
                    b't' => {
                        let lut = u64::from(c.u32("a lookup table size")?);
                        c.fits(lut, size, "lookup table entries")?;
                        c.take(lut * size, "a lookup table")?;
                        self.allocates(lut * size, &format!("a lookup table of {lut} numbers"), c.pos)?;
                        let at = c.pos;
                        for i in self.ints(&mut c, n, Width::W32, true)? {
                            if i as u32 as u64 >= lut {
                                return damaged(format!(
                                    "a float array at byte {at} names entry {} of a {lut}-entry table",
                                    i as u32
                                ));
                            }
                        }
                    }
                    _ => {}
                }
                self.allocates(n.saturating_mul(size), &format!("an array of {n} numbers"), at)?;
                count(n)
            }
            // Token array: u32 token indices.
            11 if array => {
                let (n, _, mut c) = self.array(rep, 0)?;
                c.fits(n, 4, "token indices")?;
                self.spend(n)?;
                for _ in 0..n {
                    c.index(tokens, "token")?;
                }
                count(n)
            }
            // String / asset / path expression arrays and string vectors: count-prefixed string indices.
            10 | 12 | 57 | 50 if array || ty == 50 => {
                if ty == 50 && inlined {
                    return Ok(LEAF);
                }
                if p == 0 {
                    return damaged(
                        "an empty string or asset array (payload 0), which the reader (openusd 0.6.0) misreads".into(),
                    );
                }
                let n = self.indexed(&mut self.at(p, "a string array"), strings, "string")?;
                count(n)
            }
            // Scalar token (and unregistered value): a u64 token index, inlined or at the payload.
            11 | 53 => {
                if array {
                    return Ok(LEAF);
                }
                let i = if inlined { p & 0xffff_ffff } else { self.at(p, "a token value").u64("a token index")? };
                small(i, tokens, "token")
            }
            10 | 12 | 57 => {
                let i = if inlined {
                    p & 0xffff_ffff
                } else {
                    u64::from(self.at(p, "a string value").u32("a string index")?)
                };
                if inlined && ty != 10 {
                    small(i, tokens, "token")
                } else {
                    small(i, strings, "string")
                }
            }
            // List ops (token, string, path, reference, int, int64, uint, uint64, unregistered, payload).
            32..=39 | 54 | 55 => {
                if inlined && ty != 55 {
                    return Ok(LEAF);
                }
                let mut c = self.at(p, "a list op");
                let header = c.u8("a list op header")?;
                let lists = (header >> 1 & 0x3f).count_ones();
                let mut height = 0;
                for _ in 0..lists {
                    match ty {
                        32 => _ = self.indexed(&mut c, tokens, "token")?,
                        33 | 54 => _ = self.indexed(&mut c, strings, "string")?,
                        34 => _ = self.indexed(&mut c, paths, "path")?,
                        36 | 38 => self.pods(&mut c, 4)?,
                        37 | 39 => self.pods(&mut c, 8)?,
                        35 => {
                            let n = c.u64("a reference count")?;
                            c.fits(n, 32, "references")?;
                            self.spend(n)?;
                            for _ in 0..n {
                                c.index(strings, "string")?;
                                c.index(paths, "path")?;
                                c.take(16, "a layer offset")?;
                                height = height.max(self.dictionary(&mut c, depth)? + 1);
                            }
                        }
                        _ => {
                            let offset = if self.version >= (0, 8, 0) { 16 } else { 0 };
                            let n = c.u64("a payload count")?;
                            c.fits(n, 8 + offset, "payloads")?;
                            self.spend(n)?;
                            for _ in 0..n {
                                c.index(strings, "string")?;
                                c.index(paths, "path")?;
                                c.take(offset, "a layer offset")?;
                            }
                        }
                    }
                }
                Ok(Info { count: 0, height })
            }
            41 | 40 if !inlined => {
                let (limit, table) = if ty == 41 { (tokens, "token") } else { (paths, "path") };
                let n = self.indexed(&mut self.at(p, "a vector value"), limit, table)?;
                count(n)
            }
            49 if !inlined && !array && !compressed => {
                self.pods(&mut self.at(p, "a layer offset vector"), 16)?;
                Ok(LEAF)
            }
            47 if !inlined && !array && !compressed => {
                let mut c = self.at(p, "a payload");
                c.index(strings, "string")?;
                c.index(paths, "path")?;
                Ok(LEAF)
            }
            45 if !inlined && !array && !compressed => {
                let mut c = self.at(p, "a variant selection");
                let n = c.u64("a variant selection count")?;
                c.fits(n, 8, "variant selections")?;
                self.spend(n)?;
                for _ in 0..2 * n {
                    c.index(strings, "string")?;
                }
                Ok(LEAF)
            }
            58 if !inlined => {
                let mut c = self.at(p, "relocates");
                let n = c.u64("a relocates count")?;
                c.fits(n, 8, "relocates")?;
                self.spend(n)?;
                for _ in 0..2 * n {
                    c.index(paths, "path")?;
                }
                Ok(LEAF)
            }
            // Time samples: a jump to the times' ValueRep, then a jump to the count and the values' ValueReps.
            46 if !inlined && !compressed => {
                let mut c = self.at(p, "time samples");
                c.jump()?;
                let times = c.u64("the times' ValueRep")?;
                let tt = (times >> 48) & 0xff;
                if !(tt == 48 || (tt == 9 && times & ARRAY != 0)) {
                    return Ok(LEAF);
                }
                let n = self.value(times, depth + 1)?.count;
                c.jump()?;
                let k = c.u64("a time sample count")?;
                if k != n {
                    return Ok(LEAF);
                }
                c.fits(k, 8, "time samples")?;
                self.spend(k)?;
                let mut height = 1;
                for _ in 0..k {
                    let v = c.u64("a time sample's ValueRep")?;
                    height = height.max(self.value(v, depth + 1)?.height + 1);
                }
                Ok(Info { count: k, height })
            }
            31 if !inlined && !compressed && !array => {
                let mut c = self.at(p, "a dictionary");
                Ok(Info { count: 0, height: self.dictionary(&mut c, depth)? + 1 })
            }
            _ => Ok(LEAF),
        }
    }
}

const ARRAY: u64 = 1 << 63;
const INLINED: u64 = 1 << 62;
const COMPRESSED: u64 = 1 << 61;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lz4_blocks_expand_and_corrupt_ones_are_refused() {
        // "abc", then a match 3 back of 6 bytes, then an empty last sequence
        let block = [0x32, b'a', b'b', b'c', 3, 0, 0x00];
        let mut out = Vec::new();
        assert_eq!(lz4(&block, 9, Some(&mut out), "t"), Ok(9));
        assert_eq!(out, b"abcabcabc");
        assert_eq!(lz4(&block, u64::MAX, None, "t"), Ok(9));
        let e = lz4(&block, 8, None, "t").unwrap_err();
        assert_eq!(e, format!("t: the LZ4 data expands beyond the 8 bytes expected (to 9 at least); {DAMAGED}"));
        let e = lz4(&[0x32, b'a', b'b', b'c', 4, 0, 0x00], 100, None, "t").unwrap_err();
        assert_eq!(e, format!("t: the LZ4 data is corrupt (a match points before the start); {DAMAGED}"));
        let e = lz4(&[0x50, b'a'], 100, None, "t").unwrap_err();
        assert_eq!(e, format!("t: the LZ4 data is corrupt (literals run past the end); {DAMAGED}"));
        // a long match: 15 + 255 + 10 + 4 bytes from one byte
        assert_eq!(lz4(&[0x1f, b'x', 1, 0, 255, 10, 0x00], u64::MAX, None, "t"), Ok(1 + 284));
    }

    #[test]
    fn coded_integers_decode_as_in_pixars_example() {
        // integerCoding.cpp: [123, 124, 125, 100125, 100125, 100126, 100126] is
        // int32(1) 01 00 00 11 01 00 01 XX int8(123) int32(100000) int8(0) int8(0)
        let mut coded = 1i32.to_le_bytes().to_vec();
        coded.extend_from_slice(&0b1100_0001_0001_0001u16.to_be_bytes());
        coded.push(123);
        coded.extend_from_slice(&100000i32.to_le_bytes());
        coded.extend_from_slice(&[0, 0]);
        // stored as literals only: one LZ4 sequence
        let mut block = vec![0u8, (coded.len() as u8) << 4];
        block.extend_from_slice(&coded);
        let mut file = (block.len() as u64).to_le_bytes().to_vec();
        file.extend_from_slice(&block);
        let c = Crate::new(&file, (0, 8, 0));
        let mut s = c.at(0, "T");
        assert_eq!(c.ints(&mut s, 7, Width::W32, true), Ok(vec![123, 124, 125, 100125, 100125, 100126, 100126]));
        // 100 integers cannot be coded in 4 + 2 + 7 bytes (they need 4 + 25 bytes of codes alone)
        let e = c.ints(&mut c.at(0, "T"), 100, Width::W32, false).unwrap_err();
        assert_eq!(e, format!("T: 100 integers at byte 0 need 29 bytes of codes, the block holds 13; {DAMAGED}"));
        let e = c.ints(&mut c.at(0, "T"), 1 << 40, Width::W32, false).unwrap_err();
        assert_eq!(
            e,
            format!("T claims 1099511627776 integers at byte 0, more than its 15 compressed bytes can hold; {DAMAGED}")
        );
    }

    /// The seed .usdc with its FIELDS ValueReps replaced by `reps`: a new FIELDS section (the reps stored as
    /// LZ4 literals) and a new TOC appended, the header pointing at the new TOC.
    fn with_reps(seed: &[u8], reps: &[u64]) -> Vec<u8> {
        let c = Crate::new(seed, (0, 8, 0));
        let toc = u64::from_le_bytes(seed[16..24].try_into().unwrap()) as usize;
        let n = u64::from_le_bytes(seed[toc..toc + 8].try_into().unwrap()) as usize;
        let entry = (0..n).map(|k| toc + 8 + 32 * k).find(|&e| seed[e..e + 7] == *b"FIELDS\0").unwrap();
        let start = u64::from_le_bytes(seed[entry + 16..entry + 24].try_into().unwrap());
        let mut s = c.at(start + 8, "FIELDS");
        let size = s.u64("size").unwrap();
        s.take(size, "indices").unwrap();
        let indices = &seed[start as usize..s.pos as usize];
        let mut out = seed.to_vec();
        let new_start = out.len() as u64;
        out.extend_from_slice(indices);
        let raw: Vec<u8> = reps.iter().flat_map(|r| r.to_le_bytes()).collect();
        let mut block = vec![0u8, 0xf0];
        let mut l = raw.len() - 15;
        while l >= 255 {
            block.push(255);
            l -= 255;
        }
        block.push(l as u8);
        block.extend_from_slice(&raw);
        out.extend_from_slice(&(block.len() as u64).to_le_bytes());
        out.extend_from_slice(&block);
        let new_size = out.len() as u64 - new_start;
        let new_toc = out.len() as u64;
        out.extend_from_slice(&seed[toc..toc + 8 + 32 * n]);
        let e = new_toc as usize + (entry - toc);
        out[e + 16..e + 24].copy_from_slice(&new_start.to_le_bytes());
        out[e + 24..e + 32].copy_from_slice(&new_size.to_le_bytes());
        out[16..24].copy_from_slice(&new_toc.to_le_bytes());
        out
    }

    /// The seed's FIELDS ValueReps, read back the way run() reads them.
    fn seed_reps(seed: &[u8]) -> Vec<u64> {
        let c = Crate::new(seed, (0, 8, 0));
        let toc = u64::from_le_bytes(seed[16..24].try_into().unwrap()) as usize;
        let fields = (0..6).map(|k| toc + 8 + 32 * k).find(|&e| seed[e..e + 7] == *b"FIELDS\0").unwrap();
        let start = u64::from_le_bytes(seed[fields + 16..fields + 24].try_into().unwrap());
        let mut s = c.at(start, "FIELDS");
        let count = s.u64("n").unwrap();
        c.ints(&mut s, count, Width::W32, false).unwrap();
        let (_, bytes) = c.block(&mut s, Some(count * 8), true, true, "reps").unwrap();
        bytes.chunks_exact(8).map(|b| u64::from_le_bytes(b.try_into().unwrap())).collect()
    }

    /// An LZ4 block that expands to `literals`, then `zeros` zero bytes (a match 1 back, so the last literal
    /// must be 0), then the 5 literals `tail`; as usd-core's LZ4 writes a long run (one length byte per 255).
    fn lz4_run(literals: &[u8], zeros: u64, tail: &[u8; 5]) -> Vec<u8> {
        assert!(literals.len() < 15 && literals.last() == Some(&0) && zeros >= 19);
        let mut b = vec![(literals.len() as u8) << 4 | 15];
        b.extend_from_slice(literals);
        b.extend_from_slice(&1u16.to_le_bytes());
        let mut l = zeros - 4 - 15;
        while l >= 255 {
            b.push(255);
            l -= 255;
        }
        b.push(l as u8);
        b.push(5 << 4);
        b.extend_from_slice(tail);
        b
    }

    /// `n` equal integers (all 3, as an all-triangle mesh's faceVertexCounts) as usd-core codes them: common
    /// value 0, one 2-bit code per integer (the first says "an int8 follows"), the int8 3.
    fn all_threes(n: u64) -> Vec<u8> {
        let codes = (2 * n).div_ceil(8);
        let block = lz4_run(&[0, 0, 0, 0, 1, 0], codes - 6, &[0, 0, 0, 0, 3]);
        let mut out = n.to_le_bytes().to_vec();
        out.extend_from_slice(&(block.len() as u64 + 1).to_le_bytes());
        out.push(0);
        out.extend_from_slice(&block);
        out
    }

    /// The seed with `payload` appended and every compressed int array ValueRep (faceVertexCounts and
    /// faceVertexIndices) pointing at it.
    fn with_int_arrays(seed: &[u8], payload: &[u8]) -> Vec<u8> {
        let mut b = seed.to_vec();
        let at = b.len() as u64;
        b.extend_from_slice(payload);
        let reps = seed_reps(seed);
        let ints = |r: u64| (r >> 48) & 0xff == 3 && r & ARRAY != 0;
        assert_eq!(reps.iter().filter(|&&r| ints(r)).count(), 2);
        let reps: Vec<u64> =
            reps.iter().map(|&r| if ints(r) { ARRAY | COMPRESSED | 3 << 48 | at } else { r }).collect();
        with_reps(&b, &reps)
    }

    /// usd-core codes an all-triangle mesh's faceVertexCounts to a few dozen bytes: 300 000 threes are 75 005 bytes of
    /// codes, 310 bytes of LZ4, and openusd's buffer for them is 1 275 004 bytes (4100 x). Such a file is read, not
    /// refused as damaged (a buffer that large is no sign of damage here): openusd decodes the integers, and the reader
    /// sees them (the counts add up to 900 000 corners, the indices are the same 300 000 threes).
    #[test]
    fn integer_arrays_that_code_to_a_few_bytes_are_read() {
        let seed = include_bytes!("../../fuzz/seeds/arm-pointcache.usdc");
        assert_eq!(&seed[8..11], &[0, 8, 0]);
        let payload = all_threes(300_000);
        assert_eq!(payload.len(), 16 + 1 + 310);
        let file = with_int_arrays(seed, &payload);
        check(&file, crate::memory::NATIVE_BUDGET_BYTES).unwrap();
        let e = crate::mesh::usd::read("threes.usdc", &file, &Default::default()).unwrap_err().to_string();
        assert_eq!(
            e,
            "file threes.usdc: mesh /World/Character/Body: faceVertexCounts add up to 900000 corners but \
             faceVertexIndices has 300000; the file is damaged: export it again"
        );
    }

    /// What an integer array may claim: at most 4 integers per byte its LZ4 block really decodes to (2 bits of
    /// code each), and what openusd allocates for all the file's arrays within the memory budget.
    #[test]
    fn integer_arrays_that_claim_more_than_their_data_are_refused() {
        let seed = include_bytes!("../../fuzz/seeds/arm-pointcache.usdc");
        let at = seed.len();
        // 210 000 integers claimed over the codes of 200 000
        let mut payload = all_threes(200_000);
        payload[..8].copy_from_slice(&210_000u64.to_le_bytes());
        let e = check(&with_int_arrays(seed, &payload), u64::MAX).unwrap_err();
        assert_eq!(
            e,
            format!(
                "field 15: an array value: 210000 integers at byte {} need 52504 bytes of codes, the block holds 50005; {DAMAGED}",
                at + 8
            )
        );
        // a count beyond 4 x what LZ4 can expand the block to (212 bytes: 54 076): refused before it is walked
        payload[..8].copy_from_slice(&300_000u64.to_le_bytes());
        let e = check(&with_int_arrays(seed, &payload), u64::MAX).unwrap_err();
        assert_eq!(
            e,
            format!(
                "field 15: an array value claims 300000 integers at byte {}, more than its 212 compressed bytes can hold; {DAMAGED}",
                at + 8
            )
        );
        // real data over the budget: 1 000 000 threes take 4 250 004 bytes of openusd's buffer and 4 000 000 of
        // integers (both int arrays' ValueReps are now the same value, counted once)
        let file = with_int_arrays(seed, &all_threes(1_000_000));
        check(&file, 8_300_000).unwrap();
        let e = check(&file, 8_000_000).unwrap_err();
        assert!(
            e.starts_with(&format!(
                "field 15: an array value: 1000000 integers at byte {} takes 7.9 MiB to decode, which brings the \
                 file's arrays to 7.9",
                at + 8
            )),
            "{e}"
        );
        assert!(e.contains(" MiB, more than the memory budget of 7.6 MiB; the file is damaged, or far larger than a pose population"), "{e}");
        // 4 x 10^9 integers backed by 3.9 MB of LZ4 (a 1 GB run of zero codes) are refused by the default
        // native budget, before anything is allocated
        let file = with_int_arrays(seed, &all_threes(4_000_000_000));
        assert!(file.len() > 3_900_000 && file.len() < 4_000_000, "{}", file.len());
        let e = check(&file, crate::memory::NATIVE_BUDGET_BYTES).unwrap_err();
        assert!(e.contains("4000000000 integers at byte"), "{e}");
        assert!(e.contains("takes 30.73 GiB to decode"), "{e}");
        assert!(e.contains("more than the memory budget of 8.00 GiB"), "{e}");
    }

    /// Random changes to the ValueReps of the seed .usdc (type, flags, payload: the values openusd reads
    /// lazily), read through `usd::read`: none may panic or abort. `POSEMFA_USD_MUTATIONS` (default 3000).
    #[test]
    fn mutated_value_reps_never_panic() {
        use rand::{Rng, SeedableRng};
        let seed = include_bytes!("../../fuzz/seeds/arm-pointcache.usdc");
        let mut c = Crate::new(seed, (0, 8, 0));
        c.run().unwrap();
        let mut small = Crate::new(seed, (0, 0, 0));
        small.budget = 100;
        assert!(small
            .run()
            .unwrap_err()
            .contains("make the reader walk more than 100 elements for a file of 3894 bytes"));
        let reps = seed_reps(seed);
        assert_eq!(
            crate::mesh::usd::read("seed.usdc", &with_reps(seed, &reps), &Default::default()).unwrap().poses.len(),
            2
        );
        let n: usize = std::env::var("POSEMFA_USD_MUTATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(3000);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(
            std::env::var("POSEMFA_USD_MUTATION_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(7),
        );
        let (mut loaded, mut refused) = (0, 0);
        for _ in 0..n {
            let mut r = reps.clone();
            for _ in 0..rng.gen_range(1..=3) {
                let k = rng.gen_range(0..r.len());
                let payload = r[k] & ((1 << 48) - 1);
                let flags = r[k] & (7 << 61);
                let ty = (r[k] >> 48) & 0xff;
                r[k] = match rng.gen_range(0..5) {
                    0 => (r[k] & !(0xff << 48)) | (rng.gen_range(0..60u64) << 48),
                    1 => r[k] ^ (1 << rng.gen_range(61..64)),
                    2 => flags | ty << 48 | rng.gen_range(0..seed.len() as u64 + 16),
                    3 => r[rng.gen_range(0..r.len())] & !((1 << 48) - 1) | payload,
                    _ => flags | rng.gen_range(0..60u64) << 48 | (r[rng.gen_range(0..r.len())] & ((1 << 48) - 1)),
                };
            }
            let mut b = with_reps(seed, &r);
            if rng.gen_bool(0.3) {
                let at = rng.gen_range(0..2896);
                b[at] = rng.gen();
            }
            match crate::mesh::usd::read("fuzz.usdc", &b, &Default::default()) {
                Ok(_) => loaded += 1,
                Err(crate::Error::Mesh { format: crate::error::Format::Usd, .. }) => refused += 1,
                Err(e) => panic!("{e:?}"),
            }
        }
        eprintln!("mutated_value_reps_never_panic: {n} mutations, {loaded} loaded, {refused} refused");
    }
}
