// microfacet.wgsl: the GGX microfacet core shared by dielectric_bsdf, conductor_bsdf and
// generalized_schlick_bsdf (local frame, normal +z): distribution, height-correlated Smith
// masking-shadowing, visible-normal sampling and its pdf, the Fresnel curves, and Turquin's
// energy compensation. Formulas: ../shared/design/materialx-notes.md §1.1.
//
// Smith's Λ uses the exact anisotropic form (the roughness projected on each direction); for
// isotropic roughness this is MaterialX's λ(μ) = √(α² + (1 − α²)μ²) exactly. Albedo tables are
// indexed by ᾱ = √(αx·αy), as MaterialX does.

// GGX alpha from a `roughness` input: clamped to [1e-8, 1] (NaN reads as 1e-8), as MaterialX.
fn mx_ggx_alpha(roughness: vec2<f32>) -> vec2<f32> {
    return clamp(roughness, vec2<f32>(1.0e-8), vec2<f32>(1.0));
}

// The distribution of normals D(h).
fn mx_ggx_d(h: vec3<f32>, a: vec2<f32>) -> f32 {
    let ia = 1.0 / (a.x * a.y);
    let hx = h.x * a.y * ia;
    let hy = h.y * a.x * ia;
    let t = hx * hx + hy * hy + h.z * h.z;
    return ia / (MX_PI * t * t);
}

// μ·(1 + 2Λ(w)) = √(μ² + αx²wx² + αy²wy²), the stable building block of Smith's G.
fn mx_ggx_smith_s(w: vec3<f32>, a: vec2<f32>) -> f32 {
    let mu = max(w.z, 1.0e-8);
    return sqrt(mu * mu + a.x * a.x * w.x * w.x + a.y * a.y * w.y * w.y);
}

// D·G2·μl / (4μv), i.e. f·cos θl for F = 1 (height-correlated G2); 0 below the horizon.
fn mx_ggx_reflection(v: vec3<f32>, l: vec3<f32>, h: vec3<f32>, a: vec2<f32>) -> f32 {
    let mv = max(v.z, 1.0e-8);
    let ml = max(l.z, 1.0e-8);
    let denom = 2.0 * (ml * mx_ggx_smith_s(v, a) + mv * mx_ggx_smith_s(l, a));
    return select(mx_ggx_d(h, a) * ml / denom, 0.0, l.z <= 0.0);
}

// The half vector of v and l (the normal when they cancel).
fn mx_half_vector(v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    return mx_normalize_or(v + l, vec3<f32>(0.0, 0.0, 1.0));
}

// Visible-normal sampling (Dupuy & Benyoub 2023, spherical caps) of a microfacet normal.
fn mx_ggx_sample_vndf(v: vec3<f32>, a: vec2<f32>, u: vec2<f32>) -> vec3<f32> {
    let vh = mx_normalize_or(vec3<f32>(a.x * v.x, a.y * v.y, max(v.z, 0.0)), vec3<f32>(0.0, 0.0, 1.0));
    let cs = mx_fast_cos_sin(2.0 * MX_PI * u.x);
    let z = (1.0 - u.y) * (1.0 + vh.z) - vh.z;
    let sin_t = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    let c = vec3<f32>(sin_t * cs.x, sin_t * cs.y, z);
    let hh = c + vh;
    return mx_normalize_or(vec3<f32>(a.x * hh.x, a.y * hh.y, max(hh.z, 0.0)), vec3<f32>(0.0, 0.0, 1.0));
}

// The pdf of wl = reflect(−v, h) under visible-normal sampling: G1(v)·D(h) / (4μv).
fn mx_ggx_pdf(v: vec3<f32>, h: vec3<f32>, a: vec2<f32>) -> f32 {
    let mv = max(v.z, 1.0e-8);
    let pdf = mx_ggx_d(h, a) / (2.0 * (mv + mx_ggx_smith_s(v, a)));
    return select(pdf, 0.0, (dot(v, h) <= 0.0) | (h.z <= 0.0));
}

fn mx_reflect_about(v: vec3<f32>, h: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(v, h) * h - v;
}

// Exact unpolarised dielectric Fresnel (Lagarde form); 1 under total internal reflection.
// `eta` ≤ 0 disables the curve (F = 1), as MaterialX's `ior = 0`.
fn mx_fresnel_dielectric(cos_theta: f32, eta: f32) -> f32 {
    let c = clamp(cos_theta, 0.0, 1.0);
    let g2 = eta * eta + c * c - 1.0;
    let g = sqrt(max(g2, 0.0));
    let gpc = g + c;
    let gmc = g - c;
    let x = gmc / max(gpc, 1.0e-30);
    let y = (c * gpc - 1.0) / max(c * gmc + 1.0, 1.0e-30);
    return select(0.5 * x * x * (1.0 + y * y), 1.0, (eta <= 0.0) | (g2 < 0.0));
}

// Exact conductor Fresnel for complex IOR n + ik per channel (average of s and p).
fn mx_fresnel_conductor(cos_theta: f32, n: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c = clamp(cos_theta, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let n2 = n * n;
    let k2 = k * k;
    let t0 = n2 - k2 - vec3<f32>(s2);
    let a2b2 = sqrt(t0 * t0 + 4.0 * n2 * k2);
    let t1 = a2b2 + vec3<f32>(c2);
    let a = sqrt(max(0.5 * (a2b2 + t0), vec3<f32>(0.0)));
    let t2 = 2.0 * c * a;
    let t3 = c2 * a2b2 + vec3<f32>(s2 * s2);
    let t4 = t2 * s2;
    // rs = (t1 − t2)/(t1 + t2), rp = rs·(t3 − t4)/(t3 + t4); ½(rs + rp) with one division.
    let b = max(t1 + t2, vec3<f32>(1.0e-30));
    let d = max(t3 + t4, vec3<f32>(1.0e-30));
    return 0.5 * (t1 - t2) * (d + t3 - t4) / (b * d);
}

// mx_fresnel_conductor(1, n, k) in closed form: ((n − 1)² + k²) / ((n + 1)² + k²).
fn mx_fresnel_conductor_normal(n: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let k2 = k * k;
    return ((n - 1.0) * (n - 1.0) + k2) / max((n + 1.0) * (n + 1.0) + k2, vec3<f32>(1.0e-30));
}

// x^q for x in [0, 1] and q ≥ 0 without pow(0, ·) corner cases.
fn mx_pow_unit(x: f32, q: f32) -> f32 {
    return mx_fast_pow(x, q);
}

// Hoffman's generalized Schlick with the F82 multiplier (MaterialX mx_fresnel_hoffman_schlick).
fn mx_fresnel_schlick_f82(cos_theta: f32, r0: vec3<f32>, r82: vec3<f32>, r90: vec3<f32>, exponent: f32) -> vec3<f32> {
    let cbar = 1.0 / 7.0;
    let factor = 1.0 / (cbar * pow(1.0 - cbar, 6.0));
    let x = clamp(cos_theta, 0.0, 1.0);
    let q = max(exponent, 0.0);
    let a = mix(r0, r90, mx_pow_unit(1.0 - cbar, q)) * (vec3<f32>(1.0) - r82) * factor;
    let m = 1.0 - x;
    let m2 = m * m;
    return mix(r0, r90, mx_pow_unit(m, q)) - a * x * (m2 * m2 * m2);
}

// Turquin's multiple-scattering compensation 1 + F̄(1 − Ess)/Ess for average Fresnel `favg`.
fn mx_ggx_energy_compensation(mu: f32, abar: f32, favg: vec3<f32>) -> vec3<f32> {
    let ess = max(mx_albedo_ggx_ess(mu, abar), 1.0e-4);
    return vec3<f32>(1.0) + favg * ((1.0 - ess) / ess);
}

// MaterialX's average Fresnel F̄ = F(1) + (F90 − F(1)) / 21.
fn mx_fresnel_average(f_normal: vec3<f32>, f90: vec3<f32>) -> vec3<f32> {
    return f_normal + (f90 - f_normal) * (1.0 / 21.0);
}

// The GGX lobe's local view direction and alpha, as every microfacet node starts.
struct mx_ggx_setup {
    frame: mx_frame,
    v: vec3<f32>,
    a: vec2<f32>,
    abar: f32,
    mu: f32,
}

fn mx_ggx_setup_new(cl: mx_closure, roughness: vec2<f32>, retroreflective: bool, normal: vec3<f32>, tangent: vec3<f32>) -> mx_ggx_setup {
    let frame = mx_frame_new(normal, tangent, cl.wv);
    var v = mx_to_local(frame, cl.wv);
    if (retroreflective) {
        v = vec3<f32>(-v.x, -v.y, v.z);
    }
    let a = mx_ggx_alpha(roughness);
    // The tables' roughness is MaterialX's ᾱ = √(αx·αy): exact for isotropic lobes, an
    // approximation for anisotropic ones (measured in runtime/uplift/tests/integration/closures.rs).
    return mx_ggx_setup(frame, v, a, sqrt(a.x * a.y), clamp(v.z, 0.0, 1.0));
}
