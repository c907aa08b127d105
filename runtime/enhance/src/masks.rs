//! Procedural spatial masks for the uplift (design note `lobes.md` §3.2, paper §3 Fig. 6): the
//! dust-variation mask (fingerprints and ripples on a dust layer) and the clearcoat damage mask
//! (scratches and dents on a coat). This module owns only the 2-D mask images; mapping them onto
//! a surface (triplanar blending, the up-facing dust term) is done by the caller.
//!
//! Both masks are square `size × size` images of `f32` in [0, 1], row-major, row 0 at the top,
//! texel (i, j) sampled at texture coordinate ((i + ½)/size, (j + ½)/size).
//!
//! **Dust** (1 = dust present): `M = clamp(f · (1 − ς·p) · r, 0, 1)` where
//! * `f = smoothstep(t − w, t + w, fbm)`: patchy fBm gradient noise, base frequency F ∈ {3..6}
//!   cycles per texture, 3–5 octaves (lacunarity 2, gain ½), soft threshold t ∈ [−0.12, 0.12],
//!   half-width w ∈ [0.08, 0.2];
//! * `p = max_k env_k · ½(1 + sin(2πρ_k/λ_k))`: 1–4 fingerprints, each an elliptical envelope
//!   (semi-axes a ∈ [0.05, 0.11], b = a·[0.6, 0.85], random rotation, smooth falloff over its
//!   outer half) holding concentric elliptical ridges of spacing λ = a/[6, 12], slightly warped
//!   by the fBm; ς ∈ [0.3, 1] is the removal strength;
//! * `r = 1 − A·½(1 + sin(2π(k·x + W·warp(x))))`: ripple bands of integer wave vector k
//!   (|k| ≈ 5–12 cycles), warped by a 2-octave noise of amplitude W ∈ [0.5, 2] cycles, mild
//!   depth A ∈ [0.1, 0.3].
//!
//! **Damage** (clearcoat weight; 1 = intact): `M = 1 − max(damage)` over
//! * 16–96 scratches: straight segments, 2–4-segment polylines and slightly curved arcs (total turn
//!   0.3–1 rad), length 0.05–0.35, width 0.5–2 px at 512² (0.001–0.004 in texture units),
//!   depth 0.5–1 tapering towards the ends; 60 % follow a common dominant direction (wiping);
//! * 4–16 dents: soft Gaussian spots, σ ∈ [0.003, 0.012], depth 0.6–1.
//!
//! Measured on seeds 0–15 at 128²: dust coverage (mean) 0.24–0.60 (the tests require every
//! mask in [0.1, 0.8]); damage mean 0.97–0.99 with minima 0.12–0.45.
//!
//! **Tileable**: every term is periodic with period 1 in both texture axes — lattice noise wraps its
//! lattice modulo its integer frequency, ripple wave vectors are integers, and fingerprints,
//! scratches and dents use the minimum-image (wrap-around) offset.
//! **Deterministic**: parameters come from a SplitMix64 stream (`uplift_base::rng`) keyed by (seed, kind) and
//! never depend on `size`; each texel is a pure function of its coordinate, so rows may run in
//! parallel and the output is bit-identical for any thread count.
//! **Resolution independent**: features live in [0,1)² texture units; detail finer than the texel
//! grid is band-limited (noise octaves, ridges and ripples fade out between 4 and 2 texels per
//! cycle; lines thinner than a texel and dents smaller than a texel are widened with their
//! integral preserved), so a small mask approximates a box-filtered large one.

use uplift_base::rng::{finalize as mix, SplitMix64};
use rayon::prelude::*;
use std::f32::consts::{FRAC_1_SQRT_2, TAU};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MaskKind {
    Dust,
    Damage,
}

impl MaskKind {
    pub fn file_stem(self) -> &'static str {
        match self {
            MaskKind::Dust => "dust",
            MaskKind::Damage => "damage",
        }
    }
}

/// A square mask, `data[j * size + i]` for column i, row j (row 0 at the top).
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    pub size: usize,
    pub data: Vec<f32>,
}

/// Generates the `kind` mask of `seed` at `size × size` texels (size ≥ 1).
pub fn generate(kind: MaskKind, seed: u64, size: usize) -> Mask {
    assert!(size >= 1, "mask size must be at least 1");
    let mut rng = Rng(SplitMix64::new(mix(seed ^ mix(kind as u64 + 1))));
    let texel = 1.0 / size as f32;
    let eval: Box<dyn Fn(f32, f32) -> f32 + Sync> = match kind {
        MaskKind::Dust => Dust::new(&mut rng).into_fn(texel),
        MaskKind::Damage => Damage::new(&mut rng).into_fn(texel),
    };
    let mut data = vec![0.0f32; size * size];
    data.par_chunks_mut(size).enumerate().for_each(|(j, row)| {
        let v = (j as f32 + 0.5) * texel;
        for (i, out) in row.iter_mut().enumerate() {
            *out = eval((i as f32 + 0.5) * texel, v).clamp(0.0, 1.0);
        }
    });
    Mask { size, data }
}

impl Mask {
    /// The mask as 16-bit grayscale PNG bytes (value v stored as round(v · 65535)).
    pub fn to_png16(&self) -> Result<Vec<u8>, String> {
        let px: Vec<u16> = self.data.iter().map(|v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16).collect();
        let img = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(self.size as u32, self.size as u32, px)
            .ok_or_else(|| format!("mask data has {} texels, expected {}²", self.data.len(), self.size))?;
        let mut bytes = std::io::Cursor::new(Vec::new());
        img.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("encoding mask PNG: {e}"))?;
        Ok(bytes.into_inner())
    }

    /// Writes the mask as a 16-bit PNG, atomically.
    pub fn write_png(&self, path: &std::path::Path) -> Result<(), String> {
        let bytes = self.to_png16().map_err(|e| format!("{}: {e}", path.display()))?;
        uplift_base::atomic_write::write_atomically(path, &bytes).map_err(|e| format!("writing {}: {e}", path.display()))
    }
}

// ---- RNG, noise and helpers -------------------------------------------------------------------

/// The masks' parameter stream: the runtime's SplitMix64 with the draws masks need.
struct Rng(SplitMix64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    fn f(&mut self, lo: f32, hi: f32) -> f32 {
        self.0.range(lo, hi)
    }
    fn int(&mut self, lo: u32, hi_inclusive: u32) -> u32 {
        self.0.int(lo.into(), hi_inclusive.into()) as u32
    }
    fn point(&mut self) -> (f32, f32) {
        (self.0.unit(), self.0.unit())
    }
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Minimum-image offset in [−½, ½].
fn wrap(d: f32) -> f32 {
    d - d.round()
}

/// Band limit: 1 for detail of ≥ 4 texels per cycle, fading to 0 at 2 texels per cycle.
fn band(cycles: f32, texel: f32) -> f32 {
    ((1.0 / (cycles * texel) - 2.0) * 0.5).clamp(0.0, 1.0)
}

const GRAD: [(f32, f32); 8] = [
    (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0),
    (FRAC_1_SQRT_2, FRAC_1_SQRT_2), (-FRAC_1_SQRT_2, FRAC_1_SQRT_2),
    (FRAC_1_SQRT_2, -FRAC_1_SQRT_2), (-FRAC_1_SQRT_2, -FRAC_1_SQRT_2),
];

/// Gradient noise with period `p` lattice cells in x and y, about [−1, 1].
fn noise(key: u64, x: f32, y: f32, p: u32) -> f32 {
    let (xf, yf) = (x.floor(), y.floor());
    let (fx, fy) = (x - xf, y - yf);
    let p = i64::from(p);
    let (xi, yi) = (xf as i64, yf as i64);
    let g = |ix: i64, iy: i64, dx: f32, dy: f32| {
        let h = mix(key ^ ((ix.rem_euclid(p) as u64) << 32 | iy.rem_euclid(p) as u64));
        let (gx, gy) = GRAD[(h & 7) as usize];
        gx * dx + gy * dy
    };
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (a, b) = (g(xi, yi, fx, fy), g(xi + 1, yi, fx - 1.0, fy));
    let (c, d) = (g(xi, yi + 1, fx, fy - 1.0), g(xi + 1, yi + 1, fx - 1.0, fy - 1.0));
    let (s, t) = (fade(fx), fade(fy));
    let top = a + (b - a) * s;
    1.414 * (top + (c + (d - c) * s - top) * t)
}

/// Periodic fBm on [0,1)²: `octaves` octaves from `base` cycles, band-limited to the texel grid
/// (faded octaves are dropped, not renormalised, as box filtering would average them away).
fn fbm(key: u64, u: f32, v: f32, base: u32, octaves: u32, texel: f32) -> f32 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, base);
    for o in 0..octaves {
        let k = band(freq as f32, texel);
        if k > 0.0 {
            // A random sub-cell shift per octave keeps the lattice lines of all octaves from
            // coinciding with each other and with the image border.
            let h = mix(key.wrapping_add(u64::from(o)));
            let (ox, oy) = ((h >> 40) as f32 / (1u64 << 24) as f32, (h >> 16 & 0xff_ffff) as f32 / (1u64 << 24) as f32);
            sum += amp * k * noise(h, u * freq as f32 + ox, v * freq as f32 + oy, freq);
        }
        norm += amp;
        amp *= 0.5;
        freq *= 2;
    }
    sum / norm
}

// ---- Dust -------------------------------------------------------------------------------------

/// A fingerprint: centre, rotation (cos, sin), envelope semi-axes a ≥ b, ridge spacing λ.
struct Print { c: (f32, f32), rot: (f32, f32), a: f32, b: f32, lambda: f32 }

/// fBm key, base frequency, octaves, soft threshold, removal strength ς, prints, ripple wave
/// vector, warp and depth.
struct Dust { key: u64, base: u32, octaves: u32, thr: f32, soft: f32, sigma: f32, prints: Vec<Print>, k: (f32, f32), warp: f32, amp: f32 }

impl Dust {
    fn new(r: &mut Rng) -> Dust {
        let (key, base, octaves) = (r.next(), r.int(3, 6), r.int(3, 5));
        let (thr, soft, sigma) = (r.f(-0.12, 0.12), r.f(0.08, 0.2), r.f(0.3, 1.0));
        let prints = (0..r.int(1, 4))
            .map(|_| {
                let (c, th, a) = (r.point(), r.f(0.0, TAU), r.f(0.05, 0.11));
                Print { c, rot: (th.cos(), th.sin()), a, b: a * r.f(0.6, 0.85), lambda: a / r.f(6.0, 12.0) }
            })
            .collect();
        let k = loop {
            let k = (r.int(0, 24) as f32 - 12.0, r.int(0, 24) as f32 - 12.0);
            if (25.0..=144.0).contains(&(k.0 * k.0 + k.1 * k.1)) {
                break k;
            }
        };
        Dust { key, base, octaves, thr, soft, sigma, prints, k, warp: r.f(0.5, 2.0), amp: r.f(0.1, 0.3) }
    }

    fn into_fn(self, texel: f32) -> Box<dyn Fn(f32, f32) -> f32 + Sync> {
        Box::new(move |u, v| self.eval(u, v, texel))
    }

    fn eval(&self, u: f32, v: f32, texel: f32) -> f32 {
        let n = fbm(self.key, u, v, self.base, self.octaves, texel);
        let patchy = smoothstep(self.thr - self.soft, self.thr + self.soft, n);
        let mut print = 0.0f32;
        for p in &self.prints {
            let (dx, dy) = (wrap(u - p.c.0), wrap(v - p.c.1));
            let (x, y) = (p.rot.0 * dx + p.rot.1 * dy, p.rot.0 * dy - p.rot.1 * dx);
            let q = (x / p.a).powi(2) + (y / p.b).powi(2);
            if q < 1.0 {
                let env = 1.0 - smoothstep(0.5, 1.0, q.sqrt());
                let rho = (x * x + (y * p.a / p.b).powi(2)).sqrt() + 0.6 * p.lambda * n;
                let ridge = 0.5 + 0.5 * band(1.0 / p.lambda, texel) * (TAU * rho / p.lambda).sin();
                print = print.max(env * ridge);
            }
        }
        let kk = (self.k.0 * self.k.0 + self.k.1 * self.k.1).sqrt();
        let w = fbm(self.key ^ 0x5249_5050_4c45, u, v, 2, 2, texel);
        let phase = self.k.0 * u + self.k.1 * v + self.warp * w;
        let ripple = 1.0 - self.amp * 0.5 * (1.0 + band(kk + 4.0 * self.warp, texel) * (TAU * phase).sin());
        patchy * (1.0 - self.sigma * print) * ripple
    }
}

// ---- Damage -----------------------------------------------------------------------------------

/// A polyline scratch: bounding-box centre `c` and half-extents `half`, vertices relative to `c`,
/// cumulative length fraction at each vertex, width and depth (both in texture units).
struct Scratch { c: (f32, f32), half: (f32, f32), pts: Vec<(f32, f32)>, cum: Vec<f32>, width: f32, depth: f32 }

/// A Gaussian dent: centre, σ², depth.
struct Dent { c: (f32, f32), s2: f32, depth: f32 }

struct Damage { scratches: Vec<Scratch>, dents: Vec<Dent> }

impl Damage {
    fn new(r: &mut Rng) -> Damage {
        let dominant = r.f(0.0, TAU);
        let scratches = (0..r.int(16, 96))
            .map(|_| {
                let start = r.point();
                let mut th = if r.f(0.0, 1.0) < 0.6 { dominant + r.f(-0.2, 0.2) } else { r.f(0.0, TAU) };
                let len = r.f(0.05, 0.35);
                let (segs, turn) = match r.int(0, 2) {
                    0 => (1, 0.0),
                    1 => (r.int(2, 4), 0.25),
                    _ => (8, r.f(0.3, 1.0) / 8.0 * if r.next() & 1 == 0 { 1.0 } else { -1.0 }),
                };
                let mut pts = vec![(0.0f32, 0.0f32)];
                let mut cum = vec![0.0];
                for s in 0..segs {
                    th += if segs == 8 { turn } else if s > 0 { r.f(-turn, turn) } else { 0.0 };
                    let (x, y) = pts[pts.len() - 1];
                    pts.push((x + th.cos() * len / segs as f32, y + th.sin() * len / segs as f32));
                    cum.push((s + 1) as f32 / segs as f32);
                }
                let (lo, hi) = pts.iter().fold(((9f32, 9f32), (-9f32, -9f32)), |(l, h), p| {
                    ((l.0.min(p.0), l.1.min(p.1)), (h.0.max(p.0), h.1.max(p.1)))
                });
                let m = ((lo.0 + hi.0) * 0.5, (lo.1 + hi.1) * 0.5);
                pts.iter_mut().for_each(|p| *p = (p.0 - m.0, p.1 - m.1));
                let half = ((hi.0 - lo.0) * 0.5, (hi.1 - lo.1) * 0.5);
                let c = ((start.0 + m.0).rem_euclid(1.0), (start.1 + m.1).rem_euclid(1.0));
                Scratch { c, half, pts, cum, width: r.f(0.5, 2.0) / 512.0, depth: r.f(0.5, 1.0) }
            })
            .collect();
        let dents = (0..r.int(4, 16)).map(|_| {
            let (c, s) = (r.point(), r.f(0.003, 0.012));
            Dent { c, s2: s * s, depth: r.f(0.6, 1.0) }
        });
        let dents = dents.collect();
        Damage { scratches, dents }
    }

    fn into_fn(self, texel: f32) -> Box<dyn Fn(f32, f32) -> f32 + Sync> {
        Box::new(move |u, v| self.eval(u, v, texel))
    }

    fn eval(&self, u: f32, v: f32, texel: f32) -> f32 {
        let mut damage = 0.0f32;
        for s in &self.scratches {
            let (px, py) = (wrap(u - s.c.0), wrap(v - s.c.1));
            let w = s.width.max(texel);
            if px.abs() > s.half.0 + w + texel || py.abs() > s.half.1 + w + texel {
                continue;
            }
            let (mut best, mut along) = (f32::MAX, 0.0);
            for i in 0..s.pts.len() - 1 {
                let (a, b) = (s.pts[i], s.pts[i + 1]);
                let (ex, ey) = (b.0 - a.0, b.1 - a.1);
                let t = (((px - a.0) * ex + (py - a.1) * ey) / (ex * ex + ey * ey)).clamp(0.0, 1.0);
                let d2 = (px - a.0 - t * ex).powi(2) + (py - a.1 - t * ey).powi(2);
                if d2 < best {
                    best = d2;
                    along = s.cum[i] + t * (s.cum[i + 1] - s.cum[i]);
                }
            }
            let cover = ((0.5 * w - best.sqrt()) / texel + 0.5).clamp(0.0, 1.0) * (s.width / w);
            let taper = 0.35 + 0.65 * (std::f32::consts::PI * along).sin();
            damage = damage.max(cover * s.depth * taper);
        }
        for d in &self.dents {
            let (dx, dy) = (wrap(u - d.c.0), wrap(v - d.c.1));
            let s2 = d.s2 + 0.25 * texel * texel;
            let r2 = dx * dx + dy * dy;
            if r2 < 9.0 * s2 {
                damage = damage.max(d.depth * d.s2 / s2 * (-0.5 * r2 / s2).exp());
            }
        }
        1.0 - damage
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [MaskKind; 2] = [MaskKind::Dust, MaskKind::Damage];

    fn mean(v: &[f32]) -> f32 {
        v.iter().sum::<f32>() / v.len() as f32
    }

    /// Mean |row a − row b| + mean |col a − col b|.
    fn line_diff(m: &Mask, a: usize, b: usize) -> f64 {
        let n = m.size;
        let at = |i: usize, j: usize| f64::from(m.data[j * n + i]);
        (0..n).map(|k| (at(k, a) - at(k, b)).abs() + (at(a, k) - at(b, k)).abs()).sum::<f64>() / (2 * n) as f64
    }

    /// Mean absolute differences: (seam, mean and max of interior neighbours, non-neighbour control).
    fn seams(m: &Mask) -> (f64, f64, f64, f64) {
        let n = m.size;
        let inner: Vec<f64> = (0..n - 1).map(|j| line_diff(m, j, j + 1)).collect();
        let max = inner.iter().cloned().fold(0.0, f64::max);
        (line_diff(m, n - 1, 0), inner.iter().sum::<f64>() / (n - 1) as f64, max, line_diff(m, 0, n / 2))
    }

    fn downsample(m: &Mask, f: usize) -> Vec<f32> {
        let n = m.size / f;
        let mut out = vec![0.0; n * n];
        for (j, row) in m.data.chunks(m.size).enumerate() {
            for (i, v) in row.iter().enumerate() {
                out[(j / f) * n + i / f] += v / (f * f) as f32;
            }
        }
        out
    }

    fn mad(a: &[f32], b: &[f32]) -> f32 {
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
    }

    #[test]
    fn deterministic_and_seed_dependent() {
        for kind in KINDS {
            let a = generate(kind, 7, 96);
            assert_eq!(a.data, generate(kind, 7, 96).data);
            let b = generate(kind, 8, 96);
            // Damage masks are mostly exactly 1: count only texels damaged in either mask.
            let live = a.data.iter().zip(&b.data).filter(|(x, y)| kind == MaskKind::Dust || x.min(**y) < 1.0);
            let (n, differ) = live.fold((0, 0), |(n, d), (x, y)| (n + 1, d + usize::from(x != y)));
            assert!(differ * 2 > n && n * 50 > a.data.len(), "{kind:?}: {differ} of {n} texels differ");
        }
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(pool.install(|| generate(MaskKind::Dust, 3, 77)), generate(MaskKind::Dust, 3, 77));
        assert_eq!(generate(MaskKind::Damage, 1, 1).data.len(), 1);
    }

    #[test]
    fn range_and_statistics() {
        let (mut dust, mut damage_min) = (Vec::new(), f32::MAX);
        for seed in 0..16 {
            for kind in KINDS {
                let m = generate(kind, seed, 128);
                assert!(m.data.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "{kind:?} {seed}");
                let mu = mean(&m.data);
                match kind {
                    MaskKind::Dust => dust.push(mu),
                    MaskKind::Damage => {
                        assert!(mu > 0.8, "damage mean {mu} (seed {seed})");
                        damage_min = damage_min.min(m.data.iter().cloned().fold(1.0, f32::min));
                        assert!(m.data.iter().any(|&v| v < 0.5), "seed {seed}: no damage below 0.5");
                    }
                }
            }
        }
        // Documented dust coverage band: each mask's mean in [0.1, 0.8].
        assert!(dust.iter().all(|c| (0.1..=0.8).contains(c)), "dust coverage {dust:?}");
        let spread = dust.iter().cloned().fold(0.0, f32::max) - dust.iter().cloned().fold(1.0, f32::min);
        assert!(spread > 0.15, "dust coverage hardly varies: {dust:?}");
        assert!(damage_min < 0.3, "deepest damage only {damage_min}");
    }

    #[test]
    fn tileable() {
        for kind in KINDS {
            let (mut seam, mut inner, mut control) = (0.0, 0.0, 0.0);
            for seed in 0..16 {
                let (s, i, max, c) = seams(&generate(kind, seed, 128));
                // Per seed the seam must look like an ordinary pair of neighbours.
                assert!(s <= max, "{kind:?} seed {seed}: seam {s} above every interior pair ({max})");
                if kind == MaskKind::Dust {
                    assert!(c > 3.0 * i, "dust seed {seed}: control {c} vs interior {i}");
                }
                (seam, inner, control) = (seam + s, inner + i, control + c);
            }
            assert!(seam < 1.5 * inner, "{kind:?}: seam {seam} vs interior {inner}");
            assert!(control > 2.0 * inner, "{kind:?}: control {control} vs interior {inner}");
        }
    }

    #[test]
    fn resolution_independent() {
        for seed in 0..4 {
            let small = generate(MaskKind::Dust, seed, 64);
            let big = downsample(&generate(MaskKind::Dust, seed, 256), 4);
            let other = generate(MaskKind::Dust, seed + 100, 64);
            let (same, diff) = (mad(&small.data, &big), mad(&small.data, &other.data));
            assert!(same < 0.05 && same * 3.0 < diff, "seed {seed}: 64 vs 256↓ {same}, other seed {diff}");
        }
        for kind in KINDS {
            let (a, b) = (mean(&generate(kind, 5, 64).data), mean(&generate(kind, 5, 512).data));
            assert!((a - b).abs() < 0.03, "{kind:?}: mean {a} at 64² vs {b} at 512²");
        }
    }

    #[test]
    fn png_round_trip() {
        let dir = std::env::temp_dir().join(format!("uplift-masks-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for kind in KINDS {
            let m = generate(kind, 11, 48);
            let bytes = m.to_png16().unwrap();
            assert_eq!(bytes, m.to_png16().unwrap());
            let img = image::load_from_memory(&bytes).unwrap();
            assert_eq!(img.color(), image::ColorType::L16);
            let back = img.into_luma16();
            assert_eq!((back.width(), back.height()), (48, 48));
            assert!(back.as_raw().iter().zip(&m.data).all(|(&p, &v)| (f32::from(p) / 65535.0 - v).abs() <= 1.0 / 65535.0));
            let path = dir.join(format!("{}.png", kind.file_stem()));
            m.write_png(&path).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), bytes);
        }
        let err = generate(MaskKind::Dust, 1, 4).write_png(&dir.join("missing/x.png")).unwrap_err();
        assert!(err.contains("missing/x.png"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Prints timing and statistics, writes 2×2-tiled 256² masks to the temp dir for viewing:
    /// `cargo test -p uplift --lib enhance::masks::tests::report -- --ignored --nocapture`
    #[test]
    #[ignore]
    fn report() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        for kind in KINDS {
            let t = std::time::Instant::now();
            pool.install(|| generate(kind, 1, 512));
            println!("{kind:?}: 512² on one thread {:?}", t.elapsed());
            let ms: Vec<Mask> = (0..16).map(|s| generate(kind, s, 128)).collect();
            let ratio: Vec<f64> = ms[..8].iter().map(seams).map(|(s, i, _, _)| s / i).collect();
            let means: Vec<f32> = ms.iter().map(|m| mean(&m.data)).collect();
            let mins: Vec<f32> = ms.iter().map(|m| m.data.iter().cloned().fold(1.0, f32::min)).collect();
            let rd: Vec<f32> = (0..4).map(|s| mad(&generate(kind, s, 64).data, &downsample(&generate(kind, s, 256), 4))).collect();
            println!("  seam/interior {ratio:.2?}\n  means {means:.3?}\n  minima {mins:.3?}\n  64 vs 256↓ MAD {rd:.4?}");
            let q = generate(kind, 1, 256);
            let tiled = (0..512 * 512).map(|k| q.data[(k / 512 % 256) * 256 + k % 256]).collect();
            Mask { size: 512, data: tiled }.write_png(&std::env::temp_dir().join(format!("uplift-mask-{}-2x2.png", kind.file_stem()))).unwrap();
        }
    }
}
