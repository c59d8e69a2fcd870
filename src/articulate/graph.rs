//! The part graph: which rigid parts touch, where, and the tree the interpolation walks.
//!
//! Two parts are adjacent when a mesh edge joins a vertex of one to a vertex of the other. The contact
//! region of a pair is the set of triangles that have vertices in both parts (docs/method.md, item 10); when it
//! falls into several patches (a label island inside another part adds a small second patch) the patch with
//! the largest area is kept, so that a stray island does not pull the joint away from the real contact.
//!
//! Labels are not guaranteed to be spatially coherent (docs/method.md, item 7), so a part can touch another through a small
//! island as well as through its real joint. The default tree is therefore grown from the root by always
//! taking the strongest remaining contact (the most mesh edges crossing: Prim's maximum spanning tree); the
//! paper's plain breadth-first tree is [`TreeRule::BreadthFirst`]. On a clean segmentation whose part graph
//! is itself a tree the two are the same tree.
//!
//! Parts in different connected pieces of the part graph (a mesh made of several pieces) are joined by virtual
//! contacts, so that every used part is in one tree: a minimum spanning tree over the pieces whose cost is the
//! gap between the closest vertices of two parts plus how far the smaller part moves relative to the other over
//! the poses ([`piece_join_score`]): a character's separate arm box joins the torso it swings about, not the leg
//! box beside it. Where the two parts lie against each other (faces on the other's surface) the contact is
//! those faces ([`Contact::Touching`]), else the closest pair of vertices ([`Contact::Virtual`]). Parts that
//! label no vertex are in no tree.

use super::RigidMotion;
use crate::geometry::{add, norm, scale, sub, Vec3};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};

/// How the part tree is grown from its root.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum TreeRule {
    /// Maximum spanning tree on contact strength (mesh edges crossing), grown from the root. Default.
    #[default]
    Strongest,
    /// Algorithm 2's breadth-first search, neighbours in index order.
    BreadthFirst,
}

/// Where two parts touch.
#[derive(Debug, Clone, PartialEq)]
pub enum Contact {
    /// Triangles with vertices in both parts (the largest connected patch of them), by triangle index.
    Triangles(Vec<usize>),
    /// A virtual contact between two vertices (one per part) joining disconnected pieces of the mesh.
    Virtual(u32, u32),
    /// Two disconnected pieces that lie against each other: the triangles of either part whose every corner is
    /// on the other part's surface (within a tolerance), by triangle index. A box arm against a box torso
    /// touches along the arm's inner face, whose centre is where an artist puts the joint.
    Touching(Vec<usize>),
}

/// Parts, their contacts and sizes.
#[derive(Debug, Clone, PartialEq)]
pub struct PartGraph {
    pub n_parts: usize,
    /// Vertices per part.
    pub vertex_count: Vec<usize>,
    /// Sorted neighbour lists.
    pub neighbors: Vec<Vec<usize>>,
    /// Contact of every adjacent pair, keyed (smaller, larger).
    pub contacts: BTreeMap<(usize, usize), Contact>,
    /// Mesh edges crossing between the two parts of a pair, keyed (smaller, larger) (1 for virtual contacts).
    pub strength: BTreeMap<(usize, usize), usize>,
}

/// A tree over the used parts.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tree {
    pub root: usize,
    /// Parts in the order they were reached: every part comes after its parent.
    pub order: Vec<usize>,
    /// `parent[k]`: None for the root and for parts not in the tree (no vertices).
    pub parent: Vec<Option<usize>>,
}

impl Tree {
    /// Depth of every part in the tree (root 0), None when not in the tree.
    pub fn depths(&self) -> Vec<Option<usize>> {
        let mut d = vec![None; self.parent.len()];
        for &k in &self.order {
            d[k] = Some(match self.parent[k] {
                None => 0,
                Some(p) => d[p].expect("parents come first") + 1,
            });
        }
        d
    }

    pub fn contains(&self, part: usize) -> bool {
        self.order.contains(&part)
    }

    /// The same tree (the same edges) rooted at `root`: the parent relations on the path between the two roots
    /// reversed, the order breadth-first from `root` along the tree's edges. Itself when `root` is not in it.
    pub fn rerooted(&self, root: usize) -> Tree {
        if !self.contains(root) || root == self.root {
            return self.clone();
        }
        let n = self.parent.len();
        let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); n];
        // children in the old order, then the old parent: a deterministic order of the new tree
        for &k in &self.order {
            if let Some(p) = self.parent[k] {
                adjacent[p].push(k);
            }
        }
        for &k in &self.order {
            if let Some(p) = self.parent[k] {
                adjacent[k].push(p);
            }
        }
        let mut parent = vec![None; n];
        let mut seen = vec![false; n];
        let mut order = vec![root];
        seen[root] = true;
        let mut at = 0;
        while at < order.len() {
            let c = order[at];
            at += 1;
            for &k in &adjacent[c] {
                if !seen[k] {
                    seen[k] = true;
                    parent[k] = Some(c);
                    order.push(k);
                }
            }
        }
        Tree { root, order, parent }
    }
}

/// The part of `tree` where an artist roots a skeleton: among the parts where the tree branches (at least
/// three tree neighbours, or the most any part has when no part has three), the one whose centroid in
/// `positions` is nearest the area-weighted centroid of the whole mesh; ties to the smaller index. The pelvis
/// of a biped (legs and spine) rather than the chest it joins the arms at, when the pelvis is nearer the
/// centre; a quadruped's or a man's hips rather than a hoof or a hand. Each part's area is its vertices' share
/// of their triangles (a third of each); `labels`: each vertex's part. The tree's own root when the mesh has no
/// area (measured against artists' skeletons in docs/rig.md#joints-against-artists-skeletons).
pub fn central_root(tree: &Tree, labels: &[u32], faces: &[[u32; 3]], positions: &[Vec3]) -> usize {
    let n = tree.parent.len();
    let mut area = vec![0.0; n];
    let mut moment = vec![[0.0; 3]; n];
    let (mut total, mut total_moment) = (0.0, [0.0; 3]);
    for f in faces {
        let [a, b, c] = f.map(|v| v as usize);
        if a >= positions.len() || b >= positions.len() || c >= positions.len() {
            continue;
        }
        let t = triangle_area(positions[a], positions[b], positions[c]) / 3.0;
        if !t.is_finite() {
            continue;
        }
        for v in [a, b, c] {
            let Some(l) = labels.get(v).map(|&l| l as usize).filter(|&l| l < n) else { continue };
            area[l] += t;
            moment[l] = add(moment[l], scale(positions[v], t));
            total += t;
            total_moment = add(total_moment, scale(positions[v], t));
        }
    }
    if !(total > 0.0) {
        return tree.root;
    }
    let centre = scale(total_moment, 1.0 / total);
    let mut degree = vec![0usize; n];
    for &k in &tree.order {
        if let Some(p) = tree.parent[k] {
            degree[k] += 1;
            degree[p] += 1;
        }
    }
    let most = tree.order.iter().map(|&k| degree[k]).max().unwrap_or(0);
    let mut best: Option<(f64, usize)> = None;
    for &k in &tree.order {
        if degree[k] < most.min(3) || !(area[k] > 0.0) {
            continue;
        }
        let d = norm(sub(scale(moment[k], 1.0 / area[k]), centre));
        if best.is_none_or(|(bd, bk)| d < bd || (d == bd && k < bk)) {
            best = Some((d, k));
        }
    }
    best.map_or(tree.root, |b| b.1)
}

/// Every edge of the triangles once, as (smaller, larger) vertex index, sorted.
pub fn mesh_edges(faces: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut e: Vec<[u32; 2]> = faces
        .iter()
        .flat_map(|f| [[f[0], f[1]], [f[1], f[2]], [f[2], f[0]]])
        .filter(|e| e[0] != e[1])
        .map(|e| if e[0] < e[1] { e } else { [e[1], e[0]] })
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// Each vertex's neighbours in the mesh's edge graph (compressed rows): `of(v)` lists (neighbour, index of
/// the edge in the `edges` it was built from).
pub struct VertexNeighbours {
    start: Vec<usize>,
    list: Vec<(u32, usize)>,
}

impl VertexNeighbours {
    /// From `edges` (e.g. [`mesh_edges`]) over `n_vertices` vertices.
    pub fn new(edges: &[[u32; 2]], n_vertices: usize) -> VertexNeighbours {
        let mut start = vec![0usize; n_vertices + 1];
        for e in edges {
            start[e[0] as usize + 1] += 1;
            start[e[1] as usize + 1] += 1;
        }
        for v in 0..n_vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut list = vec![(0u32, 0usize); start[n_vertices]];
        for (i, e) in edges.iter().enumerate() {
            for (a, b) in [(e[0], e[1]), (e[1], e[0])] {
                list[fill[a as usize]] = (b, i);
                fill[a as usize] += 1;
            }
        }
        VertexNeighbours { start, list }
    }

    pub fn of(&self, v: usize) -> &[(u32, usize)] {
        &self.list[self.start[v]..self.start[v + 1]]
    }
}

fn key(a: usize, b: usize) -> (usize, usize) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

/// Area of triangle (a, b, c).
pub fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    0.5 * norm(crate::geometry::cross(sub(b, a), sub(c, a)))
}

/// The closest pair of vertices between two vertex sets (non-empty), by alternating nearest-point searches from
/// the second set's centroid (exact for convex pieces; a cheap, close pair otherwise).
fn closest_pair(a: &[usize], b: &[usize], positions: &[Vec3]) -> (usize, usize) {
    let nearest = |set: &[usize], to: Vec3| {
        *set.iter()
            .min_by(|&&x, &&y| norm(sub(positions[x], to)).total_cmp(&norm(sub(positions[y], to))))
            .expect("a used part has vertices")
    };
    let centroid = scale(b.iter().fold([0.0; 3], |s, &v| add(s, positions[v])), 1.0 / b.len() as f64);
    let mut va = nearest(a, centroid);
    let mut vb = nearest(b, positions[va]);
    for _ in 0..3 {
        va = nearest(a, positions[vb]);
        vb = nearest(b, positions[va]);
    }
    (va, vb)
}

/// The first two moments of a set of points: count, Σ p, Σ p pᵀ (row-major).
#[derive(Debug, Clone, Copy, Default)]
pub struct Moments {
    pub n: f64,
    pub sum: Vec3,
    pub outer: [f64; 9],
}

impl Moments {
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Moments {
        let mut m = Moments::default();
        for p in points {
            m.n += 1.0;
            m.sum = add(m.sum, p);
            for r in 0..3 {
                for c in 0..3 {
                    m.outer[r * 3 + c] += p[r] * p[c];
                }
            }
        }
        m
    }

    /// The root mean square distance of the points from their centroid (0 for no points).
    pub fn rms_radius(&self) -> f64 {
        if !(self.n > 0.0) {
            return 0.0;
        }
        let mean = scale(self.sum, 1.0 / self.n);
        let spread = (self.outer[0] + self.outer[4] + self.outer[8]) / self.n - crate::geometry::dot(mean, mean);
        spread.max(0.0).sqrt()
    }
}

/// How well two parts of different mesh pieces are joined by a contact between their closest vertices `pa`, `pb`
/// (a length; smaller is better): the gap |pa - pb| plus how far the smaller part (`child`, its points'
/// moments) moves relative to the other, the root mean square of |M_a^i p - M_b^i p| over its points p and the
/// poses i (M^i: the parts' motions in pose i, in the frame of the points). An arm box beside a torso box moves
/// relative to it by its swing; relative to the leg box it also touches, by its swing and the leg's; a leg
/// relative to the other leg by twice its swing; an eye relative to its head, not at all. The gap alone without
/// motions.
pub fn piece_join_score(ma: &[RigidMotion], mb: &[RigidMotion], pa: Vec3, pb: Vec3, child: &Moments) -> f64 {
    let gap = norm(sub(pa, pb));
    let n = ma.len().min(mb.len());
    if n == 0 || child.n == 0.0 {
        return gap;
    }
    // Σ_p |ΔR p + Δt|² = tr(ΔRᵀΔR Σ p pᵀ) + 2 Δt · ΔR Σ p + n |Δt|²
    let mut total = 0.0;
    for (p, q) in ma.iter().zip(mb).take(n) {
        let dr = p.rotation - q.rotation;
        let dt = sub(p.translation, q.translation);
        for r in 0..3 {
            for c in 0..3 {
                let g: f64 = (0..3).map(|m| dr[(m, r)] * dr[(m, c)]).sum();
                total += g * child.outer[c * 3 + r];
            }
        }
        let drs = crate::geometry::mat_vec(&dr, child.sum);
        total += 2.0 * crate::geometry::dot(dt, drs) + child.n * crate::geometry::dot(dt, dt);
    }
    gap + (total / (n as f64 * child.n)).max(0.0).sqrt()
}

/// How far a corner may lie off the other piece's surface and still touch it ([`touching_triangles`]), as a
/// fraction of the smaller part's root mean square radius. Pieces farther apart do not touch (their contact is
/// their closest vertices); a small tolerance also keeps the search local (its grid's cells are no larger than
/// the triangles or twice the tolerance). Not the gap between the closest vertices: a box's corner can lie on
/// another box's face with no vertex of that face near it.
pub const TOUCHING_TOLERANCE: f64 = 0.01;

/// The triangles of two separate pieces (`tris[0]`, `tris[1]`: each part's own triangles) that lie against the
/// other: every corner within `tolerance` of one of the other's triangles. Both parts' triangles, sorted. The
/// time grows with the triangles in reach of each corner, so `tolerance` should be small beside the parts.
pub fn touching_triangles(tris: [&[usize]; 2], faces: &[[u32; 3]], positions: &[Vec3], tolerance: f64) -> Vec<usize> {
    use crate::geometry::surface_distance::SurfaceGrid;
    let corners = |t: usize| faces[t].map(|v| positions[v as usize]);
    let mut out = Vec::new();
    for side in 0..2 {
        let (own, other) = (tris[side], tris[1 - side]);
        let grid = SurfaceGrid::new(other.iter().map(|&t| corners(t)).collect(), tolerance);
        out.extend(own.iter().copied().filter(|&t| corners(t).iter().all(|&p| grid.near(p))));
    }
    out.sort_unstable();
    out
}

struct Dsu(Vec<usize>);
impl Dsu {
    fn find(&mut self, x: usize) -> usize {
        let mut r = x;
        while self.0[r] != r {
            r = self.0[r];
        }
        let mut y = x;
        while self.0[y] != r {
            let n = self.0[y];
            self.0[y] = r;
            y = n;
        }
        r
    }
    fn union(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a] = b;
        }
    }
}

impl PartGraph {
    /// Builds the graph from the labels (one per vertex, < `n_parts`), the triangles, and one pose of the
    /// mesh (`positions`, used for patch areas and to place virtual contacts).
    /// `motions[k][i]`: part k's motion from `positions` to pose i, used to choose where disconnected pieces
    /// join ([`piece_join_score`]); empty: by distance alone.
    pub fn new(
        labels: &[u32],
        faces: &[[u32; 3]],
        n_parts: usize,
        positions: &[Vec3],
        motions: &[Vec<RigidMotion>],
    ) -> PartGraph {
        let mut vertex_count = vec![0usize; n_parts];
        for &l in labels {
            vertex_count[l as usize] += 1;
        }
        let mut strength: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for e in mesh_edges(faces) {
            let (a, b) = (labels[e[0] as usize] as usize, labels[e[1] as usize] as usize);
            if a != b {
                *strength.entry(key(a, b)).or_default() += 1;
            }
        }
        // Triangles touching two parts, per pair.
        let mut tri_of_pair: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
        for (t, f) in faces.iter().enumerate() {
            let l = f.map(|v| labels[v as usize] as usize);
            let mut pairs = vec![key(l[0], l[1]), key(l[1], l[2]), key(l[0], l[2])];
            pairs.sort_unstable();
            pairs.dedup();
            for p in pairs {
                if p.0 != p.1 {
                    tri_of_pair.entry(p).or_default().push(t);
                }
            }
        }
        let mut contacts = BTreeMap::new();
        for (pair, tris) in tri_of_pair {
            contacts.insert(pair, Contact::Triangles(largest_patch(&tris, faces, positions)));
        }
        let mut graph = PartGraph { n_parts, vertex_count, neighbors: vec![Vec::new(); n_parts], contacts, strength };
        graph.join_pieces(labels, faces, positions, motions);
        for &(a, b) in graph.contacts.keys() {
            graph.neighbors[a].push(b);
            graph.neighbors[b].push(a);
        }
        for n in &mut graph.neighbors {
            n.sort_unstable();
            n.dedup();
        }
        graph
    }

    /// Adds contacts between pieces until the used parts form one connected graph: a minimum spanning tree over the
    /// pieces (parts joined by real contacts), each pair of parts in different pieces scored by
    /// [`piece_join_score`], the contact the faces where they lie against each other ([`touching_triangles`]), or
    /// where there are none, the pair's closest vertices.
    fn join_pieces(&mut self, labels: &[u32], faces: &[[u32; 3]], positions: &[Vec3], motions: &[Vec<RigidMotion>]) {
        let used: Vec<usize> = (0..self.n_parts).filter(|&k| self.vertex_count[k] > 0).collect();
        if used.len() < 2 {
            return;
        }
        let mut dsu = Dsu((0..self.n_parts).collect());
        for &(a, b) in self.contacts.keys() {
            dsu.union(a, b);
        }
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); self.n_parts];
        for (v, &l) in labels.iter().enumerate() {
            members[l as usize].push(v);
        }
        let moments: Vec<Moments> = members.iter().map(|m| Moments::of(m.iter().map(|&v| positions[v]))).collect();
        let mut candidates = Vec::new();
        for (i, &a) in used.iter().enumerate() {
            for &b in &used[i + 1..] {
                if dsu.find(a) == dsu.find(b) {
                    continue;
                }
                let (va, vb) = closest_pair(&members[a], &members[b], positions);
                let none = Vec::new();
                let (ma, mb) = (motions.get(a).unwrap_or(&none), motions.get(b).unwrap_or(&none));
                // the smaller part moves relative to the larger (the leg to the body), ties the later one
                let child = if members[a].len() < members[b].len() { a } else { b };
                let score = piece_join_score(ma, mb, positions[va], positions[vb], &moments[child]);
                candidates.push((score, a, b, child, va as u32, vb as u32));
            }
        }
        candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let mut faces_of: Vec<Vec<usize>> = vec![Vec::new(); self.n_parts];
        for (t, f) in faces.iter().enumerate() {
            let l = labels[f[0] as usize];
            if f.iter().all(|&v| labels[v as usize] == l) {
                faces_of[l as usize].push(t);
            }
        }
        for (_, a, b, child, va, vb) in candidates {
            if dsu.find(a) != dsu.find(b) {
                dsu.union(a, b);
                let tolerance = TOUCHING_TOLERANCE * moments[child].rms_radius();
                let touching = touching_triangles([&faces_of[a], &faces_of[b]], faces, positions, tolerance);
                let contact = if touching.is_empty() { Contact::Virtual(va, vb) } else { Contact::Touching(touching) };
                self.contacts.insert((a, b), contact);
                self.strength.insert((a, b), 1);
            }
        }
    }

    pub fn contact(&self, a: usize, b: usize) -> Option<&Contact> {
        self.contacts.get(&key(a, b))
    }

    pub fn strength(&self, a: usize, b: usize) -> usize {
        self.strength.get(&key(a, b)).copied().unwrap_or(0)
    }

    /// Parts that label at least one vertex.
    pub fn used_parts(&self) -> Vec<usize> {
        (0..self.n_parts).filter(|&k| self.vertex_count[k] > 0).collect()
    }

    /// The tree over the used parts grown from `root` by `rule`.
    pub fn tree(&self, root: usize, rule: TreeRule) -> Tree {
        let mut parent = vec![None; self.n_parts];
        let mut seen = vec![false; self.n_parts];
        let mut order = vec![root];
        seen[root] = true;
        match rule {
            TreeRule::BreadthFirst => {
                let mut queue = VecDeque::from([root]);
                while let Some(c) = queue.pop_front() {
                    for &k in &self.neighbors[c] {
                        if !seen[k] {
                            seen[k] = true;
                            parent[k] = Some(c);
                            order.push(k);
                            queue.push_back(k);
                        }
                    }
                }
            }
            TreeRule::Strongest => loop {
                // Strongest contact from the tree to a part outside; ties: smaller tree index, then part.
                let mut best: Option<(usize, usize, usize)> = None;
                for (pos, &c) in order.iter().enumerate() {
                    for &k in &self.neighbors[c] {
                        if seen[k] {
                            continue;
                        }
                        let s = self.strength(c, k);
                        let better = match best {
                            None => true,
                            Some((bs, bpos, bk)) => s > bs || (s == bs && (pos, k) < (bpos, bk)),
                        };
                        if better {
                            best = Some((s, pos, k));
                        }
                    }
                }
                let Some((_, pos, k)) = best else { break };
                seen[k] = true;
                parent[k] = Some(order[pos]);
                order.push(k);
            },
        }
        Tree { root, order, parent }
    }
}

/// The connected patch (triangles sharing a vertex) with the largest area, triangles in index order.
fn largest_patch(tris: &[usize], faces: &[[u32; 3]], positions: &[Vec3]) -> Vec<usize> {
    if tris.len() <= 1 {
        return tris.to_vec();
    }
    let mut dsu = Dsu((0..tris.len()).collect());
    let mut first_with_vertex: BTreeMap<u32, usize> = BTreeMap::new();
    for (i, &t) in tris.iter().enumerate() {
        for v in faces[t] {
            match first_with_vertex.get(&v) {
                Some(&o) => dsu.union(i, o),
                None => {
                    first_with_vertex.insert(v, i);
                }
            }
        }
    }
    let mut area: BTreeMap<usize, f64> = BTreeMap::new();
    for (i, &t) in tris.iter().enumerate() {
        let f = faces[t];
        let a = triangle_area(positions[f[0] as usize], positions[f[1] as usize], positions[f[2] as usize]);
        // a tiny floor so that degenerate patches still count by their size
        *area.entry(dsu.find(i)).or_default() += a + 1e-300;
    }
    let best = area.iter().max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(a.0))).map(|(&r, _)| r).unwrap_or(0);
    tris.iter().enumerate().filter(|&(i, _)| dsu.find(i) == best).map(|(_, &t)| t).collect()
}

/// Neighbour lists of the parts (sorted): two parts are neighbours when a mesh edge joins a vertex of one to
/// a vertex of the other. Labels must be < `n_parts`.
pub fn part_neighbours(labels: &[u32], faces: &[[u32; 3]], n_parts: usize) -> Vec<Vec<usize>> {
    let mut adj = vec![std::collections::BTreeSet::new(); n_parts];
    for [a, b] in mesh_edges(faces) {
        let (la, lb) = (labels[a as usize] as usize, labels[b as usize] as usize);
        if la != lb {
            adj[la].insert(lb);
            adj[lb].insert(la);
        }
    }
    adj.into_iter().map(|s| s.into_iter().collect()).collect()
}

/// A colour (index below `n_colours`) for every part, such that neighbouring parts (see
/// [`part_neighbours`]) differ whenever `n_colours` allows it; among the colours a part may take, the one fewest
/// of the parts two steps away have (a head beyond its neck in the trunk's colour reads as one part with it), then
/// the one used least so far, so that every part has a colour of its own while there are enough. Greedy colouring in
/// Welsh-Powell order: most neighbours first, then the larger part, then the lower index. Parts are
/// 0..=max(label); a part with more neighbours than colours takes the least used colour.
pub fn colour_parts(labels: &[u32], faces: &[[u32; 3]], n_colours: usize) -> Vec<u32> {
    colour_parts_like(labels, faces, n_colours, &[])
}

/// [`colour_parts`], keeping the colours of earlier partitions of the same vertices (`previous`: their labels and
/// their colours, the newest first) where a part is the same: a part that shares more than half of its vertices
/// with a part of the newest, and that part more than half of its vertices with it, takes its colour; a part
/// none of the newest is, but one of an older partition is, takes that one's colour unless a neighbour has it
/// already (so fits A, B and A again show A in A's colours); the others are coloured as [`colour_parts`] does
/// around them. So fits of one population can be compared by eye. A partition of another vertex count is passed
/// over; with none, the same as [`colour_parts`].
pub fn colour_parts_like(
    labels: &[u32],
    faces: &[[u32; 3]],
    n_colours: usize,
    previous: &[(&[u32], &[u32])],
) -> Vec<u32> {
    let n_parts = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    if n_colours == 0 {
        return vec![0; n_parts];
    }
    let adj = part_neighbours(labels, faces, n_parts);
    let mut size = vec![0usize; n_parts];
    for &l in labels {
        size[l as usize] += 1;
    }
    let mut colour: Vec<Option<usize>> = vec![None; n_parts];
    let mut used = vec![0usize; n_colours];
    for (k, (before, before_colours)) in previous.iter().filter(|(b, _)| b.len() == labels.len()).enumerate() {
        for (l, b) in crate::parts::labels::same_parts(labels, before).into_iter().enumerate() {
            let c = b.and_then(|b| before_colours.get(b as usize)).map(|&c| c as usize).filter(|&c| c < n_colours);
            let Some(c) = c.filter(|_| colour[l].is_none()) else { continue };
            // (the newest partition's neighbours differ already; an older one's colour must not meet a neighbour's)
            if k > 0 && adj[l].iter().any(|&q| colour[q] == Some(c)) {
                continue;
            }
            colour[l] = Some(c);
            used[c] += 1;
        }
    }
    let mut order: Vec<usize> = (0..n_parts).filter(|&p| colour[p].is_none()).collect();
    order.sort_by(|&a, &b| adj[b].len().cmp(&adj[a].len()).then(size[b].cmp(&size[a])).then(a.cmp(&b)));
    for p in order {
        let taken: Vec<usize> = adj[p].iter().filter_map(|&q| colour[q]).collect();
        // the parts two steps away (a neighbour's neighbours): a part beyond a short one (a head beyond the
        // neck) in the same colour reads as one part with it, so those colours are avoided too while there
        // are enough, and otherwise the one fewest of them have
        let two_away: std::collections::BTreeSet<usize> =
            adj[p].iter().flat_map(|&q| adj[q].iter().copied()).filter(|&r| r != p && !adj[p].contains(&r)).collect();
        let mut beyond = vec![0usize; n_colours];
        for c in two_away.into_iter().filter_map(|r| colour[r]) {
            beyond[c] += 1;
        }
        let least =
            |ok: &dyn Fn(usize) -> bool| (0..n_colours).filter(|&c| ok(c)).min_by_key(|&c| (beyond[c], used[c], c));
        let c = least(&|c| !taken.contains(&c)).or_else(|| least(&|_| true)).unwrap_or(0);
        colour[p] = Some(c);
        used[c] += 1;
    }
    colour.into_iter().map(|c| c.unwrap_or(0) as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stick biped: parts 0 pelvis, 1 spine, 2 chest, 3-4 arms, 5 head, 6-7 legs; each part one unit
    /// triangle placed at its centre.
    fn biped(anchor: usize) -> (Tree, Vec<u32>, Vec<[u32; 3]>, Vec<Vec3>) {
        let centres = [
            [0.0, 0.0, 0.0],
            [0.0, 0.6, 0.0],
            [0.0, 1.2, 0.0],
            [-0.8, 1.3, 0.0],
            [0.8, 1.3, 0.0],
            [0.0, 1.7, 0.0],
            [-0.2, -0.9, 0.0],
            [0.2, -0.9, 0.0],
        ];
        let (mut pos, mut labels, mut faces) = (Vec::new(), Vec::new(), Vec::new());
        for (k, c) in centres.iter().enumerate() {
            let s = match k {
                2 => 0.6,     // the chest the largest part (the anchor today)
                6 | 7 => 0.5, // long legs
                _ => 0.3,
            };
            let v = pos.len() as u32;
            pos.extend([add(*c, [-s, -s, 0.0]), add(*c, [s, -s, 0.0]), add(*c, [0.0, s, 0.0])]);
            labels.extend([k as u32; 3]);
            faces.push([v, v + 1, v + 2]);
        }
        let mut g = PartGraph {
            n_parts: 8,
            vertex_count: vec![3; 8],
            neighbors: vec![Vec::new(); 8],
            contacts: BTreeMap::new(),
            strength: BTreeMap::new(),
        };
        for (a, b) in [(0, 1), (1, 2), (2, 3), (2, 4), (2, 5), (0, 6), (0, 7)] {
            g.neighbors[a].push(b);
            g.neighbors[b].push(a);
            g.contacts.insert((a, b), Contact::Virtual(0, 0));
            g.strength.insert((a, b), 1);
        }
        (g.tree(anchor, TreeRule::Strongest), labels, faces, pos)
    }

    #[test]
    fn rerooting_keeps_the_edges_and_reverses_the_path() {
        let (tree, ..) = biped(2);
        let r = tree.rerooted(6);
        assert_eq!(r.root, 6);
        assert_eq!(r.parent[6], None);
        assert_eq!((r.parent[0], r.parent[1], r.parent[2]), (Some(6), Some(0), Some(1)));
        assert_eq!((r.parent[3], r.parent[7]), (Some(2), Some(0)));
        let edges = |t: &Tree| {
            let mut e: Vec<(usize, usize)> =
                t.order.iter().filter_map(|&k| t.parent[k].map(|p| (p.min(k), p.max(k)))).collect();
            e.sort();
            e
        };
        assert_eq!(edges(&tree), edges(&r));
        let mut seen = vec![false; 8];
        for &k in &r.order {
            assert!(r.parent[k].is_none_or(|p| seen[p]), "parents first");
            seen[k] = true;
        }
        assert_eq!(r.order.len(), 8);
        assert_eq!(tree.rerooted(2), tree);
        assert_eq!(tree.rerooted(99), tree);
    }

    #[test]
    fn the_root_is_the_branching_part_nearest_the_centre() {
        // rooted on the chest (the largest part), the rule picks the pelvis: both branch, the pelvis is nearer
        // the centre of area (legs heavy)
        let (tree, labels, faces, pos) = biped(2);
        assert_eq!(central_root(&tree, &labels, &faces, &pos), 0);
        // arms and head raised far: the chest comes nearer the centre than the pelvis
        let mut raised = pos.clone();
        for (v, &l) in labels.iter().enumerate() {
            if l == 3 || l == 4 || l == 5 {
                raised[v] = add(raised[v], [0.0, 3.0, 0.0]);
            }
        }
        assert_eq!(central_root(&tree, &labels, &faces, &raised), 2);
        // a chain (no part branches): the most connected, nearest the centre
        let chain = Tree { root: 0, order: vec![0, 1, 2], parent: vec![None, Some(0), Some(1)] };
        let labels3 = vec![0, 0, 0, 1, 1, 1, 2, 2, 2];
        let tri = |x: f64| [[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]];
        let pos3: Vec<Vec3> = [0.0, 2.0, 4.0].iter().flat_map(|&x| tri(x)).collect();
        let faces3 = vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        assert_eq!(central_root(&chain, &labels3, &faces3, &pos3), 1);
        // no area, or bad indices: the tree's own root, no panic
        assert_eq!(central_root(&chain, &labels3, &[[0, 0, 0]], &pos3), 0);
        assert_eq!(central_root(&chain, &labels3, &[[0, 1, 99]], &pos3), 0);
    }

    // A strip of quads (two triangles each) along x, `n` columns; labels by column.
    fn quad_strip(columns: usize) -> (Vec<[u32; 3]>, usize) {
        let mut faces = Vec::new();
        for c in 0..columns as u32 {
            let (a, b, d, e) = (2 * c, 2 * c + 1, 2 * c + 2, 2 * c + 3);
            faces.push([a, d, b]);
            faces.push([b, d, e]);
        }
        (faces, 2 * columns + 2)
    }

    #[test]
    fn a_refit_keeps_the_colours_of_unchanged_parts() {
        let (faces, n) = quad_strip(8);
        // four parts of two columns each; then the last two merged and the first split
        let before: Vec<u32> = (0..n as u32).map(|v| (v / 2).min(7) / 2).collect();
        let first = colour_parts(&before, &faces, 12);
        let after: Vec<u32> = before.iter().map(|&l| if l == 3 { 2 } else { l }).collect();
        let kept = colour_parts_like(&after, &faces, 12, &[(&before, &first)]);
        assert_eq!(kept[0], first[0]);
        assert_eq!(kept[1], first[1]);
        // part 2 of `after` holds all of the old part 2 but is twice its size: not the same part
        assert!(kept.len() == 3);
        // without a previous partition, or with another vertex count: plain colour_parts
        assert_eq!(colour_parts_like(&after, &faces, 12, &[]), colour_parts(&after, &faces, 12));
        assert_eq!(colour_parts_like(&after, &faces, 12, &[(&before[1..], &first)]), colour_parts(&after, &faces, 12));
        // a relabelled copy of the same partition keeps every colour
        let relabelled: Vec<u32> = before.iter().map(|&l| 3 - l).collect();
        let again = colour_parts_like(&relabelled, &faces, 12, &[(&before, &first)]);
        for k in 0..4 {
            assert_eq!(again[3 - k], first[k]);
        }
    }

    #[test]
    fn a_fit_like_one_before_the_last_gets_its_colours_back() {
        // fits A, B, A again: B merged A's last two parts; the second A matches A's parts, not B's
        let (faces, n) = quad_strip(8);
        let a: Vec<u32> = (0..n as u32).map(|v| (v / 2).min(7) / 2).collect();
        let b: Vec<u32> = a.iter().map(|&l| l.min(2)).collect();
        let colours_a: Vec<u32> = vec![5, 7, 9, 11];
        let colours_b = colour_parts_like(&b, &faces, 12, &[(&a, &colours_a)]);
        assert_eq!(&colours_b[..2], &colours_a[..2]);
        let again = colour_parts_like(&a, &faces, 12, &[(&b, &colours_b), (&a, &colours_a)]);
        assert_eq!(again, colours_a, "A's parts in A's colours again");
        // an older colour is not taken where a neighbour has it already: part 3 touches part 2
        let clash: Vec<u32> = vec![5, 7, 9, 9];
        let again = colour_parts_like(&a, &faces, 12, &[(&b, &colours_b), (&a, &clash)]);
        assert_ne!(again[3], again[2]);
    }

    /// Parts two steps apart (sharing a neighbour) differ too where the colours allow: on the generated
    /// quadruped's 18 true parts with 12 colours, none of them share a colour (the least-used colour alone gave
    /// the head the trunk's).
    #[test]
    fn parts_that_share_a_neighbour_get_different_colours_when_there_are_enough() {
        let g = crate::synth::generate(&crate::synth::Spec { vertices: 3000, poses: 2, ..Default::default() }).unwrap();
        let labels = &g.part_of_vertex;
        let n = g.n_parts();
        let colours = colour_parts(labels, &g.population.faces, 12);
        let adj = part_neighbours(labels, &g.population.faces, n);
        let mut clashes = Vec::new();
        for p in 0..n {
            for &q in &adj[p] {
                assert_ne!(colours[p], colours[q], "parts {p} and {q} touch");
                for &r in adj[q].iter().filter(|&&r| r > p && !adj[p].contains(&r)) {
                    if colours[p] == colours[r] {
                        clashes.push((g.part_names[p].clone(), g.part_names[r].clone()));
                    }
                }
            }
        }
        assert_eq!(clashes, Vec::<(String, String)>::new());
    }

    #[test]
    fn neighbouring_parts_get_different_colours() {
        // 30 parts in a row (each touches the next): with 12 colours, neighbours differ and the first 12
        // parts in Welsh-Powell order get 12 different colours.
        let (faces, n) = quad_strip(60);
        let labels: Vec<u32> = (0..n as u32).map(|v| (v / 2 / 2).min(29)).collect();
        let colours = colour_parts(&labels, &faces, 12);
        assert_eq!(colours.len(), 30);
        let adj = part_neighbours(&labels, &faces, 30);
        let mut pairs = 0;
        for (p, ns) in adj.iter().enumerate() {
            for &q in ns {
                assert_ne!(colours[p], colours[q], "parts {p} and {q} touch");
                pairs += 1;
            }
        }
        assert_eq!(pairs, 2 * 29, "a chain of 30 parts has 29 contacts");
        assert!(colours.iter().all(|&c| c < 12));
        let distinct: std::collections::BTreeSet<u32> = colours.iter().copied().collect();
        assert_eq!(distinct.len(), 12, "every colour is used before any repeats: {colours:?}");
        // A part that touches every other one (a hub) differs from all of them.
        let mut hub = labels.clone();
        for v in (0..n).step_by(2) {
            hub[v] = 30; // the bottom row of the strip is one part touching every column
        }
        let c = colour_parts(&hub, &faces, 12);
        for q in part_neighbours(&hub, &faces, 31)[30].iter() {
            assert_ne!(c[30], c[*q]);
        }
    }

    #[test]
    fn colouring_needs_no_more_colours_than_given() {
        let (faces, n) = quad_strip(4);
        let labels: Vec<u32> = (0..n as u32).map(|v| v % 3).collect();
        assert_eq!(colour_parts(&labels, &faces, 1), vec![0, 0, 0]);
        assert_eq!(colour_parts(&labels, &faces, 0), vec![0, 0, 0]);
        assert_eq!(colour_parts(&[], &[], 12), Vec::<u32>::new());
    }

    /// A strip of quads along x: vertices (i, y) for i = 0..=n, y = 0..rows (vertex i * rows + y); labels
    /// by column; two triangles per quad.
    fn strip_rows(
        n: usize,
        rows: usize,
        label_of_column: impl Fn(usize) -> u32,
    ) -> (Vec<u32>, Vec<[u32; 3]>, Vec<Vec3>) {
        let mut pos = Vec::new();
        let mut labels = Vec::new();
        for i in 0..=n {
            for y in 0..rows {
                pos.push([i as f64, y as f64, 0.0]);
                labels.push(label_of_column(i));
            }
        }
        let mut faces = Vec::new();
        let r = rows as u32;
        for i in 0..n as u32 {
            for y in 0..r - 1 {
                let (a, b, c, d) = (i * r + y, i * r + y + 1, (i + 1) * r + y, (i + 1) * r + y + 1);
                faces.push([a, c, b]);
                faces.push([b, c, d]);
            }
        }
        (labels, faces, pos)
    }

    fn strip(n: usize, label_of_column: impl Fn(usize) -> u32) -> (Vec<u32>, Vec<[u32; 3]>, Vec<Vec3>) {
        strip_rows(n, 2, label_of_column)
    }

    #[test]
    fn edges_are_unique_and_sorted() {
        let e = mesh_edges(&[[0, 1, 2], [2, 1, 3]]);
        assert_eq!(e, vec![[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]);
    }

    #[test]
    fn chain_adjacency_contacts_and_trees() {
        // parts 0 | 1 | 2 along the strip, part 3 unused
        let (labels, faces, pos) = strip(9, |i| (i / 4).min(2) as u32);
        let g = PartGraph::new(&labels, &faces, 4, &pos, &[]);
        assert_eq!(g.neighbors, vec![vec![1], vec![0, 2], vec![1], vec![]]);
        assert_eq!(g.used_parts(), vec![0, 1, 2]);
        // columns 3|4: one quad (2 triangles) and 3 crossing edges (two horizontal, one diagonal)
        assert_eq!(g.strength(0, 1), 3);
        let Some(Contact::Triangles(t)) = g.contact(1, 0) else { panic!("no contact") };
        assert_eq!(t, &vec![6, 7]);
        for rule in [TreeRule::Strongest, TreeRule::BreadthFirst] {
            let tr = g.tree(1, rule);
            assert_eq!(tr.order, vec![1, 0, 2]);
            assert_eq!(tr.parent, vec![Some(1), None, Some(1), None]);
            assert_eq!(tr.depths(), vec![Some(1), Some(0), Some(1), None]);
            let tr = g.tree(0, rule);
            assert_eq!(tr.parent, vec![None, Some(0), Some(1), None]);
        }
    }

    #[test]
    fn strongest_tree_ignores_a_weak_island_contact() {
        // 0: columns 0..=5, 1: columns 6..=11, 2: columns 12..=14, 5 rows, plus an island of part 2 at
        // column 2 of part 0 (one vertex). BFS from 0 hangs 2 on 0 through the island; the strongest tree
        // hangs it on 1.
        let (mut labels, faces, pos) = strip_rows(14, 5, |i| {
            if i <= 5 {
                0
            } else if i <= 11 {
                1
            } else {
                2
            }
        });
        labels[10] = 2; // vertex (2, 0)
        let g = PartGraph::new(&labels, &faces, 3, &pos, &[]);
        assert_eq!(g.neighbors[0], vec![1, 2]);
        assert!(g.strength(0, 2) < g.strength(1, 2));
        assert_eq!(g.tree(0, TreeRule::BreadthFirst).parent[2], Some(0));
        assert_eq!(g.tree(0, TreeRule::Strongest).parent[2], Some(1));
        // the contact of (1, 2) is its one real patch; the contact of (0, 2) is the island's patch
        let Some(Contact::Triangles(t)) = g.contact(0, 2) else { panic!() };
        assert!(t.iter().all(|&t| faces[t].contains(&10)));
    }

    #[test]
    fn largest_patch_is_kept() {
        // part 1 = columns 0..=2 and 8..=12 (two patches against part 0 in the middle, the second larger
        // because the mesh is stretched there)
        let (labels, faces, mut pos) = strip(12, |i| if (3..=7).contains(&i) { 0 } else { 1 });
        for p in &mut pos {
            if p[0] >= 7.0 {
                p[1] *= 3.0;
            }
        }
        let g = PartGraph::new(&labels, &faces, 2, &pos, &[]);
        let Some(Contact::Triangles(t)) = g.contact(0, 1) else { panic!() };
        // patch at columns 7|8 = quad 7 = triangles 14, 15
        assert_eq!(t, &vec![14, 15]);
    }

    #[test]
    fn disconnected_pieces_get_a_virtual_contact() {
        // two separate strips: part 0 on one, part 1 on the other, 5 units apart in y
        let (l1, f1, p1) = strip(3, |_| 0);
        let n = p1.len() as u32;
        let (_, f2, p2) = strip(3, |_| 1);
        let labels: Vec<u32> = l1.iter().copied().chain(std::iter::repeat(1).take(p2.len())).collect();
        let faces: Vec<[u32; 3]> = f1.iter().copied().chain(f2.iter().map(|f| f.map(|v| v + n))).collect();
        let pos: Vec<Vec3> = p1.iter().copied().chain(p2.iter().map(|p| [p[0], p[1] + 5.0, p[2]])).collect();
        let g = PartGraph::new(&labels, &faces, 2, &pos, &[]);
        assert_eq!(g.neighbors, vec![vec![1], vec![0]]);
        let Some(&Contact::Virtual(a, b)) = g.contact(0, 1) else { panic!("{:?}", g.contacts) };
        assert_eq!(labels[a as usize], 0);
        assert_eq!(labels[b as usize], 1);
        // the closest pair: a vertex at y = 1 of the first strip and one at y = 5 of the second
        assert!((norm(sub(pos[a as usize], pos[b as usize])) - 4.0).abs() < 1e-12);
        assert_eq!(g.tree(0, TreeRule::Strongest).order, vec![0, 1]);
    }

    #[test]
    fn moments_give_the_rms_radius() {
        let m = Moments::of(
            [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [3.0, 2.0, 0.0], [3.0, -2.0, 0.0]].map(|p| add(p, [5.0, 5.0, 5.0])),
        );
        // centroid (1.5, 0, 0) + 5: distances 0.5, 2.5, 2.5, 2.5 -> mean square (0.25 + 3 * 6.25) / 4
        assert!((m.rms_radius() - ((0.25 + 3.0 * 6.25) / 4.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(Moments::default().rms_radius(), 0.0);
    }

    /// The 12 triangles of the box from `lo` to `hi`, its 8 corners numbered from `base`.
    fn cuboid(lo: Vec3, hi: Vec3, base: u32) -> (Vec<[u32; 3]>, Vec<Vec3>) {
        let corner = |k: u32| {
            [[lo[0], hi[0]][(k & 1) as usize], [lo[1], hi[1]][(k >> 1 & 1) as usize], [lo[2], hi[2]][(k >> 2) as usize]]
        };
        let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
        let faces =
            quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]].map(|t| t.map(|v| v + base))).collect();
        (faces, (0..8).map(corner).collect())
    }

    #[test]
    fn separate_boxes_that_touch_join_at_the_face_between_them() {
        // a torso box and an arm box beside it (x 1..1.5), touching on the arm's inner face, whose centre is
        // (1, 1.25, 0); the arm's nearest corner to the torso is a corner of that face
        let (f0, p0) = cuboid([-1.0, 0.0, -0.25], [1.0, 2.0, 0.25], 0);
        let (f1, p1) = cuboid([1.0, 0.5, -0.25], [1.5, 2.0, 0.25], 8);
        let labels: Vec<u32> = [0; 8].into_iter().chain([1; 8]).collect();
        let (faces, pos) = ([f0, f1.clone()].concat(), [p0, p1.clone()].concat());
        let g = PartGraph::new(&labels, &faces, 2, &pos, &[]);
        let Some(Contact::Touching(t)) = g.contact(0, 1) else { panic!("{:?}", g.contacts) };
        // the arm's inner face (x = 1), both its triangles; none of the torso's faces lies wholly on the arm
        assert_eq!(t, &vec![12 + 8, 12 + 9]);
        let c = crate::articulate::joints::area_centroid(t, &faces, &pos);
        assert!(norm(sub(c, [1.0, 1.25, 0.0])) < 1e-12, "{c:?}");
        // moved a hair away (0.002, under 1 % of the arm's radius, 0.83) the faces still touch: the same triangles
        let moved = |d: Vec3| -> Vec<Vec3> {
            pos.iter().enumerate().map(|(v, p)| if v < 8 { *p } else { add(*p, d) }).collect()
        };
        let g = PartGraph::new(&labels, &faces, 2, &moved([0.002, 0.0, 0.0]), &[]);
        assert_eq!(g.contact(0, 1), Some(&Contact::Touching(vec![20, 21])));
        // 0.2 away they do not: the closest corners
        let g = PartGraph::new(&labels, &faces, 2, &moved([0.2, 0.0, 0.0]), &[]);
        assert!(matches!(g.contact(0, 1), Some(Contact::Virtual(..))), "{:?}", g.contacts);
        // above and beside the torso only their corners are near: the closest corners
        let g = PartGraph::new(&labels, &faces, 2, &moved([0.2, 1.7, 0.0]), &[]);
        assert!(matches!(g.contact(0, 1), Some(Contact::Virtual(..))), "{:?}", g.contacts);
    }

    #[test]
    fn separate_pieces_join_where_they_move_least_apart() {
        // three separate strips: a body (x 0..3, y 0..1), an arm above it (x 0..3, y 1.6..2.6; gap 0.6) and a leg
        // beside the arm (x 4..7, y 1.6..2.6; 1.0 from the arm, 1.17 from the body's corner)
        let piece = |label: u32, offset: [f64; 2], base: u32| {
            let (_, f, p) = strip(3, move |_| label);
            (
                f.iter().map(|t| t.map(|v| v + base)).collect::<Vec<_>>(),
                p.iter().map(|q| [q[0] + offset[0], q[1] + offset[1], q[2]]).collect::<Vec<_>>(),
            )
        };
        let (f1, p1) = piece(0, [0.0, 0.0], 0);
        let n = p1.len();
        let (f2, p2) = piece(1, [0.0, 1.6], n as u32);
        let (f3, p3) = piece(2, [4.0, 1.6], 2 * n as u32);
        let labels: Vec<u32> = (0..3 * n).map(|v| (v / n) as u32).collect();
        let faces: Vec<[u32; 3]> = f1.iter().chain(&f2).chain(&f3).copied().collect();
        let pos: Vec<Vec3> = p1.iter().chain(&p2).chain(&p3).copied().collect();
        let keys = |g: &PartGraph| g.contacts.keys().copied().collect::<Vec<_>>();
        // by distance alone: body-arm and arm-leg
        let g = PartGraph::new(&labels, &faces, 3, &pos, &[]);
        assert_eq!(keys(&g), vec![(0, 1), (1, 2)]);
        let Some(&Contact::Virtual(a, b)) = g.contact(0, 1) else { panic!() };
        assert!((norm(sub(pos[a as usize], pos[b as usize])) - 0.6).abs() < 1e-12);
        // the leg moves with the body and the arm swings about its foot: the leg joins the body, not the arm
        let still = vec![RigidMotion::IDENTITY; 4];
        let swing: Vec<RigidMotion> = (0..4)
            .map(|i| {
                let r = crate::geometry::rotation::axis_angle([0.0, 0.0, 1.0], 0.3 * i as f64);
                let pivot = [1.5, 1.6, 0.0];
                RigidMotion { rotation: r, translation: sub(pivot, crate::geometry::mat_vec(&r, pivot)) }
            })
            .collect();
        let g = PartGraph::new(&labels, &faces, 3, &pos, &[still.clone(), swing, still]);
        assert_eq!(keys(&g), vec![(0, 1), (0, 2)]);
        assert_eq!(g.tree(0, TreeRule::Strongest).parent, vec![None, Some(0), Some(0)]);
    }
}
