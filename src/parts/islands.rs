//! Every part one connected piece of the mesh.
//!
//! Labels by eq 20 are not spatially coherent (docs/method.md#item-7): a fit leaves small islands, a few
//! vertices of one part surrounded by another (up to 15 extra pieces on some meshes). A rig needs every part
//! to be one piece (its joints form a tree). An *island* is a connected component of one label in the mesh's
//! edge graph (two vertices are adjacent when a triangle has both) other than that label's largest one.
//!
//! [`connect_parts`] moves every island into the adjacent part (one with a mesh edge to it) that explains it
//! best: the highest summed log-density Σ_j log(π_k N(h_j; θ_k)) (eq 6, as eq 12 weighs it) of its vertices
//! under that part's component. Smallest islands first; repeated until none is left (each move removes at
//! least one piece, so it ends). Every label keeps its largest piece, so the part count does not change,
//! except that (when allowed) an island of at least [`SPLIT_FRACTION`] of its part's largest piece first
//! becomes a part of its own: a real piece that moves like the other (two legs that always move together).
//! The moved vertices get their latent image (eq 21) under the new part; the parts' parameters are kept as
//! fitted (the islands are a few boundary vertices whose responsibilities were split anyway).
//!
//! Vertices that no triangle uses have no neighbours and are left out of the count. A piece that touches no
//! other label (a separate mesh component that shares its label with another one) cannot be joined to
//! anything and stays counted.

use crate::mesh::Population;
use crate::mfa::result::Model;

/// Connected pieces of every label: `piece[v]` (u32::MAX for vertices in no triangle) and each piece's
/// (label, size).
fn pieces(labels: &[u32], faces: &[[u32; 3]]) -> (Vec<u32>, Vec<(u32, usize)>) {
    let n = labels.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut used = vec![false; n];
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let p = parent[x as usize];
            parent[x as usize] = parent[p as usize];
            x = p;
        }
        x
    }
    for f in faces {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            used[a as usize] = true;
            if labels[a as usize] == labels[b as usize] {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
    }
    let mut id = vec![u32::MAX; n];
    let mut piece = vec![u32::MAX; n];
    let mut out: Vec<(u32, usize)> = Vec::new();
    for v in 0..n {
        if !used[v] {
            continue;
        }
        let r = find(&mut parent, v as u32) as usize;
        if id[r] == u32::MAX {
            id[r] = out.len() as u32;
            out.push((labels[v], 0));
        }
        piece[v] = id[r];
        out[id[r] as usize].1 += 1;
    }
    (piece, out)
}

/// Number of islands: Σ over labels of (connected pieces - 1).
pub fn island_count(labels: &[u32], faces: &[[u32; 3]]) -> usize {
    let (_, p) = pieces(labels, faces);
    let mut labels_seen: Vec<u32> = p.iter().map(|x| x.0).collect();
    labels_seen.sort_unstable();
    labels_seen.dedup();
    p.len() - labels_seen.len()
}

/// What [`connect_labels`] did.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct IslandRepair {
    /// Islands that became parts of their own: the label each was split from, in the order of the new
    /// labels (the first new label is the old label count).
    pub split_from: Vec<u32>,
    /// Islands in the labels it was given.
    pub before: usize,
    /// Islands left (0 unless a piece touches no other label).
    pub after: usize,
    /// Vertices whose label changed.
    pub moved: usize,
}

/// Moves islands into adjacent labels until none is left (module doc). `score(vertex, label)` is how well a
/// label explains a vertex (higher is better); an island goes to the adjacent label with the highest sum.
/// With `split_fraction = Some(f)`, an island of at least f times its label's largest piece (and at least
/// `min_vertices`) first becomes a label of its own instead (a real piece: two limbs that move alike).
pub fn connect_labels(
    labels: &mut [u32],
    faces: &[[u32; 3]],
    score: &dyn Fn(usize, u32) -> f64,
    split_fraction: Option<f64>,
    min_vertices: usize,
) -> IslandRepair {
    let before = island_count(labels, faces);
    let mut moved = 0;
    let mut split_from = Vec::new();
    let mut first_new = u32::MAX;
    if let Some(frac) = split_fraction {
        let (piece, list) = pieces(labels, faces);
        let mut largest: std::collections::HashMap<u32, (usize, usize)> = std::collections::HashMap::new();
        for (i, &(l, size)) in list.iter().enumerate() {
            let e = largest.entry(l).or_insert((size, i));
            if size > e.0 {
                *e = (size, i);
            }
        }
        first_new = labels.iter().map(|&l| l + 1).max().unwrap_or(0);
        let mut next = first_new;
        let mut new_label = vec![u32::MAX; list.len()];
        for (i, &(l, size)) in list.iter().enumerate() {
            let (big, at) = largest[&l];
            if at != i && size >= min_vertices && size as f64 >= frac * big as f64 {
                new_label[i] = next;
                split_from.push(l);
                next += 1;
            }
        }
        for (v, &p) in piece.iter().enumerate() {
            if p != u32::MAX && new_label[p as usize] != u32::MAX {
                labels[v] = new_label[p as usize];
            }
        }
    }
    loop {
        let (piece, list) = pieces(labels, faces);
        // the largest piece of each label stays
        let mut keep: std::collections::HashMap<u32, (usize, u32)> = std::collections::HashMap::new();
        for (i, &(l, size)) in list.iter().enumerate() {
            let e = keep.entry(l).or_insert((size, i as u32));
            if size > e.0 {
                *e = (size, i as u32);
            }
        }
        let mut islands: Vec<u32> = (0..list.len() as u32).filter(|&i| keep[&list[i as usize].0].1 != i).collect();
        if islands.is_empty() {
            return IslandRepair { split_from, before, after: 0, moved };
        }
        islands.sort_by_key(|&i| (list[i as usize].1, i));
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); list.len()];
        for (v, &p) in piece.iter().enumerate() {
            if p != u32::MAX {
                members[p as usize].push(v);
            }
        }
        // labels adjacent to each piece, from the current labels
        let mut progress = false;
        let mut touched = vec![false; list.len()];
        let mut adjacency: Vec<std::collections::BTreeSet<u32>> = vec![Default::default(); list.len()];
        for f in faces.iter() {
            for e in 0..3 {
                let (a, b) = (f[e] as usize, f[(e + 1) % 3] as usize);
                if labels[a] != labels[b] {
                    adjacency[piece[a] as usize].insert(piece[b]);
                    adjacency[piece[b] as usize].insert(piece[a]);
                }
            }
        }
        for &i in &islands {
            // a neighbour that already moved this round changed its label: wait for the next round
            if adjacency[i as usize].iter().any(|&q| touched[q as usize]) {
                continue;
            }
            let candidates: std::collections::BTreeSet<u32> =
                adjacency[i as usize].iter().map(|&q| list[q as usize].0).collect();
            let best = candidates
                .iter()
                .map(|&l| {
                    // a split-off label scores as the label it was split from (same component)
                    let base = if l >= first_new { split_from[(l - first_new) as usize] } else { l };
                    (l, members[i as usize].iter().map(|&v| score(v, base)).sum::<f64>())
                })
                .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
            if let Some((l, _)) = best {
                for &v in &members[i as usize] {
                    labels[v] = l;
                }
                moved += members[i as usize].len();
                touched[i as usize] = true;
                progress = true;
            }
        }
        if !progress {
            return IslandRepair { split_from, before, after: island_count(labels, faces), moved };
        }
    }
}

/// An island of at least this fraction of its part's largest piece becomes a part of its own (when
/// [`connect_parts`] may add parts).
pub const SPLIT_FRACTION: f64 = 0.25;

/// Makes every part of `model` one connected piece of `pop`'s mesh (module doc): islands move to the
/// adjacent part whose component explains them best, and their latent images are recomputed under it.
/// With `new_parts`, an island of at least [`SPLIT_FRACTION`] of its part's largest piece (and at least
/// `min_vertices`) becomes a part of its own with a copy of the component (same motion; the mixing weight
/// is shared by vertex count), since it is a real piece that moves like the other one (two legs that always
/// move together), not a stray boundary vertex.
pub fn connect_parts(model: &mut Model, pop: &Population, new_parts: bool, min_vertices: usize) -> IslandRepair {
    let wbs: Vec<_> = model.parts.iter().map(|c| c.woodbury()).collect();
    let h = |v: usize| -> Vec<[f64; 3]> { pop.track(v) };
    let parts = &model.parts;
    let score = |v: usize, l: u32| parts[l as usize].log_weighted_density(&wbs[l as usize], &h(v));
    let old = model.labels.clone();
    let split = if new_parts { Some(SPLIT_FRACTION) } else { None };
    let repair = connect_labels(&mut model.labels, pop.graph_faces(), &score, split, min_vertices.max(1));
    let n_old = model.parts.len();
    for (n, &from) in repair.split_from.iter().enumerate() {
        let l = (n_old + n) as u32;
        let count = |x: u32| model.labels.iter().filter(|&&y| y == x).count() as f64;
        let (a, b) = (count(from), count(l));
        let mut c = model.parts[from as usize].clone();
        let w = c.weight;
        c.weight = w * b / (a + b);
        model.parts[from as usize].weight = w * a / (a + b);
        model.parts.push(c);
    }
    if crate::trace::enabled() {
        crate::trace_line!(
            "islands: {} before, {} after, {} vertices moved, {} new parts",
            repair.before,
            repair.after,
            repair.moved,
            repair.split_from.len()
        );
    }
    let same_component = |a: u32, b: u32| a == b || (b as usize >= n_old && repair.split_from[b as usize - n_old] == a);
    for (v, (&a, &b)) in old.iter().zip(&model.labels).enumerate() {
        if !same_component(a, b) {
            model.latent[v] = model.parts[b as usize].latent_image(&h(v));
        }
    }
    repair
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` columns of 2 vertices; triangles between neighbouring columns.
    fn strip(n: u32) -> Vec<[u32; 3]> {
        (0..n - 1).flat_map(|i| [[2 * i, 2 * i + 2, 2 * i + 1], [2 * i + 1, 2 * i + 2, 2 * i + 3]]).collect()
    }

    #[test]
    fn islands_are_counted_and_moved_to_the_best_neighbour() {
        let faces = strip(10);
        // columns: 0 0 0 1 0 0 2 2 1 1  -> label 0 has 2 pieces, label 1 has 2 pieces
        let cols = [0u32, 0, 0, 1, 0, 0, 2, 2, 1, 1];
        let mut labels: Vec<u32> = cols.iter().flat_map(|&c| [c, c]).collect();
        assert_eq!(island_count(&labels, &faces), 2);
        // label 1's island (column 3) is alone among 0s: only 0 is adjacent
        // label 0's island (columns 4-5) touches 1 (column 3) and 2 (column 6): the score prefers 2
        let score = |_: usize, l: u32| if l == 2 { 1.0 } else { 0.0 };
        let r = connect_labels(&mut labels, &faces, &score, None, 1);
        assert_eq!(r.before, 2);
        assert_eq!(r.after, 0);
        assert_eq!(island_count(&labels, &faces), 0);
        // column 3 (smallest island) went to 0 first, which joined 0's pieces; then nothing else is an island
        let got: Vec<u32> = labels.iter().step_by(2).copied().collect();
        assert_eq!(got, vec![0, 0, 0, 0, 0, 0, 2, 2, 1, 1]);
        assert_eq!(r.moved, 2);
    }

    #[test]
    fn an_island_goes_where_the_score_says() {
        let faces = strip(7);
        // 0 0 1 2 2 2 ... label 1 is one piece; give label 0 an island at column 6 between nothing but 2s? use
        // columns 0 0 2 0 1 1 1: label 0 has two pieces, the island (column 3) touches 2 and 1
        let cols = [0u32, 0, 2, 0, 1, 1, 1];
        for (pref, want) in [(1u32, 1u32), (2, 2)] {
            let mut labels: Vec<u32> = cols.iter().flat_map(|&c| [c, c]).collect();
            let score = move |_: usize, l: u32| if l == pref { 1.0 } else { -1.0 };
            let r = connect_labels(&mut labels, &faces, &score, None, 1);
            assert_eq!((r.before, r.after, r.moved), (1, 0, 2));
            assert_eq!(labels[6], want);
            assert_eq!(labels[7], want);
        }
    }

    #[test]
    fn a_separate_component_is_left_and_counted() {
        // two separate strips, both label 0: no other label to join
        let mut faces = strip(3);
        faces.extend(strip(3).iter().map(|f| f.map(|v| v + 6)));
        let mut labels = vec![0u32; 12];
        let r = connect_labels(&mut labels, &faces, &|_, _| 0.0, None, 1);
        assert_eq!((r.before, r.after, r.moved), (1, 1, 0));
    }

    #[test]
    fn a_large_island_becomes_its_own_label() {
        // 0 0 0 1 1 0 0 0: label 0 has two pieces of 3 columns; with splitting the second becomes label 2
        let faces = strip(8);
        let cols = [0u32, 0, 0, 1, 1, 0, 0, 0];
        let mut labels: Vec<u32> = cols.iter().flat_map(|&c| [c, c]).collect();
        let r = connect_labels(&mut labels, &faces, &|_, _| 0.0, Some(SPLIT_FRACTION), 4);
        assert_eq!(r.split_from, vec![0]);
        assert_eq!((r.before, r.after, r.moved), (1, 0, 0));
        let got: Vec<u32> = labels.iter().step_by(2).copied().collect();
        assert_eq!(got, vec![0, 0, 0, 1, 1, 2, 2, 2]);
        // below min_vertices it is merged instead
        let mut labels: Vec<u32> = cols.iter().flat_map(|&c| [c, c]).collect();
        let r = connect_labels(&mut labels, &faces, &|_, _| 0.0, Some(SPLIT_FRACTION), 7);
        assert!(r.split_from.is_empty() && r.after == 0 && r.moved == 6);
    }
}
