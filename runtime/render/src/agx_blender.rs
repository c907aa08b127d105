//! Blender's AgX view transform ("AgX Base", Blender 4) in closed form, to 8-bit sRGB: the
//! display transform of `uplift export`'s shaded frames, so that they match what the paper's
//! data pipeline rendered in Blender.
//!
//! The chain of EaryChow's AgX_LUT_Gen (`AgXBaseRec2020.py`, the generator of Blender's LUT),
//! evaluated per pixel instead of through a 3D LUT:
//! 1. linear Rec. 709 → linear Rec. 2020 (negative values clamped to 0);
//! 2. Blender's inset matrix (primaries rotated by [2.140, −1.228, −3.052]° and scaled by
//!    [0.330, 0.281, 0.125] towards white, in Rec. 2020; rows sum to 1: greys stay grey);
//! 3. log2 encoding, −10 to +6.5 stops around mid grey 0.18, clamped to [0, 1];
//! 4. Troy Sobotka's AgX sigmoid (Jed Smith's tunable sigmoid): fulcrum (10/16.5, 0.18^(1/2.4)),
//!    slope 2.4, toe and shoulder powers 1.5, limits (0, 0) and (1, 1);
//! 5. power 2.4 (the curve's output is display-encoded in that power), Blender's outset matrix
//!    (scales [0.323, 0.283, 0.037], no rotation), linear Rec. 2020 → linear Rec. 709;
//! 6. clamped to [0, 1] and encoded with the sRGB transfer function (Blender's "sRGB" display).
//!
//! Not modelled: the generator's lower guard rail (a gamut compensation for negative
//! Rec. 2020 values) and its 40 % hue-angle restoration; with them Blender's LUT differs from
//! this closed form on saturated colours, not on greys. Mid grey 0.18 maps to 0.18 before the
//! display encoding, 0.4614 after (118 of 255), as in Blender.

/// Linear Rec. 709 → linear Rec. 2020 (rows: output channel).
const REC709_TO_REC2020: [[f64; 3]; 3] = [
    [0.627_403_895_934_698_9, 0.329_283_038_377_883_7, 0.043_313_065_687_417_3],
    [0.069_097_289_358_232_1, 0.919_540_395_075_458_5, 0.011_362_315_566_309_17],
    [0.016_391_438_875_150_23, 0.088_013_307_877_225_75, 0.895_595_253_247_623_9],
];

/// Linear Rec. 2020 → linear Rec. 709.
const REC2020_TO_REC709: [[f64; 3]; 3] = [
    [1.660_491_002_108_435, -0.587_641_138_788_549_8, -0.072_849_863_319_885_04],
    [-0.124_550_474_521_590_88, 1.132_899_897_125_960_5, -0.008_349_422_604_369_46],
    [-0.018_150_763_354_905_21, -0.100_578_898_008_007_43, 1.118_729_661_362_912_7],
];

/// Blender's AgX inset matrix (in Rec. 2020).
pub const INSET: [[f64; 3]; 3] = [
    [0.856_627_156_288_779_2, 0.095_121_245_402_534_9, 0.048_251_598_308_685_8],
    [0.137_318_972_283_551_67, 0.761_241_987_009_080_6, 0.101_439_040_707_367_48],
    [0.111_898_208_045_179_53, 0.076_799_414_562_517_57, 0.811_302_377_392_303],
];

/// Blender's AgX outset matrix (in Rec. 2020).
pub const OUTSET: [[f64; 3]; 3] = [
    [1.127_100_569_630_12, -0.110_606_638_578_260_65, -0.016_493_931_051_859_02],
    [-0.141_329_754_421_353_37, 1.157_823_685_473_212_7, -0.016_493_931_051_859_03],
    [-0.141_329_754_421_353_26, -0.110_606_638_578_260_59, 1.251_936_392_999_614],
];

/// The log2 range in stops around mid grey.
pub const LOG2_MIN: f64 = -10.0;
pub const LOG2_MAX: f64 = 6.5;
pub const MID_GREY: f64 = 0.18;
/// The sigmoid's slope at the fulcrum and its toe and shoulder powers.
pub const SLOPE: f64 = 2.4;
pub const POWER: f64 = 1.5;

fn mat(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// The tunable sigmoid's scale for a segment from the fulcrum to its limit, `dx` and `dy` away.
fn scale(dx: f64, dy: f64) -> f64 {
    ((SLOPE * dx).powf(-POWER) * ((SLOPE * dx / dy).powf(POWER) - 1.0)).powf(-1.0 / POWER)
}

/// AgX's sigmoid on the log-encoded value x ∈ [0, 1].
pub fn sigmoid(x: f64) -> f64 {
    let (xp, yp) = (-LOG2_MIN / (LOG2_MAX - LOG2_MIN), MID_GREY.powf(1.0 / 2.4));
    let s = if x >= xp { scale(1.0 - xp, 1.0 - yp) } else { -scale(xp, yp) };
    let t = SLOPE * (x - xp) / s;
    s * (t / (1.0 + t.powf(POWER)).powf(1.0 / POWER)) + yp
}

/// The sRGB transfer function (linear → encoded), on [0, 1].
pub fn srgb_encode(x: f64) -> f64 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear Rec. 709 scene radiance → sRGB-encoded display value in [0, 1].
pub fn agx_blender(rgb: [f32; 3]) -> [f32; 3] {
    let v = mat(&REC709_TO_REC2020, rgb.map(|x| if x.is_finite() { x.max(0.0) as f64 } else { 0.0 }));
    let v = mat(&INSET, v).map(|x| {
        let stops = x.max(1e-10).log2() - MID_GREY.log2();
        let encoded = ((stops - LOG2_MIN) / (LOG2_MAX - LOG2_MIN)).clamp(0.0, 1.0);
        sigmoid(encoded).max(0.0).powf(2.4)
    });
    mat(&REC2020_TO_REC709, mat(&OUTSET, v)).map(|x| srgb_encode(x.clamp(0.0, 1.0)) as f32)
}

/// An image (linear RGB) → 8-bit sRGB after `exposure` (a multiplier) and Blender's AgX.
pub fn to_display_blender(radiance: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    radiance.iter().flat_map(|p| agx_blender(p.map(|x| x * exposure)).map(|x| (x * 255.0 + 0.5) as u8)).collect()
}
