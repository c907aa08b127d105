//! `fit.json`: the record of one latent fit — the decoder, the fitting settings, the paper's
//! Eq. 3 loss per term before (encoder only) and after fitting, and what the energy bound did —
//! as a typed serde struct with a format version. Losses are kept to 6 decimals and times to
//! 0.01 s, as the report prints them.

use serde::{Deserialize, Serialize};

/// The fit.json format this build writes (0: a file that predates the field).
pub const FIT_FORMAT: u32 = 1;

/// Eq. 3 and its three terms (f, T, R).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LossRecord {
    pub total: f64,
    pub f: f64,
    #[serde(rename = "T")]
    pub t: f64,
    #[serde(rename = "R")]
    pub r: f64,
}

impl LossRecord {
    /// A record of the four figures, each rounded to 6 decimals.
    pub fn new(total: f64, f: f64, t: f64, r: f64) -> LossRecord {
        LossRecord { total: round_to(total, 6), f: round_to(f, 6), t: round_to(t, 6), r: round_to(r, 6) }
    }
}

/// What the energy bound did to a fit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyRecord {
    pub groups: usize,
    pub over_before: usize,
    pub over_after: usize,
    pub worst_excess_before: f64,
    pub worst_excess_after: f64,
    pub steps: u64,
}

impl EnergyRecord {
    /// A record with the excesses rounded to 5 decimals.
    pub fn new(groups: usize, over_before: usize, over_after: usize, worst_before: f64, worst_after: f64, steps: u64) -> EnergyRecord {
        EnergyRecord { groups, over_before, over_after, worst_excess_before: round_to(worst_before, 5), worst_excess_after: round_to(worst_after, 5), steps }
    }
}

/// fit.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitRecord {
    /// [`FIT_FORMAT`] when written by this build; 0 for files that predate the field.
    #[serde(default)]
    pub format: u32,
    /// The weights file the latents were fitted against.
    pub decoder: String,
    pub texels: usize,
    /// Texel groups fitted (texels with equal quantised parameters share latents).
    pub groups: usize,
    pub steps: u64,
    pub directions: usize,
    pub levels: u32,
    pub seconds: f64,
    pub eq3_encoder_only: LossRecord,
    pub eq3_fitted: LossRecord,
    pub eq3_fitted_before_energy_bound: LossRecord,
    pub fitting_loss_first_step: LossRecord,
    pub fitting_loss_last_step: LossRecord,
    /// Absent when fitting ran without the energy bound (`null` in records before issue 46).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_bound: Option<EnergyRecord>,
}

/// `x` rounded to `decimals` decimals, exactly as `format!("{x:.decimals$}")` prints it.
pub fn round_to(x: f64, decimals: usize) -> f64 {
    format!("{x:.decimals$}").parse().unwrap_or(x)
}
