//! The presets as data: a kinematic tree of named parts with joint limits, and the tubes that make the body.
//!
//! Design units (before the generator rescales so the rest pose's longest side is 1): x forward, y left, z up.
//! Every body is one "spine" tube (a swept ellipse along a Catmull-Rom centre line in the x-z plane, closed
//! by a rounded pole at both ends) plus "limbs": tubes that start from a rectangular hole cut into the spine's
//! wall and end in a rounded pole.

use super::Preset;
use crate::geometry::{cross, norm, scale, Vec3};

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
        Preset::Spider => spider(),
        Preset::Giraffe => giraffe(),
        Preset::Hand => hand(),
    }
}

fn unit(v: Vec3) -> Vec3 {
    scale(v, 1.0 / norm(v))
}

/// Horizontal axis perpendicular to a limb's direction (`Z x dir`): turning the limb about it by a positive
/// angle lowers its tip, whichever way the limb points (so mirrored limbs get mirrored joints).
fn lift_axis(dir: Vec3) -> Vec3 {
    unit(cross(Z, dir))
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

/// Legs per side of the spider.
pub const SPIDER_LEGS_PER_SIDE: usize = 4;

/// Thin limbs on a small body: `cephalothorax` (root) and `abdomen` along the spine, and eight legs of two
/// parts (`leg1_left_femur`, `leg1_left_tibia`, ... `leg4_right_tibia`; leg 1 points forward, leg 4 back),
/// each about 1.1 long and 0.02 thick against a body 0.95 long: 18 parts. Neighbouring legs of a side leave
/// the body at alternating heights (the side and the underside), so their sockets stay apart at coarse
/// resolutions. Hips swing about the vertical and lift about the leg's own horizontal axis; knees bend down.
fn spider() -> Design {
    let mut names: Vec<String> = vec!["cephalothorax".into(), "abdomen".into()];
    let mut parent = vec![None, Some(0)];
    let mut joints = vec![None, j(&[(Y, -0.4, 0.4), (Z, -0.4, 0.4)])];
    let spine = SpineDef {
        points: vec![
            [-0.62, 0.0, 0.10],
            [-0.56, 0.0, 0.12],
            [-0.42, 0.0, 0.14],
            [-0.27, 0.0, 0.12],
            [-0.18, 0.0, 0.07],
            [-0.10, 0.0, 0.05],
            [0.00, 0.0, 0.05],
            [0.11, 0.0, 0.05],
            [0.22, 0.0, 0.05],
            [0.33, 0.0, 0.05],
            [0.40, 0.0, 0.05],
        ],
        radii: vec![
            [0.03, 0.03],
            [0.12, 0.11],
            [0.17, 0.15],
            [0.13, 0.11],
            [0.05, 0.045],
            [0.11, 0.075],
            [0.14, 0.085],
            [0.15, 0.09],
            [0.14, 0.085],
            [0.11, 0.075],
            [0.05, 0.045],
        ],
        parts: vec![1, 0],
        cuts_t: vec![4.0],
        min_around: 16,
    };
    // leg k (1 = front) on the left: spine knot, socket angle, azimuth of its direction from +x (degrees)
    let legs: [(f64, f64, f64); 4] = [(9.0, -15.0, 45.0), (8.0, -40.0, 75.0), (7.0, -15.0, 105.0), (6.0, -40.0, 140.0)];
    let mut limbs = Vec::new();
    for (side_k, side) in ["left", "right"].iter().enumerate() {
        for (k, &(t, phi, azimuth)) in legs.iter().enumerate() {
            let first = names.len();
            names.push(format!("leg{}_{side}_femur", k + 1));
            names.push(format!("leg{}_{side}_tibia", k + 1));
            parent.extend([Some(0), Some(first)]);
            let a = f64::to_radians(azimuth);
            let y = if side_k == 0 { a.sin() } else { -a.sin() };
            // out and 25 degrees down
            let dir = unit([a.cos() * 0.9063, y * 0.9063, -0.4226]);
            let lift = lift_axis(dir);
            joints.extend([j(&[(Z, -0.3, 0.3), (lift, -0.6, 0.4)]), j(&[(lift, -0.2, 1.2)])]);
            limbs.push(LimbDef {
                attach_t: t,
                attach_phi: phi.to_radians(),
                mirror_of: if side_k == 1 { Some(k) } else { None },
                dir,
                length: 1.1,
                radii: vec![(0.0, 0.025), (0.08, 0.02), (0.5, 0.017), (0.9, 0.012), (1.1, 0.009)],
                parts: vec![first, first + 1],
                cuts_u: vec![0.5],
                attached_to: 0,
            });
        }
    }
    Design { names, parent, joints, spine, limbs }
}

/// Neck parts of the giraffe.
pub const GIRAFFE_NECK: usize = 4;

/// A long neck: `trunk` (root), `tail`, `neck1` (at the shoulders) .. `neck4`, `head` along the spine, and
/// four long legs of two parts (`front_left_upper`, `front_left_lower`, ... `hind_right_lower`): 15 parts.
/// The neck rises at about 65 degrees; its joints nod about the lateral axis and bend sideways about the
/// axis across the neck.
fn giraffe() -> Design {
    let mut names: Vec<String> = vec!["trunk".into(), "tail".into()];
    names.extend((1..=GIRAFFE_NECK).map(|k| format!("neck{k}")));
    names.push("head".into());
    let head = names.len() - 1;
    let mut parent = vec![None, Some(0), Some(0)];
    parent.extend((3..=head).map(|k| Some(k - 1)));
    let points: Vec<Vec3> = vec![
        [-0.90, 0.0, 0.86],
        [-0.78, 0.0, 0.96],
        [-0.62, 0.0, 1.04],
        [-0.50, 0.0, 1.08],
        [-0.15, 0.0, 1.10],
        [0.22, 0.0, 1.14],
        [0.42, 0.0, 1.26],
        [0.52, 0.0, 1.50],
        [0.62, 0.0, 1.76],
        [0.72, 0.0, 2.02],
        [0.81, 0.0, 2.24],
        [0.94, 0.0, 2.36],
        [1.12, 0.0, 2.37],
    ];
    // the sideways axis of a neck joint: across the neck, in the x-z plane
    let neck_dir = unit([0.10, 0.0, 0.26]);
    let side = cross(neck_dir, Y);
    let mut joints = vec![None, j(&[(Z, -1.0, 1.0), (Y, -0.5, 0.5)])];
    for _ in 0..GIRAFFE_NECK {
        joints.push(j(&[(Y, -0.4, 0.4), (side, -0.6, 0.6), (neck_dir, -0.15, 0.15)]));
    }
    joints.push(j(&[(Y, -0.7, 0.7), (side, -0.5, 0.5)]));
    let spine = SpineDef {
        points,
        radii: vec![
            [0.02, 0.02],
            [0.025, 0.025],
            [0.05, 0.05],
            [0.17, 0.18],
            [0.20, 0.21],
            [0.19, 0.21],
            [0.11, 0.12],
            [0.085, 0.09],
            [0.075, 0.08],
            [0.065, 0.07],
            [0.07, 0.075],
            [0.08, 0.085],
            [0.045, 0.05],
        ],
        parts: vec![1, 0, 2, 3, 4, 5, 6],
        cuts_t: vec![2.6, 6.0, 7.0, 8.0, 9.0, 10.0],
        min_around: 16,
    };
    let mut limbs = Vec::new();
    for (k, (prefix, t, knee)) in [("front", 5.0, (Y, -1.0, 0.1)), ("hind", 3.5, (Y, -0.1, 1.0))].iter().enumerate() {
        for (side_k, side) in ["left", "right"].iter().enumerate() {
            let first = names.len();
            names.push(format!("{prefix}_{side}_upper"));
            names.push(format!("{prefix}_{side}_lower"));
            parent.extend([Some(0), Some(first)]);
            joints.extend([j(&[(Y, -0.7, 0.7), (X, -0.15, 0.15)]), j(&[*knee])]);
            limbs.push(LimbDef {
                attach_t: *t,
                attach_phi: -40f64.to_radians(),
                mirror_of: if side_k == 1 { Some(2 * k) } else { None },
                dir: [0.0, 0.0, -1.0],
                length: 0.92,
                radii: vec![(0.0, 0.06), (0.2, 0.045), (0.46, 0.033), (0.8, 0.028), (0.92, 0.032)],
                parts: vec![first, first + 1],
                cuts_u: vec![0.46],
                attached_to: 0,
            });
        }
    }
    Design { names, parent, joints, spine, limbs }
}

/// Finger names of the hand, thumb first.
pub const HAND_FINGERS: [&str; 5] = ["thumb", "index", "middle", "ring", "little"];

/// Many small parts: a flat `palm` (root; its spine runs across the hand, from the little finger's side to
/// the thumb's) and five fingers of three phalanges (`thumb1` .. `thumb3`, `index1` .. `little3`, 1 at the
/// palm): 16 parts, each phalanx 0.08-0.14 long and 0.025 thick against a palm 0.75 wide. The four fingers
/// fan out from the palm's edge; the thumb leaves its underside near the thumb's end. Knuckles flex towards
/// the palm and spread a little; the middle and end joints only flex.
fn hand() -> Design {
    let mut names: Vec<String> = vec!["palm".into()];
    let mut parent = vec![None];
    let mut joints = vec![None];
    let xs = [-0.42, -0.36, -0.27, -0.09, 0.09, 0.27, 0.36, 0.42];
    let lat = [0.10, 0.21, 0.25, 0.26, 0.26, 0.25, 0.21, 0.10];
    let up = [0.04, 0.055, 0.06, 0.065, 0.065, 0.06, 0.055, 0.04];
    let spine = SpineDef {
        points: xs.iter().map(|&x| [x, 0.0, 0.0]).collect(),
        radii: lat.iter().zip(&up).map(|(&l, &u)| [l, u]).collect(),
        parts: vec![0],
        cuts_t: Vec::new(),
        min_around: 16,
    };
    let mut limbs = Vec::new();
    // (spine parameter, socket angle in degrees, direction, length, phalanx cuts, base radius)
    let fingers: [(f64, f64, Vec3, f64, [f64; 2], f64); 5] = [
        (5.2, -130.0, unit([0.6, 0.2, -0.75]), 0.36, [0.14, 0.26], 0.034),
        (5.0, 0.0, unit([0.1, 1.0, 0.0]), 0.40, [0.16, 0.28], 0.03),
        (4.0, 0.0, unit([0.02, 1.0, 0.0]), 0.44, [0.18, 0.31], 0.03),
        (3.0, 0.0, unit([-0.06, 1.0, 0.0]), 0.40, [0.16, 0.28], 0.029),
        (2.0, 0.0, unit([-0.16, 1.0, 0.0]), 0.32, [0.13, 0.23], 0.026),
    ];
    for (f, &(t, phi, dir, length, cuts, r)) in HAND_FINGERS.iter().zip(&fingers) {
        let first = names.len();
        for k in 1..=3 {
            names.push(format!("{f}{k}"));
        }
        parent.extend([Some(0), Some(first), Some(first + 1)]);
        // flexion: the axis across the finger, turning its tip towards the palm side (-z)
        let flex = if *f == "thumb" { unit(cross(dir, [0.0, 0.0, -1.0])) } else { unit(cross([0.0, 0.0, 1.0], dir)) };
        let spread = unit(cross(dir, flex));
        joints.extend([j(&[(flex, -0.2, 1.0), (spread, -0.15, 0.15)]), j(&[(flex, 0.0, 1.2)]), j(&[(flex, 0.0, 0.8)])]);
        limbs.push(LimbDef {
            attach_t: t,
            attach_phi: phi.to_radians(),
            mirror_of: None,
            dir,
            length,
            radii: vec![(0.0, r), (cuts[0], 0.95 * r), (cuts[1], 0.85 * r), (length, 0.8 * r)],
            parts: vec![first, first + 1, first + 2],
            cuts_u: cuts.to_vec(),
            attached_to: 0,
        });
    }
    Design { names, parent, joints, spine, limbs }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::{generate, Spec};

    /// A design no resolution can build (the thumb's hole on the index finger's) is refused with the planner's
    /// error, not refined without end (it ran out of memory).
    #[test]
    fn a_design_that_cannot_be_built_is_refused() {
        let mut d = design(Preset::Hand);
        d.limbs[0].attach_t = 6.5;
        d.limbs[0].attach_phi = -60f64.to_radians();
        d.limbs[0].dir = unit([0.85, 0.45, -0.3]);
        let err = crate::synth::tube::Planner::new(&d).plan_for_target(3000).map(|p| p.n_vertices);
        assert!(err.is_err(), "{err:?}");
    }

    fn index(d: &Design, name: &str) -> usize {
        d.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("no part {name}"))
    }

    /// `chain[0]` hangs from `root`, each next part from the one before.
    fn assert_chain(d: &Design, root: &str, chain: &[String]) {
        let mut up = index(d, root);
        for c in chain {
            let k = index(d, c);
            assert_eq!(d.parent[k], Some(up), "{c} should hang from {}", d.names[up]);
            assert!(d.joints[k].is_some(), "{c} has no joint");
            up = k;
        }
    }

    fn assert_tree(d: &Design, parts: usize, root: &str) {
        assert_eq!(d.names.len(), parts);
        assert_eq!(d.parent.len(), parts);
        assert_eq!(d.joints.len(), parts);
        assert_eq!(d.root(), index(d, root));
        assert_eq!(d.root(), 0, "the generator keeps the root at index 0");
        assert!(d.joints[0].is_none());
        assert_eq!(d.topological_order().len(), parts);
        let mut names = d.names.clone();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), parts, "part names are unique");
        // every part is on exactly one chain (the spine or one limb)
        let mut seen = vec![0; parts];
        for &p in d.spine.parts.iter().chain(d.limbs.iter().flat_map(|l| l.parts.iter())) {
            seen[p] += 1;
        }
        assert!(seen.iter().all(|&s| s == 1), "{seen:?}");
    }

    #[test]
    fn spider_has_a_small_body_and_eight_two_part_legs() {
        let d = design(Preset::Spider);
        assert_tree(&d, 2 + 8 * 2, "cephalothorax");
        assert_chain(&d, "cephalothorax", &["abdomen".into()]);
        assert_eq!(d.limbs.len(), 2 * SPIDER_LEGS_PER_SIDE);
        for k in 1..=SPIDER_LEGS_PER_SIDE {
            for side in ["left", "right"] {
                assert_chain(&d, "cephalothorax", &[format!("leg{k}_{side}_femur"), format!("leg{k}_{side}_tibia")]);
            }
        }
        // thin: every leg is over 40 times as long as it is thick, and longer than the body
        let body = d.spine.points.last().unwrap()[0] - d.spine.points[0][0];
        for l in &d.limbs {
            let thickest = l.radii.iter().map(|r| r.1).fold(0.0, f64::max);
            assert!(l.length > 40.0 * thickest && l.length > body, "{} {thickest} {body}", l.length);
        }
    }

    #[test]
    fn giraffe_has_a_four_part_neck() {
        let d = design(Preset::Giraffe);
        assert_tree(&d, 7 + 4 * 2, "trunk");
        let mut neck: Vec<String> = (1..=GIRAFFE_NECK).map(|k| format!("neck{k}")).collect();
        neck.push("head".into());
        assert_chain(&d, "trunk", &neck);
        assert_chain(&d, "trunk", &["tail".into()]);
        for leg in ["front_left", "front_right", "hind_left", "hind_right"] {
            assert_chain(&d, "trunk", &[format!("{leg}_upper"), format!("{leg}_lower")]);
        }
        // the neck rises: its top is well above the trunk
        let top = d.spine.points[10][2];
        assert!(top > d.spine.points[4][2] + 1.0);
    }

    #[test]
    fn hand_has_a_palm_and_five_three_phalanx_fingers() {
        let d = design(Preset::Hand);
        assert_tree(&d, 1 + 5 * 3, "palm");
        for f in HAND_FINGERS {
            assert_chain(&d, "palm", &[format!("{f}1"), format!("{f}2"), format!("{f}3")]);
        }
    }

    #[test]
    fn every_part_of_the_new_creatures_has_vertices_at_3000() {
        for preset in [Preset::Spider, Preset::Giraffe, Preset::Hand] {
            for seed in 0..2 {
                let g = generate(&Spec { preset, vertices: 3000, poses: 10, seed, ..Spec::default() }).unwrap();
                let nv = g.population.n_vertices();
                assert!((2400..=3600).contains(&nv), "{preset:?}: {nv} vertices");
                let mut count = vec![0usize; g.n_parts()];
                for &l in &g.part_of_vertex {
                    count[l as usize] += 1;
                }
                for (name, c) in g.part_names.iter().zip(&count) {
                    assert!(*c >= 30, "{preset:?}: part {name} has {c} vertices at 3000");
                }
            }
        }
    }
}
