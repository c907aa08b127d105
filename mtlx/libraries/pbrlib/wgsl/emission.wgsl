// emission.wgsl: the EDF nodes (ND_uniform_edf, ND_conical_edf, ND_generalized_schlick_edf) and
// the EDF operators (ND_mix_edf, ND_add_edf, ND_multiply_edfC/F). An `EDF` value is the radiance
// emitted towards the viewer, cl.wv (MaterialX PBR spec, "EDF Nodes"): the constructors that
// depend on the direction take the closure context. A surface shader carries it as its
// `emission` (surface.wgsl), which closure kernels of surfaceshader and material outputs write
// as `emission_r/g/b` in every context (docs/conformance.md, "Emission").
// ND_measured_edf (an IES profile file) has no implementation: documented in docs/conformance.md.

// ND_uniform_edf: L_e(ωo) = c.
fn mx_uniform_edf(color: vec3<f32>) -> EDF {
    return EDF(color);
}

// The EDFs' normal: the input normal (zero: the local frame's +z) turned to face the viewer,
// as MaterialX's mx_forward_facing_normal.
fn mx_edf_normal(normal: vec3<f32>, wv: vec3<f32>) -> vec3<f32> {
    let n = mx_normalize_or(normal, vec3<f32>(0.0, 0.0, 1.0));
    return select(n, -n, dot(n, wv) < 0.0);
}

// ND_conical_edf: full cone angles in degrees; a hard cut at the inner cone when
// outer_angle <= inner_angle, else smoothstep(cos outer/2, cos inner/2, cos θo).
fn mx_conical_edf(cl: mx_closure, color: vec3<f32>, normal: vec3<f32>, inner_angle: f32, outer_angle: f32) -> EDF {
    let c = max(dot(mx_edf_normal(normal, cl.wv), cl.wv), 0.0);
    let c_in = cos(inner_angle * (MX_PI / 360.0));
    let c_out = cos(outer_angle * (MX_PI / 360.0));
    let t = clamp((c - c_out) / (c_in - c_out), 0.0, 1.0);
    let falloff = select(select(0.0, 1.0, c >= c_in), t * t * (3.0 - 2.0 * t), outer_angle > inner_angle);
    return EDF(color * falloff);
}

// ND_generalized_schlick_edf: the base EDF scaled by r0 + (r90 − r0)(1 − cos θo)^q at the
// shading normal (Nworld; MaterialX's GLSL clamps cos θo to [ε, 1]).
fn mx_generalized_schlick_edf(geom: mx_geometry, cl: mx_closure, color0: vec3<f32>, color90: vec3<f32>, exponent: f32, base: EDF) -> EDF {
    let c = clamp(dot(mx_edf_normal(geom.normal_world, cl.wv), cl.wv), 1.0e-6, 1.0);
    let f = color0 + (color90 - color0) * mx_pow(1.0 - c, exponent);
    return EDF(base.radiance * f);
}

// ND_mix_edf
fn mx_mix_edf(fg: EDF, bg: EDF, mix_: f32) -> EDF {
    return EDF(mix(bg.radiance, fg.radiance, mx_mix_amount(mix_)));
}

// ND_add_edf
fn mx_add_edf(in1: EDF, in2: EDF) -> EDF {
    return EDF(in1.radiance + in2.radiance);
}

// ND_multiply_edfC (MaterialX scales an EDF by its weight unclamped)
fn mx_multiply_edfC(in1: EDF, in2: vec3<f32>) -> EDF {
    return EDF(in1.radiance * in2);
}

// ND_multiply_edfF
fn mx_multiply_edfF(in1: EDF, in2: f32) -> EDF {
    return EDF(in1.radiance * in2);
}

// ND_light: a light shader's radiance, the EDF's scaled by intensity·2^exposure (lights belong
// to the renderer; the value exists so that documents with lights compile).
fn mx_light(edf: EDF, intensity: f32, exposure: f32) -> mx_lightshader {
    return mx_lightshader(edf.radiance * intensity * exp2(exposure));
}
