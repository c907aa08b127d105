// utility.wgsl: pbrlib's non-closure helpers: artistic_ior (Gulbrandsen 2014),
// roughness_anisotropy and roughness_dual (MaterialX's GLSL, clamps included).

struct mx_artistic_ior_outputs {
    ior: vec3<f32>,
    extinction: vec3<f32>,
}

// ND_artistic_ior
fn mx_artistic_ior(reflectivity: vec3<f32>, edge_color: vec3<f32>) -> mx_artistic_ior_outputs {
    let r = clamp(reflectivity, vec3<f32>(0.0), vec3<f32>(0.99));
    let r_sqrt = sqrt(r);
    let n_min = (vec3<f32>(1.0) - r) / (vec3<f32>(1.0) + r);
    let n_max = (vec3<f32>(1.0) + r_sqrt) / (vec3<f32>(1.0) - r_sqrt);
    let ior = mix(n_max, n_min, edge_color);
    let np1 = ior + vec3<f32>(1.0);
    let nm1 = ior - vec3<f32>(1.0);
    let k2 = max((np1 * np1 * r - nm1 * nm1) / (vec3<f32>(1.0) - r), vec3<f32>(0.0));
    return mx_artistic_ior_outputs(ior, sqrt(k2));
}

// ND_roughness_anisotropy
fn mx_roughness_anisotropy(roughness: f32, anisotropy: f32) -> vec2<f32> {
    let r2 = clamp(roughness * roughness, 1.0e-8, 1.0);
    if (anisotropy > 0.0) {
        let aspect = sqrt(1.0 - clamp(anisotropy, 0.0, 0.98));
        return vec2<f32>(min(r2 / aspect, 1.0), r2 * aspect);
    }
    return vec2<f32>(r2, r2);
}

// ND_roughness_dual
fn mx_roughness_dual(roughness: vec2<f32>) -> vec2<f32> {
    var r = roughness;
    if (r.y < 0.0) {
        r.y = r.x;
    }
    return clamp(r * r, vec2<f32>(1.0e-8), vec2<f32>(1.0));
}
