//! The data vectors h_j (vertex j stacked over the shapes), laid out for streaming, and centred.
//!
//! Layout: `h[(j * n_s + i) * 3 + c]`, i.e. each h_j is contiguous (3 n_s values), so the E-step and the
//! CM accumulations read one vertex at a time. Each shape is centred on its centroid inside AECM (the
//! expanded Woodbury form loses digits far from the origin); [`Data::offsets`] maps translations back.

use crate::geometry::Vec3;
use crate::mesh::Population;
use super::component::Component;

#[derive(Debug, Clone)]
pub struct Data {
    pub n_vertices: usize,
    pub n_shapes: usize,
    pub h: Vec<f64>,
    /// Centroid of every shape that was subtracted (unit-box coordinates).
    pub offsets: Vec<Vec3>,
}

impl Data {
    pub fn from_population(pop: &Population) -> Data {
        let all: Vec<usize> = (0..pop.n_vertices()).collect();
        Data::from_population_subset(pop, &all)
    }

    /// The centroid of the listed vertices in every shape (the offsets [`Data::from_population_subset`] takes).
    pub fn centroids(pop: &Population, vertices: &[usize]) -> Vec<crate::geometry::Vec3> {
        let n = vertices.len().max(1) as f64;
        pop.shapes
            .iter()
            .map(|shape| {
                let mut c = [0.0; 3];
                for &j in vertices {
                    for d in 0..3 {
                        c[d] += shape[j][d];
                    }
                }
                c.map(|v| v / n)
            })
            .collect()
    }

    /// Only the listed vertices (in that order), centred on their own centroid.
    pub fn from_population_subset(pop: &Population, vertices: &[usize]) -> Data {
        let ns = pop.n_shapes();
        let nv = vertices.len();
        let offsets = Data::centroids(pop, vertices);
        // written in order (not zeroed first: in wasm a zeroed allocation clears reused memory)
        let mut h = Vec::with_capacity(nv * ns * 3);
        for &j in vertices {
            for i in 0..ns {
                let p = pop.shapes[i][j];
                for d in 0..3 {
                    h.push(p[d] - offsets[i][d]);
                }
            }
        }
        Data { n_vertices: nv, n_shapes: ns, h, offsets }
    }

    /// h_j as n_s points.
    #[inline]
    pub fn vertex(&self, j: usize) -> &[Vec3] {
        let s = &self.h[j * self.n_shapes * 3..(j + 1) * self.n_shapes * 3];
        // SAFETY-free reinterpretation: [f64] of length 3 n_s as [[f64; 3]] of length n_s.
        let (chunks, rest) = s.as_chunks::<3>();
        debug_assert!(rest.is_empty());
        chunks
    }
}

/// Components with unit-box translations moved into the centred frame of `data`.
pub fn to_frame(data: &Data, comps: &[Component]) -> Vec<Component> {
    shifted(comps, &data.offsets, -1.0)
}

/// Components in the centred frame of `data` moved back to unit-box translations (the inverse of [`to_frame`]).
pub fn from_frame(data: &Data, comps: &[Component]) -> Vec<Component> {
    shifted(comps, &data.offsets, 1.0)
}

/// Copies of `comps` with `sign` x the shape's offset added to every translation.
fn shifted(comps: &[Component], offsets: &[crate::geometry::Vec3], sign: f64) -> Vec<Component> {
    comps
        .iter()
        .map(|c| {
            let mut c = c.clone();
            for (t, o) in c.translations.iter_mut().zip(offsets) {
                *t = [t[0] + sign * o[0], t[1] + sign * o[1], t[2] + sign * o[2]];
            }
            c
        })
        .collect()
}
