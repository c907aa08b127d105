//! The 22 parameters of the non-diffuse component (lobes.md §3), in the order of the
//! `uplift_stack` node's inputs, with their ranges and how the encoder sees them. One table
//! serves the data generator (ranges for the infill class), the encoder (normalisation), the
//! fitter (`params.exr` channel names) and the kernels (input name and component).

/// Parameters per texel.
pub const PARAMETERS: usize = 22;

/// How a parameter is mapped to the encoder's [0, 1] input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// (x − lo) / (hi − lo).
    Linear,
    /// (√x − √lo) / (√hi − √lo): GGX alphas, so the encoder sees perceptual roughness.
    Sqrt,
}

/// One scalar parameter.
#[derive(Clone, Copy, Debug)]
pub struct Parameter {
    /// The `uplift_stack` input it belongs to.
    pub input: &'static str,
    /// Its component in that input.
    pub component: usize,
    /// Its channel in `params.exr` (`input` or `input.R/G/B`).
    pub channel: &'static str,
    pub lo: f32,
    pub hi: f32,
    pub encoding: Encoding,
}

const fn p(input: &'static str, component: usize, channel: &'static str, lo: f32, hi: f32, encoding: Encoding) -> Parameter {
    Parameter { input, component, channel, lo, hi, encoding }
}

use Encoding::{Linear, Sqrt};

/// The 22 parameters, in `uplift_stack` input order (lobes.md §3 table, rows 1–22).
pub const PARAMETER_TABLE: [Parameter; PARAMETERS] = [
    p("reflectivity", 0, "reflectivity.R", 0.0, 0.99, Linear),
    p("reflectivity", 1, "reflectivity.G", 0.0, 0.99, Linear),
    p("reflectivity", 2, "reflectivity.B", 0.0, 0.99, Linear),
    p("edge_color", 0, "edge_color.R", 0.0, 1.0, Linear),
    p("edge_color", 1, "edge_color.G", 0.0, 1.0, Linear),
    p("edge_color", 2, "edge_color.B", 0.0, 1.0, Linear),
    p("metalness", 0, "metalness", 0.0, 1.0, Linear),
    p("core_roughness", 0, "core_roughness", 0.004, 1.0, Sqrt),
    p("haze_roughness", 0, "haze_roughness", 0.004, 1.0, Sqrt),
    p("haze_weight", 0, "haze_weight", 0.05, 0.6, Linear),
    p("specular_ior", 0, "specular_ior", 1.33, 1.8, Linear),
    p("fuzz_weight", 0, "fuzz_weight", 0.0, 1.0, Linear),
    p("fuzz_thickness", 0, "fuzz_thickness", 0.02, 1.0, Linear),
    p("coat_weight", 0, "coat_weight", 0.0, 1.0, Linear),
    p("coat_ior", 0, "coat_ior", 1.45, 1.65, Linear),
    p("inner_weight", 0, "inner_weight", 0.0, 1.0, Linear),
    p("inner_thickness", 0, "inner_thickness", 0.02, 1.0, Linear),
    p("scatter_color", 0, "scatter_color.R", 0.0, 1.0, Linear),
    p("scatter_color", 1, "scatter_color.G", 0.0, 1.0, Linear),
    p("scatter_color", 2, "scatter_color.B", 0.0, 1.0, Linear),
    p("subcutaneous_weight", 0, "subcutaneous_weight", 0.0, 1.0, Linear),
    p("subcutaneous_roughness", 0, "subcutaneous_roughness", 0.4, 1.0, Linear),
];

/// Index of a named parameter in [`PARAMETER_TABLE`] (by its channel name).
pub fn index_of(channel: &str) -> Option<usize> {
    PARAMETER_TABLE.iter().position(|p| p.channel == channel)
}

impl Parameter {
    /// The encoder's input for value `x` (not clamped: values outside the range stay visible).
    pub fn encode(&self, x: f32) -> f32 {
        match self.encoding {
            Encoding::Linear => (x - self.lo) / (self.hi - self.lo),
            Encoding::Sqrt => (x.max(0.0).sqrt() - self.lo.sqrt()) / (self.hi.sqrt() - self.lo.sqrt()),
        }
    }

    /// The value at encoded position `t` ∈ [0, 1] (uniform draws for the infill class).
    pub fn decode(&self, t: f32) -> f32 {
        match self.encoding {
            Encoding::Linear => self.lo + t * (self.hi - self.lo),
            Encoding::Sqrt => {
                let s = self.lo.sqrt() + t * (self.hi.sqrt() - self.lo.sqrt());
                s * s
            }
        }
    }
}

/// Encodes rows of 22 parameters for the encoder.
pub fn encode_rows(params: &[f32], out: &mut [f32]) {
    assert_eq!(params.len(), out.len());
    for (row, enc) in params.chunks_exact(PARAMETERS).zip(out.chunks_exact_mut(PARAMETERS)) {
        for ((x, e), p) in row.iter().zip(enc.iter_mut()).zip(&PARAMETER_TABLE) {
            *e = p.encode(*x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_follows_the_uplift_stack_inputs() {
        // Each input's components are consecutive, starting at 0.
        let mut previous = "";
        let mut next = 0;
        for p in &PARAMETER_TABLE {
            if p.input != previous {
                previous = p.input;
                next = 0;
            }
            assert_eq!(p.component, next, "{}", p.channel);
            next += 1;
            assert!(p.lo < p.hi);
            assert!((p.decode(p.encode(0.5 * (p.lo + p.hi))) - 0.5 * (p.lo + p.hi)).abs() < 1e-6);
            assert_eq!(index_of(p.channel).map(|i| PARAMETER_TABLE[i].channel), Some(p.channel));
        }
    }
}
