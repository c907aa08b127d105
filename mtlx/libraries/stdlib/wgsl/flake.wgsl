// ND_flake2d / ND_flake3d: MaterialX 1.39's flake noise (stdlib genglsl lib/mx_flake.glsl,
// which is its only specification), bit for bit: the lattice cell hash and xorshift32 stream
// on u32 (WGSL u32 arithmetic wraps like GLSL's uint), the coverage → probability fit, Arvo's
// fast random rotation of each candidate flake, the highest-priority overlapping flake of the
// 3×3×3 neighbourhood, and its normal drawn from a GGX distribution of the given roughness.

struct mx_flake2d_outputs {
    id: i32,
    rand: f32,
    presence: f32,
    flakenormal: vec3<f32>,
}

struct mx_flake3d_outputs {
    id: i32,
    rand: f32,
    presence: f32,
    flakenormal: vec3<f32>,
}

fn mx_flake_hash(seed: u32, i: u32) -> u32 {
    return (i ^ seed) * 1075385539u;
}

fn mx_flake_init_seed(i: vec3<i32>) -> u32 {
    return mx_flake_hash(mx_flake_hash(mx_flake_hash(0u, u32(i.x)), u32(i.y)), u32(i.z));
}

fn mx_flake_xorshift32(seed_in: u32) -> u32 {
    var seed = seed_in;
    seed = seed ^ (seed << 13u);
    seed = seed ^ (seed >> 17u);
    seed = seed ^ (seed << 5u);
    return seed;
}

fn mx_flake_uint_to_01(x: u32) -> f32 {
    return f32(x) / 4294967295.0;
}

// "Fast Random Rotation Matrices", James Arvo, Graphics Gems III p. 117.
fn mx_flake_rotate(p: vec3<f32>, i: vec3<f32>) -> vec3<f32> {
    let theta = 6.283185307179586 * i.x;
    let phi = 6.283185307179586 * i.y;
    let z = i.z * 2.0;
    let r = sqrt(z);
    let vx = sin(phi) * r;
    let vy = cos(phi) * r;
    let vz = sqrt(2.0 - z);
    let s_theta = sin(theta);
    let c_theta = cos(theta);
    let sx = vx * s_theta - vy * s_theta;
    let sy = vx * c_theta + vy * c_theta;
    let m = mat3x3<f32>(
        vec3<f32>(vx * sx - s_theta, vx * sy - s_theta, vx * vz),
        vec3<f32>(vy * sx + c_theta, vy * sy - c_theta, vy * vz),
        vec3<f32>(vz * sx, vz * sy, 1.0 - z),
    );
    return m * p;
}

// The probability that a cell holds a flake, for a coverage density x (MaterialX's fitted curve).
fn mx_flake_density_to_probability(x: f32) -> f32 {
    let xx = x * x;
    return (-26.19771808 * xx + 26.39663835 * x) / (85.53857017 * xx * x - 102.35069432 * xx - 101.42634862 * x + 118.45082288);
}

fn mx_flake(size: f32, roughness: f32, coverage: f32, position: vec3<f32>, normal: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> mx_flake3d_outputs {
    let probability = mx_flake_density_to_probability(clamp(coverage, 0.0, 1.0));
    let flake_diameter = 1.5 / sqrt(3.0);
    let P = position / vec3<f32>(size);
    let base_P = floor(P);
    let base_P_int = vec3<i32>(base_P);
    // Priority in [0, 1]: 0 is no flake; a flake of higher priority shadows those below it.
    var flake_priority = 0.0;
    var flake_seed = 0u;
    for (var i = -1; i < 2; i++) {
        for (var j = -1; j < 2; j++) {
            for (var k = -1; k < 2; k++) {
                var seed = mx_flake_xorshift32(mx_flake_init_seed(base_P_int + vec3<i32>(i, j, k)));
                if (mx_flake_uint_to_01(seed) <= probability) {
                    seed = mx_flake_xorshift32(seed);
                    let priority = mx_flake_uint_to_01(seed);
                    let flake_P = base_P + vec3<f32>(f32(i), f32(j), f32(k)) + vec3<f32>(0.5);
                    var PP = P - flake_P;
                    if (priority >= flake_priority && dot(PP, PP) < flake_diameter * flake_diameter * 4.0) {
                        var rot: vec3<f32>;
                        seed = mx_flake_xorshift32(seed);
                        rot.x = mx_flake_uint_to_01(seed);
                        seed = mx_flake_xorshift32(seed);
                        rot.y = mx_flake_uint_to_01(seed);
                        seed = mx_flake_xorshift32(seed);
                        rot.z = mx_flake_uint_to_01(seed);
                        PP = mx_flake_rotate(PP, rot);
                        if (abs(PP.x) <= flake_diameter && abs(PP.y) <= flake_diameter && abs(PP.z) <= flake_diameter) {
                            flake_priority = priority;
                            flake_seed = seed;
                        }
                    }
                }
            }
        }
    }
    if (flake_priority <= 0.0) {
        return mx_flake3d_outputs(0, 0.0, 0.0, normal);
    }
    // The flake's normal: a GGX microfacet normal of the given roughness.
    var seed = flake_seed;
    let xi0 = mx_flake_uint_to_01(seed);
    seed = mx_flake_xorshift32(seed);
    let xi1 = mx_flake_uint_to_01(seed);
    seed = mx_flake_xorshift32(seed);
    let phi = 6.283185307179586 * xi0;
    let tan_theta = roughness * roughness * sqrt(xi1) / sqrt(1.0 - xi1);
    let sin_theta = tan_theta / sqrt(1.0 + tan_theta * tan_theta);
    let cos_theta = sqrt(1.0 - sin_theta * sin_theta);
    let n = normalize(tangent * cos(phi) * sin_theta + bitangent * sin(phi) * sin_theta + normal * cos_theta);
    return mx_flake3d_outputs(i32(seed), mx_flake_uint_to_01(seed), flake_priority, n);
}

fn mx_flake2d(size: f32, roughness: f32, coverage: f32, texcoord: vec2<f32>, normal: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> mx_flake2d_outputs {
    let f = mx_flake(size, roughness, coverage, vec3<f32>(texcoord.x, texcoord.y, 0.0), normal, tangent, bitangent);
    return mx_flake2d_outputs(f.id, f.rand, f.presence, f.flakenormal);
}

fn mx_flake3d(size: f32, roughness: f32, coverage: f32, position: vec3<f32>, normal: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> mx_flake3d_outputs {
    return mx_flake(size, roughness, coverage, position, normal, tangent, bitangent);
}
