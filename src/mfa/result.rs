//! The fitted model: labels (eq 20), latent reference shape (eq 21), reconstruction (eq 22), residuals, RMSE.
//! Everything is in unit-box coordinates (see [`crate::mesh::Normalization`] to go back).

use super::component::Component;
use crate::geometry::{add, sub, Vec3};
use crate::mesh::Population;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub n_shapes: usize,
    pub n_vertices: usize,
    /// One component per rigid part.
    pub parts: Vec<Component>,
    /// I_j = argmax_k P(k | h_j) (eq 20), one per vertex.
    pub labels: Vec<u32>,
    /// v_j^ref = Λ_{I_j} E[z | h_j, Θ_{I_j}] (eq 21), one per vertex.
    pub latent: Vec<Vec3>,
    /// Log-likelihood (eq 10) after every AECM iteration of the run that produced this model.
    pub log_likelihood: Vec<f64>,
    /// AECM iterations of that run.
    pub iterations: usize,
    /// Whether |ΔL| / n_v fell below the tolerance before the iteration cap.
    pub converged: bool,
}

impl Model {
    pub fn n_parts(&self) -> usize {
        self.parts.len()
    }

    /// Shape `i` rebuilt from the latent shape: R^i_{I_j} v_j^ref + b^i_{I_j} (eq 22).
    pub fn reconstruct(&self, shape: usize) -> Vec<Vec3> {
        self.latent.iter().zip(&self.labels).map(|(&v, &l)| self.parts[l as usize].place(shape, v)).collect()
    }

    /// The latent shape with every part moved to where it is in shape i (v_j^ref + b^i_{l_j}) but not turned:
    /// the parts of eq 21 are all centred on the origin, on top of each other; this spreads them out to be seen.
    pub fn latent_placed(&self, shape: usize) -> Vec<Vec3> {
        self.latent
            .iter()
            .zip(&self.labels)
            .map(|(&v, &l)| add(v, self.parts[l as usize].translations[shape]))
            .collect()
    }

    /// Residuals ε_j^i = v_j^i - (R^i v_j^ref + b^i): the "muscle" motion, per shape and vertex.
    pub fn residuals(&self, pop: &Population) -> Vec<Vec<Vec3>> {
        (0..self.n_shapes)
            .map(|i| self.reconstruct(i).iter().zip(pop.shape(i).iter()).map(|(&r, v)| sub(v, r)).collect())
            .collect()
    }

    /// Root mean square of |ε_j^i| over all vertices and shapes (unit-box units).
    pub fn rmse(&self, pop: &Population) -> f64 {
        let mut s = 0.0;
        for i in 0..self.n_shapes {
            for (r, v) in self.reconstruct(i).iter().zip(pop.shape(i).iter()) {
                let d = sub(v, *r);
                s += d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            }
        }
        (s / (self.n_shapes * self.n_vertices).max(1) as f64).sqrt()
    }

    /// Per-vertex error |ε_j^i| of shape i (unit-box units), for error colour maps.
    pub fn vertex_errors(&self, pop: &Population, shape: usize) -> Vec<f64> {
        self.reconstruct(shape)
            .iter()
            .zip(pop.shape(shape).iter())
            .map(|(r, v)| crate::geometry::norm(sub(v, *r)))
            .collect()
    }

    /// P(k | h_j) for every part k (eq 12) for one vertex.
    pub fn responsibilities(&self, pop: &Population, vertex: usize) -> Vec<f64> {
        let h: Vec<Vec3> = pop.track(vertex);
        let logs: Vec<f64> = self.parts.iter().map(|c| c.log_weighted_density(&c.woodbury(), &h)).collect();
        let mx = logs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let e: Vec<f64> = logs.iter().map(|l| (l - mx).exp()).collect();
        let z: f64 = e.iter().sum();
        e.iter().map(|v| v / z).collect()
    }
}
