//! A skinned rig that reproduces the training poses: bind positions, per-vertex bone weights (at most K
//! per vertex, non-negative, summing to 1) and one rigid bone motion per part and training pose, played by
//! linear blend skinning (what glTF viewers do): v_j^i = Σ_k w_jk M_k^i u_j.
//!
//! Three kinds of weights ([`RigWeights`]):
//! - **rigid**: every vertex on its part; the mesh is bound in the bind pose's rigid reconstruction (eq 22)
//!   and M_k^i = T_k^i (T_k^bind)^-1 from the MFA fit, so the clip reproduces every rigid reconstruction;
//! - **smooth**: the articulation's smooth weights ([`super::skin::smooth_weights`]) on the bind shape itself,
//!   same motions;
//! - **fitted** (SSDR, Le & Deng 2012): starting from the MFA fit (rigid labels, T_k^i, the bind pose's rigid
//!   reconstruction as bind positions), three solves alternate [`RigOptions::iterations`] times, each an exact
//!   minimisation of the error over its own unknowns with the others fixed:
//!   - *weights*, vertex by vertex: min_w |A_j w - v_j|² + λ |w - w̄_j|² subject to w >= 0, Σ w = 1, with
//!     A_j's columns the vertex's bind position moved by each candidate bone over all poses (3 n_s rows).
//!     Candidates: the vertex's own part and the parts within [`RigOptions::rings`] steps of it in the part
//!     graph. A_jᵀA_j and A_jᵀv_j come from sums over the poses kept per part ([`OwnPart`]): per vertex, one
//!     pass over its poses per candidate, none per pair of candidates. Solved exactly by a primal active-set
//!     method on the (small) KKT system; when more than K weights are non-zero, the K largest are kept and
//!     the problem is solved again on them (kept only if it beats the current weights).
//!   - *smoothness*: w̄_j is the mean of the mesh neighbours' weights of the previous iteration and
//!     λ = [`RigOptions::smoothness`] · n_s · ℓ², ℓ² the mean squared edge length of the bind shape: a weight
//!     vector that differs from its neighbours' mean by 1 costs as much as an error of sqrt(smoothness) edge
//!     lengths in every pose (default 1e-4: 1 % of an edge). Where the data decides the weights this is
//!     negligible (measured: E_RMS unchanged to 3 digits); where it does not (candidate bones that move a
//!     vertex almost alike, deep inside a part or across a joint that barely moves), it makes the weights
//!     follow their neighbours instead of jumping from vertex to vertex. A relative λ (a fraction of the data
//!     term's scale) was tried first and lost 40-70 % of the gain on the generated quadruped: the data term
//!     is tiny exactly where smoothing should decide, so any λ large enough to matter there diffuses
//!     weights everywhere else.
//!   - *bones*, pose by pose and part by part in tree order (block coordinate descent): with the others
//!     fixed, the part's rigid motion minimising Σ_j |r_j - w_jk (R u_j + t)|² (r_j: the target minus the
//!     other bones' share) is a weighted Procrustes problem: C = Σ_j w_jk r_j (u_j - ū)^T with
//!     ū = Σ w² u / Σ w², R by SVD with the handedness fix, t = (Σ w r) / Σ w² - R ū. C and Σ w r come from
//!     sums, not from a pass over the vertices per update: the target's share once per pose and bone, and per
//!     pair of bones sharing vertices pose-free sums of w_k w_l u (u - ū)ᵀ, carried by the other bone's current
//!     motion ([`Solver::bones`]). The bind pose's bones
//!     stay the identity: otherwise a bone's motions and its vertices' bind positions can drift together
//!     (M_k G, G⁻¹ u give the same poses), and the mesh stored in the file wanders away from the bind pose
//!     (measured on horse-gallop at 10 bones: 3736 of 8431 vertices more than 1 % of the diagonal away,
//!     up to 18 %); with it the bind positions stay near the bind pose, which they must reproduce alone.
//!   - *bind positions* ([`RigOptions::fit_rest`]): per vertex the 3x3 least squares
//!     (Σ_i L_iᵀ L_i) u = Σ_i L_iᵀ (v_i - c_i), L_i and c_i the blended linear part and translation. The rest
//!     mesh is the rig's to choose (Dem Bones keeps the one it is given); without this step, the bind shape
//!     carries its own pose's residual into every pose.
//! - **fixed joints** ([`Joints::Fixed`]): every non-root bone turns about its joint point p_k (bind pose),
//!   which its parent carries: M_k^i p_k = M_p^i p_k, so in the skeleton the local animation is rotation only
//!   and bone lengths are constant. After half the iterations free, each joint point moves to where the two
//!   bones move most alike: min_p Σ_i |M_k^i p - M_p^i p|² + μ |p - p_0|² (a 3x3 solve; p_0 the contact
//!   centroid, μ keeps a hinge's point near it along the axis); the bones are then made to satisfy the
//!   constraint down the tree, and refitted with it: in tree order, the root's whole subtree gets the rigid
//!   motion, every other bone's subtree the rotation about the bone's joint, that best carries the subtree's
//!   share of every vertex onto what the rest leaves of the target (a Procrustes problem again, exact, so the
//!   error never grows), alternating with the weights and bind positions.
//! - **bone scale** ([`RigOptions::bone_scale`], fitted weights with free joints): every bone's motion is
//!   x -> R Q S Qᵀ x + t, Q a fixed rotation per bone (the principal axes of its vertices' w²-weighted bind
//!   positions, from the MFA start), S = diag(s) per pose, 9 numbers per bone and pose instead of 6. The bone step
//!   alternates R (the best rotation of C Q S Qᵀ) and s (s_a = (Qᵀ Rᵀ C Q)_aa / (Qᵀ G Q)_aa, G = Σ w² (u - ū)(u - ū)ᵀ,
//!   clamped to [0.5, 2]), each exact with the other fixed, starting from the pose's current s, so it never raises
//!   the error. The weights and bind positions take the general linear part as they are. In the .glb each bone
//!   gets a leaf node under its joint with the fixed rotation to Q and the animated scale (a scale on the joint
//!   itself would reach its children).
//! - **affine bones** ([`RigOptions::bone_affine`], fitted weights with free joints): every bone's linear part is
//!   any 3x3 matrix A with a positive determinant, 12 numbers per bone and pose, as Hyperspectral Inverse
//!   Skinning's bones (Liu et al. 2020). The bone step is the least-squares A = C G⁻¹ (C and G as above, a ridge
//!   of 1e-6 tr G), exact with the other bones fixed; where it would turn the bone inside out (det A <= 0) or
//!   scale it beyond [0.5, 2] along some direction, the bone takes the best by its own error of that A clamped,
//!   the scaled step and its current A, so the step never raises the error. After the fit every
//!   A is split by the polar decomposition A = R P, P = Q S Qᵀ (Q and S per pose), which the .glb plays as two
//!   leaf nodes under the joint: rotation Q and scale S, then rotation Qᵀ.
//!
//! All in unit-box coordinates; the .glb writer ([`crate::export::gltf`]) converts.

use super::graph::{mesh_edges, Tree, TreeRule, VertexNeighbours};
use super::skin::SkinWeights;
use super::{Articulation, RigidMotion};
use crate::error::{Error, Result};
use crate::geometry::procrustes::best_rotation;
use crate::geometry::{add, dot, mat_vec, scale, sub, Mat3, Vec3};
use crate::mesh::population::widen;
use serde::{Deserialize, Serialize};

/// Which weights the rig carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RigWeights {
    /// Each vertex on its part (one bone, weight 1). Default.
    #[default]
    Rigid,
    /// The articulation's smooth weights (a prior, not fitted).
    Smooth,
    /// Weights and bone motions solved against every training pose (SSDR, module doc).
    Fitted,
}

/// How the skeleton's joints move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Joints {
    /// Every bone has its own rigid motion (the local animation has translations: bone lengths vary).
    /// Default.
    #[default]
    Free,
    /// Every non-root bone turns about the joint its parent carries: rotation-only local animation.
    Fixed,
}

/// Rig options. Defaults in each field's doc.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, rename_all = "camelCase")]
pub struct RigOptions {
    /// Default [`RigWeights::Rigid`].
    pub weights: RigWeights,
    /// Most bones per vertex, 1..=8. Default 4.
    pub influences: usize,
    /// Default [`Joints::Free`].
    pub joints: Joints,
    /// Training shape the mesh is bound in (0-based). Default 0.
    pub bind_pose: usize,
    /// Fitted weights: most alternations of the weight and bone solves. Default 30 (docs/rig.md).
    pub iterations: usize,
    /// Fitted weights: the alternations stop once one lowers the squared error by less than this fraction of
    /// it (E_RMS by about half of it), >= 0; 0 runs all [`RigOptions::iterations`]. Default 1e-2.
    pub tol: f64,
    /// Fitted weights: rings of the part graph around a vertex's part that give its candidate bones, 1..=3.
    /// Default 1.
    pub rings: usize,
    /// Fitted weights: smoothness, in squared edge lengths per pose (module doc), >= 0. Default 1e-4.
    pub smoothness: f64,
    /// Fitted weights: the bind positions are solved too (module doc). Default true.
    pub fit_rest: bool,
    /// Fitted weights with free joints: every bone also scales along three fixed axes of its own, per pose
    /// ([`BoneScale`]). Default false.
    pub bone_scale: bool,
    /// Fitted weights with free joints: every bone's linear part is any 3x3 matrix of positive determinant, per
    /// pose (module doc; [`BoneScale::turning`]). Default false.
    pub bone_affine: bool,
}

impl Default for RigOptions {
    fn default() -> RigOptions {
        RigOptions {
            weights: RigWeights::Rigid,
            influences: 4,
            joints: Joints::Free,
            bind_pose: 0,
            iterations: 30,
            tol: 1e-2,
            rings: 1,
            smoothness: 1e-4,
            fit_rest: true,
            bone_scale: false,
            bone_affine: false,
        }
    }
}

impl RigOptions {
    pub fn validate(&self, n_shapes: usize) -> Result<()> {
        if !(1..=8).contains(&self.influences) {
            return Err(Error::Params(format!(
                "influences = {} must be between 1 and 8 (glTF: 4 per JOINTS_n set)",
                self.influences
            )));
        }
        if self.bind_pose >= n_shapes {
            return Err(Error::Request(format!(
                "bind pose {} (0-based): the population has {n_shapes} poses",
                self.bind_pose
            )));
        }
        if !(1..=3).contains(&self.rings) {
            return Err(Error::Params(format!("rings = {} must be between 1 and 3", self.rings)));
        }
        if !(self.smoothness >= 0.0 && self.smoothness.is_finite()) {
            return Err(Error::Params(format!("smoothness = {} must be a number >= 0 (try 1e-4)", self.smoothness)));
        }
        if !(self.tol >= 0.0 && self.tol.is_finite()) {
            return Err(Error::Params(format!(
                "tol = {} must be a number >= 0 (try 1e-2; 0 runs every iteration)",
                self.tol
            )));
        }
        if self.bone_scale && (self.weights != RigWeights::Fitted || self.joints != Joints::Free) {
            return Err(Error::Params(
                "bone scale needs fitted weights and free joints (--weights fitted --joints free)".into(),
            ));
        }
        if self.bone_affine && (self.weights != RigWeights::Fitted || self.joints != Joints::Free) {
            return Err(Error::Params(
                "affine bones need fitted weights and free joints (--weights fitted --joints free)".into(),
            ));
        }
        if self.bone_affine && self.bone_scale {
            return Err(Error::Params(
                "bone scale and affine bones exclude each other (affine bones scale too): ask for one".into(),
            ));
        }
        if self.iterations > 10_000 || (self.iterations == 0 && self.weights == RigWeights::Fitted) {
            return Err(Error::Params(format!(
                "alternations (iterations) = {} must be between 1 and 10000 (default 30)",
                self.iterations
            )));
        }
        Ok(())
    }
}

/// A skinned rig (module doc), unit-box coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    /// Bind positions u_j (the mesh as stored in the .glb).
    pub rest: Vec<Vec3>,
    /// Per vertex (part, weight): at most `influences`, positive, summing to 1.
    pub weights: SkinWeights,
    /// `bones[i][k]`: part k's motion from the bind pose to training pose i.
    pub bones: Vec<Vec<RigidMotion>>,
    /// The skeleton (parts as bones, strongest contacts): rooted at the anchor while the bones are fitted; with
    /// fitted weights and free joints, re-rooted afterwards on the central part ([`super::joints::place_free_joints`]).
    pub tree: Tree,
    /// Each bone's joint point in the bind pose: with its parent (the contact's centroid, or with fitted weights and
    /// free joints the pivot where parent and child move most alike), or the root's centroid.
    pub joint_points: Vec<Vec3>,
    pub joints: Joints,
    /// Sum of squared errors after each alternation (fitted weights), unit box.
    pub trace: Vec<f64>,
    /// With [`RigOptions::bone_scale`] or [`RigOptions::bone_affine`]: each bone's scale axes and factors.
    /// `bones[i][k].rotation` is then R Q S Qᵀ (a rotation after a scaling along the axes), not a rotation.
    pub scale: Option<BoneScale>,
}

/// Per-bone scale channels: bone k's skin motion in pose i is x -> R (Q_ki S_ki Q_kiᵀ x) + t, Q_ki a rotation
/// whose columns are the bone's scale axes, S_ki = diag(`factors[i][k]`). With bone scale the axes are fixed
/// (`axes[k]`, from the bind pose); with affine bones they turn from pose to pose (`turning[i][k]`).
#[derive(Debug, Clone, PartialEq)]
pub struct BoneScale {
    pub axes: Vec<Mat3>,
    pub factors: Vec<Vec<Vec3>>,
    /// Affine bones: the scale axes Q of every pose and bone (the polar decomposition of each bone's A).
    pub turning: Option<Vec<Vec<Mat3>>>,
}

impl BoneScale {
    /// The scale axes Q of bone k in pose i.
    pub fn axes_of(&self, i: usize, k: usize) -> &Mat3 {
        match &self.turning {
            Some(t) => &t[i][k],
            None => &self.axes[k],
        }
    }

    /// Q S Qᵀ of bone k in pose i.
    pub fn stretch(&self, i: usize, k: usize) -> Mat3 {
        stretch(self.axes_of(i, k), self.factors[i][k])
    }

    /// (Q S Qᵀ)⁻¹ of bone k in pose i.
    pub fn stretch_inverse(&self, i: usize, k: usize) -> Mat3 {
        stretch(self.axes_of(i, k), self.factors[i][k].map(|f| 1.0 / f))
    }
}

/// The polar decomposition A = R Q S Qᵀ of a 3x3 matrix of positive determinant: (Q, S), Q a rotation whose
/// columns are the principal axes of the stretch, S its factors (the singular values of A). None when det A <= 0.
pub fn polar_stretch(a: &Mat3) -> Option<(Mat3, Vec3)> {
    if !(a.determinant() > 0.0) {
        return None;
    }
    // AᵀA = Q S² Qᵀ
    let e = (a.transpose() * a).symmetric_eigen();
    let mut q = e.eigenvectors;
    if q.determinant() < 0.0 {
        q.column_mut(2).neg_mut();
    }
    let s = [0, 1, 2].map(|c| e.eigenvalues[c].max(0.0).sqrt());
    if s.iter().all(|x| x.is_finite() && *x > 0.0) && q.iter().all(|x| x.is_finite()) {
        Some((q, s))
    } else {
        None
    }
}

/// Q diag(s) Qᵀ.
fn stretch(q: &Mat3, s: Vec3) -> Mat3 {
    q * Mat3::from_diagonal(&nalgebra::Vector3::new(s[0], s[1], s[2])) * q.transpose()
}

impl Rig {
    /// Linear blend skinning of the bind positions for training pose i (f64).
    pub fn pose(&self, i: usize) -> Vec<Vec3> {
        (0..self.rest.len())
            .map(|v| {
                let mut x = [0.0; 3];
                for (k, w) in self.weights.influences(v) {
                    x = add(x, scale(self.bones[i][k].apply(self.rest[v]), w));
                }
                x
            })
            .collect()
    }
}

/// Small dense solve (Gaussian elimination, partial pivoting) of the n x n system a x = b, a row-major.
/// Returns false when singular. Inlined where it is called, so the bind-position solve's 3 x 3 case is
/// compiled for n = 3 (the same operations in the same order).
#[inline(always)]
fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for col in 0..n {
        let mut piv = col;
        for r in col + 1..n {
            if a[r * n + col].abs() > a[piv * n + col].abs() {
                piv = r;
            }
        }
        if a[piv * n + col].abs() < 1e-300 {
            return false;
        }
        if piv != col {
            for c in 0..n {
                a.swap(piv * n + c, col * n + c);
            }
            b.swap(piv, col);
        }
        let d = a[col * n + col];
        for r in col + 1..n {
            let f = a[r * n + col] / d;
            if f != 0.0 {
                for c in col..n {
                    a[r * n + c] -= f * a[col * n + c];
                }
                b[r] -= f * b[col];
            }
        }
    }
    for col in (0..n).rev() {
        let mut s = b[col];
        for c in col + 1..n {
            s -= a[col * n + c] * b[c];
        }
        b[col] = s / a[col * n + col];
    }
    b.iter().all(|x| x.is_finite())
}

/// min ½ wᵀHw - fᵀw subject to w >= 0, Σ w = 1 (H symmetric positive definite, c x c row-major), by a
/// primal active-set method started from `w` (feasible). Indices with `allowed[i] == false` stay at 0.
pub fn simplex_qp(h: &[f64], f: &[f64], w: &mut [f64], allowed: &[bool]) {
    QpScratch::default().solve(h, f, w, allowed);
}

/// Working memory of [`simplex_qp`], kept across the vertices of a weight solve (no allocation per vertex).
#[derive(Default)]
struct QpScratch {
    free: Vec<bool>,
    idx: Vec<usize>,
    a: Vec<f64>,
    rhs: Vec<f64>,
}

impl QpScratch {
    /// [`simplex_qp`].
    fn solve(&mut self, h: &[f64], f: &[f64], w: &mut [f64], allowed: &[bool]) {
        let QpScratch { free, idx, a, rhs } = self;
        let c = f.len();
        free.clear();
        free.extend((0..c).map(|i| allowed[i] && w[i] > 0.0));
        for _ in 0..(4 * c + 10) {
            idx.clear();
            idx.extend((0..c).filter(|&i| free[i]));
            let m = idx.len();
            // KKT: [H_FF 1; 1ᵀ 0] [p; μ] = [f_F; 1]
            a.clear();
            a.resize((m + 1) * (m + 1), 0.0);
            rhs.clear();
            rhs.resize(m + 1, 0.0);
            for (r, &i) in idx.iter().enumerate() {
                for (s, &j) in idx.iter().enumerate() {
                    a[r * (m + 1) + s] = h[i * c + j];
                }
                a[r * (m + 1) + m] = 1.0;
                a[m * (m + 1) + r] = 1.0;
                rhs[r] = f[i];
            }
            rhs[m] = 1.0;
            if !solve_dense(a, rhs, m + 1) {
                return;
            }
            let (p, mu) = (&rhs[..m], rhs[m]);
            if p.iter().all(|&x| x >= 0.0) {
                for (r, &i) in idx.iter().enumerate() {
                    w[i] = p[r];
                }
                for i in 0..c {
                    if !free[i] {
                        w[i] = 0.0;
                    }
                }
                // multipliers of the bound constraints: ν_i = (H w - f)_i - (-μ)... with the KKT sign convention
                // H w - f + μ 1 - ν = 0, ν_i = (H w - f)_i + μ must be >= 0 at the optimum
                let mut worst: Option<(usize, f64)> = None;
                for i in 0..c {
                    if free[i] || !allowed[i] {
                        continue;
                    }
                    let g: f64 = (0..c).map(|j| h[i * c + j] * w[j]).sum::<f64>() - f[i];
                    let nu = g + mu;
                    if nu < -1e-14 * (1.0 + g.abs()) && worst.is_none_or(|x| nu < x.1) {
                        worst = Some((i, nu));
                    }
                }
                match worst {
                    Some((i, _)) => free[i] = true,
                    None => return,
                }
            } else {
                // step from w toward p until a free weight hits 0
                let mut t = 1.0;
                let mut block = None;
                for (r, &i) in idx.iter().enumerate() {
                    if p[r] < 0.0 {
                        let s = w[i] / (w[i] - p[r]);
                        if s < t {
                            t = s;
                            block = Some(i);
                        }
                    }
                }
                for (r, &i) in idx.iter().enumerate() {
                    w[i] += t * (p[r] - w[i]);
                }
                if let Some(i) = block {
                    w[i] = 0.0;
                    free[i] = false;
                }
                for i in 0..c {
                    if free[i] && w[i] <= 0.0 {
                        w[i] = 0.0;
                        free[i] = false;
                    }
                }
                if !free.iter().any(|&x| x) {
                    return;
                }
            }
        }
    }
}

/// The rig of an articulation (module doc).
pub fn build(art: &Articulation, opts: &RigOptions) -> Result<Rig> {
    opts.validate(art.n_shapes())?;
    let ns = art.n_shapes();
    let bind = opts.bind_pose;
    let tree = art.graph.tree(art.anchor, TreeRule::Strongest);
    let n_parts = art.n_parts();
    let mfa_bones: Vec<Vec<RigidMotion>> = (0..ns)
        .map(|i| {
            (0..n_parts).map(|k| art.training_motion(k, i).then_after_inverse(&art.training_motion(k, bind))).collect()
        })
        .collect();
    let joint_points: Vec<Vec3> = (0..n_parts)
        .map(
            |k| if tree.contains(k) { art.training_motion(k, bind).apply(art.node_offset(&tree, k)) } else { [0.0; 3] },
        )
        .collect();
    let (rest, weights) = match opts.weights {
        RigWeights::Rigid => (art.rigid(bind), art.rigid_weights.capped(opts.influences)),
        RigWeights::Smooth => (art.shape(bind), art.smooth_weights.capped(opts.influences)),
        RigWeights::Fitted => (art.rigid(bind), art.rigid_weights.clone()),
    };
    let mut rig = Rig {
        rest,
        weights,
        bones: mfa_bones,
        tree,
        joint_points,
        joints: opts.joints,
        trace: Vec::new(),
        scale: None,
    };
    if opts.weights == RigWeights::Fitted {
        fit(&mut rig, art, opts);
        if opts.joints == Joints::Free {
            // the root and the joints' nodes where an artist puts them; bones and weights as fitted
            super::joints::place_free_joints(art, &mut rig, bind);
        }
    } else if opts.joints == Joints::Fixed {
        // rigid or smooth weights with fixed joints: the bones are refitted with the constraint, weights kept
        let solver = Solver::new(art, &rig, opts);
        fit_joint_points(&mut rig);
        constrain(&mut rig);
        for _ in 0..opts.iterations.max(1) {
            solver.bones_fixed(&mut rig);
        }
        rig.trace.push(solver.sse(&rig));
    }
    Ok(rig)
}

impl RigidMotion {
    /// self ∘ other⁻¹.
    fn then_after_inverse(&self, other: &RigidMotion) -> RigidMotion {
        self.then_after(&other.inverse())
    }
}

struct Solver {
    /// The training poses, read one at a time (an f64 copy of them all would be 24 bytes per vertex-pose).
    targets: crate::mesh::Population,
    /// How many.
    ns: usize,
    /// The targets vertex by vertex: `by_vertex[v * n_s + i]` is vertex v in pose i (a vertex's poses contiguous,
    /// for the per-vertex solves), as the population stores them (f32: 12 bytes per vertex-pose, not 24; every
    /// reader widens them to the same f64 the population's shapes give).
    by_vertex: Vec<[f32; 3]>,
    /// Σ_i |v_i|² of every vertex over the poses.
    target_norms: Vec<f64>,
    /// Candidate parts per vertex (own part first).
    candidates: Vec<Vec<u32>>,
    /// Each vertex's part (its candidates are `near[label]`).
    labels: Vec<u32>,
    /// Candidate parts of the vertices of each part.
    near: Vec<Vec<u32>>,
    /// Mean bind position of each part's vertices at the start ([`OwnPart`]'s fixed point).
    origin: Vec<Vec3>,
    /// CSR mesh neighbours.
    neighbours: VertexNeighbours,
    influences: usize,
    smoothness: f64,
    /// Mean squared edge length of the bind shape.
    edge2: f64,
    /// The bind pose: its bones stay the identity (below).
    bind: usize,
    /// Affine bones ([`RigOptions::bone_affine`]).
    affine: bool,
}

/// Working memory of [`Solver::weights`], reused by every vertex and every pass.
#[derive(Default)]
struct WeightScratch {
    qp: QpScratch,
    cols: Vec<f64>,
    h: Vec<f64>,
    f: Vec<f64>,
    w: Vec<f64>,
    start: Vec<f64>,
    allowed: Vec<bool>,
    order: Vec<usize>,
    dense_nbr: Vec<f64>,
    /// The weight lists of the pass before last, overwritten in place.
    new: Vec<Vec<(u32, f64)>>,
    /// Per part, its candidates' motions relative to it and their sums over the poses (this pass's bones).
    own: Vec<OwnPart>,
}

/// What the weight solve of the vertices of one part needs of the bones, for the current pass: with p the part,
/// a = 1..c its other candidate bones, o a fixed point near the part (its vertices' mean bind position),
/// ΔR_a = R_a - R_p and Δt'_a = ΔR_a o + t_a - t_p per pose (so M_a u - M_p u = ΔR_a (u - o) + Δt'_a), the
/// per-vertex Gram matrix of [`vertex_weights`] is a quadratic in u - o whose coefficients are sums over
/// the poses, and its right-hand side needs, per vertex, only Σ_i ΔR_aᵀ y'_i and Σ_i Δt'_a · y'_i.
#[derive(Default)]
struct OwnPart {
    origin: Vec3,
    /// Per pose: M_p o (3), then per a: [ΔR_a | Δt'_a] row-major (3 x 4, so that ΔR_aᵀ y and Δt'_a · y are one
    /// 4-lane sum of its rows weighted by y).
    poses: Vec<f64>,
    /// Per pair a <= b (index a c + b, 16 each): Σ ΔR_aᵀ ΔR_b row-major (9), Σ ΔR_aᵀ Δt'_b (3), Σ Δt'_a · Δt'_b,
    /// Σ ΔR_bᵀ Δt'_a (3).
    pairs: Vec<f64>,
    /// Per a (12 each): Σ ΔR_aᵀ R_p row-major (9), Σ R_pᵀ Δt'_a (3).
    own: Vec<f64>,
}

impl OwnPart {
    fn update(&mut self, cand: &[u32], origin: Vec3, bones: &[Vec<RigidMotion>]) {
        let c = cand.len();
        self.origin = origin;
        self.poses.clear();
        self.pairs.clear();
        self.pairs.resize(c * c * 16, 0.0);
        self.own.clear();
        self.own.resize(c * 12, 0.0);
        if c <= 1 {
            return;
        }
        let mut rel = vec![[0.0; 12]; c];
        for pose in bones {
            let mp = &pose[cand[0] as usize];
            let rp = &mp.rotation;
            let po = mp.apply(origin);
            self.poses.extend_from_slice(&po);
            for a in 1..c {
                let ma = &pose[cand[a] as usize];
                let m = &mut rel[a];
                for r in 0..3 {
                    for q in 0..3 {
                        m[r * 3 + q] = ma.rotation[(r, q)] - rp[(r, q)];
                    }
                }
                let dro = [
                    m[0] * origin[0] + m[1] * origin[1] + m[2] * origin[2],
                    m[3] * origin[0] + m[4] * origin[1] + m[5] * origin[2],
                    m[6] * origin[0] + m[7] * origin[1] + m[8] * origin[2],
                ];
                for r in 0..3 {
                    m[9 + r] = dro[r] + (ma.translation[r] - mp.translation[r]);
                }
                for r in 0..3 {
                    self.poses.extend_from_slice(&[m[r * 3], m[r * 3 + 1], m[r * 3 + 2], m[9 + r]]);
                }
            }
            for a in 1..c {
                let ma = &rel[a];
                for b in a..c {
                    let mb = &rel[b];
                    let q = &mut self.pairs[(a * c + b) * 16..(a * c + b + 1) * 16];
                    for r in 0..3 {
                        for s in 0..3 {
                            q[r * 3 + s] += ma[r] * mb[s] + ma[3 + r] * mb[3 + s] + ma[6 + r] * mb[6 + s];
                        }
                        q[9 + r] += ma[r] * mb[9] + ma[3 + r] * mb[10] + ma[6 + r] * mb[11];
                        q[13 + r] += mb[r] * ma[9] + mb[3 + r] * ma[10] + mb[6 + r] * ma[11];
                    }
                    q[12] += ma[9] * mb[9] + ma[10] * mb[10] + ma[11] * mb[11];
                }
                let q = &mut self.own[a * 12..(a + 1) * 12];
                for r in 0..3 {
                    for s in 0..3 {
                        q[r * 3 + s] += ma[r] * rp[(0, s)] + ma[3 + r] * rp[(1, s)] + ma[6 + r] * rp[(2, s)];
                    }
                    q[9 + r] += rp[(0, r)] * ma[9] + rp[(1, r)] * ma[10] + rp[(2, r)] * ma[11];
                }
            }
        }
    }
}

impl Solver {
    fn new(art: &Articulation, rig: &Rig, opts: &RigOptions) -> Solver {
        let nv = art.n_vertices();
        let n_parts = art.n_parts();
        let in_tree: Vec<bool> = (0..n_parts).map(|k| rig.tree.contains(k)).collect();
        // parts within `rings` steps of each part in the part graph
        let near: Vec<Vec<u32>> = (0..n_parts)
            .map(|k| {
                let mut set = vec![k];
                let mut frontier = vec![k];
                for _ in 0..opts.rings {
                    let mut next = Vec::new();
                    for &p in &frontier {
                        for &q in &art.graph.neighbors[p] {
                            if !set.contains(&q) {
                                set.push(q);
                                next.push(q);
                            }
                        }
                    }
                    frontier = next;
                }
                set.into_iter().filter(|&q| in_tree[q]).map(|q| q as u32).collect()
            })
            .collect();
        let candidates = art.model.labels.iter().map(|&l| near[l as usize].clone()).collect();
        let mut origin = vec![[0.0; 3]; n_parts];
        let mut count = vec![0usize; n_parts];
        for (&l, &u) in art.model.labels.iter().zip(&rig.rest) {
            origin[l as usize] = add(origin[l as usize], u);
            count[l as usize] += 1;
        }
        for (o, &n) in origin.iter_mut().zip(&count) {
            *o = scale(*o, 1.0 / n.max(1) as f64);
        }
        let edges = mesh_edges(&art.faces);
        let neighbours = VertexNeighbours::new(&edges, nv);
        let targets = art.population.clone();
        let bind = &art.shape(opts.bind_pose);
        let edge2 = edges
            .iter()
            .map(|e| {
                let d = sub(bind[e[0] as usize], bind[e[1] as usize]);
                dot(d, d)
            })
            .sum::<f64>()
            / edges.len().max(1) as f64;
        let ns = targets.n_shapes();
        let mut by_vertex = vec![[0.0f32; 3]; nv * ns];
        for (i, shape) in targets.shapes().enumerate() {
            for (v, &p) in shape.as_f32().iter().enumerate() {
                by_vertex[v * ns + i] = p;
            }
        }
        let target_norms =
            (0..nv).map(|v| by_vertex[v * ns..(v + 1) * ns].iter().map(|&p| dot(widen(p), widen(p))).sum()).collect();
        Solver {
            targets,
            ns,
            by_vertex,
            target_norms,
            labels: art.model.labels.clone(),
            near,
            origin,
            bind: opts.bind_pose,
            candidates,
            neighbours,
            influences: opts.influences,
            smoothness: opts.smoothness,
            edge2,
            affine: opts.bone_affine,
        }
    }

    fn sse(&self, rig: &Rig) -> f64 {
        self.targets.shapes().enumerate().map(|(i, target)| pose_sse(rig, i, &target.to_vec())).sum()
    }

    /// One pass of the weight solve (module doc), Jacobi in the smoothness term. `scratch` keeps the working
    /// memory (and the previous pass's weight lists) from one pass to the next: nothing is allocated per vertex.
    fn weights(&self, rig: &mut Rig, scratch: &mut WeightScratch) {
        let nv = rig.rest.len();
        let mut own = std::mem::take(&mut scratch.own);
        own.resize_with(self.near.len(), OwnPart::default);
        for (p, op) in own.iter_mut().enumerate() {
            op.update(&self.near[p], self.origin[p], &rig.bones);
        }
        scratch.own = own;
        let mut new = std::mem::take(&mut scratch.new);
        new.resize_with(nv, Vec::new);
        for (v, out) in new.iter_mut().enumerate() {
            vertex_weights(self, v, rig, scratch, out);
        }
        new.truncate(nv);
        std::mem::swap(&mut rig.weights.influences, &mut new);
        scratch.new = new;
    }

    /// One pass of the bone solve over every pose (module doc); the bind pose's bones stay the identity.
    fn bones(&self, rig: &mut Rig) {
        match rig.scale.as_mut() {
            None => bone_pass(
                &self.by_vertex,
                self.ns,
                Some(self.bind),
                &rig.rest,
                &rig.weights,
                &rig.tree.order,
                &mut rig.bones,
            ),
            Some(sc) => {
                let sums = BoneSums::new(
                    &self.by_vertex,
                    self.ns,
                    &rig.rest,
                    &rig.weights,
                    &rig.tree.order,
                    rig.bones[0].len(),
                );
                for i in 0..self.ns {
                    if i == self.bind {
                        continue;
                    }
                    if self.affine {
                        sums.step_affine(i, &rig.tree.order, &mut rig.bones[i], &sc.axes, &mut sc.factors[i]);
                    } else {
                        sums.step_scaled(i, &rig.tree.order, &mut rig.bones[i], &sc.axes, &mut sc.factors[i]);
                    }
                }
            }
        }
    }

    /// Each bone's scale axes: the principal axes of its vertices' bind positions weighted by w² (the bone
    /// step's own Gram matrix), identity scale in every pose.
    fn start_scale(&self, rig: &mut Rig) {
        let n_parts = rig.bones[0].len();
        let sums = BoneSums::new(&self.by_vertex, self.ns, &rig.rest, &rig.weights, &rig.tree.order, n_parts);
        let axes = sums
            .gram
            .iter()
            .map(|g| {
                let e = Mat3::from_row_slice(g).symmetric_eigen();
                let mut q = e.eigenvectors;
                if q.determinant() < 0.0 {
                    q.column_mut(2).neg_mut();
                }
                if q.iter().all(|x| x.is_finite()) {
                    q
                } else {
                    crate::geometry::IDENTITY
                }
            })
            .collect();
        rig.scale = Some(BoneScale { axes, factors: vec![vec![[1.0; 3]; n_parts]; self.ns], turning: None });
    }
}

/// One pass of the rig's bone step (module doc, *bones*) over the poses of `by_vertex` (vertex-major: vertex v in
/// pose i at `v * ns + i`): pose by pose, bone by bone in `order`, the weighted Procrustes step with the weights
/// and bind positions fixed; pose `skip` (the bind pose of a fit) is left as it is. Used by the fit and by
/// [`super::pose::solve_frames`] (new frames onto a finished rig).
pub(crate) fn bone_pass<T: Target>(
    by_vertex: &[T],
    ns: usize,
    skip: Option<usize>,
    rest: &[Vec3],
    weights: &SkinWeights,
    order: &[usize],
    bones: &mut [Vec<RigidMotion>],
) {
    let sums = BoneSums::new(by_vertex, ns, rest, weights, order, bones[0].len());
    for i in 0..ns {
        if Some(i) == skip {
            continue;
        }
        sums.step(i, order, &mut bones[i]);
    }
}

/// The sums the bone step needs (see [`bone_pass`]): they depend on the weights, the bind positions and the targets,
/// not on the bones, so repeated steps with the weights fixed ([`super::pose::solve_frames`]) compute them once.
pub(crate) struct BoneSums {
    ns: usize,
    /// ū and Σ w² per bone.
    stats: Vec<(Vec3, f64)>,
    pairs: Vec<Vec<(usize, PairSums)>>,
    /// Target sums per bone and pose: [C | Σ w y] row-major (3 x 4), bone k pose i at k ns + i.
    sums: Vec<[f64; 12]>,
    /// Per bone: G = Σ w² (u - ū)(u - ū)ᵀ, row-major (the scaled step's quadratic term).
    gram: Vec<[f64; 9]>,
}

impl BoneSums {
    pub(crate) fn new<T: Target>(
        by_vertex: &[T],
        ns: usize,
        rest: &[Vec3],
        weights: &SkinWeights,
        order: &[usize],
        n_parts: usize,
    ) -> BoneSums {
        let nv = rest.len();
        // supports: (vertex, weight) per part, and ū, Σ w² per part
        let mut support: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n_parts];
        for v in 0..nv {
            for (k, w) in weights.influences(v) {
                support[k].push((v as u32, w));
            }
        }
        let stats: Vec<(Vec3, f64)> = support
            .iter()
            .map(|s| {
                let w2: f64 = s.iter().map(|x| x.1 * x.1).sum();
                let mut m = [0.0; 3];
                for &(v, w) in s {
                    m = add(m, scale(rest[v as usize], w * w));
                }
                (if w2 > 0.0 { scale(m, 1.0 / w2) } else { m }, w2)
            })
            .collect();
        let gram: Vec<[f64; 9]> = support
            .iter()
            .zip(&stats)
            .map(|(s, &(ubar, _))| {
                let mut g = [0.0; 9];
                for &(v, w) in s {
                    let d = sub(rest[v as usize], ubar);
                    for a in 0..3 {
                        for b in 0..3 {
                            g[a * 3 + b] += w * w * d[a] * d[b];
                        }
                    }
                }
                g
            })
            .collect();
        // The step of bone k in pose i needs C = Σ_v w_k r_v (u_v - ū_k)ᵀ and Σ_v w_k r_v with
        // r_v = y_v - Σ_{l≠k} w_l (R_l u_v + t_l) (the target minus the other bones' share), so
        //   C = Σ_v w_k y_v (u_v - ū_k)ᵀ - Σ_{l≠k} (R_l S_kl + t_l s_klᵀ),
        //   Σ_v w_k r_v = Σ_v w_k y_v - Σ_{l≠k} (R_l g_kl + m_kl t_l),
        // with the pose-free sums S_kl = Σ_v w_k w_l u_v (u_v - ū_k)ᵀ, s_kl = Σ_v w_k w_l (u_v - ū_k),
        // g_kl = Σ_v w_k w_l u_v, m_kl = Σ_v w_k w_l over the vertices both bones carry, and the target sums
        // (first terms) once per pose and bone: no pass over the vertices per bone update.
        let mut pair_of = vec![usize::MAX; n_parts * n_parts];
        let mut pairs: Vec<Vec<(usize, PairSums)>> = vec![Vec::new(); n_parts];
        for v in 0..nv {
            let u = rest[v];
            let infl = &weights.influences[v];
            for &(k, wk) in infl {
                let k = k as usize;
                let ubar = stats[k].0;
                let d = sub(u, ubar);
                for &(l, wl) in infl {
                    let l = l as usize;
                    if l == k {
                        continue;
                    }
                    let slot = &mut pair_of[k * n_parts + l];
                    if *slot == usize::MAX {
                        *slot = pairs[k].len();
                        pairs[k].push((l, PairSums::default()));
                    }
                    let ps = &mut pairs[k][*slot].1;
                    let ww = wk * wl;
                    for a in 0..3 {
                        for b in 0..3 {
                            ps.s[a * 3 + b] += ww * u[a] * d[b];
                        }
                        ps.d[a] += ww * d[a];
                        ps.g[a] += ww * u[a];
                    }
                    ps.m += ww;
                }
            }
        }
        // target sums per bone and pose: [C | Σ w y] row-major (3 x 4)
        let mut sums = vec![[0.0; 12]; n_parts * ns];
        for &k in order {
            if stats[k].1 > 0.0 {
                T::bone_target_sums(by_vertex, ns, rest, &support[k], stats[k].0, &mut sums[k * ns..(k + 1) * ns]);
            }
        }
        BoneSums { ns, stats, pairs, sums, gram }
    }

    /// [`BoneSums::step`] with scale channels: bone k's linear part is R Q_k S Qᵀ_k, R and S alternating
    /// (each exact with the other fixed: R the best rotation of C Q S Qᵀ, S's diagonal (Qᵀ Rᵀ C Q)_aa /
    /// (Qᵀ G Q)_aa), starting from the current S, so the step never raises the error.
    pub(crate) fn step_scaled(
        &self,
        i: usize,
        order: &[usize],
        bones: &mut [RigidMotion],
        axes: &[Mat3],
        s: &mut [Vec3],
    ) {
        self.step_linear(i, order, bones, |k, c, _| self.scaled_linear(k, c, &axes[k], &mut s[k]));
    }

    /// One bone step for pose i over the bones of `order`, each bone's linear part A given by
    /// `linear(k, C, its current A)` (C its cross-covariance with the other bones at their current motions), its
    /// translation the best for that A: Σ w r / Σ w² - A ū.
    fn step_linear(
        &self,
        i: usize,
        order: &[usize],
        bones: &mut [RigidMotion],
        mut linear: impl FnMut(usize, &Mat3, &Mat3) -> Mat3,
    ) {
        for &k in order {
            let (ubar, w2) = self.stats[k];
            if w2 <= 0.0 {
                continue;
            }
            let (c, wr) = bone_cross(&self.sums[k * self.ns + i], &self.pairs[k], bones);
            let a = linear(k, &c, &bones[k].rotation);
            bones[k] = RigidMotion { rotation: a, translation: sub(scale(wr, 1.0 / w2), mat_vec(&a, ubar)) };
        }
    }

    /// Bone k's linear part R Q S Qᵀ of [`BoneSums::step_scaled`] from its cross-covariance `c`, updating `f`.
    fn scaled_linear(&self, k: usize, c: &Mat3, q: &Mat3, f: &mut Vec3) -> Mat3 {
        let g = Mat3::from_row_slice(&self.gram[k]);
        let gq = q.transpose() * g * q;
        let mut rot = best_rotation(&(c * stretch(q, *f)));
        for _ in 0..3 {
            let cq = q.transpose() * rot.transpose() * c * q;
            for a in 0..3 {
                // a direction the bone's vertices do not spread along keeps its scale
                if gq[(a, a)] > 1e-9 * gq.trace().max(f64::MIN_POSITIVE) {
                    f[a] = (cq[(a, a)] / gq[(a, a)]).clamp(SCALE_MIN, SCALE_MAX);
                }
            }
            rot = best_rotation(&(c * stretch(q, *f)));
        }
        rot * stretch(q, *f)
    }

    /// [`BoneSums::step`] with affine bones: bone k's linear part is the least-squares A = C (G + ε tr G I)⁻¹
    /// (ε = 1e-6), exact with the other bones fixed, when det A > 0 and every singular value of A is within
    /// [0.5, 2]; else the best, by the bone's own squared error tr(A G Aᵀ) - 2 tr(A Cᵀ), of that A with its
    /// singular values clamped, the scaled step's R Q S Qᵀ (its factors `s` are kept for that alone) and the
    /// bone's current A, so the step never raises the error.
    pub(crate) fn step_affine(
        &self,
        i: usize,
        order: &[usize],
        bones: &mut [RigidMotion],
        axes: &[Mat3],
        s: &mut [Vec3],
    ) {
        let within =
            |a: &Mat3| polar_stretch(a).is_some_and(|(_, f)| f.iter().all(|x| (SCALE_MIN..=SCALE_MAX).contains(x)));
        self.step_linear(i, order, bones, |k, c, current| {
            let g = Mat3::from_row_slice(&self.gram[k]);
            let ridge = AFFINE_RIDGE * g.trace().max(f64::MIN_POSITIVE);
            let least = (g + Mat3::identity() * ridge).try_inverse().map(|gi| c * gi);
            match least {
                Some(a) if within(&a) => a,
                _ => {
                    let cost = |a: &Mat3| (a * g * a.transpose()).trace() - 2.0 * (a * c.transpose()).trace();
                    let scaled = self.scaled_linear(k, c, &axes[k], &mut s[k]);
                    let clamped = least.and_then(|a| clamp_stretch(&a));
                    [Some(scaled), clamped, within(current).then_some(*current)]
                        .into_iter()
                        .flatten()
                        .min_by(|x, y| cost(x).total_cmp(&cost(y)))
                        .unwrap_or(scaled)
                }
            }
        });
    }

    /// One bone step for pose i: every bone of `order` in turn, the others at their current motions in `bones`.
    pub(crate) fn step(&self, i: usize, order: &[usize], bones: &mut [RigidMotion]) {
        for &k in order {
            let (ubar, w2) = self.stats[k];
            if w2 <= 0.0 {
                continue;
            }
            bones[k] = bone_step(&self.sums[k * self.ns + i], &self.pairs[k], bones, ubar, w2);
        }
    }
}

avx2_fn! {
    /// Vertex v's weights of [`Solver::weights`] into `out`. A function of its own, called once per vertex, for
    /// the page: V8 runs a wasm function in its baseline compiler until it is hot and uses the optimised code
    /// from its next call on, so one long call per pass ran mostly unoptimised.
    /// Under `avx2_fn!`: the same bits, with AVX2 where the CPU has it.
    #[inline(never)]
    fn vertex_weights(solver: &Solver, v: usize, rig: &Rig, scratch: &mut WeightScratch, out: &mut Vec<(u32, f64)>) {
        let ns = solver.ns;
        let old = &rig.weights;
        let WeightScratch { qp, cols, h, f, w, start, allowed, order, dense_nbr, own, .. } = scratch;
        {
            let cand = &solver.candidates[v];
            let c = cand.len();
            out.clear();
            if c == 1 {
                out.push((cand[0], 1.0));
                return;
            }
            // H = DᵀD and f = Dᵀy, D's columns (M_k u - M_own u) over the poses and y the target's offset
            // y - M_own u, from the own part's sums over the poses ([`OwnPart`]): only Σ_i ΔR_aᵀ y'_i and
            // Σ_i Δt'_a · y'_i (y'_i = v_i - M_own o) are summed over the vertex's poses
            let op = &own[solver.labels[v] as usize];
            let u = sub(rig.rest[v], op.origin);
            h.clear();
            h.resize(c * c, 0.0);
            f.clear();
            f.resize(c, 0.0);
            cols.clear();
            cols.resize(4 * c, 0.0);
            let stride = 3 + 12 * (c - 1);
            let targets = &solver.by_vertex[v * ns..(v + 1) * ns];
            let sums = &mut cols[4..];
            match c - 1 {
                1 => candidate_sums::<1>(targets, &op.poses, sums),
                2 => candidate_sums::<2>(targets, &op.poses, sums),
                3 => candidate_sums::<3>(targets, &op.poses, sums),
                4 => candidate_sums::<4>(targets, &op.poses, sums),
                5 => candidate_sums::<5>(targets, &op.poses, sums),
                6 => candidate_sums::<6>(targets, &op.poses, sums),
                7 => candidate_sums::<7>(targets, &op.poses, sums),
                8 => candidate_sums::<8>(targets, &op.poses, sums),
                _ => {
                    for (t, pose) in targets.iter().zip(op.poses.chunks_exact(stride)) {
                        let t = widen(*t);
                        let y = [t[0] - pose[0], t[1] - pose[1], t[2] - pose[2]];
                        for (g, m) in sums.chunks_exact_mut(4).zip(pose[3..].chunks_exact(12)) {
                            let mut acc = [g[0], g[1], g[2], g[3]];
                            add_candidate_sums(&mut acc, m, &y);
                            g.copy_from_slice(&acc);
                        }
                    }
                }
            }
            for a in 1..c {
                for b in a..c {
                    let q = &op.pairs[(a * c + b) * 16..(a * c + b + 1) * 16];
                    let ku = [
                        q[0] * u[0] + q[1] * u[1] + q[2] * u[2],
                        q[3] * u[0] + q[4] * u[1] + q[5] * u[2],
                        q[6] * u[0] + q[7] * u[1] + q[8] * u[2],
                    ];
                    let s = dot(u, ku) + u[0] * q[9] + u[1] * q[10] + u[2] * q[11] + q[12] + q[13] * u[0] + q[14] * u[1] + q[15] * u[2];
                    h[a * c + b] = s;
                    h[b * c + a] = s;
                }
                let g = &cols[4 * a..4 * a + 4];
                let q = &op.own[a * 12..(a + 1) * 12];
                let ju = [
                    q[0] * u[0] + q[1] * u[1] + q[2] * u[2],
                    q[3] * u[0] + q[4] * u[1] + q[5] * u[2],
                    q[6] * u[0] + q[7] * u[1] + q[8] * u[2],
                ];
                f[a] = u[0] * g[0] + u[1] * g[1] + u[2] * g[2] + g[3] - dot(u, ju) - (u[0] * q[9] + u[1] * q[10] + u[2] * q[11]);
            }
            let tr: f64 = (1..c).map(|a| h[a * c + a]).sum::<f64>() / c as f64;
            let lambda = solver.smoothness * ns as f64 * solver.edge2 + 1e-12 * tr + 1e-300;
            // neighbours' mean weights on the candidates
            dense_nbr.clear();
            dense_nbr.resize(c, 0.0);
            let nb = solver.neighbours.of(v);
            for &(q, _) in nb {
                for (k, wk) in old.influences(q as usize) {
                    if let Some(a) = cand.iter().position(|&x| x as usize == k) {
                        dense_nbr[a] += wk / nb.len() as f64;
                    }
                }
            }
            for a in 0..c {
                h[a * c + a] += lambda;
                f[a] += lambda * dense_nbr[a];
            }
            w.clear();
            w.resize(c, 0.0);
            // start from the current weights where they are candidates
            let mut any = false;
            for (k, wk) in old.influences(v) {
                if let Some(a) = cand.iter().position(|&x| x as usize == k) {
                    w[a] = wk;
                    any = true;
                }
            }
            let sum: f64 = w.iter().sum();
            if !any || !(sum > 0.0) {
                w.iter_mut().for_each(|x| *x = 0.0);
                w[0] = 1.0;
            } else {
                w.iter_mut().for_each(|x| *x /= sum);
            }
            start.clear();
            start.extend_from_slice(w);
            let objective = |w: &[f64]| -> f64 {
                let mut o = 0.0;
                for a in 0..c {
                    o -= 2.0 * f[a] * w[a];
                    for b in 0..c {
                        o += w[a] * h[a * c + b] * w[b];
                    }
                }
                o
            };
            allowed.clear();
            allowed.resize(c, true);
            qp.solve(h, f, w, allowed);
            let nnz = w.iter().filter(|&&x| x > 0.0).count();
            if nnz > solver.influences {
                order.clear();
                order.extend(0..c);
                order.sort_by(|&a, &b| w[b].total_cmp(&w[a]).then(a.cmp(&b)));
                for &a in &order[solver.influences..] {
                    allowed[a] = false;
                    w[a] = 0.0;
                }
                let s: f64 = w.iter().sum();
                w.iter_mut().for_each(|x| *x /= s);
                qp.solve(h, f, w, allowed);
                // the cap makes this a heuristic: never take a worse point than the current weights
                if start.iter().filter(|&&x| x > 0.0).count() <= solver.influences && objective(start) < objective(w) {
                    w.copy_from_slice(start);
                }
            }
            out.extend(cand.iter().zip(w.iter()).filter(|(_, &x)| x > 0.0).map(|(&k, &x)| (k, x)));
            out.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            let s: f64 = out.iter().map(|x| x.1).sum();
            out.iter_mut().for_each(|x| x.1 /= s);
        }
    }
}

/// One pose's terms of [`vertex_weights`]'s sums over the poses of ΔR_aᵀ y'_i (`g[..3]`) and Δt'_a · y'_i
/// (`g[3]`), with `m` = [ΔR_a | Δt'_a] row-major (3 x 4): the rows of m weighted by y'_i, one 4-lane step.
#[inline(always)]
fn add_candidate_sums(g: &mut [f64; 4], m: &[f64], y: &Vec3) {
    for j in 0..4 {
        g[j] += m[j] * y[0] + m[4 + j] * y[1] + m[8 + j] * y[2];
    }
}

/// [`vertex_weights`]'s sums over the poses for its `N` candidates other than its own part, into `out` (4 each),
/// with y'_i = v_i - M_own o from `targets` and `poses` ([`OwnPart::poses`]): pose by pose as the general case,
/// but the N running sums stay in registers (N known at compile time) instead of a load and a store per pose.
#[inline(always)]
fn candidate_sums<const N: usize>(targets: &[[f32; 3]], poses: &[f64], out: &mut [f64]) {
    let mut acc = [[0.0; 4]; N];
    for (t, pose) in targets.iter().zip(poses.chunks_exact(3 + 12 * N)) {
        let t = widen(*t);
        let y = [t[0] - pose[0], t[1] - pose[1], t[2] - pose[2]];
        for (g, m) in acc.iter_mut().zip(pose[3..].chunks_exact(12)) {
            add_candidate_sums(g, m, &y);
        }
    }
    for (o, g) in out.chunks_exact_mut(4).zip(&acc) {
        o.copy_from_slice(g);
    }
}

/// Pose-free sums of one ordered pair of bones (k, l) sharing vertices, for [`Solver::bones`].
#[derive(Debug, Clone, Copy, Default)]
struct PairSums {
    /// S_kl = Σ w_k w_l u (u - ū_k)ᵀ, row-major.
    s: [f64; 9],
    /// s_kl = Σ w_k w_l (u - ū_k).
    d: Vec3,
    /// g_kl = Σ w_k w_l u.
    g: Vec3,
    /// m_kl = Σ w_k w_l.
    m: f64,
}

/// A target point of the bone step: f32 as a population stores it ([`Solver`]), or f64 (new frames in
/// original units, [`super::pose::solve_frames`]); read as f64 either way.
pub(crate) trait Target: Copy {
    fn widen(self) -> Vec3;
    /// [`bone_target_sums_of`] over targets of this type.
    fn bone_target_sums(
        by_vertex: &[Self],
        ns: usize,
        rest: &[Vec3],
        support: &[(u32, f64)],
        ubar: Vec3,
        out: &mut [[f64; 12]],
    );
}

impl Target for [f32; 3] {
    #[inline(always)]
    fn widen(self) -> Vec3 {
        widen(self)
    }
    fn bone_target_sums(
        by_vertex: &[Self],
        ns: usize,
        rest: &[Vec3],
        support: &[(u32, f64)],
        ubar: Vec3,
        out: &mut [[f64; 12]],
    ) {
        bone_target_sums_f32(by_vertex, ns, rest, support, ubar, out)
    }
}

impl Target for Vec3 {
    #[inline(always)]
    fn widen(self) -> Vec3 {
        self
    }
    fn bone_target_sums(
        by_vertex: &[Self],
        ns: usize,
        rest: &[Vec3],
        support: &[(u32, f64)],
        ubar: Vec3,
        out: &mut [[f64; 12]],
    ) {
        bone_target_sums_f64(by_vertex, ns, rest, support, ubar, out)
    }
}

/// Bone k's target sums of [`Solver::bones`] in every pose: `out[i]` = [Σ_v w y_v (u_v - ū)ᵀ | Σ_v w y_v]
/// row-major (3 x 4) over its support. Row a gains y_a [w (u_v - ū), w] per vertex: one 4-lane step per row.
#[inline(always)]
fn bone_target_sums_of<T: Target>(
    by_vertex: &[T],
    ns: usize,
    rest: &[Vec3],
    support: &[(u32, f64)],
    ubar: Vec3,
    out: &mut [[f64; 12]],
) {
    for &(v, w) in support {
        let v = v as usize;
        let d = scale(sub(rest[v], ubar), w);
        let dw = [d[0], d[1], d[2], w];
        for (o, y) in out.iter_mut().zip(&by_vertex[v * ns..(v + 1) * ns]) {
            let y = y.widen();
            let mut acc = *o;
            for a in 0..3 {
                for b in 0..4 {
                    acc[a * 4 + b] += y[a] * dw[b];
                }
            }
            *o = acc;
        }
    }
}

avx2_fn! {
    /// [`bone_target_sums_of`] on f32 targets (a function of its own for V8's tiering, as [`vertex_weights`]).
    #[inline(never)]
    fn bone_target_sums_f32(by_vertex: &[[f32; 3]], ns: usize, rest: &[Vec3], support: &[(u32, f64)], ubar: Vec3, out: &mut [[f64; 12]]) {
        bone_target_sums_of(by_vertex, ns, rest, support, ubar, out)
    }
}

avx2_fn! {
    /// [`bone_target_sums_of`] on f64 targets.
    #[inline(never)]
    fn bone_target_sums_f64(by_vertex: &[Vec3], ns: usize, rest: &[Vec3], support: &[(u32, f64)], ubar: Vec3, out: &mut [[f64; 12]]) {
        bone_target_sums_of(by_vertex, ns, rest, support, ubar, out)
    }
}

/// The scale factors a bone may take (a clamp: the least squares would otherwise flip or blow up a bone whose
/// vertices barely constrain it).
const SCALE_MIN: f64 = 0.5;
const SCALE_MAX: f64 = 2.0;
/// The ridge of the affine bone step, a fraction of tr G (a bone whose vertices lie in a plane keeps a finite A).
const AFFINE_RIDGE: f64 = 1e-6;

/// The cross-covariance C and Σ w r of [`bone_step`].
fn bone_cross(sums: &[f64; 12], pairs: &[(usize, PairSums)], bones: &[RigidMotion]) -> (Mat3, Vec3) {
    let mut c = [sums[0], sums[1], sums[2], sums[4], sums[5], sums[6], sums[8], sums[9], sums[10]];
    let mut wr = [sums[3], sums[7], sums[11]];
    for (l, ps) in pairs {
        let m = &bones[*l];
        let r = &m.rotation;
        let t = m.translation;
        for a in 0..3 {
            for b in 0..3 {
                c[a * 3 + b] -=
                    r[(a, 0)] * ps.s[b] + r[(a, 1)] * ps.s[3 + b] + r[(a, 2)] * ps.s[6 + b] + t[a] * ps.d[b];
            }
            wr[a] -= r[(a, 0)] * ps.g[0] + r[(a, 1)] * ps.g[1] + r[(a, 2)] * ps.g[2] + t[a] * ps.m;
        }
    }
    (Mat3::from_row_slice(&c), wr)
}

/// One bone's weighted Procrustes step of [`Solver::bones`] for one pose (module doc), from its target sums and
/// the pair sums with the bones it shares vertices with, at their current motions `bones`.
#[inline(never)]
fn bone_step(sums: &[f64; 12], pairs: &[(usize, PairSums)], bones: &[RigidMotion], ubar: Vec3, w2: f64) -> RigidMotion {
    let (cm, wr) = bone_cross(sums, pairs, bones);
    let rot = best_rotation(&cm);
    RigidMotion { rotation: rot, translation: sub(scale(wr, 1.0 / w2), mat_vec(&rot, ubar)) }
}

impl Solver {
    /// One pass of the fixed-joint bone solve over every pose: in tree order, the root's subtree (everything)
    /// takes the rigid motion, and every other bone's subtree the rotation about the bone's joint, that best
    /// carries the subtree's share of every vertex onto what the rest leaves of its target (an exact block
    /// minimisation, so the error never grows). The joint constraint holds before and after.
    fn bones_fixed(&self, rig: &mut Rig) {
        let nv = rig.rest.len();
        let n_parts = rig.bones[0].len();
        // subtree membership of every bone, and the vertices each subtree touches
        let mut in_sub = vec![vec![false; n_parts]; n_parts];
        for &k in rig.tree.order.iter().rev() {
            in_sub[k][k] = true;
            if let Some(p) = rig.tree.parent[k] {
                let child = in_sub[k].clone();
                for (a, b) in in_sub[p].iter_mut().zip(child) {
                    *a |= b;
                }
            }
        }
        let touched: Vec<Vec<u32>> = (0..n_parts)
            .map(|k| {
                (0..nv as u32).filter(|&v| rig.weights.influences(v as usize).any(|(l, _)| in_sub[k][l])).collect()
            })
            .collect();
        let order = rig.tree.order.clone();
        let mut share = vec![[0.0; 3]; nv];
        let mut mass = vec![0.0; nv];
        for i in 0..self.ns {
            if i == self.bind {
                continue;
            }
            let target = self.targets.shape(i).to_vec();
            let mut pred = vec![[0.0; 3]; nv];
            for (v, p) in pred.iter_mut().enumerate() {
                for (k, w) in rig.weights.influences(v) {
                    *p = add(*p, scale(rig.bones[i][k].apply(rig.rest[v]), w));
                }
            }
            for &k in &order {
                let sub_k = &in_sub[k];
                let verts = &touched[k];
                if verts.is_empty() {
                    continue;
                }
                for &v in verts {
                    let v = v as usize;
                    let (mut s, mut m) = ([0.0; 3], 0.0);
                    for (l, w) in rig.weights.influences(v) {
                        if sub_k[l] {
                            s = add(s, scale(rig.bones[i][l].apply(rig.rest[v]), w));
                            m += w;
                        }
                    }
                    share[v] = s;
                    mass[v] = m;
                }
                // r_v = target - (pred - share): what the subtree should produce
                let q: RigidMotion = match rig.tree.parent[k] {
                    None => {
                        // min Σ |r - (Q s + t)|² over rigid (Q, t): plain Procrustes
                        let n = verts.len() as f64;
                        let (mut rb, mut sb) = ([0.0; 3], [0.0; 3]);
                        for &v in verts {
                            let v = v as usize;
                            rb = add(rb, sub(target[v], sub(pred[v], share[v])));
                            sb = add(sb, share[v]);
                        }
                        rb = scale(rb, 1.0 / n);
                        sb = scale(sb, 1.0 / n);
                        let mut cm = Mat3::zeros();
                        for &v in verts {
                            let v = v as usize;
                            let r = sub(sub(target[v], sub(pred[v], share[v])), rb);
                            let s = sub(share[v], sb);
                            for a in 0..3 {
                                for b in 0..3 {
                                    cm[(a, b)] += r[a] * s[b];
                                }
                            }
                        }
                        let rot = best_rotation(&cm);
                        RigidMotion { rotation: rot, translation: sub(rb, mat_vec(&rot, sb)) }
                    }
                    Some(_) => {
                        // rotation Q about the world joint c: s -> Q (s - m c) + m c
                        let c = rig.bones[i][k].apply(rig.joint_points[k]);
                        let mut cm = Mat3::zeros();
                        for &v in verts {
                            let v = v as usize;
                            let r = sub(sub(target[v], sub(pred[v], share[v])), scale(c, mass[v]));
                            let s = sub(share[v], scale(c, mass[v]));
                            for a in 0..3 {
                                for b in 0..3 {
                                    cm[(a, b)] += r[a] * s[b];
                                }
                            }
                        }
                        let rot = best_rotation(&cm);
                        RigidMotion { rotation: rot, translation: sub(c, mat_vec(&rot, c)) }
                    }
                };
                for l in 0..n_parts {
                    if sub_k[l] {
                        rig.bones[i][l] = q.then_after(&rig.bones[i][l]);
                    }
                }
                for &v in verts {
                    let v = v as usize;
                    let mut s = [0.0; 3];
                    for (l, w) in rig.weights.influences(v) {
                        if sub_k[l] {
                            s = add(s, scale(rig.bones[i][l].apply(rig.rest[v]), w));
                        }
                    }
                    pred[v] = add(sub(pred[v], share[v]), s);
                }
            }
        }
    }
}

impl Solver {
    /// The bind positions that the current weights and bones carry best onto every pose: per vertex
    /// (Σ_i L_iᵀ L_i) u = Σ_i L_iᵀ (v_i - c_i), with L_i, c_i the blended linear part and translation. Returns the
    /// squared error over all poses at the new bind positions (what [`Solver::sse`] gives, from the same sums).
    ///
    /// With L_i = Σ_k w_k R_k^i and c_i = Σ_l w_l t_l^i these sums are, per vertex, Σ_kl w_k w_l P_kl,
    /// Σ_k w_k z_k - Σ_kl w_k w_l q_kl and Σ_i |v_i - c_i|² = Σ_i |v_i|² - 2 Σ_l w_l s_l + Σ_kl w_k w_l τ_kl, from
    /// per pair of bones P_kl = Σ_i R_kᵀ R_l, q_kl = Σ_i R_kᵀ t_l, τ_kl = Σ_i t_k · t_l and per vertex and bone
    /// z_k = Σ_i R_kᵀ v_i, s_k = Σ_i t_k · v_i: one pass over the poses per influence, none per pair.
    fn rest(&self, rig: &mut Rig) -> f64 {
        let ns = self.ns;
        let n_parts = rig.bones[0].len();
        // bone-major motions: [R | t] row-major (3 x 4) of bone k in pose i at k ns + i
        let mut motions = vec![[0.0; 12]; n_parts * ns];
        for (i, pose) in rig.bones.iter().enumerate() {
            for (k, m) in pose.iter().enumerate() {
                let x = &mut motions[k * ns + i];
                for r in 0..3 {
                    for q in 0..3 {
                        x[r * 4 + q] = m.rotation[(r, q)];
                    }
                    x[r * 4 + 3] = m.translation[r];
                }
            }
        }
        // per ordered pair (k, l): P_kl row-major (9), q_kl (3), τ_kl
        let mut pairs = vec![[0.0; 13]; n_parts * n_parts];
        for k in 0..n_parts {
            for l in 0..n_parts {
                let out = &mut pairs[k * n_parts + l];
                for (a, b) in motions[k * ns..(k + 1) * ns].iter().zip(&motions[l * ns..(l + 1) * ns]) {
                    for r in 0..3 {
                        for q in 0..3 {
                            out[r * 3 + q] += a[r] * b[q] + a[4 + r] * b[4 + q] + a[8 + r] * b[8 + q];
                        }
                        out[9 + r] += a[r] * b[3] + a[4 + r] * b[7] + a[8 + r] * b[11];
                    }
                    out[12] += a[3] * b[3] + a[7] * b[7] + a[11] * b[11];
                }
            }
        }
        let mut sse = 0.0;
        for v in 0..rig.rest.len() {
            let (u, e) = vertex_rest(self, v, rig, &motions, &pairs, n_parts);
            if let Some(u) = u {
                rig.rest[v] = u;
            }
            sse += e;
        }
        sse
    }
}

avx2_fn! {
    /// Vertex v's bind position of [`Solver::rest`] (None when its system is singular: the position is kept), and
    /// the vertex's squared error over the poses at the position it ends with: with A = Σ_i L_iᵀ L_i,
    /// b = Σ_i L_iᵀ y_i, y_i = v_i - c_i, it is uᵀA u - 2 bᵀu + Σ_i |y_i|² (a function of its own for V8's tiering,
    /// as [`vertex_weights`]).
    /// Under `avx2_fn!`: the same bits, with AVX2 where the CPU has it.
    #[inline(never)]
    fn vertex_rest(solver: &Solver, v: usize, rig: &Rig, motions: &[[f64; 12]], pairs: &[[f64; 13]], n_parts: usize) -> (Option<Vec3>, f64) {
        let ns = solver.ns;
        let targets = &solver.by_vertex[v * ns..(v + 1) * ns];
        let infl = &rig.weights.influences[v];
        let mut a = [0.0; 9];
        let mut b = [0.0; 3];
        let mut yy = solver.target_norms[v];
        let poses = |k: u32| &motions[k as usize * ns..(k as usize + 1) * ns];
        for two in infl.chunks(2) {
            // [z_k, s_k] with z_k = Σ_i R_kᵀ v_i, s_k = Σ_i t_k · v_i, for two influences in one pass over the
            // poses (twice the independent sums in flight; each still summed in pose order)
            let mut zs = [[0.0; 4]; 2];
            match *two {
                [(k, _), (l, _)] => {
                    for ((m, n), t) in poses(k).iter().zip(poses(l)).zip(targets) {
                        let t = widen(*t);
                        add_influence_sums(&mut zs[0], m, &t);
                        add_influence_sums(&mut zs[1], n, &t);
                    }
                }
                [(k, _)] => {
                    for (m, t) in poses(k).iter().zip(targets) {
                        add_influence_sums(&mut zs[0], m, &widen(*t));
                    }
                }
                _ => {}
            }
            for (&(k, wk), z) in two.iter().zip(&zs) {
                let k = k as usize;
                b[0] += wk * z[0];
                b[1] += wk * z[1];
                b[2] += wk * z[2];
                yy -= 2.0 * wk * z[3];
                for &(l, wl) in infl {
                    let p = &pairs[k * n_parts + l as usize];
                    let ww = wk * wl;
                    for (x, y) in a.iter_mut().zip(&p[..9]) {
                        *x += ww * y;
                    }
                    b[0] -= ww * p[9];
                    b[1] -= ww * p[10];
                    b[2] -= ww * p[11];
                    yy += ww * p[12];
                }
            }
        }
        let error = |u: Vec3| {
            let au = [
                a[0] * u[0] + a[1] * u[1] + a[2] * u[2],
                a[3] * u[0] + a[4] * u[1] + a[5] * u[2],
                a[6] * u[0] + a[7] * u[1] + a[8] * u[2],
            ];
            (dot(u, au) - 2.0 * dot(b, u) + yy).max(0.0)
        };
        let (mut m, mut x) = (a, b);
        let tr = a[0] + a[4] + a[8];
        if solve_dense(&mut m, &mut x, 3) && x.iter().all(|x| x.is_finite()) && tr > 0.0 {
            (Some(x), error(x))
        } else {
            (None, error(rig.rest[v]))
        }
    }
}

/// One pose's terms of [`vertex_rest`]'s sums z_k = Σ_i R_kᵀ v_i (`z[..3]`) and s_k = Σ_i t_k · v_i (`z[3]`), with
/// `m` = [R_k | t_k] row-major (3 x 4) in pose i and `t` = v_i: the rows of m weighted by v_i, one 4-lane step.
#[inline(always)]
fn add_influence_sums(z: &mut [f64; 4], m: &[f64; 12], t: &Vec3) {
    for j in 0..4 {
        z[j] += m[j] * t[0] + m[4 + j] * t[1] + m[8 + j] * t[2];
    }
}

/// Squared error of pose i (a function of its own for V8's tiering, as [`vertex_weights`]).
#[inline(never)]
fn pose_sse(rig: &Rig, i: usize, target: &[Vec3]) -> f64 {
    let mut s = 0.0;
    for (v, q) in target.iter().enumerate() {
        let mut x = [0.0; 3];
        for (k, w) in rig.weights.influences(v) {
            x = add(x, scale(rig.bones[i][k].apply(rig.rest[v]), w));
        }
        let d = sub(x, *q);
        s += dot(d, d);
    }
    s
}

/// Joint points where parent and child bones move most alike (module doc), from the current bones.
fn fit_joint_points(rig: &mut Rig) {
    let ns = rig.bones.len();
    for &k in &rig.tree.order {
        let Some(p) = rig.tree.parent[k] else { continue };
        let p0 = rig.joint_points[k];
        // Σ_i |ΔR_i x + Δt_i|² + μ |x - p0|²: (Σ ΔRᵀΔR + μ I) x = -Σ ΔRᵀ Δt + μ p0
        let (mut a, mut b) =
            super::joints::joint_normal_equations(rig.bones.iter().take(ns).map(|pose| (&pose[k], &pose[p])));
        let mut tr = 0.0;
        for r in 0..3 {
            tr += a[r * 3 + r];
        }
        let mu = 1e-3 * tr / 3.0 + 1e-12;
        for r in 0..3 {
            a[r * 3 + r] += mu;
            b[r] += mu * p0[r];
        }
        if solve_dense(&mut a, &mut b, 3) {
            rig.joint_points[k] = b;
        }
    }
}

/// Makes the bones satisfy the joint constraint (child translation from its parent), tree order.
fn constrain(rig: &mut Rig) {
    for i in 0..rig.bones.len() {
        for &k in &rig.tree.order {
            if let Some(p) = rig.tree.parent[k] {
                let pk = rig.joint_points[k];
                let c = rig.bones[i][p].apply(pk);
                let r = rig.bones[i][k].rotation;
                rig.bones[i][k].translation = sub(c, mat_vec(&r, pk));
            }
        }
    }
}

/// Whether an alternation that took the squared error from `before` to `after` lowered it by less than `tol`
/// of it ([`RigOptions::tol`]; never with tol = 0).
fn converged(before: f64, after: f64, tol: f64) -> bool {
    tol > 0.0 && before - after <= tol * after
}

fn fit(rig: &mut Rig, art: &Articulation, opts: &RigOptions) {
    let solver = Solver::new(art, rig, opts);
    let mut scratch = WeightScratch::default();
    // the MFA motions map the rigid reconstruction; the bind shape itself differs by its residual
    solver.bones(rig);
    rig.trace.push(solver.sse(rig));
    if (opts.bone_scale || opts.bone_affine) && opts.joints == Joints::Free {
        solver.start_scale(rig);
    }
    let free_iters = if opts.joints == Joints::Fixed { opts.iterations / 2 } else { opts.iterations };
    let mut done = 0;
    while done < free_iters {
        solver.weights(rig, &mut scratch);
        solver.bones(rig);
        let sse = if opts.fit_rest { solver.rest(rig) } else { solver.sse(rig) };
        done += 1;
        let (before, after) = (rig.trace[rig.trace.len() - 1], sse);
        rig.trace.push(after);
        if converged(before, after, opts.tol) {
            break;
        }
    }
    if opts.joints == Joints::Fixed {
        fit_joint_points(rig);
        constrain(rig);
        rig.trace.push(solver.sse(rig));
        for _ in done..opts.iterations.max(done + 1) {
            let before = rig.trace[rig.trace.len() - 1];
            solver.bones_fixed(rig);
            solver.bones_fixed(rig);
            rig.trace.push(solver.sse(rig));
            solver.weights(rig, &mut scratch);
            let after = if opts.fit_rest { solver.rest(rig) } else { solver.sse(rig) };
            rig.trace.push(after);
            if converged(before, after, opts.tol) {
                break;
            }
        }
        solver.bones_fixed(rig);
        rig.trace.push(solver.sse(rig));
    }
    if opts.bone_affine {
        split_affine(rig);
    }
}

/// A with its stretch factors clamped to [0.5, 2] (A = R Q S Qᵀ -> R Q clamp(S) Qᵀ); None when det A <= 0.
fn clamp_stretch(a: &Mat3) -> Option<Mat3> {
    let (q, f) = polar_stretch(a)?;
    let r = a * stretch(&q, f.map(|x| 1.0 / x));
    Some(r * stretch(&q, f.map(|x| x.clamp(SCALE_MIN, SCALE_MAX))))
}

/// Affine bones: every bone's A split as R Q S Qᵀ ([`polar_stretch`]) into the scale axes and factors the .glb
/// plays ([`BoneScale::turning`]). The bone step keeps det A > 0, so every A splits.
fn split_affine(rig: &mut Rig) {
    let Some(sc) = rig.scale.as_mut() else { return };
    let mut turning = Vec::with_capacity(rig.bones.len());
    for (i, bones) in rig.bones.iter().enumerate() {
        let mut axes = Vec::with_capacity(bones.len());
        for (k, m) in bones.iter().enumerate() {
            let (q, f) = polar_stretch(&m.rotation).unwrap_or((sc.axes[k], sc.factors[i][k]));
            sc.factors[i][k] = f;
            axes.push(q);
        }
        turning.push(axes);
    }
    sc.turning = Some(turning);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simplex_qp_matches_brute_force() {
        // min |A w - y|² on the simplex for a few random small problems, against a fine grid (c = 3)
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for _ in 0..50 {
            let rows = 6;
            let a: Vec<f64> = (0..rows * 3).map(|_| rnd()).collect();
            let y: Vec<f64> = (0..rows).map(|_| rnd()).collect();
            let obj = |w: &[f64]| -> f64 {
                (0..rows).map(|r| ((0..3).map(|c| a[r * 3 + c] * w[c]).sum::<f64>() - y[r]).powi(2)).sum()
            };
            let mut h = vec![0.0; 9];
            let mut f = vec![0.0; 3];
            for i in 0..3 {
                for j in 0..3 {
                    h[i * 3 + j] =
                        (0..rows).map(|r| a[r * 3 + i] * a[r * 3 + j]).sum::<f64>() + if i == j { 1e-9 } else { 0.0 };
                }
                f[i] = (0..rows).map(|r| a[r * 3 + i] * y[r]).sum();
            }
            let mut w = vec![1.0, 0.0, 0.0];
            simplex_qp(&h, &f, &mut w, &[true; 3]);
            assert!(w.iter().all(|&x| x >= 0.0) && (w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{w:?}");
            let got = obj(&w);
            let n = 200;
            let mut best = f64::INFINITY;
            for p in 0..=n {
                for q in 0..=n - p {
                    let g = [p as f64 / n as f64, q as f64 / n as f64, (n - p - q) as f64 / n as f64];
                    best = best.min(obj(&g));
                }
            }
            assert!(got <= best + 1e-9, "qp {got} > grid {best}");
        }
    }

    /// One bone, exact data y = R Q S Qᵀ u + t in pose 1 (pose 0 the identity): repeated scaled steps from S = 1
    /// never raise the error and recover S and the map; the rigid step cannot fit it.
    #[test]
    fn scaled_bone_step_recovers_a_stretch() {
        let rest = box_points(11);
        let q = crate::geometry::rotation::axis_angle([0.0, 0.0, 1.0], 0.3);
        let r = crate::geometry::rotation::axis_angle([1.0, 2.0, 0.5], 0.9);
        let f = [1.3, 0.8, 1.1];
        let a = r * stretch(&q, f);
        let t = [0.2, -0.1, 0.4];
        let ns = 2;
        let by_vertex = moved(&rest, &a, t);
        let weights = SkinWeights { influences: vec![vec![(0, 1.0)]; rest.len()] };
        let sums = BoneSums::new(&by_vertex, ns, &rest, &weights, &[0], 1);
        let err = |m: &RigidMotion| -> f64 {
            rest.iter()
                .map(|&u| {
                    let d = sub(m.apply(u), add(mat_vec(&a, u), t));
                    dot(d, d)
                })
                .sum()
        };
        let mut rigid = vec![RigidMotion::IDENTITY];
        sums.step(1, &[0], &mut rigid);
        let mut bones = vec![RigidMotion::IDENTITY];
        let mut s = vec![[1.0; 3]];
        let mut last = f64::INFINITY;
        for _ in 0..30 {
            sums.step_scaled(1, &[0], &mut bones, &[q], &mut s);
            let e = err(&bones[0]);
            assert!(e <= last * (1.0 + 1e-12) + 1e-18, "the error rose: {last} -> {e}");
            last = e;
        }
        assert!(err(&rigid[0]) > 1.0, "the rigid step fits a stretch: {}", err(&rigid[0]));
        assert!(last < 1e-16, "{last}");
        for d in 0..3 {
            assert!((s[0][d] - f[d]).abs() < 1e-6, "{:?} vs {f:?}", s[0]);
        }
        // a scale past the clamp stays at the clamp
        let mut bones = vec![RigidMotion::IDENTITY];
        let far = [f[0] * 3.0, f[1], f[2]];
        let a3 = r * stretch(&q, far);
        let by3 = moved(&rest, &a3, t);
        let sums3 = BoneSums::new(&by3, ns, &rest, &weights, &[0], 1);
        let mut s3 = vec![[1.0; 3]];
        for _ in 0..10 {
            sums3.step_scaled(1, &[0], &mut bones, &[q], &mut s3);
        }
        assert_eq!(s3[0][0], SCALE_MAX);
    }

    /// 200 pseudo-random bind positions in a 4 x 2 x 1 box (a bone's vertices spread unevenly along its axes).
    fn box_points(mut seed: u64) -> Vec<Vec3> {
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        (0..200).map(|_| [2.0 * rnd(), rnd(), 0.5 * rnd()]).collect()
    }

    /// Points, a bone's rest positions, and their image under x -> a x + t (pose 1; pose 0 the rest).
    fn moved(rest: &[Vec3], a: &Mat3, t: Vec3) -> Vec<Vec3> {
        rest.iter().flat_map(|&u| [u, add(mat_vec(a, u), t)]).collect()
    }

    #[test]
    fn polar_stretch_splits_a_rotation_after_a_stretch() {
        let q = crate::geometry::rotation::axis_angle([1.0, -1.0, 0.5], 0.7);
        let r = crate::geometry::rotation::axis_angle([0.2, 1.0, 0.1], -1.1);
        let a = r * stretch(&q, [1.7, 0.6, 1.2]);
        let (q2, f2) = polar_stretch(&a).expect("det > 0");
        assert!((q2.determinant() - 1.0).abs() < 1e-12);
        let p = stretch(&q2, f2);
        let r2 = a * p.try_inverse().unwrap();
        assert!((r2.transpose() * r2 - Mat3::identity()).norm() < 1e-12, "the rest of A is a rotation");
        assert!((r2 * p - a).norm() < 1e-12);
        let mut sorted = f2;
        sorted.sort_by(f64::total_cmp);
        assert!((sorted[0] - 0.6).abs() < 1e-12 && (sorted[2] - 1.7).abs() < 1e-12, "{f2:?}");
        // a reflection is no stretch
        assert!(polar_stretch(&(a * Mat3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, -1.0)))).is_none());
    }

    #[test]
    fn affine_bone_step_recovers_a_shear_and_never_raises_the_error() {
        let rest = box_points(5);
        let weights = SkinWeights { influences: vec![vec![(0, 1.0)]; rest.len()] };
        let q = crate::geometry::rotation::axis_angle([0.0, 0.0, 1.0], 0.3);
        let r = crate::geometry::rotation::axis_angle([1.0, 2.0, 0.5], 0.9);
        let t = [0.2, -0.1, 0.4];
        // a shear: no rotation after a stretch along fixed axes gives it, one affine step does
        let shear = Mat3::new(1.0, 0.4, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let a = r * shear;
        let by_vertex = moved(&rest, &a, t);
        let sums = BoneSums::new(&by_vertex, 2, &rest, &weights, &[0], 1);
        let err = |m: &RigidMotion, a: &Mat3| -> f64 {
            rest.iter()
                .map(|&u| {
                    let d = sub(m.apply(u), add(mat_vec(a, u), t));
                    dot(d, d)
                })
                .sum()
        };
        let mut scaled = vec![RigidMotion::IDENTITY];
        let mut s = vec![[1.0; 3]];
        for _ in 0..30 {
            sums.step_scaled(1, &[0], &mut scaled, &[q], &mut s);
        }
        let mut bones = vec![RigidMotion::IDENTITY];
        let mut s = vec![[1.0; 3]];
        sums.step_affine(1, &[0], &mut bones, &[q], &mut s);
        assert!(err(&scaled[0], &a) > 0.1, "a stretch along fixed axes fits the shear: {}", err(&scaled[0], &a));
        // exact but for the ridge (1e-6 of tr G)
        assert!(err(&bones[0], &a) < 1e-6, "{}", err(&bones[0], &a));
        // a stretch of 3 along one axis is past [0.5, 2]: the step takes the best allowed A, never a worse one
        let far = r * stretch(&q, [3.0, 1.0, 0.9]);
        let by_far = moved(&rest, &far, t);
        let sums = BoneSums::new(&by_far, 2, &rest, &weights, &[0], 1);
        let mut bones = vec![RigidMotion::IDENTITY];
        let mut s = vec![[1.0; 3]];
        let mut last = err(&bones[0], &far);
        for _ in 0..10 {
            sums.step_affine(1, &[0], &mut bones, &[q], &mut s);
            let e = err(&bones[0], &far);
            assert!(e <= last * (1.0 + 1e-12) + 1e-18, "the error rose: {last} -> {e}");
            last = e;
            let (_, f) = polar_stretch(&bones[0].rotation).expect("det > 0");
            assert!(f.iter().all(|x| (SCALE_MIN - 1e-12..=SCALE_MAX + 1e-12).contains(x)), "{f:?}");
        }
        // the stretch held at 2 where 3 was asked for, and a fit far better than the start's
        let (_, f) = polar_stretch(&bones[0].rotation).unwrap();
        assert!(f.iter().any(|x| (x - SCALE_MAX).abs() < 1e-6), "{f:?}");
        // and at least as good as the same motion with its stretch of 3 cut to 2
        let cut = RigidMotion { rotation: r * stretch(&q, [SCALE_MAX, 1.0, 0.9]), translation: t };
        assert!(last <= err(&cut, &far) * (1.0 + 1e-9), "{last} against {}", err(&cut, &far));
    }
}
