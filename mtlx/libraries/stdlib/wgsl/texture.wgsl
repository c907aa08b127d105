// texture.wgsl: the stdlib `image` node (float, color3, color4, vector2, vector3, vector4).
//
// Kernels are compute shaders, so sampling is done by hand with textureLoad/textureDimensions
// (what GL/Vulkan samplers do in MaterialX's GLSL renderer):
// * UV origin is the image's lower-left corner; texel row 0 of the texture is the image's TOP
//   row, so v maps to row (1 - v) * height (MaterialX GLSL with fileTextureVerticalFlip).
// * uaddressmode / vaddressmode (enum constant,clamp,periodic,mirror → 0,1,2,3), applied to
//   texel indices: clamp = clamp to edge, periodic = repeat, mirror = mirrored repeat,
//   constant = `default` for a coordinate outside [0,1] (inside it, the edge texels are
//   clamped; GL's clamp-to-border would instead blend with the border colour within half a
//   texel of the edge). Unknown values behave as periodic, the nodedef's default.
// * filtertype (enum closest,linear,cubic → 0,1,2): closest = nearest texel; linear = bilinear
//   between texel centres at (i + 0.5) / size; cubic is treated as linear (MaterialX's GL
//   renderer has no bicubic path either: "cubic" only selects a linear/mipmapped GL filter).
//   No mipmapping: kernels have no derivatives to choose a level, level 0 is always read.
//   (MaterialX's GL renderer always magnifies with GL_LINEAR, even for "closest"; here
//   closest is nearest-texel in both directions, as the spec means.)
// * frameoffset / frameendaction (image sequences) are accepted and ignored: the kernel is bound
//   to one image. `layer` and `framerange` are strings without enum and are not passed.
// * Channels: float = .r, vector2 = .rg, color3/vector3 = .rgb, color4/vector4 = .rgba. The
//   texture's missing channels read as the GPU convention (0, 0, 0, 1), as the spec requires.
// * An empty (0-sized) texture returns `default`.

// Address mode on an integer texel index `i` for an axis of `n` texels.
fn mx_image_address(i: i32, n: i32, mode: i32) -> i32 {
    if (mode == 0 || mode == 1) {
        // constant (inside [0,1]) and clamp: clamp to edge
        return clamp(i, 0, n - 1);
    }
    if (mode == 3) {
        // mirror: period 2n, second half reflected
        let period = 2 * n;
        var m = ((i % period) + period) % period;
        if (m >= n) {
            m = period - 1 - m;
        }
        return m;
    }
    // periodic
    return ((i % n) + n) % n;
}

fn mx_image_texel(file: texture_2d<f32>, ix: i32, iy: i32, size: vec2<i32>, uaddressmode: i32, vaddressmode: i32) -> vec4<f32> {
    let x = mx_image_address(ix, size.x, uaddressmode);
    let y = mx_image_address(iy, size.y, vaddressmode);
    return textureLoad(file, vec2<i32>(x, y), 0);
}

// All four channels of the image at `texcoord`; `default_` already widened to vec4.
fn mx_image_sample(file: texture_2d<f32>, default_: vec4<f32>, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32) -> vec4<f32> {
    let dims = textureDimensions(file);
    if (dims.x == 0u || dims.y == 0u) {
        return default_;
    }
    if (uaddressmode == 0 && !(texcoord.x >= 0.0 && texcoord.x <= 1.0)) {
        return default_;
    }
    if (vaddressmode == 0 && !(texcoord.y >= 0.0 && texcoord.y <= 1.0)) {
        return default_;
    }
    let size = vec2<i32>(dims);
    // Texel space: x to the right, y down from the top row.
    let st = vec2<f32>(texcoord.x, 1.0 - texcoord.y) * vec2<f32>(size);
    if (filtertype == 0) {
        let i = vec2<i32>(floor(st));
        return mx_image_texel(file, i.x, i.y, size, uaddressmode, vaddressmode);
    }
    // linear (and cubic): bilinear between the four nearest texel centres.
    let t = st - vec2<f32>(0.5);
    let t0 = floor(t);
    let fr = t - t0;
    let i0 = vec2<i32>(t0);
    let c00 = mx_image_texel(file, i0.x,     i0.y,     size, uaddressmode, vaddressmode);
    let c10 = mx_image_texel(file, i0.x + 1, i0.y,     size, uaddressmode, vaddressmode);
    let c01 = mx_image_texel(file, i0.x,     i0.y + 1, size, uaddressmode, vaddressmode);
    let c11 = mx_image_texel(file, i0.x + 1, i0.y + 1, size, uaddressmode, vaddressmode);
    return mix(mix(c00, c10, vec4<f32>(fr.x)), mix(c01, c11, vec4<f32>(fr.x)), vec4<f32>(fr.y));
}

fn mx_image_float(file: texture_2d<f32>, default_: f32, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32, frameoffset: i32, frameendaction: i32) -> f32 {
    return mx_image_sample(file, vec4<f32>(default_, 0.0, 0.0, 0.0), texcoord, uaddressmode, vaddressmode, filtertype).r;
}

fn mx_image_color3(file: texture_2d<f32>, default_: vec3<f32>, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32, frameoffset: i32, frameendaction: i32) -> vec3<f32> {
    return mx_image_sample(file, vec4<f32>(default_, 0.0), texcoord, uaddressmode, vaddressmode, filtertype).rgb;
}

fn mx_image_color4(file: texture_2d<f32>, default_: vec4<f32>, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32, frameoffset: i32, frameendaction: i32) -> vec4<f32> {
    return mx_image_sample(file, default_, texcoord, uaddressmode, vaddressmode, filtertype);
}

fn mx_image_vector2(file: texture_2d<f32>, default_: vec2<f32>, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32, frameoffset: i32, frameendaction: i32) -> vec2<f32> {
    return mx_image_sample(file, vec4<f32>(default_, 0.0, 0.0), texcoord, uaddressmode, vaddressmode, filtertype).rg;
}

fn mx_image_vector3(file: texture_2d<f32>, default_: vec3<f32>, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32, frameoffset: i32, frameendaction: i32) -> vec3<f32> {
    return mx_image_sample(file, vec4<f32>(default_, 0.0), texcoord, uaddressmode, vaddressmode, filtertype).rgb;
}

fn mx_image_vector4(file: texture_2d<f32>, default_: vec4<f32>, texcoord: vec2<f32>, uaddressmode: i32, vaddressmode: i32, filtertype: i32, frameoffset: i32, frameendaction: i32) -> vec4<f32> {
    return mx_image_sample(file, default_, texcoord, uaddressmode, vaddressmode, filtertype);
}
