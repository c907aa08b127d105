//! Colour-space transfer functions shared by the runtime: texture loading, the procedural PBR
//! sets and the training-data classes decode sRGB-encoded values through one function.

/// The sRGB EOTF (IEC 61966-2-1): an encoded value in [0, 1] to linear.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_reference_points() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // 0.5 encodes 0.21404 (IEC 61966-2-1), and the two pieces meet at 0.04045.
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        let (a, b) = (0.04045f32 / 12.92, ((0.04045f32 + 0.055) / 1.055).powf(2.4));
        assert!((a - b).abs() < 1e-6);
    }
}
