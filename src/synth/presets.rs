//! The page's built-in examples: a generated population, the fit parameters to use on it, and one line of
//! what to notice. Some fail on purpose, and say why.

use super::{part_index, Preset, Spec};
use crate::mfa::{LambdaRule, Params};
use serde::Serialize;

#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Example {
    /// Stable id (used in URLs).
    pub id: &'static str,
    pub title: &'static str,
    /// What to notice, one line.
    pub note: &'static str,
    /// True when the example shows a failure on purpose.
    pub fails_on_purpose: bool,
    pub spec: Spec,
    /// The default parameters, except where an example shows a failure of a non-default choice (the literal eq 18):
    /// what people see on the examples is what they get on their own meshes.
    pub params: Params,
}

fn quadruped_spec() -> Spec {
    Spec {
        preset: Preset::Quadruped,
        vertices: 3000,
        poses: 10,
        seed: 0,
        joint_band: 0.01,
        max_angle_deg: 60.0,
        ..Spec::default()
    }
}

/// The creatures of other proportions (tests of the part rule beyond the quadruped) at the generator's defaults,
/// 3 000 vertices and 10 poses.
fn new_creature(preset: Preset) -> Spec {
    Spec { preset, vertices: 3000, poses: 10, ..Spec::default() }
}

/// Every example, the default (the quadruped) first.
pub fn examples() -> Vec<Example> {
    let q = quadruped_spec();
    let tied: Vec<(usize, usize)> = ["upper", "lower", "foot"]
        .iter()
        .filter_map(|seg| {
            let a = part_index(Preset::Quadruped, &format!("front_left_{seg}"))?;
            let b = part_index(Preset::Quadruped, &format!("front_right_{seg}"))?;
            Some((a, b))
        })
        .collect();
    vec![
        Example {
            id: "quadruped",
            title: "Quadruped (18 parts)",
            note: "Trunk, neck, head, a 3-piece tail and four 3-piece legs, with soft flesh at the joints: the fit finds the parts and their rotations (see the ground-truth accuracy).",
            fails_on_purpose: false,
            spec: q.clone(),
            params: Params::default(),
        },
        Example {
            id: "arm",
            title: "Two-link arm (3 parts)",
            note: "The smallest articulated case: base, upper arm, forearm. The start (Stages) is the three bones and thin slices of skin at the joints, dissolved as flesh: 3 parts remain; Step by step shows the paper's coarse stage over-split it.",
            fails_on_purpose: false,
            spec: Spec { preset: Preset::Arm, vertices: 1500, poses: 8, joint_band: 0.01, ..Spec::default() },
            params: Params::default(),
        },
        Example {
            id: "snake",
            title: "Snake (8 segments)",
            note: "A chain: every segment moves relative to its neighbours, so every joint is found; the interpolation keeps the chain attached.",
            fails_on_purpose: false,
            spec: Spec { preset: Preset::Snake, vertices: 2500, poses: 10, joint_band: 0.01, max_angle_deg: 45.0, ..Spec::default() },
            params: Params::default(),
        },
        Example {
            id: "spider",
            title: "Spider (18 parts, thin legs)",
            note: "Eight long, thin two-part legs on a small body: each leg piece holds few vertices and little volume, the hardest case for the part count. Default parameters; compare the parts found with the ground truth.",
            fails_on_purpose: false,
            spec: new_creature(Preset::Spider),
            params: Params::default(),
        },
        Example {
            id: "giraffe",
            title: "Giraffe (15 parts, long neck)",
            note: "A neck of four parts, a head, a tail and four long two-part legs: each neck joint bends a little and the bends add up. Default parameters; see whether the neck is cut at its joints.",
            fails_on_purpose: false,
            spec: new_creature(Preset::Giraffe),
            params: Params::default(),
        },
        Example {
            id: "hand",
            title: "Hand (16 parts, small phalanges)",
            note: "A palm and five fingers of three phalanges each: parts ten times smaller than the palm, side by side. Default parameters; see whether every phalanx is found.",
            fails_on_purpose: false,
            spec: new_creature(Preset::Hand),
            params: Params::default(),
        },
        Example {
            id: "literal-eq18",
            title: "Fails on purpose: the paper's literal eq 18",
            note: "Λ from per-shape covariance eigenvalues is no maximisation step: the fit fails, not the parts. The log-likelihood drops and AECM cycles to the iteration cap, unconverged (see the plot). The exact Λ step never lowers it.",
            fails_on_purpose: true,
            spec: q.clone(),
            params: Params { lambda_rule: LambdaRule::PaperEq18, max_iter: 60, ..Params::default() },
        },
        Example {
            id: "too-few-poses",
            title: "Limit: two legs that always move together",
            note: "The front legs bend by the same angles in every pose: their motions cannot tell them apart, and their parts get one and the same motion. They are still two parts, because they do not touch: a part is one connected piece of the mesh.",
            fails_on_purpose: false,
            spec: Spec { tied, poses: 6, ..q.clone() },
            params: Params::default(),
        },
        Example {
            id: "blob",
            title: "Fails on purpose: a non-articulated deformation",
            note: "A smoothly bent and twisted blob has no rigid parts: the result says it is not articulated (rigid parts explain too little of its motion) and suggests a deformation model instead.",
            fails_on_purpose: true,
            spec: Spec { preset: Preset::Blob, vertices: 2000, poses: 8, ..Spec::default() },
            params: Params::default(),
        },
    ]
}

pub fn example(id: &str) -> Option<Example> {
    examples().into_iter().find(|e| e.id == id)
}
