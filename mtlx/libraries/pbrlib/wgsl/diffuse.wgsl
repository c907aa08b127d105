// diffuse.wgsl: ND_oren_nayar_diffuse_bsdf (MaterialX's qualitative Oren–Nayar; roughness 0 is
// Lambert), ND_burley_diffuse_bsdf, ND_subsurface_bsdf and ND_translucent_bsdf. All opaque
// (throughput 0, as MaterialX sets it), cosine sampled, albedo from the project's tables.
// `energy_compensation` (EON) is not implemented yet: the uncompensated lobe is evaluated.

fn mx_oren_nayar_factor(v: vec3<f32>, l: vec3<f32>, sigma: f32) -> f32 {
    let mv = clamp(v.z, 1.0e-8, 1.0);
    let s = dot(l, v) - l.z * mv;
    let stinv = select(0.0, s / max(max(l.z, mv), 1.0e-8), s > 0.0);
    let s2 = sigma * sigma;
    let a = 1.0 - 0.5 * (s2 / (s2 + 0.33));
    let b = 0.45 * s2 / (s2 + 0.09);
    return a + b * stinv;
}

fn mx_burley_factor(v: vec3<f32>, l: vec3<f32>, r: f32) -> f32 {
    let h = mx_half_vector(v, l);
    let ldoth = dot(l, h);
    let f90 = 0.5 + 2.0 * r * ldoth * ldoth;
    let ml = 1.0 - clamp(l.z, 0.0, 1.0);
    let mv = 1.0 - clamp(v.z, 0.0, 1.0);
    let ml2 = ml * ml;
    let mv2 = mv * mv;
    return (1.0 + (f90 - 1.0) * ml2 * ml2 * ml) * (1.0 + (f90 - 1.0) * mv2 * mv2 * mv);
}

// The contexts of an opaque diffuse lobe: `kind` 0 Oren–Nayar, 1 Burley, 2 Lambert.
fn mx_diffuse_lobe(cl: mx_closure, weight: f32, color: vec3<f32>, roughness: f32, normal: vec3<f32>, kind: i32) -> BSDF {
    let w = mx_lobe_weight(weight);
    let opaque = vec3<f32>(0.0);
    let frame = mx_frame_new(normal, vec3<f32>(0.0), cl.wv);
    let v = mx_to_local(frame, cl.wv);
    let c = max(color, vec3<f32>(0.0));
    let r = max(roughness, 0.0);
    if (cl.context == MX_CONTEXT_EVAL || cl.context == MX_CONTEXT_PDF) {
        let l = mx_to_local(frame, cl.wl);
        var shape: f32 = 1.0;
        if (kind == 1) {
            shape = mx_burley_factor(v, l, r);
        } else if (kind == 0) {
            shape = mx_oren_nayar_factor(v, l, r);
        }
        let f = select(shape * l.z * MX_INV_PI, 0.0, l.z <= 0.0);
        let response = (w * f) * c;
        if (cl.context == MX_CONTEXT_EVAL) {
            return BSDF(response, opaque, mx_bsdf_empty().lobe);
        }
        return mx_lobe_with_pdf(response, opaque, mx_luminance_rgb(w * c * mx_diffuse_albedo(v.z, r, kind)), mx_pdf_cosine(l));
    }
    let albedo = w * c * mx_diffuse_albedo(v.z, r, kind);
    if (cl.context == MX_CONTEXT_ALBEDO) {
        return BSDF(albedo, opaque, mx_bsdf_empty().lobe);
    }
    return mx_lobe_sampled(cl, opaque, mx_to_world(frame, mx_sample_cosine(cl.u.xy)), mx_luminance_rgb(albedo));
}

// `kind` 0 Oren–Nayar, 1 Burley, 2 Lambert (albedo 1).
fn mx_diffuse_albedo(mu: f32, r: f32, kind: i32) -> f32 {
    if (kind == 2) {
        return 1.0;
    }
    if (kind == 1) {
        return mx_albedo_burley(mu, r);
    }
    return mx_albedo_oren_nayar(mu, r);
}

// ND_oren_nayar_diffuse_bsdf
fn mx_oren_nayar_diffuse_bsdf(cl: mx_closure, weight: f32, color: vec3<f32>, roughness: f32, normal: vec3<f32>, energy_compensation: bool) -> BSDF {
    return mx_diffuse_lobe(cl, weight, color, roughness, normal, 0);
}

// ND_burley_diffuse_bsdf
fn mx_burley_diffuse_bsdf(cl: mx_closure, weight: f32, color: vec3<f32>, roughness: f32, normal: vec3<f32>) -> BSDF {
    return mx_diffuse_lobe(cl, weight, color, roughness, normal, 1);
}

// ND_subsurface_bsdf. MaterialX's GLSL approximates subsurface transport from the screen-space
// curvature |∇N|/|∇P| (mx_subsurface_scattering_approx): the diffusion profile integrated over
// the curved neighbourhood. A BSDF kernel sees one point and no screen, so it evaluates the
// flat-surface limit (curvature → 0), where the integrated profile is Lambert's cosine:
// f·cos = weight·color·μl/π. `radius` and `anisotropy` only shape the curved case.
fn mx_subsurface_bsdf(cl: mx_closure, weight: f32, color: vec3<f32>, radius: vec3<f32>, anisotropy: f32, normal: vec3<f32>) -> BSDF {
    return mx_diffuse_lobe(cl, weight, color, 0.0, normal, 2);
}

// ND_translucent_bsdf: pure diffuse transmission. It scatters into the lower hemisphere only,
// so in uplift's reflection contexts it contributes no response, no albedo and is never
// sampled; its throughput is 0, as MaterialX's GLSL sets it in every context.
fn mx_translucent_bsdf(cl: mx_closure, weight: f32, color: vec3<f32>, normal: vec3<f32>) -> BSDF {
    return BSDF(vec3<f32>(0.0), vec3<f32>(0.0), mx_bsdf_empty().lobe);
}
