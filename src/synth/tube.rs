//! Rest-pose mesh of a [`Design`]: one closed, consistently oriented triangle mesh of sphere topology.
//!
//! The spine is a stack of rings (N vertices each, N even so the mesh is mirror-symmetric) between two pole
//! vertices. Each limb removes a rectangle of k_s x k_a cells from the spine's ring grid; the rectangle's
//! boundary loop (2 (k_s + k_a) vertices) becomes ring 0 of the limb tube, which is lofted from that loop to
//! a circle just outside the body (a fillet of cubic Bezier curves, tangent to the body and to the limb)
//! and then swept along the limb axis to a pole. Removing a disc and gluing a
//! capped tube to its boundary keeps the surface a sphere (Euler characteristic 2).
//!
//! Resolution: a target edge length e sets N = 2 round(pi rho_max / e) and ring spacing
//! sqrt(e * around spacing) (measured along the meridian, so poles are rounded evenly), at most a fraction of
//! the shortest part; [`plan_for_target`] searches e so that the vertex count meets the target.

use super::creature::{Design, LimbDef};
use super::curve::{along, interp, Monotone, Spline};
use crate::error::{Error, Result};
use crate::geometry::{add, cross, dot, norm, scale, sub, Vec3};
use std::f64::consts::PI;

/// Skinning coordinate of a vertex: which chain (0 = spine, 1 + k = limb k) and the position along it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkinCoord {
    pub chain: u16,
    pub u: f64,
}

/// Parts along a chain and where they meet (centre-line coordinate u).
#[derive(Debug, Clone)]
pub struct ChainGeom {
    pub parts: Vec<usize>,
    pub cuts: Vec<f64>,
    /// Limbs: the first cut (the hip, u = 0) is where the tube leaves the body, so its blend band lies on
    /// the limb side only.
    pub one_sided_first: bool,
    pub length: f64,
}

#[derive(Debug, Clone)]
pub struct RestMesh {
    pub positions: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
    pub skin: Vec<SkinCoord>,
    pub chains: Vec<ChainGeom>,
    /// Rest-pose joint centre of every non-root part (rotation centre relative to its parent).
    pub joint_centers: Vec<Option<Vec3>>,
}

/// Spine surface: swept ellipse with hemispherical ends.
pub struct SpineGeom {
    pub spline: Spline,
    lat: Monotone,
    up: Monotone,
    pub length: f64,
    cap0: f64,
    cap1: f64,
}

fn cap_factor(d: f64, c: f64) -> f64 {
    if d >= c {
        1.0
    } else if d <= 0.0 {
        0.0
    } else {
        let x = 1.0 - d / c;
        (1.0 - x * x).max(0.0).sqrt()
    }
}

impl SpineGeom {
    pub fn new(design: &Design) -> SpineGeom {
        let sp = &design.spine;
        let spline = Spline::new(sp.points.clone());
        let knots: Vec<f64> = (0..sp.points.len()).map(|k| k as f64).collect();
        let lat = Monotone::new(knots.clone(), sp.radii.iter().map(|r| r[0]).collect());
        let up = Monotone::new(knots, sp.radii.iter().map(|r| r[1]).collect());
        let length = spline.length();
        let first = sp.radii[0];
        let last = sp.radii[sp.radii.len() - 1];
        SpineGeom { spline, lat, up, length, cap0: first[0].max(first[1]), cap1: last[0].max(last[1]) }
    }

    /// Mean half-width without the rounded ends.
    pub fn body(&self, s: f64) -> f64 {
        let t = self.spline.t_of_s(s);
        0.5 * (self.lat.eval(t) + self.up.eval(t))
    }

    fn cap(&self, s: f64) -> f64 {
        cap_factor(s, self.cap0) * cap_factor(self.length - s, self.cap1)
    }

    /// Mean half-width with the rounded ends (0 at the poles).
    pub fn radius(&self, s: f64) -> f64 {
        self.body(s) * self.cap(s)
    }

    /// Outward unit normal at (s, phi), by central differences (away from the poles).
    pub fn normal(&self, s: f64, phi: f64) -> Vec3 {
        let h = 1e-5 * self.length;
        let ds = sub(self.point((s + h).min(self.length), phi), self.point((s - h).max(0.0), phi));
        let dp = sub(self.point(s, phi + 1e-5), self.point(s, phi - 1e-5));
        let n = cross(dp, ds);
        scale(n, 1.0 / norm(n))
    }

    /// Surface point at arc length s and angle phi (0 = +y side, pi/2 = top).
    pub fn point(&self, s: f64, phi: f64) -> Vec3 {
        let t = self.spline.t_of_s(s);
        let (c, d) = self.spline.eval(t);
        let tn = norm(d);
        let tan = if tn > 0.0 { scale(d, 1.0 / tn) } else { self.spline.tangent(t) };
        let y = [0.0, 1.0, 0.0];
        let l = sub(y, scale(tan, dot(y, tan)));
        let l = scale(l, 1.0 / norm(l));
        let u = cross(tan, l);
        let k = self.cap(s);
        let (rl, ru) = (self.lat.eval(t) * k, self.up.eval(t) * k);
        add(c, add(scale(l, rl * phi.cos()), scale(u, ru * phi.sin())))
    }
}

/// Fine samples of a tube for ring placement: meridian length of every interval and the body radius.
struct Profile {
    u: Vec<f64>,
    body: Vec<f64>,
    dl: Vec<f64>,
}

const FINE: usize = 8192;

impl Profile {
    fn new(length: f64, body: impl Fn(f64) -> f64, radius: impl Fn(f64) -> f64) -> Profile {
        let u: Vec<f64> = (0..=FINE).map(|k| length * k as f64 / FINE as f64).collect();
        let b: Vec<f64> = u.iter().map(|&x| body(x)).collect();
        let r: Vec<f64> = u.iter().map(|&x| radius(x)).collect();
        let dl = (0..FINE).map(|k| ((u[k + 1] - u[k]).powi(2) + (r[k + 1] - r[k]).powi(2)).sqrt()).collect();
        Profile { u, body: b, dl }
    }

    fn max_body(&self) -> f64 {
        self.body.iter().cloned().fold(0.0, f64::max)
    }

    /// Interior ring positions (strictly between both ends) for `around` vertices per ring and edge length e.
    fn rings(&self, around: usize, e: f64, dmax: f64) -> Vec<f64> {
        let mut q = Vec::with_capacity(FINE + 1);
        q.push(0.0);
        let mut acc = 0.0;
        for k in 0..FINE {
            let rho = 0.5 * (self.body[k] + self.body[k + 1]);
            let a = 2.0 * PI * rho / around as f64;
            let delta = (e * a).sqrt().min(dmax);
            acc += self.dl[k] / delta;
            q.push(acc);
        }
        let n = (acc.round() as usize).max(2);
        (1..n).map(|j| interp(&q, &self.u, acc * j as f64 / n as f64)).collect()
    }
}

/// A rectangle of ring-grid cells removed from the spine: rings j0..=j0+ks, around a0..=a0+ka (mod N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Patch {
    pub j0: usize,
    pub ks: usize,
    pub a0: usize,
    pub ka: usize,
}

impl Patch {
    fn rel(&self, a: usize, n: usize) -> usize {
        (a + n - self.a0) % n
    }
    fn has_cell(&self, j: usize, a: usize, n: usize) -> bool {
        j >= self.j0 && j < self.j0 + self.ks && self.rel(a, n) < self.ka
    }
    fn has_interior_vertex(&self, j: usize, a: usize, n: usize) -> bool {
        let r = self.rel(a, n);
        j > self.j0 && j < self.j0 + self.ks && r > 0 && r < self.ka
    }
    /// Boundary loop (ring index, around index), in the orientation the removed cells induced.
    fn boundary(&self, n: usize) -> Vec<(usize, usize)> {
        let (j0, j1) = (self.j0, self.j0 + self.ks);
        let col = |r: usize| (self.a0 + r) % n;
        let mut out = Vec::with_capacity(2 * (self.ks + self.ka));
        for r in 0..self.ka {
            out.push((j0, col(r)));
        }
        for j in j0..j1 {
            out.push((j, col(self.ka)));
        }
        for r in (1..=self.ka).rev() {
            out.push((j1, col(r)));
        }
        for j in (j0 + 1..=j1).rev() {
            out.push((j, col(0)));
        }
        out
    }
    /// Whether the two patches share a vertex or an edge, i.e. leave no free cell between them.
    fn touches(&self, other: &Patch, n: usize) -> bool {
        // rows of self grown by one cell against rows of other
        let (a_lo, a_hi) = (self.j0 as isize - 1, (self.j0 + self.ks) as isize + 1);
        let (b_lo, b_hi) = (other.j0 as isize, (other.j0 + other.ks) as isize);
        if a_hi <= b_lo || b_hi <= a_lo {
            return false;
        }
        let grown: Vec<usize> = (0..self.ka + 2).map(|r| (self.a0 + n + r - 1) % n).collect();
        (0..other.ka).any(|r| grown.contains(&((other.a0 + r) % n)))
    }
}

/// Ring layout for one edge length.
#[derive(Debug, Clone)]
pub struct Plan {
    pub e: f64,
    pub around: usize,
    pub spine_rings: Vec<f64>,
    pub patches: Vec<Patch>,
    pub limb_rings: Vec<Vec<f64>>,
    pub n_vertices: usize,
}

/// Shortest part along each chain (for the ring-spacing cap).
fn spine_part_lengths(design: &Design, geom: &SpineGeom) -> Vec<f64> {
    let mut b = vec![0.0];
    b.extend(design.spine.cuts_t.iter().map(|&t| geom.spline.s_of_t(t)));
    b.push(geom.length);
    b.windows(2).map(|w| w[1] - w[0]).collect()
}

fn limb_part_lengths(limb: &LimbDef) -> Vec<f64> {
    let mut b = vec![0.0];
    b.extend(limb.cuts_u.iter().cloned());
    b.push(limb.length);
    b.windows(2).map(|w| w[1] - w[0]).collect()
}

fn limb_radius_fn(limb: &LimbDef) -> (Monotone, f64) {
    let m = Monotone::new(limb.radii.iter().map(|r| r.0).collect(), limb.radii.iter().map(|r| r.1).collect());
    let cap = m.eval(limb.length);
    (m, cap)
}

/// Half-size of a limb's hole in the body, in limb radii: the margin is the fillet.
const HOLE: f64 = 1.4;

/// Fraction of the shortest part used as the largest ring spacing (so each part keeps a few rings).
const SPACING_CAP: f64 = 1.0 / 2.5;

pub struct Planner<'a> {
    design: &'a Design,
    pub geom: SpineGeom,
    spine_profile: Profile,
    spine_dmax: f64,
    limb_profiles: Vec<Profile>,
    limb_dmax: Vec<f64>,
}

impl<'a> Planner<'a> {
    pub fn new(design: &'a Design) -> Planner<'a> {
        let geom = SpineGeom::new(design);
        let spine_profile = Profile::new(geom.length, |s| geom.body(s), |s| geom.radius(s));
        let spine_dmax = spine_part_lengths(design, &geom).into_iter().fold(f64::INFINITY, f64::min) * SPACING_CAP;
        let mut limb_profiles = Vec::new();
        let mut limb_dmax = Vec::new();
        for limb in &design.limbs {
            let (m, cap) = limb_radius_fn(limb);
            let len = limb.length;
            limb_profiles.push(Profile::new(len, |u| m.eval(u), |u| m.eval(u) * cap_factor(len - u, cap)));
            limb_dmax.push(limb_part_lengths(limb).into_iter().fold(f64::INFINITY, f64::min) * SPACING_CAP);
        }
        Planner { design, geom, spine_profile, spine_dmax, limb_profiles, limb_dmax }
    }

    /// The layout for edge length e, or an error when e is too coarse to cut the limb holes.
    pub fn plan(&self, e: f64) -> Result<Plan> {
        let d = self.design;
        let min_n = d.spine.min_around.max(6);
        let half = (PI * self.spine_profile.max_body() / e).round();
        let around =
            if half.is_finite() && half * 2.0 > min_n as f64 { (half as usize) * 2 } else { min_n.div_ceil(2) * 2 };
        let spine_rings = self.spine_profile.rings(around, e, self.spine_dmax);
        let m = spine_rings.len();
        let mut patches: Vec<Patch> = Vec::new();
        for limb in &d.limbs {
            let patch = if let Some(src) = limb.mirror_of {
                let p: Patch = patches[src];
                let a0 = ((around / 2) as isize - p.a0 as isize - p.ka as isize).rem_euclid(around as isize) as usize;
                Patch { a0, ..p }
            } else {
                let s_att = self.geom.spline.s_of_t(limb.attach_t);
                let idx: Vec<f64> = (0..m).map(|k| k as f64).collect();
                let cf = interp(&spine_rings, &idx, s_att);
                let c = (cf.round() as usize).clamp(1, m.saturating_sub(2).max(1));
                let ds = if m >= 3 { (spine_rings[c + 1] - spine_rings[c - 1]) / 2.0 } else { self.geom.length };
                let step = 2.0 * PI / around as f64;
                let s_c = spine_rings[c.min(m - 1)];
                let da = norm(sub(
                    self.geom.point(s_c, limb.attach_phi + step / 2.0),
                    self.geom.point(s_c, limb.attach_phi - step / 2.0),
                ));
                let top = HOLE * limb.radii[0].1;
                let ks = ((2.0 * top / ds).round() as usize).max(1);
                let ka = ((2.0 * top / da).round() as usize).max(1);
                let j0 = (cf - ks as f64 / 2.0).round();
                if j0 < 0.0 || j0 as usize + ks >= m {
                    return Err(Error::Data("resolution too coarse for the limb holes".into()));
                }
                let a0 = (limb.attach_phi / step - ka as f64 / 2.0).round() as isize;
                Patch { j0: j0 as usize, ks, a0: a0.rem_euclid(around as isize) as usize, ka }
            };
            if patch.ka * 2 + 4 > around {
                return Err(Error::Data("resolution too coarse for the limb holes".into()));
            }
            if patches.iter().any(|p| p.touches(&patch, around)) {
                return Err(Error::Data("limb holes touch at this resolution".into()));
            }
            patches.push(patch);
        }
        let mut n_vertices = around * m + 2;
        let mut limb_rings = Vec::new();
        for (k, p) in patches.iter().enumerate() {
            n_vertices -= (p.ks - 1) * (p.ka - 1);
            let n_l = 2 * (p.ks + p.ka);
            let rings = self.limb_profiles[k].rings(n_l, e, self.limb_dmax[k]);
            n_vertices += n_l * rings.len() + 1;
            limb_rings.push(rings);
        }
        Ok(Plan { e, around, spine_rings, patches, limb_rings, n_vertices })
    }

    /// The plan whose vertex count is closest to `target` (the coarsest valid one if the target is below it).
    pub fn plan_for_target(&self, target: usize) -> Result<Plan> {
        let count = |e: f64| self.plan(e).map(|p| p.n_vertices).unwrap_or(0);
        // Start coarse and refine until the count exceeds the target, then bisect in log e.
        let mut hi = self.geom.length;
        let mut lo = hi / 2.0;
        let mut guard = 0;
        while count(lo) <= target {
            // a design whose plan fails at every resolution (limb holes that touch however fine the rings) would
            // refine until a plan's arrays no longer fit in memory: past a spacing that puts several times the
            // target's rings along the spine alone, no valid plan has as few vertices, and the plan's own error
            // is the answer
            if self.geom.length / lo > 4.0 * target.max(1) as f64 {
                return self.plan(lo);
            }
            hi = lo;
            lo /= 2.0;
            guard += 1;
            if guard > 60 {
                return Err(Error::Data("could not reach the vertex target".into()));
            }
        }
        for _ in 0..60 {
            let mid = (lo * hi).sqrt();
            if count(mid) > target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (pl, ph) = (self.plan(lo)?, self.plan(hi));
        match ph {
            Ok(ph) if ph.n_vertices.abs_diff(target) <= pl.n_vertices.abs_diff(target) => Ok(ph),
            _ => Ok(pl),
        }
    }

    pub fn build(&self, plan: &Plan) -> RestMesh {
        let d = self.design;
        let n = plan.around;
        let m = plan.spine_rings.len();
        let geom = &self.geom;
        let mut positions: Vec<Vec3> = Vec::with_capacity(plan.n_vertices);
        let mut skin: Vec<SkinCoord> = Vec::with_capacity(plan.n_vertices);
        let mut faces: Vec<[u32; 3]> = Vec::with_capacity(2 * plan.n_vertices);
        fn push(p: Vec3, c: SkinCoord, positions: &mut Vec<Vec3>, skin: &mut Vec<SkinCoord>) -> u32 {
            positions.push(p);
            skin.push(c);
            (positions.len() - 1) as u32
        }

        // Spine: pole, rings, pole.
        let start = push(geom.point(0.0, 0.0), SkinCoord { chain: 0, u: 0.0 }, &mut positions, &mut skin);
        const NONE: u32 = u32::MAX;
        let mut grid = vec![NONE; m * n];
        let phis: Vec<f64> = (0..n).map(|a| 2.0 * PI * a as f64 / n as f64).collect();
        for (j, &s) in plan.spine_rings.iter().enumerate() {
            for a in 0..n {
                if plan.patches.iter().any(|p| p.has_interior_vertex(j, a, n)) {
                    continue;
                }
                grid[j * n + a] = push(geom.point(s, phis[a]), SkinCoord { chain: 0, u: s }, &mut positions, &mut skin);
            }
        }
        let end = push(geom.point(geom.length, 0.0), SkinCoord { chain: 0, u: geom.length }, &mut positions, &mut skin);
        for a in 0..n {
            let b = (a + 1) % n;
            faces.push([start, grid[b], grid[a]]);
            faces.push([end, grid[(m - 1) * n + a], grid[(m - 1) * n + b]]);
        }
        for j in 0..m - 1 {
            for a in 0..n {
                if plan.patches.iter().any(|p| p.has_cell(j, a, n)) {
                    continue;
                }
                let b = (a + 1) % n;
                let (p00, p01, p10, p11) =
                    (grid[j * n + a], grid[j * n + b], grid[(j + 1) * n + a], grid[(j + 1) * n + b]);
                faces.push([p00, p01, p10]);
                faces.push([p01, p11, p10]);
            }
        }

        // Limbs.
        let mut joint_centers: Vec<Option<Vec3>> = vec![None; d.names.len()];
        let mut chains = Vec::new();
        let spine_cuts: Vec<f64> = d.spine.cuts_t.iter().map(|&t| geom.spline.s_of_t(t)).collect();
        for (k, &s) in spine_cuts.iter().enumerate() {
            let (a, b) = (d.spine.parts[k], d.spine.parts[k + 1]);
            let child = if d.parent[b] == Some(a) { b } else { a };
            debug_assert!(
                d.parent[child] == Some(if child == b { a } else { b }),
                "spine parts {a} and {b} are not linked"
            );
            joint_centers[child] = Some(geom.spline.point_at_s(s));
        }
        chains.push(ChainGeom {
            parts: d.spine.parts.clone(),
            cuts: spine_cuts,
            one_sided_first: false,
            length: geom.length,
        });

        for (li, limb) in d.limbs.iter().enumerate() {
            let patch = plan.patches[li];
            let chain = (li + 1) as u16;
            let ring0: Vec<u32> = patch.boundary(n).iter().map(|&(j, a)| grid[j * n + a]).collect();
            debug_assert!(ring0.iter().all(|&v| v != NONE));
            let s_mid = 0.5 * (plan.spine_rings[patch.j0] + plan.spine_rings[patch.j0 + patch.ks]);
            let phi_mid = 2.0 * PI * (patch.a0 as f64 + patch.ka as f64 / 2.0) / n as f64;
            let hip = geom.point(s_mid, phi_mid);
            let dir = scale(limb.dir, 1.0 / norm(limb.dir));
            // basis (p, q) perpendicular to the axis
            let helper = if dir[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
            let p = sub(helper, scale(dir, dot(helper, dir)));
            let p = scale(p, 1.0 / norm(p));
            let q = cross(dir, p);
            // angles of the loop vertices: by arc length along the loop, starting at vertex 0's angle,
            // turning in the loop's own sense around the axis
            let loop_pos: Vec<Vec3> = ring0.iter().map(|&v| positions[v as usize]).collect();
            let proj: Vec<[f64; 2]> = loop_pos.iter().map(|&x| [dot(sub(x, hip), p), dot(sub(x, hip), q)]).collect();
            let nl = proj.len();
            let mut area = 0.0;
            let mut cum = vec![0.0; nl + 1];
            for i in 0..nl {
                let (a, b) = (proj[i], proj[(i + 1) % nl]);
                area += a[0] * b[1] - a[1] * b[0];
                cum[i + 1] = cum[i] + ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            }
            let sign = if area >= 0.0 { 1.0 } else { -1.0 };
            let theta0 = proj[0][1].atan2(proj[0][0]);
            let dirs: Vec<Vec3> = (0..nl)
                .map(|i| {
                    let th = theta0 + sign * 2.0 * PI * cum[i] / cum[nl];
                    add(scale(p, th.cos()), scale(q, th.sin()))
                })
                .collect();
            let (rad, cap) = limb_radius_fn(limb);
            let radius = |u: f64| rad.eval(u) * cap_factor(limb.length - u, cap);
            // The fillet: from each loop vertex a cubic Bezier curve leaves the body tangent to its surface,
            // heading for the hip, and bends into the limb's circle at u_t (below every loop vertex), arriving
            // along the limb axis; both tangent handles are half the chord.
            let depth = loop_pos.iter().map(|&x| dot(sub(x, hip), dir)).fold(0.0, f64::max);
            let u_t = depth + 0.5 * limb.radii[0].1;
            let loop_sa: Vec<(f64, f64)> =
                patch.boundary(n).iter().map(|&(j, a)| (plan.spine_rings[j], phis[a])).collect();
            let fillet: Vec<[Vec3; 4]> = (0..nl)
                .map(|i| {
                    let p0 = loop_pos[i];
                    let p1 = add(along(hip, dir, u_t), scale(dirs[i], radius(u_t)));
                    let normal = geom.normal(loop_sa[i].0, loop_sa[i].1);
                    let toward = sub(hip, p0);
                    let a = sub(toward, scale(normal, dot(toward, normal)));
                    let handle = 0.5 * norm(sub(p1, p0));
                    let al = norm(a);
                    let c0 = if al > 0.0 { add(p0, scale(a, handle / al)) } else { p0 };
                    [p0, c0, sub(p1, scale(dir, handle)), p1]
                })
                .collect();
            let mut prev = ring0.clone();
            for &u in &plan.limb_rings[li] {
                let ring: Vec<u32> = (0..nl)
                    .map(|i| {
                        let x = if u < u_t {
                            let t = u / u_t;
                            let [p0, c0, c1, p1] = fillet[i];
                            let r = 1.0 - t;
                            add(
                                add(scale(p0, r * r * r), scale(c0, 3.0 * r * r * t)),
                                add(scale(c1, 3.0 * r * t * t), scale(p1, t * t * t)),
                            )
                        } else {
                            add(along(hip, dir, u), scale(dirs[i], radius(u)))
                        };
                        push(x, SkinCoord { chain, u }, &mut positions, &mut skin)
                    })
                    .collect();
                for i in 0..nl {
                    let i1 = (i + 1) % nl;
                    faces.push([prev[i], prev[i1], ring[i]]);
                    faces.push([prev[i1], ring[i1], ring[i]]);
                }
                prev = ring;
            }
            let tip =
                push(along(hip, dir, limb.length), SkinCoord { chain, u: limb.length }, &mut positions, &mut skin);
            for i in 0..nl {
                faces.push([tip, prev[i], prev[(i + 1) % nl]]);
            }
            joint_centers[limb.parts[0]] = Some(hip);
            for (k, &u) in limb.cuts_u.iter().enumerate() {
                joint_centers[limb.parts[k + 1]] = Some(along(hip, dir, u));
            }
            let mut parts = vec![limb.attached_to];
            parts.extend(limb.parts.iter().cloned());
            let mut cuts = vec![0.0];
            cuts.extend(limb.cuts_u.iter().cloned());
            chains.push(ChainGeom { parts, cuts, one_sided_first: true, length: limb.length });
        }
        debug_assert_eq!(positions.len(), plan.n_vertices);
        let hips: Vec<(Vec3, f64)> =
            d.limbs.iter().map(|l| (joint_centers[l.parts[0]].expect("hip centre set above"), l.radii[0].1)).collect();
        relax_sockets(&mut positions, &faces, &hips);
        RestMesh { positions, faces, skin, chains, joint_centers }
    }
}

/// Evens out the few-edge kinks the rectangular holes leave at their corners: a fixed number of Taubin
/// passes (lambda 0.5, mu -0.53: a low-pass filter that does not shrink) on the vertices within about two
/// limb radii of each hip, weighted down smoothly to 0 at 2.6 radii. The fillet's shape itself comes from
/// the Bezier curves; this only removes high-frequency wrinkles, so it needs no more passes at higher
/// resolution.
fn relax_sockets(positions: &mut [Vec3], faces: &[[u32; 3]], hips: &[(Vec3, f64)]) {
    if hips.is_empty() {
        return;
    }
    let weight = |p: Vec3| -> f64 {
        hips.iter()
            .map(|&(h, r)| {
                let d = norm(sub(p, h)) / r;
                if d <= 2.0 {
                    1.0
                } else if d >= 2.6 {
                    0.0
                } else {
                    let x = (2.6 - d) / 0.6;
                    x * x * (3.0 - 2.0 * x)
                }
            })
            .fold(0.0, f64::max)
    };
    let w: Vec<f64> = positions.iter().map(|&p| weight(p)).collect();
    let moving: Vec<usize> = (0..positions.len()).filter(|&i| w[i] > 0.0).collect();
    let mut slot = vec![u32::MAX; positions.len()];
    for (k, &i) in moving.iter().enumerate() {
        slot[i] = k as u32;
    }
    // in a closed consistent mesh every edge a->b of a triangle appears once in each direction, so adding
    // the successor of every vertex in every triangle lists all its neighbours
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); moving.len()];
    for f in faces {
        for a in 0..3 {
            let k = slot[f[a] as usize];
            if k != u32::MAX {
                nbrs[k as usize].push(f[(a + 1) % 3]);
            }
        }
    }
    let mut delta = vec![[0.0; 3]; moving.len()];
    for pass in 0..2 * SOCKET_PASSES {
        let f = if pass % 2 == 0 { 0.5 } else { -0.53 };
        for (k, &i) in moving.iter().enumerate() {
            let n = &nbrs[k];
            let c = n.iter().fold([0.0; 3], |acc, &j| add(acc, positions[j as usize]));
            delta[k] = scale(sub(scale(c, 1.0 / n.len() as f64), positions[i]), f * w[i]);
        }
        for (k, &i) in moving.iter().enumerate() {
            positions[i] = add(positions[i], delta[k]);
        }
    }
}

const SOCKET_PASSES: usize = 10;
