// hextile.wgsl: ND_hextiledimage_color3/color4 and ND_hextilednormalmap_vector3, hex-tiling
// after Mikkelsen, "Practical Real-Time Hex-Tiling" (JCGT 11(2), 2022), as MaterialX's GLSL
// (lib/mx_hextile.glsl): the plane is cut into a triangle grid whose vertices are tile centres;
// each point blends three lookups, one per surrounding vertex, each rotated, scaled and offset by
// a hash of its vertex, with barycentric weights raised to the 7th power (luminance-weighted for
// images), then an optional Schlick gain (`falloff` ≠ 0.5). The image is read as `image` reads a
// periodic, linearly filtered texture (texture.wgsl: no mipmaps, so the GLSL's textureGrad
// derivatives have nothing to select). `default` is returned for an empty texture.

// Shadertoy 4djSRW's hash, as MaterialX's mx_hextile_hash.
fn mx_hextile_hash(p: vec2<f32>) -> vec2<f32> {
    var p3 = fract(vec3<f32>(p.x, p.y, p.x) * vec3<f32>(0.1031, 0.1030, 0.0973));
    p3 = p3 + vec3<f32>(dot(p3, vec3<f32>(p3.y, p3.z, p3.x) + vec3<f32>(33.33)));
    return fract((vec2<f32>(p3.x, p3.x) + vec2<f32>(p3.y, p3.z)) * vec2<f32>(p3.z, p3.y));
}

// Schlick's gain (Graphics Gems IV), as MaterialX's mx_schlick_gain.
fn mx_schlick_gain(x: f32, r: f32) -> f32 {
    let rr = clamp(r, 0.001, 0.999);
    let a = (1.0 / rr - 2.0) * (1.0 - 2.0 * x);
    return select((a - x) / (a - 1.0), x / (a + 1.0), x < 0.5);
}

// The three lookups of a point: coordinates, barycentric weights and rotation angles.
struct mx_hextile_data {
    coord1: vec2<f32>,
    coord2: vec2<f32>,
    coord3: vec2<f32>,
    weights: vec3<f32>,
    rot: vec3<f32>,
}

fn mx_hextile_vertex(coord: vec2<f32>, id: vec2<i32>, rotation: f32, rotationrange: vec2<f32>, scale: f32, scalerange: vec2<f32>, offset: f32, offsetrange: vec2<f32>) -> vec3<f32> {
    // (coord.xy, angle) of the lookup for vertex `id`.
    let sqrt3_2 = sqrt(3.0) * 2.0;
    let inv_skewed = mat2x2<f32>(1.0, 0.0, 0.5, 1.0 / 1.15470054);
    let ctr = inv_skewed * (vec2<f32>(id) / vec2<f32>(sqrt3_2));
    let rnd = mx_hextile_hash(vec2<f32>(id) + vec2<f32>(0.12345));
    let rr = radians(rotationrange);
    let rv = mix(rr.x, rr.y, rnd.x * rotation);
    let s = sin(rv);
    let c = cos(rv);
    let rm = mat2x2<f32>(c, -s, s, c);
    let sc = vec2<f32>(mix(1.0, mix(scalerange.x, scalerange.y, rnd.y), scale));
    let off = mix(vec2<f32>(offsetrange.x), vec2<f32>(offsetrange.y), rnd * offset);
    let uv = ((coord - ctr) * rm) / sc + ctr + off;
    return vec3<f32>(uv, rv);
}

fn mx_hextile_coord(coord: vec2<f32>, rotation: f32, rotationrange: vec2<f32>, scale: f32, scalerange: vec2<f32>, offset: f32, offsetrange: vec2<f32>) -> mx_hextile_data {
    let sqrt3_2 = sqrt(3.0) * 2.0;
    let st = coord * sqrt3_2;
    let to_skewed = mat2x2<f32>(1.0, 0.0, -0.57735027, 1.15470054);
    let st_skewed = to_skewed * st;
    let st_frac = fract(st_skewed);
    let tz = 1.0 - st_frac.x - st_frac.y;
    let s = step(0.0, -tz);
    let s2 = 2.0 * s - 1.0;
    let w = vec3<f32>(-tz * s2, s - st_frac.y * s2, s - st_frac.x * s2);
    let base_id = vec2<i32>(floor(st_skewed));
    let si = i32(s);
    let v1 = mx_hextile_vertex(coord, base_id + vec2<i32>(si, si), rotation, rotationrange, scale, scalerange, offset, offsetrange);
    let v2 = mx_hextile_vertex(coord, base_id + vec2<i32>(si, 1 - si), rotation, rotationrange, scale, scalerange, offset, offsetrange);
    let v3 = mx_hextile_vertex(coord, base_id + vec2<i32>(1 - si, si), rotation, rotationrange, scale, scalerange, offset, offsetrange);
    return mx_hextile_data(v1.xy, v2.xy, v3.xy, w, vec3<f32>(v1.z, v2.z, v3.z));
}

// Blend weights: (cw ⊙ w^7) normalised, then the gain when falloff ≠ 0.5.
fn mx_hextile_blend_weights(weights: vec3<f32>, cw: vec3<f32>, falloff: f32) -> vec3<f32> {
    let w7 = weights * weights * weights * weights * weights * weights * weights;
    var w = cw * w7;
    w = w / (w.x + w.y + w.z);
    if (falloff != 0.5) {
        w = vec3<f32>(mx_schlick_gain(w.x, falloff), mx_schlick_gain(w.y, falloff), mx_schlick_gain(w.z, falloff));
        w = w / (w.x + w.y + w.z);
    }
    return w;
}

// ND_hextiledimage_color4 (alpha: the mean of the three, through the gain when falloff ≠ 0.5)
fn mx_hextiledimage_color4(file: texture_2d<f32>, default_: vec4<f32>, texcoord: vec2<f32>, tiling: vec2<f32>, rotation: f32, rotationrange: vec2<f32>, scale: f32, scalerange: vec2<f32>, offset: f32, offsetrange: vec2<f32>, falloff: f32, falloffcontrast: f32, lumacoeffs: vec3<f32>) -> vec4<f32> {
    let dims = textureDimensions(file);
    if (dims.x == 0u || dims.y == 0u) {
        return default_;
    }
    let t = mx_hextile_coord(texcoord * tiling, rotation, rotationrange, scale, scalerange, offset, offsetrange);
    let c1 = mx_image_sample(file, default_, t.coord1, 2, 2, 1);
    let c2 = mx_image_sample(file, default_, t.coord2, 2, 2, 1);
    let c3 = mx_image_sample(file, default_, t.coord3, 2, 2, 1);
    let cw = mix(vec3<f32>(1.0), vec3<f32>(dot(c1.rgb, lumacoeffs), dot(c2.rgb, lumacoeffs), dot(c3.rgb, lumacoeffs)), vec3<f32>(falloffcontrast));
    let w = mx_hextile_blend_weights(t.weights, cw, falloff);
    let a = (c1.a + c2.a + c3.a) / 3.0;
    return vec4<f32>(w.x * c1.rgb + w.y * c2.rgb + w.z * c3.rgb, select(a, mx_schlick_gain(a, falloff), falloff != 0.5));
}

// ND_hextiledimage_color3
fn mx_hextiledimage_color3(file: texture_2d<f32>, default_: vec3<f32>, texcoord: vec2<f32>, tiling: vec2<f32>, rotation: f32, rotationrange: vec2<f32>, scale: f32, scalerange: vec2<f32>, offset: f32, offsetrange: vec2<f32>, falloff: f32, falloffcontrast: f32, lumacoeffs: vec3<f32>) -> vec3<f32> {
    return mx_hextiledimage_color4(file, vec4<f32>(default_, 1.0), texcoord, tiling, rotation, rotationrange, scale, scalerange, offset, offsetrange, falloff, falloffcontrast, lumacoeffs).rgb;
}

// Mikkelsen's surface-gradient blend of three normals around N (MaterialX's
// mx_gradient_blend_3_normals).
fn mx_hextile_normal_gradient(n: vec3<f32>, np: vec3<f32>) -> vec3<f32> {
    let d = dot(n, np);
    return (d * n - np) / max(1.0e-8, abs(d));
}

// ND_hextilednormalmap_vector3: each lookup decoded as a tangent-space normal map whose tangent
// frame is turned by the lookup's rotation about N, the three normals blended by their gradients.
fn mx_hextilednormalmap_vector3(file: texture_2d<f32>, default_: vec3<f32>, texcoord: vec2<f32>, tiling: vec2<f32>, rotation: f32, rotationrange: vec2<f32>, scale: f32, scalerange: vec2<f32>, offset: f32, offsetrange: vec2<f32>, falloff: f32, strength: f32, flip_g: bool, normal: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> vec3<f32> {
    let dims = textureDimensions(file);
    if (dims.x == 0u || dims.y == 0u) {
        return default_;
    }
    let t = mx_hextile_coord(texcoord * tiling, rotation, rotationrange, scale, scalerange, offset, offsetrange);
    let n = select(vec3<f32>(0.0, 0.0, 1.0), normal * inverseSqrt(max(dot(normal, normal), 1.0e-30)), dot(normal, normal) > 1.0e-30);
    var nm = array<vec3<f32>, 3>(
        mx_image_sample(file, vec4<f32>(default_, 1.0), t.coord1, 2, 2, 1).xyz,
        mx_image_sample(file, vec4<f32>(default_, 1.0), t.coord2, 2, 2, 1).xyz,
        mx_image_sample(file, vec4<f32>(default_, 1.0), t.coord3, 2, 2, 1).xyz);
    var g = vec3<f32>(0.0);
    let w = mx_hextile_blend_weights(t.weights, vec3<f32>(1.0), falloff);
    for (var k = 0; k < 3; k++) {
        var m = nm[k];
        m.y = select(m.y, 1.0 - m.y, flip_g);
        m = 2.0 * m - vec3<f32>(1.0);
        let r = mx_math_rotation_matrix(n, -t.rot[k]);
        let nk0 = (r * tangent) * strength * m.x + (r * bitangent) * strength * m.y + n * m.z;
        let nk = select(n, nk0 * inverseSqrt(max(dot(nk0, nk0), 1.0e-30)), dot(nk0, nk0) > 1.0e-30);
        g = g + clamp(w[k], 0.0, 1.0) * mx_hextile_normal_gradient(n, nk);
    }
    let b = n - g;
    return select(n, b * inverseSqrt(max(dot(b, b), 1.0e-30)), dot(b, b) > 1.0e-30);
}
