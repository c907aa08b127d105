// hair.wgsl: ND_chiang_hair_bsdf (Chiang, Bitterli, Tappan & Burley 2016, as MaterialX's GLSL
// mx_chiang_hair_bsdf): R, TT, TRT and TRRT+ lobes, each a longitudinal term M_p (d'Eon's
// Bessel form; its log form below variance 0.1) times an azimuthal trimmed logistic N_p times
// the attenuation A_p (dielectric Fresnel, absorption along the refracted path), rotated by the
// cuticle tilt, tinted per lobe. The hair runs along `curve_direction` (made orthogonal to the
// forward-facing normal). MaterialX reports the response F/π (no cosine) and throughput 0.
// Differences, both for well-defined energy: TRRT+'s azimuthal term is 1/(2π) (MaterialX's
// `1.0 / 2.0 * M_PI` evaluates to π/2), and like every uplift lobe the hair reflects into the
// upper hemisphere only (response 0 for wl below the shading normal). Inputs are kept in their
// domain: ior ≥ 1, absorption ≥ 0, cuticle_angle in [0, 1], roughness in [0.001, 1] (MaterialX
// clamps roughness too).
// The albedo context integrates the eval over 256 Fibonacci directions of the hemisphere (the
// BCSDF has no table); sampling is cosine-weighted. Transcendentals are the library's call-free
// ones (closure.wgsl), so both engines evaluate the same polynomials.

fn mx_hair_i0(x: f32) -> f32 {
    let x2 = x * x;
    var v = 1.0;
    var n = 1.0;
    var d = 1.0;
    var f = 1.0;
    for (var i = 0; i < 9; i++) {
        d *= 4.0 * f * f;
        n *= x2;
        v += n / d;
        f += 1.0;
    }
    return v;
}

fn mx_hair_log_i0(x: f32) -> f32 {
    let big = x + 0.5 * (-mx_fast_ln(2.0 * MX_PI) + mx_fast_ln(1.0 / max(x, 1.0e-30)) + 1.0 / (8.0 * max(x, 1.0e-30)));
    return select(mx_fast_ln(mx_hair_i0(x)), big, x > 12.0);
}

// M_p: the longitudinal scattering of variance v.
fn mx_hair_longitudinal(sin_i: f32, cos_i: f32, sin_o: f32, cos_o: f32, v: f32) -> f32 {
    let inv_v = 1.0 / v;
    let a = cos_o * cos_i * inv_v;
    let b = sin_o * sin_i * inv_v;
    let narrow = mx_fast_exp(mx_hair_log_i0(a) - b - inv_v + 0.6931 + mx_fast_ln(0.5 * inv_v));
    let sinh_inv_v = 0.5 * (mx_fast_exp(inv_v) - mx_fast_exp(-inv_v));
    let wide = mx_fast_exp(-b) * mx_hair_i0(a) / (2.0 * v * sinh_inv_v);
    return select(wide, narrow, v < 0.1);
}

fn mx_hair_logistic(x: f32, s: f32) -> f32 {
    let f = mx_fast_exp(-abs(x) / s);
    return f / (s * (1.0 + f) * (1.0 + f));
}

fn mx_hair_logistic_cdf(x: f32, s: f32) -> f32 {
    return 1.0 / (1.0 + mx_fast_exp(-x / s));
}

// N_p for p = 0, 1, 2: a logistic of scale s (× √(π/8)) trimmed to [−π, π] around the
// deflection angle 2pγt − 2γo + pπ.
fn mx_hair_azimuthal(phi: f32, p: f32, s: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    var d = phi - (2.0 * p * gamma_t - 2.0 * gamma_o + p * MX_PI);
    d = d - 2.0 * MX_PI * round(d / (2.0 * MX_PI));
    let ss = s * 0.626657;
    return mx_hair_logistic(d, ss) / (mx_hair_logistic_cdf(MX_PI, ss) - mx_hair_logistic_cdf(-MX_PI, ss));
}

// The rotated (sin θi, cos θi) of lobe p for the cuticle tilt α (rotation by (2 − 3p)·α).
fn mx_hair_tilt(sin_i: f32, cos_i: f32, alpha: f32, p: f32) -> vec2<f32> {
    let m = (2.0 - 3.0 * p) * alpha;
    let cs = mx_fast_cos_sin(m);
    let sa = cs.y;
    let ca = cs.x;
    return vec2<f32>(sin_i * ca + cos_i * sa, cos_i * ca - sin_i * sa);
}

// F/π for local directions v, l (x along the hair, z the normal).
fn mx_hair_response(v: vec3<f32>, l: vec3<f32>, tint_r: vec3<f32>, tint_tt: vec3<f32>, tint_trt: vec3<f32>, ior: f32, rough_r: vec2<f32>, rough_tt: vec2<f32>, rough_trt: vec2<f32>, cuticle_angle: f32, absorption: vec3<f32>) -> vec3<f32> {
    let eta = max(ior, 1.0);
    let sin_o = clamp(v.x, -1.0, 1.0);
    let sin_i = clamp(l.x, -1.0, 1.0);
    let cos_o = sqrt(max(1.0 - sin_o * sin_o, 0.0));
    let cos_i = sqrt(max(1.0 - sin_i * sin_i, 0.0));
    let phi = mx_fast_atan2(l.z * v.y - v.z * l.y, l.y * v.y + l.z * v.z);
    let k1 = mx_normalize_or(vec3<f32>(0.0, v.y, v.z), vec3<f32>(0.0, 0.0, 1.0));
    let cos_go = k1.z;
    let sin_go = select(1.0, -1.0, k1.y > 0.0) * sqrt(max(1.0 - cos_go * cos_go, 0.0));
    let gamma_o = mx_fast_asin(sin_go);
    let sin_t = sin_o / eta;
    let cos_t = sqrt(max(1.0 - sin_t * sin_t, 0.0));
    let eta_p = sqrt(max(eta * eta - sin_o * sin_o, 0.0)) / max(cos_o, 1.0e-8);
    let sin_gt = clamp(sin_go / eta_p, -1.0, 1.0);
    let cos_gt = sqrt(1.0 - sin_gt * sin_gt);
    let gamma_t = mx_fast_asin(sin_gt);
    // Attenuations A_p.
    let f = mx_fresnel_dielectric(cos_o * cos_go, eta);
    let x = -max(absorption, vec3<f32>(0.0)) * (2.0 * cos_gt / max(cos_t, 1.0e-8));
    let t = vec3<f32>(mx_fast_exp(x.x), mx_fast_exp(x.y), mx_fast_exp(x.z));
    let a0 = vec3<f32>(f);
    let a1 = (1.0 - f) * (1.0 - f) * t;
    let a2 = a1 * t * f;
    let a3 = a2 * t * f / max(vec3<f32>(1.0) - t * f, vec3<f32>(1.0e-8));
    let alpha = clamp(cuticle_angle, 0.0, 1.0) * MX_PI - 0.5 * MX_PI;
    let vr = clamp(rough_r, vec2<f32>(0.001), vec2<f32>(1.0));
    let vtt = clamp(rough_tt, vec2<f32>(0.001), vec2<f32>(1.0));
    let vtrt = clamp(rough_trt, vec2<f32>(0.001), vec2<f32>(1.0));
    let r0 = mx_hair_tilt(sin_i, cos_i, alpha, 0.0);
    let r1 = mx_hair_tilt(sin_i, cos_i, alpha, 1.0);
    let r2 = mx_hair_tilt(sin_i, cos_i, alpha, 2.0);
    var sum = mx_hair_longitudinal(r0.x, r0.y, sin_o, cos_o, vr.x) * mx_hair_azimuthal(phi, 0.0, vr.y, gamma_o, gamma_t) * max(tint_r, vec3<f32>(0.0)) * a0;
    sum += mx_hair_longitudinal(r1.x, r1.y, sin_o, cos_o, vtt.x) * mx_hair_azimuthal(phi, 1.0, vtt.y, gamma_o, gamma_t) * max(tint_tt, vec3<f32>(0.0)) * a1;
    sum += mx_hair_longitudinal(r2.x, r2.y, sin_o, cos_o, vtrt.x) * mx_hair_azimuthal(phi, 2.0, vtrt.y, gamma_o, gamma_t) * max(tint_trt, vec3<f32>(0.0)) * a2;
    sum += mx_hair_longitudinal(sin_i, cos_i, sin_o, cos_o, vtrt.x) * (0.5 / MX_PI) * max(tint_trt, vec3<f32>(0.0)) * a3;
    return select(sum * MX_INV_PI, vec3<f32>(0.0), l.z <= 0.0);
}

// ND_chiang_hair_bsdf
fn mx_chiang_hair_bsdf(cl: mx_closure, tint_R: vec3<f32>, tint_TT: vec3<f32>, tint_TRT: vec3<f32>, ior: f32, roughness_R: vec2<f32>, roughness_TT: vec2<f32>, roughness_TRT: vec2<f32>, cuticle_angle: f32, absorption_coefficient: vec3<f32>, normal: vec3<f32>, curve_direction: vec3<f32>) -> BSDF {
    let opaque = vec3<f32>(0.0);
    let frame = mx_frame_new(normal, curve_direction, cl.wv);
    let v = mx_to_local(frame, cl.wv);
    if (cl.context == MX_CONTEXT_EVAL) {
        let r = mx_hair_response(v, mx_to_local(frame, cl.wl), tint_R, tint_TT, tint_TRT, ior, roughness_R, roughness_TT, roughness_TRT, cuticle_angle, absorption_coefficient);
        return BSDF(r, opaque, mx_bsdf_empty().lobe);
    }
    // Albedo: 256 directions uniform in z over the hemisphere, golden-angle azimuths.
    var albedo = vec3<f32>(0.0);
    for (var i = 0; i < 256; i++) {
        let z = (f32(i) + 0.5) * (1.0 / 256.0);
        let cs = mx_fast_cos_sin(2.39996323 * f32(i));
        let r = sqrt(max(1.0 - z * z, 0.0));
        albedo += mx_hair_response(v, vec3<f32>(r * cs.x, r * cs.y, z), tint_R, tint_TT, tint_TRT, ior, roughness_R, roughness_TT, roughness_TRT, cuticle_angle, absorption_coefficient);
    }
    albedo *= 2.0 * MX_PI / 256.0;
    if (cl.context == MX_CONTEXT_ALBEDO) {
        return BSDF(albedo, opaque, mx_bsdf_empty().lobe);
    }
    if (cl.context == MX_CONTEXT_SAMPLE) {
        return mx_lobe_sampled(cl, opaque, mx_to_world(frame, mx_sample_cosine(cl.u.xy)), mx_luminance_rgb(albedo));
    }
    let l = mx_to_local(frame, cl.wl);
    let r = mx_hair_response(v, l, tint_R, tint_TT, tint_TRT, ior, roughness_R, roughness_TT, roughness_TRT, cuticle_angle, absorption_coefficient);
    return mx_lobe_with_pdf(r, opaque, mx_luminance_rgb(albedo), mx_pdf_cosine(l));
}

// ND_deon_hair_absorption_from_melanin (d'Eon et al. 2011): σ_a from the melanin concentration
// and redness, the two pigments' colours being exp(−σ) of their absorption.
fn mx_deon_hair_absorption_from_melanin(melanin_concentration: f32, melanin_redness: f32, eumelanin_color: vec3<f32>, pheomelanin_color: vec3<f32>) -> vec3<f32> {
    let melanin = -log(max(1.0 - melanin_concentration, 0.0001));
    let eu = melanin * (1.0 - melanin_redness);
    let pheo = melanin * melanin_redness;
    let sigma_eu = -log(max(eumelanin_color, vec3<f32>(1.0e-30)));
    let sigma_pheo = -log(max(pheomelanin_color, vec3<f32>(1.0e-30)));
    return max(eu * sigma_eu + pheo * sigma_pheo, vec3<f32>(0.0));
}

// ND_chiang_hair_absorption_from_color (Chiang et al. 2016, eq. 9): the absorption that gives
// `color` after multiple scattering at azimuthal roughness βn.
fn mx_chiang_hair_absorption_from_color(color: vec3<f32>, azimuthal_roughness: f32) -> vec3<f32> {
    let b = azimuthal_roughness;
    let b2 = b * b;
    let b4 = b2 * b2;
    let d = 5.969 - 0.215 * b + 2.532 * b2 - 10.73 * b2 * b + 5.574 * b4 + 0.245 * b4 * b;
    let s = log(clamp(color, vec3<f32>(0.001), vec3<f32>(1.0))) / d;
    return s * s;
}

struct mx_chiang_hair_roughness_outputs {
    roughness_R: vec2<f32>,
    roughness_TT: vec2<f32>,
    roughness_TRT: vec2<f32>,
}

// ND_chiang_hair_roughness (Chiang et al. 2016, eqs. 7–8): longitudinal variance v and
// azimuthal logistic scale s per lobe, TT and TRT's v scaled by scale² (Marschner et al. 2003).
fn mx_chiang_hair_roughness(longitudinal: f32, azimuthal: f32, scale_TT: f32, scale_TRT: f32) -> mx_chiang_hair_roughness_outputs {
    let lr = clamp(longitudinal, 0.001, 1.0);
    let ar = clamp(azimuthal, 0.001, 1.0);
    let v0 = 0.726 * lr + 0.812 * lr * lr + 3.7 * pow(lr, 20.0);
    let v = v0 * v0;
    let s = 0.265 * ar + 1.194 * ar * ar + 5.372 * pow(ar, 22.0);
    return mx_chiang_hair_roughness_outputs(vec2<f32>(v, s), vec2<f32>(v * scale_TT * scale_TT, s), vec2<f32>(v * scale_TRT * scale_TRT, s));
}
