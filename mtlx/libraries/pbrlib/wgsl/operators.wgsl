// operators.wgsl: the closure operators of MaterialX 1.39's reference shaders
// (materialx-notes.md §1.3): layer R = R_top + T_top·R_base, T = T_top·T_base; mix lerps both
// by the mix amount; add sums responses and T = max(T1 + T2 − 1, 0); multiply scales the
// response by the weight clamped to [0, 1] and leaves T alone. In the sampling contexts each
// operator scales its operands' contributions the same way (a layer's base by the luminance of
// the top's throughput).

// A mix amount with NaN read as 0 (anything else passes, unclamped, as in MaterialX).
fn mx_mix_amount(m: f32) -> f32 {
    return select(0.0, m, abs(m) <= 1.0e30);
}

// ND_layer_bsdf
fn mx_layer_bsdf(cl: mx_closure, top: BSDF, base: BSDF) -> BSDF {
    let s = max(mx_luminance_rgb(top.throughput), 0.0);
    return BSDF(top.response + top.throughput * base.response, top.throughput * base.throughput, mx_lobe_combine(cl, top.lobe, 1.0, base.lobe, s));
}

// ND_mix_bsdf
fn mx_mix_bsdf(cl: mx_closure, fg: BSDF, bg: BSDF, mix_: f32) -> BSDF {
    let m = mx_mix_amount(mix_);
    return BSDF(mix(bg.response, fg.response, m), mix(bg.throughput, fg.throughput, m), mx_lobe_combine(cl, fg.lobe, m, bg.lobe, 1.0 - m));
}

// ND_add_bsdf
fn mx_add_bsdf(cl: mx_closure, in1: BSDF, in2: BSDF) -> BSDF {
    return BSDF(in1.response + in2.response, max(in1.throughput + in2.throughput - vec3<f32>(1.0), vec3<f32>(0.0)), mx_lobe_combine(cl, in1.lobe, 1.0, in2.lobe, 1.0));
}

// ND_multiply_bsdfC
fn mx_multiply_bsdfC(cl: mx_closure, in1: BSDF, in2: vec3<f32>) -> BSDF {
    let s = clamp(in2, vec3<f32>(0.0), vec3<f32>(1.0));
    return BSDF(in1.response * s, in1.throughput, mx_lobe_combine(cl, in1.lobe, mx_luminance_rgb(s), mx_bsdf_empty().lobe, 0.0));
}

// ND_multiply_bsdfF
fn mx_multiply_bsdfF(cl: mx_closure, in1: BSDF, in2: f32) -> BSDF {
    let s = clamp(in2, 0.0, 1.0);
    return BSDF(in1.response * s, in1.throughput, mx_lobe_combine(cl, in1.lobe, s, mx_bsdf_empty().lobe, 0.0));
}
