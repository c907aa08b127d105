//! The directional-albedo tables of the pbrlib closure library, computed by the project's own
//! quasi-Monte-Carlo integrator (`uplift tables -o DIR` writes them bit-for-bit). They are
//! checked in as `mtlx/libraries/pbrlib/wgsl/albedo_tables.wgsl` (WGSL `const` arrays, read by
//! albedo_lookup.wgsl); docs/albedo-tables.md documents each grid and its measured error.
//!
//! Tables (axes in [`Axis`]; the GGX view and ᾱ axes are logarithmic, 32 nodes each):
//! - `ggx_ess` [ᾱ 32][μ 32]: GGX single scattering with F = 1 (energy compensation);
//! - `ggx_moments` [ᾱ 32][μ 32][16]: the weights of 16 hat functions of v·h (nodes
//!   c_j = (j/15)²), so that any Fresnel curve's albedo is Σ_j W_j F(c_j) — conductors,
//!   generalized Schlick (the split pair of Schlick is its special case);
//! - `ggx_film_moments` [ᾱ 32][μ 32][32]: the same for 32 hat functions at nodes c_j = j/31,
//!   uniform in v·h, for curves that oscillate with angle (the Airy reflectance of a thin film);
//! - `ggx_dielectric` [q 32][ᾱ 32][μ 32]: exact dielectric Fresnel for η ∈ [1, 3],
//!   q = (η−1)/(η+1) on the IOR axis t = √(2q);
//! - `ggx_dielectric_inside` [q 32][ᾱ 32][μ 32]: the same for η ∈ [⅓, 1] (light inside the
//!   denser medium, total internal reflection included), on the axis of |q| = (1−η)/(1+η), so
//!   that node k holds the relative IOR 1/η_k of the outside table's node k;
//! - `sheen_conty_kulla`, `oren_nayar`, `burley` [t 32][μ 32], t = roughness ∈ [0, 1].

pub mod errors;
pub mod qmc;
pub mod reference;

use rayon::prelude::*;
use reference::*;
use std::fmt::Write;

pub const VIEW_NODES: usize = 32;
pub const ROUGHNESS_NODES: usize = 32;
pub const IOR_NODES: usize = 32;
pub const FRESNEL_NODES: usize = 16;
/// Nodes of the thin-film moments, uniform in v·h.
pub const FILM_FRESNEL_NODES: usize = 32;
/// Format version of the generated file (bump when layout or grids change).
pub const FORMAT_VERSION: u32 = 3;
/// Hammersley points per node: GGX tables (visible-normal sampling) and the cosine-sampled
/// diffuse and sheen tables.
pub const GGX_SAMPLES: u32 = 4096;
pub const COSINE_SAMPLES: u32 = 16384;

/// The scale of the logarithmic axes: t = ln(1 + v/ε) / ln(1 + 1/ε) is logarithmic for
/// v ≫ ε... ≪ 1 and close to linear near 1.
pub const LOG_AXIS_SCALE: f64 = 0.01;

/// How a table axis maps a quantity to t ∈ [0, 1] (nodes are uniform in t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis {
    /// t = ln(1 + v/ε) / ln(1 + 1/ε), ε = 0.01: GGX view and roughness axes (near grazing the
    /// albedo depends on the ratio α/μ), the sheen view axis.
    Log,
    /// t = 1 − (2/π)·acos(v): the view axis of the diffuse tables (smooth in θ at normal
    /// incidence, where Oren–Nayar varies with sin θ).
    Angle,
    /// t = √v: the sheen roughness axis.
    Sqrt,
    /// t = v.
    Linear,
    /// t = √(2q), q = (η − 1)/(η + 1): η ∈ [1, 3].
    Ior,
}

impl Axis {
    pub fn coordinate(self, v: f64) -> f64 {
        match self {
            Axis::Log => ((1.0 + v.clamp(0.0, 1.0) / LOG_AXIS_SCALE).ln() / (1.0 + 1.0 / LOG_AXIS_SCALE).ln()).clamp(0.0, 1.0),
            Axis::Angle => 1.0 - v.clamp(0.0, 1.0).acos() * std::f64::consts::FRAC_2_PI,
            Axis::Sqrt => v.clamp(0.0, 1.0).sqrt(),
            Axis::Linear => v.clamp(0.0, 1.0),
            Axis::Ior => (2.0 * ((v - 1.0) / (v + 1.0)).max(0.0)).min(1.0).sqrt(),
        }
    }

    /// The quantity at coordinate t (the inverse of `coordinate`).
    pub fn value(self, t: f64) -> f64 {
        match self {
            Axis::Log => LOG_AXIS_SCALE * ((1.0 + 1.0 / LOG_AXIS_SCALE).powf(t) - 1.0),
            Axis::Angle => ((1.0 - t) * std::f64::consts::FRAC_PI_2).cos(),
            Axis::Sqrt => t * t,
            Axis::Linear => t,
            Axis::Ior => {
                let q = 0.5 * t * t;
                (1.0 + q) / (1.0 - q)
            }
        }
    }
}

/// The axes of the GGX tables (view μ, ᾱ, η) and of the 2-D diffuse and sheen tables.
pub const GGX_VIEW: Axis = Axis::Log;
pub const GGX_ROUGHNESS: Axis = Axis::Log;
pub const GGX_IOR: Axis = Axis::Ior;

/// μ as integrated at a view node (never exactly 0).
pub fn view_mu(axis: Axis, t: f64) -> f64 {
    axis.value(t).max(1e-7)
}

/// GGX alpha at roughness coordinate t.
pub fn ggx_alpha(t: f64) -> f64 {
    GGX_ROUGHNESS.value(t).max(1e-8)
}

/// η at IOR coordinate t.
pub fn ior_eta(t: f64) -> f64 {
    GGX_IOR.value(t)
}

pub fn fresnel_node(m: usize) -> f64 {
    let t = m as f64 / (FRESNEL_NODES - 1) as f64;
    t * t
}

/// The cosine of thin-film Fresnel node m.
pub fn film_fresnel_node(m: usize) -> f64 {
    m as f64 / (FILM_FRESNEL_NODES - 1) as f64
}

/// The hat-function weights of cosine `c` on the thin-film nodes.
pub fn film_fresnel_hats(c: f64) -> [(usize, f64); 2] {
    let t = c.clamp(0.0, 1.0) * (FILM_FRESNEL_NODES - 1) as f64;
    let m = (t.floor() as usize).min(FILM_FRESNEL_NODES - 2);
    let w1 = t - m as f64;
    [(m, 1.0 - w1), (m + 1, w1)]
}

fn node(i: usize, n: usize) -> f64 {
    i as f64 / (n - 1) as f64
}

/// The hat-function weights of cosine `c` on the Fresnel nodes: (node, weight) pairs.
pub fn fresnel_hats(c: f64) -> [(usize, f64); 2] {
    let c = c.clamp(0.0, 1.0);
    let t = c.sqrt() * (FRESNEL_NODES - 1) as f64;
    let m = (t.floor() as usize).min(FRESNEL_NODES - 2);
    let (c0, c1) = (fresnel_node(m), fresnel_node(m + 1));
    let w1 = (c - c0) / (c1 - c0);
    [(m, 1.0 - w1), (m + 1, w1)]
}

/// Everything the GGX tables need at one (μ, ᾱ): E_ss, the Fresnel moments and the dielectric
/// albedos at every IOR node, outside (η_k ≥ 1) and inside (1/η_k).
pub struct GgxNode {
    pub ess: f64,
    pub moments: [f64; FRESNEL_NODES],
    pub film_moments: [f64; FILM_FRESNEL_NODES],
    pub dielectric: [f64; IOR_NODES],
    pub dielectric_inside: [f64; IOR_NODES],
}

/// Integrates the GGX quantities at (μ, α) with `n` Hammersley points.
pub fn integrate_ggx(mu: f64, alpha: f64, n: u32) -> GgxNode {
    let v = view(mu);
    let etas: Vec<f64> = (0..IOR_NODES).map(|k| ior_eta(node(k, IOR_NODES))).collect();
    let mut out = GgxNode { ess: 0.0, moments: [0.0; FRESNEL_NODES], film_moments: [0.0; FILM_FRESNEL_NODES], dielectric: [0.0; IOR_NODES], dielectric_inside: [0.0; IOR_NODES] };
    for i in 0..n {
        let (u1, u2) = qmc::hammersley(i, n);
        let (c, w) = ggx_albedo_sample(v, alpha, u1, u2);
        if w == 0.0 {
            continue;
        }
        out.ess += w;
        for (m, hw) in fresnel_hats(c) {
            out.moments[m] += w * hw;
        }
        for (m, hw) in film_fresnel_hats(c) {
            out.film_moments[m] += w * hw;
        }
        for (k, &eta) in etas.iter().enumerate() {
            out.dielectric[k] += w * fresnel_dielectric(c, eta);
            out.dielectric_inside[k] += w * fresnel_dielectric(c, 1.0 / eta);
        }
    }
    let s = 1.0 / n as f64;
    out.ess *= s;
    out.moments.iter_mut().for_each(|x| *x *= s);
    out.film_moments.iter_mut().for_each(|x| *x *= s);
    out.dielectric.iter_mut().for_each(|x| *x *= s);
    out.dielectric_inside.iter_mut().for_each(|x| *x *= s);
    out
}

/// The cosine-sampled albedo of `f_cos` at μ with `n` Hammersley points.
pub fn integrate_cosine(mu: f64, n: u32, f_cos: impl Fn(V3, V3) -> f64) -> f64 {
    let v = view(mu);
    let mut sum = 0.0;
    for i in 0..n {
        let (u1, u2) = qmc::hammersley(i, n);
        let l = sample_cosine(u1, u2);
        if l[2] > 0.0 {
            sum += f_cos(v, l) * std::f64::consts::PI / l[2];
        }
    }
    sum / n as f64
}

/// Which 2-D cosine-sampled table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiffuseTable {
    SheenContyKulla,
    OrenNayar,
    Burley,
}

impl DiffuseTable {
    pub const ALL: [DiffuseTable; 3] = [DiffuseTable::SheenContyKulla, DiffuseTable::OrenNayar, DiffuseTable::Burley];

    pub fn name(self) -> &'static str {
        match self {
            DiffuseTable::SheenContyKulla => "sheen_conty_kulla",
            DiffuseTable::OrenNayar => "oren_nayar",
            DiffuseTable::Burley => "burley",
        }
    }

    pub fn view_axis(self) -> Axis {
        match self {
            DiffuseTable::SheenContyKulla => Axis::Log,
            _ => Axis::Angle,
        }
    }

    pub fn roughness_axis(self) -> Axis {
        match self {
            DiffuseTable::SheenContyKulla => Axis::Sqrt,
            _ => Axis::Linear,
        }
    }

    /// The albedo at (μ, t) by brute-force integration with `n` points.
    pub fn integrate(self, mu: f64, t: f64, n: u32) -> f64 {
        match self {
            DiffuseTable::SheenContyKulla => integrate_cosine(mu, n, |v, l| sheen_conty_kulla_f_cos(v, l, t)),
            DiffuseTable::OrenNayar => integrate_cosine(mu, n, |v, l| oren_nayar_f_cos(v, l, t)),
            DiffuseTable::Burley => integrate_cosine(mu, n, |v, l| burley_f_cos(v, l, t)),
        }
    }
}

/// All tables as flat arrays in the layouts the WGSL lookups read.
pub struct Tables {
    pub ggx_ess: Vec<f32>,
    pub ggx_moments: Vec<f32>,
    pub ggx_film_moments: Vec<f32>,
    pub ggx_dielectric: Vec<f32>,
    pub ggx_dielectric_inside: Vec<f32>,
    pub diffuse: Vec<(DiffuseTable, Vec<f32>)>,
}

/// Rounds to the precision the file stores (6 decimals), so tables read back exactly.
fn stored(x: f64) -> f32 {
    format!("{x:.6}").parse::<f32>().unwrap()
}

/// A stored value as the file writes it: 6 decimals, trailing zeros dropped ("0.25", "0.0").
fn literal(x: f32) -> String {
    let s = format!("{x:.6}");
    let t = s.trim_end_matches('0');
    if t.ends_with('.') {
        format!("{t}0")
    } else {
        t.to_string()
    }
}

impl Tables {
    /// Computes every table (parallel over nodes; each node is independent, so the result does
    /// not depend on the thread count).
    pub fn compute(progress: &(dyn Fn(&str) + Sync)) -> Tables {
        progress("GGX tables");
        let nodes: Vec<GgxNode> = (0..ROUGHNESS_NODES * VIEW_NODES)
            .into_par_iter()
            .map(|idx| {
                let (j, i) = (idx / VIEW_NODES, idx % VIEW_NODES);
                integrate_ggx(view_mu(GGX_VIEW, node(i, VIEW_NODES)), ggx_alpha(node(j, ROUGHNESS_NODES)), GGX_SAMPLES)
            })
            .collect();
        let ggx_ess = nodes.iter().map(|n| stored(n.ess)).collect();
        let ggx_moments = nodes.iter().flat_map(|n| n.moments.iter().map(|&x| stored(x))).collect();
        let ggx_film_moments = nodes.iter().flat_map(|n| n.film_moments.iter().map(|&x| stored(x))).collect();
        let mut ggx_dielectric = vec![0.0; IOR_NODES * ROUGHNESS_NODES * VIEW_NODES];
        let mut ggx_dielectric_inside = vec![0.0; IOR_NODES * ROUGHNESS_NODES * VIEW_NODES];
        for (idx, n) in nodes.iter().enumerate() {
            for k in 0..IOR_NODES {
                ggx_dielectric[k * ROUGHNESS_NODES * VIEW_NODES + idx] = stored(n.dielectric[k]);
                ggx_dielectric_inside[k * ROUGHNESS_NODES * VIEW_NODES + idx] = stored(n.dielectric_inside[k]);
            }
        }
        let mut diffuse = Vec::new();
        for t in DiffuseTable::ALL {
            progress(t.name());
            let values = (0..ROUGHNESS_NODES * VIEW_NODES)
                .into_par_iter()
                .map(|idx| {
                    let (j, i) = (idx / VIEW_NODES, idx % VIEW_NODES);
                    stored(t.integrate(view_mu(t.view_axis(), node(i, VIEW_NODES)), t.roughness_axis().value(node(j, ROUGHNESS_NODES)), COSINE_SAMPLES))
                })
                .collect();
            diffuse.push((t, values));
        }
        Tables { ggx_ess, ggx_moments, ggx_film_moments, ggx_dielectric, ggx_dielectric_inside, diffuse }
    }

    // ---- lookups (the same interpolation as albedo_lookup.wgsl) ---------------------------

    fn axis(t: f64, n: usize) -> (usize, f64) {
        let p = t.clamp(0.0, 1.0) * (n - 1) as f64;
        let i = p.floor().min((n - 2) as f64);
        (i as usize, p - i)
    }

    fn lerp(a: f64, b: f64, t: f64) -> f64 {
        a + (b - a) * t
    }

    /// Bilinear lookup at axis coordinates (x: view, y: roughness).
    fn bilinear(table: &[f32], stride: usize, base: usize, x: f64, y: f64) -> f64 {
        let (i, fx) = Self::axis(x, VIEW_NODES);
        let (j, fy) = Self::axis(y, ROUGHNESS_NODES);
        let at = |jj: usize, ii: usize| table[base + (jj * VIEW_NODES + ii) * stride] as f64;
        Self::lerp(Self::lerp(at(j, i), at(j, i + 1), fx), Self::lerp(at(j + 1, i), at(j + 1, i + 1), fx), fy)
    }

    pub fn ess(&self, mu: f64, alpha: f64) -> f64 {
        Self::bilinear(&self.ggx_ess, 1, 0, GGX_VIEW.coordinate(mu), GGX_ROUGHNESS.coordinate(alpha))
    }

    /// GGX albedo for a Fresnel curve `f(cos)` through the moment weights.
    pub fn with_fresnel(&self, mu: f64, alpha: f64, f: impl Fn(f64) -> f64) -> f64 {
        let (x, y) = (GGX_VIEW.coordinate(mu), GGX_ROUGHNESS.coordinate(alpha));
        (0..FRESNEL_NODES).map(|m| Self::bilinear(&self.ggx_moments, FRESNEL_NODES, m, x, y) * f(fresnel_node(m))).sum()
    }

    /// GGX albedo for a Fresnel curve `f(cos)` through the thin-film moment weights.
    pub fn with_film_fresnel(&self, mu: f64, alpha: f64, f: impl Fn(f64) -> f64) -> f64 {
        let (x, y) = (GGX_VIEW.coordinate(mu), GGX_ROUGHNESS.coordinate(alpha));
        (0..FILM_FRESNEL_NODES).map(|m| Self::bilinear(&self.ggx_film_moments, FILM_FRESNEL_NODES, m, x, y) * f(film_fresnel_node(m))).sum()
    }

    /// The dielectric albedo for relative IOR η > 0: the outside table for η ≥ 1 (η above 3
    /// reads as 3), the inside table of 1/η below 1 (η below ⅓ reads as ⅓).
    pub fn dielectric(&self, mu: f64, alpha: f64, eta: f64) -> f64 {
        let (table, eta) = if eta < 1.0 { (&self.ggx_dielectric_inside, 1.0 / eta) } else { (&self.ggx_dielectric, eta) };
        let (k, fz) = Self::axis(GGX_IOR.coordinate(eta), IOR_NODES);
        let plane = ROUGHNESS_NODES * VIEW_NODES;
        let (x, y) = (GGX_VIEW.coordinate(mu), GGX_ROUGHNESS.coordinate(alpha));
        let a = Self::bilinear(table, 1, k * plane, x, y);
        let b = Self::bilinear(table, 1, (k + 1) * plane, x, y);
        Self::lerp(a, b, fz)
    }

    pub fn diffuse(&self, which: DiffuseTable, mu: f64, t: f64) -> f64 {
        let table = &self.diffuse.iter().find(|(w, _)| *w == which).unwrap().1;
        Self::bilinear(table, 1, 0, which.view_axis().coordinate(mu), which.roughness_axis().coordinate(t))
    }

    /// Reads the tables back from [`Tables::to_wgsl`]'s text (the checked-in file): each table's
    /// offset constant and the values of `mx_albedo_table_data`, sized by this module's grids.
    pub fn from_wgsl(text: &str) -> Result<Tables, String> {
        let start = text.find("const mx_albedo_table_data = array<f32, ").ok_or("no mx_albedo_table_data array")?;
        let body = &text[start..];
        let open = body.find('(').ok_or("no array body")? + 1;
        let close = body.find(");").ok_or("unterminated array")?;
        let values: Vec<f32> = body[open..close]
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .flat_map(|l| l.split(','))
            .map(str::trim)
            .filter(|v| !v.is_empty())
            .map(|v| v.parse::<f32>().map_err(|e| format!("value {v:?}: {e}")))
            .collect::<Result<_, _>>()?;
        let table = |name: &str, len: usize| -> Result<Vec<f32>, String> {
            let key = format!("const {} = ", name.to_uppercase());
            let line = text.lines().find(|l| l.starts_with(&key)).ok_or_else(|| format!("no offset for {name}"))?;
            let offset: usize = line[key.len()..].trim_end_matches(';').parse().map_err(|e| format!("{name}: {e}"))?;
            values.get(offset..offset + len).map(<[f32]>::to_vec).ok_or_else(|| format!("{name} runs past the array"))
        };
        let plane = ROUGHNESS_NODES * VIEW_NODES;
        Ok(Tables {
            ggx_ess: table("mx_table_ggx_ess", plane)?,
            ggx_moments: table("mx_table_ggx_moments", plane * FRESNEL_NODES)?,
            ggx_film_moments: table("mx_table_ggx_film_moments", plane * FILM_FRESNEL_NODES)?,
            ggx_dielectric: table("mx_table_ggx_dielectric", plane * IOR_NODES)?,
            ggx_dielectric_inside: table("mx_table_ggx_dielectric_inside", plane * IOR_NODES)?,
            diffuse: DiffuseTable::ALL.into_iter().map(|t| Ok((t, table(&format!("mx_table_{}", t.name()), plane)?))).collect::<Result<_, String>>()?,
        })
    }

    /// The generated WGSL file: header, grid constants, one `const` array per table.
    pub fn to_wgsl(&self) -> String {
        let mut arrays = vec![
            ("mx_table_ggx_ess", &self.ggx_ess),
            ("mx_table_ggx_moments", &self.ggx_moments),
            ("mx_table_ggx_film_moments", &self.ggx_film_moments),
            ("mx_table_ggx_dielectric", &self.ggx_dielectric),
            ("mx_table_ggx_dielectric_inside", &self.ggx_dielectric_inside),
        ];
        let names: Vec<String> = self.diffuse.iter().map(|(t, _)| format!("mx_table_{}", t.name())).collect();
        for ((_, v), n) in self.diffuse.iter().zip(&names) {
            arrays.push((n.as_str(), v));
        }
        // One array (the GPU binds it as one storage buffer), each table at its offset.
        let total: usize = arrays.iter().map(|(_, v)| v.len()).sum();
        let mut offsets = String::new();
        let mut body = format!("const mx_albedo_table_data = array<f32, {total}>(");
        let mut offset = 0;
        for (name, values) in &arrays {
            let _ = writeln!(offsets, "const {} = {offset};", name.to_uppercase());
            let _ = write!(body, "\n    // {name} at {offset}");
            for (k, x) in values.iter().enumerate() {
                if k % 16 == 0 {
                    body.push_str("\n    ");
                }
                let _ = write!(body, "{}, ", literal(*x));
            }
            offset += values.len();
        }
        body.push_str("\n);\n");
        let hash = uplift_base::rng::hash_str(&body);
        let mut s = String::new();
        let _ = writeln!(s, "// albedo_tables.wgsl: directional-albedo tables of the pbrlib closure library.");
        let _ = writeln!(s, "// Generated by `uplift tables` (runtime/kernels/src/albedo_tables); do not edit. Grids, integrands and");
        let _ = writeln!(s, "// measured errors: docs/albedo-tables.md. Lookups: albedo_lookup.wgsl.");
        let _ = writeln!(s, "//");
        let _ = writeln!(s, "// format {FORMAT_VERSION}; every table is [axis 3][roughness][view], nodes uniform in t in [0, 1]: view {VIEW_NODES} nodes,");
        let _ = writeln!(s, "// roughness {ROUGHNESS_NODES}, IOR {IOR_NODES}, Fresnel moments {FRESNEL_NODES} (at cos = (j/15)^2), thin-film moments {FILM_FRESNEL_NODES} (at cos = j/31).");
        let _ = writeln!(s, "// Axes: log t = ln(1 + 100 v)/ln(101)");
        let _ = writeln!(s, "// (GGX view mu and alpha_bar, sheen view), angle t = 1 - acos(mu)*2/pi (diffuse view), sqrt t = sqrt(v) (sheen");
        let _ = writeln!(s, "// roughness), linear (diffuse roughness), IOR t = sqrt(2|q|), q = (eta-1)/(eta+1), eta in [1, 3]");
        let _ = writeln!(s, "// (ggx_dielectric) or [1/3, 1] (ggx_dielectric_inside, whose node k is the IOR 1/eta_k).");
        let _ = writeln!(s, "// Integrator: 2-D Hammersley points, {GGX_SAMPLES} per node with visible-normal sampling (GGX tables), {COSINE_SAMPLES}");
        let _ = writeln!(s, "// per node with cosine sampling (sheen_conty_kulla, oren_nayar, burley). Values rounded to 6 decimals.");
        for (name, values) in &arrays {
            let _ = writeln!(s, "//   {name}: {} values", values.len());
        }
        let _ = writeln!(s, "// content hash (FNV-1a 64 of the array text): {hash:016x}");
        let _ = writeln!(s);
        let _ = writeln!(s, "const MX_TABLE_VIEW_NODES: i32 = {VIEW_NODES};");
        let _ = writeln!(s, "const MX_TABLE_ROUGHNESS_NODES: i32 = {ROUGHNESS_NODES};");
        let _ = writeln!(s, "const MX_TABLE_IOR_NODES: i32 = {IOR_NODES};");
        let _ = writeln!(s, "const MX_TABLE_FRESNEL_NODES: i32 = {FRESNEL_NODES};");
        let _ = writeln!(s, "const MX_TABLE_FILM_FRESNEL_NODES: i32 = {FILM_FRESNEL_NODES};");
        let _ = writeln!(s);
        let _ = writeln!(s, "// Where each table starts in mx_albedo_table_data.");
        s.push_str(&offsets);
        let _ = writeln!(s);
        let _ = writeln!(s, "// Element i of the tables. The compiler keeps this function for CPU kernels and, for GPU");
        let _ = writeln!(s, "// kernels, reads a storage buffer holding mx_albedo_table_data instead (lower.rs).");
        let _ = writeln!(s, "fn mx_albedo_table(i: i32) -> f32 {{\n    return mx_albedo_table_data[i];\n}}\n");
        s + &body
    }
}
