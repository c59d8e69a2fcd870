//! The parameters of one fit's runs: the hyperparameters and what the fit measured of its population. The
//! variance floor follows the population's size ([`Params::variance_floor`]); the scale is measured once per
//! fit, on the whole population, and every run of that fit (on a subset, a coarse mesh) keeps it. It is the
//! fit's state, not a parameter: nobody sets it.

use super::{Params, REFERENCE_SQUARED_RADIUS};

/// [`Params`] with the floor's scale of the fit they run in. Derefs to the parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct RunParams {
    params: Params,
    /// The population's mean squared radius over [`REFERENCE_SQUARED_RADIUS`] (1 when it is not a positive
    /// finite number).
    floor_scale: f64,
}

impl std::ops::Deref for RunParams {
    type Target = Params;
    fn deref(&self) -> &Params {
        &self.params
    }
}

impl RunParams {
    /// `params` for a population of mean squared radius `mean_squared_radius` (unit box).
    pub fn new(params: &Params, mean_squared_radius: f64) -> RunParams {
        let scale = mean_squared_radius / REFERENCE_SQUARED_RADIUS;
        let floor_scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        RunParams { params: params.clone(), floor_scale }
    }

    /// The parameters, without the fit's state.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Other parameters in the same fit (the floor's scale kept).
    pub fn with(&self, params: Params) -> RunParams {
        RunParams { params, floor_scale: self.floor_scale }
    }

    /// These parameters changed by `change`, in the same fit.
    pub fn map(&self, change: impl FnOnce(&mut Params)) -> RunParams {
        let mut params = self.params.clone();
        change(&mut params);
        self.with(params)
    }

    /// The variance floor in this population's unit box: `variance_floor` scaled by the population's size.
    pub fn floor(&self) -> f64 {
        self.params.variance_floor * self.floor_scale
    }

    /// [`Params::for_refinement`], in the same fit.
    pub fn for_refinement(&self) -> RunParams {
        self.with(self.params.for_refinement())
    }

    /// [`Params::at_loose_tolerance`], in the same fit.
    pub fn at_loose_tolerance(&self) -> RunParams {
        self.with(self.params.at_loose_tolerance())
    }
}

/// Parameters a run can take: [`Params`] alone (a run on its own: the floor is scaled by the data it runs on)
/// or [`RunParams`] (a run inside a fit: the fit's scale, whatever data the run is on).
pub trait InFit {
    /// The parameters of a run on data of mean squared radius `mean_squared_radius()` (measured only when
    /// needed).
    fn in_fit(&self, mean_squared_radius: impl FnOnce() -> f64) -> RunParams;
}

impl InFit for Params {
    fn in_fit(&self, mean_squared_radius: impl FnOnce() -> f64) -> RunParams {
        RunParams::new(self, mean_squared_radius())
    }
}

impl InFit for RunParams {
    fn in_fit(&self, _: impl FnOnce() -> f64) -> RunParams {
        self.clone()
    }
}
