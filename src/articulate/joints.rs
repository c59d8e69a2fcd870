//! Joints: where two adjacent parts meet in every training shape, and that point's image in each part's
//! latent frame.
//!
//! J_pc^i: the area-weighted centroid of the contact triangles (those with vertices in both p and c) in
//! shape i (docs/method.md, item 10). Its latent image in part k is Λ_k E_k[z | J_pc] (eq 23 mapped through Λ,
//! item 4): the point of part k's latent shape that part k's rigid motions send closest to J_pc^i, all
//! shapes together. For a virtual contact (disconnected mesh pieces) J^i is the midpoint of its two vertices; for
//! pieces that touch, the area-weighted centroid of the triangles where they lie against each other.
//!
//! Eq 23 pins the child to the parent at that point. In a training shape the two parts do not meet there
//! exactly: the parent places it at R_p^i e_p + b_p^i, the child at R_c^i e_c + b_c^i. [`Joint::offset`] is
//! that mismatch in the parent's latent frame; blending it in t makes Algorithm 2 reproduce both end poses.

use super::graph::{triangle_area, Contact, PartGraph};
use super::RigidMotion;
use crate::geometry::{add, mat_t_vec, norm, scale, sub, Vec3};
use crate::mfa::Model;
use std::collections::BTreeMap;

/// One contact between parts `a` < `b`.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub a: usize,
    pub b: usize,
    /// J^i, one per shape (unit box).
    pub points: Vec<Vec3>,
    /// Λ_a E_a[z | J] and Λ_b E_b[z | J]: the joint in the latent frames of a and b.
    pub latent_a: Vec3,
    pub latent_b: Vec3,
}

impl Joint {
    /// The joint in part `k`'s latent frame (k must be a or b).
    pub fn latent(&self, k: usize) -> Vec3 {
        if k == self.a {
            self.latent_a
        } else {
            debug_assert_eq!(k, self.b);
            self.latent_b
        }
    }

    /// d^i = R_p^iT [(R_p^i e_p + b_p^i) - (R_c^i e_c + b_c^i)]: in shape i, how far the parent's image of
    /// the joint is from the child's, in the parent's latent frame.
    pub fn offset(&self, model: &Model, parent: usize, child: usize, shape: usize) -> Vec3 {
        let (p, c) = (&model.parts[parent], &model.parts[child]);
        let at_parent = p.place(shape, self.latent(parent));
        let at_child = c.place(shape, self.latent(child));
        mat_t_vec(&p.rotations[shape], sub(at_parent, at_child))
    }
}

/// Area-weighted centroid of triangles `tris` in one pose; the plain mean of their corners if every
/// triangle is degenerate.
pub fn area_centroid(tris: &[usize], faces: &[[u32; 3]], positions: &[Vec3]) -> Vec3 {
    let (mut c, mut w) = ([0.0; 3], 0.0);
    let (mut m, mut n) = ([0.0; 3], 0.0f64);
    for &t in tris {
        let f = faces[t];
        let (p0, p1, p2) = (positions[f[0] as usize], positions[f[1] as usize], positions[f[2] as usize]);
        let centre = scale(add(add(p0, p1), p2), 1.0 / 3.0);
        let a = triangle_area(p0, p1, p2);
        c = add(c, scale(centre, a));
        w += a;
        m = add(m, centre);
        n += 1.0;
    }
    if w > 0.0 {
        scale(c, 1.0 / w)
    } else {
        scale(m, 1.0 / n.max(1.0))
    }
}

/// Every contact's joint, keyed (smaller, larger) like [`PartGraph::contacts`]. `shapes`: the training shapes in
/// order (unit box), read one at a time.
pub fn joints<S: AsRef<[Vec3]>>(
    graph: &PartGraph,
    model: &Model,
    faces: &[[u32; 3]],
    shapes: impl IntoIterator<Item = S>,
) -> BTreeMap<(usize, usize), Joint> {
    let mut points: Vec<Vec<Vec3>> = vec![Vec::new(); graph.contacts.len()];
    for s in shapes {
        let s = s.as_ref();
        for (contact, p) in graph.contacts.values().zip(points.iter_mut()) {
            p.push(match contact {
                Contact::Triangles(t) | Contact::Touching(t) => area_centroid(t, faces, s),
                Contact::Virtual(u, v) => scale(add(s[*u as usize], s[*v as usize]), 0.5),
            });
        }
    }
    graph
        .contacts
        .keys()
        .zip(points)
        .map(|(&(a, b), points)| {
            let latent_a = model.parts[a].latent_image(&points);
            let latent_b = model.parts[b].latent_image(&points);
            ((a, b), Joint { a, b, points, latent_a, latent_b })
        })
        .collect()
}

/// The normal equations of the point x that a child and its parent bone move most alike over the poses,
/// min Σ_i |(R_c^i - R_p^i) x + t_c^i - t_p^i|²: (Σ ΔRᵀΔR, -Σ ΔRᵀ Δt), row-major, one (child, parent) pair of
/// motions per pose. [`pivot`] and the fixed joints' points ([`super::rig`]) add their own pull to them.
pub(crate) fn joint_normal_equations<'a>(
    pairs: impl Iterator<Item = (&'a RigidMotion, &'a RigidMotion)>,
) -> ([f64; 9], [f64; 3]) {
    let mut a = [0.0; 9];
    let mut b = [0.0; 3];
    for (mk, mp) in pairs {
        let dr = mk.rotation - mp.rotation;
        let dt = sub(mk.translation, mp.translation);
        for r in 0..3 {
            for c in 0..3 {
                a[r * 3 + c] += (0..3).map(|m| dr[(m, r)] * dr[(m, c)]).sum::<f64>();
            }
            b[r] -= (0..3).map(|m| dr[(m, r)] * dt[m]).sum::<f64>();
        }
    }
    (a, b)
}

/// Where a free joint's node goes: the point that parent and child move most alike over the poses (the pivot),
/// pulled toward `contact` (the contact centroid) the more, the less the joint turns, and kept within `radius`
/// of it. `child`, `parent`: the two bones' motions from the bind pose, one per pose.
///
/// Minimises Σ_i |(R_c^i - R_p^i) x + t_c^i - t_p^i|² + μ |x - contact|² with μ = μ_rel tr/3 + μ_abs n: tr/3 is
/// the mean eigenvalue of Σ_i ΔR_iᵀΔR_i (a hinge leaves its axis undetermined; μ_rel ties it to the contact),
/// and μ_abs n is what n poses that each turn [`PIVOT_TURN`] would give, so a joint that turns much less than
/// that stays near the contact and one that turns much more goes to its pivot. The answer is then drawn back
/// along the line to `contact` to at most `radius` from it (a pivot the poses leave undetermined can fall far
/// outside the body). `contact` itself when the motions are empty or the system singular.
///
/// `axial`: where along a hinge's axis the joint goes, when the contact does not say (two separate pieces that
/// touch side by side: a box arm against a box torso swings about an axis through the contact face, and the
/// artist's shoulder is on the arm's middle line, not on its face). The anchor then takes `axial`'s coordinate
/// along the axis ([`hinge_anchor`]).
pub fn pivot(child: &[RigidMotion], parent: &[RigidMotion], contact: Vec3, radius: f64, axial: Option<Vec3>) -> Vec3 {
    let (mu_rel, turn, guard) = (PIVOT_MU_REL, PIVOT_TURN, PIVOT_GUARD);
    let n = child.len().min(parent.len());
    if n == 0 {
        return contact;
    }
    let (mut a, mut b) = joint_normal_equations(child.iter().zip(parent).take(n));
    let tr = a[0] + a[4] + a[8];
    // |R - I|_F² = 4 (1 - cos θ) for a turn θ
    let mu = mu_rel * tr / 3.0 + n as f64 * 4.0 * (1.0 - turn.cos()) + 1e-12;
    let anchor = match axial {
        Some(g) => hinge_anchor(&a, mu, contact, g),
        None => contact,
    };
    for r in 0..3 {
        a[r * 3 + r] += mu;
        b[r] += mu * anchor[r];
    }
    let Some(x) = solve3(a, b) else { return contact };
    if !x.iter().all(|c| c.is_finite()) {
        return contact;
    }
    let d = sub(x, contact);
    let len = norm(d);
    let limit = guard * radius.max(0.0);
    if len > limit {
        if len > 0.0 && limit > 0.0 {
            return add(contact, scale(d, limit / len));
        }
        return contact;
    }
    x
}

/// The anchor of a hinge's undetermined axis: `contact` moved along the axis u (the eigenvector of the smallest
/// eigenvalue λ₀ of Σ ΔRᵀΔR, `a` row-major) toward `axial`'s coordinate, by the weight (λ₁ - λ₀) / (λ₁ + μ), μ the
/// pivot's pull: near 1 for a hinge (its turns share one axis, λ₀ ≈ 0) that turns well beyond the pull, so that
/// the poses fix the other two directions; near 0 for a joint that turns about every axis (λ₀ ≈ λ₁) or turns
/// little (λ₁ ≪ μ), which stays at its contact.
pub fn hinge_anchor(a: &[f64; 9], mu: f64, contact: Vec3, axial: Vec3) -> Vec3 {
    if !a.iter().chain(&axial).chain(&contact).all(|v| v.is_finite()) {
        return contact;
    }
    let m = nalgebra::Matrix3::from_row_slice(a);
    let eig = nalgebra::SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let (l0, l1) = (eig.eigenvalues[order[0]].max(0.0), eig.eigenvalues[order[1]]);
    if !(l1 > 0.0) || !l1.is_finite() {
        return contact;
    }
    let weight = ((l1 - l0) / (l1 + mu)).clamp(0.0, 1.0);
    let u = eig.eigenvectors.column(order[0]);
    let u = [u[0], u[1], u[2]];
    add(contact, scale(u, weight * crate::geometry::dot(u, sub(axial, contact))))
}

/// [`pivot`]'s pull relative to the mean eigenvalue.
pub const PIVOT_MU_REL: f64 = 0.1;
/// [`pivot`]'s turn (radians): a joint turning this much in every pose is pulled as much as it is free.
pub const PIVOT_TURN: f64 = 5.0 * std::f64::consts::PI / 180.0;
/// [`pivot`]'s guard, in contact radii.
pub const PIVOT_GUARD: f64 = 1.0;

/// 3 x 3 solve by Cramer's rule; None when singular.
fn solve3(a: [f64; 9], b: [f64; 3]) -> Option<Vec3> {
    let det = |m: &[f64; 9]| {
        m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6])
    };
    let d = det(&a);
    if !(d.abs() > 1e-300) || !d.is_finite() {
        return None;
    }
    let mut x = [0.0; 3];
    for (c, xc) in x.iter_mut().enumerate() {
        let mut m = a;
        for r in 0..3 {
            m[r * 3 + c] = b[r];
        }
        *xc = det(&m) / d;
    }
    Some(x)
}

/// The radius of a contact in `positions`: the largest distance of its vertices from `centre`; for a virtual
/// contact (two vertices of separate pieces, which say little of where the joint is), that of the child part's
/// vertices (`child_vertices`) from their own centroid.
pub fn contact_radius(
    contact: &Contact,
    faces: &[[u32; 3]],
    positions: &[Vec3],
    centre: Vec3,
    child_vertices: &[usize],
) -> f64 {
    match contact {
        Contact::Triangles(t) | Contact::Touching(t) => t
            .iter()
            .flat_map(|&t| faces.get(t).copied().unwrap_or([0; 3]))
            .filter_map(|v| positions.get(v as usize))
            .map(|&p| norm(sub(p, centre)))
            .fold(0.0, f64::max),
        Contact::Virtual(..) => {
            let Some(c) = vertex_centroid(child_vertices, positions) else { return 0.0 };
            child_vertices.iter().filter_map(|&v| positions.get(v)).map(|&p| norm(sub(p, c))).fold(0.0, f64::max)
        }
    }
}

/// The mean of the `vertices`' positions that exist; None when there are none.
fn vertex_centroid(vertices: &[usize], positions: &[Vec3]) -> Option<Vec3> {
    let (sum, n) =
        vertices.iter().filter_map(|&v| positions.get(v)).fold(([0.0; 3], 0usize), |(s, n), &p| (add(s, p), n + 1));
    (n > 0).then(|| scale(sum, 1.0 / n as f64))
}

/// A fitted rig's free joints placed as an artist would: the skeleton re-rooted on its central part
/// ([`super::graph::central_root`]), each non-root joint at its [`pivot`] (from the fitted bones), the root at
/// its part's centroid. Changes neither bones nor weights: what the rig plays is the same.
pub fn place_free_joints(art: &super::Articulation, rig: &mut super::rig::Rig, bind: usize) {
    let rest = &rig.rest;
    let labels = &art.model.labels;
    let root = super::graph::central_root(&rig.tree, labels, &art.faces, rest);
    let tree = rig.tree.rerooted(root);
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); rig.joint_points.len()];
    for (v, &l) in labels.iter().enumerate() {
        if let Some(m) = members.get_mut(l as usize) {
            m.push(v);
        }
    }
    let ns = rig.bones.len();
    for &k in &tree.order {
        let contact = art.training_motion(k, bind).apply(art.node_offset(&tree, k));
        rig.joint_points[k] = contact;
        let Some(p) = tree.parent[k] else { continue };
        let Some(c) = art.graph.contacts.get(&(p.min(k), p.max(k))) else { continue };
        let radius = contact_radius(c, &art.faces, rest, contact, &members[k]);
        let child: Vec<RigidMotion> = (0..ns).map(|i| rig.bones[i][k]).collect();
        let parent: Vec<RigidMotion> = (0..ns).map(|i| rig.bones[i][p]).collect();
        // separate pieces: a hinge's joint on the child's middle along the axis
        let separate = matches!(c, Contact::Touching(_) | Contact::Virtual(..));
        let axial = if separate { vertex_centroid(&members[k], rest) } else { None };
        rig.joint_points[k] = pivot(&child, &parent, contact, radius, axial);
    }
    rig.tree = tree;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centroid_weights_by_area() {
        let pos = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [10.0, 0.0, 0.0],
            [10.5, 0.0, 0.0],
            [10.0, 0.5, 0.0],
        ];
        let faces = vec![[0, 1, 2], [3, 4, 5]];
        // areas 2 and 0.125; centres (2/3, 2/3) and (10 + 1/6, 1/6)
        let c = area_centroid(&[0, 1], &faces, &pos);
        let want_x = (2.0 * (2.0 / 3.0) + 0.125 * (10.0 + 1.0 / 6.0)) / 2.125;
        let want_y = (2.0 * (2.0 / 3.0) + 0.125 * (1.0 / 6.0)) / 2.125;
        assert!((c[0] - want_x).abs() < 1e-12 && (c[1] - want_y).abs() < 1e-12, "{c:?}");
        // degenerate triangles: plain mean of the centres
        let flat = vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let c = area_centroid(&[0], &[[0, 1, 2]], &flat);
        assert!((c[0] - 1.0).abs() < 1e-12);
    }

    /// A rotation by `deg` degrees about axis `axis` (unit) through `centre`.
    fn turn_about(axis: Vec3, deg: f64, centre: Vec3) -> RigidMotion {
        let r = *nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(nalgebra::Vector3::new(axis[0], axis[1], axis[2])),
            deg.to_radians(),
        )
        .matrix();
        let m = RigidMotion { rotation: r, translation: [0.0; 3] };
        // x -> R (x - c) + c
        RigidMotion { rotation: r, translation: sub(centre, m.apply(centre)) }
    }

    #[test]
    fn a_joint_that_turns_goes_to_its_pivot_and_one_that_barely_turns_stays() {
        let pivot_at = [0.3, -0.2, 0.5];
        let contact = [0.35, -0.1, 0.5];
        let parent = vec![RigidMotion::IDENTITY; 6];
        // turns about two axes through the pivot: the pivot is determined
        let child: Vec<RigidMotion> = (0..6)
            .map(|i| {
                turn_about(if i % 2 == 0 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] }, 40.0 + 5.0 * i as f64, pivot_at)
            })
            .collect();
        let x = pivot(&child, &parent, contact, 1.0, None);
        // (the contact is 0.11 away; the pull leaves 0.011 of it)
        assert!(norm(sub(x, pivot_at)) < 0.02, "{x:?}");
        // the parent moving too: only the relative motion counts
        let lift = RigidMotion { rotation: crate::geometry::IDENTITY, translation: [0.0, 2.0, 0.0] };
        let child2: Vec<RigidMotion> = child.iter().map(|m| lift.then_after(m)).collect();
        let x2 = pivot(&child2, &vec![lift; 6], contact, 1.0, None);
        assert!(norm(sub(x2, x)) < 1e-9, "{x2:?} {x:?}");
        // the guard: no further than radius from the contact, on the line toward the pivot
        let g = pivot(&child, &parent, contact, 0.05, None);
        assert!((norm(sub(g, contact)) - 0.05).abs() < 1e-9, "{g:?}");
        // a joint that turns a fraction of a degree, with noise the size of its turn: it stays at the contact
        let child3: Vec<RigidMotion> = (0..6)
            .map(|i| {
                let mut m = turn_about([0.0, 0.0, 1.0], 0.2, [5.0, 0.0, 0.0]);
                m.translation = add(m.translation, [0.0, 0.0, 1e-3 * i as f64]);
                m
            })
            .collect();
        let y = pivot(&child3, &parent, contact, 10.0, None);
        assert!(norm(sub(y, contact)) < 0.05, "{y:?}");
        // nothing to go on: the contact
        assert_eq!(pivot(&[], &[], contact, 1.0, None), contact);
    }

    #[test]
    fn a_hinge_beside_its_parent_takes_the_child_middle_along_its_axis() {
        // a box arm beside a box torso swings about the x axis through (0, 1, 0); the pieces touch on the arm's
        // inner face, whose centre (0.5, 0.4, 0) is the contact; the arm's middle is at x = 1
        let (axis_point, contact, middle) = ([0.0, 1.0, 0.0], [0.5, 0.4, 0.0], [1.0, 0.4, 0.0]);
        let parent = vec![RigidMotion::IDENTITY; 8];
        let swing: Vec<RigidMotion> =
            (0..8).map(|i| turn_about([1.0, 0.0, 0.0], -40.0 + 10.0 * i as f64, axis_point)).collect();
        // without the middle: on the axis (drawn a little toward the contact), at the contact's x
        let x0 = pivot(&swing, &parent, contact, 2.0, None);
        assert!((x0[0] - 0.5).abs() < 1e-6 && (x0[1] - 1.0).abs() < 0.1 && x0[2].abs() < 1e-6, "{x0:?}");
        // with it: the same point of the axis moved most of the way to the arm's middle x (all of it as the
        // turns grow beyond the pull)
        let x = pivot(&swing, &parent, contact, 2.0, Some(middle));
        assert!(x[0] > 0.9 && x[0] <= 1.0 && (x[1] - x0[1]).abs() < 0.02 && x[2].abs() < 1e-6, "{x:?}");
        // a joint turning about every axis is fixed by its poses, not by the middle
        let pivot_at = [0.5, 0.9, 0.1];
        let free: Vec<RigidMotion> = (0..8)
            .map(|i| turn_about([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]][i % 3], 35.0, pivot_at))
            .collect();
        let with = pivot(&free, &parent, contact, 2.0, Some(middle));
        let without = pivot(&free, &parent, contact, 2.0, None);
        assert!(
            norm(sub(with, without)) < 1e-3 && norm(sub(with, pivot_at)) < norm(sub(contact, pivot_at)) / 4.0,
            "{with:?} {without:?}"
        );
        // a hinge turning a fraction of a degree stays at its contact
        let small: Vec<RigidMotion> =
            (0..8).map(|i| turn_about([1.0, 0.0, 0.0], 0.05 * i as f64, axis_point)).collect();
        let x = pivot(&small, &parent, contact, 2.0, Some(middle));
        assert!(norm(sub(x, contact)) < 0.02, "{x:?}");
        // nothing finite to go on: the contact
        assert_eq!(hinge_anchor(&[f64::NAN; 9], 1.0, contact, middle), contact);
    }
}
