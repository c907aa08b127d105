// volume.wgsl: the VDF nodes (ND_absorption_vdf, ND_anisotropic_vdf), ND_volume and
// ND_volumematerial, and ND_layer_vdf, a BSDF
// over an interior medium. A VDF only attenuates light that is transmitted into the medium
// (MaterialX: T_vdf = exp(−absorption) in the TRANSMISSION context); uplift's kernels evaluate
// reflection, where a layer over a VDF is its top BSDF unchanged.

// ND_absorption_vdf
fn mx_absorption_vdf(absorption: vec3<f32>) -> VDF {
    return VDF(absorption, vec3<f32>(0.0));
}

// ND_anisotropic_vdf (the Henyey–Greenstein anisotropy only matters inside the medium).
fn mx_anisotropic_vdf(absorption: vec3<f32>, scattering: vec3<f32>, anisotropy: f32) -> VDF {
    return VDF(absorption, scattering);
}

// ND_layer_vdf
fn mx_layer_vdf(cl: mx_closure, top: BSDF, base: VDF) -> BSDF {
    return top;
}

// ND_volume: a volume shader from its VDF (its EDF, volume emission, is not kept: kernels
// evaluate surfaces).
fn mx_volume(vdf: VDF, edf: EDF) -> mx_volumeshader {
    return mx_volumeshader(vdf);
}

// ND_volumematerial: a material with no surface — nothing scattered or emitted at the surface,
// everything passes (the empty surface shader).
fn mx_volumematerial(volumeshader: mx_volumeshader) -> mx_surfaceshader {
    return mx_surfaceshader_empty();
}
