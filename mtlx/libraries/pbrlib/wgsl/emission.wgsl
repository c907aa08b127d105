// emission.wgsl: ND_uniform_edf. An EDF value is the radiance emitted towards the view.
// `surface` scatters with its BSDF only (uplift's kernels evaluate reflection, not emission), so
// EDF constructors exist for documents that attach emission to a surface. Direction-dependent
// EDFs (conical, measured, generalized_schlick) need the shading normal, which closure values
// do not carry; they are not implemented.

// ND_uniform_edf
fn mx_uniform_edf(color: vec3<f32>) -> EDF {
    return EDF(color);
}
