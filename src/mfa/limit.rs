//! How close the E-step comes to the machine's limit: the tight kernels of [`super::estep`] (f64, and f32 for
//! the screen) are measured on the fitted model and the population, and the E-step's time is compared with
//! the time those kernels need for the same arithmetic.

use super::aecm::StageStats;
use super::component::Component;
use super::data::Data;
use super::estep::{kernel_limit_f32_on, kernel_limit_on, Blocked, KernelRate};
use serde::Serialize;

#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct LimitReport {
    /// The f64 kernel (the exact evaluations).
    pub f64: KernelRate,
    /// The f32 kernel (the screen of the first shapes).
    pub f32: KernelRate,
    /// Per stage: the kernels' time for that stage's E-step arithmetic / the E-step's time (1 = at the limit).
    pub stage_fractions: Vec<f64>,
    /// The same over all stages.
    pub fraction: f64,
}

/// Time the tight kernels would need for `flops` of E-step arithmetic, `flops_f32` of it in f32.
fn kernel_ms(flops: f64, flops_f32: f64, f64_rate: &KernelRate, f32_rate: &KernelRate) -> f64 {
    ((flops - flops_f32) / f64_rate.gflops_per_s + flops_f32 / f32_rate.gflops_per_s) / 1e6
}

/// Measures both kernels for at least `min_ms` each on `parts` (a fitted model's components) and compares
/// them with the E-step figures of `stats`.
pub fn limit_report(data: &Data, parts: &[Component], stats: &[StageStats], min_ms: f64) -> LimitReport {
    // one layout for both kernels
    let blocked = Blocked::new(data);
    let f64_rate = kernel_limit_on(&blocked, parts, min_ms);
    let f32_rate = kernel_limit_f32_on(&blocked, parts, min_ms);
    drop(blocked);
    let frac = |flops: f64, flops_f32: f64, ms: f64| {
        if ms > 0.0 {
            kernel_ms(flops, flops_f32, &f64_rate, &f32_rate) / ms
        } else {
            0.0
        }
    };
    let stage_fractions = stats.iter().map(|s| frac(s.estep_flops, s.estep_flops_f32, s.estep_ms)).collect();
    let sum = |f: fn(&StageStats) -> f64| stats.iter().map(f).sum::<f64>();
    let fraction = frac(sum(|s| s.estep_flops), sum(|s| s.estep_flops_f32), sum(|s| s.estep_ms));
    LimitReport { f64: f64_rate, f32: f32_rate, stage_fractions, fraction }
}
