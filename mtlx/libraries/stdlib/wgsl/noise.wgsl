// noise.wgsl: MaterialX's noise library (genglsl/lib/mx_noise.glsl, itself a port of OSL's
// oslnoise.h) and the stdlib noise nodes built on it:
//   noise2d, noise3d          float, vector2, vector3, vector4   (signed Perlin, ~[-1,1])
//   fractal2d, fractal3d      float, vector2, vector3, vector4   (Perlin fBm, no pivot)
//   cellnoise2d, cellnoise3d  float                              ([0,1] per integer cell)
//   worleynoise2d/3d          float, vector2, vector3            (F1/F2/F3 distances or cell ids)
// The colorN / FA variants of noise and fractal are nodegraphs over these (stdlib_ng.mtlx).
//
// Bit-exactness with OSL/MaterialX: the Bob Jenkins lookup3 hash runs on u32 (WGSL u32
// arithmetic wraps like C unsigned); signed lattice coordinates are reinterpreted with u32(i32),
// which is the two's-complement bit pattern, exactly as GLSL's uint(int). See NOISE.md.
//
// WGSL has no overloading: MaterialX's overloaded helpers get a suffix naming the dimension of
// their input (`_2d`, `_3d`) or their arity (`mx_hash_int2`). Helper names that could clash with
// other library files carry an `mx_noise_` prefix.
//
// The only structural deviation from the GLSL: mx_worley_* computes each feature point once
// (the GLSL computes it twice, in mx_worley_distance and again for `cellpos`); the values are
// identical. Worley feature points are hashed from their integer cell directly instead of
// round-tripping the cell index through a float (identical for |cell| < 2^24).

// ---------------------------------------------------------------------------------------------
// Small helpers

fn mx_noise_floor(x: f32) -> i32 {
    return i32(floor(x));
}

// The Perlin lattice cell of x: MaterialX's int(floor(x)) for |x| < 2^31. Beyond, where the
// GLSL conversion is undefined (and a saturating one leaves x - float(cell) huge, so the fade
// overflows and the noise is NaN), every f32 is an integer and the cell is x modulo 2^32 — the
// two's-complement wrap the u32 hash arithmetic applies to lattice coordinates anyway (exact:
// the remainder is a multiple of x's ulp below 2^32); ±inf and NaN give cell 0.
fn mx_noise_cell(x: f32) -> i32 {
    let wrapped = x - 4294967296.0 * floor(x / 4294967296.0);
    let far = i32(u32(select(0.0, wrapped, abs(x) <= 3.4028235e38)));
    return select(far, i32(floor(x)), abs(x) < 2147483648.0);
}

// x's position in its cell, x - floor(x): MaterialX's x - float(int(floor(x))) wherever that is
// defined. From |x| = 2^24 on every f32 is an integer and it is 0 (so Perlin noise is 0 there,
// as MaterialX's is up to 2^31); also 0 for ±inf and NaN, which would give NaN.
fn mx_noise_frac(x: f32) -> f32 {
    return select(0.0, x - floor(x), abs(x) < 16777216.0);
}

// Quintic fade 6t^5 - 15t^4 + 10t^3.
fn mx_noise_fade(t: f32) -> f32 {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

fn mx_noise_bilerp_float(v0: f32, v1: f32, v2: f32, v3: f32, s: f32, t: f32) -> f32 {
    let s1 = 1.0 - s;
    return (1.0 - t) * (v0 * s1 + v1 * s) + t * (v2 * s1 + v3 * s);
}

fn mx_noise_bilerp_vec3(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, v3: vec3<f32>, s: f32, t: f32) -> vec3<f32> {
    let s1 = 1.0 - s;
    return (1.0 - t) * (v0 * s1 + v1 * s) + t * (v2 * s1 + v3 * s);
}

fn mx_noise_trilerp_float(v0: f32, v1: f32, v2: f32, v3: f32, v4: f32, v5: f32, v6: f32, v7: f32, s: f32, t: f32, r: f32) -> f32 {
    let s1 = 1.0 - s;
    let t1 = 1.0 - t;
    let r1 = 1.0 - r;
    return (r1 * (t1 * (v0 * s1 + v1 * s) + t * (v2 * s1 + v3 * s)) +
            r * (t1 * (v4 * s1 + v5 * s) + t * (v6 * s1 + v7 * s)));
}

fn mx_noise_trilerp_vec3(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, v3: vec3<f32>, v4: vec3<f32>, v5: vec3<f32>, v6: vec3<f32>, v7: vec3<f32>, s: f32, t: f32, r: f32) -> vec3<f32> {
    let s1 = 1.0 - s;
    let t1 = 1.0 - t;
    let r1 = 1.0 - r;
    return (r1 * (t1 * (v0 * s1 + v1 * s) + t * (v2 * s1 + v3 * s)) +
            r * (t1 * (v4 * s1 + v5 * s) + t * (v6 * s1 + v7 * s)));
}

// ---------------------------------------------------------------------------------------------
// Gradients: dot product of (x, y[, z]) with a hash-chosen lattice direction (not normalized;
// the 0.6616 / 0.9820 factors in the Perlin functions account for that).

// 2D: 8 directions (+-1, +-2) and (+-2, +-1), from hash & 7.
fn mx_gradient_float_2d(hash: u32, x: f32, y: f32) -> f32 {
    let h = hash & 7u;
    let u = select(y, x, h < 4u);
    let v = 2.0 * select(x, y, h < 4u);
    return select(u, -u, (h & 1u) != 0u) + select(v, -v, (h & 2u) != 0u);
}

// 3D: the 12 cube-edge directions (16 entries, 4 repeated), from hash & 15.
fn mx_gradient_float_3d(hash: u32, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15u;
    let u = select(y, x, h < 8u);
    let v = select(select(z, x, (h == 12u) || (h == 14u)), y, h < 4u);
    return select(u, -u, (h & 1u) != 0u) + select(v, -v, (h & 2u) != 0u);
}

fn mx_gradient_vec3_2d(hash: vec3<u32>, x: f32, y: f32) -> vec3<f32> {
    return vec3<f32>(mx_gradient_float_2d(hash.x, x, y),
                     mx_gradient_float_2d(hash.y, x, y),
                     mx_gradient_float_2d(hash.z, x, y));
}

fn mx_gradient_vec3_3d(hash: vec3<u32>, x: f32, y: f32, z: f32) -> vec3<f32> {
    return vec3<f32>(mx_gradient_float_3d(hash.x, x, y, z),
                     mx_gradient_float_3d(hash.y, x, y, z),
                     mx_gradient_float_3d(hash.z, x, y, z));
}

// ---------------------------------------------------------------------------------------------
// Bob Jenkins' lookup3 hash (bjmix / bjfinal), seeded as OSL: 0xdeadbeef + (len << 2) + 13.

fn mx_rotl32(x: u32, k: u32) -> u32 {
    return (x << k) | (x >> (32u - k));
}

// lookup3 mix(a, b, c); returns the mixed (a, b, c).
fn mx_bjmix(abc: vec3<u32>) -> vec3<u32> {
    var a = abc.x;
    var b = abc.y;
    var c = abc.z;
    a -= c; a ^= mx_rotl32(c, 4u);  c += b;
    b -= a; b ^= mx_rotl32(a, 6u);  a += c;
    c -= b; c ^= mx_rotl32(b, 8u);  b += a;
    a -= c; a ^= mx_rotl32(c, 16u); c += b;
    b -= a; b ^= mx_rotl32(a, 19u); a += c;
    c -= b; c ^= mx_rotl32(b, 4u);  b += a;
    return vec3<u32>(a, b, c);
}

// lookup3 final(a, b, c); returns c.
fn mx_bjfinal(a_in: u32, b_in: u32, c_in: u32) -> u32 {
    var a = a_in;
    var b = b_in;
    var c = c_in;
    c ^= b; c -= mx_rotl32(b, 14u);
    a ^= c; a -= mx_rotl32(c, 11u);
    b ^= a; b -= mx_rotl32(a, 25u);
    c ^= b; c -= mx_rotl32(b, 16u);
    a ^= c; a -= mx_rotl32(c, 4u);
    b ^= a; b -= mx_rotl32(a, 14u);
    c ^= b; c -= mx_rotl32(b, 24u);
    return c;
}

// u32 → [0,1]: bits / 2^32 in f32 (float(0xffffffff) rounds to 2^32, as in the GLSL). Values
// within 128 of 0xffffffff round to exactly 1.0.
fn mx_bits_to_01(bits: u32) -> f32 {
    return f32(bits) / f32(0xffffffffu);
}

fn mx_hash_int1(x: i32) -> u32 {
    let seed = 0xdeadbeefu + (1u << 2u) + 13u;
    return mx_bjfinal(seed + u32(x), seed, seed);
}

fn mx_hash_int2(x: i32, y: i32) -> u32 {
    let seed = 0xdeadbeefu + (2u << 2u) + 13u;
    return mx_bjfinal(seed + u32(x), seed + u32(y), seed);
}

fn mx_hash_int3(x: i32, y: i32, z: i32) -> u32 {
    let seed = 0xdeadbeefu + (3u << 2u) + 13u;
    return mx_bjfinal(seed + u32(x), seed + u32(y), seed + u32(z));
}

fn mx_hash_int4(x: i32, y: i32, z: i32, xx: i32) -> u32 {
    let seed = 0xdeadbeefu + (4u << 2u) + 13u;
    let m = mx_bjmix(vec3<u32>(seed + u32(x), seed + u32(y), seed + u32(z)));
    return mx_bjfinal(m.x + u32(xx), m.y, m.z);
}

// One 32-bit hash split into three 8-bit channel hashes (only low bits feed the gradients).
fn mx_hash_vec3_2d(x: i32, y: i32) -> vec3<u32> {
    let h = mx_hash_int2(x, y);
    return vec3<u32>(h & 0xFFu, (h >> 8u) & 0xFFu, (h >> 16u) & 0xFFu);
}

fn mx_hash_vec3_3d(x: i32, y: i32, z: i32) -> vec3<u32> {
    let h = mx_hash_int3(x, y, z);
    return vec3<u32>(h & 0xFFu, (h >> 8u) & 0xFFu, (h >> 16u) & 0xFFu);
}

// ---------------------------------------------------------------------------------------------
// Perlin gradient noise, signed, roughly [-1, 1].

fn mx_perlin_noise_float_2d(p: vec2<f32>) -> f32 {
    let X = mx_noise_cell(p.x);
    let Y = mx_noise_cell(p.y);
    let fx = mx_noise_frac(p.x);
    let fy = mx_noise_frac(p.y);
    let u = mx_noise_fade(fx);
    let v = mx_noise_fade(fy);
    let result = mx_noise_bilerp_float(
        mx_gradient_float_2d(mx_hash_int2(X,     Y    ), fx,       fy      ),
        mx_gradient_float_2d(mx_hash_int2(X + 1, Y    ), fx - 1.0, fy      ),
        mx_gradient_float_2d(mx_hash_int2(X,     Y + 1), fx,       fy - 1.0),
        mx_gradient_float_2d(mx_hash_int2(X + 1, Y + 1), fx - 1.0, fy - 1.0),
        u, v);
    return 0.6616 * result;
}

fn mx_perlin_noise_float_3d(p: vec3<f32>) -> f32 {
    let X = mx_noise_cell(p.x);
    let Y = mx_noise_cell(p.y);
    let Z = mx_noise_cell(p.z);
    let fx = mx_noise_frac(p.x);
    let fy = mx_noise_frac(p.y);
    let fz = mx_noise_frac(p.z);
    let u = mx_noise_fade(fx);
    let v = mx_noise_fade(fy);
    let w = mx_noise_fade(fz);
    let result = mx_noise_trilerp_float(
        mx_gradient_float_3d(mx_hash_int3(X,     Y,     Z    ), fx,       fy,       fz      ),
        mx_gradient_float_3d(mx_hash_int3(X + 1, Y,     Z    ), fx - 1.0, fy,       fz      ),
        mx_gradient_float_3d(mx_hash_int3(X,     Y + 1, Z    ), fx,       fy - 1.0, fz      ),
        mx_gradient_float_3d(mx_hash_int3(X + 1, Y + 1, Z    ), fx - 1.0, fy - 1.0, fz      ),
        mx_gradient_float_3d(mx_hash_int3(X,     Y,     Z + 1), fx,       fy,       fz - 1.0),
        mx_gradient_float_3d(mx_hash_int3(X + 1, Y,     Z + 1), fx - 1.0, fy,       fz - 1.0),
        mx_gradient_float_3d(mx_hash_int3(X,     Y + 1, Z + 1), fx,       fy - 1.0, fz - 1.0),
        mx_gradient_float_3d(mx_hash_int3(X + 1, Y + 1, Z + 1), fx - 1.0, fy - 1.0, fz - 1.0),
        u, v, w);
    return 0.9820 * result;
}

fn mx_perlin_noise_vec3_2d(p: vec2<f32>) -> vec3<f32> {
    let X = mx_noise_cell(p.x);
    let Y = mx_noise_cell(p.y);
    let fx = mx_noise_frac(p.x);
    let fy = mx_noise_frac(p.y);
    let u = mx_noise_fade(fx);
    let v = mx_noise_fade(fy);
    let result = mx_noise_bilerp_vec3(
        mx_gradient_vec3_2d(mx_hash_vec3_2d(X,     Y    ), fx,       fy      ),
        mx_gradient_vec3_2d(mx_hash_vec3_2d(X + 1, Y    ), fx - 1.0, fy      ),
        mx_gradient_vec3_2d(mx_hash_vec3_2d(X,     Y + 1), fx,       fy - 1.0),
        mx_gradient_vec3_2d(mx_hash_vec3_2d(X + 1, Y + 1), fx - 1.0, fy - 1.0),
        u, v);
    return 0.6616 * result;
}

fn mx_perlin_noise_vec3_3d(p: vec3<f32>) -> vec3<f32> {
    let X = mx_noise_cell(p.x);
    let Y = mx_noise_cell(p.y);
    let Z = mx_noise_cell(p.z);
    let fx = mx_noise_frac(p.x);
    let fy = mx_noise_frac(p.y);
    let fz = mx_noise_frac(p.z);
    let u = mx_noise_fade(fx);
    let v = mx_noise_fade(fy);
    let w = mx_noise_fade(fz);
    let result = mx_noise_trilerp_vec3(
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X,     Y,     Z    ), fx,       fy,       fz      ),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X + 1, Y,     Z    ), fx - 1.0, fy,       fz      ),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X,     Y + 1, Z    ), fx,       fy - 1.0, fz      ),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X + 1, Y + 1, Z    ), fx - 1.0, fy - 1.0, fz      ),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X,     Y,     Z + 1), fx,       fy,       fz - 1.0),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X + 1, Y,     Z + 1), fx - 1.0, fy,       fz - 1.0),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X,     Y + 1, Z + 1), fx,       fy - 1.0, fz - 1.0),
        mx_gradient_vec3_3d(mx_hash_vec3_3d(X + 1, Y + 1, Z + 1), fx - 1.0, fy - 1.0, fz - 1.0),
        u, v, w);
    return 0.9820 * result;
}

// ---------------------------------------------------------------------------------------------
// Cell noise: one hash per integer lattice cell, mapped to [0,1].

fn mx_cell_noise_float_2d(p: vec2<f32>) -> f32 {
    return mx_bits_to_01(mx_hash_int2(mx_noise_floor(p.x), mx_noise_floor(p.y)));
}

fn mx_cell_noise_float_3d(p: vec3<f32>) -> f32 {
    return mx_bits_to_01(mx_hash_int3(mx_noise_floor(p.x), mx_noise_floor(p.y), mx_noise_floor(p.z)));
}

// Three independent cell values for integer cell (ix, iy): hashes (ix, iy, 0..2).
fn mx_cell_noise_vec3_i2(ix: i32, iy: i32) -> vec3<f32> {
    return vec3<f32>(mx_bits_to_01(mx_hash_int3(ix, iy, 0)),
                     mx_bits_to_01(mx_hash_int3(ix, iy, 1)),
                     mx_bits_to_01(mx_hash_int3(ix, iy, 2)));
}

// Three independent cell values for integer cell (ix, iy, iz): hashes (ix, iy, iz, 0..2).
fn mx_cell_noise_vec3_i3(ix: i32, iy: i32, iz: i32) -> vec3<f32> {
    return vec3<f32>(mx_bits_to_01(mx_hash_int4(ix, iy, iz, 0)),
                     mx_bits_to_01(mx_hash_int4(ix, iy, iz, 1)),
                     mx_bits_to_01(mx_hash_int4(ix, iy, iz, 2)));
}

fn mx_cell_noise_vec3_2d(p: vec2<f32>) -> vec3<f32> {
    return mx_cell_noise_vec3_i2(mx_noise_floor(p.x), mx_noise_floor(p.y));
}

fn mx_cell_noise_vec3_3d(p: vec3<f32>) -> vec3<f32> {
    return mx_cell_noise_vec3_i3(mx_noise_floor(p.x), mx_noise_floor(p.y), mx_noise_floor(p.z));
}

// ---------------------------------------------------------------------------------------------
// Fractal (fBm) sums of Perlin noise: sum_{i<octaves} diminish^i * perlin(p * lacunarity^i),
// MaterialX's loop (powers by repeated multiplication). It stays finite for any octave count:
// the lattice helpers above give 0 where MaterialX's int conversion overflows (lacunarity 2
// takes a coordinate of 1 past 2^31 at octave 32, and MaterialX's GLSL is undefined there; a
// saturating conversion gives NaN), and the loop stops at the first octave from which every
// later one adds exactly 0 — the amplitude has underflowed to 0, or every coordinate is 0 or an
// integer of at least 2^24 that |lacunarity| >= 1 keeps integer (Perlin noise is 0 on the
// lattice). Where MaterialX's sum is defined, the value is MaterialX's to the bit; beyond, it
// is the converged sum. (With diminish > 1 the sum grows as MaterialX's does.)

fn mx_fractal_done_2d(pp: vec2<f32>, amplitude: f32, lacunarity: f32) -> bool {
    let lattice = (pp == vec2<f32>(0.0)) | (abs(pp) >= vec2<f32>(16777216.0));
    return amplitude == 0.0 || (all(lattice) && abs(lacunarity) >= 1.0);
}

fn mx_fractal_done_3d(pp: vec3<f32>, amplitude: f32, lacunarity: f32) -> bool {
    let lattice = (pp == vec3<f32>(0.0)) | (abs(pp) >= vec3<f32>(16777216.0));
    return amplitude == 0.0 || (all(lattice) && abs(lacunarity) >= 1.0);
}

fn mx_fractal2d_noise_float(p: vec2<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> f32 {
    var result = 0.0;
    var amplitude = 1.0;
    var pp = p;
    for (var i = 0; i < octaves; i++) {
        if (mx_fractal_done_2d(pp, amplitude, lacunarity)) {
            break;
        }
        result += amplitude * mx_perlin_noise_float_2d(pp);
        amplitude *= diminish;
        pp *= lacunarity;
    }
    return result;
}

fn mx_fractal2d_noise_vec3(p: vec2<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> vec3<f32> {
    var result = vec3<f32>(0.0);
    var amplitude = 1.0;
    var pp = p;
    for (var i = 0; i < octaves; i++) {
        if (mx_fractal_done_2d(pp, amplitude, lacunarity)) {
            break;
        }
        result += amplitude * mx_perlin_noise_vec3_2d(pp);
        amplitude *= diminish;
        pp *= lacunarity;
    }
    return result;
}

fn mx_fractal2d_noise_vec2(p: vec2<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> vec2<f32> {
    return vec2<f32>(mx_fractal2d_noise_float(p, octaves, lacunarity, diminish),
                     mx_fractal2d_noise_float(p + vec2<f32>(19.0, 193.0), octaves, lacunarity, diminish));
}

fn mx_fractal2d_noise_vec4(p: vec2<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> vec4<f32> {
    let c = mx_fractal2d_noise_vec3(p, octaves, lacunarity, diminish);
    let f = mx_fractal2d_noise_float(p + vec2<f32>(19.0, 193.0), octaves, lacunarity, diminish);
    return vec4<f32>(c, f);
}

fn mx_fractal3d_noise_float(p: vec3<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> f32 {
    var result = 0.0;
    var amplitude = 1.0;
    var pp = p;
    for (var i = 0; i < octaves; i++) {
        if (mx_fractal_done_3d(pp, amplitude, lacunarity)) {
            break;
        }
        result += amplitude * mx_perlin_noise_float_3d(pp);
        amplitude *= diminish;
        pp *= lacunarity;
    }
    return result;
}

fn mx_fractal3d_noise_vec3(p: vec3<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> vec3<f32> {
    var result = vec3<f32>(0.0);
    var amplitude = 1.0;
    var pp = p;
    for (var i = 0; i < octaves; i++) {
        if (mx_fractal_done_3d(pp, amplitude, lacunarity)) {
            break;
        }
        result += amplitude * mx_perlin_noise_vec3_3d(pp);
        amplitude *= diminish;
        pp *= lacunarity;
    }
    return result;
}

fn mx_fractal3d_noise_vec2(p: vec3<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> vec2<f32> {
    return vec2<f32>(mx_fractal3d_noise_float(p, octaves, lacunarity, diminish),
                     mx_fractal3d_noise_float(p + vec3<f32>(19.0, 193.0, 17.0), octaves, lacunarity, diminish));
}

fn mx_fractal3d_noise_vec4(p: vec3<f32>, octaves: i32, lacunarity: f32, diminish: f32) -> vec4<f32> {
    let c = mx_fractal3d_noise_vec3(p, octaves, lacunarity, diminish);
    let f = mx_fractal3d_noise_float(p + vec3<f32>(19.0, 193.0, 17.0), octaves, lacunarity, diminish);
    return vec4<f32>(c, f);
}

// ---------------------------------------------------------------------------------------------
// Worley (cellular) noise. One feature point per integer cell, at cell + 0.5 + jitter *
// (cellnoise_vec3(cell) - 0.5); the 3x3 (3x3x3) neighbourhood of the sample's cell is searched.
// metric: 0 Euclidean (the only one the stdlib nodes use), 1 squared Euclidean,
// 2 Manhattan, 3 Chebyshev. style: 0 distances (F1[, F2[, F3]]), 1 "solid" = cell noise of the
// nearest feature point (a per-cell random value).

// Feature point of cell (xoff + x, yoff + y), relative to cell (xoff, yoff).
fn mx_worley_cell_position_2d(x: i32, y: i32, xoff: i32, yoff: i32, jitter: f32) -> vec2<f32> {
    let tmp = mx_cell_noise_vec3_i2(x + xoff, y + yoff);
    var off = vec2<f32>(tmp.x, tmp.y);
    off -= 0.5;
    off *= jitter;
    off += 0.5;
    return vec2<f32>(f32(x), f32(y)) + off;
}

fn mx_worley_cell_position_3d(x: i32, y: i32, z: i32, xoff: i32, yoff: i32, zoff: i32, jitter: f32) -> vec3<f32> {
    var off = mx_cell_noise_vec3_i3(x + xoff, y + yoff, z + zoff);
    off -= 0.5;
    off *= jitter;
    off += 0.5;
    return vec3<f32>(f32(x), f32(y), f32(z)) + off;
}

// Distance measure of the offset diff = cellpos - p (squared for metrics 0 and 1).
fn mx_worley_distance_2d(diff: vec2<f32>, metric: i32) -> f32 {
    if (metric == 2) {
        return abs(diff.x) + abs(diff.y);
    }
    if (metric == 3) {
        return max(abs(diff.x), abs(diff.y));
    }
    return dot(diff, diff);
}

fn mx_worley_distance_3d(diff: vec3<f32>, metric: i32) -> f32 {
    if (metric == 2) {
        return abs(diff.x) + abs(diff.y) + abs(diff.z);
    }
    if (metric == 3) {
        return max(max(abs(diff.x), abs(diff.y)), abs(diff.z));
    }
    return dot(diff, diff);
}

fn mx_worley_noise_float_2d(p: vec2<f32>, jitter: f32, style: i32, metric: i32) -> f32 {
    let X = mx_noise_floor(p.x);
    let Y = mx_noise_floor(p.y);
    let localpos = vec2<f32>(p.x - f32(X), p.y - f32(Y));
    var sqdist = 1e6;
    var minpos = vec2<f32>(0.0, 0.0);
    for (var x = -1; x <= 1; x++) {
        for (var y = -1; y <= 1; y++) {
            let cellpos = mx_worley_cell_position_2d(x, y, X, Y, jitter) - localpos;
            let dist = mx_worley_distance_2d(cellpos, metric);
            if (dist < sqdist) {
                sqdist = dist;
                minpos = cellpos;
            }
        }
    }
    if (style == 1) {
        return mx_cell_noise_float_2d(minpos + p);
    }
    if (metric == 0) {
        sqdist = sqrt(sqdist);
    }
    return sqdist;
}

fn mx_worley_noise_vec2_2d(p: vec2<f32>, jitter: f32, style: i32, metric: i32) -> vec2<f32> {
    let X = mx_noise_floor(p.x);
    let Y = mx_noise_floor(p.y);
    let localpos = vec2<f32>(p.x - f32(X), p.y - f32(Y));
    var sqdist = vec2<f32>(1e6, 1e6);
    var minpos = vec2<f32>(0.0, 0.0);
    for (var x = -1; x <= 1; x++) {
        for (var y = -1; y <= 1; y++) {
            let cellpos = mx_worley_cell_position_2d(x, y, X, Y, jitter) - localpos;
            let dist = mx_worley_distance_2d(cellpos, metric);
            if (dist < sqdist.x) {
                sqdist.y = sqdist.x;
                sqdist.x = dist;
                minpos = cellpos;
            } else if (dist < sqdist.y) {
                sqdist.y = dist;
            }
        }
    }
    if (style == 1) {
        let tmp = mx_cell_noise_vec3_2d(minpos + p);
        return vec2<f32>(tmp.x, tmp.y);
    }
    if (metric == 0) {
        sqdist = sqrt(sqdist);
    }
    return sqdist;
}

fn mx_worley_noise_vec3_2d(p: vec2<f32>, jitter: f32, style: i32, metric: i32) -> vec3<f32> {
    let X = mx_noise_floor(p.x);
    let Y = mx_noise_floor(p.y);
    let localpos = vec2<f32>(p.x - f32(X), p.y - f32(Y));
    var sqdist = vec3<f32>(1e6, 1e6, 1e6);
    var minpos = vec2<f32>(0.0, 0.0);
    for (var x = -1; x <= 1; x++) {
        for (var y = -1; y <= 1; y++) {
            let cellpos = mx_worley_cell_position_2d(x, y, X, Y, jitter) - localpos;
            let dist = mx_worley_distance_2d(cellpos, metric);
            if (dist < sqdist.x) {
                sqdist.z = sqdist.y;
                sqdist.y = sqdist.x;
                sqdist.x = dist;
                minpos = cellpos;
            } else if (dist < sqdist.y) {
                sqdist.z = sqdist.y;
                sqdist.y = dist;
            } else if (dist < sqdist.z) {
                sqdist.z = dist;
            }
        }
    }
    if (style == 1) {
        return mx_cell_noise_vec3_2d(minpos + p);
    }
    if (metric == 0) {
        sqdist = sqrt(sqdist);
    }
    return sqdist;
}

fn mx_worley_noise_float_3d(p: vec3<f32>, jitter: f32, style: i32, metric: i32) -> f32 {
    let X = mx_noise_floor(p.x);
    let Y = mx_noise_floor(p.y);
    let Z = mx_noise_floor(p.z);
    let localpos = vec3<f32>(p.x - f32(X), p.y - f32(Y), p.z - f32(Z));
    var sqdist = 1e6;
    var minpos = vec3<f32>(0.0, 0.0, 0.0);
    for (var x = -1; x <= 1; x++) {
        for (var y = -1; y <= 1; y++) {
            for (var z = -1; z <= 1; z++) {
                let cellpos = mx_worley_cell_position_3d(x, y, z, X, Y, Z, jitter) - localpos;
                let dist = mx_worley_distance_3d(cellpos, metric);
                if (dist < sqdist) {
                    sqdist = dist;
                    minpos = cellpos;
                }
            }
        }
    }
    if (style == 1) {
        return mx_cell_noise_float_3d(minpos + p);
    }
    if (metric == 0) {
        sqdist = sqrt(sqdist);
    }
    return sqdist;
}

fn mx_worley_noise_vec2_3d(p: vec3<f32>, jitter: f32, style: i32, metric: i32) -> vec2<f32> {
    let X = mx_noise_floor(p.x);
    let Y = mx_noise_floor(p.y);
    let Z = mx_noise_floor(p.z);
    let localpos = vec3<f32>(p.x - f32(X), p.y - f32(Y), p.z - f32(Z));
    var sqdist = vec2<f32>(1e6, 1e6);
    var minpos = vec3<f32>(0.0, 0.0, 0.0);
    for (var x = -1; x <= 1; x++) {
        for (var y = -1; y <= 1; y++) {
            for (var z = -1; z <= 1; z++) {
                let cellpos = mx_worley_cell_position_3d(x, y, z, X, Y, Z, jitter) - localpos;
                let dist = mx_worley_distance_3d(cellpos, metric);
                if (dist < sqdist.x) {
                    sqdist.y = sqdist.x;
                    sqdist.x = dist;
                    minpos = cellpos;
                } else if (dist < sqdist.y) {
                    sqdist.y = dist;
                }
            }
        }
    }
    if (style == 1) {
        let tmp = mx_cell_noise_vec3_3d(minpos + p);
        return vec2<f32>(tmp.x, tmp.y);
    }
    if (metric == 0) {
        sqdist = sqrt(sqdist);
    }
    return sqdist;
}

fn mx_worley_noise_vec3_3d(p: vec3<f32>, jitter: f32, style: i32, metric: i32) -> vec3<f32> {
    let X = mx_noise_floor(p.x);
    let Y = mx_noise_floor(p.y);
    let Z = mx_noise_floor(p.z);
    let localpos = vec3<f32>(p.x - f32(X), p.y - f32(Y), p.z - f32(Z));
    var sqdist = vec3<f32>(1e6, 1e6, 1e6);
    var minpos = vec3<f32>(0.0, 0.0, 0.0);
    for (var x = -1; x <= 1; x++) {
        for (var y = -1; y <= 1; y++) {
            for (var z = -1; z <= 1; z++) {
                let cellpos = mx_worley_cell_position_3d(x, y, z, X, Y, Z, jitter) - localpos;
                let dist = mx_worley_distance_3d(cellpos, metric);
                if (dist < sqdist.x) {
                    sqdist.z = sqdist.y;
                    sqdist.y = sqdist.x;
                    sqdist.x = dist;
                    minpos = cellpos;
                } else if (dist < sqdist.y) {
                    sqdist.z = sqdist.y;
                    sqdist.y = dist;
                } else if (dist < sqdist.z) {
                    sqdist.z = dist;
                }
            }
        }
    }
    if (style == 1) {
        return mx_cell_noise_vec3_3d(minpos + p);
    }
    if (metric == 0) {
        sqdist = sqrt(sqdist);
    }
    return sqdist;
}

// =============================================================================================
// Nodes

// ---- noise2d: amplitude * perlin(texcoord) + pivot ----

fn mx_noise2d_float(amplitude: f32, pivot: f32, texcoord: vec2<f32>) -> f32 {
    return mx_perlin_noise_float_2d(texcoord) * amplitude + pivot;
}

fn mx_noise2d_vector2(amplitude: vec2<f32>, pivot: f32, texcoord: vec2<f32>) -> vec2<f32> {
    let value = mx_perlin_noise_vec3_2d(texcoord);
    return value.xy * amplitude + pivot;
}

fn mx_noise2d_vector3(amplitude: vec3<f32>, pivot: f32, texcoord: vec2<f32>) -> vec3<f32> {
    return mx_perlin_noise_vec3_2d(texcoord) * amplitude + pivot;
}

fn mx_noise2d_vector4(amplitude: vec4<f32>, pivot: f32, texcoord: vec2<f32>) -> vec4<f32> {
    let xyz = mx_perlin_noise_vec3_2d(texcoord);
    let w = mx_perlin_noise_float_2d(texcoord + vec2<f32>(19.0, 73.0));
    return vec4<f32>(xyz, w) * amplitude + pivot;
}

// ---- noise3d: amplitude * perlin(position) + pivot ----

fn mx_noise3d_float(amplitude: f32, pivot: f32, position: vec3<f32>) -> f32 {
    return mx_perlin_noise_float_3d(position) * amplitude + pivot;
}

fn mx_noise3d_vector2(amplitude: vec2<f32>, pivot: f32, position: vec3<f32>) -> vec2<f32> {
    let value = mx_perlin_noise_vec3_3d(position);
    return value.xy * amplitude + pivot;
}

fn mx_noise3d_vector3(amplitude: vec3<f32>, pivot: f32, position: vec3<f32>) -> vec3<f32> {
    return mx_perlin_noise_vec3_3d(position) * amplitude + pivot;
}

fn mx_noise3d_vector4(amplitude: vec4<f32>, pivot: f32, position: vec3<f32>) -> vec4<f32> {
    let xyz = mx_perlin_noise_vec3_3d(position);
    let w = mx_perlin_noise_float_3d(position + vec3<f32>(19.0, 73.0, 29.0));
    return vec4<f32>(xyz, w) * amplitude + pivot;
}

// ---- fractal2d: amplitude * fbm(texcoord) (no pivot) ----

fn mx_fractal2d_float(amplitude: f32, octaves: i32, lacunarity: f32, diminish: f32, texcoord: vec2<f32>) -> f32 {
    return mx_fractal2d_noise_float(texcoord, octaves, lacunarity, diminish) * amplitude;
}

fn mx_fractal2d_vector2(amplitude: vec2<f32>, octaves: i32, lacunarity: f32, diminish: f32, texcoord: vec2<f32>) -> vec2<f32> {
    return mx_fractal2d_noise_vec2(texcoord, octaves, lacunarity, diminish) * amplitude;
}

fn mx_fractal2d_vector3(amplitude: vec3<f32>, octaves: i32, lacunarity: f32, diminish: f32, texcoord: vec2<f32>) -> vec3<f32> {
    return mx_fractal2d_noise_vec3(texcoord, octaves, lacunarity, diminish) * amplitude;
}

fn mx_fractal2d_vector4(amplitude: vec4<f32>, octaves: i32, lacunarity: f32, diminish: f32, texcoord: vec2<f32>) -> vec4<f32> {
    return mx_fractal2d_noise_vec4(texcoord, octaves, lacunarity, diminish) * amplitude;
}

// ---- fractal3d: amplitude * fbm(position) (no pivot) ----

fn mx_fractal3d_float(amplitude: f32, octaves: i32, lacunarity: f32, diminish: f32, position: vec3<f32>) -> f32 {
    return mx_fractal3d_noise_float(position, octaves, lacunarity, diminish) * amplitude;
}

fn mx_fractal3d_vector2(amplitude: vec2<f32>, octaves: i32, lacunarity: f32, diminish: f32, position: vec3<f32>) -> vec2<f32> {
    return mx_fractal3d_noise_vec2(position, octaves, lacunarity, diminish) * amplitude;
}

fn mx_fractal3d_vector3(amplitude: vec3<f32>, octaves: i32, lacunarity: f32, diminish: f32, position: vec3<f32>) -> vec3<f32> {
    return mx_fractal3d_noise_vec3(position, octaves, lacunarity, diminish) * amplitude;
}

fn mx_fractal3d_vector4(amplitude: vec4<f32>, octaves: i32, lacunarity: f32, diminish: f32, position: vec3<f32>) -> vec4<f32> {
    return mx_fractal3d_noise_vec4(position, octaves, lacunarity, diminish) * amplitude;
}

// ---- cellnoise ----

fn mx_cellnoise2d_float(texcoord: vec2<f32>) -> f32 {
    return mx_cell_noise_float_2d(texcoord);
}

fn mx_cellnoise3d_float(position: vec3<f32>) -> f32 {
    return mx_cell_noise_float_3d(position);
}

// ---- worleynoise: style 0 = Distance, 1 = Solid; Euclidean metric ----

fn mx_worleynoise2d_float(texcoord: vec2<f32>, jitter: f32, style: i32) -> f32 {
    return mx_worley_noise_float_2d(texcoord, jitter, style, 0);
}

fn mx_worleynoise2d_vector2(texcoord: vec2<f32>, jitter: f32, style: i32) -> vec2<f32> {
    return mx_worley_noise_vec2_2d(texcoord, jitter, style, 0);
}

fn mx_worleynoise2d_vector3(texcoord: vec2<f32>, jitter: f32, style: i32) -> vec3<f32> {
    return mx_worley_noise_vec3_2d(texcoord, jitter, style, 0);
}

fn mx_worleynoise3d_float(position: vec3<f32>, jitter: f32, style: i32) -> f32 {
    return mx_worley_noise_float_3d(position, jitter, style, 0);
}

fn mx_worleynoise3d_vector2(position: vec3<f32>, jitter: f32, style: i32) -> vec2<f32> {
    return mx_worley_noise_vec2_3d(position, jitter, style, 0);
}

fn mx_worleynoise3d_vector3(position: vec3<f32>, jitter: f32, style: i32) -> vec3<f32> {
    return mx_worley_noise_vec3_3d(position, jitter, style, 0);
}
