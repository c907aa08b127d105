// microfacet_nodes.wgsl: the three GGX BSDF nodes — dielectric_bsdf (reflection; scatter_mode T
// contributes nothing to reflection, as MaterialX's REFLECTION context), conductor_bsdf
// (opaque: throughput 0, even at weight 0) and generalized_schlick_bsdf — in every closure
// context. Albedos come from the project's Monte Carlo tables (albedo_tables.wgsl), so
// albedo + throughput of a white lobe is exactly 1. A thin film (`thinfilm_thickness` > 0 nm)
// replaces the Fresnel curve by the Airy reflectance (thin_film.wgsl) everywhere it enters:
// the response at v·h, F(1) in the energy compensation (with F90 = 1, as MaterialX) and the
// albedo, Σ W_m F_airy(c_m) over the Fresnel moments (so throughputs stay consistent; MaterialX
// approximates this albedo). A film thickness that is a constant 0 folds away at compile time.

// A GGX lobe with its Fresnel curve evaluated at v·h, given everything the contexts share:
// `scale` (weight·tint·compensation, RGB), the throughput, and the albedo luminance `c`.
fn mx_ggx_lobe_sample(cl: mx_closure, s: mx_ggx_setup, throughput: vec3<f32>, c: f32) -> BSDF {
    let h = mx_ggx_sample_vndf(s.v, s.a, cl.u.xy);
    var l = mx_reflect_about(s.v, h);
    return mx_lobe_sampled(cl, throughput, mx_to_world(s.frame, l), c);
}

// The local light direction of the eval and pdf contexts (mirrored back for retroreflection,
// whose view direction was mirrored).
fn mx_ggx_light(cl: mx_closure, s: mx_ggx_setup) -> vec3<f32> {
    return mx_to_local(s.frame, cl.wl);
}

// ND_dielectric_bsdf
fn mx_dielectric_bsdf(cl: mx_closure, weight: f32, tint: vec3<f32>, ior: f32, roughness: vec2<f32>, retroreflective: bool, thinfilm_thickness: f32, thinfilm_ior: f32, normal: vec3<f32>, tangent: vec3<f32>, distribution: i32, scatter_mode: i32) -> BSDF {
    let w = mx_lobe_weight(weight);
    if (scatter_mode == 1) {
        return mx_bsdf_empty();
    }
    let s = mx_ggx_setup_new(cl, roughness, retroreflective, normal, tangent);
    let eta = max(ior, 0.0);
    let t = max(tint, vec3<f32>(0.0));
    let film = thinfilm_thickness > 0.0;
    let n3 = vec3<f32>(eta);
    let k3 = vec3<f32>(0.0);
    // Branches, not `select`s: the Airy terms cost far more than Fresnel's, and a film that is
    // an input (not a constant 0) is off for most points.
    var f1 = vec3<f32>(mx_fresnel_dielectric(1.0, eta));
    // Untinted albedo (tint stays out of the throughput, as in MaterialX).
    var e = vec3<f32>(0.0);
    if (film) {
        f1 = mx_fresnel_airy_conductor(1.0, n3, k3, thinfilm_thickness, thinfilm_ior);
        e = mx_albedo_ggx_airy_conductor(s.mu, s.abar, n3, k3, thinfilm_thickness, thinfilm_ior);
    } else {
        e = vec3<f32>(mx_albedo_ggx_dielectric(s.mu, s.abar, eta));
    }
    let comp = mx_ggx_energy_compensation(s.mu, s.abar, mx_fresnel_average(f1, vec3<f32>(1.0)));
    let albedo = comp * e;
    let throughput = vec3<f32>(1.0) - w * albedo;
    let tinted = w * t * albedo;
    if (cl.context == MX_CONTEXT_ALBEDO) {
        return BSDF(tinted, throughput, mx_bsdf_empty().lobe);
    }
    if (cl.context == MX_CONTEXT_SAMPLE) {
        return mx_ggx_lobe_sample(cl, s, throughput, mx_luminance_rgb(tinted));
    }
    let l = mx_ggx_light(cl, s);
    let h = mx_half_vector(s.v, l);
    let vh = dot(s.v, h);
    var f = vec3<f32>(0.0);
    if (film) {
        f = mx_fresnel_airy_conductor(vh, n3, k3, thinfilm_thickness, thinfilm_ior);
    } else {
        f = vec3<f32>(mx_fresnel_dielectric(vh, eta));
    }
    let response = (w * mx_ggx_reflection(s.v, l, h, s.a)) * f * comp * t;
    if (cl.context == MX_CONTEXT_EVAL) {
        return BSDF(response, throughput, mx_bsdf_empty().lobe);
    }
    return mx_lobe_with_pdf(response, throughput, mx_luminance_rgb(tinted), mx_ggx_pdf(s.v, h, s.a));
}

// The conductor's Fresnel curve at v·h, Airy over the conductor when a film is present.
fn mx_conductor_fresnel(vh: f32, n: vec3<f32>, k: vec3<f32>, thickness: f32, film_ior: f32) -> vec3<f32> {
    return select(mx_fresnel_conductor(vh, n, k), mx_fresnel_airy_conductor(vh, n, k, thickness, film_ior), thickness > 0.0);
}

// ND_conductor_bsdf
fn mx_conductor_bsdf(cl: mx_closure, weight: f32, ior: vec3<f32>, extinction: vec3<f32>, roughness: vec2<f32>, retroreflective: bool, thinfilm_thickness: f32, thinfilm_ior: f32, normal: vec3<f32>, tangent: vec3<f32>, distribution: i32) -> BSDF {
    let w = mx_lobe_weight(weight);
    let opaque = vec3<f32>(0.0);
    let s = mx_ggx_setup_new(cl, roughness, retroreflective, normal, tangent);
    // Beyond 10⁶ a conductor reflects 1 − 4·10⁻⁶ at normal incidence; the bound keeps the
    // Fresnel products inside f32.
    let n = clamp(ior, vec3<f32>(0.0), vec3<f32>(1.0e6));
    let k = clamp(extinction, vec3<f32>(0.0), vec3<f32>(1.0e6));
    let film = thinfilm_thickness > 0.0;
    let f1 = select(mx_fresnel_conductor_normal(n, k), mx_fresnel_airy_conductor(1.0, n, k, thinfilm_thickness, thinfilm_ior), film);
    let comp = mx_ggx_energy_compensation(s.mu, s.abar, mx_fresnel_average(f1, vec3<f32>(1.0)));
    if (cl.context == MX_CONTEXT_EVAL) {
        let l = mx_ggx_light(cl, s);
        let h = mx_half_vector(s.v, l);
        let f = mx_conductor_fresnel(dot(s.v, h), n, k, thinfilm_thickness, thinfilm_ior);
        return BSDF((w * mx_ggx_reflection(s.v, l, h, s.a)) * f * comp, opaque, mx_bsdf_empty().lobe);
    }
    let e = select(mx_albedo_ggx_conductor(s.mu, s.abar, n, k), mx_albedo_ggx_airy_conductor(s.mu, s.abar, n, k, thinfilm_thickness, thinfilm_ior), film);
    let albedo = w * comp * e;
    if (cl.context == MX_CONTEXT_ALBEDO) {
        return BSDF(albedo, opaque, mx_bsdf_empty().lobe);
    }
    if (cl.context == MX_CONTEXT_SAMPLE) {
        return mx_ggx_lobe_sample(cl, s, opaque, mx_luminance_rgb(albedo));
    }
    let l = mx_ggx_light(cl, s);
    let h = mx_half_vector(s.v, l);
    let f = mx_conductor_fresnel(dot(s.v, h), n, k, thinfilm_thickness, thinfilm_ior);
    let response = (w * mx_ggx_reflection(s.v, l, h, s.a)) * f * comp;
    return mx_lobe_with_pdf(response, opaque, mx_luminance_rgb(albedo), mx_ggx_pdf(s.v, h, s.a));
}

// ND_generalized_schlick_bsdf: throughput 1 − w·mean(albedo) (scalar, as MaterialX), with the
// albedo of the full curve (F82 and exponent included) so that white lobes conserve energy.
fn mx_generalized_schlick_bsdf(cl: mx_closure, weight: f32, color0: vec3<f32>, color82: vec3<f32>, color90: vec3<f32>, exponent: f32, roughness: vec2<f32>, retroreflective: bool, thinfilm_thickness: f32, thinfilm_ior: f32, normal: vec3<f32>, tangent: vec3<f32>, distribution: i32, scatter_mode: i32) -> BSDF {
    let w = mx_lobe_weight(weight);
    if (scatter_mode == 1) {
        return mx_bsdf_empty();
    }
    let s = mx_ggx_setup_new(cl, roughness, retroreflective, normal, tangent);
    let r0 = max(color0, vec3<f32>(0.0));
    let r82 = max(color82, vec3<f32>(0.0));
    let r90 = max(color90, vec3<f32>(0.0));
    let q = max(exponent, 0.0);
    let film = thinfilm_thickness > 0.0;
    let th = thinfilm_thickness;
    let favg = select(mx_fresnel_average(mx_fresnel_schlick_f82(1.0, r0, r82, r90, q), r90), mx_fresnel_average(mx_fresnel_airy_schlick(1.0, r0, r82, r90, q, th, thinfilm_ior), vec3<f32>(1.0)), film);
    let comp = mx_ggx_energy_compensation(s.mu, s.abar, favg);
    let e = select(mx_albedo_ggx_schlick(s.mu, s.abar, r0, r82, r90, q), mx_albedo_ggx_airy_schlick(s.mu, s.abar, r0, r82, r90, q, th, thinfilm_ior), film);
    let albedo = w * comp * e;
    let throughput = vec3<f32>(1.0 - (albedo.x + albedo.y + albedo.z) * (1.0 / 3.0));
    if (cl.context == MX_CONTEXT_ALBEDO) {
        return BSDF(albedo, throughput, mx_bsdf_empty().lobe);
    }
    if (cl.context == MX_CONTEXT_SAMPLE) {
        return mx_ggx_lobe_sample(cl, s, throughput, mx_luminance_rgb(albedo));
    }
    let l = mx_ggx_light(cl, s);
    let h = mx_half_vector(s.v, l);
    let vh = dot(s.v, h);
    let f = select(mx_fresnel_schlick_f82(vh, r0, r82, r90, q), mx_fresnel_airy_schlick(vh, r0, r82, r90, q, th, thinfilm_ior), film);
    let response = (w * mx_ggx_reflection(s.v, l, h, s.a)) * f * comp;
    if (cl.context == MX_CONTEXT_EVAL) {
        return BSDF(response, throughput, mx_bsdf_empty().lobe);
    }
    return mx_lobe_with_pdf(response, throughput, mx_luminance_rgb(albedo), mx_ggx_pdf(s.v, h, s.a));
}
