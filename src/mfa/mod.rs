//! The constrained mixture of factor analyzers (paper sections 3-4) and its fit: the first room. It knows
//! nothing of how parts are decided ([`crate::parts`] does that, calling in here).
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
//! - [`result`]: the fitted [`Model`]: labels (eq 20), latent shape (eq 21), reconstruction (eq 22).
//! - [`limit`]: the E-step's speed against the machine's limit (tight kernels, measured).

pub mod aecm;
pub mod cm;
pub mod component;
pub mod data;
pub mod estep;
pub mod init;
pub mod limit;
pub mod params;
pub mod result;
pub mod squarem;

pub use component::Component;
pub use params::{
    Algorithm1Params, DistinctParams, FitStart, FlatParams, InFit, LambdaRule, Params, PartRule, RunParams,
    ThresholdParams, TreeParams,
};
pub use result::Model;
