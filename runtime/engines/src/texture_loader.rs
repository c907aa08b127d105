//! Loading a kernel's texture files (PNG and JPEG, through the `image` crate) into the RGBA
//! float [`TextureData`] the engines bind. 8-bit channels become `v / 255`, 16-bit `v / 65535`;
//! row 0 is the top of the image. The colour space recorded on the binding decides the
//! conversion of RGB to linear (alpha is never converted):
//! * names with an sRGB transfer (`srgb_texture`, `srgb_displayp3`, any other name containing
//!   `srgb` that does not start with `lin_`): the sRGB EOTF;
//! * `g22_rec709`, `adobergb`: a 2.2 (Adobe RGB: 563/256) power; `g18_rec709`: a 1.8 power;
//! * anything else (`lin_rec709`, `acescg`, no colour space, unknown names): already linear.
//!
//! Only the transfer function is applied; primaries are not converted.

use crate::batch::TextureData;
use uplift_base::color::srgb_to_linear;
use std::path::Path;

/// The transfer function of a MaterialX colour space name, as applied by [`load_texture`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transfer {
    Linear,
    Srgb,
    Gamma(f32),
}

impl Transfer {
    pub fn of(colorspace: Option<&str>) -> Transfer {
        let Some(name) = colorspace.map(|c| c.trim().to_ascii_lowercase()) else { return Transfer::Linear };
        match name.as_str() {
            "g22_rec709" => Transfer::Gamma(2.2),
            "g18_rec709" => Transfer::Gamma(1.8),
            "adobergb" => Transfer::Gamma(563.0 / 256.0),
            n if n.contains("srgb") && !n.starts_with("lin_") => Transfer::Srgb,
            _ => Transfer::Linear,
        }
    }

    /// Converts one encoded colour channel to linear.
    pub fn to_linear(self, v: f32) -> f32 {
        match self {
            Transfer::Linear => v,
            Transfer::Srgb => srgb_to_linear(v),
            Transfer::Gamma(g) => v.max(0.0).powf(g),
        }
    }
}


/// Reads an image file as linear RGBA floats; errors name the file.
pub fn load_texture(path: &Path, colorspace: Option<&str>) -> Result<TextureData, String> {
    let reader = image::ImageReader::open(path)
        .map_err(|e| format!("{}: cannot read texture: {e}", path.display()))?
        .with_guessed_format()
        .map_err(|e| format!("{}: cannot read texture: {e}", path.display()))?;
    let image = reader.decode().map_err(|e| format!("{}: cannot decode texture (PNG and JPEG are supported): {e}", path.display()))?;
    let rgba = image.to_rgba32f();
    let (width, height) = rgba.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("{}: the texture is empty ({width}x{height})", path.display()));
    }
    let transfer = Transfer::of(colorspace);
    let mut data = rgba.into_raw();
    if transfer != Transfer::Linear {
        for px in data.chunks_mut(4) {
            for c in &mut px[..3] {
                *c = transfer.to_linear(*c);
            }
        }
    }
    Ok(TextureData { width, height, rgba: data })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_space_names() {
        assert_eq!(Transfer::of(Some("srgb_texture")), Transfer::Srgb);
        assert_eq!(Transfer::of(Some("srgb_displayp3")), Transfer::Srgb);
        assert_eq!(Transfer::of(Some("lin_rec709")), Transfer::Linear);
        assert_eq!(Transfer::of(Some("lin_srgb")), Transfer::Linear);
        assert_eq!(Transfer::of(None), Transfer::Linear);
        assert_eq!(Transfer::of(Some("g22_rec709")), Transfer::Gamma(2.2));
    }

    #[test]
    fn srgb_eotf() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.21404114).abs() < 1e-6);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-9);
    }

    #[test]
    fn missing_file_is_named() {
        let e = load_texture(Path::new("/nonexistent/tex.png"), None).unwrap_err();
        assert!(e.starts_with("/nonexistent/tex.png: cannot read texture"), "{e}");
    }
}
