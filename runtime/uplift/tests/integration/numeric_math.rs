//! Every nodedef of the stdlib `math` node group, every type variant: compiled from a generated
//! nodegraph, run on wgpu for 256 random rows, compared with a closed form written here from
//! the MaterialX spec (MaterialX.StandardNodes.md) and MaterialX's GLSL semantics (where they
//! differ, the GLSL wins, as the library README says; each such place is commented).
//!
//! Matrices are MaterialX row-major value lists (row by row); the kernel's WGSL matrix has the
//! MaterialX rows as columns, as GLSL's `mat3(...)` does with the same list. So GLSL's
//! `mat * v` is the row vector `v · A`, and GLSL's `in1 * in2` is `A2 · A1`.
//!
//! Tolerances: arithmetic 1e-5 absolute; transcendental functions 1e-4 absolute. Where outputs
//! can be large (products of matrices, `power`, `exp`, `safepower`, `determinant`, ...) the
//! tolerance is relative, err ≤ tol · max(1, |want|), with the same tol (Tol::Rel).

use crate::common;
use crate::nodedef_harness;

use common::Rng;
use mtlx::schema::{NodeDef, PortDef};
use mtlx::DataType;
use nodedef_harness::*;

/// OSL's `safe_pow` (the library's definition of `power` on the whole line, math.wgsl), in f64:
/// x^0 = 1; 0^y = 0; a negative base to a whole power keeps the power's parity in its sign, to
/// any other power gives 0.
fn osl_pow(a: f32, b: f32) -> f32 {
    let (a, b) = (a as f64, b as f64);
    if b == 0.0 {
        1.0
    } else if a == 0.0 {
        0.0
    } else if a > 0.0 {
        a.powf(b) as f32
    } else if b.trunc() != b {
        0.0
    } else {
        let m = (-a).powf(b);
        (if (b as i64) % 2 != 0 { -m } else { m }) as f32
    }
}

/// Input domains: keep functions in their domains and away from ill-conditioned points.
fn gen(nd: &NodeDef, p: &PortDef, rng: &mut Rng) -> Option<Vec<f32>> {
    let n = p.ty.components()?;
    let is_matrix = matches!(p.ty, DataType::Matrix33 | DataType::Matrix44);
    Some(match (nd.node.as_str(), p.name.as_str()) {
        // Divisors away from zero; componentwise matrix division too (see `divide`).
        ("divide", "in2") | ("modulo", "in2") => away_from_zero(rng, n, 0.5, 2.0),
        ("modulo", "in1") | ("floor", _) | ("ceil", _) | ("round", _) | ("trianglewave", _) | ("fract", _) => {
            uniform(rng, n, -5.0, 5.0)
        }
        ("place2d", "operationorder") => vec![int_in(rng, 0, 1)],
        // Integers are whole numbers (passed as f32); keep sums small.
        (_, _) if p.ty == DataType::Integer => vec![int_in(rng, -100, 100)],
        // The whole line, zero included: the library defines pow everywhere (OSL's safe_pow).
        ("power", "in1") => (0..n).map(|_| if rng.next_u64() % 8 == 0 { 0.0 } else { rng.range(-3.0, 3.0) }).collect(),
        // Whole exponents (odd and even, signs of negative bases) half of the time.
        ("power", "in2") => (0..n).map(|_| if rng.next_u64() & 1 == 0 { int_in(rng, -3, 3) } else { rng.range(-2.0, 2.0) }).collect(),
        ("safepower", "in1") => away_from_zero(rng, n, 0.1, 3.0),
        ("sin", _) | ("cos", _) => uniform(rng, n, -6.0, 6.0),
        ("tan", _) => uniform(rng, n, -1.2, 1.2),
        ("asin", _) | ("acos", _) => uniform(rng, n, -0.99, 0.99),
        ("sqrt", _) => uniform(rng, n, 0.01, 4.0),
        ("ln", _) => uniform(rng, n, 0.05, 5.0),
        ("exp", _) => uniform(rng, n, -3.0, 3.0),
        ("clamp", "in") => uniform(rng, n, -3.0, 3.0),
        ("clamp", "low") => uniform(rng, n, -2.0, 0.0),
        ("clamp", "high") => uniform(rng, n, 0.0, 2.0),
        ("normalize", _) => away_from_zero(rng, n, 0.2, 2.0),
        ("rotate3d", "axis") => away_from_zero(rng, n, 0.2, 2.0),
        ("rotate2d", "amount") | ("rotate3d", "amount") => uniform(rng, n, -360.0, 360.0),
        ("place2d", "scale") => away_from_zero(rng, n, 0.5, 2.0),
        ("place2d", "rotate") => uniform(rng, n, -180.0, 180.0),
        // Unit vectors for reflect/refract (as a renderer passes them).
        ("reflect", _) | ("refract", "in") | ("refract", "normal") => normalize(&away_from_zero(rng, 3, 0.1, 1.0)),
        ("refract", "ior") => uniform(rng, 1, 0.5, 2.0),
        // An encoded normal map value (z > 0) and a perturbed orthonormal-ish frame.
        ("normalmap", "in") => vec![rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.6, 1.0)],
        ("normalmap", "scale") => uniform(rng, n, 0.5, 2.0),
        ("normalmap", "normal") => vec![rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), rng.range(0.7, 1.3)],
        ("normalmap", "tangent") => vec![rng.range(0.7, 1.3), rng.range(-0.3, 0.3), rng.range(-0.3, 0.3)],
        ("normalmap", "bitangent") => vec![rng.range(-0.3, 0.3), rng.range(0.7, 1.3), rng.range(-0.3, 0.3)],
        // Well-conditioned matrices: 2·I plus a small perturbation.
        ("determinant", _) | ("invertmatrix", _) => {
            let d = if n == 9 { 3 } else { 4 };
            (0..n).map(|k| if k % (d + 1) == 0 { 2.0 } else { 0.0 } + rng.range(-0.5, 0.5)).collect()
        }
        _ if is_matrix => uniform(rng, n, -2.0, 2.0),
        _ => return None,
    })
}

fn rotate2(v: &[f32], degrees: f32) -> Vec<f32> {
    // MaterialX GLSL mx_rotate_vector2: (c·x + s·y, -s·x + c·y); that turns clockwise for
    // positive angles although the spec says counter-clockwise. The GLSL wins (README).
    let (s, c) = (degrees as f64).to_radians().sin_cos();
    let (x, y) = (v[0] as f64, v[1] as f64);
    vec![(c * x + s * y) as f32, (-s * x + c * y) as f32]
}

fn matrix_dim(t: &DataType) -> usize {
    match t {
        DataType::Matrix33 => 3,
        DataType::Matrix44 => 4,
        _ => 0,
    }
}

/// Row vector `v · A` (GLSL `mat * v`), A row-major d×d.
fn row_times(v: &[f32], a: &[f32], d: usize) -> Vec<f32> {
    (0..d).map(|j| (0..d).map(|i| v[i] as f64 * a[i * d + j] as f64).sum::<f64>() as f32).collect()
}

fn reference(nd: &NodeDef, x: &Inputs) -> Vec<f32> {
    let out_ty = &nd.outputs[0].ty;
    let md = matrix_dim(out_ty);
    match nd.node.as_str() {
        "add" if *out_ty == DataType::Integer => vec![(x.i("in1") + x.i("in2")) as f32],
        "subtract" if *out_ty == DataType::Integer => vec![(x.i("in1") - x.i("in2")) as f32],
        "add" => map2(nd, x, "in1", "in2", |a, b| a + b),
        "subtract" => map2(nd, x, "in1", "in2", |a, b| a - b),
        // GLSL `in1 * in2` on matrices whose columns are the MaterialX rows: A2 · A1.
        "multiply" if md > 0 => matmul(&x.v("in2"), &x.v("in1"), md),
        "multiply" => map2(nd, x, "in1", "in2", |a, b| a * b),
        // MaterialX GLSL writes `in1 / in2`, componentwise for GLSL matrices (the spec says
        // in1 · inverse(in2)); the GLSL wins, so the reference is componentwise for every type.
        "divide" => map2(nd, x, "in1", "in2", |a, b| a / b),
        // GLSL mod: x - y·floor(x/y).
        "modulo" => map2(nd, x, "in1", "in2", |a, b| (a as f64 - b as f64 * (a as f64 / b as f64).floor()) as f32),
        "fract" => map1(nd, x, "in", |a| a - a.floor()),
        "invert" => map2(nd, x, "amount", "in", |amount, v| amount - v),
        "absval" => map1(nd, x, "in", f32::abs),
        "sign" => map1(nd, x, "in", |a| if a > 0.0 { 1.0 } else if a < 0.0 { -1.0 } else { 0.0 }),
        "floor" => x.n("in", out_n(nd)).iter().map(|a| a.floor()).collect(),
        "ceil" => x.n("in", out_n(nd)).iter().map(|a| a.ceil()).collect(),
        // Ties (x.5) have probability zero here, so GLSL's round and WGSL's round agree.
        "round" => x.n("in", out_n(nd)).iter().map(|a| a.round()).collect(),
        "power" => map2(nd, x, "in1", "in2", osl_pow),
        "safepower" => map2(nd, x, "in1", "in2", |a, b| (a.signum() as f64 * (a.abs() as f64).powf(b as f64)) as f32),
        "sin" => map1(nd, x, "in", f32::sin),
        "cos" => map1(nd, x, "in", f32::cos),
        "tan" => map1(nd, x, "in", f32::tan),
        "asin" => map1(nd, x, "in", f32::asin),
        "acos" => map1(nd, x, "in", f32::acos),
        "atan2" => map2(nd, x, "iny", "inx", f32::atan2),
        "sqrt" => map1(nd, x, "in", f32::sqrt),
        "ln" => map1(nd, x, "in", f32::ln),
        "exp" => map1(nd, x, "in", |a| (a as f64).exp() as f32),
        "clamp" => map3(nd, x, "in", "low", "high", |v, lo, hi| v.max(lo).min(hi)),
        "min" => map2(nd, x, "in1", "in2", f32::min),
        "max" => map2(nd, x, "in1", "in2", f32::max),
        "mincomponent" => vec![x.v("in").into_iter().fold(f32::INFINITY, f32::min)],
        "maxcomponent" => vec![x.v("in").into_iter().fold(f32::NEG_INFINITY, f32::max)],
        "normalize" => normalize(&x.v("in")),
        "magnitude" => vec![length(&x.v("in"))],
        "distance" => {
            let d: Vec<f32> = x.v("in1").iter().zip(x.v("in2")).map(|(a, b)| a - b).collect();
            vec![length(&d)]
        }
        "dotproduct" => vec![dot(&x.v("in1"), &x.v("in2"))],
        "crossproduct" => cross(&x.v("in1"), &x.v("in2")),
        // From "world" to "world" (see the harness): the identity in any renderer.
        "transformpoint" | "transformvector" | "transformnormal" => x.v("in"),
        "transformmatrix" => {
            let (v, m) = (x.v("in"), x.v("mat"));
            let d = matrix_dim(&nd.input("mat").unwrap().ty);
            // vector2 with a matrix33 and vector3 with a matrix44 are homogeneous points (w = 1).
            let mut h = v.clone();
            h.resize(d, 1.0);
            let r = row_times(&h, &m, d);
            r[..v.len()].to_vec()
        }
        "normalmap" => {
            let v: Vec<f32> = x.v("in").iter().map(|c| c * 2.0 - 1.0).collect();
            let s = x.n("scale", 2);
            let (n, t, b) = (x.v("normal"), x.v("tangent"), x.v("bitangent"));
            let w: Vec<f32> = (0..3).map(|k| t[k] * v[0] * s[0] + b[k] * v[1] * s[1] + n[k] * v[2]).collect();
            normalize(&w)
        }
        "transpose" => transpose(&x.v("in"), md),
        "determinant" => {
            let a: Vec<f64> = x.v("in").iter().map(|&v| v as f64).collect();
            let d = matrix_dim(&nd.input("in").unwrap().ty);
            vec![det(&a, d) as f32]
        }
        "invertmatrix" => inverse(&x.v("in"), md),
        "rotate2d" => rotate2(&x.v("in"), x.f("amount")),
        "rotate3d" => {
            // MaterialX GLSL mx_rotationMatrix lists the Rodrigues matrix row by row into a
            // column-major mat4, i.e. its transpose: a rotation by -amount about the
            // normalized axis (same handedness as rotate2d). The GLSL wins.
            let k: Vec<f64> = normalize(&x.v("axis")).iter().map(|&c| c as f64).collect();
            let v: Vec<f64> = x.v("in").iter().map(|&c| c as f64).collect();
            let th = -(x.f("amount") as f64).to_radians();
            let (s, c) = th.sin_cos();
            let kxv = [k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]];
            let kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
            (0..3).map(|i| (v[i] * c + kxv[i] * s + k[i] * kv * (1.0 - c)) as f32).collect()
        }
        "place2d" => {
            // Texture placement moves coordinates inversely: the scale divides and the offset
            // subtracts. SRT (0): -pivot, scale, rotate, translate, +pivot; TRS (1): -pivot,
            // translate, rotate, scale, +pivot.
            let (t, p, s, o) = (x.v("texcoord"), x.v("pivot"), x.v("scale"), x.v("offset"));
            let r = x.f("rotate");
            let c: Vec<f32> = (0..2).map(|k| t[k] - p[k]).collect();
            if x.i("operationorder") == 0 {
                let scaled: Vec<f32> = (0..2).map(|k| c[k] / s[k]).collect();
                let rot = rotate2(&scaled, r);
                (0..2).map(|k| rot[k] - o[k] + p[k]).collect()
            } else {
                let moved: Vec<f32> = (0..2).map(|k| c[k] - o[k]).collect();
                let rot = rotate2(&moved, r);
                (0..2).map(|k| rot[k] / s[k] + p[k]).collect()
            }
        }
        "trianglewave" => {
            let a = x.f("in").abs();
            let m = a - a.floor();
            vec![0.5 - (m - 0.5).abs()]
        }
        "reflect" => {
            let (i, n) = (x.v("in"), x.v("normal"));
            let d = dot(&n, &i);
            (0..3).map(|k| i[k] - 2.0 * d * n[k]).collect()
        }
        "refract" => {
            // GLSL refract(I, N, eta) with eta = ior: zero on total internal reflection.
            let (i, n, eta) = (x.v("in"), x.v("normal"), x.f("ior") as f64);
            let d = dot(&n, &i) as f64;
            let k = 1.0 - eta * eta * (1.0 - d * d);
            if k < 0.0 {
                vec![0.0; 3]
            } else {
                (0..3).map(|c| (eta * i[c] as f64 - (eta * d + k.sqrt()) * n[c] as f64) as f32).collect()
            }
        }
        "creatematrix" => {
            let rows: Vec<Vec<f32>> = nd.inputs.iter().map(|p| x.v(&p.name)).collect();
            if md == 4 && rows[0].len() == 3 {
                // vector3 rows: appended with 0, the fourth with 1.
                rows.iter().enumerate().flat_map(|(r, v)| [v.clone(), vec![if r == 3 { 1.0 } else { 0.0 }]].concat()).collect()
            } else {
                rows.concat()
            }
        }
        c => panic!("no reference for {c}"),
    }
}

const ABS: Tol = Tol::Abs(1e-5);
const ABS_T: Tol = Tol::Abs(1e-4);
const REL: Tol = Tol::Rel(1e-5);
const REL_T: Tol = Tol::Rel(1e-4);

macro_rules! specs {
    ($($cat:literal => $tol:expr),* $(,)?) => {
        &[$(Spec { category: $cat, tol: $tol, gen, reference }),*]
    };
}

const SPECS: &[Spec] = specs![
    "add" => ABS, "subtract" => ABS,
    // Products of matrices and of [-2, 2] values reach 16: relative.
    "multiply" => REL, "divide" => REL, "modulo" => ABS, "fract" => ABS, "invert" => ABS,
    "absval" => ABS, "sign" => ABS, "floor" => ABS, "ceil" => ABS, "round" => ABS,
    "power" => REL_T, "safepower" => REL_T,
    "sin" => ABS_T, "cos" => ABS_T, "tan" => ABS_T, "asin" => ABS_T, "acos" => ABS_T, "atan2" => ABS_T,
    "sqrt" => ABS_T, "ln" => ABS_T, "exp" => REL_T,
    "clamp" => ABS, "min" => ABS, "max" => ABS, "mincomponent" => ABS, "maxcomponent" => ABS,
    "normalize" => ABS_T, "magnitude" => ABS_T, "distance" => ABS_T,
    "dotproduct" => REL, "crossproduct" => REL,
    "transformpoint" => ABS, "transformvector" => ABS, "transformnormal" => ABS,
    "transformmatrix" => REL, "normalmap" => ABS_T,
    "transpose" => ABS, "determinant" => REL, "invertmatrix" => ABS,
    "rotate2d" => ABS_T, "rotate3d" => ABS_T, "place2d" => REL_T, "trianglewave" => ABS,
    "reflect" => REL, "refract" => ABS_T, "creatematrix" => ABS,
];

/// Not tested, with the reason.
const SKIP: &[(&str, &str)] = &[
    // Samples a texture file with hex-tiling randomization: needs an image, not a closed form.
    ("ND_hextilednormalmap_vector3", "filename input (texture sampling)"),
    // bxdf/usd_preview_surface.mtlx's texture-coordinate transform: a nodegraph of place2d and
    // the math nodes above, run by the Examples materials test (materials.rs).
    ("ND_UsdTransform2d", "a nodegraph of tested nodes (UsdPreviewSurface's helper)"),
];

/// Left out because of a known compiler problem (reported; see the test's report).
const KNOWN_FAILURES: &[(&str, &str)] = &[];

#[test]
fn every_math_nodedef_matches_its_closed_form() {
    run_plan(&Plan { groups: &["math"], filter: all, specs: SPECS, skip: SKIP, known_failures: KNOWN_FAILURES, seed: 11 });
}
