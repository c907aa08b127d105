//! Every nodedef of the stdlib `compositing` and `adjustment` node groups, every type variant
//! (atomic ones and those MaterialX implements with nodegraphs, which the compiler inlines):
//! compiled from a generated nodegraph, run on wgpu for 256 random rows, compared with a closed
//! form written here from the MaterialX spec (MaterialX.StandardNodes.md) and MaterialX's GLSL
//! semantics (mix(fg, bg, m) = bg·(1-m) + fg·m; blend modes mix their result with bg by `mix`).
//!
//! Tolerances: 1e-5 absolute for arithmetic (compositing, remap, contrast, smoothstep,
//! luminance, saturate); 1e-4 for the HSV conversions; `range` and `colorcorrect` contain a
//! power and can reach tens, so their 1e-4 is relative (err ≤ 1e-4 · max(1, |want|)).

use crate::common;
use crate::nodedef_harness;

use common::Rng;
use mtlx::schema::{NodeDef, PortDef};
use nodedef_harness::*;

fn gen(nd: &NodeDef, p: &PortDef, rng: &mut Rng) -> Option<Vec<f32>> {
    let n = p.ty.components()?;
    let unit = |rng: &mut Rng| uniform(rng, n, 0.0, 1.0);
    Some(match (nd.node.as_str(), p.name.as_str()) {
        // ---- compositing: colors and alphas in [0, 1], mix in [0, 1] ----
        ("mix", "fg" | "bg") => uniform(rng, n, -2.0, 2.0),
        ("inside" | "outside", "in") => uniform(rng, n, -2.0, 2.0),
        // burn divides by fg, dodge by 1 - fg: keep both away from zero.
        ("burn", "fg") => uniform(rng, n, 0.2, 1.0),
        ("dodge", "fg") => uniform(rng, n, 0.0, 0.8),
        // unpremult divides by alpha.
        ("unpremult", "in") => vec![rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.2, 1.0)],
        (_, "fg" | "bg" | "mix" | "mask") if nd.nodegroup.as_deref() == Some("compositing") => unit(rng),
        ("premult", "in") => unit(rng),
        // ---- adjustment ----
        ("remap" | "range", "inlow") => uniform(rng, n, -1.0, 0.0),
        ("remap" | "range", "inhigh") => uniform(rng, n, 0.5, 2.0),
        ("range", "in") => uniform(rng, n, -1.5, 2.5),
        ("range", "gamma") => uniform(rng, n, 0.5, 2.0),
        ("range", "outlow") => uniform(rng, n, -1.0, 0.0),
        ("range", "outhigh") => uniform(rng, n, 0.5, 2.0),
        ("smoothstep", "in") => uniform(rng, n, -1.5, 2.5),
        ("smoothstep", "low") => uniform(rng, n, -1.0, 0.4),
        ("smoothstep", "high") => uniform(rng, n, 0.6, 2.0),
        ("luminance" | "saturate", "lumacoeffs") => unit(rng),
        ("luminance" | "rgbtohsv" | "hsvadjust" | "saturate" | "colorcorrect", "in") => unit(rng),
        ("hsvtorgb", "in") => {
            let mut v = vec![rng.range(-1.0, 2.0), rng.range(0.0, 1.0), rng.range(0.0, 1.0)];
            if n == 4 {
                v.push(rng.range(0.0, 1.0));
            }
            v
        }
        ("hsvadjust", "amount") => vec![rng.range(-1.0, 1.0), rng.range(0.0, 1.5), rng.range(0.0, 1.5)],
        ("saturate", "amount") => vec![rng.range(0.0, 2.0)],
        ("colorcorrect", "hue") => vec![rng.range(-1.0, 1.0)],
        ("colorcorrect", "saturation") => vec![rng.range(0.0, 2.0)],
        ("colorcorrect", "gamma") => vec![rng.range(0.5, 2.0)],
        ("colorcorrect", "lift") => vec![rng.range(-0.5, 0.5)],
        ("colorcorrect", "gain") => vec![rng.range(0.5, 2.0)],
        ("colorcorrect", "contrast") => vec![rng.range(0.5, 2.0)],
        ("colorcorrect", "contrastpivot") => vec![rng.range(0.0, 1.0)],
        ("colorcorrect", "exposure") => vec![rng.range(-2.0, 2.0)],
        _ => return None,
    })
}

/// RGB to HSV (Foley & van Dam), H and S in [0, 1].
fn rgb_to_hsv(c: &[f32]) -> [f32; 3] {
    let (r, g, b) = (c[0] as f64, c[1] as f64, c[2] as f64);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let s = if max > 0.0 { delta / max } else { 0.0 };
    let mut h = if delta <= 0.0 {
        0.0
    } else if r >= max {
        (g - b) / delta
    } else if g >= max {
        2.0 + (b - r) / delta
    } else {
        4.0 + (r - g) / delta
    } / 6.0;
    if h < 0.0 {
        h += 1.0;
    }
    [h as f32, s as f32, max as f32]
}

/// HSV to RGB (Foley & van Dam); the hue wraps at the 0-1 boundaries.
fn hsv_to_rgb(c: &[f32]) -> [f32; 3] {
    let (h, s, v) = (c[0] as f64, c[1] as f64, c[2] as f64);
    let h6 = (h - h.floor()) * 6.0;
    let i = (h6.floor() as i32).min(5);
    let f = h6 - i as f64;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let rgb = match i {
        0 => (v, t, p),
        1 => (q, v, p),
        2 => (p, v, t),
        3 => (p, q, v),
        4 => (t, p, v),
        _ => (v, p, q),
    };
    [rgb.0 as f32, rgb.1 as f32, rgb.2 as f32]
}

/// Applies `f` to the RGB part; a fourth (alpha) channel passes unchanged.
fn on_rgb(v: &[f32], f: impl Fn(&[f32]) -> [f32; 3]) -> Vec<f32> {
    let mut out = f(&v[..3]).to_vec();
    out.extend_from_slice(&v[3..]);
    out
}

fn hsv_adjust(c: &[f32], a: &[f32]) -> [f32; 3] {
    let hsv = rgb_to_hsv(c);
    hsv_to_rgb(&[hsv[0] + a[0], hsv[1] * a[1], hsv[2] * a[2]])
}

fn saturate(c: &[f32], amount: f32, coeffs: &[f32]) -> [f32; 3] {
    let l = dot(c, coeffs);
    [l + amount * (c[0] - l), l + amount * (c[1] - l), l + amount * (c[2] - l)]
}

fn remap(v: f32, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> f32 {
    outlow + (v - inlow) * (outhigh - outlow) / (inhigh - inlow)
}

/// `range` on one channel: remap to [0, 1], gamma "in the middle" (sign-preserving power
/// 1/gamma), remap to [outlow, outhigh], clamp to that range when asked.
fn range(v: f32, inlow: f32, inhigh: f32, gamma: f32, outlow: f32, outhigh: f32, doclamp: bool) -> f32 {
    let r = remap(v, inlow, inhigh, 0.0, 1.0) as f64;
    let g = r.signum() * r.abs().powf(1.0 / gamma as f64);
    let o = remap(g as f32, 0.0, 1.0, outlow, outhigh);
    if doclamp {
        o.max(outlow).min(outhigh)
    } else {
        o
    }
}

/// The ACEScg luma coefficients: `saturate`'s default `lumacoeffs`.
const ACESCG_LUMA: [f32; 3] = [0.2722287, 0.6740818, 0.0536895];

/// Blend on every channel, then mix with bg: m·blend(F, B) + (1 - m)·B (MaterialX GLSL).
fn blend(nd: &NodeDef, x: &Inputs, f: impl Fn(f32, f32) -> f32) -> Vec<f32> {
    let m = x.f("mix");
    map2(nd, x, "fg", "bg", |fg, bg| m * f(fg, bg) + (1.0 - m) * bg)
}

/// Merge of two color4: `op` gives the unmixed result from (fg, bg); then mixed with bg.
fn merge(x: &Inputs, op: impl Fn(&[f32], &[f32]) -> [f32; 4]) -> Vec<f32> {
    let (fg, bg, m) = (x.v("fg"), x.v("bg"), x.f("mix"));
    let r = op(&fg, &bg);
    (0..4).map(|k| r[k] * m + bg[k] * (1.0 - m)).collect()
}

fn reference(nd: &NodeDef, x: &Inputs) -> Vec<f32> {
    let n = out_n(nd);
    match nd.node.as_str() {
        // ---- compositing ----
        "premult" => {
            let v = x.v("in");
            vec![v[0] * v[3], v[1] * v[3], v[2] * v[3], v[3]]
        }
        "unpremult" => {
            let v = x.v("in");
            vec![v[0] / v[3], v[1] / v[3], v[2] / v[3], v[3]]
        }
        "plus" => blend(nd, x, |f, b| b + f),
        "minus" => blend(nd, x, |f, b| b - f),
        "difference" => blend(nd, x, |f, b| (b - f).abs()),
        // 1 - (1 - B)/F (GLSL gives 0 where |F| < eps; F ≥ 0.2 here).
        "burn" => blend(nd, x, |f, b| 1.0 - (1.0 - b) / f),
        // B/(1 - F) (GLSL gives 0 where |1 - F| < eps; F ≤ 0.8 here).
        "dodge" => blend(nd, x, |f, b| b / (1.0 - f)),
        "screen" => blend(nd, x, |f, b| 1.0 - (1.0 - f) * (1.0 - b)),
        "overlay" => blend(nd, x, |f, b| if b < 0.5 { 2.0 * f * b } else { 1.0 - 2.0 * (1.0 - f) * (1.0 - b) }),
        "disjointover" => merge(x, |f, b| {
            let sum = f[3] + b[3];
            let rgb: Vec<f32> = if sum <= 1.0 {
                (0..3).map(|k| f[k] + b[k]).collect()
            } else {
                (0..3).map(|k| f[k] + b[k] * (1.0 - f[3]) / b[3]).collect()
            };
            [rgb[0], rgb[1], rgb[2], sum.min(1.0)]
        }),
        // RGB = F·b, alpha = f·b.
        "in" => merge(x, |f, b| [f[0] * b[3], f[1] * b[3], f[2] * b[3], f[3] * b[3]]),
        // RGB = B·f, alpha = b·f.
        "mask" => merge(x, |f, b| [b[0] * f[3], b[1] * f[3], b[2] * f[3], b[3] * f[3]]),
        // RGB = F·f + B·(1 - f), alpha = f + b·(1 - f).
        "matte" => merge(x, |f, b| {
            let k = 1.0 - f[3];
            [f[0] * f[3] + b[0] * k, f[1] * f[3] + b[1] * k, f[2] * f[3] + b[2] * k, f[3] + b[3] * k]
        }),
        // RGB = F·(1 - b), alpha = f·(1 - b).
        "out" => merge(x, |f, b| {
            let k = 1.0 - b[3];
            [f[0] * k, f[1] * k, f[2] * k, f[3] * k]
        }),
        // RGB = F + B·(1 - f), alpha = f + b·(1 - f).
        "over" => merge(x, |f, b| {
            let k = 1.0 - f[3];
            [f[0] + b[0] * k, f[1] + b[1] * k, f[2] + b[2] * k, f[3] + b[3] * k]
        }),
        "inside" => map1(nd, x, "in", |v| v * x.f("mask")),
        "outside" => map1(nd, x, "in", |v| v * (1.0 - x.f("mask"))),
        // fg·m + bg·(1 - m), m a float or per channel.
        "mix" => map3(nd, x, "fg", "bg", "mix", |f, b, m| b * (1.0 - m) + f * m),
        // ---- adjustment ----
        "remap" => {
            let (v, il, ih, ol, oh) = (x.v("in"), x.n("inlow", n), x.n("inhigh", n), x.n("outlow", n), x.n("outhigh", n));
            (0..n).map(|k| remap(v[k], il[k], ih[k], ol[k], oh[k])).collect()
        }
        "smoothstep" => map3(nd, x, "in", "low", "high", |v, lo, hi| {
            if v >= hi {
                1.0
            } else if v <= lo {
                0.0
            } else {
                let t = (v - lo) / (hi - lo);
                t * t * (3.0 - 2.0 * t)
            }
        }),
        "contrast" => map3(nd, x, "in", "amount", "pivot", |v, a, p| (v - p) * a + p),
        "range" => {
            let (v, il, ih, g, ol, oh) =
                (x.v("in"), x.n("inlow", n), x.n("inhigh", n), x.n("gamma", n), x.n("outlow", n), x.n("outhigh", n));
            let c = x.b("doclamp");
            (0..n).map(|k| range(v[k], il[k], ih[k], g[k], ol[k], oh[k], c)).collect()
        }
        "luminance" => {
            let l = dot(&x.v("in")[..3], &x.v("lumacoeffs"));
            on_rgb(&x.v("in"), |_| [l, l, l])
        }
        "rgbtohsv" => on_rgb(&x.v("in"), rgb_to_hsv),
        "hsvtorgb" => on_rgb(&x.v("in"), hsv_to_rgb),
        "hsvadjust" => on_rgb(&x.v("in"), |c| hsv_adjust(c, &x.v("amount"))),
        "saturate" => on_rgb(&x.v("in"), |c| saturate(c, x.f("amount"), &x.v("lumacoeffs"))),
        "colorcorrect" => on_rgb(&x.v("in"), |c| {
            // MaterialX's chain: hue (hsvadjust), saturation (saturate, default ACEScg luma),
            // gamma (range on [0, 1], unclamped), lift (c·(1 - lift) + lift), gain (·gain),
            // contrast (about contrastpivot), exposure (·2^exposure).
            let h = hsv_adjust(c, &[x.f("hue"), 1.0, 1.0]);
            let s = saturate(&h, x.f("saturation"), &ACESCG_LUMA);
            let (lift, gain, amount, pivot) = (x.f("lift"), x.f("gain"), x.f("contrast"), x.f("contrastpivot"));
            let e = 2f64.powf(x.f("exposure") as f64) as f32;
            let ch = |v: f32| {
                let g = range(v, 0.0, 1.0, x.f("gamma"), 0.0, 1.0, false);
                let l = g * (1.0 - lift) + lift;
                (((l * gain) - pivot) * amount + pivot) * e
            };
            [ch(s[0]), ch(s[1]), ch(s[2])]
        }),
        c => panic!("no reference for {c}"),
    }
}

const ABS: Tol = Tol::Abs(1e-5);
const ABS_T: Tol = Tol::Abs(1e-4);
const REL_T: Tol = Tol::Rel(1e-4);

macro_rules! specs {
    ($($cat:literal => $tol:expr),* $(,)?) => {
        &[$(Spec { category: $cat, tol: $tol, gen, reference }),*]
    };
}

const SPECS: &[Spec] = specs![
    "premult" => ABS, "unpremult" => ABS, "plus" => ABS, "minus" => ABS, "difference" => ABS,
    "burn" => ABS, "dodge" => ABS, "screen" => ABS, "overlay" => ABS, "disjointover" => ABS,
    "in" => ABS, "mask" => ABS, "matte" => ABS, "out" => ABS, "over" => ABS,
    "inside" => ABS, "outside" => ABS, "mix" => ABS,
    "remap" => ABS, "smoothstep" => ABS, "contrast" => ABS, "range" => REL_T, "luminance" => ABS,
    "rgbtohsv" => ABS_T, "hsvtorgb" => ABS_T, "hsvadjust" => ABS_T, "saturate" => ABS,
    "colorcorrect" => REL_T,
];

/// Not tested, with the reason.
const SKIP: &[(&str, &str)] = &[
    // Shader-typed mixes: closures, not pattern values.
    ("ND_mix_surfaceshader", "shader type"),
    ("ND_mix_displacementshader", "shader type"),
    ("ND_mix_volumeshader", "shader type"),
];

/// Left out because of a known compiler problem (reported; see the test's report).
const KNOWN_FAILURES: &[(&str, &str)] = &[];

#[test]
fn every_compositing_and_adjustment_nodedef_matches_its_closed_form() {
    run_plan(&Plan {
        groups: &["compositing", "adjustment"],
        filter: all,
        specs: SPECS,
        skip: SKIP,
        known_failures: KNOWN_FAILURES,
        seed: 33,
    });
}
