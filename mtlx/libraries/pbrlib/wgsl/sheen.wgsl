// sheen.wgsl: ND_sheen_bsdf in both MaterialX modes. `conty_kulla` (0): Imageworks' sheen NDF
// with the smooth "Neubelt–Pettineo" denominator 1/(4(μl + μv − μlμv)), albedo from the
// project's table, cosine sampling. `zeltner` (1): the LTC sheen of Zeltner, Burley & Chiang
// 2022 with MaterialX's fits; the LTC is normalised over the hemisphere, so the albedo is the
// fitted E exactly, and it is sampled exactly. Throughput 1 − w·E (colour excluded).

fn mx_sheen_conty_kulla_d(cos_h: f32, r: f32) -> f32 {
    let inv_r = 1.0 / max(r, 0.005);
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + inv_r) * mx_fast_pow(sin2, 0.5 * inv_r) / (2.0 * MX_PI);
}

// Zeltner's LTC coefficients (1/a, b of the inverse transform) and albedo fit, x = μv, y = r.
fn mx_sheen_zeltner_ltc(x: f32, y: f32) -> vec2<f32> {
    let a_inv = (2.58126 * x + 0.813703 * y) * y / (1.0 + 0.310327 * x * x + 2.60994 * x * y);
    let b_inv = sqrt(max(1.0 - x, 0.0)) * (y - 1.0) * y * y * y / (2.54053e-5 + 1.71228 * x - 1.71506 * x * y + 1.34174 * y * y);
    return vec2<f32>(a_inv, b_inv);
}

fn mx_sheen_zeltner_albedo(x: f32, y: f32) -> f32 {
    let s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y));
    let m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y);
    let o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y));
    let q = (x - m) / s;
    return mx_fast_exp(-0.5 * q * q) / (s * sqrt(2.0 * MX_PI)) + o;
}

// The LTC density of local direction l (already "f·cos" per unit albedo).
fn mx_sheen_zeltner_density(l_ltc: vec3<f32>, ltc: vec2<f32>) -> f32 {
    let wo = vec3<f32>(ltc.x * l_ltc.x + ltc.y * l_ltc.z, ltc.x * l_ltc.y, l_ltc.z);
    let len2 = max(dot(wo, wo), 1.0e-30);
    let j = ltc.x / len2;
    return max(wo.z, 0.0) * MX_INV_PI * j * j;
}

// ND_sheen_bsdf
fn mx_sheen_bsdf(cl: mx_closure, weight: f32, color: vec3<f32>, roughness: f32, normal: vec3<f32>, mode: i32) -> BSDF {
    let w = mx_lobe_weight(weight);
    let frame = mx_frame_new(normal, vec3<f32>(0.0), cl.wv);
    let v = mx_to_local(frame, cl.wv);
    let mu = clamp(v.z, 1.0e-8, 1.0);
    let c = max(color, vec3<f32>(0.0));
    // Zeltner's frame: x in the plane of v and the normal.
    let xv = mx_normalize_or(vec3<f32>(v.x, v.y, 0.0), vec3<f32>(1.0, 0.0, 0.0));
    let y = clamp(roughness, 0.01, 1.0);
    let ltc = mx_sheen_zeltner_ltc(mu, y);
    var e: f32;
    // conty_kulla reflects more than it receives at grazing views for low roughness (its
    // smooth denominator is not a shadowing term): its response is normalised there so that
    // its albedo never exceeds 1 (MaterialX clamps only the albedo it uses for throughput).
    var norm = 1.0;
    if (mode == 1) {
        e = clamp(mx_sheen_zeltner_albedo(mu, y), 0.0, 1.0);
    } else {
        let e_ck = max(mx_albedo_sheen_conty_kulla(mu, roughness), 0.0);
        norm = 1.0 / max(e_ck, 1.0);
        e = e_ck * norm;
    }
    let throughput = vec3<f32>(1.0 - w * e);
    let albedo = w * e * c;
    if (cl.context == MX_CONTEXT_ALBEDO) {
        return BSDF(albedo, throughput, mx_bsdf_empty().lobe);
    }
    if (cl.context == MX_CONTEXT_SAMPLE) {
        var l: vec3<f32>;
        if (mode == 1) {
            let o = mx_sample_cosine(cl.u.xy);
            let a = 1.0 / max(ltc.x, 1.0e-20);
            let m = mx_normalize_or(vec3<f32>((o.x - ltc.y * o.z) * a, o.y * a, o.z), vec3<f32>(0.0, 0.0, 1.0));
            l = m.x * xv + m.y * vec3<f32>(-xv.y, xv.x, 0.0) + vec3<f32>(0.0, 0.0, m.z);
        } else {
            l = mx_sample_cosine(cl.u.xy);
        }
        return mx_lobe_sampled(cl, throughput, mx_to_world(frame, l), mx_luminance_rgb(albedo));
    }
    let l = mx_to_local(frame, cl.wl);
    var f: f32 = 0.0;
    var pdf: f32;
    if (mode == 1) {
        let l_ltc = vec3<f32>(dot(l, xv), xv.x * l.y - xv.y * l.x, l.z);
        let density = mx_sheen_zeltner_density(l_ltc, ltc);
        f = e * density;
        pdf = density;
    } else {
        let h = mx_half_vector(v, l);
        let ml = max(l.z, 0.0);
        f = select(norm * mx_sheen_conty_kulla_d(h.z, roughness) * ml / (4.0 * (ml + mu - ml * mu)), 0.0, l.z <= 0.0);
        pdf = mx_pdf_cosine(l);
    }
    let response = (w * f) * c;
    if (cl.context == MX_CONTEXT_EVAL) {
        return BSDF(response, throughput, mx_bsdf_empty().lobe);
    }
    return mx_lobe_with_pdf(response, throughput, mx_luminance_rgb(albedo), pdf);
}
