//! Posing: skinning weights from the chain coordinates, random joint angles, forward kinematics, linear blend
//! skinning, and the non-articulated bend-and-twist of the blob.

use super::creature::{Design, JointDef};
use super::tube::{ChainGeom, SkinCoord};
use crate::geometry::procrustes::best_rotation;
use crate::geometry::rotation::axis_angle;
use crate::geometry::{add, mat_mul, mat_vec, scale, sub, Mat3, Vec3, IDENTITY};
use rand::Rng;

/// Skinning of one vertex: position = (1 - weight) (R_a x + t_a) + weight (R_b x + t_b), with
/// `parts = [a, b]`. A vertex moved by one part alone has `a == b` and `weight == 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blend {
    pub parts: [u32; 2],
    pub weight: f64,
}

impl Blend {
    /// The part with the larger weight (the first on a tie): the ground-truth label.
    pub fn label(&self) -> u32 {
        if self.weight > 0.5 {
            self.parts[1]
        } else {
            self.parts[0]
        }
    }

    /// True when the vertex follows one part rigidly.
    pub fn is_rigid(&self) -> bool {
        self.parts[0] == self.parts[1] || self.weight == 0.0
    }
}

fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Blend intervals (lo, hi) of every cut of a chain for a band width `band` (design units): centred on the cut,
/// half-width min(band / 2, 0.45 x either neighbouring part's length); the hip of a limb blends on the limb
/// side only, over min(band, 0.45 x the first limb part's length).
pub fn intervals(chain: &ChainGeom, band: f64) -> Vec<(f64, f64)> {
    let mut bounds = vec![0.0];
    bounds.extend(chain.cuts.iter().cloned());
    bounds.push(chain.length);
    let lens: Vec<f64> = bounds.windows(2).map(|w| (w[1] - w[0]).max(0.0)).collect();
    chain
        .cuts
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            if k == 0 && chain.one_sided_first {
                (c, c + band.min(0.45 * lens[1]))
            } else {
                let h = (band / 2.0).min(0.45 * lens[k]).min(0.45 * lens[k + 1]);
                (c - h, c + h)
            }
        })
        .collect()
}

pub fn blends(chains: &[ChainGeom], skin: &[SkinCoord], band: f64) -> Vec<Blend> {
    let ivs: Vec<Vec<(f64, f64)>> = chains.iter().map(|c| intervals(c, band)).collect();
    skin.iter()
        .map(|sc| {
            let ch = &chains[sc.chain as usize];
            let iv = &ivs[sc.chain as usize];
            for (k, &(lo, hi)) in iv.iter().enumerate() {
                let a = ch.parts[k] as u32;
                if sc.u < lo {
                    return Blend { parts: [a, a], weight: 0.0 };
                }
                if sc.u < hi {
                    return Blend { parts: [a, ch.parts[k + 1] as u32], weight: smoothstep((sc.u - lo) / (hi - lo)) };
                }
            }
            let last = *ch.parts.last().expect("a chain has parts") as u32;
            Blend { parts: [last, last], weight: 0.0 }
        })
        .collect()
}

/// Local rotation drawn within a joint's limits.
pub fn sample_joint<R: Rng>(rng: &mut R, joint: &JointDef, max_angle: f64) -> Mat3 {
    let mut m = IDENTITY;
    for &(axis, lo, hi) in &joint.axes {
        let f = lo + (hi - lo) * rng.gen::<f64>();
        m = mat_mul(&m, &axis_angle(axis, f * max_angle));
    }
    m
}

/// Uniform random unit vector.
pub fn random_axis<R: Rng>(rng: &mut R) -> Vec3 {
    let z = 2.0 * rng.gen::<f64>() - 1.0;
    let a = 2.0 * std::f64::consts::PI * rng.gen::<f64>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    [r * a.cos(), r * a.sin(), z]
}

/// Standard normal deviate (Box-Muller; rand's default features have no normal distribution).
pub fn gaussian<R: Rng>(rng: &mut R) -> f64 {
    let u1 = 1.0 - rng.gen::<f64>(); // (0, 1]
    let u2 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// World transform (R, t) of every part by forward kinematics: each part turns by its local rotation about
/// its rest joint centre, after its parent: R_c = R_p L_c, t_c = R_p J_c + t_p - R_c J_c.
pub fn forward_kinematics(
    design: &Design,
    order: &[usize],
    joints: &[Option<Vec3>],
    local: &[Mat3],
    root: (Mat3, Vec3),
) -> (Vec<Mat3>, Vec<Vec3>) {
    let n = design.names.len();
    let mut rot = vec![IDENTITY; n];
    let mut tr = vec![[0.0; 3]; n];
    for &c in order {
        match design.parent[c] {
            None => {
                rot[c] = root.0;
                tr[c] = root.1;
            }
            Some(p) => {
                let j = joints[c].expect("every non-root part has a joint centre");
                rot[c] = mat_mul(&rot[p], &local[c]);
                tr[c] = sub(add(mat_vec(&rot[p], j), tr[p]), mat_vec(&rot[c], j));
            }
        }
    }
    (rot, tr)
}

/// Linear blend skinning of the rest positions.
pub fn skin(rest: &[Vec3], blend: &[Blend], rot: &[Mat3], tr: &[Vec3], out: &mut Vec<Vec3>) {
    out.clear();
    out.extend(rest.iter().zip(blend).map(|(&x, b)| {
        let a = b.parts[0] as usize;
        let pa = add(mat_vec(&rot[a], x), tr[a]);
        if b.weight == 0.0 {
            return pa;
        }
        let c = b.parts[1] as usize;
        let pb = add(mat_vec(&rot[c], x), tr[c]);
        add(scale(pa, 1.0 - b.weight), scale(pb, b.weight))
    }));
}

/// Bend (total angle `bend` over `length`, in the plane of x and (0, cos psi, sin psi)) after a twist about x
/// (angle `twist` per `half` of x). Smooth and non-rigid; the identity at x = 0.
pub fn bend_twist(x: Vec3, twist: f64, half: f64, bend: f64, length: f64, psi: f64) -> Vec3 {
    let a = twist * x[0] / half;
    let (ca, sa) = (a.cos(), a.sin());
    let v = [x[0], ca * x[1] - sa * x[2], sa * x[1] + ca * x[2]];
    let n = [0.0, psi.cos(), psi.sin()];
    let h = v[1] * n[1] + v[2] * n[2];
    let w = [0.0, v[1] - h * n[1], v[2] - h * n[2]];
    let k = bend / length;
    if k.abs() < 1e-12 {
        return v;
    }
    let th = k * v[0];
    let (c, s) = (th.cos(), th.sin());
    let p = [s / k, (1.0 - c) / k * n[1], (1.0 - c) / k * n[2]];
    let nn = [-s, c * n[1], c * n[2]];
    add(add(p, scale(nn, h)), w)
}

/// Best rigid fit (Procrustes) of `pose` to `rest`: pose ~ R rest + t.
pub fn best_rigid(rest: &[Vec3], pose: &[Vec3]) -> (Mat3, Vec3) {
    let n = rest.len().max(1) as f64;
    let mean = |v: &[Vec3]| v.iter().fold([0.0; 3], |a, &b| add(a, b)).map(|c| c / n);
    let (mx, my) = (mean(rest), mean(pose));
    let mut c = Mat3::zeros();
    for (x, y) in rest.iter().zip(pose) {
        let (dx, dy) = (sub(*x, mx), sub(*y, my));
        for a in 0..3 {
            for b in 0..3 {
                c[(a, b)] += dy[a] * dx[b];
            }
        }
    }
    let r = best_rotation(&c);
    (r, sub(my, mat_vec(&r, mx)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::norm;

    #[test]
    fn blend_weights_are_a_partition_and_continuous() {
        let ch = ChainGeom { parts: vec![4, 7, 9], cuts: vec![1.0, 2.0], one_sided_first: false, length: 3.0 };
        let sk: Vec<SkinCoord> = (0..=300).map(|k| SkinCoord { chain: 0, u: k as f64 / 100.0 }).collect();
        let b = blends(std::slice::from_ref(&ch), &sk, 0.4);
        // far from cuts: one part
        assert_eq!(b[50], Blend { parts: [4, 4], weight: 0.0 });
        assert_eq!(b[150], Blend { parts: [7, 7], weight: 0.0 });
        assert_eq!(b[250], Blend { parts: [9, 9], weight: 0.0 });
        // inside the band of the first cut (0.8 .. 1.2)
        assert_eq!(b[100].parts, [4, 7]);
        assert!((b[100].weight - 0.5).abs() < 1e-12);
        assert_eq!(b[79].parts, [4, 4]);
        assert!(b[81].weight > 0.0 && b[81].weight < 0.01);
        // band 0: a step at the cut, labels by side
        let b0 = blends(&[ch], &sk, 0.0);
        assert_eq!(b0[99].label(), 4);
        assert_eq!(b0[100].label(), 7);
        assert!(b0.iter().all(|b| b.is_rigid()));
    }

    #[test]
    fn band_is_clamped_by_short_parts_and_one_sided_at_hips() {
        let ch = ChainGeom { parts: vec![0, 1, 2], cuts: vec![0.0, 0.2], one_sided_first: true, length: 0.3 };
        let iv = intervals(&ch, 1.0);
        assert_eq!(iv[0], (0.0, 0.45 * 0.2));
        assert!((iv[1].0 - (0.2 - 0.45 * 0.1)).abs() < 1e-15 && (iv[1].1 - (0.2 + 0.45 * 0.1)).abs() < 1e-15);
    }

    #[test]
    fn bend_twist_is_smooth_and_not_rigid() {
        let pts = [[0.3, 0.1, 0.0], [-0.3, 0.0, 0.1], [0.0, 0.2, 0.2], [0.1, -0.1, 0.0]];
        let id: Vec<Vec3> = pts.iter().map(|&p| bend_twist(p, 0.0, 0.5, 0.0, 1.0, 0.3)).collect();
        for (a, b) in id.iter().zip(&pts) {
            assert!(norm(sub(*a, *b)) < 1e-15);
        }
        let bent: Vec<Vec3> = pts.iter().map(|&p| bend_twist(p, 0.5, 0.5, 0.8, 1.0, 0.3)).collect();
        let (r, t) = best_rigid(&pts, &bent);
        let resid: f64 = pts.iter().zip(&bent).map(|(x, y)| norm(sub(*y, add(mat_vec(&r, *x), t)))).sum();
        assert!(resid > 1e-3, "bend and twist must not be a rigid motion ({resid})");
        // tiny bend is close to the straight limit
        let a = bend_twist([0.2, 0.1, 0.05], 0.0, 0.5, 1e-9, 1.0, 0.0);
        assert!(norm(sub(a, [0.2, 0.1, 0.05])) < 1e-8);
    }

    #[test]
    fn gaussian_has_unit_variance() {
        use rand::SeedableRng;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let xs: Vec<f64> = (0..20000).map(|_| gaussian(&mut rng)).collect();
        let m = xs.iter().sum::<f64>() / xs.len() as f64;
        let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(m.abs() < 0.03 && (v - 1.0).abs() < 0.05, "mean {m} var {v}");
    }
}
