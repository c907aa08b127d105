//! The demo's bundled inputs: a procedural PBR material set generated from a seed, so the main
//! job needs no downloads. Per enhancement Type, `per_type` materials; Types 0–3 alternate
//! dielectrics and metals, Types 4–5 (dielectric only) are dielectrics. Each has a base colour
//! (a measured metal F0 or a random dielectric hue) modulated by tileable fractal value noise,
//! a roughness field (a base level, the same noise and fine streaks) and constant metalness.

use uplift_engines::batch::TextureData;
use uplift_enhance::pbr_input::{PbrChannel, PbrMaterial, Surface};
use uplift_base::rng::{mix64, unit_from_key as unit};
use uplift_enhance::rules::EnhancementType;
use std::sync::Arc;

/// Linear F0 of some metals (after Hoffman / physicallybased.info).
const METALS: [(&str, [f32; 3]); 6] = [
    ("gold", [1.0, 0.766, 0.336]),
    ("copper", [0.955, 0.638, 0.538]),
    ("silver", [0.972, 0.960, 0.915]),
    ("aluminium", [0.913, 0.922, 0.924]),
    ("iron", [0.562, 0.565, 0.578]),
    ("brass", [0.910, 0.778, 0.423]),
];

/// Tileable value noise with `period` lattice cells across the texture, smoothstep-interpolated.
fn value_noise(x: f32, y: f32, period: u32, key: u64) -> f32 {
    let (fx, fy) = (x * period as f32, y * period as f32);
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let lattice = |i: i64, j: i64| unit(key ^ mix64((i.rem_euclid(period as i64) as u64) << 32 | j.rem_euclid(period as i64) as u64));
    let (i, j) = (x0 as i64, y0 as i64);
    let a = lattice(i, j) + s(tx) * (lattice(i + 1, j) - lattice(i, j));
    let b = lattice(i, j + 1) + s(tx) * (lattice(i + 1, j + 1) - lattice(i, j + 1));
    a + s(ty) * (b - a)
}

/// Four octaves of value noise in [0, 1].
fn fractal(x: f32, y: f32, key: u64) -> f32 {
    let mut v = 0.0;
    let mut amp = 0.5;
    for o in 0..4u32 {
        v += amp * value_noise(x, y, 4 << o, key ^ o as u64);
        amp *= 0.5;
    }
    v / 0.9375
}

fn hsv_to_rgb(h: f32, s: f32, v: f32) -> [f32; 3] {
    let k = |n: f32| {
        let k = (n + h * 6.0) % 6.0;
        v - v * s * k.min(4.0 - k).clamp(0.0, 1.0)
    };
    [k(5.0), k(3.0), k(1.0)]
}

fn texture(size: usize, f: impl Fn(f32, f32) -> [f32; 3]) -> Arc<TextureData> {
    let mut rgba = Vec::with_capacity(size * size * 4);
    for y in 0..size {
        for x in 0..size {
            let c = f((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
            rgba.extend_from_slice(&[c[0], c[1], c[2], 1.0]);
        }
    }
    Arc::new(TextureData { width: size as u32, height: size as u32, rgba })
}

/// One generated material with the Type it is to be enhanced by.
pub struct DemoMaterial {
    pub material: PbrMaterial,
    pub kind: EnhancementType,
    pub metal: bool,
}

/// The procedural set: `per_type` materials for each of the six Types, textures `size`².
pub fn procedural_set(per_type: usize, size: usize, seed: u64) -> Vec<DemoMaterial> {
    let mut out = Vec::new();
    for kind in EnhancementType::ALL {
        for i in 0..per_type {
            let key = mix64(seed ^ mix64((kind.index() as u64) << 16 | i as u64));
            let metal = !kind.dielectric_only() && i % 2 == 1;
            let (family, base) = if metal {
                let m = METALS[(mix64(key ^ 1) % METALS.len() as u64) as usize];
                (m.0.to_string(), m.1)
            } else {
                let h = unit(key ^ 2);
                let rgb = hsv_to_rgb(h, 0.35 + 0.5 * unit(key ^ 3), 0.25 + 0.6 * unit(key ^ 4));
                ("dielectric".to_string(), rgb.map(|c| c * c))
            };
            let rough_base = 0.15 + 0.55 * unit(key ^ 5);
            let contrast = 0.1 + 0.25 * unit(key ^ 6);
            let streaks = unit(key ^ 7) < 0.5;
            let base_color = texture(size, |x, y| {
                let n = fractal(x, y, key ^ 11);
                let m = 1.0 + contrast * (n - 0.5) * 2.0;
                base.map(|c| (c * m).clamp(0.0, 1.0))
            });
            let roughness = texture(size, |x, y| {
                let n = fractal(x, y, key ^ 12);
                let s = if streaks { 0.08 * (value_noise(x * 0.05, y, 64, key ^ 13) - 0.5) } else { 0.0 };
                let r = (rough_base + 0.3 * (n - 0.5) + s).clamp(0.05, 1.0);
                [r; 3]
            });
            let name = format!("t{}_{:02}_{family}", kind.index(), i);
            out.push(DemoMaterial {
                material: PbrMaterial {
                    source: format!("uplift demo procedural set (seed {seed}) #{name}"),
                    name,
                    base_color: PbrChannel::Pixels(base_color),
                    roughness: PbrChannel::Pixels(roughness),
                    metalness: PbrChannel::Constant(vec![if metal { 1.0 } else { 0.0 }]),
                    normal_map: None,
                    surface: Surface::Plane,
                },
                kind,
                metal,
            });
        }
    }
    out
}
