// uplift_glint (ND_uplift_glint_bsdf) and uplift_glint_factor (ND_uplift_glint_factor_color3):
// the paper's glints (§5.3, Eq. 6), f_glint = f · N(λ, ωv, ωl, x), a sparkle pattern tied to the
// surface position x and energy-neutral: E_x[N] = 1 per RGB channel for any directions.
//
// The surface is cut into cubic cells of edge `size` (in position units); the half vector h,
// in the shading frame, falls into an angular bin of about `angle` radians (a grid on its
// stereographic projection, tan(θh/2)). A cell holds a flake facing the bin with probability p
// (a hash of cell, bin and seed): N = (1 − w) + w · [flake] · c / p, with w = `strength` and c
// the flake's colour, a hue on a rainbow 1 + spread·cos(2π(t − channel/3)) for a random phase t
// (each channel's mean 1: the stand-in for a wave-optics glint's spectral spread). p = `density` clustered by Perlin noise over the cells,
// p = density · (1 + 0.8·noise(cell centre / 16 cells)); dividing by the same p keeps
// E[N | cell] = 1, so clusters move where sparkles appear, never the mean. The albedo context is unchanged (the
// expected reflectance); eval and pdf multiply the response; sampling ignores N (unbiased).

// PCG's output permutation of a 32-bit state.
fn uplift_glint_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn uplift_glint_unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// N for the half vector of (wv, wl) in the frame of (normal, tangent) at `position`.
fn uplift_glint_factor(density: f32, size: f32, angle: f32, spread: f32, strength: f32, seed: f32, position: vec3<f32>, normal: vec3<f32>, tangent: vec3<f32>, wv: vec3<f32>, wl: vec3<f32>) -> vec3<f32> {
    let f = mx_frame_new(normal, tangent, wv);
    let h = mx_normalize_or(mx_to_local(f, wv) + mx_to_local(f, wl), vec3<f32>(0.0, 0.0, 1.0));
    let d = h.xy / (1.0 + max(h.z, 0.0));
    let bin = vec2<i32>(floor(d * (2.0 / max(angle, 1.0e-4))));
    let cell_size = max(size, 1.0e-6);
    let cell = vec3<i32>(floor(position / cell_size));
    var k = uplift_glint_hash(bitcast<u32>(seed));
    k = uplift_glint_hash(k ^ bitcast<u32>(bin.x));
    k = uplift_glint_hash(k ^ bitcast<u32>(bin.y));
    k = uplift_glint_hash(k ^ bitcast<u32>(cell.x));
    k = uplift_glint_hash(k ^ bitcast<u32>(cell.y));
    k = uplift_glint_hash(k ^ bitcast<u32>(cell.z));
    // The cluster noise at the cell's centre: one flake, one brightness.
    let cluster = mx_perlin_noise_float_3d((vec3<f32>(cell) + vec3<f32>(0.5)) / 16.0);
    let p = clamp(density * (1.0 + 0.8 * clamp(cluster, -1.0, 1.0)), 1.0e-4, 1.0);
    let on = select(0.0, 1.0, uplift_glint_unit(k) < p);
    // The flake's colour: one random phase t (its "wavelength") drives the three channels
    // through a rainbow, c = 1 + spread·cos(2π(t − channel/3)); over uniform t each channel's
    // mean is exactly 1, and a flake is one saturated hue, as a diffraction sparkle is.
    let t = uplift_glint_unit(uplift_glint_hash(k + 1u));
    let s = clamp(spread, 0.0, 1.0);
    let c = vec3<f32>(1.0) + s * cos(6.283185307179586 * (vec3<f32>(t) - vec3<f32>(0.0, 1.0 / 3.0, 2.0 / 3.0)));
    let w = clamp(strength, 0.0, 1.0);
    return vec3<f32>(1.0 - w) + (w * on / p) * c;
}

// ND_uplift_glint_factor_color3: N as a pattern value (the renderer multiplies the reference
// stack's and the neural material's response by it).
fn mx_uplift_glint_factor_color3(density: f32, size: f32, angle: f32, spread: f32, strength: f32, seed: f32, position: vec3<f32>, normal: vec3<f32>, tangent: vec3<f32>, wv: vec3<f32>, wl: vec3<f32>) -> vec3<f32> {
    return uplift_glint_factor(density, size, angle, spread, strength, seed, position, normal, tangent, wv, wl);
}

// ND_uplift_glint_bsdf: `in` with its response multiplied by N where a response is evaluated
// (eval, and the pdf pass of sample and pdf); albedo, throughput and sampling unchanged.
fn mx_uplift_glint_bsdf(cl: mx_closure, in: BSDF, density: f32, size: f32, angle: f32, spread: f32, strength: f32, seed: f32, position: vec3<f32>, normal: vec3<f32>, tangent: vec3<f32>) -> BSDF {
    if (cl.context == MX_CONTEXT_EVAL || cl.context == MX_CONTEXT_PDF) {
        let n = uplift_glint_factor(density, size, angle, spread, strength, seed, position, normal, tangent, cl.wv, cl.wl);
        return BSDF(in.response * n, in.throughput, in.lobe);
    }
    return in;
}
