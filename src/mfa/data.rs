//! The data vectors h_j (vertex j stacked over the shapes), centred, in the E-step's blocked layout.
//!
//! Each shape is centred on its centroid inside AECM (the expanded Woodbury form loses digits far from the
//! origin); [`Data::offsets`] maps translations back. The values are stored once, in f32 (12 bytes per vertex
//! and shape, see [`crate::memory`]), in the layout the E-step streams ([`Layout`]: blocks of
//! [`LANES`] vertices close in the first shape, the shapes in farthest-first order), and read as f64 by
//! everyone else ([`Data::point`], [`Data::vertex`], [`Data::vertex_into`]): every computation on them is f64,
//! on the same numbers wherever they are read. The population's coordinates are f32 in the unit box; centred,
//! they are rounded once more to f32 (at most 6e-8 in the unit box).

use super::component::Component;
pub use super::estep::LANES;
use crate::geometry::Vec3;
use crate::mesh::Population;

/// The data vectors regrouped for the E-step: blocks of [`LANES`] vertices that are close in the first shape
/// (Morton order), stored structure-of-arrays, `h[(b * n_s + t) * 3 + c][l]` = coordinate c of vertex
/// `idx[b][l]` in shape `order[t]`. The last block repeats its last vertex in the unused lanes (`valid[b]` are
/// real). Nearby vertices mostly belong to the same parts, so a block shares its pruning decisions. The shapes
/// are in farthest-first order (each next shape the one least like those before it), so that the early-exit
/// bound over the first few shapes already sees most of the motion.
#[derive(Debug)]
pub struct Layout {
    pub h: Vec<[f32; LANES]>,
    pub idx: Vec<[u32; LANES]>,
    pub valid: Vec<u8>,
    /// Shapes in layout order (t -> shape), and each shape's place in it (shape -> t).
    pub order: Vec<usize>,
    rank: Vec<usize>,
    /// Where vertex j is: block * LANES + lane.
    slot: Vec<u32>,
}

impl Layout {
    pub fn n_blocks(&self) -> usize {
        self.idx.len()
    }
}

#[derive(Debug, Clone)]
pub struct Data {
    pub n_vertices: usize,
    pub n_shapes: usize,
    /// The values, shared by clones and by the E-step's [`super::estep::Blocked`].
    pub layout: std::sync::Arc<Layout>,
    /// Centroid of every shape that was subtracted (unit-box coordinates).
    pub offsets: Vec<Vec3>,
}

/// h_j of one vertex: its n_s points, read as f64.
#[derive(Debug, Clone, Copy)]
pub struct Vertex<'a> {
    data: &'a Data,
    j: usize,
}

impl Vertex<'_> {
    /// The point in shape i.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Vec3 {
        self.data.point(self.j, i)
    }

    pub fn len(&self) -> usize {
        self.data.n_shapes
    }

    pub fn is_empty(&self) -> bool {
        self.data.n_shapes == 0
    }

    pub fn iter(&self) -> impl ExactSizeIterator<Item = Vec3> + '_ {
        (0..self.data.n_shapes).map(|i| self.get(i))
    }

    /// A copy in f64.
    pub fn to_vec(&self) -> Vec<Vec3> {
        self.iter().collect()
    }
}

/// Most vertices the farthest-first shape order looks at.
const ORDER_SAMPLE: usize = 4096;

impl Data {
    pub fn from_population(pop: &Population) -> Data {
        let all: Vec<usize> = (0..pop.n_vertices()).collect();
        Data::from_population_subset(pop, &all)
    }

    /// Data from f64 values laid out `h[(j * n_s + i) * 3 + c]` (each rounded to f32 as stored): for vectors other
    /// than the population's (residuals) and for tests.
    pub fn from_f64(n_vertices: usize, n_shapes: usize, h: &[f64], offsets: Vec<Vec3>) -> Data {
        assert_eq!(h.len(), n_vertices * n_shapes * 3, "h needs 3 values per vertex and shape");
        let at = |j: usize, i: usize| {
            let a = (j * n_shapes + i) * 3;
            [h[a] as f32, h[a + 1] as f32, h[a + 2] as f32]
        };
        Data::build(n_vertices, n_shapes, offsets, &at)
    }

    /// The centroid of the listed vertices in every shape (the offsets [`Data::from_population_subset`] takes).
    pub fn centroids(pop: &Population, vertices: &[usize]) -> Vec<crate::geometry::Vec3> {
        let n = vertices.len().max(1) as f64;
        pop.shapes()
            .map(|shape| {
                let mut c = [0.0; 3];
                for &j in vertices {
                    let p = shape.get(j);
                    for d in 0..3 {
                        c[d] += p[d];
                    }
                }
                c.map(|v| v / n)
            })
            .collect()
    }

    /// Only the listed vertices (in that order), centred on their own centroid (in f64, then stored in f32).
    /// Read from the population straight into the layout (no other copy).
    pub fn from_population_subset(pop: &Population, vertices: &[usize]) -> Data {
        let ns = pop.n_shapes();
        let offsets = Data::centroids(pop, vertices);
        let at = |j: usize, i: usize| {
            let (p, o) = (pop.point(i, vertices[j]), offsets[i]);
            [(p[0] - o[0]) as f32, (p[1] - o[1]) as f32, (p[2] - o[2]) as f32]
        };
        let layout = Data::lay_out(vertices.len(), ns, &at);
        Data { n_vertices: vertices.len(), n_shapes: ns, layout, offsets }
    }

    fn build(nv: usize, ns: usize, offsets: Vec<Vec3>, at: &dyn Fn(usize, usize) -> [f32; 3]) -> Data {
        Data { n_vertices: nv, n_shapes: ns, layout: Data::lay_out(nv, ns, at), offsets }
    }

    /// The layout of the values `at(j, i)` (vertex j in shape i).
    fn lay_out(nv: usize, ns: usize, at: &dyn Fn(usize, usize) -> [f32; 3]) -> std::sync::Arc<Layout> {
        let wide = |j: usize, i: usize| {
            let p = at(j, i);
            [p[0] as f64, p[1] as f64, p[2] as f64]
        };
        let vertices = morton_order(nv, &wide);
        let order = farthest_first_shapes(nv, ns, &wide);
        let mut rank = vec![0; ns];
        for (t, &i) in order.iter().enumerate() {
            rank[i] = t;
        }
        let nb = nv.div_ceil(LANES);
        let mut idx = Vec::with_capacity(nb);
        let mut valid = Vec::with_capacity(nb);
        let mut slot = vec![0u32; nv];
        // written in order, one lane vector at a time (not zeroed first: in wasm the allocator clears reused memory
        // for a zeroed allocation)
        let mut h: Vec<[f32; LANES]> = Vec::with_capacity(nb * ns * 3);
        for (b, chunk) in vertices.chunks(LANES).enumerate() {
            let ids: [usize; LANES] = std::array::from_fn(|l| chunk[l.min(chunk.len() - 1)]);
            for &i in &order {
                let p: [[f32; 3]; LANES] = std::array::from_fn(|l| at(ids[l], i));
                for c in 0..3 {
                    h.push(std::array::from_fn(|l| p[l][c]));
                }
            }
            for (l, &j) in chunk.iter().enumerate() {
                slot[j] = (b * LANES + l) as u32;
            }
            idx.push(ids.map(|j| j as u32));
            valid.push(chunk.len() as u8);
        }
        std::sync::Arc::new(Layout { h, idx, valid, order, rank, slot })
    }

    /// Vertex j in shape i.
    #[inline(always)]
    pub fn point(&self, j: usize, i: usize) -> Vec3 {
        let layout = &*self.layout;
        let s = layout.slot[j] as usize;
        let at = ((s / LANES) * self.n_shapes + layout.rank[i]) * 3;
        let l = s % LANES;
        [layout.h[at][l] as f64, layout.h[at + 1][l] as f64, layout.h[at + 2][l] as f64]
    }

    /// Where vertex j is stored: its block and lane ([`Layout`]).
    #[inline(always)]
    pub fn block_lane(&self, j: usize) -> (usize, usize) {
        let s = self.layout.slot[j] as usize;
        (s / LANES, s % LANES)
    }

    /// h_j.
    #[inline]
    pub fn vertex(&self, j: usize) -> Vertex<'_> {
        Vertex { data: self, j }
    }

    /// h_j as n_s points in f64, written into `buf` (reused between calls).
    #[inline]
    pub fn vertex_into<'b>(&self, j: usize, buf: &'b mut Vec<Vec3>) -> &'b [Vec3] {
        buf.clear();
        buf.extend(self.vertex(j).iter());
        buf
    }

    /// h_j as 3 n_s values (shape by shape, x y z) in f32 as stored, written into `buf`.
    #[inline]
    pub fn row_into<'b>(&self, j: usize, buf: &'b mut Vec<f32>) -> &'b [f32] {
        let layout = &*self.layout;
        let s = layout.slot[j] as usize;
        let (b, l) = (s / LANES, s % LANES);
        buf.clear();
        for i in 0..self.n_shapes {
            let at = (b * self.n_shapes + layout.rank[i]) * 3;
            buf.extend_from_slice(&[layout.h[at][l], layout.h[at + 1][l], layout.h[at + 2][l]]);
        }
        buf
    }

    /// Mean squared distance of the vertices from their shape's centroid (unit box), over every vertex and
    /// shape: [`crate::mesh::Population::mean_squared_radius`] of the vertices held.
    pub fn mean_squared_radius(&self) -> f64 {
        let sum: f64 = (0..self.n_vertices)
            .map(|j| self.vertex(j).iter().map(|p| p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sum::<f64>())
            .sum();
        sum / (self.n_vertices * self.n_shapes).max(1) as f64
    }

    /// The first vertex and shape (0-based) with a non-finite coordinate, and that coordinate.
    pub fn first_non_finite(&self) -> Option<(usize, usize, f64)> {
        // one pass over the stored values first (every lane holds a vertex's value, the last block's spare lanes
        // a copy of its last vertex's): vertex by vertex only when one is not finite
        if self.layout.h.iter().flatten().all(|v| v.is_finite()) {
            return None;
        }
        (0..self.n_vertices).find_map(|j| {
            (0..self.n_shapes).find_map(|i| self.point(j, i).into_iter().find(|v| !v.is_finite()).map(|v| (j, i, v)))
        })
    }
}

/// Shapes in farthest-first order: shape 0, then repeatedly the shape whose smallest summed squared vertex
/// distance to the shapes already taken is largest, for as many shapes as the early-exit checks look at (8);
/// the rest follow in their own order. The distances are summed over at most [`ORDER_SAMPLE`] evenly spaced
/// vertices (the order only decides how early the bounds prune; every order gives the same E-step). `at` gives
/// stored f32 values, widened.
fn farthest_first_shapes(nv: usize, ns: usize, at: &dyn Fn(usize, usize) -> Vec3) -> Vec<usize> {
    let stride = nv.div_ceil(ORDER_SAMPLE).max(1);
    // the sampled vertices of every shape, read once (each shape's distances are summed many times); `at`
    // gives stored f32 values widened, so they are kept in f32 exactly
    let sampled: Vec<Vec<[f32; 3]>> =
        (0..ns).map(|i| (0..nv).step_by(stride).map(|j| at(j, i).map(|c| c as f32)).collect()).collect();
    let dist = |a: usize, b: usize| -> f64 {
        sampled[a]
            .iter()
            .zip(&sampled[b])
            .map(|(va, vb)| {
                let (va, vb) = (va.map(f64::from), vb.map(f64::from));
                let d = [va[0] - vb[0], va[1] - vb[1], va[2] - vb[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
            })
            .sum()
    };
    if ns == 0 {
        return Vec::new();
    }
    let mut order = vec![0];
    let mut taken = vec![false; ns];
    taken[0] = true;
    let mut nearest: Vec<f64> = (0..ns).map(|i| if i == 0 { -1.0 } else { dist(0, i) }).collect();
    let chosen = ns.min(super::estep::CHECK_AFTER[super::estep::CHECK_AFTER.len() - 1]);
    while order.len() < chosen {
        let next = (0..ns).filter(|&i| !taken[i]).fold(None, |a: Option<usize>, i| match a {
            Some(b) if nearest[b] >= nearest[i] => Some(b),
            _ => Some(i),
        });
        let Some(next) = next else { break };
        order.push(next);
        taken[next] = true;
        if order.len() < chosen {
            for i in 0..ns {
                if !taken[i] {
                    nearest[i] = nearest[i].min(dist(next, i));
                }
            }
        }
    }
    order.extend((0..ns).filter(|&i| !taken[i]));
    order
}

/// Vertices sorted along a Z-order curve of their positions in the first shape (10 bits per axis).
fn morton_order(nv: usize, at: &dyn Fn(usize, usize) -> Vec3) -> Vec<usize> {
    if nv == 0 {
        return Vec::new();
    }
    let first: Vec<[f64; 3]> = (0..nv).map(|j| at(j, 0)).collect();
    let (lo, hi) = crate::geometry::bounds(&first);
    let spread = |x: u32| -> u64 {
        let mut v = 0u64;
        for bit in 0..10 {
            v |= (((x >> bit) & 1) as u64) << (3 * bit);
        }
        v
    };
    let mut keyed: Vec<(u64, usize)> = (0..nv)
        .map(|j| {
            let p = first[j];
            let mut key = 0u64;
            for c in 0..3 {
                let w = hi[c] - lo[c];
                let t =
                    if w > 0.0 && p[c].is_finite() { ((p[c] - lo[c]) / w * 1023.0).clamp(0.0, 1023.0) } else { 0.0 };
                key |= spread(t as u32) << c;
            }
            (key, j)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, j)| j).collect()
}

/// Components with unit-box translations moved into the centred frame of `data`.
pub fn to_frame(data: &Data, comps: &[Component]) -> Vec<Component> {
    shifted(comps, &data.offsets, -1.0)
}

/// Components in the centred frame of `data` moved back to unit-box translations (the inverse of [`to_frame`]).
pub fn from_frame(data: &Data, comps: &[Component]) -> Vec<Component> {
    shifted(comps, &data.offsets, 1.0)
}

/// One component with unit-box translations moved to the centred frame of `data` ([`to_frame`] of one, without
/// a copy).
pub fn component_to_frame(data: &Data, mut c: Component) -> Component {
    shift(&mut c, &data.offsets, -1.0);
    c
}

/// Adds `sign` x the shape's offset to every translation of `c`.
fn shift(c: &mut Component, offsets: &[crate::geometry::Vec3], sign: f64) {
    for (t, o) in c.translations.iter_mut().zip(offsets) {
        *t = [t[0] + sign * o[0], t[1] + sign * o[1], t[2] + sign * o[2]];
    }
}

/// Copies of `comps` with `sign` x the shape's offset added to every translation.
fn shifted(comps: &[Component], offsets: &[crate::geometry::Vec3], sign: f64) -> Vec<Component> {
    comps
        .iter()
        .map(|c| {
            let mut c = c.clone();
            shift(&mut c, offsets, sign);
            c
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first non-finite value in (vertex, shape) order, found whatever block and lane it is stored in, and
    /// none in finite data.
    #[test]
    fn the_first_non_finite_value_by_vertex_then_shape() {
        let (nv, ns) = (11, 3);
        let h: Vec<f64> = (0..nv * ns * 3).map(|a| (a as f64 * 0.37).sin()).collect();
        assert_eq!(Data::from_f64(nv, ns, &h, vec![[0.0; 3]; ns]).first_non_finite(), None);
        let at = |j: usize, i: usize, c: usize| (j * ns + i) * 3 + c;
        let mut bad = h.clone();
        bad[at(9, 0, 2)] = f64::INFINITY;
        bad[at(7, 2, 1)] = f64::NAN;
        bad[at(7, 1, 0)] = f64::NEG_INFINITY;
        let found = Data::from_f64(nv, ns, &bad, vec![[0.0; 3]; ns]).first_non_finite();
        assert_eq!(found.map(|(j, i, v)| (j, i, v)), Some((7, 1, f64::NEG_INFINITY)));
    }
}
