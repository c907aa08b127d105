// thin_film.wgsl: the Airy reflectance of a thin dielectric film over a substrate (Belcour &
// Barla 2017, as MaterialX's mx_fresnel_airy): the microfacet nodes replace their Fresnel curve
// by it when `thinfilm_thickness` > 0 (nm). Two polarisations, the m = 0 term and two pairs of
// spectral Diracs (MaterialX's hwAiryFresnelIterations = 2), integrated against Gaussian fits of
// the CIE XYZ sensitivities, converted to RGB and clamped to [0, 1]. Substrates: a dielectric
// or conductor of complex IOR (η₃, κ₃), or a generalized Schlick curve (R₂₃ = F_schlick(cos θt)
// split evenly over the polarisations, phase π where η₃ = ior(r₀) < η₂, as MaterialX does).

// Fresnel reflectances of one polarisation pair: `p` parallel, `s` perpendicular, per channel.
struct mx_polarized {
    p: vec3<f32>,
    s: vec3<f32>,
}

// atan2 without library calls: an odd degree-15 polynomial for atan on [0, 1] (absolute error
// 4e-8) with the octant folded back; atan2(0, 0) = 0.
fn mx_fast_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let hi = max(ax, ay);
    let t = select(min(ax, ay) / hi, 0.0, hi <= 0.0);
    let t2 = t * t;
    var r = t * (0.999999336 + t2 * (-0.333298611 + t2 * (0.19946569 + t2 * (-0.139086473 + t2 * (0.0964224522 + t2 * (-0.0559130131 + t2 * (0.0218634546 + t2 * -0.00405471004)))))));
    r = select(r, 0.5 * MX_PI - r, ay > ax);
    r = select(r, MX_PI - r, x < 0.0);
    return select(r, -r, y < 0.0);
}

fn mx_fast_atan2_vec3(y: vec3<f32>, x: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(mx_fast_atan2(y.x, x.x), mx_fast_atan2(y.y, x.y), mx_fast_atan2(y.z, x.z));
}

fn mx_fast_cos_vec3(x: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(mx_fast_cos_sin(x.x).x, mx_fast_cos_sin(x.y).x, mx_fast_cos_sin(x.z).x);
}

// (p, s) reflectances of a dielectric interface of relative IOR `eta` ≥ 1.
fn mx_fresnel_dielectric_polarized(cos_theta: f32, eta: f32) -> vec2<f32> {
    let c = clamp(cos_theta, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = max(eta * eta - s2, 0.0);
    let t1 = t0 + c2;
    let t2 = 2.0 * sqrt(t0) * c;
    let rs = (t1 - t2) / max(t1 + t2, 1.0e-30);
    let t3 = c2 * t0 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / max(t3 + t4, 1.0e-30);
    return vec2<f32>(rp, rs);
}

// (p, s) reflectances of a conductor of complex relative IOR n + ik (mx_fresnel_conductor's
// two terms).
fn mx_fresnel_conductor_polarized(cos_theta: f32, n: vec3<f32>, k: vec3<f32>) -> mx_polarized {
    let c = clamp(cos_theta, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let n2 = n * n;
    let k2 = k * k;
    let t0 = n2 - k2 - vec3<f32>(s2);
    let a2b2 = sqrt(t0 * t0 + 4.0 * n2 * k2);
    let t1 = a2b2 + vec3<f32>(c2);
    let a = sqrt(max(0.5 * (a2b2 + t0), vec3<f32>(0.0)));
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / max(t1 + t2, vec3<f32>(1.0e-30));
    let t3 = c2 * a2b2 + vec3<f32>(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / max(t3 + t4, vec3<f32>(1.0e-30));
    return mx_polarized(rp, rs);
}

// (p, s) phase shifts on reflection at a conductor (η₂ + iκ₂) seen from a medium of IOR η₁.
fn mx_fresnel_conductor_phase_polarized(cos_theta: f32, eta1: f32, eta2: vec3<f32>, kappa2: vec3<f32>) -> mx_polarized {
    let e2 = max(eta2, vec3<f32>(1.0e-6));
    let k = kappa2 / e2;
    let s2 = 1.0 - cos_theta * cos_theta;
    let a = e2 * e2 * (vec3<f32>(1.0) - k * k) - vec3<f32>(eta1 * eta1 * s2);
    let b = sqrt(a * a + (2.0 * e2 * e2 * k) * (2.0 * e2 * e2 * k));
    let u = sqrt(max(0.5 * (a + b), vec3<f32>(0.0)));
    let v = sqrt(max(0.5 * (b - a), vec3<f32>(0.0)));
    let ec = eta1 * cos_theta;
    let phi_s = mx_fast_atan2_vec3(2.0 * eta1 * v * cos_theta, u * u + v * v - vec3<f32>(ec * ec));
    let q = e2 * e2 * (vec3<f32>(1.0) + k * k) * cos_theta;
    let phi_p = mx_fast_atan2_vec3(2.0 * eta1 * e2 * e2 * cos_theta * (2.0 * k * u - (vec3<f32>(1.0) - k * k) * v), q * q - eta1 * eta1 * (u * u + v * v));
    return mx_polarized(phi_p, phi_s);
}

// The CIE XYZ sensitivities' Fourier transform at optical path difference `opd` (m) with a
// phase `shift` per channel (Gaussian fits of Belcour & Barla).
fn mx_eval_sensitivity(opd: f32, shift: vec3<f32>) -> vec3<f32> {
    let phase = 2.0 * MX_PI * opd;
    let val = vec3<f32>(5.4856e-13, 4.4201e-13, 5.2481e-13);
    let pos = vec3<f32>(1.6810e+06, 1.7953e+06, 2.2084e+06);
    let var_ = vec3<f32>(4.3278e+09, 9.3046e+09, 6.6121e+09);
    let g = -phase * phase;
    var xyz = val * sqrt(2.0 * MX_PI * var_) * mx_fast_cos_vec3(pos * phase + shift) * vec3<f32>(mx_fast_exp(var_.x * g), mx_fast_exp(var_.y * g), mx_fast_exp(var_.z * g));
    xyz.x += 9.7470e-14 * sqrt(2.0 * MX_PI * 4.5282e+09) * mx_fast_cos_sin(2.2399e+06 * phase + shift.x).x * mx_fast_exp(4.5282e+09 * g);
    return xyz / 1.0685e-7;
}

// One polarisation's iridescent reflectance (XYZ): interface 1–2 reflectance `r12`, substrate
// reflectance `r23` and phase `phi23`, film phase `phi21`, optical path difference `opd`.
fn mx_airy_polarization(r12: f32, r23: vec3<f32>, phi: vec3<f32>, opd: f32) -> vec3<f32> {
    let t121 = 1.0 - r12;
    let rs = t121 * t121 * r23 / max(vec3<f32>(1.0) - r12 * r23, vec3<f32>(1.0e-30));
    let r123 = sqrt(max(r12 * r23, vec3<f32>(0.0)));
    let c1 = (rs - vec3<f32>(t121)) * r123;
    let c2 = c1 * r123;
    return vec3<f32>(r12) + rs + c1 * 2.0 * mx_eval_sensitivity(opd, phi) + c2 * 2.0 * mx_eval_sensitivity(2.0 * opd, 2.0 * phi);
}

// The Airy reflectance (RGB) at incidence `cos_theta` of a film of IOR `eta2` ≥ 1 and
// `thickness` nm, given the substrate's polarised reflectance and phase at the film's internal
// angle `cos_t`.
fn mx_airy_reflectance(cos_theta: f32, cos_t: f32, eta2: f32, thickness: f32, r23: mx_polarized, phi23: mx_polarized) -> vec3<f32> {
    let r12 = mx_fresnel_dielectric_polarized(cos_theta, eta2);
    // Brewster's angle: cos(atan(η₂)) = 1/√(1 + η₂²).
    let cos_b = 1.0 / sqrt(1.0 + eta2 * eta2);
    let phi21p = select(MX_PI, 0.0, cos_theta < cos_b);
    let opd = 2.0 * eta2 * cos_t * max(thickness, 0.0) * 1.0e-9;
    let xyz = 0.5 * (mx_airy_polarization(r12.x, r23.p, phi23.p + vec3<f32>(phi21p), opd) + mx_airy_polarization(r12.y, r23.s, phi23.s + vec3<f32>(MX_PI), opd));
    // CIE XYZ to RGB (neutral E illuminant), MaterialX's XYZ_TO_RGB.
    let rgb = xyz.x * vec3<f32>(2.3706743, -0.5138850, 0.0052982) + xyz.y * vec3<f32>(-0.9000405, 1.4253036, -0.0146949) + xyz.z * vec3<f32>(-0.4706338, 0.0885814, 1.0093968);
    return clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0));
}

// The film's internal cosine (η₁ = 1 outside, η₂ ≥ 1: never total internal reflection).
fn mx_thin_film_cos(cos_theta: f32, eta2: f32) -> f32 {
    let c = clamp(cos_theta, 0.0, 1.0);
    return sqrt(max(1.0 - (1.0 - c * c) / (eta2 * eta2), 0.0));
}

// Airy reflectance over a dielectric or conductor substrate of complex IOR n + ik (κ = 0 for
// a dielectric).
fn mx_fresnel_airy_conductor(cos_theta: f32, n: vec3<f32>, k: vec3<f32>, thickness: f32, film_ior: f32) -> vec3<f32> {
    let eta2 = max(film_ior, 1.0);
    let cos_t = mx_thin_film_cos(cos_theta, eta2);
    let r23 = mx_fresnel_conductor_polarized(cos_t, n / eta2, k / eta2);
    let phi23 = mx_fresnel_conductor_phase_polarized(cos_t, eta2, n, k);
    return mx_airy_reflectance(cos_theta, cos_t, eta2, thickness, r23, phi23);
}

// Airy reflectance over a generalized Schlick substrate.
fn mx_fresnel_airy_schlick(cos_theta: f32, r0: vec3<f32>, r82: vec3<f32>, r90: vec3<f32>, exponent: f32, thickness: f32, film_ior: f32) -> vec3<f32> {
    let eta2 = max(film_ior, 1.0);
    let cos_t = mx_thin_film_cos(cos_theta, eta2);
    let f = mx_fresnel_schlick_f82(cos_t, r0, r82, r90, exponent);
    let sq = sqrt(clamp(r0, vec3<f32>(0.01), vec3<f32>(0.99)));
    let eta3 = (vec3<f32>(1.0) + sq) / (vec3<f32>(1.0) - sq);
    let phi = select(vec3<f32>(0.0), vec3<f32>(MX_PI), eta3 < vec3<f32>(eta2));
    return mx_airy_reflectance(cos_theta, cos_t, eta2, thickness, mx_polarized(0.5 * f, 0.5 * f), mx_polarized(phi, phi));
}

// GGX albedo of the Airy reflectance over a conductor or dielectric substrate: Σ_m W_m F(c_m)
// over the thin-film moments (32 nodes uniform in v·h: the Airy curve oscillates with angle,
// which the 16 standard nodes resolve badly).
fn mx_albedo_ggx_airy_conductor(mu: f32, abar: f32, n: vec3<f32>, k: vec3<f32>, thickness: f32, film_ior: f32) -> vec3<f32> {
    let p = mx_ggx_moments_position(mu, abar, MX_TABLE_FILM_FRESNEL_NODES);
    var e = vec3<f32>(0.0);
    for (var m = 0; m < MX_TABLE_FILM_FRESNEL_NODES; m++) {
        e += mx_ggx_moment(MX_TABLE_GGX_FILM_MOMENTS, MX_TABLE_FILM_FRESNEL_NODES, p, m) * mx_fresnel_airy_conductor(mx_film_fresnel_node(m), n, k, thickness, film_ior);
    }
    return e;
}

// GGX albedo of the Airy reflectance over a generalized Schlick substrate.
fn mx_albedo_ggx_airy_schlick(mu: f32, abar: f32, r0: vec3<f32>, r82: vec3<f32>, r90: vec3<f32>, exponent: f32, thickness: f32, film_ior: f32) -> vec3<f32> {
    let p = mx_ggx_moments_position(mu, abar, MX_TABLE_FILM_FRESNEL_NODES);
    var e = vec3<f32>(0.0);
    for (var m = 0; m < MX_TABLE_FILM_FRESNEL_NODES; m++) {
        e += mx_ggx_moment(MX_TABLE_GGX_FILM_MOMENTS, MX_TABLE_FILM_FRESNEL_NODES, p, m) * mx_fresnel_airy_schlick(mx_film_fresnel_node(m), r0, r82, r90, exponent, thickness, film_ior);
    }
    return e;
}
