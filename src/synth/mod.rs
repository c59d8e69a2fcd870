//! Synthetic populations with ground truth: articulated creatures posed at random, for tests, presets and
//! benchmarks.
//!
//! [`generate`] builds ONE closed, consistently oriented triangle mesh of sphere topology for a [`Preset`]
//! (a swept-ellipse body with limb tubes glued into holes of its wall, see [`tube`]), then poses it
//! [`Spec::poses`] times: every joint gets a random angle within its limits (scaled by
//! [`Spec::max_angle_deg`]), forward kinematics places every part, and linear blend skinning over a band of
//! width [`Spec::joint_band`] around each joint makes the joints bend like flesh (band 0 = piecewise rigid).
//! Everything is seeded ([`rand_pcg::Pcg64`]); no OS randomness, so it runs the same on wasm32.
//!
//! Units: the design is rescaled so that the rest pose's longest bounding-box side is 1; `joint_band`,
//! `noise` and the root translation are in those units. The posed shapes are then moved, all with one
//! offset and one scale, into the unit box, so the [`Population`]'s normalisation is exactly the identity:
//! generated coordinates, unit-box coordinates and "original units" ([`obj_files`]) are the same numbers.

pub mod creature;
pub mod curve;
pub mod pose;
pub mod presets;
pub mod tube;

pub use pose::Blend;

use crate::error::{Error, Result};
use crate::geometry::{add, mat_vec, scale, sub, Mat3, Vec3, IDENTITY};
use crate::mesh::Population;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// What creature to generate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// 18 parts: trunk (root), neck, head, tail1..tail3, and four legs of three parts
    /// (`front_left_upper`, `..._lower`, `..._foot`, then front right, hind left, hind right). Legs hinge
    /// about the lateral axis; neck, head and tail turn about two or three axes.
    #[default]
    Quadruped,
    /// 3 parts: a fixed `base`, `upper_arm` (3-axis shoulder) and `forearm` (one-way elbow hinge).
    Arm,
    /// 8 parts `seg1` (tail tip) .. `seg8` (head) along one tube; the root is `seg4`.
    Snake,
    /// A bean-shaped closed surface (a swept ellipse, its ends rounded, about 1.5 : 1) bent along its length
    /// in a random plane and twisted about its axis, both smoothly (no rigid parts). Ground truth: one part
    /// `blob`, its rotation the best rigid (Procrustes) fit of each pose to the rest shape.
    Blob,
    /// 18 thin-limbed parts: a small body (`cephalothorax` (root), `abdomen`) and eight long thin legs of two
    /// parts (`leg1_left_femur`, `leg1_left_tibia` .. `leg4_right_tibia`, leg 1 in front).
    Spider,
    /// 15 parts with a long neck: `trunk` (root), `tail`, `neck1` .. `neck4`, `head`, and four long legs of
    /// two parts (`front_left_upper`, `front_left_lower`, ... `hind_right_lower`).
    Giraffe,
    /// 16 parts, many of them small: a flat `palm` (root) and five fingers of three phalanges (`thumb1` ..
    /// `thumb3`, `index1` .. `little3`; 1 next to the palm).
    Hand,
}

impl Preset {
    /// Every preset, in the order the CLI lists them.
    pub const ALL: [Preset; 7] =
        [Preset::Quadruped, Preset::Arm, Preset::Snake, Preset::Blob, Preset::Spider, Preset::Giraffe, Preset::Hand];

    pub fn name(&self) -> &'static str {
        match self {
            Preset::Quadruped => "quadruped",
            Preset::Arm => "arm",
            Preset::Snake => "snake",
            Preset::Blob => "blob",
            Preset::Spider => "spider",
            Preset::Giraffe => "giraffe",
            Preset::Hand => "hand",
        }
    }
}

/// Generator parameters. Each field's default is in its doc comment; [`Spec::validate`] checks them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, rename_all = "camelCase", deny_unknown_fields)]
pub struct Spec {
    /// The creature. Default [`Preset::Quadruped`].
    pub preset: Preset,
    /// Target vertex count, 100..=2 000 000; the mesh gets within a few percent of it (a preset's coarsest
    /// mesh is used for targets below it: about 1 100 vertices for the quadruped, 160 for the snake).
    /// Default 10 000.
    pub vertices: usize,
    /// Number of posed shapes, at least 2. Default 20.
    pub poses: usize,
    /// Seed of the one random stream (angles, root motion, noise). Default 0.
    pub seed: u64,
    /// Width of the skinning blend band around each joint, as a fraction of the rest pose's longest side;
    /// 0 makes every part exactly rigid. Clamped per joint to 45 % of the neighbouring parts' lengths.
    /// Default 0.05.
    pub joint_band: f64,
    /// Standard deviation of Gaussian noise added to every coordinate, fraction of the rest pose's longest
    /// side, 0..=0.1. Default 0.
    pub noise: f64,
    /// Scale of the joint limits in degrees, (0, 180]: each joint axis turns by up to a preset-specific
    /// fraction (up to 1.5) of this. For the blob: the largest end-to-end twist (twice this is the
    /// largest bend). Default 40.
    pub max_angle_deg: f64,
    /// Also move the root (and so the whole creature) by a random rotation of up to `max_angle_deg` about
    /// the rest pose's centre and a translation of up to 0.25 per axis. Default false: the root stays put.
    pub root_motion: bool,
    /// Pairs (a, b) of part indices: part b takes part a's local joint rotation in every pose (applied in
    /// list order, after drawing). Two limbs tied part by part never move apart: for the quadruped, tying
    /// `front_left_*` to `front_right_*` makes the two front legs one rigid body (their joints only hinge
    /// about the lateral axis joining them). See [`part_index`]. Default empty.
    pub tied: Vec<(usize, usize)>,
}

impl Default for Spec {
    fn default() -> Spec {
        Spec {
            preset: Preset::Quadruped,
            vertices: 10_000,
            poses: 20,
            seed: 0,
            joint_band: 0.05,
            noise: 0.0,
            max_angle_deg: 40.0,
            root_motion: false,
            tied: Vec::new(),
        }
    }
}

pub const MIN_VERTICES: usize = 100;
pub const MAX_VERTICES: usize = 2_000_000;
/// Largest vertices x poses (about 1.2 GB of coordinates).
pub const MAX_COORDINATES: usize = 50_000_000;

impl Spec {
    /// Checks every field; the error says which field, its value and the valid range.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Params(m));
        if !(MIN_VERTICES..=MAX_VERTICES).contains(&self.vertices) {
            return bad(format!("vertices must be between {MIN_VERTICES} and {MAX_VERTICES}, got {}", self.vertices));
        }
        if self.poses < 2 {
            return bad(format!("poses must be at least 2 (a population needs two shapes), got {}", self.poses));
        }
        if self.vertices.saturating_mul(self.poses) > MAX_COORDINATES {
            return bad(format!(
                "vertices x poses must be at most {MAX_COORDINATES}, got {} x {}; lower one of them",
                self.vertices, self.poses
            ));
        }
        if !(self.joint_band.is_finite() && (0.0..=0.5).contains(&self.joint_band)) {
            return bad(format!(
                "joint_band must be between 0 and 0.5 (fraction of the creature's size), got {}",
                self.joint_band
            ));
        }
        if !(self.noise.is_finite() && (0.0..=0.1).contains(&self.noise)) {
            return bad(format!(
                "noise must be between 0 and 0.1 (fraction of the creature's size), got {}",
                self.noise
            ));
        }
        if !(self.max_angle_deg.is_finite() && self.max_angle_deg > 0.0 && self.max_angle_deg <= 180.0) {
            return bad(format!("max_angle_deg must be in (0, 180], got {}", self.max_angle_deg));
        }
        let d = creature::design(self.preset);
        let n = d.names.len();
        let root = d.root();
        let mut targets = Vec::new();
        for &(a, b) in &self.tied {
            if a >= n || b >= n {
                return bad(format!(
                    "tied pair ({a}, {b}): the {} preset has parts 0..{} only",
                    self.preset.name(),
                    n - 1
                ));
            }
            if a == b {
                return bad(format!("tied pair ({a}, {b}): a part cannot be tied to itself"));
            }
            if a == root || b == root {
                return bad(format!(
                    "tied pair ({a}, {b}): part {root} ({}) is the root and has no joint; use root_motion instead",
                    d.names[root]
                ));
            }
            if targets.contains(&b) {
                return bad(format!("tied pair ({a}, {b}): part {b} ({}) is tied twice", d.names[b]));
            }
            targets.push(b);
        }
        Ok(())
    }
}

/// Part names of a preset, in part-index order.
pub fn part_names(preset: Preset) -> Vec<String> {
    creature::design(preset).names
}

/// Parent of every part (None for the root).
pub fn part_parents(preset: Preset) -> Vec<Option<usize>> {
    creature::design(preset).parent
}

/// Index of a part by name, e.g. `part_index(Preset::Quadruped, "front_left_upper")`.
pub fn part_index(preset: Preset, name: &str) -> Option<usize> {
    part_names(preset).iter().position(|n| n == name)
}

/// A generated population and its ground truth. All coordinates are the population's (unit-box) ones.
#[derive(Debug, Clone, PartialEq)]
pub struct Generated {
    pub spec: Spec,
    /// Shapes named `pose01.obj`, `pose02.obj`, ... in generation order (= natural order).
    pub population: Population,
    /// Ground-truth part of every vertex: the part with the largest skinning weight.
    pub part_of_vertex: Vec<u32>,
    /// `rotations[pose][part]`: world rotation of the part relative to the rest pose.
    pub rotations: Vec<Vec<Mat3>>,
    /// `translations[pose][part]`: a vertex moved by that part alone is at `R rest + t`.
    pub translations: Vec<Vec<Vec3>>,
    /// The unposed mesh, mapped into the population's frame with the same offset and scale.
    pub rest: Vec<Vec3>,
    pub part_names: Vec<String>,
    pub parent: Vec<Option<usize>>,
    /// Rest-pose centre of the joint of every non-root part with its parent (None for the root).
    pub joint_centers: Vec<Option<Vec3>>,
    /// Skinning of every vertex (for the blob: all `[0, 0]`, and the motion is not rigid).
    pub blend: Vec<Blend>,
}

impl Generated {
    pub fn n_parts(&self) -> usize {
        self.part_names.len()
    }
}

fn shape_names(poses: usize) -> Vec<String> {
    let width = poses.to_string().len().max(2);
    (1..=poses).map(|i| format!("pose{i:0width$}.obj")).collect()
}

/// Generates a population for `spec` (validated first).
pub fn generate(spec: &Spec) -> Result<Generated> {
    spec.validate()?;
    let design = creature::design(spec.preset);
    let planner = tube::Planner::new(&design);
    let plan = planner.plan_for_target(spec.vertices)?;
    let mesh = planner.build(&plan);
    let nv = mesh.positions.len();
    let n_parts = design.names.len();

    // Rest pose centred at the origin; size = longest side.
    let (lo, hi) = bounds(std::iter::once(&mesh.positions));
    let size = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let centre = scale(add(lo, hi), 0.5);
    let rest: Vec<Vec3> = mesh.positions.iter().map(|&p| sub(p, centre)).collect();
    let joints: Vec<Option<Vec3>> = mesh.joint_centers.iter().map(|j| j.map(|p| sub(p, centre))).collect();

    let blend = pose::blends(&mesh.chains, &mesh.skin, spec.joint_band * size);
    let order = design.topological_order();
    let max_angle = spec.max_angle_deg.to_radians();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(spec.seed);
    let blob = spec.preset == Preset::Blob;

    let mut shapes: Vec<Vec<Vec3>> = Vec::with_capacity(spec.poses);
    let mut rotations = Vec::with_capacity(spec.poses);
    let mut translations = Vec::with_capacity(spec.poses);
    for _ in 0..spec.poses {
        let mut local = vec![IDENTITY; n_parts];
        let mut bend = (0.0, 0.0, 0.0);
        if blob {
            bend = (
                (2.0 * rng.gen::<f64>() - 1.0) * max_angle,
                (2.0 * rng.gen::<f64>() - 1.0) * 2.0 * max_angle,
                2.0 * std::f64::consts::PI * rng.gen::<f64>(),
            );
        } else {
            for (l, j) in local.iter_mut().zip(&design.joints) {
                if let Some(j) = j {
                    *l = pose::sample_joint(&mut rng, j, max_angle);
                }
            }
            for &(a, b) in &spec.tied {
                local[b] = local[a];
            }
        }
        let root = if spec.root_motion {
            let axis = pose::random_axis(&mut rng);
            let angle = rng.gen::<f64>() * max_angle;
            let t = [0; 3].map(|_| (rng.gen::<f64>() - 0.5) * 0.5 * size);
            (crate::geometry::rotation::axis_angle(axis, angle), t)
        } else {
            (IDENTITY, [0.0; 3])
        };
        let mut out = Vec::with_capacity(nv);
        if blob {
            let (twist, b, psi) = bend;
            out.extend(rest.iter().map(|&x| {
                let y = pose::bend_twist(x, twist, size / 2.0, b, size, psi);
                add(mat_vec(&root.0, y), root.1)
            }));
            let (r, t) = pose::best_rigid(&rest, &out);
            rotations.push(vec![r]);
            translations.push(vec![t]);
        } else {
            let (rot, tr) = pose::forward_kinematics(&design, &order, &joints, &local, root);
            pose::skin(&rest, &blend, &rot, &tr, &mut out);
            rotations.push(rot);
            translations.push(tr);
        }
        shapes.push(out);
    }
    if spec.noise > 0.0 {
        let sigma = spec.noise * size;
        for s in &mut shapes {
            for p in s.iter_mut() {
                for c in p.iter_mut() {
                    *c += sigma * pose::gaussian(&mut rng);
                }
            }
        }
    }

    // One offset and scale for every shape: x_n = (x - lo) / side, so the min of each axis is exactly 0
    // and the longest side exactly 1 (Population then keeps the coordinates as they are).
    let (lo, hi) = bounds(shapes.iter());
    let side = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let to_n = |p: Vec3| [(p[0] - lo[0]) / side, (p[1] - lo[1]) / side, (p[2] - lo[2]) / side];
    for s in &mut shapes {
        for p in s.iter_mut() {
            *p = to_n(*p);
        }
    }
    let rest_n: Vec<Vec3> = rest.iter().map(|&p| to_n(p)).collect();
    let joints_n: Vec<Option<Vec3>> = joints.iter().map(|j| j.map(to_n)).collect();
    // R x + t - lo = R (x - lo) + (R lo + t - lo)
    let translations: Vec<Vec<Vec3>> = translations
        .iter()
        .zip(&rotations)
        .map(|(ts, rs)| ts.iter().zip(rs).map(|(&t, r)| scale(sub(add(mat_vec(r, lo), t), lo), 1.0 / side)).collect())
        .collect();

    let population = Population::new(crate::mesh::Sources::UnitShapes {
        names: shape_names(spec.poses),
        faces: mesh.faces,
        shapes,
    })?;
    debug_assert_eq!(population.normalization, crate::mesh::Normalization::IDENTITY);
    Ok(Generated {
        spec: spec.clone(),
        population,
        part_of_vertex: blend.iter().map(|b| b.label()).collect(),
        rotations,
        translations,
        rest: rest_n,
        part_names: design.names.clone(),
        parent: design.parent.clone(),
        joint_centers: joints_n,
        blend,
    })
}

fn bounds<'a>(sets: impl Iterator<Item = &'a Vec<Vec3>>) -> (Vec3, Vec3) {
    crate::geometry::bounds(sets.flatten())
}

/// The population as OBJ files: (`pose01.obj`, text), ... in order. Coordinates are in original units,
/// i.e. `population.normalization.to_original` of the unit-box shapes; for a generated population that
/// normalisation is the identity, so they are exactly the unit-box coordinates, and loading the files with
/// [`Population::read`] of them gives back the same numbers bit for bit.
pub fn obj_files(generated: &Generated) -> Vec<(String, String)> {
    let pop = &generated.population;
    let spec = &generated.spec;
    let n = pop.n_shapes();
    pop.names
        .iter()
        .zip(pop.shapes())
        .enumerate()
        .map(|(i, (name, shape))| {
            let header = format!(
                "posemfa synthetic population: preset {}, shape {} of {n}, seed {}, {} vertices, {} triangles\n\
                 max_angle_deg {}, joint_band {}, noise {}, root_motion {}, parts {}",
                spec.preset.name(),
                i + 1,
                spec.seed,
                shape.len(),
                pop.faces.len(),
                spec.max_angle_deg,
                spec.joint_band,
                spec.noise,
                spec.root_motion,
                generated.n_parts()
            );
            let original: Vec<Vec3> = shape.iter().map(|p| pop.normalization.to_original(p)).collect();
            (name.clone(), crate::export::obj::write_obj(&original, &pop.faces, &header))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(spec: Spec) -> String {
        match spec.validate() {
            Err(Error::Params(m)) => m,
            other => panic!("expected Error::Params, got {other:?}"),
        }
    }

    #[test]
    fn validation_names_the_field() {
        assert!(Spec::default().validate().is_ok());
        assert!(err(Spec { poses: 1, ..Spec::default() }).contains("poses must be at least 2"));
        assert!(err(Spec { vertices: 99, ..Spec::default() }).contains("vertices must be between 100"));
        assert!(err(Spec { vertices: 2_000_001, ..Spec::default() }).contains("vertices"));
        assert!(err(Spec { vertices: 1_000_000, poses: 51, ..Spec::default() }).contains("vertices x poses"));
        assert!(err(Spec { joint_band: -0.1, ..Spec::default() }).contains("joint_band"));
        assert!(err(Spec { joint_band: f64::NAN, ..Spec::default() }).contains("joint_band"));
        assert!(err(Spec { noise: f64::INFINITY, ..Spec::default() }).contains("noise"));
        assert!(err(Spec { noise: -1e-9, ..Spec::default() }).contains("noise"));
        assert!(err(Spec { max_angle_deg: 0.0, ..Spec::default() }).contains("max_angle_deg"));
        assert!(err(Spec { max_angle_deg: 181.0, ..Spec::default() }).contains("max_angle_deg"));
        assert!(err(Spec { tied: vec![(6, 18)], ..Spec::default() }).contains("parts 0..17"));
        assert!(err(Spec { tied: vec![(6, 6)], ..Spec::default() }).contains("itself"));
        assert!(err(Spec { tied: vec![(0, 6)], ..Spec::default() }).contains("root"));
        assert!(err(Spec { tied: vec![(6, 9), (7, 9)], ..Spec::default() }).contains("tied twice"));
        assert!(err(Spec { preset: Preset::Blob, tied: vec![(0, 1)], ..Spec::default() }).contains("parts 0..0"));
        assert!(matches!(generate(&Spec { poses: 0, ..Spec::default() }), Err(Error::Params(_))));
    }

    #[test]
    fn part_lists() {
        assert_eq!(part_names(Preset::Quadruped).len(), 18);
        assert_eq!(part_names(Preset::Arm), vec!["base", "upper_arm", "forearm"]);
        assert_eq!(part_names(Preset::Snake).len(), creature::SNAKE_SEGMENTS);
        assert_eq!(part_names(Preset::Blob), vec!["blob"]);
        assert_eq!(part_index(Preset::Quadruped, "front_right_upper"), Some(9));
        assert_eq!(part_index(Preset::Quadruped, "hind_right_foot"), Some(17));
        assert_eq!(part_index(Preset::Quadruped, "wing"), None);
        for p in Preset::ALL {
            assert_eq!(part_parents(p).iter().filter(|x| x.is_none()).count(), 1);
        }
    }

    #[test]
    fn names_sort_naturally_in_generation_order() {
        let names = shape_names(120);
        assert_eq!(names[0], "pose001.obj");
        let mut sorted = names.clone();
        sorted.sort_by(|a, b| crate::mesh::population::natural_cmp(a, b));
        assert_eq!(sorted, names);
        assert_eq!(shape_names(3), vec!["pose01.obj", "pose02.obj", "pose03.obj"]);
    }

    #[test]
    fn spec_json_round_trip() {
        let s = Spec { preset: Preset::Snake, tied: vec![(1, 2)], root_motion: true, ..Spec::default() };
        let j = serde_json::to_string(&s).unwrap();
        assert!(j.contains("\"preset\":\"snake\"") && j.contains("rootMotion"), "{j}");
        assert_eq!(serde_json::from_str::<Spec>(&j).unwrap(), s);
        assert_eq!(serde_json::from_str::<Spec>("{}").unwrap(), Spec::default());
    }
}
