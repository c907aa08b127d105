// Adjustment nodes of the MaterialX standard library (nodegroup "adjustment") that are atomic:
// remap, smoothstep, luminance, rgbtohsv, hsvtorgb. (The others are nodegraphs.)
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl);
// the HSV conversions are MaterialX's mx_hsvtorgb/mx_rgbtohsv (Foley & van Dam, via OSL).

// MaterialX GLSL mx_hsvtorgb (lib/mx_hsv.glsl).
fn mx_adjustment_hsvtorgb(hsv: vec3<f32>) -> vec3<f32> {
    var h = hsv.x;
    let s = hsv.y;
    let v = hsv.z;
    if (s < 0.0001) {
        return vec3<f32>(v, v, v);
    }
    h = 6.0 * (h - floor(h)); // expand to [0..6)
    let hi = i32(trunc(h));
    let f = h - f32(hi);
    let p = v * (1.0 - s);
    let q = v * (1.0 - s * f);
    let t = v * (1.0 - s * (1.0 - f));
    if (hi == 0) {
        return vec3<f32>(v, t, p);
    } else if (hi == 1) {
        return vec3<f32>(q, v, p);
    } else if (hi == 2) {
        return vec3<f32>(p, v, t);
    } else if (hi == 3) {
        return vec3<f32>(p, q, v);
    } else if (hi == 4) {
        return vec3<f32>(t, p, v);
    }
    return vec3<f32>(v, p, q);
}

// MaterialX GLSL mx_rgbtohsv (lib/mx_hsv.glsl).
fn mx_adjustment_rgbtohsv(c: vec3<f32>) -> vec3<f32> {
    let r = c.x;
    let g = c.y;
    let b = c.z;
    let mincomp = min(r, min(g, b));
    let maxcomp = max(r, max(g, b));
    let delta = maxcomp - mincomp; // chroma
    let v = maxcomp;
    var s = 0.0;
    if (maxcomp > 0.0) {
        s = delta / maxcomp;
    }
    var h = 0.0;
    if (s > 0.0) {
        if (r >= maxcomp) {
            h = (g - b) / delta;
        } else if (g >= maxcomp) {
            h = 2.0 + (b - r) / delta;
        } else {
            h = 4.0 + (r - g) / delta;
        }
        h = h * (1.0 / 6.0);
        if (h < 0.0) {
            h = h + 1.0;
        }
    }
    return vec3<f32>(h, s, v);
}

// ---- remap ----

fn mx_remap_float(in: f32, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> f32 {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_color3(in: vec3<f32>, inlow: vec3<f32>, inhigh: vec3<f32>, outlow: vec3<f32>, outhigh: vec3<f32>) -> vec3<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_color4(in: vec4<f32>, inlow: vec4<f32>, inhigh: vec4<f32>, outlow: vec4<f32>, outhigh: vec4<f32>) -> vec4<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_vector2(in: vec2<f32>, inlow: vec2<f32>, inhigh: vec2<f32>, outlow: vec2<f32>, outhigh: vec2<f32>) -> vec2<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_vector3(in: vec3<f32>, inlow: vec3<f32>, inhigh: vec3<f32>, outlow: vec3<f32>, outhigh: vec3<f32>) -> vec3<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_vector4(in: vec4<f32>, inlow: vec4<f32>, inhigh: vec4<f32>, outlow: vec4<f32>, outhigh: vec4<f32>) -> vec4<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_color3FA(in: vec3<f32>, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> vec3<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_color4FA(in: vec4<f32>, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> vec4<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_vector2FA(in: vec2<f32>, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> vec2<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_vector3FA(in: vec3<f32>, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> vec3<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

fn mx_remap_vector4FA(in: vec4<f32>, inlow: f32, inhigh: f32, outlow: f32, outhigh: f32) -> vec4<f32> {
    return outlow + (in - inlow) * (outhigh - outlow) / (inhigh - inlow);
}

// ---- smoothstep ----

fn mx_smoothstep_float(in: f32, low: f32, high: f32) -> f32 {
    if (in <= low) {
        return 0.0;
    }
    if (in >= high) {
        return 1.0;
    }
    return smoothstep(low, high, in);
}

// ---- luminance ----

fn mx_luminance_color3(in: vec3<f32>, lumacoeffs: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(in, lumacoeffs));
}

fn mx_luminance_color4(in: vec4<f32>, lumacoeffs: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(vec3<f32>(dot(in.rgb, lumacoeffs)), in.a);
}

// ---- rgbtohsv ----

fn mx_rgbtohsv_color3(in: vec3<f32>) -> vec3<f32> {
    return mx_adjustment_rgbtohsv(in);
}

fn mx_rgbtohsv_color4(in: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(mx_adjustment_rgbtohsv(in.rgb), in.a);
}

// ---- hsvtorgb ----

fn mx_hsvtorgb_color3(in: vec3<f32>) -> vec3<f32> {
    return mx_adjustment_hsvtorgb(in);
}

fn mx_hsvtorgb_color4(in: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(mx_adjustment_hsvtorgb(in.rgb), in.a);
}
