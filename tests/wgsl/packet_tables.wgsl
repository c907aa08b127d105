// Runtime indices into constant f32 arrays (the albedo tables' shape) in the packet writer:
// gathers, the index clamped as the scalar writer clamps it; compared lane by lane in
// tests/rs_compile/tests/integration/packet_vs_scalar.rs.
const TABLE = array<f32, 8>(0.5, 1.5, 2.5, 4.0, 8.0, 16.0, 32.0, 64.0);
fn lookup(x: f32) -> f32 {
    let i = i32(floor(x * 4.0));
    return TABLE[i] + TABLE[clamp(i + 1, 0, 7)] * 0.5 + TABLE[u32(abs(x) * 2.0)];
}
