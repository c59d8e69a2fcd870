//! Algorithm 2, corrected: interpolation between two training poses, and along a sequence of poses.
//!
//! For poses i -> j and t in [0, 1]:
//! 1. every part's rotation: R_k^t = slerp(R_k^i, R_k^j, t) along the shorter arc (docs/method.md, item 10);
//! 2. the root's translation: with exact ends its latent centroid c moves on a straight line,
//!    b_r^t = (1-t)(R_r^i c + b_r^i) + t(R_r^j c + b_r^j) - R_r^t c; as printed, b_r^t = (1-t) b_r^i + t b_r^j;
//! 3. walking the tree from the root, every child c of p is pinned at their joint (eq 23 with Λ and the
//!    minus sign, item 4):  b_c^t = R_p^t (e_p - d^t) + b_p^t - R_c^t e_c, with e_k = Λ_k E_k[z | J_pc] and
//!    d^t = (1-t) d^i + t d^j the training shapes' joint mismatch in p's frame (item 9; d = 0 as printed);
//! 4. vertices: rigid, x_j = R^t v_j + b^t + ε_j^t with eq 24's ε_j^t = R^t((1-t) R^iT ε_j^i + t R^jT ε_j^j);
//!    skinned, x_j = (1-t) S_j(M^{i->t}) y_j^i + t S_j(M^{j->t}) y_j^j where M_k^{i->t} = T_k^t (T_k^i)^-1
//!    moves part k from pose i to pose t, S_j blends them with vertex j's weights, and y is the training shape
//!    (residual on) or its rigid reconstruction (off). With one-hot weights this IS step 4's rigid formula.
//!    With [`Options::edge_blend`] the two skinned ends are blended by their edges instead of their positions
//!    ([`super::skin::edge_blend`]): every edge points half-way (slerp) between its two skinned versions and
//!    is as long as the linear mix of its lengths in the two end shapes y^i, y^j; positions are the least-
//!    squares fit to those edges. That keeps joints from collapsing where the data is least rigid.

use super::skin::{blend_motion, edge_blend, SkinWeights, EDGE_BLEND_ANCHOR};
use super::{lerp, Articulation, Options, RigidMotion, Skin};
use crate::error::{Error, Result};
use crate::geometry::rotation::slerp;
use crate::geometry::{add, mat_t_vec, mat_vec, norm, sub, Vec3};

/// Plain linear vertex blending of two shapes at t in [0, 1]: the baseline the part-wise interpolation is
/// compared with (Fig 5, 6).
pub fn linear_blend(a: &[Vec3], b: &[Vec3], t: f64) -> Result<Vec<Vec3>> {
    check_t(t)?;
    if a.len() != b.len() {
        return Err(Error::Request(format!("the shapes have {} and {} vertices", a.len(), b.len())));
    }
    Ok(a.iter().zip(b).map(|(&a, &b)| lerp(a, b, t)).collect())
}

fn check_t(t: f64) -> Result<()> {
    if (0.0..=1.0).contains(&t) {
        Ok(())
    } else {
        Err(Error::Request(format!("t must be between 0 and 1, got {t}")))
    }
}

impl Articulation {
    /// Every part's rigid motion (latent -> space) at t between poses i and j (0-based).
    /// Parts that label no vertex are interpolated on their own (slerp, linear b).
    pub fn part_motions(&self, i: usize, j: usize, t: f64, opts: &Options) -> Result<Vec<RigidMotion>> {
        self.check_shape(i)?;
        self.check_shape(j)?;
        check_t(t)?;
        let n = self.n_parts();
        let rot: Vec<_> = (0..n)
            .map(|k| {
                let c = &self.model.parts[k];
                slerp(&c.rotations[i], &c.rotations[j], t)
            })
            .collect();
        let mut out: Vec<RigidMotion> = (0..n)
            .map(|k| {
                let c = &self.model.parts[k];
                RigidMotion { rotation: rot[k], translation: lerp(c.translations[i], c.translations[j], t) }
            })
            .collect();
        let tree = self.tree(opts, i, j);
        for &k in &tree.order {
            match tree.parent[k] {
                None => {
                    if opts.exact_ends {
                        let c = self.part_centroid[k];
                        let x = lerp(self.training_motion(k, i).apply(c), self.training_motion(k, j).apply(c), t);
                        out[k].translation = sub(x, mat_vec(&rot[k], c));
                    }
                }
                Some(p) => {
                    let joint = self.joint(p, k).expect("tree edges are contacts");
                    let (e_p, e_c) = (joint.latent(p), joint.latent(k));
                    let d = if opts.exact_ends {
                        lerp(joint.offset(&self.model, p, k, i), joint.offset(&self.model, p, k, j), t)
                    } else {
                        [0.0; 3]
                    };
                    let at_joint = out[p].apply(sub(e_p, d));
                    out[k].translation = sub(at_joint, mat_vec(&rot[k], e_c));
                }
            }
        }
        Ok(out)
    }

    /// The interpolated shape at t between poses i and j (0-based), unit box.
    pub fn interpolate(&self, i: usize, j: usize, t: f64, opts: &Options) -> Result<Vec<Vec3>> {
        let motions = self.part_motions(i, j, t, opts)?;
        Ok(match opts.skin {
            Skin::Rigid => self.place_rigid(&motions, i, j, t, opts.residual),
            Skin::Smooth => self.place_skinned(&motions, self.weights(Skin::Smooth), i, j, t, opts),
        })
    }

    /// Step 4, rigid: x_j = R^t v_j + b^t (+ eq 24's residual).
    pub fn place_rigid(&self, motions: &[RigidMotion], i: usize, j: usize, t: f64, residual: bool) -> Vec<Vec3> {
        let m = &self.model;
        // (the end shapes and their reconstructions only for the residual)
        let ends = residual.then(|| [self.shape(i), self.rigid(i), self.shape(j), self.rigid(j)]);
        (0..self.n_vertices())
            .map(|v| {
                let k = m.labels[v] as usize;
                let x = motions[k].apply(m.latent[v]);
                if !residual {
                    return x;
                }
                let c = &m.parts[k];
                let [yi, ri, yj, rj] = ends.as_ref().expect("made when residual");
                let ei = sub(yi[v], ri[v]);
                let ej = sub(yj[v], rj[v]);
                let local = lerp(mat_t_vec(&c.rotations[i], ei), mat_t_vec(&c.rotations[j], ej), t);
                add(x, mat_vec(&motions[k].rotation, local))
            })
            .collect()
    }

    /// Step 4, skinned: blends the part motions from each end pose to t with the given weights.
    pub fn place_skinned(
        &self,
        motions: &[RigidMotion],
        weights: &SkinWeights,
        i: usize,
        j: usize,
        t: f64,
        opts: &Options,
    ) -> Vec<Vec3> {
        let (yi, yj) = if opts.residual { (self.shape(i), self.shape(j)) } else { (self.rigid(i), self.rigid(j)) };
        let from_i: Vec<RigidMotion> =
            (0..self.n_parts()).map(|k| motions[k].then_after(&self.training_motion(k, i).inverse())).collect();
        let from_j: Vec<RigidMotion> =
            (0..self.n_parts()).map(|k| motions[k].then_after(&self.training_motion(k, j).inverse())).collect();
        let a: Vec<Vec3> =
            (0..self.n_vertices()).map(|v| blend_motion(&from_i, weights, v, opts.blend).apply(yi[v])).collect();
        if i == j {
            return a;
        }
        let b: Vec<Vec3> =
            (0..self.n_vertices()).map(|v| blend_motion(&from_j, weights, v, opts.blend).apply(yj[v])).collect();
        if opts.edge_blend {
            // every edge's length moves linearly between its lengths in the two end shapes
            let lengths: Vec<f64> = self
                .edges
                .iter()
                .map(|e| {
                    let (p, q) = (e[0] as usize, e[1] as usize);
                    (1.0 - t) * norm(sub(yi[p], yi[q])) + t * norm(sub(yj[p], yj[q]))
                })
                .collect();
            edge_blend(&a, &b, t, &self.edges, Some(&lengths), EDGE_BLEND_ANCHOR)
        } else {
            a.iter().zip(&b).map(|(&p, &q)| lerp(p, q, t)).collect()
        }
    }

    /// Plain linear vertex interpolation (1-t) x^i + t x^j of the training shapes: the baseline.
    pub fn linear(&self, i: usize, j: usize, t: f64) -> Result<Vec<Vec3>> {
        self.check_shape(i)?;
        self.check_shape(j)?;
        check_t(t)?;
        linear_blend(&self.shape(i), &self.shape(j), t)
    }

    /// Which segment of a key sequence s falls in, and where in it: s in [0, keys.len() - 1].
    pub fn keyframe_segment(&self, keys: &[usize], s: f64) -> Result<(usize, usize, f64)> {
        if keys.is_empty() {
            return Err(Error::Request("a keyframe sequence needs at least one pose".into()));
        }
        for &k in keys {
            self.check_shape(k)?;
        }
        let last = (keys.len() - 1) as f64;
        if !(0.0..=last).contains(&s) {
            return Err(Error::Request(format!("keyframe time must be between 0 and {last}, got {s}")));
        }
        if keys.len() == 1 {
            return Ok((keys[0], keys[0], 0.0));
        }
        let seg = (s.floor() as usize).min(keys.len() - 2);
        Ok((keys[seg], keys[seg + 1], s - seg as f64))
    }

    /// The shape at time s along a sequence of poses (0-based keys; s = 0 is `keys[0]`, s = 1 `keys[1]`, ...).
    pub fn keyframes(&self, keys: &[usize], s: f64, opts: &Options) -> Result<Vec<Vec3>> {
        let (i, j, t) = self.keyframe_segment(keys, s)?;
        self.interpolate(i, j, t, opts)
    }

    /// Part motions at time s along a sequence of poses.
    pub fn keyframe_motions(&self, keys: &[usize], s: f64, opts: &Options) -> Result<Vec<RigidMotion>> {
        let (i, j, t) = self.keyframe_segment(keys, s)?;
        self.part_motions(i, j, t, opts)
    }
}
