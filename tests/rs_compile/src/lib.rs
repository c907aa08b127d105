//! Compiles every Rust snapshot (`tests/out/rs/*.rs`, written by the compiler's snapshot test)
//! as a module of this crate, so the generated Rust is checked by rustc and not only as text.
//! `build.rs` lists the snapshots; the tests in `tests/` run some kernels against closed forms.

/// A kernel of the table: its column counts and its batch entry point, on row-major buffers
/// (the tests' layout; [`with_rows`] turns them into the kernel's columns and back).
pub struct Kernel {
    pub name: &'static str,
    pub input_stride: usize,
    pub output_stride: usize,
    pub batch: fn(&[f32], &[f32], &mut [f32], &Checker),
    /// Textures the kernel reads (`TEXTURE_COUNT`).
    pub texture_count: usize,
    /// The same batch function with any [`Textures`] (dynamically dispatched).
    pub batch_with: fn(&[f32], &[f32], &mut [f32], &dyn Textures),
}

/// Textures for any snapshot kernel: every module's `MxTextures` is implemented for each type
/// implementing this trait (same contract: texel indices may lie outside the texture and read
/// zero there; row 0 is the first row of the image; a missing texture has dimensions 0 × 0).
pub trait Textures {
    fn load(&self, texture: usize, x: i32, y: i32) -> glam::Vec4;
    fn dimensions(&self, texture: usize) -> glam::UVec2;
}

impl Textures for Checker {
    fn load(&self, texture: usize, x: i32, y: i32) -> glam::Vec4 {
        Checker::load(self, texture, x, y)
    }
    fn dimensions(&self, texture: usize) -> glam::UVec2 {
        Checker::dimensions(self, texture)
    }
}

/// A procedural stand-in for the runtime's textures: texture `k` is `width(k)` × 2 texels and
/// texel (x, y) is `(x, y, k, 1)`; coordinates outside the texture read zero, as wgpu's robust
/// access does. Texture indices at or past `present` are missing (dimensions 0 × 0).
#[derive(Clone, Copy, Debug)]
pub struct Checker {
    pub present: usize,
}

impl Checker {
    /// Width of texture `k`.
    pub fn width(k: usize) -> u32 {
        4 + k as u32
    }

    pub fn dimensions(&self, texture: usize) -> glam::UVec2 {
        if texture < self.present {
            glam::UVec2::new(Self::width(texture), 2)
        } else {
            glam::UVec2::ZERO
        }
    }

    pub fn load(&self, texture: usize, x: i32, y: i32) -> glam::Vec4 {
        let d = self.dimensions(texture);
        if x < 0 || y < 0 || x as u32 >= d.x || y as u32 >= d.y {
            return glam::Vec4::ZERO;
        }
        glam::Vec4::new(x as f32, y as f32, texture as f32, 1.0)
    }
}

use uplift_engines::batch::Columns;

/// Runs `f`, a batch over structure-of-arrays columns (a generated `mx_pattern_batch`), on
/// row-major buffers: `geom` rows of `geometry_columns` floats, `inputs` rows of
/// `input_columns`, `outputs` rows of `output_columns` (the number of points is
/// `outputs.len() / output_columns`).
pub fn with_rows(
    geom: &[f32],
    inputs: &[f32],
    outputs: &mut [f32],
    (geometry_columns, input_columns, output_columns): (usize, usize, usize),
    f: impl FnOnce(&[&[f32]], &[&[f32]], &mut [&mut [f32]]),
) {
    let g = Columns::from_rows(geom, geometry_columns);
    let x = if input_columns == 0 { Columns::zeros(g.n(), 0) } else { Columns::from_rows(inputs, input_columns) };
    let mut o = Columns::zeros(outputs.len() / output_columns, output_columns);
    f(&g.columns(), &x.columns(), &mut o.columns_mut());
    outputs.copy_from_slice(&o.to_rows());
}

/// `$k::mx_pattern_batch` on row-major buffers (see [`with_rows`]).
#[macro_export]
macro_rules! batch_rows {
    ($k:ident, $geom:expr, $inputs:expr, $out:expr, $tex:expr) => {
        $crate::with_rows($geom, $inputs, $out, ($k::GEOMETRY_COLUMNS, $k::INPUT_COLUMNS, $k::OUTPUT_COLUMNS), |g, x, o| $k::mx_pattern_batch(g, x, o, $tex))
    };
}

// The generated code is meant to compile without rustc warnings (it allows the naming lints itself
// where it keeps naga's names); clippy's style lints are not its concern.
#[allow(clippy::all)]
mod generated {
    use super::{Kernel, Textures};
    include!(concat!(env!("OUT_DIR"), "/kernels.rs"));
}

pub use generated::*;

/// The seeded generator the differential and oracle tests share: the runtime's SplitMix64.
pub use uplift_base::rng::SplitMix64 as Rng;

/// Random unit vectors for the tests' geometry.
pub trait UnitVector {
    /// A uniformly distributed unit vector (rejection sampling in the unit ball).
    fn unit_vector(&mut self) -> [f32; 3];
}

impl UnitVector for Rng {
    fn unit_vector(&mut self) -> [f32; 3] {
        loop {
            let v = [self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0)];
            let l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if (0.01..=1.0).contains(&l2) {
                let l = l2.sqrt();
                return [v[0] / l, v[1] / l, v[2] / l];
            }
        }
    }
}
