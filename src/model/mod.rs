//! The constrained mixture of factor analyzers (paper sections 3-4) and its fit.
//!
//! Component k: h = R_k Λ_k z + b_k + ε, z ~ N(0, I_3), R_k = [R_k^1; ...; R_k^ns] (each in SO(3)),
//! Λ_k = diag(λ), Φ_k = diag(s_k^1 I_3, ..., s_k^ns I_3).
//!
//! - [`params`]: validated fit parameters, defaults in the doc comments.
//! - [`component`]: one factor analyser: Woodbury log-density (eq 6), posterior of z (eq 8).
//! - [`estep`]: responsibilities (eq 12) for all vertices and components, in log space.
//! - [`cm`]: cycle 1 (π eq 13, b eq 14); cycle 2 (exact Λ, R by eq 19 + 31, Φ eq 16 isotropic).
//! - [`init`]: k-means++ with restarts and the per-cluster Procrustes start.
//! - [`aecm`]: a [`aecm::Fit`] in progress: `step()` (one AECM iteration), `run()`, trace, convergence.
//! - [`squarem`]: SQUAREM extrapolation of the AECM iteration (fewer iterations, still monotone).
//! - [`hierarchy`]: Algorithm 1 (coarse, refinement, final), every stage kept.
//! - [`multires`]: the coarse and refinement stages on a well-spread vertex subset, labels carried to all.
//! - [`diagnosis`]: whether the population looks articulated (how much of the motion rigid parts explain).
//! - [`distinct`]: the default part rule: flesh between parts dissolved, parts without a distinct motion merged.
//! - [`motion_labels`]: final labels by least-squares rigid motion (boundaries on the joints).
//! - [`islands`]: every part one connected piece of the mesh (islands moved to the best adjacent part).
//! - [`result`]: the fitted [`Model`]: labels (eq 20), latent shape (eq 21), reconstruction (eq 22).
//! - [`limit`]: the E-step's speed against the machine's limit (tight kernels, measured).

pub mod aecm;
pub mod cm;
pub mod component;
pub mod data;
pub mod diagnosis;
pub mod distinct;
pub mod estep;
pub mod hierarchy;
pub mod init;
pub mod islands;
pub mod label_fit;
pub mod limit;
pub mod merge_tree;
pub mod memory;
pub mod motion_labels;
pub mod multires;
pub mod params;
pub mod part_count;
pub mod result;
pub mod robustness;
pub mod squarem;

pub use params::{LambdaRule, Params, PartRule};
pub use component::Component;
pub use result::Model;
