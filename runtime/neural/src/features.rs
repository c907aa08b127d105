//! The decoder's direction features (lobes.md §4.1, variant B) and the directions the training
//! data is drawn at. The stack is isotropic, so the frame is rotated about the normal until the
//! view lies in the x–z plane (φv = 0) and the azimuth's sign is folded: ωv' = (sin θv, μv),
//! ωl' = (x, |y|, z), h' = (x, |y|, z), and c_d = ωv·h — 9 numbers. Directions are in the
//! local shading frame (normal +z).

/// Direction features per query.
pub const FEATURES: usize = 9;

/// The smallest view cosine the data holds (θv ≤ 87°).
pub const MIN_VIEW_COSINE: f32 = 0.052_335_96;

/// The features of the direction pair (wv, wl); both are unit vectors above the surface.
pub fn direction_features(wv: [f32; 3], wl: [f32; 3]) -> [f32; FEATURES] {
    let sin_v = (wv[0] * wv[0] + wv[1] * wv[1]).sqrt();
    let (c, s) = if sin_v > 1e-7 { (wv[0] / sin_v, wv[1] / sin_v) } else { (1.0, 0.0) };
    // Rotate by −φv about z.
    let rot = |d: [f32; 3]| [c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]];
    let l = rot(wl);
    let v = [sin_v, 0.0, wv[2]];
    let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt().max(1e-12);
    let h = [h[0] / len, h[1] / len, h[2] / len];
    let cd = v[0] * h[0] + v[2] * h[2];
    [sin_v, wv[2], l[0], l[1].abs(), l[2], h[0], h[1].abs(), h[2], cd]
}

/// A cosine-weighted direction from two uniforms, with θ ≤ 87°.
pub fn cosine_view(u1: f32, u2: f32) -> [f32; 3] {
    // μ² uniform on [μmin², 1].
    let m2 = MIN_VIEW_COSINE * MIN_VIEW_COSINE;
    let mu = (m2 + u1 * (1.0 - m2)).sqrt();
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u2;
    [s * phi.cos(), s * phi.sin(), mu]
}

/// A view with μ uniform in [μmin, 1] (θ ≤ 87°): more grazing views than `cosine_view`
/// (16 % below μ = 0.2 instead of 4 %).
pub fn uniform_cosine_view(u1: f32, u2: f32) -> [f32; 3] {
    let mu = MIN_VIEW_COSINE + u1 * (1.0 - MIN_VIEW_COSINE);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u2;
    [s * phi.cos(), s * phi.sin(), mu]
}

/// A cosine-weighted direction on the upper hemisphere (pdf μ/π).
pub fn cosine_hemisphere(u1: f32, u2: f32) -> [f32; 3] {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    [r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt()]
}

/// The view direction with cosine `mu` in the x–z plane (φv = 0).
pub fn view_direction(mu: f32) -> [f32; 3] {
    [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu]
}

/// `views` view cosines evenly spaced from 1 down to the smallest the data holds (the white
/// furnace's and the fit's energy bound's views).
pub fn view_cosines(views: usize) -> Vec<f32> {
    let views = views.max(1);
    (0..views).map(|k| if views == 1 { 1.0 } else { 1.0 - (1.0 - MIN_VIEW_COSINE) * k as f32 / (views - 1) as f32 }).collect()
}

/// A uniformly distributed direction on the upper hemisphere (μ > 0).
pub fn uniform_hemisphere(u1: f32, u2: f32) -> [f32; 3] {
    let mu = 1.0 - u1.clamp(0.0, 1.0 - 1e-7);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u2;
    [s * phi.cos(), s * phi.sin(), mu]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn norm(v: [f32; 3]) -> [f32; 3] {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    }

    #[test]
    fn features_are_invariant_under_rotation_and_mirroring() {
        let wv = norm([0.3, 0.4, 0.8]);
        let wl = norm([-0.5, 0.2, 0.6]);
        let f = direction_features(wv, wl);
        for angle in [0.3f32, 1.7, 4.0] {
            let (c, s) = (angle.cos(), angle.sin());
            let r = |d: [f32; 3]| [c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]];
            let g = direction_features(r(wv), r(wl));
            let m = |d: [f32; 3]| [d[0], -d[1], d[2]];
            let h = direction_features(m(r(wv)), m(r(wl)));
            for k in 0..FEATURES {
                assert!((f[k] - g[k]).abs() < 1e-5 && (f[k] - h[k]).abs() < 1e-5, "feature {k}: {f:?} {g:?} {h:?}");
            }
        }
        // c_d equals ωl·h too.
        let h = norm([wv[0] + wl[0], wv[1] + wl[1], wv[2] + wl[2]]);
        assert!((f[8] - (wl[0] * h[0] + wl[1] * h[1] + wl[2] * h[2])).abs() < 1e-5);
    }
}
