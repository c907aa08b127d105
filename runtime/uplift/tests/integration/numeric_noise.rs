//! Noise nodes (noise2d, noise3d, fractal2d, fractal3d, cellnoise2d, cellnoise3d,
//! worleynoise2d, worleynoise3d), every type variant including the FA (float amplitude) and
//! colour variants that the stdlib implements as nodegraphs: compiled, run on wgpu for 256
//! seeded points, and compared with an independent scalar Rust implementation written here
//! (module `reference`) from MaterialX's algorithm (`genglsl/lib/mx_noise.glsl`, itself OSL's
//! `oslnoise.h`): Bob Jenkins' lookup3 hash, quintic fade, gradient lattice noise, cell noise,
//! Worley noise, fBm. The WGSL library is deliberately not consulted by this file.
//!
//! Tolerances: |err| ≤ 1e-5 for unit amplitude (arithmetic only; f32 rounding and possible FMA
//! contraction on the device), 1e-5 · max(1, |amplitude|) when amplitudes vary; cell noise
//! is hash-derived and matches to 1e-6. Coordinates cross lattice lines: negatives, values up
//! to ±100, exact integers and points a hair off them.
//!
//! Also checked over 4096 points: the output ranges NOISE.md documents (perlin in [-1, 1]
//! with both signs, 0 at lattice points; fractal within ±Σ diminish^i; cell noise in [0, 1);
//! Worley distances ≥ 0 and sorted, F1 within the own cell's bound; Solid in [0, 1]).

use crate::common;
use crate::graph_kit;

use common::*;
use graph_kit::*;
use uplift_engines::batch::Geometry;
use uplift_compiler::PatternKernel;


/// An independent implementation of MaterialX's (OSL's) noise, in f32 like the shaders.
mod reference {
    /// lookup3 `mix`.
    fn mix(a: &mut u32, b: &mut u32, c: &mut u32) {
        *a = a.wrapping_sub(*c);
        *a ^= c.rotate_left(4);
        *c = c.wrapping_add(*b);
        *b = b.wrapping_sub(*a);
        *b ^= a.rotate_left(6);
        *a = a.wrapping_add(*c);
        *c = c.wrapping_sub(*b);
        *c ^= b.rotate_left(8);
        *b = b.wrapping_add(*a);
        *a = a.wrapping_sub(*c);
        *a ^= c.rotate_left(16);
        *c = c.wrapping_add(*b);
        *b = b.wrapping_sub(*a);
        *b ^= a.rotate_left(19);
        *a = a.wrapping_add(*c);
        *c = c.wrapping_sub(*b);
        *c ^= b.rotate_left(4);
        *b = b.wrapping_add(*a);
    }

    /// lookup3 `final`; returns c.
    fn fin(mut a: u32, mut b: u32, mut c: u32) -> u32 {
        c ^= b;
        c = c.wrapping_sub(b.rotate_left(14));
        a ^= c;
        a = a.wrapping_sub(c.rotate_left(11));
        b ^= a;
        b = b.wrapping_sub(a.rotate_left(25));
        c ^= b;
        c = c.wrapping_sub(b.rotate_left(16));
        a ^= c;
        a = a.wrapping_sub(c.rotate_left(4));
        b ^= a;
        b = b.wrapping_sub(a.rotate_left(14));
        c ^= b;
        c = c.wrapping_sub(b.rotate_left(24));
        c
    }

    /// lookup3 `hashword(keys, len, 13)`: the general form (consume three keys per `mix`, then
    /// add the remaining 1..3 keys and `final`). MaterialX unrolls this for 1..5 keys.
    pub fn hash(keys: &[i32]) -> u32 {
        assert!(!keys.is_empty());
        let init = 0xdead_beef_u32.wrapping_add((keys.len() as u32) << 2).wrapping_add(13);
        let (mut a, mut b, mut c) = (init, init, init);
        let mut k: Vec<u32> = keys.iter().map(|&x| x as u32).collect();
        while k.len() > 3 {
            a = a.wrapping_add(k[0]);
            b = b.wrapping_add(k[1]);
            c = c.wrapping_add(k[2]);
            mix(&mut a, &mut b, &mut c);
            k.drain(0..3);
        }
        if k.len() == 3 {
            c = c.wrapping_add(k[2]);
        }
        if k.len() >= 2 {
            b = b.wrapping_add(k[1]);
        }
        a = a.wrapping_add(k[0]);
        fin(a, b, c)
    }

    pub fn bits_to_01(h: u32) -> f32 {
        h as f32 / u32::MAX as f32
    }

    /// (floor as integer, fractional part).
    fn floorfrac(x: f32) -> (i32, f32) {
        let i = x.floor() as i32;
        (i, x - i as f32)
    }

    fn fade(t: f32) -> f32 {
        t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
    }

    fn neg_if(v: f32, b: bool) -> f32 {
        if b {
            -v
        } else {
            v
        }
    }

    /// 2D gradient: directions (±1, ±2) and (±2, ±1) from the low 3 bits.
    fn grad2(h: u32, x: f32, y: f32) -> f32 {
        let h = h & 7;
        let (u, v) = if h < 4 { (x, 2.0 * y) } else { (y, 2.0 * x) };
        neg_if(u, h & 1 != 0) + neg_if(v, h & 2 != 0)
    }

    /// 3D gradient: the 12 cube-edge directions (plus 4 repeats) from the low 4 bits.
    fn grad3(h: u32, x: f32, y: f32, z: f32) -> f32 {
        let h = h & 15;
        let u = if h < 8 { x } else { y };
        let v = if h < 4 {
            y
        } else if h == 12 || h == 14 {
            x
        } else {
            z
        };
        neg_if(u, h & 1 != 0) + neg_if(v, h & 2 != 0)
    }

    fn lerp2(v: [f32; 4], s: f32, t: f32) -> f32 {
        let s1 = 1.0 - s;
        (1.0 - t) * (v[0] * s1 + v[1] * s) + t * (v[2] * s1 + v[3] * s)
    }

    fn lerp3(v: [f32; 8], s: f32, t: f32, r: f32) -> f32 {
        let (s1, t1, r1) = (1.0 - s, 1.0 - t, 1.0 - r);
        r1 * (t1 * (v[0] * s1 + v[1] * s) + t * (v[2] * s1 + v[3] * s)) + r * (t1 * (v[4] * s1 + v[5] * s) + t * (v[6] * s1 + v[7] * s))
    }

    /// Gradient noise on the 2D lattice; `slice` picks the hash bits (None: the whole hash,
    /// Some(k): byte k, as the 3-channel noise does).
    fn perlin2_with(p: [f32; 2], slice: Option<u32>) -> f32 {
        let (ix, fx) = floorfrac(p[0]);
        let (iy, fy) = floorfrac(p[1]);
        let h = |dx: i32, dy: i32| {
            let full = hash(&[ix.wrapping_add(dx), iy.wrapping_add(dy)]);
            match slice {
                None => full,
                Some(k) => (full >> (8 * k)) & 0xff,
            }
        };
        let v = [grad2(h(0, 0), fx, fy), grad2(h(1, 0), fx - 1.0, fy), grad2(h(0, 1), fx, fy - 1.0), grad2(h(1, 1), fx - 1.0, fy - 1.0)];
        0.6616 * lerp2(v, fade(fx), fade(fy))
    }

    fn perlin3_with(p: [f32; 3], slice: Option<u32>) -> f32 {
        let (ix, fx) = floorfrac(p[0]);
        let (iy, fy) = floorfrac(p[1]);
        let (iz, fz) = floorfrac(p[2]);
        let mut v = [0.0; 8];
        for (k, slot) in v.iter_mut().enumerate() {
            let (dx, dy, dz) = ((k & 1) as i32, ((k >> 1) & 1) as i32, ((k >> 2) & 1) as i32);
            let full = hash(&[ix.wrapping_add(dx), iy.wrapping_add(dy), iz.wrapping_add(dz)]);
            let h = match slice {
                None => full,
                Some(c) => (full >> (8 * c)) & 0xff,
            };
            *slot = grad3(h, fx - dx as f32, fy - dy as f32, fz - dz as f32);
        }
        0.9820 * lerp3(v, fade(fx), fade(fy), fade(fz))
    }

    pub fn perlin2(p: [f32; 2]) -> f32 {
        perlin2_with(p, None)
    }
    pub fn perlin3(p: [f32; 3]) -> f32 {
        perlin3_with(p, None)
    }
    pub fn perlin2_v3(p: [f32; 2]) -> [f32; 3] {
        [0, 1, 2].map(|c| perlin2_with(p, Some(c)))
    }
    pub fn perlin3_v3(p: [f32; 3]) -> [f32; 3] {
        [0, 1, 2].map(|c| perlin3_with(p, Some(c)))
    }

    /// fBm: Σ diminish^i · noise(p · lacunarity^i), with the powers accumulated by repeated
    /// multiplication as the shaders do. `noise` returns any number of channels.
    pub fn fbm<const D: usize>(mut p: [f32; D], octaves: i32, lacunarity: f32, diminish: f32, noise: &dyn Fn([f32; D]) -> Vec<f32>) -> Vec<f32> {
        let mut result = noise(p).iter().map(|_| 0.0).collect::<Vec<f32>>();
        let mut amp = 1.0f32;
        for _ in 0..octaves.max(0) {
            let n = noise(p);
            for (r, v) in result.iter_mut().zip(n) {
                *r += amp * v;
            }
            amp *= diminish;
            for c in p.iter_mut() {
                *c *= lacunarity;
            }
        }
        result
    }

    pub fn cell2(p: [f32; 2]) -> f32 {
        bits_to_01(hash(&[p[0].floor() as i32, p[1].floor() as i32]))
    }
    pub fn cell3(p: [f32; 3]) -> f32 {
        bits_to_01(hash(&[p[0].floor() as i32, p[1].floor() as i32, p[2].floor() as i32]))
    }
    /// 3-channel cell noise of an integer cell (channel index as an extra hash key).
    fn cell_v3_int(cell: &[i32]) -> [f32; 3] {
        [0, 1, 2].map(|ch| {
            let mut keys = cell.to_vec();
            keys.push(ch);
            bits_to_01(hash(&keys))
        })
    }

    /// Worley result of one point: the three smallest squared distances (ascending), and the
    /// nearest feature point in absolute coordinates (computed as the GLSL does:
    /// (feature − local position) + p), plus the gap between the two smallest squared
    /// distances (to recognise ties).
    pub struct Worley {
        pub sq: [f32; 3],
        pub nearest_abs: Vec<f32>,
        pub gap: f32,
    }

    pub fn worley<const D: usize>(p: [f32; D], jitter: f32) -> Worley {
        let cell: Vec<i32> = p.iter().map(|x| x.floor() as i32).collect();
        let local: Vec<f32> = p.iter().zip(&cell).map(|(x, i)| x - *i as f32).collect();
        let mut sq = [1e6f32; 3];
        let mut nearest_rel = vec![0.0; D];
        let mut all = Vec::new();
        // Offsets in the shaders' loop order: x outermost, the last axis innermost.
        let n = 3usize.pow(D as u32);
        for k in 0..n {
            let off: Vec<i32> = (0..D).map(|a| ((k / 3usize.pow((D - 1 - a) as u32)) % 3) as i32 - 1).collect();
            let c: Vec<i32> = off.iter().zip(&cell).map(|(o, i)| o.wrapping_add(*i)).collect();
            let r = cell_v3_int(&c);
            let feat: Vec<f32> = (0..D).map(|a| off[a] as f32 + ((r[a] - 0.5) * jitter + 0.5)).collect();
            let rel: Vec<f32> = feat.iter().zip(&local).map(|(f, l)| f - l).collect();
            let d: f32 = rel.iter().map(|x| x * x).sum();
            all.push(d);
            if d < sq[0] {
                sq = [d, sq[0], sq[1]];
                nearest_rel = rel;
            } else if d < sq[1] {
                sq = [sq[0], d, sq[1]];
            } else if d < sq[2] {
                sq[2] = d;
            }
        }
        let gap = sq[1] - sq[0];
        Worley { sq, nearest_abs: nearest_rel.iter().zip(&p).map(|(r, x)| r + x).collect(), gap }
    }

    pub fn worley_out<const D: usize>(p: [f32; D], jitter: f32, style: i32, channels: usize) -> (Vec<f32>, f32) {
        let w = worley(p, jitter);
        let v = if style == 1 {
            if channels == 1 {
                let q = &w.nearest_abs;
                let keys: Vec<i32> = q.iter().map(|x| x.floor() as i32).collect();
                vec![bits_to_01(hash(&keys))]
            } else {
                let keys: Vec<i32> = w.nearest_abs.iter().map(|x| x.floor() as i32).collect();
                cell_v3_int(&keys)[..channels].to_vec()
            }
        } else {
            w.sq[..channels].iter().map(|d| d.sqrt()).collect()
        };
        (v, w.gap)
    }
}

use reference as r;

/// The reference implementation against the hash check values and sample table of NOISE.md
/// (no GPU involved): validates the test's own implementation.
#[test]
#[allow(clippy::excessive_precision)] // the values as NOISE.md prints them
fn reference_matches_documented_values() {
    assert_eq!(r::hash(&[0, 0]), 0xdc3d74f9);
    assert_eq!(r::hash(&[0, 0, 0]), 0x9c6eedfb);
    assert_eq!(r::hash(&[1, 2, 3]), 0xb8d17a0a);
    assert_eq!(r::hash(&[1, 2, 3, 0]), 0x129dac66);
    let t2: [([f32; 2], f32, f32, f32); 3] =
        [([0.5, 0.5], 0.0, 0.8603128, 0.3332307), ([1.25, 2.75], -0.2610395, 0.0633514, 0.2507259), ([-3.3, 4.1], 0.3355922, 0.7787855, 0.6382641)];
    for (p, n, c, w) in t2 {
        assert!((r::perlin2(p) - n).abs() < 1e-6, "perlin2 {p:?}: {}", r::perlin2(p));
        assert!((r::cell2(p) - c).abs() < 1e-6, "cell2 {p:?}: {}", r::cell2(p));
        let f1 = r::worley_out(p, 1.0, 0, 1).0[0];
        assert!((f1 - w).abs() < 1e-6, "worley2 {p:?}: {f1}");
    }
    let t3: [([f32; 3], f32, f32, f32); 3] = [
        ([0.5, 0.5, 0.5], 0.1227500, 0.6110677, 0.4550631),
        ([1.25, 2.75, -0.6], 0.4617804, 0.1760370, 0.2656688),
        ([-3.3, 4.1, 9.9], 0.0120480, 0.9841983, 0.2663136),
    ];
    for (p, n, c, w) in t3 {
        assert!((r::perlin3(p) - n).abs() < 1e-6, "perlin3 {p:?}: {}", r::perlin3(p));
        assert!((r::cell3(p) - c).abs() < 1e-6, "cell3 {p:?}: {}", r::cell3(p));
        let f1 = r::worley_out(p, 1.0, 0, 1).0[0];
        assert!((f1 - w).abs() < 1e-6, "worley3 {p:?}: {f1}");
    }
}

// ---- point generation ---------------------------------------------------------------------

/// One coordinate that exercises the lattice: small signed values, large values (±100),
/// exact integers, and values a hair either side of an integer.
fn coord(rng: &mut Rng) -> f32 {
    let class = rng.next_u64() % 5;
    match class {
        0 => rng.range(-3.0, 3.0),
        1 => rng.range(-100.0, 100.0),
        2 => rng.range(-60.0, 60.0).floor(),
        3 => rng.range(-60.0, 60.0).floor() + [1e-4, -1e-4, 0.5, 0.999, 1e-3][(rng.next_u64() % 5) as usize],
        _ => rng.range(-12.0, 12.0),
    }
}

fn point<const D: usize>(rng: &mut Rng) -> [f32; D] {
    [0; D].map(|_| coord(rng))
}

fn splat(x: f32, n: usize) -> Vec<f32> {
    vec![x; n]
}

/// amplitude * value + pivot, componentwise (amplitude given per component).
fn scale(v: &[f32], amp: &[f32], pivot: f32) -> Vec<f32> {
    v.iter().zip(amp).map(|(x, a)| x * a + pivot).collect()
}

fn check(what: &str, i: usize, got: &[f32], want: &[f32], tol: f32, ctx: &dyn Fn() -> String) {
    let e = max_err(got, want);
    assert!(e <= tol || (got.iter().any(|g| g.is_nan()) && want.iter().any(|w| w.is_nan())), "{what}, point {i} ({}): got {got:?}, want {want:?}, max |err| {e} > {tol}", ctx());
}

fn run_rows(k: &PatternKernel, rows: &[Vec<f32>], geom: Option<&[Geometry]>) -> Vec<Vec<f32>> {
    let g: Vec<Geometry> = match geom {
        Some(g) => g.to_vec(),
        None => vec![Geometry::default(); rows.len()],
    };
    run(k, &g, rows, vec![])
}

// ---- noise2d / noise3d ----------------------------------------------------------------------

/// The 11 node signatures of noise2d/noise3d/fractal2d/fractal3d: (output type, amplitude type).
const VARIANTS: [(&str, &str); 11] = [
    ("float", "float"),
    ("vector2", "vector2"),
    ("vector3", "vector3"),
    ("vector4", "vector4"),
    ("color3", "vector3"),
    ("color4", "vector4"),
    ("vector2", "float"),
    ("vector3", "float"),
    ("vector4", "float"),
    ("color3", "float"),
    ("color4", "float"),
];

fn amp_input(ty: &str) -> &'static str {
    match ty {
        "float" => "a1",
        "vector2" => "a2",
        "vector3" => "a3",
        _ => "a4",
    }
}

fn variant_name(out_ty: &str, amp_ty: &str) -> String {
    if out_ty != "float" && amp_ty == "float" {
        format!("{out_ty}FA")
    } else {
        out_ty.to_string()
    }
}

/// The perlin value of `dim`-D noise at p, with `n` channels, before amplitude and pivot:
/// 1: float; 2: the first two of the 3-channel noise; 3: 3-channel; 4: (3-channel, float
/// noise at p + (19, 73[, 29])).
fn noise_channels(p: &[f32], n: usize) -> Vec<f32> {
    let v3 = |p: &[f32]| if p.len() == 2 { r::perlin2_v3([p[0], p[1]]).to_vec() } else { r::perlin3_v3([p[0], p[1], p[2]]).to_vec() };
    let f = |p: &[f32]| if p.len() == 2 { r::perlin2([p[0], p[1]]) } else { r::perlin3([p[0], p[1], p[2]]) };
    match n {
        1 => vec![f(p)],
        2 => v3(p)[..2].to_vec(),
        3 => v3(p),
        _ => {
            let mut v = v3(p);
            let off = [19.0, 73.0, 29.0];
            let q: Vec<f32> = p.iter().zip(off).map(|(x, o)| x + o).collect();
            v.push(f(&q));
            v
        }
    }
}

fn noise_test(dim: usize) {
    let (node_tag, coord_input, coord_ty) = if dim == 2 { ("noise2d", "texcoord", "vector2") } else { ("noise3d", "position", "vector3") };
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    for (o, a) in VARIANTS {
        let name = format!("n_{}", variant_name(o, a));
        nodes.push(node(node_tag, &name, o, &[("amplitude", a, Src::I(amp_input(a))), ("pivot", "float", Src::I("pivot")), (coord_input, coord_ty, Src::I("p"))]));
        outs.push((name.clone(), o.to_string(), name));
        // Unit amplitude, zero pivot (the nodedef defaults): the tight checks.
        let uname = format!("u_{}", variant_name(o, a));
        nodes.push(node(node_tag, &uname, o, &[(coord_input, coord_ty, Src::I("p"))]));
        outs.push((uname.clone(), o.to_string(), uname));
    }
    // The coordinate left unconnected: UV0 (2D) / Pobject (3D) from the geometry.
    nodes.push(node(node_tag, "g_float", "float", &[]));
    outs.push(("g_float".into(), "float".into(), "g_float".into()));
    let doc = graph_doc(&[("p", coord_ty), ("a1", "float"), ("a2", "vector2"), ("a3", "vector3"), ("a4", "vector4"), ("pivot", "float")], &nodes, &outs);
    let k = compile(&doc);

    let mut rng = Rng::new(0x2d00 + dim as u64);
    let n = 256;
    let mut rows = Vec::new();
    let mut geom = Vec::new();
    let mut pts = Vec::new();
    let mut amps = Vec::new();
    for _ in 0..n {
        let p: Vec<f32> = if dim == 2 { point::<2>(&mut rng).to_vec() } else { point::<3>(&mut rng).to_vec() };
        let a: Vec<f32> = (0..4).map(|_| rng.range(-2.0, 2.0)).collect();
        let pivot = rng.range(-1.0, 1.0);
        rows.push(input_row(&k, &[("p", p.clone()), ("a1", vec![a[0]]), ("a2", a[..2].to_vec()), ("a3", a[..3].to_vec()), ("a4", a.clone()), ("pivot", vec![pivot])]));
        let q: Vec<f32> = (0..dim).map(|_| rng.range(-20.0, 20.0)).collect();
        geom.push(if dim == 2 {
            Geometry { texcoord: [q[0], q[1]], ..Default::default() }
        } else {
            Geometry { position: [q[0], q[1], q[2]], ..Default::default() }
        });
        pts.push(p);
        amps.push((a, pivot));
    }
    let got = run_rows(&k, &rows, Some(&geom));
    for i in 0..n {
        let p = &pts[i];
        let (a, pivot) = &amps[i];
        let ctx = || format!("p = {p:?}, amplitude = {a:?}, pivot = {pivot}");
        for (o, at) in VARIANTS {
            let v = variant_name(o, at);
            let ch = comps(o);
            let base = noise_channels(p, ch);
            let amp: Vec<f32> = if at == "float" { splat(a[0], ch) } else { a[..ch].to_vec() };
            let want = scale(&base, &amp, *pivot);
            let tol = 1e-5 * amp.iter().fold(1.0f32, |m, x| m.max(x.abs()));
            check(&format!("{node_tag} {v}"), i, out(&k, &got[i], &format!("n_{v}")), &want, tol, &ctx);
            check(&format!("{node_tag} {v} (unit amplitude)"), i, out(&k, &got[i], &format!("u_{v}")), &base, 1e-5, &ctx);
        }
        let gp: Vec<f32> = if dim == 2 { geom[i].texcoord.to_vec() } else { geom[i].position.to_vec() };
        check(&format!("{node_tag} float, coordinate from geometry"), i, out(&k, &got[i], "g_float"), &noise_channels(&gp, 1), 1e-5, &|| format!("{gp:?}"));
    }

    // Ranges over many points (unit amplitude): within [-1, 1], both signs, 0 at lattice points.
    let m = 4096;
    let mut rows = Vec::new();
    let mut pts = Vec::new();
    for j in 0..m {
        let mut p: Vec<f32> = (0..dim).map(|_| rng.range(-100.0, 100.0)).collect();
        if j % 16 == 0 {
            p.iter_mut().for_each(|x| *x = x.round());
        }
        rows.push(input_row(&k, &[("p", p.clone()), ("a1", vec![1.0]), ("a2", vec![1.0; 2]), ("a3", vec![1.0; 3]), ("a4", vec![1.0; 4]), ("pivot", vec![0.0])]));
        pts.push(p);
    }
    let got = run_rows(&k, &rows, None);
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for (j, row) in got.iter().enumerate() {
        for (o, at) in VARIANTS {
            let v = out(&k, row, &format!("u_{}", variant_name(o, at)));
            for &x in v {
                assert!((-1.0..=1.0).contains(&x), "{node_tag} {o}: {x} outside [-1, 1] at {:?}", pts[j]);
                lo = lo.min(x);
                hi = hi.max(x);
            }
            if j % 16 == 0 {
                // Every channel (the 4th too: p + (19, 73[, 29]) is a lattice point as well).
                assert!(v.iter().all(|x| x.abs() <= 1e-6), "{node_tag} {o} at lattice point {:?}: {v:?}", pts[j]);
            }
        }
    }
    assert!(lo < -0.5 && hi > 0.5, "{node_tag}: observed range [{lo}, {hi}] should span both signs");
}

#[test]
fn noise2d_all_variants() {
    noise_test(2);
}

#[test]
fn noise3d_all_variants() {
    noise_test(3);
}

// ---- fractal2d / fractal3d --------------------------------------------------------------------

/// fBm channels before amplitude: 1: float; 2: (float at p, float at p + (19, 193[, 17]));
/// 3: 3-channel; 4: (3-channel, float at p + (19, 193[, 17])).
fn fractal_channels(p: &[f32], n: usize, oct: i32, lac: f32, dim_: f32) -> Vec<f32> {
    let off = [19.0, 193.0, 17.0];
    let q: Vec<f32> = p.iter().zip(off).map(|(x, o)| x + o).collect();
    let f = |p: &[f32]| -> f32 {
        if p.len() == 2 {
            r::fbm([p[0], p[1]], oct, lac, dim_, &|x| vec![r::perlin2(x)])[0]
        } else {
            r::fbm([p[0], p[1], p[2]], oct, lac, dim_, &|x| vec![r::perlin3(x)])[0]
        }
    };
    let v3 = |p: &[f32]| -> Vec<f32> {
        if p.len() == 2 {
            r::fbm([p[0], p[1]], oct, lac, dim_, &|x| r::perlin2_v3(x).to_vec())
        } else {
            r::fbm([p[0], p[1], p[2]], oct, lac, dim_, &|x| r::perlin3_v3(x).to_vec())
        }
    };
    match n {
        1 => vec![f(p)],
        2 => vec![f(p), f(&q)],
        3 => v3(p),
        _ => {
            let mut v = v3(p);
            v.push(f(&q));
            v
        }
    }
}

fn fractal_test(dim: usize) {
    let (node_tag, coord_input, coord_ty) = if dim == 2 { ("fractal2d", "texcoord", "vector2") } else { ("fractal3d", "position", "vector3") };
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    let params = |a: &'static str, at: &'static str| {
        vec![
            ("amplitude", at, Src::I(a)),
            ("octaves", "integer", Src::I("octaves")),
            ("lacunarity", "float", Src::I("lacunarity")),
            ("diminish", "float", Src::I("diminish")),
            (coord_input, coord_ty, Src::I("p")),
        ]
    };
    for (o, a) in VARIANTS {
        let name = format!("n_{}", variant_name(o, a));
        nodes.push(node(node_tag, &name, o, &params(amp_input(a), a)));
        outs.push((name.clone(), o.to_string(), name));
    }
    // Defaults (amplitude 1, 3 octaves, lacunarity 2, diminish 0.5), coordinate from the graph.
    for o in ["float", "vector2", "vector3", "vector4"] {
        let name = format!("d_{o}");
        nodes.push(node(node_tag, &name, o, &[(coord_input, coord_ty, Src::I("p"))]));
        outs.push((name.clone(), o.to_string(), name));
    }
    let doc = graph_doc(
        &[("p", coord_ty), ("a1", "float"), ("a2", "vector2"), ("a3", "vector3"), ("a4", "vector4"), ("octaves", "integer"), ("lacunarity", "float"), ("diminish", "float")],
        &nodes,
        &outs,
    );
    let k = compile(&doc);

    let mut rng = Rng::new(0xf2a0 + dim as u64);
    let n = 256;
    let mut rows = Vec::new();
    let mut cases = Vec::new();
    for i in 0..n {
        // Coordinates up to ±50 (higher octaves reach ±50 · lacunarity^4 ≈ 2000).
        let p: Vec<f32> = (0..dim).map(|_| coord(&mut rng) * 0.5).collect();
        let a: Vec<f32> = (0..4).map(|_| rng.range(-2.0, 2.0)).collect();
        // octaves: -1 and 0 give 0; up to 5.
        let oct = i % 7 - 1;
        let lac = rng.range(1.5, 2.5);
        let dmn = rng.range(0.3, 0.7);
        rows.push(input_row(
            &k,
            &[
                ("p", p.clone()),
                ("a1", vec![a[0]]),
                ("a2", a[..2].to_vec()),
                ("a3", a[..3].to_vec()),
                ("a4", a.clone()),
                ("octaves", vec![oct as f32]),
                ("lacunarity", vec![lac]),
                ("diminish", vec![dmn]),
            ],
        ));
        cases.push((p, a, oct, lac, dmn));
    }
    let got = run_rows(&k, &rows, None);
    for (i, (p, a, oct, lac, dmn)) in cases.iter().enumerate() {
        let ctx = || format!("p = {p:?}, amplitude = {a:?}, octaves {oct}, lacunarity {lac}, diminish {dmn}");
        // Σ diminish^i bounds each channel's error scale as well as its value.
        let bound: f32 = (0..(*oct).max(0)).map(|j| dmn.powi(j)).sum();
        for (o, at) in VARIANTS {
            let v = variant_name(o, at);
            let ch = comps(o);
            let base = fractal_channels(p, ch, *oct, *lac, *dmn);
            let amp: Vec<f32> = if at == "float" { splat(a[0], ch) } else { a[..ch].to_vec() };
            let want = scale(&base, &amp, 0.0);
            let tol = 1e-5 * amp.iter().fold(1.0f32, |m, x| m.max(x.abs())) * bound.max(1.0);
            check(&format!("{node_tag} {v}"), i, out(&k, &got[i], &format!("n_{v}")), &want, tol, &ctx);
            for x in &base {
                assert!(x.abs() <= bound + 1e-5, "{node_tag} {v}: |{x}| > Σ diminish^i = {bound} ({})", ctx());
            }
        }
        for o in ["float", "vector2", "vector3", "vector4"] {
            let want = fractal_channels(p, comps(o), 3, 2.0, 0.5);
            check(&format!("{node_tag} {o} (defaults)"), i, out(&k, &got[i], &format!("d_{o}")), &want, 1.75e-5, &ctx);
            for x in out(&k, &got[i], &format!("d_{o}")) {
                assert!(x.abs() <= 1.75, "{node_tag} {o} (defaults): |{x}| > 1.75 at {p:?}");
            }
        }
    }
}

#[test]
fn fractal2d_all_variants() {
    fractal_test(2);
}

#[test]
fn fractal3d_all_variants() {
    fractal_test(3);
}

/// Issue 46: fractal3d at 34, 64 and 1000 octaves (MaterialX's GLSL converts lattice
/// coordinates past 2^31 to int, undefined; a saturating conversion gave NaN from 34 octaves on)
/// is finite and is the converged sum. With lacunarity 2, every coordinate of p · 2^i is an f32
/// integer from the first octave K where all of them are (at most 2^25 here, inside MaterialX's
/// defined range), and Perlin noise is exactly 0 on the lattice, so MaterialX's sum over K
/// octaves is the sum over any more: the extra octaves must add exactly 0 (the same bits as at K
/// octaves), and the value must match the reference's K-octave sum within the fractal tests'
/// tolerance, 1e-5 · Σ 0.5^i < 2e-5 (f32 rounding of each term, possible FMA contraction).
/// A point whose coordinates differ by 2^-70 (one passes 2^31 long before the other is an
/// integer) is finite and within the ±Σ 0.5^i = 2 bound.
#[test]
fn fractal3d_is_finite_and_converged_for_any_octave_count() {
    let doc = graph_doc(
        &[("p", "vector3"), ("octaves", "integer")],
        &[node("fractal3d", "n", "float", &[("octaves", "integer", Src::I("octaves")), ("position", "vector3", Src::I("p"))])],
        &[("n".to_string(), "float".to_string(), "n".to_string())],
    );
    let k = compile(&doc);
    let mut rng = Rng::new(0x46_12);
    let mut points: Vec<[f32; 3]> = (0..16).map(|_| [0; 3].map(|_| rng.range(0.5, 4.0) * if rng.next_u64() % 2 == 0 { 1.0 } else { -1.0 })).collect();
    points.push([0.3, 0.7, 1.1]);
    let lattice_from = |p: [f32; 3]| (0..64).find(|&i| p.iter().all(|c| { let x = c * 2f32.powi(i); x.floor() == x })).unwrap();
    let counts = [34, 64, 1000];
    let mut rows = Vec::new();
    for p in &points {
        let kk = lattice_from(*p);
        assert!(kk <= 25, "{p:?}: lattice from octave {kk}");
        for oct in std::iter::once(kk).chain(counts) {
            rows.push(input_row(&k, &[("p", p.to_vec()), ("octaves", vec![oct as f32])]));
        }
    }
    let mixed = [0.3f32, 0.3 * 2f32.powi(-70), 0.7];
    for oct in counts {
        rows.push(input_row(&k, &[("p", mixed.to_vec()), ("octaves", vec![oct as f32])]));
    }
    let got = run_rows(&k, &rows, None);
    for (j, p) in points.iter().enumerate() {
        let kk = lattice_from(*p);
        let at_k = out(&k, &got[j * 4], "n")[0];
        let want = r::fbm(*p, kk, 2.0, 0.5, &|x| vec![r::perlin3(x)])[0];
        assert!((at_k - want).abs() <= 2e-5, "{p:?}, {kk} octaves: {at_k}, reference {want}");
        for (c, oct) in counts.iter().enumerate() {
            let v = out(&k, &got[j * 4 + 1 + c], "n")[0];
            assert!(v.is_finite() && v.to_bits() == at_k.to_bits(), "{p:?}: {oct} octaves give {v}, {kk} octaves {at_k}");
        }
    }
    for (c, oct) in counts.iter().enumerate() {
        let v = out(&k, &got[points.len() * 4 + c], "n")[0];
        assert!(v.is_finite() && v.abs() <= 2.0, "{mixed:?}: {oct} octaves give {v}");
    }
}

// ---- cellnoise ----------------------------------------------------------------------------

#[test]
fn cellnoise2d_and_cellnoise3d() {
    let nodes = vec![
        node("cellnoise2d", "c2", "float", &[("texcoord", "vector2", Src::I("p2"))]),
        node("cellnoise3d", "c3", "float", &[("position", "vector3", Src::I("p3"))]),
        node("cellnoise2d", "g2", "float", &[]),
        node("cellnoise3d", "g3", "float", &[]),
    ];
    let outs: Vec<(String, String, String)> = ["c2", "c3", "g2", "g3"].iter().map(|n| (n.to_string(), "float".to_string(), n.to_string())).collect();
    let k = compile(&graph_doc(&[("p2", "vector2"), ("p3", "vector3")], &nodes, &outs));
    let mut rng = Rng::new(0xce11);
    let n = 4096;
    let mut rows = Vec::new();
    let mut geom = Vec::new();
    let mut pts = Vec::new();
    for _ in 0..n {
        let p2 = point::<2>(&mut rng);
        let p3 = point::<3>(&mut rng);
        rows.push(input_row(&k, &[("p2", p2.to_vec()), ("p3", p3.to_vec())]));
        let g = Geometry { texcoord: point::<2>(&mut rng), position: point::<3>(&mut rng), ..Default::default() };
        geom.push(g);
        pts.push((p2, p3));
    }
    let got = run_rows(&k, &rows, Some(&geom));
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for i in 0..n {
        let (p2, p3) = pts[i];
        let g = &geom[i];
        // Hash-derived: equal up to the rounding of the u32 → f32 conversion.
        let cases = [("cellnoise2d", "c2", r::cell2(p2), format!("{p2:?}")), ("cellnoise3d", "c3", r::cell3(p3), format!("{p3:?}")), ("cellnoise2d (UV0)", "g2", r::cell2(g.texcoord), format!("{:?}", g.texcoord)), ("cellnoise3d (Pobject)", "g3", r::cell3(g.position), format!("{:?}", g.position))];
        for (what, name, want, p) in cases {
            let v = out(&k, &got[i], name)[0];
            if i < 256 {
                check(what, i, &[v], &[want], 1e-6, &|| p.clone());
            }
            assert!((0.0..1.0).contains(&v), "{what}: {v} outside [0, 1) at {p}");
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    assert!(lo < 0.01 && hi > 0.99, "cell noise should cover [0, 1): observed [{lo}, {hi}]");
}

// ---- worleynoise ----------------------------------------------------------------------------

fn worley_test(dim: usize) {
    let (node_tag, coord_input, coord_ty) = if dim == 2 { ("worleynoise2d", "texcoord", "vector2") } else { ("worleynoise3d", "position", "vector3") };
    let types = ["float", "vector2", "vector3"];
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    for t in types {
        let name = format!("w_{t}");
        nodes.push(node(node_tag, &name, t, &[(coord_input, coord_ty, Src::I("p")), ("jitter", "float", Src::I("jitter")), ("style", "integer", Src::I("style"))]));
        outs.push((name.clone(), t.to_string(), name));
        // Defaults: jitter 1, style 0 (Distance).
        let name = format!("d_{t}");
        nodes.push(node(node_tag, &name, t, &[(coord_input, coord_ty, Src::I("p"))]));
        outs.push((name.clone(), t.to_string(), name));
    }
    let k = compile(&graph_doc(&[("p", coord_ty), ("jitter", "float"), ("style", "integer")], &nodes, &outs));
    let mut rng = Rng::new(0x3017 + dim as u64);
    let n = 2048;
    let mut rows = Vec::new();
    let mut cases = Vec::new();
    for i in 0..n {
        let p: Vec<f32> = (0..dim).map(|_| coord(&mut rng)).collect();
        // jitter: 0 (regular grid), 1, random in [0, 1.2]; style: Distance / Solid.
        let jitter = match i % 4 {
            0 => 0.0,
            1 => 1.0,
            _ => rng.range(0.0, 1.2),
        };
        let style = (i / 4) % 2;
        rows.push(input_row(&k, &[("p", p.clone()), ("jitter", vec![jitter]), ("style", vec![style as f32])]));
        cases.push((p, jitter, style));
    }
    let got = run_rows(&k, &rows, None);
    let mut solid_checked = 0;
    for (i, (p, jitter, style)) in cases.iter().enumerate() {
        let ctx = || format!("p = {p:?}, jitter {jitter}, style {style}");
        for (ti, t) in types.iter().enumerate() {
            let ch = ti + 1;
            let (want, gap) = if dim == 2 { r::worley_out([p[0], p[1]], *jitter, *style, ch) } else { r::worley_out([p[0], p[1], p[2]], *jitter, *style, ch) };
            let (dwant, _) = if dim == 2 { r::worley_out([p[0], p[1]], 1.0, 0, ch) } else { r::worley_out([p[0], p[1], p[2]], 1.0, 0, ch) };
            let v = out(&k, &got[i], &format!("w_{t}"));
            let d = out(&k, &got[i], &format!("d_{t}"));
            if i < 256 {
                check(&format!("{node_tag} {t} (defaults)"), i, d, &dwant, 1e-5, &ctx);
            }
            // Solid: which feature point is nearest decides the value; skip exact-tie points
            // (squared distances within 1e-5), where rounding may pick the other one.
            if i < 256 && (*style == 0 || gap > 1e-5) {
                check(&format!("{node_tag} {t}"), i, v, &want, 1e-5, &ctx);
                if *style == 1 {
                    solid_checked += 1;
                }
            }
            // Ranges.
            if *style == 0 {
                assert!(v.iter().all(|x| *x >= 0.0), "{node_tag} {t}: negative distance {v:?} ({})", ctx());
                assert!(v.windows(2).all(|w| w[0] <= w[1]), "{node_tag} {t}: distances not sorted {v:?} ({})", ctx());
                if *jitter <= 1.0 {
                    let own = (dim as f32).sqrt();
                    assert!(v[0] <= own + 1e-6, "{node_tag} {t}: F1 {} > √{dim} ({})", v[0], ctx());
                }
            } else {
                assert!(v.iter().all(|x| (0.0..=1.0).contains(x)), "{node_tag} {t} Solid: {v:?} outside [0, 1] ({})", ctx());
            }
            assert!(d.iter().all(|x| *x >= 0.0) && d.windows(2).all(|w| w[0] <= w[1]) && d[0] <= (dim as f32).sqrt() + 1e-6, "{node_tag} {t} (defaults): {d:?} at {p:?}");
        }
        // With jitter 0 the feature points are the cell centres.
        if *jitter == 0.0 && *style == 0 {
            let centre: f32 = p.iter().map(|x| (x - x.floor() - 0.5).powi(2)).sum::<f32>().sqrt();
            let v = out(&k, &got[i], "w_float")[0];
            assert!((v - centre).abs() <= 1e-5, "{node_tag} jitter 0: F1 {v}, distance to the cell centre {centre} ({})", ctx());
        }
    }
    assert!(solid_checked > 300, "too few Solid points checked: {solid_checked}");
}

#[test]
fn worleynoise2d_all_variants() {
    worley_test(2);
}

#[test]
fn worleynoise3d_all_variants() {
    worley_test(3);
}

