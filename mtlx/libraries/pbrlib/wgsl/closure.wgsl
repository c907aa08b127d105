// closure.wgsl: the closure value (`BSDF`), the closure context every BSDF node receives, the
// shading frame, and the bookkeeping the sampling contexts share.
//
// A BSDF value is `BSDF { response, throughput, lobe }` (ARCHITECTURE.md, "Closure semantics"):
// `response` and `throughput` are MaterialX's own two RGB vectors; `lobe` carries what the two
// sampling passes need and is ignored by the eval and albedo contexts.
//
// Contexts (README rule 4b: a function whose first parameter, after `geom`, is
// `cl: mx_closure` receives it; the compiler passes one per lobe call):
//   eval   (0) response = f(wv, wl)·cos θl, throughput = what passes to the layer below (a
//              function of wv only);
//   albedo (1) response = directional albedo ∫ f cos dωl, throughput as in eval;
//   sample (2) each lobe draws a candidate wl from its own distribution with cl.u.xy and
//              enters a race: lobe = (wl, key), key = Exp(1) / c with c the lobe's albedo
//              luminance scaled by everything above it (operators divide keys by their
//              weights, layers by the top's throughput); the smallest key wins, so lobe k is
//              chosen with probability c_k / Σ c (an exponential race, exact for any tree);
//   pdf    (3) response as in eval at cl.wl, and lobe = (Σ c_k·pdf_k(wl), Σ c_k, 0, 0): the
//              pdf of the sample context's choice is lobe.x / lobe.y.
// Directions: `wv` points to the viewer, `wl` to the light; both in the space of the BSDF's
// `normal` and `tangent` inputs. A zero normal means the local frame (normal +z, tangent +x),
// which is what a kernel evaluated without geometry gets.

struct BSDF {
    response: vec3<f32>,
    throughput: vec3<f32>,
    lobe: vec4<f32>,
}

// An EDF value: the radiance emitted towards cl.wv (emission.wgsl).
struct EDF {
    radiance: vec3<f32>,
}

// A surface shader (MaterialX `surfaceshader`, and `material`, whose value is its front surface
// shader): the BSDF it scatters with, opacity folded in (surface.wgsl), and the radiance it
// emits towards cl.wv. Closure kernels of such outputs write the BSDF's columns and `emission`.
struct mx_surfaceshader {
    bsdf: BSDF,
    emission: vec3<f32>,
}

// The empty surface shader (an unconnected surfaceshader input): no scattering, no emission.
fn mx_surfaceshader_empty() -> mx_surfaceshader {
    return mx_surfaceshader(mx_bsdf_empty(), vec3<f32>(0.0));
}

// Volume, displacement and light shaders: uplift's kernels evaluate surfaces; these types
// exist so that documents using them type-check.

struct VDF {
    absorption: vec3<f32>,
    scattering: vec3<f32>,
}

struct mx_volumeshader {
    vdf: VDF,
}

struct mx_displacementshader {
    offset: vec3<f32>,
}

struct mx_lightshader {
    radiance: vec3<f32>,
}

const MX_CONTEXT_EVAL: i32 = 0;
const MX_CONTEXT_ALBEDO: i32 = 1;
const MX_CONTEXT_SAMPLE: i32 = 2;
const MX_CONTEXT_PDF: i32 = 3;

// The race key of a lobe that can never be chosen.
const MX_LOBE_NEVER: f32 = 3.0e38;

struct mx_closure {
    context: i32,
    wv: vec3<f32>,
    wl: vec3<f32>,
    u: vec3<f32>,
    // Which lobe call this is (sample context: decorrelates the lobes' race variables).
    lobe_id: u32,
}

const MX_PI: f32 = 3.14159265358979;
const MX_INV_PI: f32 = 0.318309886183791;

// normalize() with a fallback for zero-length (or non-finite-length) vectors.
fn mx_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    let ok = (len2 > 1.0e-30) & (len2 < 1.0e30);
    return select(fallback, v * inverseSqrt(clamp(len2, 1.0e-30, 1.0e30)), ok);
}

// The context for one evaluation: directions normalized (a zero direction reads as the normal).
fn mx_closure_new(context: i32, wv: vec3<f32>, wl: vec3<f32>, u: vec3<f32>) -> mx_closure {
    let z = vec3<f32>(0.0, 0.0, 1.0);
    let uu = clamp(u, vec3<f32>(0.0), vec3<f32>(0.99999994));
    return mx_closure(context, mx_normalize_or(wv, z), mx_normalize_or(wl, z), uu, 0u);
}

// The context a lobe call receives: the kernel's context tagged with the call's id.
fn mx_closure_for_lobe(cl: mx_closure, id: u32) -> mx_closure {
    return mx_closure(cl.context, cl.wv, cl.wl, cl.u, id);
}

// The empty closure (MaterialX's default for an unconnected BSDF input): no response, fully
// transparent to layering, never sampled.
fn mx_bsdf_empty() -> BSDF {
    return BSDF(vec3<f32>(0.0), vec3<f32>(1.0), vec4<f32>(0.0, 0.0, 1.0, MX_LOBE_NEVER));
}

fn mx_luminance_rgb(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// A weight as the lobes use it: NaN and negative values read as 0.
fn mx_lobe_weight(w: f32) -> f32 {
    return max(w, 0.0);
}

// An orthonormal shading frame (x, y, n). `n` faces the viewer (MaterialX's forward-facing
// normal); `x` is the tangent made orthogonal to `n`, or any perpendicular when it is degenerate.
struct mx_frame {
    x: vec3<f32>,
    y: vec3<f32>,
    n: vec3<f32>,
}

fn mx_frame_new(normal: vec3<f32>, tangent: vec3<f32>, wv: vec3<f32>) -> mx_frame {
    let n0 = mx_normalize_or(normal, vec3<f32>(0.0, 0.0, 1.0));
    let n = select(n0, -n0, dot(n0, wv) < 0.0);
    // Duff et al. 2017 branchless basis as the fallback tangent.
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let any_x = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let x = mx_normalize_or(tangent - dot(tangent, n) * n, any_x);
    return mx_frame(x, cross(n, x), n);
}

fn mx_to_local(f: mx_frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.x), dot(v, f.y), dot(v, f.n));
}

fn mx_to_world(f: mx_frame, v: vec3<f32>) -> vec3<f32> {
    return v.x * f.x + v.y * f.y + v.z * f.n;
}

// A uniform number in (0, 1] for the race of lobe `id`, from cl.u.z (PCG hash).
fn mx_race_uniform(cl: mx_closure) -> f32 {
    var h = bitcast<u32>(cl.u.z) ^ (cl.lobe_id * 0x9E3779B9u);
    h = h * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = (h >> 22u) ^ h;
    return (f32(h >> 8u) + 1.0) * (1.0 / 16777216.0);
}

// A leaf's BSDF in the sample context: its candidate (world space) and its race key for
// albedo luminance `c`.
fn mx_lobe_sampled(cl: mx_closure, throughput: vec3<f32>, wl: vec3<f32>, c: f32) -> BSDF {
    let e = -0.693147181 * mx_fast_log2(mx_race_uniform(cl));
    let key = select(MX_LOBE_NEVER, e / c, c > 1.0e-30);
    return BSDF(vec3<f32>(0.0), throughput, vec4<f32>(wl, min(key, MX_LOBE_NEVER)));
}

// A leaf's BSDF in the pdf context: response at cl.wl and its weighted pdf.
fn mx_lobe_with_pdf(response: vec3<f32>, throughput: vec3<f32>, c: f32, pdf: f32) -> BSDF {
    let cc = max(c, 0.0);
    return BSDF(response, throughput, vec4<f32>(cc * max(pdf, 0.0), cc, 0.0, 0.0));
}

// Combines the `lobe` fields of two operands whose contributions are scaled by `wa` and `wb`:
// the race (sample context) or the weighted pdf sums (pdf context).
fn mx_lobe_combine(cl: mx_closure, a: vec4<f32>, wa: f32, b: vec4<f32>, wb: f32) -> vec4<f32> {
    if (cl.context == MX_CONTEXT_SAMPLE) {
        let ka = select(MX_LOBE_NEVER, a.w / wa, wa > 1.0e-30);
        let kb = select(MX_LOBE_NEVER, b.w / wb, wb > 1.0e-30);
        let pick_b = kb < ka;
        return vec4<f32>(select(a.xyz, b.xyz, pick_b), min(select(ka, kb, pick_b), MX_LOBE_NEVER));
    }
    return vec4<f32>(max(wa, 0.0) * a.xy + max(wb, 0.0) * b.xy, 0.0, 0.0);
}

// Cosine-weighted hemisphere sampling (local frame) and its pdf.
fn mx_sample_cosine(u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let cs = mx_fast_cos_sin(2.0 * MX_PI * u.y);
    return vec3<f32>(r * cs.x, r * cs.y, sqrt(max(1.0 - u.x, 0.0)));
}

fn mx_pdf_cosine(l: vec3<f32>) -> f32 {
    return max(l.z, 0.0) * MX_INV_PI;
}

// The pdf of the sample context's choice, from the pdf pass's root value (0 when nothing
// could be chosen).
fn mx_closure_pdf(b: BSDF) -> f32 {
    return select(0.0, b.lobe.x / b.lobe.y, b.lobe.y > 0.0);
}

// log2, exp2, pow, exp, acos and cos/sin without library calls, so that the CPU backend's batch
// loops vectorise (a call to the math library per lane keeps LLVM from vectorising the loop;
// see ARCHITECTURE.md, "CPU kernel shape"). Relative error below 2e-7 (log2 absolute 2e-7).
fn mx_fast_log2(x: f32) -> f32 {
    let bits = bitcast<u32>(max(x, 1.0e-37));
    var e = f32(i32((bits >> 23u) & 0xffu) - 127);
    var m = bitcast<f32>((bits & 0x007fffffu) | 0x3f800000u);
    let big = m > 1.41421356;
    m = select(m, 0.5 * m, big);
    e = select(e, e + 1.0, big);
    // ln(m) = 2·atanh(s), s = (m − 1)/(m + 1) in [−0.172, 0.172].
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let ln_m = 2.0 * s * (1.0 + s2 * (0.333333333 + s2 * (0.2 + s2 * (0.142857143 + s2 * 0.111111111))));
    return e + ln_m * 1.44269504;
}

fn mx_fast_exp2(x: f32) -> f32 {
    let y = clamp(x, -126.0, 127.0);
    let e = floor(y);
    let f = y - e;
    // 2^f on [0, 1): Taylor series of exp(f·ln 2) to degree 7 (error < 2e-7 relative).
    let t = f * 0.693147181;
    let p = 1.0 + t * (1.0 + t * (0.5 + t * (0.166666667 + t * (0.0416666667 + t * (0.00833333333 + t * (0.00138888889 + t * 0.000198412698))))));
    return bitcast<f32>(u32(i32(e) + 127) << 23u) * p;
}

// e^x (error < 3e-7 relative, as mx_fast_exp2).
fn mx_fast_exp(x: f32) -> f32 {
    return mx_fast_exp2(x * 1.44269504);
}

// Natural logarithm (absolute error 2e-7·ln 2).
fn mx_fast_ln(x: f32) -> f32 {
    return mx_fast_log2(x) * 0.693147181;
}

// asin on [−1, 1] (inputs clamped), from mx_fast_acos.
fn mx_fast_asin(x: f32) -> f32 {
    return 0.5 * MX_PI - mx_fast_acos(clamp(x, -1.0, 1.0));
}

// acos on [−1, 1] (inputs clamped): Abramowitz & Stegun 4.4.46, √(1 − |x|) times a degree-7
// polynomial (absolute error 2e-8, below 3e-7 in f32).
fn mx_fast_acos(x: f32) -> f32 {
    let a = min(abs(x), 1.0);
    let p = sqrt(1.0 - a) * (1.5707963050 + a * (-0.2145988016 + a * (0.0889789874 + a * (-0.0501743046 + a * (0.0308918810 + a * (-0.0170881256 + a * (0.0066700901 + a * -0.0012624911)))))));
    return select(p, MX_PI - p, x < 0.0);
}

// (cos φ, sin φ): φ reduced to r in [−π/4, π/4] around the nearest multiple q of π/2, Taylor
// series of degree 8 and 9 there (error below 3e-8 before rounding), rotated by q quarter
// turns. Exact to f32 rounding for |φ| up to a few hundred radians.
fn mx_fast_cos_sin(phi: f32) -> vec2<f32> {
    let q = round(phi * (2.0 / MX_PI));
    let r = (phi - q * 1.5703125) - q * 4.83826795e-4;
    let r2 = r * r;
    let s = r * (1.0 + r2 * (-0.166666667 + r2 * (0.00833333333 + r2 * (-0.000198412698 + r2 * 2.75573192e-6))));
    let c = 1.0 + r2 * (-0.5 + r2 * (0.0416666667 + r2 * (-0.00138888889 + r2 * 2.48015873e-5)));
    let k = i32(q) & 3;
    let cs = select(vec2<f32>(c, s), vec2<f32>(-s, c), k == 1);
    return select(cs, select(vec2<f32>(-c, -s), vec2<f32>(s, -c), k == 3), k >= 2);
}

// x^q for x > 0 (0 for x ≤ 0 and q > 0, 1 for q = 0).
fn mx_fast_pow(x: f32, q: f32) -> f32 {
    let r = mx_fast_exp2(q * mx_fast_log2(x));
    return select(select(0.0, 1.0, q <= 0.0), r, x > 0.0);
}
