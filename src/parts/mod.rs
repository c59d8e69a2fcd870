//! Which vertices form a part, and how many parts there are: the second room. It calls into [`crate::mfa`]
//! (the model and its fit) and is never called from there.
//!
//! Listed in the order of their imports: each module uses only the ones above it (`tests/module_rooms.rs`).
//!
//! - [`labels`]: small operations on part labels (renumbering, which parts touch).
//! - [`motion_labels`]: final labels by least-squares rigid motion (boundaries on the joints).
//! - [`islands`]: every part one connected piece of the mesh (islands moved to the best adjacent part).
//! - [`patches`]: the mesh cut into small compact pieces (farthest-point seeds, geodesic), and well-spread poses.
//! - [`merge_tree`]: patches merged greedily by the part rule's score, every merge recorded (the default start
//!   and the count read off the tree).
//! - [`coarse_mesh`]: a registered coarse mesh of a large population (the patches' seeds), to decide on.
//! - [`distinct`]: the part rule's two rules: flesh between parts dissolved, parts without a distinct motion merged.
//! - [`pair_blend`]: what a blend of two parts' rigid motions leaves of a vertex, and a split's drop of it.
//! - [`part_count`]: an exact part count asked for (`--bones N`).
//! - [`label_fit`]: the mixture fitted to given labels.
//! - [`multires`]: the coarse and refinement stages on a well-spread vertex subset, labels carried to all.
//! - [`hierarchy`]: the driver (`Pipeline`: runs the AECM, keeps its statistics, lifts results from a coarse mesh to
//!   every vertex, reports progress) and its two rules in child modules, each saying the next run once a run
//!   finished: `tree_rule` (the default: the merge tree's start and count), `algorithm1` (the paper's coarse and
//!   refinement stages, and its part rules); `rounds` (the steps after a final-stage run both rules take), and
//!   what a fit reports (`result`).
//! - [`diagnosis`]: whether the population looks articulated (how much of the motion rigid parts explain).
//! - [`robustness`]: fits over seeds and nuisance variants, and how much they agree.

pub mod labels;
pub mod motion_labels;
pub mod islands;
pub mod patches;
pub mod merge_tree;
pub mod coarse_mesh;
pub mod distinct;
pub mod pair_blend;
pub mod part_count;
pub mod label_fit;
pub mod multires;
pub mod hierarchy;
pub mod diagnosis;
pub mod robustness;
