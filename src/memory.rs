//! The memory budget of a fit, checked before the big allocations.
//!
//! [`estimate_bytes`] is an upper estimate of the peak working set of Algorithm 1 (coarse AECM, refinement,
//! final AECM) on a population of `n_vertices` x `n_shapes`, with at most `parts` components in any stage:
//!
//! - 48 bytes per (vertex, shape) for the coordinates, which are stored in f32 and read as f64 (the
//!   arithmetic stays f64): the population, 12 bytes, one copy shared by the caller, the pipeline and the
//!   page's models ([`crate::mesh::Population`]); the running AECM's data vectors h_j, 12 bytes, stored once in
//!   the E-step's blocked layout and shared with it ([`crate::mfa::data::Data`]); and 24 bytes for what comes
//!   and goes around them: a part's data in the refinement, the f32 points of a Procrustes start or of the
//!   diagnosis, the readers' f64 poses while a population is assembled (24 bytes, freed pose by pose), and the
//!   allocator's slack (wasm's linear memory never shrinks, so a large block freed where a larger one is
//!   needed stays unused). Measured in wasm (`node scripts/bench-wasm.mjs INPUT --node`, see
//!   docs/speed.md): 49.6 bytes per (vertex, shape) at 20 k x 200 (where the terms below vanish), 59.1 at
//!   42 k x 11; 7 copies of 24 bytes (168) before. Deciding the parts on a coarse mesh
//!   ([`crate::parts::coarse_mesh`]) adds its own copy of 8 000 vertices' coordinates and data (24 bytes per
//!   coarse vertex and shape): 59.5 at 20 k x 200, still 59.1 at 42 k x 11, within the 24 bytes above;
//! - the responsibilities, dense when labels are read, 8 bytes per (vertex, component);
//! - 128 bytes per vertex of labels, latent points, k-means distances, the sparse responsibilities of the
//!   CM steps (40 bytes per pair, one or two pairs per vertex) and such;
//! - 3 copies of the components (the running one, the best one seen, the model), each with 9 + 3 + 1 numbers
//!   per shape, and the cycle-2 statistics (9 + 1 per shape): 8 x 49 bytes per (component, shape).
//!
//! The budget ([`budget_bytes`]) is 1 GiB in wasm32 (a browser tab's heap: wasm32 addresses 4 GiB at most, and
//! the page, the worker and the typed arrays of the views need their share) and 8 GiB natively, where the
//! environment variable `POSEMFA_MEMORY_BUDGET` can change it (bytes, or a number with a K, M or G suffix, in
//! units of 1024). A population whose smallest fit (1 part) does not fit is refused when it is assembled
//! ([`crate::mesh::Population::read`]); a fit whose parts do not fit is refused when it starts
//! ([`crate::mfa::aecm::Fit::new`]). Both errors say the size, the budget and what to do.

use crate::error::{Error, Result};

const KIB: u64 = 1024;
const MIB: u64 = 1024 * KIB;
const GIB: u64 = 1024 * MIB;

/// Default budget in wasm32: 1 GiB.
pub const WASM_BUDGET_BYTES: u64 = GIB;
/// Default native budget: 8 GiB (override with `POSEMFA_MEMORY_BUDGET`).
pub const NATIVE_BUDGET_BYTES: u64 = 8 * GIB;

/// Bytes per (vertex, shape) for the coordinates at the peak (see the module documentation): 4 x 12 (f32).
pub const COORDINATE_BYTES: u64 = 48;

/// Upper estimate, in bytes, of the working set of a fit of `n_vertices` x `n_shapes` with at most `parts`
/// components in any stage. Saturates instead of overflowing (wasm32's usize is 32 bits).
pub fn estimate_bytes(n_vertices: usize, n_shapes: usize, parts: usize) -> u64 {
    let (nv, ns, m) = (n_vertices as u64, n_shapes as u64, parts.max(1) as u64);
    let coordinates = nv.saturating_mul(ns).saturating_mul(COORDINATE_BYTES);
    let responsibilities = nv.saturating_mul(m).saturating_mul(8);
    let per_vertex = nv.saturating_mul(128);
    let components = m.saturating_mul(ns).saturating_mul(8 * 49);
    coordinates.saturating_add(responsibilities).saturating_add(per_vertex).saturating_add(components)
}

/// The most components a fit with these settings can hold at once: `parts`, times `max_subparts` when the
/// refinement runs (each coarse part may be split that many ways), never more than the vertices.
pub fn max_components(parts: usize, refine: bool, max_subparts: usize, n_vertices: usize) -> usize {
    let m = if refine { parts.saturating_mul(max_subparts.max(1)) } else { parts };
    m.min(n_vertices.max(1)).max(1)
}

/// The memory budget of a fit in bytes: [`WASM_BUDGET_BYTES`] in wasm32; natively [`NATIVE_BUDGET_BYTES`]
/// unless `POSEMFA_MEMORY_BUDGET` says otherwise.
pub fn budget_bytes() -> Result<u64> {
    #[cfg(target_arch = "wasm32")]
    {
        Ok(WASM_BUDGET_BYTES)
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        match std::env::var("POSEMFA_MEMORY_BUDGET") {
            Ok(text) => parse_size(&text).ok_or_else(|| {
                Error::Params(format!(
                    "POSEMFA_MEMORY_BUDGET = {text:?} is not a size; write bytes or a number with K, M or G \
                     (e.g. 16G), or unset it for the default of 8G"
                ))
            }),
            Err(_) => Ok(NATIVE_BUDGET_BYTES),
        }
    }
}

/// "123", "500M", "16G", "1.5g", "64k" (units of 1024) -> bytes. None for anything else, 0 or overflow.
pub fn parse_size(text: &str) -> Option<u64> {
    let t = text.trim();
    let (number, unit) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let scale = match unit {
        'B' => 1,
        'K' => KIB,
        'M' => MIB,
        'G' => GIB,
        _ => return None,
    };
    let value: f64 = number.trim().parse().ok()?;
    let bytes = value * scale as f64;
    (bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64).then_some(bytes as u64)
}

/// A size for a message: "1.50 GiB", "12.0 MiB", "900 bytes".
pub fn show_bytes(b: u64) -> String {
    if b >= GIB {
        format!("{:.2} GiB", b as f64 / GIB as f64)
    } else if b >= MIB {
        format!("{:.1} MiB", b as f64 / MIB as f64)
    } else if b >= KIB {
        format!("{:.1} KiB", b as f64 / KIB as f64)
    } else {
        format!("{b} bytes")
    }
}

/// Upper estimate of what [`crate::mesh::subdivide::subdivide`] needs for `levels` midpoint subdivisions of a
/// mesh of `n_vertices` and `n_faces` in `n_shapes` poses: (vertices of the result, bytes). Each level adds at most
/// one vertex per edge and an edge belongs to at most 3 triangles' worth of splits, so the result has at most
/// V + F (4^L - 1) vertices; while a level is made, two poses' worth of f64 coordinates per pose (the old and the
/// new), and the faces (12 bytes each, 4^L of them per original face).
pub fn subdivision_bytes(n_vertices: usize, n_faces: usize, n_shapes: usize, levels: usize) -> (f64, f64) {
    let grow = 4f64.powi(levels.min(32) as i32);
    let vertices = n_vertices as f64 + n_faces as f64 * (grow - 1.0);
    (vertices, 2.0 * 24.0 * vertices * n_shapes as f64 + 12.0 * n_faces as f64 * grow)
}

/// Err([`Error::Request`]) when [`subdivision_bytes`] is more than `budget`; the message gives the size, the
/// budget and what to do.
pub fn check_subdivision(n_vertices: usize, n_faces: usize, n_shapes: usize, levels: usize, budget: u64) -> Result<()> {
    let (vertices, need) = subdivision_bytes(n_vertices, n_faces, n_shapes, levels);
    if need <= budget as f64 {
        return Ok(());
    }
    let shown = if need >= u64::MAX as f64 {
        "more than 16 EiB".to_string()
    } else {
        format!("about {}", show_bytes(need as u64))
    };
    Err(Error::Request(format!(
        "subdividing {levels} times gives up to {vertices:.0} vertices in each of {n_shapes} poses, {shown}, more than \
         the memory budget of {}; ask for fewer levels (or raise POSEMFA_MEMORY_BUDGET if this machine has the memory)",
        show_bytes(budget)
    )))
}

/// Err([`Error::Data`]) when a fit of `n_vertices` x `n_shapes` with at most `parts` components needs more
/// than `budget` bytes. The message gives the estimate, the budget and what to change.
pub fn check(n_vertices: usize, n_shapes: usize, parts: usize, budget: u64) -> Result<()> {
    let need = estimate_bytes(n_vertices, n_shapes, parts);
    if need <= budget {
        return Ok(());
    }
    let knob = if cfg!(target_arch = "wasm32") {
        "the command-line program has a budget of 8 GiB (and POSEMFA_MEMORY_BUDGET to change it)"
    } else {
        "or raise the budget with POSEMFA_MEMORY_BUDGET (e.g. POSEMFA_MEMORY_BUDGET=32G) if this machine has the \
         memory"
    };
    let (parts_text, fewer_parts) = if parts > 1 {
        (format!(" with up to {parts} parts"), " or fewer parts (parts, or max_subparts of the refinement)")
    } else {
        (String::new(), "")
    };
    Err(Error::Data(format!(
        "{n_vertices} vertices x {n_shapes} shapes{parts_text} needs about {} of memory, more than the budget of \
         {}; use fewer vertices (decimate the mesh the same way in every pose), fewer poses{fewer_parts}; {knob}",
        show_bytes(need),
        show_bytes(budget),
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimate_grows_with_each_size_and_saturates() {
        let base = estimate_bytes(1000, 10, 11);
        assert!(estimate_bytes(2000, 10, 11) > base);
        assert!(estimate_bytes(1000, 20, 11) > base);
        assert!(estimate_bytes(1000, 10, 22) > base);
        // 1000 x 10 x 48 + 1000 x 11 x 8 + 128 000 + 11 x 10 x 392
        assert_eq!(base, 480_000 + 88_000 + 128_000 + 43_120);
        assert_eq!(estimate_bytes(usize::MAX, usize::MAX, usize::MAX), u64::MAX);
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("123"), Some(123));
        assert_eq!(parse_size(" 16G "), Some(16 * GIB));
        assert_eq!(parse_size("1.5g"), Some(3 * GIB / 2));
        assert_eq!(parse_size("500M"), Some(500 * MIB));
        assert_eq!(parse_size("64k"), Some(64 * KIB));
        for bad in ["", "G", "-1G", "0", "1T", "nanG", "1e30G", "12 GB"] {
            assert_eq!(parse_size(bad), None, "{bad}");
        }
    }

    #[test]
    fn max_components_caps() {
        assert_eq!(max_components(11, true, 6, 10_000), 66);
        assert_eq!(max_components(11, false, 6, 10_000), 11);
        assert_eq!(max_components(11, true, 6, 20), 20);
        assert_eq!(max_components(0, true, 0, 0), 1);
    }
}
