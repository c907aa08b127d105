// Convolution helpers. `heighttonormal` (ND_heighttonormal_vector3) is built by the compiler
// (compiler/src/graph_builder/height_to_normal.rs): compute kernels have no screen-space
// derivatives, so it differentiates along UV0 by central differences and calls this function
// with the height `h` and the node's texcoord `t` at UV0 ± ε·(1, 0) and UV0 ± ε·(0, 1).

// MaterialX's mx_heighttonormal_vector3 with the derivatives d/du, d/dv in place of dFdx, dFdy:
// n = (dT/du, s·dH/du) × (dT/dv, s·dH/dv), s = scale/16 (parity with the Sobel filter), flat
// where degenerate, flipped to +z for mirrored coordinates, encoded as n·0.5 + 0.5.
fn mx_heighttonormal_from_differences(h_u1: f32, h_u0: f32, h_v1: f32, h_v0: f32, t_u1: vec2<f32>, t_u0: vec2<f32>, t_v1: vec2<f32>, t_v0: vec2<f32>, scale: f32, step: f32) -> vec3<f32> {
    let inv = 1.0 / (2.0 * step);
    let s = scale / 16.0;
    let tangent = vec3<f32>((t_u1 - t_u0) * inv, (h_u1 - h_u0) * inv * s);
    let bitangent = vec3<f32>((t_v1 - t_v0) * inv, (h_v1 - h_v0) * inv * s);
    var n = cross(tangent, bitangent);
    let eps = 1.192092896e-07;
    if (!(dot(n, n) >= eps * eps)) {
        n = vec3<f32>(0.0, 0.0, 1.0);
    } else if (n.z < 0.0) {
        n = -n;
    }
    return normalize(n) * 0.5 + 0.5;
}
