// blackbody.wgsl: ND_blackbody, the colour of a blackbody radiator at a temperature (K), as
// MaterialX computes it: the Planckian locus in CIE xy by Kim et al.'s cubic approximation
// (temperature clamped to its range, 1667–25000 K), Y = 1, converted to linear Rec.709 and
// clamped at 0.

// ND_blackbody
fn mx_blackbody(temperature: f32) -> vec3<f32> {
    let k = clamp(temperature, 1667.0, 25000.0);
    let t = 1000.0 / k;
    let t2 = t * t;
    let t3 = t2 * t;
    let xc = select(-3.0258469 * t3 + 2.1070379 * t2 + 0.2226347 * t + 0.240390, -0.2661239 * t3 - 0.2343580 * t2 + 0.8776956 * t + 0.179910, k < 4000.0);
    let x2 = xc * xc;
    let x3 = x2 * xc;
    let y_hot = 3.0817580 * x3 - 5.87338670 * x2 + 3.75112997 * xc - 0.37001483;
    let y_warm = -0.9549476 * x3 - 1.37418593 * x2 + 2.09137015 * xc - 0.16748867;
    let y_cool = -1.1063814 * x3 - 1.34811020 * x2 + 2.18555832 * xc - 0.20219683;
    let yc = select(select(y_hot, y_warm, k < 4000.0), y_cool, k < 2222.0);
    let xyz = vec3<f32>(xc / max(yc, 1.0e-6), 1.0, (1.0 - xc - yc) / max(yc, 1.0e-6));
    // XYZ to linear Rec.709.
    let rgb = xyz.x * vec3<f32>(3.2406, -0.9689, 0.0557) + xyz.y * vec3<f32>(-1.5372, 1.8758, -0.2040) + xyz.z * vec3<f32>(-0.4986, 0.0415, 1.0570);
    return select(max(rgb, vec3<f32>(0.0)), vec3<f32>(1.0), yc <= 0.0);
}
