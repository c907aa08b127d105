// Structs in the packet writer (packet structs of packets, blended member-wise under masks):
// written as packet Rust (tests/out/packet/) and by the scalar writer (the oracle), compared lane
// by lane in tests/rs_compile/tests/integration/packet_vs_scalar.rs.
struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
    t: f32,
}
struct Hit {
    ray: Ray,
    hit: bool,
    id: i32,
}
fn make_ray(o: vec3<f32>, d: vec3<f32>) -> Ray {
    return Ray(o, normalize(d), 0.0);
}
fn advance(r: Ray, dt: f32) -> Ray {
    var q = r;
    q.t = q.t + dt;
    q.origin = q.origin + q.dir * dt;
    return q;
}
fn trace(o: vec3<f32>, d: vec3<f32>, limit: f32) -> f32 {
    var h = Hit(make_ray(o, d), false, 0);
    for (var k = 0; k < 6; k++) {
        h.ray = advance(h.ray, 0.5);
        if (h.ray.origin.z > limit) {
            h.hit = true;
            h.id = k;
            break;
        }
    }
    return select(-1.0, h.ray.t + f32(h.id), h.hit);
}
fn pick_ray(a: f32, o: vec3<f32>) -> vec3<f32> {
    var r = make_ray(o, vec3(1.0, 0.0, 0.0));
    if (a > 0.0) {
        r = make_ray(o * a, vec3(0.0, a, 1.0));
    }
    return r.dir + r.origin;
}
