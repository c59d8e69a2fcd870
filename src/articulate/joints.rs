//! Joints: where two adjacent parts meet in every training shape, and that point's image in each part's
//! latent frame.
//!
//! J_pc^i: the area-weighted centroid of the contact triangles (those with vertices in both p and c) in
//! shape i (docs/method.md, item 10). Its latent image in part k is Λ_k E_k[z | J_pc] (eq 23 mapped through Λ,
//! item 4): the point of part k's latent shape that part k's rigid motions send closest to J_pc^i, all
//! shapes together. For a virtual contact (disconnected mesh pieces) J^i is the midpoint of its two vertices.
//!
//! Eq 23 pins the child to the parent at that point. In a training shape the two parts do not meet there
//! exactly: the parent places it at R_p^i e_p + b_p^i, the child at R_c^i e_c + b_c^i. [`Joint::offset`] is
//! that mismatch in the parent's latent frame; blending it in t makes Algorithm 2 reproduce both end poses.

use super::graph::{triangle_area, Contact, PartGraph};
use crate::geometry::{add, mat_t_vec, scale, sub, Vec3};
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
                Contact::Triangles(t) => area_centroid(t, faces, s),
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
}
