//! The batch API both engines implement: a pattern kernel evaluated for `n` points given as
//! structure-of-arrays columns (geometry, interface inputs, textures), returning its output
//! columns. Column `c` of a [`Columns`] holds component `c` of every point, contiguously; this is
//! the layout of the WGSL kernel's buffers and of the generated Rust's `mx_pattern_batch`.

use uplift_compiler::kernel::GEOMETRY_STRIDE;
use uplift_compiler::PatternKernel;

/// `width` columns of `n` floats each, stored column after column (`data[c * n + i]`).
///
/// A column may be marked *uniform* ([`Columns::mark_uniform`], checked: every value equal):
/// the CPU engine then hands kernels one value for it instead of streaming `n` equal floats
/// from memory (a BSDF batch with one material and one frame is otherwise bound by memory
/// bandwidth, not by the kernel). Marks never change the values; writing a column clears its
/// mark. Equality compares values only.
#[derive(Clone, Debug, Default)]
pub struct Columns {
    n: usize,
    width: usize,
    data: Vec<f32>,
    /// Per column, when marked; empty when none is.
    uniform: Vec<bool>,
}

impl PartialEq for Columns {
    fn eq(&self, o: &Columns) -> bool {
        self.n == o.n && self.width == o.width && self.data == o.data
    }
}

impl Columns {
    /// `width` columns of `n` zeros.
    pub fn zeros(n: usize, width: usize) -> Columns {
        Columns { n, width, data: vec![0.0; n * width], uniform: Vec::new() }
    }

    /// Marks column `k` uniform if every value in it is the same (bit for bit); returns whether
    /// it did.
    pub fn mark_uniform(&mut self, k: usize) -> bool {
        let col = self.column(k);
        let same = col.iter().all(|v| v.to_bits() == col[0].to_bits());
        if same {
            self.uniform.resize(self.width, false);
            self.uniform[k] = true;
        }
        same
    }

    /// Marks every column whose values are all the same.
    pub fn mark_uniform_columns(&mut self) {
        for k in 0..self.width {
            self.mark_uniform(k);
        }
    }

    /// Whether column `k` is marked uniform.
    pub fn is_uniform(&self, k: usize) -> bool {
        self.uniform.get(k).copied().unwrap_or(false)
    }

    /// Column `k`, or its one value (a slice of length 1) if it is marked uniform: the form the
    /// CPU kernels' block loop takes (`uplift_kernels::driver::run_column_blocks`).
    pub fn column_or_uniform(&self, k: usize) -> &[f32] {
        let c = self.column(k);
        match self.is_uniform(k) {
            true => &c[..c.len().min(1)],
            false => c,
        }
    }

    /// Columns from column-major data (`data.len()` must be `n * width`).
    pub fn from_column_major(n: usize, width: usize, data: Vec<f32>) -> Result<Columns, String> {
        if data.len() != n * width {
            return Err(format!("{} floats cannot be {width} columns of {n}", data.len()));
        }
        Ok(Columns { n, width, data, uniform: Vec::new() })
    }

    /// Columns from row-major data: `rows.len() / width` rows of `width` floats. Panics when
    /// `rows.len()` is not a multiple of `width` (a caller's bug, not bad input).
    pub fn from_rows(rows: &[f32], width: usize) -> Columns {
        let n = rows.len().checked_div(width).unwrap_or(0);
        assert_eq!(n * width, rows.len(), "Columns::from_rows: {} floats are not rows of {width}", rows.len());
        let mut c = Columns::zeros(n, width);
        for (i, row) in rows.chunks_exact(width.max(1)).enumerate().take(n) {
            for (k, v) in row.iter().enumerate() {
                c.data[k * n + i] = *v;
            }
        }
        c
    }

    /// The same values row-major: point `i`'s `width` floats at `[i * width..]`.
    pub fn to_rows(&self) -> Vec<f32> {
        let mut rows = vec![0.0; self.data.len()];
        for k in 0..self.width {
            for (i, v) in self.column(k).iter().enumerate() {
                rows[i * self.width + k] = *v;
            }
        }
        rows
    }

    /// Points (rows).
    pub fn n(&self) -> usize {
        self.n
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.width
    }

    pub fn column(&self, k: usize) -> &[f32] {
        &self.data[k * self.n..(k + 1) * self.n]
    }

    pub fn column_mut(&mut self, k: usize) -> &mut [f32] {
        if let Some(u) = self.uniform.get_mut(k) {
            *u = false;
        }
        &mut self.data[k * self.n..(k + 1) * self.n]
    }

    /// Every column as a slice.
    pub fn columns(&self) -> Vec<&[f32]> {
        (0..self.width).map(|k| self.column(k)).collect()
    }

    /// Every column as a mutable slice.
    pub fn columns_mut(&mut self) -> Vec<&mut [f32]> {
        self.uniform.clear();
        let mut rest = self.data.as_mut_slice();
        let mut columns = Vec::with_capacity(self.width);
        for _ in 0..self.width {
            let (column, tail) = std::mem::take(&mut rest).split_at_mut(self.n);
            columns.push(column);
            rest = tail;
        }
        columns
    }

    /// The column-major data.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    pub fn data_mut(&mut self) -> &mut [f32] {
        self.uniform.clear();
        &mut self.data
    }

    pub fn into_data(self) -> Vec<f32> {
        self.data
    }

    /// Points `start..start + m` as columns of their own.
    pub fn slice(&self, start: usize, m: usize) -> Columns {
        let mut data = Vec::with_capacity(m * self.width);
        for k in 0..self.width {
            data.extend_from_slice(&self.column(k)[start..start + m]);
        }
        Columns { n: m, width: self.width, data, uniform: self.uniform.clone() }
    }

    /// Writes `part`'s points at `start..` of these columns.
    pub fn write_at(&mut self, start: usize, part: &Columns) {
        assert_eq!(part.width, self.width, "Columns::write_at: widths differ");
        for k in 0..self.width {
            self.column_mut(k)[start..start + part.n].copy_from_slice(part.column(k));
        }
    }
}

/// An RGBA float image bound to a kernel texture; row 0 is the top of the image. Both engines
/// bind textures this way: texel (x, y) is `rgba[4 * (y * width + x)..]`.
#[derive(Clone, Debug)]
pub struct TextureData {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<f32>,
}

impl TextureData {
    /// Checks that the data holds `width × height` RGBA texels.
    pub fn check(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 || self.rgba.len() != (self.width as usize) * (self.height as usize) * 4 {
            return Err(format!("texture data has {} floats for {}x{} RGBA", self.rgba.len(), self.width, self.height));
        }
        Ok(())
    }
}

/// One shading point's geometry; object space equals world space.
#[derive(Clone, Copy, Debug)]
pub struct Geometry {
    pub texcoord: [f32; 2],
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub tangent: [f32; 3],
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry { texcoord: [0.0; 2], position: [0.0; 3], normal: [0.0, 0.0, 1.0], tangent: [1.0, 0.0, 0.0] }
    }
}

impl Geometry {
    /// The point's [`GEOMETRY_STRIDE`] geometry components, in column order
    /// (`uplift_compiler::kernel::GEOMETRY_LAYOUT`).
    pub fn row(&self) -> [f32; GEOMETRY_STRIDE] {
        let mut r = [0.0; GEOMETRY_STRIDE];
        r[0..2].copy_from_slice(&self.texcoord);
        for (k, v) in [self.position, self.normal, self.tangent].iter().enumerate() {
            r[2 + 6 * k..5 + 6 * k].copy_from_slice(v);
            r[5 + 6 * k..8 + 6 * k].copy_from_slice(v);
        }
        r
    }

    /// The geometry columns of `n` points that all share this geometry (a constant fill, without
    /// the row-to-column transpose of [`Geometry::columns`]), every column marked uniform.
    pub fn repeated(&self, n: usize) -> Columns {
        let mut c = Columns::zeros(n, GEOMETRY_STRIDE);
        for (k, v) in self.row().into_iter().enumerate() {
            c.column_mut(k).fill(v);
        }
        c.mark_uniform_columns();
        c
    }

    /// The geometry columns of `points`.
    pub fn columns(points: &[Geometry]) -> Columns {
        let rows: Vec<f32> = points.iter().flat_map(|g| g.row()).collect();
        Columns::from_rows(&rows, GEOMETRY_STRIDE)
    }
}

pub use uplift_kernels::KernelShape;

/// The most graph values a kernel the engines build may have (issue 46). The engines hand a
/// kernel's code to a compiler whose time grows faster than linearly with one function's length
/// (lavapipe's NIR passes for wgpu, LLVM for the CPU engine's runner): a 4,096-value chain builds
/// in 1.7 s on lavapipe, a 20,000-value one in 65 s. The largest shipped kernel, the 8-lobe
/// stack, has 70; MaterialX's example materials have a few hundred.
pub const MAX_BUILD_VALUES: usize = 4096;

/// Refuses a kernel too large for the engines to build in reasonable time ([`MAX_BUILD_VALUES`]),
/// before any build starts, with a clear message (`uplift compile` still emits it).
pub fn check_build_size(kernel: &PatternKernel) -> Result<(), String> {
    let n = kernel.graph.values.len();
    match n <= MAX_BUILD_VALUES {
        true => Ok(()),
        false => Err(format!(
            "the kernel has {n} graph values; the engines build kernels of up to {MAX_BUILD_VALUES} (their shader and Rust compilers slow down faster than linearly past that: a 20,000-value chain takes over a minute). `uplift compile` still emits its code"
        )),
    }
}

/// A compiled kernel's shape: its input and output columns and its textures.
pub fn kernel_shape(kernel: &PatternKernel) -> KernelShape {
    KernelShape { input_columns: kernel.input_stride, output_columns: kernel.output_stride, texture_count: kernel.textures.len() }
}

/// What a pattern kernel reads for a batch of points.
#[derive(Clone, Debug, Default)]
pub struct PatternBatch {
    /// [`GEOMETRY_STRIDE`] columns.
    pub geometry: Columns,
    /// The kernel's `input_stride` columns (interface inputs).
    pub inputs: Columns,
    /// One image per kernel texture, in the kernel's order.
    pub textures: Vec<TextureData>,
    /// K, the batch's grouped layout: consecutive runs of K points share every input but the
    /// per-point ones of a BSDF kernel (`wl` in eval and pdf, `u` in sample), and all their
    /// geometry — one material and one view, K light directions. A promise of the caller
    /// (1: no grouping); the CPU engine runs such batches through a kernel's dependence-split
    /// form when it ships one (`uplift_kernels::shipped::Grouped`), other engines ignore it.
    pub points_per_group: usize,
}

impl PatternBatch {
    /// A batch from per-point geometry and row-major interface inputs (`input_rows` holds
    /// `points.len()` rows of `input_stride` floats).
    pub fn from_rows(points: &[Geometry], input_rows: &[f32], input_stride: usize, textures: Vec<TextureData>) -> PatternBatch {
        let inputs = if input_stride == 0 { Columns::zeros(points.len(), 0) } else { Columns::from_rows(input_rows, input_stride) };
        PatternBatch { geometry: Geometry::columns(points), inputs, textures, points_per_group: 1 }
    }

    /// Points in the batch.
    pub fn n(&self) -> usize {
        self.geometry.n()
    }

    /// Checks the batch against `kernel`'s interface; returns the number of points.
    pub fn check(&self, kernel: &PatternKernel) -> Result<usize, String> {
        self.check_shape(&kernel_shape(kernel))
    }

    /// Checks the batch against a kernel's shape; returns the number of points.
    pub fn check_shape(&self, shape: &KernelShape) -> Result<usize, String> {
        let n = self.geometry.n();
        if self.geometry.width() != GEOMETRY_STRIDE {
            return Err(format!("the batch has {} geometry columns; kernels read {GEOMETRY_STRIDE}", self.geometry.width()));
        }
        if self.inputs.width() != shape.input_columns || (shape.input_columns > 0 && self.inputs.n() != n) {
            return Err(format!(
                "the batch has {} input columns of {} points; the kernel reads {} columns of {n}",
                self.inputs.width(),
                self.inputs.n(),
                shape.input_columns
            ));
        }
        if self.textures.len() != shape.texture_count {
            return Err(format!("the kernel reads {} textures, {} given", shape.texture_count, self.textures.len()));
        }
        for t in &self.textures {
            t.check()?;
        }
        Ok(n)
    }
}

/// An engine that evaluates pattern kernels over batches: the CPU engine (generated Rust) and
/// the wgpu engine (generated WGSL) implement it, and tests hold them to the same results.
pub trait PatternEngine {
    /// A short description of the engine and its device.
    fn describe(&self) -> String;

    /// Evaluates `kernel` for every point of `batch`; returns `kernel.output_stride` columns.
    fn run_pattern(&self, kernel: &PatternKernel, batch: &PatternBatch) -> Result<Columns, String>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_columns_round_trip() {
        let rows: Vec<f32> = (0..12).map(|v| v as f32).collect();
        let c = Columns::from_rows(&rows, 3);
        assert_eq!((c.n(), c.width()), (4, 3));
        assert_eq!(c.column(1), &[1.0, 4.0, 7.0, 10.0]);
        assert_eq!(c.to_rows(), rows);
        let part = c.slice(1, 2);
        assert_eq!(part.column(2), &[5.0, 8.0]);
        let mut z = Columns::zeros(4, 3);
        z.write_at(1, &part);
        assert_eq!(z.column(0), &[0.0, 3.0, 6.0, 0.0]);
        z.columns_mut()[2][3] = 9.0;
        assert_eq!(z.column(2), &[0.0, 5.0, 8.0, 9.0]);
        assert_eq!(Columns::zeros(0, 2).columns_mut().len(), 2);
    }

    #[test]
    fn geometry_row_follows_the_kernel_layout() {
        let g = Geometry { texcoord: [0.5, 0.25], position: [1.0, 2.0, 3.0], normal: [0.0, 1.0, 0.0], tangent: [1.0, 0.0, 0.0] };
        for (prop, offset) in uplift_compiler::kernel::GEOMETRY_LAYOUT {
            let want: &[f32] = match prop.field() {
                "texcoord" => &g.texcoord,
                f if f.starts_with("position") => &g.position,
                f if f.starts_with("normal") => &g.normal,
                _ => &g.tangent,
            };
            assert_eq!(&g.row()[offset..offset + want.len()], want, "{}", prop.field());
        }
    }
}
