//! The pair-blend residual: what a skinning rig with fitted weights leaves of a vertex's motion, two influences
//! at a time, and how much cutting a part in two lowers it ([`Blends::split_drop`], the split
//! [`super::part_count`] makes to reach `--bones N`).
//!
//! For a vertex j (h_j^i its point in shape i) and a set C of parts that may move it,
//!
//! ```text
//! r(j; C) = min_{a, b in C} min_{w in [0, 1]} Σ_i |h_j^i - (1 - w) T_a(j)^i - w T_b(j)^i|²
//! ```
//!
//! with T_p(j) the vertex's best rigid trajectory under part p's motion (the mean of its points brought back
//! by p's inverse motions, placed again in every shape: [`super::distinct::rigid_trajectory`], as
//! [`super::distinct::blend_fit_ratio`] blends two sides): a blend of two bones whose weights sum to 1, fitted
//! per vertex, with no constant term. With e_p = h_j - T_p(j) and G_pq = Σ_i e_p^i · e_q^i, the pair (a, b)
//! leaves G_aa - 2 w (G_aa - G_ab) + w² (G_aa - 2 G_ab + G_bb) at w = (G_aa - G_ab) / (G_aa - 2 G_ab + G_bb)
//! clamped to [0, 1] (w = 0 or 1: one bone alone). With one part in C, r = G_aa.
//!
//! A vertex is offered its own part l_j and the parts adjacent to it (sharing a mesh edge): C_j = {l_j} ∪
//! adj(l_j). The **split drop** of part k cut into halves A and B is
//!
//! ```text
//! D(k; A, B) = Σ_{j in k ∪ adj(k)} r(j; C_j) - r(j; C_j with k replaced by A and B)
//! ```
//!
//! every part's motion fitted to its own vertices in closed form
//! ([`crate::mfa::init::component_from_points`]): the part's motion before, its two halves' after. Splitting
//! where D is largest puts the new bone where a rig blending two bones per vertex gains the most, which the
//! classification log-likelihood of the part alone does not see (a cut between two bones a blend already
//! explains gains log-likelihood without helping the rig).

use super::distinct::{rigid_trajectory, two_bone_blend};
use super::labels::adjacency;
use crate::geometry::Vec3;
use crate::mfa::data::Data;
use crate::mfa::Component;

/// r(j; C) of the module doc for the points `h` of one vertex and the motions of the parts in C. `errors` is
/// scratch space (reused between calls).
pub fn pair_blend_residual(h: &[Vec3], parts: &[&Component], errors: &mut Vec<Vec3>) -> f64 {
    let ns = h.len();
    let m = parts.len();
    if m == 0 {
        return f64::INFINITY;
    }
    errors.resize(m * ns, [0.0; 3]);
    for (p, part) in parts.iter().enumerate() {
        let e = &mut errors[p * ns..(p + 1) * ns];
        rigid_trajectory(part, h, e);
        for (x, hi) in e.iter_mut().zip(h) {
            *x = [hi[0] - x[0], hi[1] - x[1], hi[2] - x[2]];
        }
    }
    let dot = |p: usize, q: usize| -> f64 {
        let (a, b) = (&errors[p * ns..(p + 1) * ns], &errors[q * ns..(q + 1) * ns]);
        a.iter().zip(b).map(|(x, y)| x[0] * y[0] + x[1] * y[1] + x[2] * y[2]).sum()
    };
    let diag: Vec<f64> = (0..m).map(|p| dot(p, p)).collect();
    let mut best = diag.iter().copied().fold(f64::INFINITY, f64::min);
    for a in 0..m {
        for b in a + 1..m {
            // e_b = e_a - d: Σ e_a·d = G_aa - G_ab, Σ|d|² = G_aa - 2 G_ab + G_bb
            let gab = dot(a, b);
            best = best.min(two_bone_blend(diag[a], diag[a] - gab, diag[a] - 2.0 * gab + diag[b]));
        }
    }
    best
}

/// The parts of a labelling, their motions and every vertex's r(j; C_j), kept up to date while parts are split.
pub struct Blends<'a> {
    data: &'a Data,
    faces: &'a [[u32; 3]],
    labels: Vec<u32>,
    /// Parts adjacent to each part (sorted).
    adjacent: Vec<Vec<usize>>,
    members: Vec<Vec<usize>>,
    /// Each part's motion (None: a part without vertices).
    motions: Vec<Option<Component>>,
    /// r(j; C_j) of every vertex, NaN until computed (and again once C_j changes).
    own: Vec<f64>,
}

impl<'a> Blends<'a> {
    /// `motions[p]`: part p's motion (a component of `data`'s frame), for every label in `labels`.
    pub fn new(data: &'a Data, faces: &'a [[u32; 3]], labels: Vec<u32>, motions: Vec<Option<Component>>) -> Blends<'a> {
        let (adjacent, members) = adjacency(&labels, faces, motions.len());
        let own = vec![f64::NAN; labels.len()];
        Blends { data, faces, labels, adjacent, members, motions, own }
    }

    /// C_j's motions, with part k's replaced by `halves` when given.
    fn offered<'b>(&'b self, j: usize, k: usize, halves: Option<&'b [Component; 2]>, out: &mut Vec<&'b Component>) {
        out.clear();
        let l = self.labels[j] as usize;
        for p in std::iter::once(l).chain(self.adjacent[l].iter().copied()) {
            match halves {
                Some(h) if p == k => out.extend(h.iter()),
                _ => out.extend(self.motions[p].as_ref()),
            }
        }
    }

    /// The vertices of part k and of the parts adjacent to it.
    fn near(&self, k: usize) -> Vec<usize> {
        let mut region: Vec<usize> = self.members[k].clone();
        for &p in &self.adjacent[k] {
            region.extend_from_slice(&self.members[p]);
        }
        region
    }

    /// D(k; A, B) of the module doc, for part k cut into two halves moved by `motions`.
    pub fn split_drop(&mut self, k: usize, motions: &[Component; 2]) -> f64 {
        let (before, after) = self.split_residuals(k, motions);
        before - after
    }

    /// The two sums of D(k; A, B): Σ_j r(j; C_j) and Σ_j r(j; C_j with k replaced by A and B), over the vertices
    /// of part k and of the parts adjacent to it.
    pub fn split_residuals(&mut self, k: usize, motions: &[Component; 2]) -> (f64, f64) {
        let region = self.near(k);
        let (mut h, mut errors, mut offered) = (Vec::new(), Vec::new(), Vec::new());
        // (taken out while `offered` borrows the motions)
        let mut own = std::mem::take(&mut self.own);
        let (mut before, mut after) = (0.0, 0.0);
        for j in region {
            let h = self.data.vertex_into(j, &mut h);
            if own[j].is_nan() {
                self.offered(j, k, None, &mut offered);
                own[j] = pair_blend_residual(h, &offered, &mut errors);
            }
            self.offered(j, k, Some(motions), &mut offered);
            before += own[j];
            after += pair_blend_residual(h, &offered, &mut errors);
        }
        self.own = own;
        (before, after)
    }

    /// Part k cut: `moved` (some of k's vertices) become part `new` (the next label), k keeps the rest; the two
    /// halves move by `motions`. Returns the parts whose split drops changed (those within two adjacencies of
    /// k before the cut, and k and `new`).
    pub fn apply_split(&mut self, k: usize, moved: &[usize], motions: [Component; 2]) -> Vec<usize> {
        let new = self.motions.len();
        let mut stale: Vec<usize> = vec![k, new];
        for &p in &self.adjacent[k] {
            stale.push(p);
            stale.extend_from_slice(&self.adjacent[p]);
        }
        stale.sort_unstable();
        stale.dedup();
        // every vertex offered k before: k's and its neighbours'
        for p in std::iter::once(k).chain(self.adjacent[k].iter().copied()) {
            for &j in &self.members[p] {
                self.own[j] = f64::NAN;
            }
        }
        for &j in moved {
            self.labels[j] = new as u32;
        }
        let [a, b] = motions;
        self.motions[k] = Some(a);
        self.motions.push(Some(b));
        let (adjacent, members) = adjacency(&self.labels, self.faces, self.motions.len());
        self.adjacent = adjacent;
        self.members = members;
        stale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mfa::init::component_from_points;
    use crate::synth::{generate, part_index, Preset, Spec};

    #[test]
    fn one_bone_or_a_blend_of_two_is_what_is_left() {
        use crate::geometry::rotation::axis_angle;
        let part = |angles: &[f64]| Component {
            rotations: angles.iter().map(|&a| axis_angle([0.0, 0.0, 1.0], a)).collect(),
            translations: vec![[0.0; 3]; angles.len()],
            lambda: [0.1; 3],
            variances: vec![1e-6; angles.len()],
            weight: 1.0,
        };
        let (a, b) = (part(&[0.0, 0.4, -0.3, 0.8]), part(&[0.0, -0.2, 0.5, 0.1]));
        let x = [1.0, 0.5, 0.2];
        let (ta, tb): (Vec<Vec3>, Vec<Vec3>) =
            ((0..4).map(|i| a.place(i, x)).collect(), (0..4).map(|i| b.place(i, x)).collect());
        let mut e = Vec::new();
        // moved by a alone: nothing left, with a offered; something without it
        assert!(pair_blend_residual(&ta, &[&a, &b], &mut e) < 1e-20);
        assert!(pair_blend_residual(&ta, &[&b], &mut e) > 1e-3);
        // 30 % of the way from a to b, per shape: a blend of the two leaves little (each bone's best rigid
        // trajectory of a point that is not rigid under it is not the point's own; measured 0.024 against 0.14)
        let h: Vec<Vec3> = ta.iter().zip(&tb).map(|(p, q)| std::array::from_fn(|c| 0.7 * p[c] + 0.3 * q[c])).collect();
        let (blend, alone) = (pair_blend_residual(&h, &[&b, &a], &mut e), pair_blend_residual(&h, &[&a], &mut e));
        assert!(blend < 0.25 * alone);
        assert_eq!(pair_blend_residual(&h, &[], &mut e), f64::INFINITY);
    }

    #[test]
    fn the_drop_prefers_the_cut_between_two_true_parts_over_one_inside_a_part() {
        // the arm's upper arm and forearm as one part; cut at the elbow (the truth) or across the forearm
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let idx = |name| part_index(Preset::Arm, name).unwrap() as u32;
        let (upper, forearm) = (idx("upper_arm"), idx("forearm"));
        let mut labels = g.part_of_vertex.clone();
        labels.iter_mut().filter(|l| **l == forearm).for_each(|l| *l = upper);
        let k = upper as usize;
        let arm: Vec<usize> = (0..labels.len()).filter(|&j| labels[j] == upper).collect();
        let data = Data::from_population(pop);
        let fit = |m: &[usize]| component_from_points(&data, m, labels.len(), 1e-12);
        let n = labels.iter().map(|&l| l as usize + 1).max().unwrap();
        let motions: Vec<Option<Component>> = (0..n)
            .map(|p| {
                let m: Vec<usize> = (0..labels.len()).filter(|&j| labels[j] as usize == p).collect();
                (!m.is_empty()).then(|| fit(&m))
            })
            .collect();
        let mut blends = Blends::new(&data, pop.graph_faces(), labels.clone(), motions);
        // the truth's cut
        let (fore, rest): (Vec<usize>, Vec<usize>) = arm.iter().partition(|&&j| g.part_of_vertex[j] == forearm);
        let (before, truth) = blends.split_residuals(k, &[fit(&rest), fit(&fore)]);
        // cuts inside a true part: across the forearm or the upper arm halfway along it (by the rest pose's distance
        // from the elbow), each half one connected piece
        let elbow = g.joint_centers[forearm as usize].expect("the forearm has a joint");
        let from_elbow = |j: usize| crate::geometry::norm(crate::geometry::sub(g.rest[j], elbow));
        let mut across = |part: u32| -> f64 {
            let mut d: Vec<f64> =
                arm.iter().filter(|&&j| g.part_of_vertex[j] == part).map(|&j| from_elbow(j)).collect();
            d.sort_by(f64::total_cmp);
            let mid = d[d.len() / 2];
            let (a, b): (Vec<usize>, Vec<usize>) =
                arm.iter().partition(|&&j| g.part_of_vertex[j] != part || from_elbow(j) < mid);
            blends.split_residuals(k, &[fit(&a), fit(&b)]).1
        };
        let (in_fore, in_upper) = (across(forearm), across(upper));
        // what is left after each cut: the truth's leaves a blend that explains the arm (measured 0.002 of 1.55,
        // against 0.20 and 0.08 inside the forearm and the upper arm), so its drop is the largest
        let msg = format!("before {before}, left by the truth's cut {truth}, inside {in_fore} / {in_upper}");
        assert!(truth < 0.01 * before && truth < 0.1 * in_fore.min(in_upper), "{msg}");
        assert!(blends.split_drop(k, &[fit(&rest), fit(&fore)]) > before - in_fore.min(in_upper), "{msg}");
        // applied, the truth's cut makes the drops near it stale, and cutting the rigid forearm again gains little
        let stale = blends.apply_split(k, &fore, [fit(&rest), fit(&fore)]);
        assert!(stale.contains(&k) && stale.contains(&n));
        let again = blends.split_drop(n, &[fit(&fore[..fore.len() / 2]), fit(&fore[fore.len() / 2..])]);
        assert!(again.abs() < 0.05 * (before - truth), "again {again}, {msg}");
    }
}
