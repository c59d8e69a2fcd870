//! A registered coarse mesh of a large population, on which the parts are decided ([`super::hierarchy`]): the patches
//! of [`super::patches::seeded_patches`] at about `target` vertices (farthest-point seeds by edge hops, every vertex to
//! its nearest seed), each patch one coarse vertex. Hops, not the poses' edge lengths: the coarse mesh is then the same
//! whichever poses are given, and the decisions on it move less with one pose dropped (docs/decisions.md, "Figures
//! behind src/parts"). A coarse vertex is its seed, a vertex of the population, so its trajectory is a real one and the
//! coarse mesh is registered in every pose as the population is (no new positions are made). Its triangles are where
//! three patches meet on a triangle of the mesh; two patches that touch only along an edge get a triangle with a patch
//! next to both. It depends on the mesh's connectivity alone: not on the poses, their order, nor where the population
//! stands (no axis-aligned grid).
//!
//! A part is a union of patches there; [`CoarseMesh::to_fine`] gives every vertex its patch's label.

use super::patches::seeded_patches;
use crate::mesh::Population;

/// A population's coarse mesh (module doc).
pub struct CoarseMesh {
    /// The coarse population: the seeds' coordinates in every pose, the patches' triangles.
    pub pop: Population,
    /// The population's vertex of each coarse vertex (its patch's seed).
    pub seeds: Vec<usize>,
    /// The coarse vertex (patch) of each vertex of the population.
    pub patch: Vec<u32>,
}

impl CoarseMesh {
    /// The coarse mesh of about `target` vertices (fewer when the mesh has fewer vertices on its triangles).
    pub fn build(pop: &Population, target: usize) -> CoarseMesh {
        let (patch, seeds) = seeded_patches(pop, target, true);
        // per patch: the patches it shares an edge of the mesh with (and whether a triangle holds the pair), and
        // the triangles where three patches meet that it is the lowest of (the first of each three in the mesh's
        // order, as the mesh orients it). Small lists: a patch has a few neighbours, and in wasm a large block
        // the freed memory cannot hold grows the instance for good.
        let n = seeds.len();
        let mut around: Vec<Vec<(u32, bool)>> = vec![Vec::new(); n];
        let mut lowest_of: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
        let mut faces: Vec<[u32; 3]> = Vec::new();
        for f in pop.graph_faces().iter() {
            let p = f.map(|v| patch[v as usize]);
            for s in 0..3 {
                let (a, b) = (p[s], p[(s + 1) % 3]);
                if a != b {
                    for (x, y) in [(a, b), (b, a)] {
                        if !around[x as usize].iter().any(|e| e.0 == y) {
                            around[x as usize].push((y, false));
                        }
                    }
                }
            }
            if p[0] != p[1] && p[1] != p[2] && p[0] != p[2] {
                let mut key = p;
                key.sort_unstable();
                let list = &mut lowest_of[key[0] as usize];
                if !list.contains(&(key[1], key[2])) {
                    list.push((key[1], key[2]));
                    faces.push(p);
                }
            }
        }
        drop(lowest_of);
        for f in &faces {
            for s in 0..3 {
                let (a, b) = (f[s], f[(s + 1) % 3]);
                for (x, y) in [(a, b), (b, a)] {
                    if let Some(e) = around[x as usize].iter_mut().find(|e| e.0 == y) {
                        e.1 = true;
                    }
                }
            }
        }
        around.iter_mut().for_each(|x| x.sort_unstable());
        // a pair no triangle holds (in order of the pair): a triangle with the first patch (lowest id) next to
        // both, else a degenerate one, so that every pair of touching patches is an edge of the coarse mesh
        for a in 0..n as u32 {
            for &(b, held) in &around[a as usize] {
                if b <= a || held {
                    continue;
                }
                let next_to_b = &around[b as usize];
                let c = around[a as usize]
                    .iter()
                    .map(|e| e.0)
                    .find(|c| next_to_b.binary_search_by_key(c, |e| e.0).is_ok())
                    .unwrap_or(b);
                faces.push([a, b, c]);
            }
        }
        CoarseMesh { pop: pop.restricted(&seeds, faces), seeds, patch }
    }

    /// Every vertex's value from its patch's: `per_patch[patch[j]]` for each vertex j.
    pub fn to_fine<T: Copy>(&self, per_patch: &[T]) -> Vec<T> {
        self.patch.iter().map(|&p| per_patch[p as usize]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regular grid of `n x n` vertices in two poses (the second bent about its middle column).
    fn sheet(n: usize) -> Population {
        let mut faces = Vec::new();
        for r in 0..n - 1 {
            for c in 0..n - 1 {
                let v = (r * n + c) as u32;
                let n = n as u32;
                faces.push([v, v + 1, v + n]);
                faces.push([v + 1, v + n + 1, v + n]);
            }
        }
        let h = 1.0 / (n - 1) as f64;
        let flat: Vec<[f64; 3]> = (0..n * n).map(|j| [(j % n) as f64 * h, (j / n) as f64 * h, 0.0]).collect();
        let bent: Vec<[f64; 3]> = flat.iter().map(|p| if p[0] > 0.5 { [0.5, p[1], p[0] - 0.5] } else { *p }).collect();
        Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces,
            shapes: vec![flat, bent],
        })
        .unwrap()
    }

    #[test]
    fn the_coarse_mesh_is_made_of_real_vertices_and_stays_connected() {
        let pop = sheet(40);
        let coarse = CoarseMesh::build(&pop, 200);
        assert_eq!(coarse.seeds.len(), 200);
        assert_eq!(coarse.pop.n_vertices(), 200);
        // every coarse vertex is its seed, in every pose, to the bit
        for (c, &j) in coarse.seeds.iter().enumerate() {
            assert_eq!(coarse.patch[j] as usize, c, "a seed lies in its own patch");
            for i in 0..2 {
                assert_eq!(coarse.pop.point(i, c), pop.point(i, j));
            }
        }
        // one connected piece (no island beside the largest piece), as the sheet is, and no coarse vertex left
        // without a triangle
        let labels = vec![0u32; 200];
        assert_eq!(super::super::islands::island_count(&labels, &coarse.pop.faces), 0);
        let mut used = vec![false; 200];
        coarse.pop.faces.iter().flatten().for_each(|&v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u));
        // a patch's label goes to each of its vertices
        let ids: Vec<u32> = (0..200).collect();
        assert_eq!(coarse.to_fine(&ids), coarse.patch);
    }
}
