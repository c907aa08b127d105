// surface.wgsl: ND_surface (a surface shader is its BSDF seen through `opacity`: response
// scaled by it, throughput 1 − opacity + opacity·T, as MaterialX's `color *= opacity` and
// `transparency = mix(1, T, opacity)`; emission is not part of uplift's kernels) and
// ND_surfacematerial (the front surface shader) and ND_surface_unlit (no reflection; its
// transparency mix(1, transmission·transmission_color, opacity) is the throughput, as MaterialX's
// GLSL). Surface shaders and materials are `BSDF` values.

// ND_surface
fn mx_surface(cl: mx_closure, bsdf: BSDF, edf: EDF, opacity: f32, thin_walled: bool) -> BSDF {
    let o = clamp(opacity, 0.0, 1.0);
    return BSDF(bsdf.response * o, vec3<f32>(1.0 - o) + o * bsdf.throughput, mx_lobe_combine(cl, bsdf.lobe, o, mx_bsdf_empty().lobe, 0.0));
}

// ND_surfacematerial
fn mx_surfacematerial(surfaceshader: BSDF, backsurfaceshader: BSDF, displacementshader: mx_displacementshader) -> BSDF {
    return surfaceshader;
}

// ND_surface_unlit (declared in stdlib; a surface shader, so it lives with the closures).
fn mx_surface_unlit(cl: mx_closure, emission: f32, emission_color: vec3<f32>, transmission: f32, transmission_color: vec3<f32>, opacity: f32) -> BSDF {
    let o = clamp(opacity, 0.0, 1.0);
    let t = max(transmission, 0.0) * max(transmission_color, vec3<f32>(0.0));
    return BSDF(vec3<f32>(0.0), mix(vec3<f32>(1.0), t, o), mx_bsdf_empty().lobe);
}
