//! Patches: the mesh cut into many small, compact pieces by farthest-point sampling with geodesic distances along
//! its edges (each edge's length averaged over the poses), every vertex to its nearest seed; the leaves of the
//! merge tree ([`super::merge_tree`]) and the seeds of the coarse mesh ([`super::coarse_mesh`]). Only the
//! connectivity and the poses' edge lengths enter, so the patches do not depend on the order of the poses nor on
//! where the population stands. Also the poses spread over a population ([`spread_poses`]), which the tree and
//! the flesh test read.

use crate::mesh::Population;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Most patches ([`patches`]); a patch has about [`PATCH_VERTICES`] vertices below that.
pub const MAX_PATCHES: usize = 400;
/// Vertices per patch on small meshes.
pub const PATCH_VERTICES: usize = 6;

/// Up to `most` poses spread over the population: the pose farthest from the mean shape first, then each next
/// the one farthest (RMS vertex distance) from those chosen. Independent of the poses' order (up to exact ties).
pub fn spread_poses(pop: &Population, most: usize) -> Vec<usize> {
    let ns = pop.n_shapes();
    if ns <= most {
        return (0..ns).collect();
    }
    // each next pose does not depend on how many are asked for: the order's first SPREAD_ORDER poses are
    // worked out once per population (the tree, the flesh test and every round ask again)
    let mut chosen = if most <= SPREAD_ORDER {
        pop.pose_order(|| farthest_first(pop, SPREAD_ORDER))[..most].to_vec()
    } else {
        farthest_first(pop, most)
    };
    chosen.sort_unstable();
    chosen
}

/// The most poses of [`spread_poses`]'s order that a population keeps ([`Population::pose_order`]): as many as
/// its largest use asks for (the flesh test's 24 reference poses).
const SPREAD_ORDER: usize = 24;

/// The first `most` poses (at most all) in [`spread_poses`]'s order, unsorted.
fn farthest_first(pop: &Population, most: usize) -> Vec<usize> {
    let ns = pop.n_shapes();
    let most = most.min(ns);
    // distances on at most 2 000 evenly spaced vertices, gathered pose by pose
    let nv = pop.n_vertices();
    let stride = nv.div_ceil(2000).max(1);
    let sample: Vec<usize> = (0..nv).step_by(stride).collect();
    let points: Vec<Vec<[f64; 3]>> = (0..ns).map(|i| sample.iter().map(|&j| pop.point(i, j)).collect()).collect();
    let dist = |a: &[[f64; 3]], i: usize| -> f64 {
        points[i]
            .iter()
            .zip(a)
            .map(|(p, r)| (p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2) + (p[2] - r[2]).powi(2))
            .sum()
    };
    // the mean shape at the sampled vertices
    let mut means = vec![[0.0; 3]; sample.len()];
    for (t, m) in means.iter_mut().enumerate() {
        for p in &points {
            for c in 0..3 {
                m[c] += p[t][c] / ns as f64;
            }
        }
    }
    let mean = &means[..];
    let first = (0..ns).map(|i| (dist(mean, i), i)).max_by(|x, y| x.0.total_cmp(&y.0)).expect("poses").1;
    let mut chosen = vec![first];
    let mut near: Vec<f64> = (0..ns).map(|i| dist(&points[first], i)).collect();
    while chosen.len() < most {
        let next = (0..ns)
            .filter(|i| !chosen.contains(i))
            .max_by(|&x, &y| near[x].total_cmp(&near[y]).then(y.cmp(&x)))
            .expect("poses left");
        chosen.push(next);
        for i in 0..ns {
            near[i] = near[i].min(dist(&points[next], i));
        }
    }
    chosen
}

/// The mesh's edges (i < j, sorted, unique) with their length averaged over the poses.
fn edges(pop: &Population) -> Vec<(u32, u32, f64)> {
    let e = edge_list(pop);
    let ns = pop.n_shapes() as f64;
    // shape by shape (each shape's points are read in one sweep), each edge's sum in the order of the shapes
    let mut len = vec![0.0; e.len()];
    for s in pop.shapes() {
        for (l, &(a, b)) in len.iter_mut().zip(&e) {
            *l += crate::geometry::norm(crate::geometry::sub(s.get(a as usize), s.get(b as usize)));
        }
    }
    e.into_iter().zip(len).map(|((a, b), l)| (a, b, l / ns)).collect()
}

/// The mesh's edges (i < j, sorted, unique).
fn edge_list(pop: &Population) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = Vec::with_capacity(pop.faces.len() * 3);
    for f in pop.graph_faces().iter() {
        for s in 0..3 {
            let (a, b) = (f[s], f[(s + 1) % 3]);
            if a != b {
                e.push((a.min(b), a.max(b)));
            }
        }
    }
    e.sort_unstable();
    e.dedup();
    e
}

/// A vertex keyed by its distance, for a max-heap ([`BinaryHeap`]): with `NEAREST` the smallest distance
/// first (Dijkstra's front), else the largest (the farthest vertex); ties to the lowest id.
#[derive(PartialEq)]
struct Keyed<const NEAREST: bool>(f64, u32);
impl<const N: bool> Eq for Keyed<N> {}
impl<const N: bool> PartialOrd for Keyed<N> {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl<const N: bool> Ord for Keyed<N> {
    fn cmp(&self, o: &Self) -> Ordering {
        let by_distance = self.0.total_cmp(&o.0);
        (if N { by_distance.reverse() } else { by_distance }).then(o.1.cmp(&self.1))
    }
}

/// How many patches for `n_vertices` vertices.
pub fn patch_count(n_vertices: usize) -> usize {
    (n_vertices / PATCH_VERTICES).clamp(1, MAX_PATCHES).min(n_vertices)
}

/// Cuts the mesh into `count` compact patches (more when the mesh has more connected pieces): geodesic
/// farthest-point seeds (edge lengths averaged over the poses; the first seed is vertex 0, every connected piece
/// of the mesh gets one), each vertex to its nearest seed. A vertex on no triangle goes to the patch of the nearest vertex on one (mean shape).
pub fn patches(pop: &Population, count: usize) -> Vec<u32> {
    seeded_patches(pop, count, false).0
}

/// [`patches`] with the seed vertex of every patch (`seeds[p]` is patch p's); with `hops`, every edge counts
/// as length 1 (the patches then depend on the mesh's connectivity alone, not on the poses).
pub fn seeded_patches(pop: &Population, count: usize, hops: bool) -> (Vec<u32>, Vec<usize>) {
    let nv = pop.n_vertices();
    // each vertex's neighbours side by side in one array (u32 offsets per vertex), in the edges' order, and by
    // lengths the edges' lengths beside them (small arrays: in wasm a large block the freed memory cannot hold
    // grows the instance for good)
    let (pairs, lengths): (Vec<(u32, u32)>, Vec<f64>) =
        if hops { (edge_list(pop), Vec::new()) } else { edges(pop).into_iter().map(|(a, b, w)| ((a, b), w)).unzip() };
    let mut start = vec![0u32; nv + 1];
    for &(a, b) in &pairs {
        start[a as usize + 1] += 1;
        start[b as usize + 1] += 1;
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut neighbour = vec![0u32; start[nv] as usize];
    let mut length = vec![0.0f64; if hops { 0 } else { neighbour.len() }];
    let mut fill: Vec<u32> = start[..nv].to_vec();
    for (e, &(a, b)) in pairs.iter().enumerate() {
        for (x, y) in [(a, b), (b, a)] {
            let at = fill[x as usize] as usize;
            neighbour[at] = y;
            if !hops {
                length[at] = lengths[e];
            }
            fill[x as usize] += 1;
        }
    }
    drop((pairs, lengths, fill));
    let range = |v: u32| start[v as usize] as usize..start[v as usize + 1] as usize;
    let on_mesh: Vec<bool> = (0..nv).map(|v| start[v + 1] > start[v]).collect();
    let mut dist = vec![f64::INFINITY; nv];
    let mut owner = vec![u32::MAX; nv];
    let mut heap: BinaryHeap<Keyed<true>> = BinaryHeap::new();
    let mut queue: std::collections::VecDeque<u32> = std::collections::VecDeque::new();
    // by lengths, one entry per vertex, at least its distance (distances only fall), the largest first: an entry
    // above its vertex's distance goes back in at that distance until the top one is exact, and that vertex is
    // the farthest (any other's distance is at most its entry, at most the top's) without a scan of the mesh
    // per seed
    let mut farthest: BinaryHeap<Keyed<false>> = if hops {
        BinaryHeap::new()
    } else {
        (0..nv).filter(|&j| on_mesh[j]).map(|j| Keyed(f64::INFINITY, j as u32)).collect()
    };
    // by hops, the same farthest vertex from buckets: `level[d]` holds (lowest id first) the vertices that came
    // to distance d, some since gone closer; `unreached` the vertices no seed reaches yet, by id
    let mut level: Vec<BinaryHeap<std::cmp::Reverse<u32>>> = Vec::new();
    let mut unreached = (0..nv as u32).filter(|&j| on_mesh[j as usize]).peekable();
    let mut seeds: Vec<usize> = Vec::new();
    let mut next = (0..nv).find(|&j| on_mesh[j]);
    while let Some(s) = next {
        let patch = seeds.len() as u32;
        seeds.push(s);
        dist[s] = 0.0;
        owner[s] = patch;
        if hops {
            // every edge of length 1: a breadth-first search visits in order of distance, as the heap would, and
            // reaches (strictly closer than before) the same vertices with the same distances
            queue.push_back(s as u32);
            while let Some(v) = queue.pop_front() {
                let nd = dist[v as usize] + 1.0;
                for &u in &neighbour[range(v)] {
                    if nd < dist[u as usize] {
                        dist[u as usize] = nd;
                        owner[u as usize] = patch;
                        queue.push_back(u);
                        let d = nd as usize;
                        if level.len() <= d {
                            level.resize_with(d + 1, BinaryHeap::new);
                        }
                        level[d].push(std::cmp::Reverse(u));
                    }
                }
            }
            // the farthest vertex: an unreached one first (lowest id), else the lowest id at the largest distance
            while unreached.next_if(|&j| dist[j as usize].is_finite()).is_some() {}
            next = match unreached.peek() {
                Some(&j) => Some(j as usize),
                None => loop {
                    let d = level.len().wrapping_sub(1);
                    let Some(top) = level.last_mut() else { break None };
                    match top.peek() {
                        Some(&std::cmp::Reverse(j)) if dist[j as usize] as usize == d => {
                            break (d > 0).then_some(j as usize)
                        }
                        Some(_) => {
                            top.pop();
                        }
                        None => {
                            level.pop();
                        }
                    }
                },
            };
            if seeds.len() >= count {
                next = next.filter(|&j| dist[j].is_infinite());
            }
            continue;
        }
        heap.push(Keyed(0.0, s as u32));
        while let Some(Keyed(d, v)) = heap.pop() {
            if d > dist[v as usize] {
                continue;
            }
            for (&u, &w) in neighbour[range(v)].iter().zip(&length[range(v)]) {
                let nd = d + w;
                if nd < dist[u as usize] {
                    dist[u as usize] = nd;
                    owner[u as usize] = patch;
                    heap.push(Keyed(nd, u));
                }
            }
        }
        // the farthest vertex on the mesh (an unreached piece first); ties to the lowest id
        while let Some(mut top) = farthest.peek_mut().filter(|f| f.0 != dist[f.1 as usize]) {
            top.0 = dist[top.1 as usize];
        }
        next = farthest.peek().filter(|f| f.0 > 0.0).map(|f| f.1 as usize);
        if seeds.len() >= count {
            // past `count` only for a piece of the mesh that no seed reaches (every vertex on a triangle gets a
            // patch, also in a soup of more unwelded pieces than `count`)
            next = next.filter(|&j| dist[j].is_infinite());
        }
    }
    // vertices on no triangle: the patch of the nearest vertex on one, in the mean shape
    if on_mesh.iter().any(|&m| !m) {
        let ns = pop.n_shapes() as f64;
        let mean = |j: usize| {
            let mut m = [0.0; 3];
            for s in pop.shapes() {
                let p = s.get(j);
                for c in 0..3 {
                    m[c] += p[c] / ns;
                }
            }
            m
        };
        let placed: Vec<(usize, [f64; 3])> = (0..nv).filter(|&j| on_mesh[j]).map(|j| (j, mean(j))).collect();
        for j in (0..nv).filter(|&j| !on_mesh[j]) {
            let p = mean(j);
            let d2 = |q: &[f64; 3]| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>();
            if let Some(&(k, _)) = placed.iter().min_by(|x, y| d2(&x.1).total_cmp(&d2(&y.1))) {
                owner[j] = owner[k];
            } else {
                owner[j] = 0;
            }
        }
    }
    (owner, seeds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parts::merge_tree::TREE_POSES;
    use crate::synth::{generate, Preset, Spec};

    #[test]
    fn every_piece_of_a_triangle_soup_gets_a_patch_past_the_count() {
        // 50 unwelded triangles, 10 patches asked for: each triangle is a piece no other seed reaches
        let faces: Vec<[u32; 3]> = (0..50u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let shape = |s: f64| -> Vec<[f64; 3]> {
            (0..150).map(|j| [(j / 3) as f64 / 50.0, (j % 3) as f64 * 0.01 * s, 0.0]).collect()
        };
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces,
            shapes: vec![shape(1.0), shape(2.0)],
        })
        .unwrap();
        let (owner, seeds) = seeded_patches(&pop, 10, false);
        assert_eq!(seeds.len(), 50);
        assert!(owner.iter().all(|&o| (o as usize) < seeds.len()));
        // and a count past the pieces is the farthest-point count, as on any mesh
        assert_eq!(seeded_patches(&pop, 100, true).1.len(), 100);
    }

    /// By hops, the seeds and patches are farthest-point sampling done the slow way: after each seed, every
    /// vertex's hop distance to the nearest seed (a breadth-first search from each seed), the next seed the
    /// farthest vertex (an unreached piece first, ties to the lowest id), and each vertex in the patch of the
    /// first seed at its distance. On a mesh of two pieces (a strip, a fan) and vertices on no triangle.
    #[test]
    fn seeds_by_hops_are_the_plain_farthest_point_sampling() {
        let mut faces: Vec<[u32; 3]> =
            (0..30u32).map(|t| if t % 2 == 0 { [t, t + 1, t + 2] } else { [t + 1, t, t + 2] }).collect();
        faces.extend((0..9u32).map(|k| [40, 41 + k, 42 + k]));
        let nv = 53;
        let shape = |s: f64| -> Vec<[f64; 3]> {
            (0..nv).map(|j| [j as f64 / nv as f64, (j % 2) as f64 * 0.1 * s, 0.0]).collect()
        };
        let pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a".into(), "b".into()],
            faces: faces.clone(),
            shapes: vec![shape(1.0), shape(2.0)],
        })
        .unwrap();
        let mut adj = vec![Vec::new(); nv];
        for f in &faces {
            for s in 0..3 {
                adj[f[s] as usize].push(f[(s + 1) % 3] as usize);
                adj[f[(s + 1) % 3] as usize].push(f[s] as usize);
            }
        }
        let hops_from = |s: usize| {
            let mut d = vec![usize::MAX; nv];
            d[s] = 0;
            let mut queue = std::collections::VecDeque::from([s]);
            while let Some(v) = queue.pop_front() {
                for &u in &adj[v] {
                    if d[u] == usize::MAX {
                        d[u] = d[v] + 1;
                        queue.push_back(u);
                    }
                }
            }
            d
        };
        for count in [1, 2, 5, 12, 40] {
            let mut seeds = vec![0usize];
            let mut from: Vec<Vec<usize>> = vec![hops_from(0)];
            let nearest = |from: &Vec<Vec<usize>>, j: usize| from.iter().map(|d| d[j]).min().unwrap();
            loop {
                // (vertices 32-39, 51 and 52 are on no triangle: never seeds)
                let far = (0..nv)
                    .filter(|&j| !adj[j].is_empty())
                    .max_by(|&a, &b| nearest(&from, a).cmp(&nearest(&from, b)).then(b.cmp(&a)))
                    .unwrap();
                let d = nearest(&from, far);
                if d == 0 || (seeds.len() >= count && d != usize::MAX) {
                    break;
                }
                seeds.push(far);
                from.push(hops_from(far));
            }
            let (owner, got) = seeded_patches(&pop, count, true);
            assert_eq!(got, seeds, "{count} seeds");
            for j in (0..nv).filter(|&j| !adj[j].is_empty()) {
                let d = nearest(&from, j);
                assert_eq!(
                    owner[j] as usize,
                    (0..seeds.len()).find(|&k| from[k][j] == d).unwrap(),
                    "{count} seeds, vertex {j}"
                );
            }
        }
    }

    /// The poses kept once per population are the ones worked out afresh for every count asked for, and new
    /// shapes are asked about afresh.
    #[test]
    fn the_kept_pose_order_gives_each_count_what_a_fresh_search_does() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 300, poses: 30, seed: 5, ..Spec::default() })
            .unwrap();
        let mut pop = g.population.clone();
        for most in [2, 5, TREE_POSES, SPREAD_ORDER, 29] {
            let mut fresh = farthest_first(&pop, most);
            fresh.sort_unstable();
            assert_eq!(spread_poses(&pop, most), fresh, "{most} poses");
        }
        assert_eq!(spread_poses(&pop, 30), (0..30).collect::<Vec<_>>());
        // the same shapes in reverse order: another order is worked out for them
        let before = spread_poses(&pop, TREE_POSES);
        let mut shapes = pop.unit_shapes();
        shapes.reverse();
        pop.set_shapes(&shapes);
        let after = spread_poses(&pop, TREE_POSES);
        assert_eq!(after, before.iter().rev().map(|&i| 29 - i).collect::<Vec<_>>());
    }
}
