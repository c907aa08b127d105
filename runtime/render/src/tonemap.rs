//! Display transform: exposure, then AgX (Troy Sobotka's "AgX" base, the view transform
//! Blender ships and the paper's dataset renders use), to 8-bit display values.
//!
//! AgX here is the widely used closed form of its base look: the linear Rec. 709 input goes
//! through AgX's inset matrix, to log2 clamped to [−12.47, +4.03] (mid grey 0.18 sits at −2.47,
//! so 10 stops below and 6.5 above it) and normalised to [0, 1], through a 6th-order polynomial fit of the AgX default contrast
//! sigmoid (Benjamin Wrensch, 2023), and back through the outset matrix. The curve's output is
//! already display-encoded (it bakes the 2.2 display EOTF's inverse), so it is quantised as is.

/// AgX inset matrix (rows: output channel).
const INSET: [[f32; 3]; 3] = [
    [0.842_479_06, 0.078_433_6, 0.079_223_745],
    [0.042_328_242, 0.878_468_64, 0.079_166_13],
    [0.042_375_655, 0.078_433_6, 0.879_142_97],
];

/// AgX outset matrix (the inverse of the inset one; rows: output channel).
const OUTSET: [[f32; 3]; 3] = [
    [1.196_879, -0.098_020_88, -0.099_029_74],
    [-0.052_896_85, 1.151_903_1, -0.098_961_18],
    [-0.052_971_635, -0.098_043_45, 1.151_073_6],
];

const MIN_EV: f32 = -12.473_93;
const MAX_EV: f32 = 4.026_069;

fn mat(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// The AgX default-contrast sigmoid on [0, 1] (polynomial fit).
fn contrast(x: f32) -> f32 {
    let x2 = x * x;
    let x4 = x2 * x2;
    15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.00232
}

/// Linear Rec. 709 scene radiance → display value in [0, 1].
pub fn agx(rgb: [f32; 3]) -> [f32; 3] {
    let v = mat(&INSET, rgb.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 }));
    let v = v.map(|x| {
        let ev = if x > 0.0 { x.log2().clamp(MIN_EV, MAX_EV) } else { MIN_EV };
        contrast((ev - MIN_EV) / (MAX_EV - MIN_EV))
    });
    mat(&OUTSET, v).map(|x| x.clamp(0.0, 1.0))
}

/// An image (linear RGB) → 8-bit display RGB after `exposure` (a multiplier) and AgX.
pub fn to_display(radiance: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    let mut out = Vec::with_capacity(radiance.len() * 3);
    for p in radiance {
        let d = agx(p.map(|x| x * exposure));
        out.extend(d.map(|x| (x * 255.0 + 0.5) as u8));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outset_inverts_inset() {
        for r in 0..3 {
            for c in 0..3 {
                let e: f32 = (0..3).map(|k| OUTSET[r][k] * INSET[k][c]).sum();
                assert!((e - if r == c { 1.0 } else { 0.0 }).abs() < 1e-5, "({r}, {c}): {e}");
            }
        }
    }

    #[test]
    fn agx_is_monotone_neutral_and_bounded() {
        // Neutral stays neutral, black maps to ≈ 0, mid grey near the middle, monotone in
        // exposure, saturating below 1 at +4 EV.
        let grey = agx([0.18; 3]);
        assert!((grey[0] - grey[1]).abs() < 1e-4 && (grey[1] - grey[2]).abs() < 1e-4, "{grey:?}");
        assert!(grey[0] > 0.35 && grey[0] < 0.6, "mid grey → {}", grey[0]);
        assert!(agx([0.0; 3])[0] < 0.01);
        let mut last = -1.0;
        for k in -60..=60 {
            let y = agx([0.18 * 2f32.powf(k as f32 / 10.0); 3])[1];
            assert!(y >= last - 1e-6, "not monotone at {k}");
            last = y;
        }
        assert!(last > 0.9 && last <= 1.0, "{last}");
    }
}
