//! Posing what was learned: new frames onto a finished rig, poses of one's own (a part turned about
//! its joint, its subtree following), and the space of poses the population spans.
//!
//! - [`SkinnedRig`]: what posing needs of a rig: bind positions u_j, per-vertex bone weights, the skeleton (a
//!   parent per bone) and each bone's joint point in the bind pose. From a [`Rig`] ([`SkinnedRig::from_rig`],
//!   bones = parts) or from a .glb this project wrote ([`crate::export::pose_glb`], bones = skin joints). A pose
//!   is one rigid motion M_k per bone (bind -> pose); the mesh is v_j = Σ_k w_jk M_k u_j (linear blend
//!   skinning, what glTF players do: [`SkinnedRig::skin`]).
//! - [`solve_frames`]: every bone's motion per new frame with the weights and bind positions fixed: the rig's own
//!   bone step ([`super::rig`], *bones*: per bone the weighted Procrustes problem with the other bones fixed, in
//!   tree order), repeated until no bone moves by more than 1e-9 of the bind pose's diagonal (at most
//!   [`MAX_STEPS`] steps), each step an exact block minimisation so the error never grows. It starts from each
//!   bone's own best rigid motion (weighted Procrustes of its vertices, weights w_jk). Similarity-invariant, so
//!   it works in whatever units the rig and the frames share.
//! - [`turn`]: a part's subtree turned about the part's joint (the page's drag).
//! - [`PoseSpace`]: each pose as the log map of every non-root bone's rotation relative to its parent's, relative
//!   to the bind pose (Q_k = R_pᵀ R_k with R the bind -> pose rotations; 3 numbers per bone), then principal
//!   component analysis over the poses: the mean, the modes (as many as the poses span, at most n_poses - 1),
//!   their standard deviations and every training pose's coordinates. A vector of mode coefficients gives a
//!   pose vector (mean + Σ c_m mode_m), the pose vector local rotations (exp map), and the local rotations a
//!   pose ([`pose_from_locals`]: the root at its bind placement, every other bone turned by Q_k about its joint
//!   point, carried by its parent). The root's own motion (where the body is, which way it faces) is not part
//!   of the pose space.

use super::rig::{BoneSums, Rig};
use super::skin::SkinWeights;
use super::RigidMotion;
use crate::error::{Error, Result};
use crate::geometry::procrustes::best_rotation;
use crate::geometry::rotation::axis_angle;
use crate::geometry::{add, dot, mat_mul, mat_vec, norm, scale, sub, transpose, Mat3, Vec3, IDENTITY};
use serde::Serialize;

/// Most bone steps per frame in [`solve_frames`].
pub const MAX_STEPS: usize = 200;

/// A rig as posing needs it (module doc). Bones are indexed 0..n_bones; bones outside the skeleton (no parent
/// and not in `order`) carry no vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinnedRig {
    /// Bind positions.
    pub rest: Vec<Vec3>,
    /// Per vertex (bone, weight), positive, summing to 1.
    pub weights: SkinWeights,
    /// Parent of every bone (None for the root and for bones outside the skeleton).
    pub parent: Vec<Option<usize>>,
    /// The skeleton's bones, every bone after its parent.
    pub order: Vec<usize>,
    /// Each bone's joint point in the bind pose (with its parent; the root's: its centroid).
    pub joint_points: Vec<Vec3>,
}

impl SkinnedRig {
    /// The rig's bind positions, weights and skeleton (bones = parts).
    pub fn from_rig(rig: &Rig) -> SkinnedRig {
        SkinnedRig {
            rest: rig.rest.clone(),
            weights: rig.weights.clone(),
            parent: rig.tree.parent.clone(),
            order: rig.tree.order.clone(),
            joint_points: rig.joint_points.clone(),
        }
    }

    pub fn n_bones(&self) -> usize {
        self.parent.len()
    }

    pub fn n_vertices(&self) -> usize {
        self.rest.len()
    }

    /// Checks the parts fit together (sizes, weights on skeleton bones, parents before children).
    pub fn validate(&self) -> Result<()> {
        let nb = self.n_bones();
        if self.weights.len() != self.rest.len() || self.joint_points.len() != nb {
            return Err(Error::Data(format!(
                "rig: {} bind positions, {} weight lists, {} bones, {} joint points",
                self.rest.len(),
                self.weights.len(),
                nb,
                self.joint_points.len()
            )));
        }
        let mut seen = vec![false; nb];
        for &k in &self.order {
            if k >= nb || seen[k] {
                return Err(Error::Data(format!("rig: bone {k} is out of range or listed twice in the skeleton")));
            }
            if let Some(p) = self.parent[k] {
                if p >= nb || !seen[p] {
                    return Err(Error::Data(format!("rig: bone {k} comes before its parent {p}")));
                }
            }
            seen[k] = true;
        }
        for v in 0..self.rest.len() {
            let mut sum = 0.0;
            for (k, w) in self.weights.influences(v) {
                if k >= nb || !seen[k] {
                    return Err(Error::Data(format!(
                        "rig: vertex {v} is weighted to bone {k}, which is not in the skeleton"
                    )));
                }
                if !(w >= 0.0 && w.is_finite()) {
                    return Err(Error::Data(format!("rig: vertex {v} has weight {w} on bone {k}")));
                }
                sum += w;
            }
            if (sum - 1.0).abs() > 1e-3 {
                return Err(Error::Data(format!("rig: the weights of vertex {v} sum to {sum}, not 1")));
            }
        }
        Ok(())
    }

    /// Linear blend skinning of the bind positions by one motion per bone.
    pub fn skin(&self, bones: &[RigidMotion]) -> Vec<Vec3> {
        (0..self.rest.len())
            .map(|v| {
                let mut x = [0.0; 3];
                for (k, w) in self.weights.influences(v) {
                    x = add(x, scale(bones[k].apply(self.rest[v]), w));
                }
                x
            })
            .collect()
    }

    /// Diagonal of the bind positions' bounding box.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = crate::geometry::bounds(&self.rest);
        norm(sub(hi, lo))
    }

    /// Whether bone `b` is `k` or below it in the skeleton.
    pub fn in_subtree(&self, k: usize, mut b: usize) -> bool {
        loop {
            if b == k {
                return true;
            }
            match self.parent[b] {
                Some(p) => b = p,
                None => return false,
            }
        }
    }
}

/// Sum of squared distances between two point lists.
pub fn sse(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let d = sub(*x, *y);
            dot(d, d)
        })
        .sum()
}

/// E_RMS over several frames of the same mesh from each frame's E_RMS (the root of the mean square).
pub fn overall_e_rms(per_frame: &[f64]) -> f64 {
    (per_frame.iter().map(|x| x * x).sum::<f64>() / per_frame.len().max(1) as f64).sqrt()
}

/// E_RMS (Kavan et al. 2010) of a squared error over `n_points` points (vertices x poses): 1000 · sqrt(sse / (3 n)) / d.
pub fn e_rms(sse: f64, n_points: usize, diagonal: f64) -> f64 {
    1000.0 * (sse / (3.0 * n_points.max(1) as f64)).sqrt() / diagonal
}

/// New frames solved onto a rig ([`solve_frames`]).
#[derive(Debug, Clone)]
pub struct FrameSolve {
    /// `bones[f][k]`: bone k's motion from the bind pose to frame f.
    pub bones: Vec<Vec<RigidMotion>>,
    /// Squared error of every frame (the rig's skinning against the frame).
    pub sse: Vec<f64>,
    /// Bone steps each frame took.
    pub steps: Vec<usize>,
}

/// The first of the named frames (name, vertex count) that is not the rig's mesh, refused by its name: what the
/// page and the CLI check before [`solve_frames`], which knows the frames only by their place. `rig` names the
/// rig's file in the message where there is one.
pub fn check_frame_sizes<'a>(
    frames: impl IntoIterator<Item = (&'a str, usize)>,
    nv: usize,
    rig: Option<&str>,
) -> Result<()> {
    match frames.into_iter().find(|&(_, n)| n != nv) {
        None => Ok(()),
        Some((name, n)) => Err(Error::Population {
            file: name.to_string(),
            message: format!(
                "has {n} vertices but the rig {}has {nv}: add frames of the fitted mesh (the same vertices in the \
                 same order, as the training poses)",
                rig.map(|r| format!("{r} ")).unwrap_or_default()
            ),
        }),
    }
}

/// Every bone's motion per frame, weights and bind positions fixed (module doc). Frames must have the rig's
/// vertex count (same mesh, same vertex order). They are read once, in order, into the solve's own
/// vertex-by-vertex copy: a caller can make each frame as it is asked for (pose mode's training poses in
/// original units), so that only one is held beside the copy.
pub fn solve_frames<F: AsRef<[Vec3]>>(
    rig: &SkinnedRig,
    frames: impl IntoIterator<Item = F, IntoIter: ExactSizeIterator>,
) -> Result<FrameSolve> {
    rig.validate()?;
    let nv = rig.n_vertices();
    let frames = frames.into_iter();
    let ns = frames.len();
    let mut by_vertex = vec![[0.0; 3]; nv * ns];
    for (f, frame) in frames.enumerate() {
        let frame = frame.as_ref();
        if frame.len() != nv {
            return Err(Error::Request(format!(
                "frame {} has {} vertices but the rig has {nv}: the frames must be the rig's mesh (same vertices, same order)",
                f + 1,
                frame.len()
            )));
        }
        if let Some(v) = frame.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::Request(format!("frame {}: vertex {v} is not a finite point", f + 1)));
        }
        for (v, &p) in frame.iter().enumerate() {
            by_vertex[v * ns + f] = p;
        }
    }
    let nb = rig.n_bones();
    let sums = BoneSums::new(&by_vertex, ns, &rig.rest, &rig.weights, &rig.order, nb);
    // supports for the starting motions
    let mut support: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nb];
    for v in 0..nv {
        for (k, w) in rig.weights.influences(v) {
            support[k].push((v, w));
        }
    }
    let diag = rig.diagonal().max(1e-300);
    let mut bones = Vec::with_capacity(ns);
    let mut errors = Vec::with_capacity(ns);
    let mut steps = Vec::with_capacity(ns);
    for i in 0..ns {
        let frame = |v: usize| by_vertex[v * ns + i];
        let mut m = vec![RigidMotion::IDENTITY; nb];
        for &k in &rig.order {
            m[k] = match weighted_procrustes(&support[k], &rig.rest, frame) {
                Some(x) => x,
                None => rig.parent[k].map_or(RigidMotion::IDENTITY, |p| m[p]),
            };
        }
        let mut n = 0;
        while n < MAX_STEPS {
            let before = m.clone();
            sums.step(i, &rig.order, &mut m);
            n += 1;
            let moved = rig.order.iter().map(|&k| motion_change(&before[k], &m[k], diag)).fold(0.0, f64::max);
            if moved <= 1e-9 * diag {
                break;
            }
        }
        // bones without vertices follow their parent
        for &k in &rig.order {
            if support[k].is_empty() {
                if let Some(p) = rig.parent[k] {
                    m[k] = m[p];
                }
            }
        }
        errors.push(
            rig.skin(&m)
                .iter()
                .enumerate()
                .map(|(v, &x)| {
                    let d = sub(x, frame(v));
                    dot(d, d)
                })
                .sum(),
        );
        bones.push(m);
        steps.push(n);
    }
    Ok(FrameSolve { bones, sse: errors, steps })
}

/// How far two motions move points within `radius` of the origin apart, at most (a bound: |ΔR| r + |Δt|).
fn motion_change(a: &RigidMotion, b: &RigidMotion, radius: f64) -> f64 {
    let dr = (a.rotation - b.rotation).norm();
    dr * radius + norm(sub(a.translation, b.translation))
}

/// min Σ w |M u - y|² over rigid M, on the listed (vertex, weight) pairs; None when there are none.
fn weighted_procrustes(support: &[(usize, f64)], rest: &[Vec3], target: impl Fn(usize) -> Vec3) -> Option<RigidMotion> {
    let wsum: f64 = support.iter().map(|x| x.1).sum();
    if support.is_empty() || !(wsum > 0.0) {
        return None;
    }
    let (mut ub, mut yb) = ([0.0; 3], [0.0; 3]);
    for &(v, w) in support {
        ub = add(ub, scale(rest[v], w));
        yb = add(yb, scale(target(v), w));
    }
    ub = scale(ub, 1.0 / wsum);
    yb = scale(yb, 1.0 / wsum);
    let mut c = Mat3::zeros();
    for &(v, w) in support {
        let (y, u) = (sub(target(v), yb), sub(rest[v], ub));
        for a in 0..3 {
            for b in 0..3 {
                c[(a, b)] += w * y[a] * u[b];
            }
        }
    }
    let r = best_rotation(&c);
    Some(RigidMotion { rotation: r, translation: sub(yb, mat_vec(&r, ub)) })
}

/// Every bone's rotation relative to its parent's (the root's: its own), from bind -> pose motions: Q_k = R_pᵀ R_k.
pub fn local_rotations(rig: &SkinnedRig, bones: &[RigidMotion]) -> Vec<Mat3> {
    (0..rig.n_bones())
        .map(|k| match rig.parent[k] {
            Some(p) => mat_mul(&transpose(&bones[p].rotation), &bones[k].rotation),
            None => bones[k].rotation,
        })
        .collect()
}

/// The pose with the root at `root` and every other bone turned by `locals[k]` (relative to its parent, about its
/// joint point) and carried by its parent: M_k x = M_p (p_k + Q_k (x - p_k)).
pub fn pose_from_locals(rig: &SkinnedRig, root: RigidMotion, locals: &[Mat3]) -> Vec<RigidMotion> {
    let mut m = vec![RigidMotion::IDENTITY; rig.n_bones()];
    for &k in &rig.order {
        m[k] = match rig.parent[k] {
            None => root,
            Some(p) => {
                let pk = rig.joint_points[k];
                let turn = RigidMotion { rotation: locals[k], translation: sub(pk, mat_vec(&locals[k], pk)) };
                m[p].then_after(&turn)
            }
        };
    }
    m
}

/// Bone k's subtree turned by `angle` radians about `axis` (world) through bone k's joint as it is in the pose
/// (its bind joint point carried by its parent; the root's by itself): the page's drag. Bones outside the subtree
/// keep their motions, so vertices weighted only to them do not move, and the joint stays where it is.
pub fn turn(rig: &SkinnedRig, bones: &[RigidMotion], k: usize, axis: Vec3, angle: f64) -> Result<Vec<RigidMotion>> {
    if k >= rig.n_bones() || !rig.order.contains(&k) {
        return Err(Error::Request(format!("no bone {k} in the skeleton ({} bones)", rig.n_bones())));
    }
    if bones.len() != rig.n_bones() {
        return Err(Error::Request(format!("{} bone motions for {} bones", bones.len(), rig.n_bones())));
    }
    if !(norm(axis) > 0.0) || !angle.is_finite() {
        return Err(Error::Request("turn: the axis must be a non-zero vector and the angle a number".into()));
    }
    let holder = rig.parent[k].unwrap_or(k);
    let c = bones[holder].apply(rig.joint_points[k]);
    let r = axis_angle(axis, angle);
    let g = RigidMotion { rotation: r, translation: sub(c, mat_vec(&r, c)) };
    Ok((0..rig.n_bones())
        .map(|b| if rig.order.contains(&b) && rig.in_subtree(k, b) { g.then_after(&bones[b]) } else { bones[b] })
        .collect())
}

/// Log map of a rotation: axis · angle (radians), angle in [0, π].
pub fn log_map(r: &Mat3) -> Vec3 {
    let q = crate::geometry::rotation::to_quat(r);
    let v = q.scaled_axis();
    [v[0], v[1], v[2]]
}

/// Exp map: the rotation of axis · angle.
pub fn exp_map(v: Vec3) -> Mat3 {
    let a = norm(v);
    if a == 0.0 {
        IDENTITY
    } else {
        axis_angle(v, a)
    }
}

/// The space of poses a set of training poses spans (module doc).
#[derive(Debug, Clone, Serialize)]
pub struct PoseSpace {
    /// The bones whose local rotations make the pose vector (the skeleton's non-root bones, in skeleton order):
    /// coordinates 3 b .. 3 b + 3 are `bones[b]`'s log map.
    pub bones: Vec<usize>,
    /// Mean pose vector.
    pub mean: Vec<f64>,
    /// Unit modes, largest variance first (as many as the poses span).
    pub modes: Vec<Vec<f64>>,
    /// Standard deviation of the training poses along each mode (radians).
    pub sd: Vec<f64>,
    /// Each training pose's pose vector.
    pub training: Vec<Vec<f64>>,
    /// Each training pose's coordinates along the modes.
    pub coords: Vec<Vec<f64>>,
    /// Smallest and largest training coordinate along each mode.
    pub range: Vec<[f64; 2]>,
}

impl PoseSpace {
    /// From bind -> pose motions of the training poses (`poses[i][k]`).
    pub fn new(rig: &SkinnedRig, poses: &[Vec<RigidMotion>]) -> Result<PoseSpace> {
        if poses.is_empty() {
            return Err(Error::Request("the pose space needs at least one pose".into()));
        }
        if let Some(i) = poses.iter().position(|p| p.len() != rig.n_bones()) {
            return Err(Error::Request(format!(
                "pose {} has {} bone motions for {} bones",
                i + 1,
                poses[i].len(),
                rig.n_bones()
            )));
        }
        let bones: Vec<usize> = rig.order.iter().copied().filter(|&k| rig.parent[k].is_some()).collect();
        let dim = 3 * bones.len();
        let training: Vec<Vec<f64>> = poses
            .iter()
            .map(|p| {
                let q = local_rotations(rig, p);
                bones.iter().flat_map(|&k| log_map(&q[k])).collect()
            })
            .collect();
        let n = training.len();
        let mut mean = vec![0.0; dim];
        for x in &training {
            for (m, v) in mean.iter_mut().zip(x) {
                *m += v / n as f64;
            }
        }
        let mut modes = Vec::new();
        let mut sd = Vec::new();
        if n >= 2 && dim > 0 {
            let centred = nalgebra::DMatrix::from_fn(n, dim, |i, d| training[i][d] - mean[d]);
            let svd = centred.svd(false, true);
            let vt = svd.v_t.expect("asked for V");
            let mut idx: Vec<usize> = (0..svd.singular_values.len()).collect();
            idx.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
            let top = idx.first().map_or(0.0, |&i| svd.singular_values[i]);
            for &i in &idx {
                let s = svd.singular_values[i];
                if !(s > 1e-9 * top.max(1e-300)) || modes.len() >= n - 1 {
                    break;
                }
                let mut m: Vec<f64> = vt.row(i).iter().copied().collect();
                // sign: the largest component positive (deterministic)
                let big = m.iter().copied().fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
                if big < 0.0 {
                    m.iter_mut().for_each(|x| *x = -*x);
                }
                modes.push(m);
                sd.push(s / ((n - 1) as f64).sqrt());
            }
        }
        let mut space = PoseSpace { bones, mean, modes, sd, training, coords: Vec::new(), range: Vec::new() };
        space.coords = space.training.iter().map(|x| space.project(x)).collect();
        space.range = (0..space.modes.len())
            .map(|m| {
                space.coords.iter().fold([f64::INFINITY, f64::NEG_INFINITY], |r, c| [r[0].min(c[m]), r[1].max(c[m])])
            })
            .collect();
        Ok(space)
    }

    pub fn n_modes(&self) -> usize {
        self.modes.len()
    }

    /// Coordinates of a pose vector along the modes.
    pub fn project(&self, x: &[f64]) -> Vec<f64> {
        self.modes.iter().map(|m| m.iter().zip(x).zip(&self.mean).map(|((a, b), c)| a * (b - c)).sum()).collect()
    }

    /// The pose vector of mode coefficients (missing ones 0): mean + Σ c_m mode_m.
    pub fn vector(&self, coeffs: &[f64]) -> Vec<f64> {
        let mut x = self.mean.clone();
        for (m, &c) in self.modes.iter().zip(coeffs) {
            for (a, b) in x.iter_mut().zip(m) {
                *a += c * b;
            }
        }
        x
    }

    /// Local rotations (per bone, identity for the root and bones outside the pose vector) of a pose vector.
    pub fn locals(&self, n_bones: usize, x: &[f64]) -> Vec<Mat3> {
        let mut q = vec![IDENTITY; n_bones];
        for (b, &k) in self.bones.iter().enumerate() {
            q[k] = exp_map([x[3 * b], x[3 * b + 1], x[3 * b + 2]]);
        }
        q
    }

    /// The pose (bind -> pose motions) of mode coefficients, the root at its bind placement.
    pub fn pose(&self, rig: &SkinnedRig, coeffs: &[f64]) -> Vec<RigidMotion> {
        pose_from_locals(rig, RigidMotion::IDENTITY, &self.locals(rig.n_bones(), &self.vector(coeffs)))
    }

    /// Mode coefficients drawn uniformly within the training range of every mode (seeded).
    pub fn random(&self, seed: u64) -> Vec<f64> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        self.range.iter().map(|r| if r[1] > r[0] { rng.gen_range(r[0]..=r[1]) } else { r[0] }).collect()
    }
}

/// One fold of [`crossval`]: pose `name` left out.
#[derive(Debug, Clone, Serialize)]
pub struct Fold {
    pub name: String,
    /// E_RMS of the fold's rig over its own training poses (every pose but this one).
    pub in_sample_e_rms: f64,
    /// E_RMS of the left-out pose solved onto the fold's rig ([`solve_frames`]).
    pub held_out_e_rms: f64,
    /// Bones of the fold's rig.
    pub bones: usize,
    /// Milliseconds: fit + rig, and the held-out solve.
    pub fit_ms: f64,
    pub solve_ms: f64,
}

/// Leave-one-out cross-validation of the rig: for every pose, fit (`params`) and build the rig (`rig_opts`, bind
/// pose [`crate::export::rig_report::default_bind_pose`] of the remaining poses) on all poses but that one, then
/// solve the left-out pose onto it. E_RMS as [`crate::export::rig_report`]: with the diagonal of the fold's bind
/// pose. Every fold starts from `start` ([`crate::mfa::FitStart`]: the same vertices in every fold). `progress(i,
/// n)` is called before each fold.
pub fn crossval(
    pop: &crate::mesh::Population,
    params: &crate::mfa::Params,
    start: &crate::mfa::FitStart,
    rig_opts: &super::rig::RigOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<Fold>> {
    let ns = pop.n_shapes();
    if ns < 3 {
        return Err(Error::Request(format!(
            "cross-validation leaves one pose out of at least 3; the population has {ns}"
        )));
    }
    let mut folds = Vec::with_capacity(ns);
    for out in 0..ns {
        progress(out, ns);
        let t0 = crate::clock::now_ms();
        let keep: Vec<usize> = (0..ns).filter(|&i| i != out).collect();
        let names: Vec<String> = keep.iter().map(|&i| pop.names[i].clone()).collect();
        let shapes: Vec<Vec<Vec3>> =
            keep.iter().map(|&i| pop.shape(i).iter().map(|p| pop.normalization.to_original(p)).collect()).collect();
        let train = crate::mesh::Population::new(crate::mesh::Sources::UnitShapes {
            names,
            faces: pop.faces.to_vec(),
            shapes,
        })?;
        let fit = crate::parts::hierarchy::fit_from(&train, params, start, &mut |_| true)?;
        let art = super::Articulation::new(&fit.model, &train)?;
        let bind = crate::export::rig_report::default_bind_pose(&train);
        let opts = super::rig::RigOptions { bind_pose: bind, ..*rig_opts };
        let rig = super::rig::build(&art, &opts)?;
        let t1 = crate::clock::now_ms();
        let nv = train.n_vertices();
        let diag = {
            let (lo, hi) = crate::geometry::bounds(&train.shape(bind).to_vec());
            norm(sub(hi, lo))
        };
        let in_sse: f64 = (0..train.n_shapes()).map(|i| sse(&rig.pose(i), &train.shape(i).to_vec())).sum();
        let skinned = SkinnedRig::from_rig(&rig);
        let frame: Vec<Vec3> =
            pop.shape(out).iter().map(|p| train.normalization.to_unit(pop.normalization.to_original(p))).collect();
        let solved = solve_frames(&skinned, std::slice::from_ref(&frame))?;
        let t2 = crate::clock::now_ms();
        folds.push(Fold {
            name: pop.names[out].clone(),
            in_sample_e_rms: e_rms(in_sse, nv * train.n_shapes(), diag),
            held_out_e_rms: e_rms(solved.sse[0], nv, diag),
            bones: rig.tree.order.len(),
            fit_ms: t1 - t0,
            solve_ms: t2 - t1,
        });
    }
    Ok(folds)
}

/// Median of the held-out / in-sample ratios of the folds.
pub fn median_ratio(folds: &[Fold]) -> f64 {
    let mut r: Vec<f64> = folds.iter().map(|f| f.held_out_e_rms / f.in_sample_e_rms).collect();
    r.sort_by(f64::total_cmp);
    match r.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => r[n / 2],
        n => 0.5 * (r[n / 2 - 1] + r[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_of_another_mesh_is_refused_by_its_name() {
        assert!(check_frame_sizes([("a.obj", 5), ("b.obj", 5)], 5, None).is_ok());
        let e = check_frame_sizes([("a.obj", 5), ("b10.obj", 4), ("c.obj", 3)], 5, Some("rig.glb")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "file b10.obj: has 4 vertices but the rig rig.glb has 5: add frames of the fitted mesh (the same \
             vertices in the same order, as the training poses)"
        );
        let e = check_frame_sizes([("c.obj", 3)], 5, None).unwrap_err();
        assert!(e.to_string().contains("but the rig has 5"), "{e}");
    }
}
