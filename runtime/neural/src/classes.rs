//! The five training-data classes of paper §4.2 (lobes.md §3.3), as parameter vectors generated
//! on the fly from a counter-based RNG keyed by (seed, class, tile, cell) — never stored.
//!
//! A themed class (haze, dust, clearcoat, inner/subcutaneous) draws a *base material* per tile
//! of 128 × 128 cells from physically informed distributions (conductor reflectivities from
//! measured metals, dielectric albedos, IORs of real dielectrics), holds it constant over the
//! tile and samples roughness densely across it: the cell column i sets the input roughness
//! r ∈ [0.02, 1], the row j interpolates the enhancement's exponent triple (p, q, s) from
//! (2.5, 1.8, 1.2) to (4, 1, 2), so a tile covers the (α_core, α_haze) manifold the Type-0 rule
//! produces. The specular colour varies per cell. The decorators follow the rules' ranges
//! (lobes.md §3), with per-cell weights standing in for the masks. The infill class draws every
//! parameter uniformly in its range (in the encoder's encoding).

use uplift_base::color::srgb_to_linear;
use uplift_engines::stack::Stack;
use uplift_base::rng::mix64;

/// Cells per tile edge.
pub const TILE: u64 = 128;

/// A training-data class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DataClass {
    Haze,
    Dust,
    Clearcoat,
    InnerSubcutaneous,
    Infill,
}

impl DataClass {
    pub const ALL: [DataClass; 5] = [DataClass::Haze, DataClass::Dust, DataClass::Clearcoat, DataClass::InnerSubcutaneous, DataClass::Infill];

    pub fn name(self) -> &'static str {
        match self {
            DataClass::Haze => "haze",
            DataClass::Dust => "dust",
            DataClass::Clearcoat => "clearcoat",
            DataClass::InnerSubcutaneous => "inner",
            DataClass::Infill => "infill",
        }
    }

    pub fn parse(name: &str) -> Result<DataClass, String> {
        Self::ALL.into_iter().find(|c| c.name() == name).ok_or_else(|| {
            format!("unknown data class `{name}` (expected one of {})", Self::ALL.map(|c| c.name()).join(", "))
        })
    }

    pub fn index(self) -> usize {
        Self::ALL.iter().position(|&c| c == self).unwrap()
    }
}

/// Uniform numbers of one keyed stream.
struct Stream {
    key: u64,
    k: u64,
}

impl Stream {
    fn new(key: u64) -> Stream {
        Stream { key: mix64(key), k: 0 }
    }
    fn u(&mut self) -> f32 {
        self.k += 1;
        ((mix64(self.key.wrapping_add(self.k)) >> 40) as f32) / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.u()
    }
    fn chance(&mut self, p: f32) -> bool {
        self.u() < p
    }
    /// A normal draw truncated to [lo, hi] (by rejection; Box–Muller).
    fn truncated_normal(&mut self, mean: f32, sd: f32, lo: f32, hi: f32) -> f32 {
        for _ in 0..64 {
            let (u1, u2) = (self.u().max(1e-7), self.u());
            let x = mean + sd * (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos();
            if (lo..=hi).contains(&x) {
                return x;
            }
        }
        mean
    }
}

/// Normal-incidence reflectivity (linear Rec.709) of measured metals (Naty Hoffman, "Physics and
/// Math of Shading", SIGGRAPH 2015 course; values also in Karis 2013 / Lagarde's charts).
const METALS: [[f32; 3]; 12] = [
    [1.000, 0.766, 0.336], // gold
    [0.972, 0.960, 0.915], // silver
    [0.955, 0.638, 0.538], // copper
    [0.913, 0.922, 0.924], // aluminium
    [0.562, 0.565, 0.578], // iron
    [0.550, 0.556, 0.554], // chromium
    [0.660, 0.609, 0.526], // nickel
    [0.542, 0.497, 0.449], // titanium
    [0.673, 0.637, 0.585], // platinum
    [0.664, 0.824, 0.850], // zinc
    [0.910, 0.778, 0.423], // brass
    [0.662, 0.655, 0.634], // cobalt
];

/// A dielectric albedo: a random hue and saturation at an sRGB value in [0.12, 0.95] (linear
/// albedos ≈ 0.013–0.89, the range of real dielectric surfaces).
fn dielectric_color(s: &mut Stream) -> [f32; 3] {
    let (h, sat, v) = (s.u(), s.u().powf(1.5) * 0.9, s.range(0.12, 0.95));
    let c = v * sat;
    let hp = h * 6.0;
    let x = c * (1.0 - ((hp % 2.0) - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [srgb_to_linear(r + m), srgb_to_linear(g + m), srgb_to_linear(b + m)]
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// (1 − d)·c + d·Y(c).
fn desaturate(c: [f32; 3], d: f32) -> [f32; 3] {
    let y = luminance(c);
    c.map(|x| (1.0 - d) * x + d * y)
}

/// The Type-0 mapping of lobes.md §3 (rows 8–10): (α_core, α_haze, w_h) from input roughness r,
/// exponents p, q, scale s and haze gain κh.
pub fn haze_mapping(r: f32, p: f32, q: f32, s: f32, kappa: f32) -> (f32, f32, f32) {
    let core = r.powf(p).clamp(0.004, 1.0);
    let haze = (s * r.powf(q)).clamp(0.004, 1.0);
    let denom = haze * haze - core * core;
    let w_vm = if denom > 1e-12 { (r.powi(4) - core * core) / denom } else { 0.0 };
    (core, haze, (kappa * w_vm).clamp(0.05, 0.6))
}

/// Which decorators a themed tile has on.
struct Decorators {
    dust: bool,
    coat: bool,
    inner: bool,
}

/// The parameter vector of cell `cell` (0 … 128² − 1) of tile `tile` of `class`.
pub fn class_parameters(stack: &Stack, class: DataClass, seed: u64, tile: u64, cell: u64) -> Vec<f32> {
    let tile_key = mix64(seed ^ ((class.index() as u64) << 58)) ^ mix64(tile.wrapping_mul(0x2545_f491_4f6c_dd1d));
    let mut cs = Stream::new(tile_key ^ mix64(cell.wrapping_add(0x51ed_27)));
    if class == DataClass::Infill {
        return stack.parameters().iter().map(|p| p.decode(cs.u())).collect();
    }
    let mut ts = Stream::new(tile_key);
    let deco = match class {
        DataClass::Haze => Decorators { dust: false, coat: false, inner: false },
        DataClass::Dust => Decorators { dust: true, coat: ts.chance(0.5), inner: false },
        DataClass::Clearcoat => Decorators { dust: false, coat: true, inner: false },
        _ => Decorators { dust: false, coat: ts.chance(2.0 / 3.0), inner: true },
    };
    // Base material (per tile).
    let metal = !deco.inner && ts.chance(0.35);
    let color = if metal {
        if ts.chance(0.2) {
            [ts.range(0.3, 0.95), ts.range(0.3, 0.95), ts.range(0.3, 0.95)]
        } else {
            let m = METALS[(ts.u() * METALS.len() as f32) as usize % METALS.len()];
            let k = ts.range(0.9, 1.05);
            m.map(|x| (x * k).min(0.99))
        }
    } else {
        dielectric_color(&mut ts)
    };
    let metalness = if metal {
        if ts.chance(0.8) { 1.0 } else { ts.range(0.5, 1.0) }
    } else if ts.chance(0.8) {
        0.0
    } else {
        ts.range(0.0, if deco.inner { 0.3 } else { 0.5 })
    };
    let gamma_g = ts.range(0.1, 1.0);
    let kappa = ts.range(1.0, 2.0);
    let eta_d = ts.truncated_normal(1.5, 0.08, 1.33, 1.8);
    // Densely sampled roughness: column → r, row → (p, q, s).
    let (i, j) = (cell % TILE, (cell / TILE) % TILE);
    let r = 0.02 + 0.98 * ((i as f32 + cs.u()) / TILE as f32);
    let t = (j as f32 + cs.u()) / TILE as f32;
    let (p, q, s) = (2.5 + 1.5 * t, 1.8 - 0.8 * t, 1.2 + 0.8 * t);
    let (core, haze, w_h) = haze_mapping(r, p, q, s, kappa);
    // Specular colour per cell; metalness transitions in a few cells.
    let spec = if cs.chance(0.2) { [cs.range(0.0, 0.99), cs.range(0.0, 0.99), cs.range(0.0, 0.99)] } else { color.map(|x| (x * cs.range(0.85, 1.15)).clamp(0.0, 0.99)) };
    let metalness = if cs.chance(0.1) { cs.u() } else { metalness };
    let edge = spec.map(|x| x.powf(gamma_g));
    // Decorators, with canonical values when off.
    let (mut w_f, mut tau_f, mut w_c, mut eta_c) = (0.0, 0.5, 0.0, 1.5);
    let (mut w_in, mut tau_in, mut scatter, mut w_sub, mut a_sub) = (0.0, 0.5, desaturate(color, 0.35), 0.0, 0.64);
    if deco.dust {
        let full = ts.range(0.4, 1.0);
        tau_f = ts.range(0.5, 1.0);
        w_f = if cs.chance(0.3) { full } else { full * cs.u() };
    }
    if deco.coat {
        eta_c = ts.range(1.45, 1.65);
        w_c = if cs.chance(0.9) { 1.0 } else { 0.0 };
    }
    if deco.inner {
        w_f = ts.range(0.3, 0.9);
        tau_f = ts.range(0.2, 0.5);
        w_in = ts.range(0.3, 1.0);
        tau_in = ts.range(0.3, 0.7);
        scatter = desaturate(color, ts.range(0.2, 0.5));
        w_sub = 1.0;
        let r_sub = ts.range(0.7, 1.0);
        a_sub = r_sub * r_sub;
    }
    let v = [
        spec[0], spec[1], spec[2], edge[0], edge[1], edge[2], metalness, core, haze, w_h, eta_d, w_f, tau_f, w_c, eta_c, w_in, tau_in, scatter[0], scatter[1],
        scatter[2], w_sub, a_sub,
    ];
    let mut row = stack.defaults();
    row[..v.len()].copy_from_slice(&v);
    row
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn haze_mapping_matches_the_worked_example() {
        // lobes.md §3: p = 3, q = 1.5, s = 1.5, κh = 1.
        for (r, core, haze, w) in [(0.2, 0.008, 0.134, 0.09), (0.4, 0.064, 0.380, 0.15), (0.6, 0.216, 0.697, 0.19)] {
            let (c, h, wh) = haze_mapping(r, 3.0, 1.5, 1.5, 1.0);
            assert!((c - core).abs() < 1e-3 && (h - haze).abs() < 1e-3 && (wh - w).abs() < 5e-3, "r {r}: {c} {h} {wh}");
        }
    }

    #[test]
    fn every_class_stays_in_range_and_is_deterministic() {
        for class in DataClass::ALL {
            for cell in (0..TILE * TILE).step_by(97) {
                let stack = Stack::builtin();
                let p = class_parameters(&stack, class, 7, cell / 13, cell);
                assert_eq!(p, class_parameters(&stack, class, 7, cell / 13, cell));
                for (x, spec) in p.iter().zip(stack.parameters()) {
                    assert!(x.is_finite() && *x >= spec.lo - 1e-6 && *x <= spec.hi + 1e-6, "{} {}: {x}", class.name(), spec.channel);
                }
            }
        }
    }
}
