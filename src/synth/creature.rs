//! The presets as data: a kinematic tree of named parts with joint limits, and the tubes that make the body.
//!
//! Design units (before the generator rescales so the rest pose's longest side is 1): x forward, y left, z up.
//! Every body is one "spine" tube (a swept ellipse along a Catmull-Rom centre line in the x-z plane, closed
//! by a rounded pole at both ends) plus "limbs": tubes that start from a rectangular hole cut into the spine's
//! wall and end in a rounded pole.

use super::Preset;
use crate::geometry::Vec3;

/// Joint limits of one part relative to its parent: the local rotation is the product, in this order, of
/// rotations about `axis` (rest-pose world frame) by an angle drawn uniformly in `[lo, hi] * max_angle`.
#[derive(Debug, Clone)]
pub struct JointDef {
    pub axes: Vec<(Vec3, f64, f64)>,
}

#[derive(Debug, Clone)]
pub struct SpineDef {
    /// Centre-line knots (x-z plane).
    pub points: Vec<Vec3>,
    /// (lateral, vertical) half-widths at the knots.
    pub radii: Vec<[f64; 2]>,
    /// Parts along the spine, from its start (t = 0) to its end.
    pub parts: Vec<usize>,
    /// Spline parameter of the boundary between `parts[k]` and `parts[k + 1]`.
    pub cuts_t: Vec<f64>,
    /// Fewest vertices around the spine (even).
    pub min_around: usize,
}

#[derive(Debug, Clone)]
pub struct LimbDef {
    /// Spine parameter and angle (radians; 0 = +y side, -pi/2 = underneath) of the hole the limb grows from.
    pub attach_t: f64,
    pub attach_phi: f64,
    /// Mirror image (y -> -y) of an earlier limb: its hole is the mirror of that limb's hole.
    pub mirror_of: Option<usize>,
    /// Rest direction of the (straight) limb axis.
    pub dir: Vec3,
    /// Length of the axis, from the hip to the rounded tip.
    pub length: f64,
    /// Radius knots (u along the axis, radius).
    pub radii: Vec<(f64, f64)>,
    /// Parts along the limb; the first hangs from `attached_to` at the hip.
    pub parts: Vec<usize>,
    /// u of the boundary between `parts[k]` and `parts[k + 1]`.
    pub cuts_u: Vec<f64>,
    /// The spine part the limb grows from.
    pub attached_to: usize,
}

#[derive(Debug, Clone)]
pub struct Design {
    pub names: Vec<String>,
    pub parent: Vec<Option<usize>>,
    /// None for the root.
    pub joints: Vec<Option<JointDef>>,
    pub spine: SpineDef,
    pub limbs: Vec<LimbDef>,
}

impl Design {
    pub fn root(&self) -> usize {
        self.parent.iter().position(|p| p.is_none()).expect("a design has a root")
    }

    /// Parts ordered so that every parent comes before its children.
    pub fn topological_order(&self) -> Vec<usize> {
        let n = self.names.len();
        let mut order = vec![self.root()];
        let mut k = 0;
        while k < order.len() {
            let p = order[k];
            for c in 0..n {
                if self.parent[c] == Some(p) {
                    order.push(c);
                }
            }
            k += 1;
        }
        debug_assert_eq!(order.len(), n, "every part is reachable from the root");
        order
    }
}

const X: Vec3 = [1.0, 0.0, 0.0];
const Y: Vec3 = [0.0, 1.0, 0.0];
const Z: Vec3 = [0.0, 0.0, 1.0];

fn j(axes: &[(Vec3, f64, f64)]) -> Option<JointDef> {
    Some(JointDef { axes: axes.to_vec() })
}

pub fn design(preset: Preset) -> Design {
    match preset {
        Preset::Quadruped => quadruped(),
        Preset::Arm => arm(),
        Preset::Snake => snake(),
        Preset::Blob => blob(),
    }
}

fn quadruped() -> Design {
    let mut names: Vec<String> =
        ["trunk", "neck", "head", "tail1", "tail2", "tail3"].iter().map(|s| s.to_string()).collect();
    let mut parent = vec![None, Some(0), Some(1), Some(0), Some(3), Some(4)];
    let mut joints = vec![
        None,
        j(&[(Y, -0.6, 0.6), (Z, -0.8, 0.8), (X, -0.2, 0.2)]),
        j(&[(Y, -0.7, 0.7), (Z, -0.5, 0.5)]),
        j(&[(Z, -1.0, 1.0), (Y, -0.5, 0.5)]),
        j(&[(Z, -1.0, 1.0), (Y, -0.5, 0.5)]),
        j(&[(Z, -1.0, 1.0), (Y, -0.5, 0.5)]),
    ];
    let spine = SpineDef {
        points: vec![
            [-1.05, 0.0, -0.02],
            [-0.85, 0.0, 0.02],
            [-0.64, 0.0, 0.06],
            [-0.45, 0.0, 0.06],
            [0.0, 0.0, 0.07],
            [0.40, 0.0, 0.09],
            [0.56, 0.0, 0.17],
            [0.68, 0.0, 0.36],
            [0.80, 0.0, 0.42],
            [0.98, 0.0, 0.37],
        ],
        radii: vec![
            [0.02, 0.02],
            [0.03, 0.03],
            [0.045, 0.045],
            [0.15, 0.14],
            [0.17, 0.16],
            [0.16, 0.17],
            [0.09, 0.10],
            [0.07, 0.07],
            [0.09, 0.09],
            [0.05, 0.05],
        ],
        parts: vec![5, 4, 3, 0, 1, 2],
        cuts_t: vec![0.8, 1.6, 2.35, 6.0, 7.0],
        min_around: 16,
    };
    // Legs hinge about the lateral axis only, so a left and a right leg with tied angles are one rigid body.
    let mut limbs = Vec::new();
    for (k, (prefix, t, knee)) in [("front", 4.75, (Y, -1.2, 0.1)), ("hind", 3.4, (Y, -0.1, 1.2))].iter().enumerate() {
        for (side_k, side) in ["left", "right"].iter().enumerate() {
            let first = names.len();
            for seg in ["upper", "lower", "foot"] {
                names.push(format!("{prefix}_{side}_{seg}"));
            }
            parent.extend([Some(0), Some(first), Some(first + 1)]);
            joints.extend([j(&[(Y, -0.9, 0.9)]), j(&[*knee]), j(&[(Y, -0.7, 0.7)])]);
            limbs.push(LimbDef {
                attach_t: *t,
                attach_phi: -50f64.to_radians(),
                mirror_of: if side_k == 1 { Some(2 * k) } else { None },
                dir: [0.0, 0.0, -1.0],
                length: 0.48,
                radii: vec![(0.0, 0.055), (0.2, 0.042), (0.38, 0.032), (0.48, 0.036)],
                parts: vec![first, first + 1, first + 2],
                cuts_u: vec![0.2, 0.38],
                attached_to: 0,
            });
        }
    }
    Design { names, parent, joints, spine, limbs }
}

fn arm() -> Design {
    let names = vec!["base".to_string(), "upper_arm".to_string(), "forearm".to_string()];
    let parent = vec![None, Some(0), Some(1)];
    let joints = vec![None, j(&[(Z, -1.0, 1.0), (Y, -0.6, 0.6), (X, -0.5, 0.5)]), j(&[(Z, 0.0, 1.5)])];
    let xs = [0.0, 0.25, 0.45, 0.65, 0.85, 1.05, 1.15];
    let rs = [0.11, 0.10, 0.085, 0.07, 0.06, 0.05, 0.055];
    let spine = SpineDef {
        points: xs.iter().map(|&x| [x, 0.0, 0.0]).collect(),
        radii: rs.iter().map(|&r| [r, r * 0.95]).collect(),
        parts: vec![0, 1, 2],
        cuts_t: vec![1.0, 3.0],
        min_around: 8,
    };
    Design { names, parent, joints, spine, limbs: Vec::new() }
}

/// Segments of the snake; the root is the fourth from the tail.
pub const SNAKE_SEGMENTS: usize = 8;
const SNAKE_ROOT: usize = 3;

fn snake() -> Design {
    let n = SNAKE_SEGMENTS;
    let names = (1..=n).map(|k| format!("seg{k}")).collect();
    let parent = (0..n)
        .map(|k| match k.cmp(&SNAKE_ROOT) {
            std::cmp::Ordering::Less => Some(k + 1),
            std::cmp::Ordering::Equal => None,
            std::cmp::Ordering::Greater => Some(k - 1),
        })
        .collect();
    let joints = (0..n)
        .map(|k| if k == SNAKE_ROOT { None } else { j(&[(Z, -1.0, 1.0), (Y, -0.35, 0.35), (X, -0.15, 0.15)]) })
        .collect();
    let xs = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.52, 1.62];
    let rs = [0.012, 0.028, 0.042, 0.05, 0.053, 0.053, 0.05, 0.045, 0.062, 0.04];
    let spine = SpineDef {
        points: xs.iter().enumerate().map(|(k, &x)| [x, 0.0, 0.01 * (k as f64 * 0.9).sin()]).collect(),
        radii: rs.iter().map(|&r| [r, r * 0.85]).collect(),
        parts: (0..n).collect(),
        cuts_t: (1..n).map(|k| k as f64).collect(),
        min_around: 8,
    };
    Design { names, parent, joints, spine, limbs: Vec::new() }
}

fn blob() -> Design {
    let spine = SpineDef {
        points: vec![[0.0, 0.0, 0.0], [0.35, 0.0, 0.03], [0.7, 0.0, 0.03], [1.05, 0.0, 0.0]],
        radii: vec![[0.24, 0.21], [0.28, 0.24], [0.26, 0.23], [0.22, 0.2]],
        parts: vec![0],
        cuts_t: Vec::new(),
        min_around: 8,
    };
    Design { names: vec!["blob".to_string()], parent: vec![None], joints: vec![None], spine, limbs: Vec::new() }
}
