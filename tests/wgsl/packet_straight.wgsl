// Straight-line functions for the packet writer (compiler/src/backend_packet.rs): written twice,
// as packet Rust (tests/out/packet/) and by the scalar writer (tests/out/rs_wgsl/, the oracle),
// and compared lane by lane on every SIMD level in tests/rs_compile/tests/integration/packet_vs_scalar.rs.
fn poly(x: f32) -> f32 { return ((x * 0.5 + 1.0) * x - 2.0) / (x * x + 1.0); }
fn shade(n: vec3<f32>, l: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    let nl = max(dot(normalize(n), normalize(l)), 0.0);
    return albedo * nl + vec3(0.04) * (1.0 - nl);
}
fn mixes(a: vec4<f32>, b: vec4<f32>, t: f32) -> vec4<f32> {
    return mix(a, b, vec4(t)) + clamp(a, vec4(-1.0), vec4(1.0)) * step(b, a);
}
fn hashes(x: u32, y: i32) -> f32 {
    let h = (x * 747796405u + 2891336453u) ^ (u32(y) >> 3u);
    return f32(h >> 8u) * (1.0 / 16777216.0) + f32(y % 7) - f32(i32(floor(f32(y) * 0.3)));
}
fn pick(a: f32, b: f32) -> f32 {
    let m = a < b;
    let v = select(b, a, m);
    return v + select(0.0, 1.0, (a > 0.0) & !(b > 0.0));
}
fn locals(a: vec2<f32>) -> vec2<f32> {
    var p = a;
    p.x = p.x * 2.0;
    p = p.yx + vec2(fract(a.x), round(a.y));
    return p;
}
fn calls(a: f32, v: vec3<f32>) -> f32 {
    return poly(a) + length(cross(v, vec3(0.0, 1.0, 0.0))) + sqrt(abs(a)) + inverseSqrt(abs(a) + 1.0) + sin(a);
}
fn converts(x: f32) -> i32 { return i32(x * 1000.0) + i32(u32(abs(x) * 3.0)); }
