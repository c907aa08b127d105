// surface.wgsl: the surface-shader nodes. ND_surface: a surface shader is its BSDF seen through
// `opacity` — response scaled by it, throughput 1 − opacity + opacity·T, as MaterialX's
// `color *= opacity` and `transparency = mix(1, T, opacity)` — and its EDF's radiance scaled by
// the opacity too (the PBR spec's L_o = O·[L_e + ∫ f L_i cos]). ND_surfacematerial (the front
// surface shader), ND_surface_unlit (no scattering; emission·emission_color·opacity emitted; its
// transparency mix(1, transmission·transmission_color, opacity) is the throughput, as MaterialX's
// GLSL), ND_mix_surfaceshader (both parts mixed), ND_dot_surfaceshader (pass-through),
// ND_displacement_float/vector3 (a displacement shader's offset; unused by material kernels).

// ND_surface (`thin_walled` only matters to transmission, which reflection kernels do not see)
fn mx_surface(cl: mx_closure, bsdf: BSDF, edf: EDF, opacity: f32, thin_walled: bool) -> mx_surfaceshader {
    let o = clamp(opacity, 0.0, 1.0);
    let b = BSDF(bsdf.response * o, vec3<f32>(1.0 - o) + o * bsdf.throughput, mx_lobe_combine(cl, bsdf.lobe, o, mx_bsdf_empty().lobe, 0.0));
    return mx_surfaceshader(b, o * edf.radiance);
}

// ND_surfacematerial
fn mx_surfacematerial(surfaceshader: mx_surfaceshader, backsurfaceshader: mx_surfaceshader, displacementshader: mx_displacementshader) -> mx_surfaceshader {
    return surfaceshader;
}

// ND_surface_unlit (declared in stdlib; a surface shader, so it lives with the closures).
fn mx_surface_unlit(cl: mx_closure, emission: f32, emission_color: vec3<f32>, transmission: f32, transmission_color: vec3<f32>, opacity: f32) -> mx_surfaceshader {
    let o = clamp(opacity, 0.0, 1.0);
    let t = max(transmission, 0.0) * max(transmission_color, vec3<f32>(0.0));
    return mx_surfaceshader(BSDF(vec3<f32>(0.0), mix(vec3<f32>(1.0), t, o), mx_bsdf_empty().lobe), emission * emission_color * o);
}

// ND_mix_surfaceshader (MaterialX's GLSL mixes colour and transparency: here the BSDFs, as
// ND_mix_bsdf, and the emission)
fn mx_mix_surfaceshader(cl: mx_closure, fg: mx_surfaceshader, bg: mx_surfaceshader, mix_: f32) -> mx_surfaceshader {
    return mx_surfaceshader(mx_mix_bsdf(cl, fg.bsdf, bg.bsdf, mix_), mix(bg.emission, fg.emission, mx_mix_amount(mix_)));
}

// ND_dot_surfaceshader
fn mx_dot_surfaceshader(in: mx_surfaceshader) -> mx_surfaceshader {
    return in;
}

// ND_displacement_float: the displacement shader's offset in (dPdu, dPdv, N) space, here along
// the normal. Material kernels do not move geometry: `surfacematerial` carries it unused.
fn mx_displacement_float(displacement: f32, scale: f32) -> mx_displacementshader {
    return mx_displacementshader(vec3<f32>(0.0, 0.0, displacement * scale));
}

// ND_displacement_vector3: a vector displacement in (dPdu, dPdv, N) space.
fn mx_displacement_vector3(displacement: vec3<f32>, scale: f32) -> mx_displacementshader {
    return mx_displacementshader(displacement * scale);
}
