// volume.wgsl: the VDF nodes (ND_absorption_vdf, ND_anisotropic_vdf) and ND_layer_vdf, a BSDF
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
