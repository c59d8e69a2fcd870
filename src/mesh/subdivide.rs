//! Midpoint subdivision of a registered population: every triangle split in four at its edge midpoints, the same
//! split in every pose, so the finer population stays registered (high-resolution test data: horse-gallop
//! once subdivided is about 34 k vertices x 49 poses).
//!
//! Triangle (a, b, c) with edge midpoints m_ab, m_bc, m_ca becomes (a, m_ab, m_ca), (m_ab, b, m_bc),
//! (m_ca, m_bc, c) and (m_ab, m_bc, m_ca): every new triangle keeps the orientation of the one it came from.
//! An edge shared by two triangles gets one midpoint vertex, so a closed mesh stays closed and its Euler
//! characteristic V - E + F is unchanged. New vertices are numbered after the old ones, in the order their
//! edges are first met in the face list, so vertex j < n of the result is vertex j of the input.

use super::Population;
use crate::error::{Error, Result};
use std::collections::HashMap;

/// The connectivity of one subdivision step: the new triangles and, for every new vertex n + e, the edge
/// `edges[e]` whose midpoint it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Midpoints {
    /// Vertex count before the step.
    pub n_vertices: usize,
    /// Four triangles per input triangle, in input order.
    pub faces: Vec<[u32; 3]>,
    /// The edges (smaller index first) whose midpoints are the new vertices.
    pub edges: Vec<[u32; 2]>,
}

impl Midpoints {
    /// One step on `faces` of a mesh with `n_vertices` vertices. Errors if a face names a vertex that does not
    /// exist, or if the result would not fit 32-bit vertex indices.
    pub fn of(faces: &[[u32; 3]], n_vertices: usize) -> Result<Midpoints> {
        let bad = |message: String| Error::Population { file: "(subdivision)".into(), message };
        if let Some((f, t)) = faces.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= n_vertices)) {
            return Err(bad(format!(
                "triangle {} names vertex {} of a mesh of {n_vertices}",
                f + 1,
                t.iter().max().unwrap_or(&0) + 1
            )));
        }
        let mut index: HashMap<[u32; 2], u32> = HashMap::with_capacity(faces.len() * 3 / 2 + 1);
        let mut edges: Vec<[u32; 2]> = Vec::with_capacity(faces.len() * 3 / 2 + 1);
        let mut out = Vec::with_capacity(faces.len() * 4);
        for &[a, b, c] in faces {
            let mut mid = |p: u32, q: u32| -> Result<u32> {
                let key = if p < q { [p, q] } else { [q, p] };
                if let Some(&m) = index.get(&key) {
                    return Ok(m);
                }
                let m = u32::try_from(n_vertices + edges.len()).map_err(|_| {
                    bad(format!(
                        "{} vertices after subdivision: more than 32-bit indices hold",
                        n_vertices + edges.len()
                    ))
                })?;
                index.insert(key, m);
                edges.push(key);
                Ok(m)
            };
            let (ab, bc, ca) = (mid(a, b)?, mid(b, c)?, mid(c, a)?);
            out.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        Ok(Midpoints { n_vertices, faces: out, edges })
    }

    /// Vertex count after the step.
    pub fn n_vertices_after(&self) -> usize {
        self.n_vertices + self.edges.len()
    }

    /// One pose's positions after the step: the old vertices, then the midpoints.
    pub fn apply(&self, positions: impl ExactSizeIterator<Item = [f64; 3]>) -> Vec<[f64; 3]> {
        debug_assert_eq!(positions.len(), self.n_vertices);
        let mut out = Vec::with_capacity(self.n_vertices_after());
        out.extend(positions);
        for &[p, q] in &self.edges {
            let (p, q) = (out[p as usize], out[q as usize]);
            out.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 0.5 * (p[2] + q[2])]);
        }
        out
    }
}

/// The population with every triangle split in four, `levels` times, in its original units (each pose's coordinates
/// mapped back through the population's normalization), with the same names. Its shapes and faces, for writing out;
/// [`Population::read`] of them ([`crate::mesh::Sources::Meshes`]) gives the finer population. Refused before anything
/// is allocated when the result could need more than `budget` bytes ([`crate::memory::subdivision_bytes`]: each level
/// multiplies the triangles by 4).
pub fn subdivide(pop: &Population, levels: usize, budget: u64) -> Result<(Vec<[u32; 3]>, Vec<Vec<[f64; 3]>>)> {
    crate::memory::check_subdivision(pop.n_vertices(), pop.faces.len(), pop.n_shapes(), levels, budget)?;
    let norm = pop.normalization;
    let mut faces = pop.faces.to_vec();
    let mut shapes: Vec<Vec<[f64; 3]>> =
        pop.shapes().map(|s| s.iter().map(|p| norm.to_original(p)).collect()).collect();
    for _ in 0..levels {
        let step = Midpoints::of(&faces, shapes.first().map_or(0, Vec::len))?;
        shapes = shapes.iter().map(|s| step.apply(s.iter().copied())).collect();
        faces = step.faces;
    }
    Ok((faces, shapes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron, outward-facing.
    fn tetra() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (v, f)
    }

    fn normal(p: &[[f64; 3]], t: [u32; 3]) -> [f64; 3] {
        let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
    }

    fn euler(n_vertices: usize, faces: &[[u32; 3]]) -> i64 {
        let mut edges = std::collections::HashSet::new();
        for t in faces {
            for k in 0..3 {
                let (p, q) = (t[k], t[(k + 1) % 3]);
                edges.insert((p.min(q), p.max(q)));
            }
        }
        n_vertices as i64 - edges.len() as i64 + faces.len() as i64
    }

    #[test]
    fn a_closed_mesh_gets_one_midpoint_per_edge_and_keeps_its_euler_characteristic() {
        let (v, f) = tetra();
        let step = Midpoints::of(&f, v.len()).unwrap();
        assert_eq!(step.edges.len(), 6);
        assert_eq!(step.n_vertices_after(), 10);
        assert_eq!(step.faces.len(), 16);
        assert_eq!(euler(10, &step.faces), euler(4, &f));
        assert_eq!(euler(10, &step.faces), 2);
        // every edge of the result is shared by exactly two triangles (still closed, still manifold)
        let mut uses = HashMap::new();
        for t in &step.faces {
            for k in 0..3 {
                let (p, q) = (t[k], t[(k + 1) % 3]);
                *uses.entry((p.min(q), p.max(q))).or_insert(0) += 1;
            }
        }
        assert!(uses.values().all(|&u| u == 2), "{uses:?}");
    }

    #[test]
    fn new_triangles_face_the_way_their_parent_did_and_cover_its_area() {
        let (v, f) = tetra();
        let step = Midpoints::of(&f, v.len()).unwrap();
        let p = step.apply(v.iter().copied());
        for (k, &parent) in f.iter().enumerate() {
            let n = normal(&v, parent);
            let mut area = 0.0;
            for &child in &step.faces[4 * k..4 * k + 4] {
                let c = normal(&p, child);
                let dot = n[0] * c[0] + n[1] * c[1] + n[2] * c[2];
                assert!(dot > 0.0, "triangle {child:?} of {parent:?} is flipped");
                area += c.iter().map(|x| x * x).sum::<f64>().sqrt();
            }
            let whole = n.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((area - whole).abs() < 1e-12 * whole, "{area} vs {whole}");
        }
    }

    #[test]
    fn old_vertices_stay_and_new_ones_are_midpoints_in_every_pose() {
        let (v, f) = tetra();
        let step = Midpoints::of(&f, v.len()).unwrap();
        // a second pose: the tetrahedron turned and moved (a midpoint of a rigid motion is the moved midpoint)
        let moved: Vec<[f64; 3]> = v.iter().map(|p| [3.0 - p[1], 2.0 + p[0], p[2] - 1.0]).collect();
        for pose in [&v, &moved] {
            let p = step.apply(pose.iter().copied());
            assert_eq!(&p[..4], &pose[..]);
            for (e, &[a, b]) in step.edges.iter().enumerate() {
                let (a, b) = (pose[a as usize], pose[b as usize]);
                for d in 0..3 {
                    assert_eq!(p[4 + e][d], 0.5 * (a[d] + b[d]));
                }
            }
        }
    }

    #[test]
    fn a_face_naming_a_missing_vertex_is_refused_by_number() {
        let e = Midpoints::of(&[[0, 1, 2], [0, 2, 7]], 3).unwrap_err().to_string();
        assert!(e.contains("triangle 2") && e.contains("vertex 8"), "{e}");
    }

    #[test]
    fn a_population_subdivided_twice_in_original_units() {
        let (v, f) = tetra();
        let moved: Vec<[f64; 3]> = v.iter().map(|p| [10.0 * p[0] + 5.0, 10.0 * p[2], -10.0 * p[1]]).collect();
        let pop = Population::new(crate::mesh::Sources::Meshes(vec![
            (
                "a.obj".into(),
                crate::mesh::Mesh {
                    positions: v.iter().map(|p| [10.0 * p[0], 10.0 * p[1], 10.0 * p[2]]).collect(),
                    faces: f.clone(),
                },
            ),
            ("b.obj".into(), crate::mesh::Mesh { positions: moved, faces: f.clone() }),
        ]))
        .unwrap();
        let (faces, shapes) = subdivide(&pop, 2, u64::MAX).unwrap();
        assert_eq!(faces.len(), 4 * 4 * f.len());
        assert_eq!(shapes.len(), 2);
        // V - E + F = 2 with F = 64 and E = 3F/2 = 96: 34 vertices
        assert_eq!(shapes[0].len(), 34);
        assert!((shapes[0][1][0] - 10.0).abs() < 1e-5, "{:?}", shapes[0][1]);
        let finer = Population::new(crate::mesh::Sources::Meshes(
            shapes
                .into_iter()
                .zip(["a.obj", "b.obj"])
                .map(|(s, n)| (n.to_string(), crate::mesh::Mesh { positions: s, faces: faces.clone() }))
                .collect(),
        ))
        .unwrap();
        assert_eq!(finer.n_vertices(), 34);
        // a result larger than the budget is refused by its size, before anything is made
        let e = subdivide(&pop, 4, 100_000).unwrap_err().to_string();
        assert!(e.contains("subdividing 4 times") && e.contains("fewer levels"), "{e}");
        assert!(subdivide(&pop, 1, 100_000).is_ok());
    }
}
