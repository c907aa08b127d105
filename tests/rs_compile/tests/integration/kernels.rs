//! Runs generated Rust kernels (snapshots in tests/out/rs) through `mx_pattern_batch` and checks
//! them against closed forms computed here; and runs every snapshot kernel once.

use glam::{Vec2, Vec3};
use uplift_engines::batch::Geometry;
use uplift_rs_snapshots::{Checker, Rng, KERNELS};

/// A geometry row (the runtime's `Geometry::row`): texcoord, then position, normal and tangent
/// in object and world space.
fn geometry_row(uv: Vec2, p: Vec3, n: Vec3, t: Vec3) -> Vec<f32> {
    Geometry { texcoord: uv.into(), position: p.into(), normal: n.into(), tangent: t.into() }.row().to_vec()
}

/// A vector with components uniform in [-2, 2).
fn vec3(rng: &mut Rng) -> Vec3 {
    Vec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0))
}

#[test]
fn math_float_ops_matches_its_closed_form() {
    use uplift_rs_snapshots::math_float_ops as k;
    let us: Vec<f32> = (0..200).map(|i| -1.3 + i as f32 * 0.0173).collect();
    let geom: Vec<f32> = us.iter().flat_map(|&u| geometry_row(Vec2::new(u, 0.5), Vec3::ZERO, Vec3::Z, Vec3::X)).collect();
    let mut out = vec![0.0; us.len() * k::OUTPUT_COLUMNS];
    uplift_rs_snapshots::batch_rows!(k, &geom, &[], &mut out, &Checker { present: 0 });
    for (i, &u) in us.iter().enumerate() {
        let m = (u + 0.25 - 0.125) * 3.0;
        let d = m / 2.0;
        let md = d - 0.75 * (d / 0.75).floor();
        let expected = md.powf(2.2).sqrt().abs().clamp(0.1, 0.9);
        assert_eq!(out[2 * i], expected, "result at u = {u}");
        assert_eq!(out[2 * i + 1], m.floor(), "floored at u = {u}");
    }
}

#[test]
fn math_vector_ops_matches_glam() {
    use uplift_rs_snapshots::math_vector_ops as k;
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    // The geometry nodes normalize their vectors: use unit vectors.
    let rows: Vec<(Vec3, Vec3)> = (0..100).map(|_| (vec3(&mut rng).normalize(), vec3(&mut rng).normalize())).collect();
    let geom: Vec<f32> = rows.iter().flat_map(|&(n, t)| geometry_row(Vec2::ZERO, Vec3::ONE, n, t)).collect();
    let mut out = vec![0.0; rows.len() * k::OUTPUT_COLUMNS];
    uplift_rs_snapshots::batch_rows!(k, &geom, &[], &mut out, &Checker { present: 0 });
    assert_eq!(k::OUTPUTS, &[("ndotl_out", 0, 1), ("len_out", 1, 1), ("dist_out", 2, 1)]);
    for (i, &(n, t)) in rows.iter().enumerate() {
        let nn = n / n.length();
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-6 * (1.0 + b.abs());
        // tests/in/math_vector_ops.mtlx's literal, not 1/√2.
        #[allow(clippy::approx_constant)]
        let in2 = Vec3::new(0.0, 0.7071, 0.7071);
        assert!(close(out[3 * i], nn.dot(in2)), "ndotl row {i}");
        assert!(close(out[3 * i + 1], nn.cross(t).length()), "len row {i}");
        assert!(close(out[3 * i + 2], (n - t).length()), "dist row {i}");
    }
}

#[test]
fn math_integer_is_constant() {
    use uplift_rs_snapshots::math_integer as k;
    let geom = geometry_row(Vec2::ZERO, Vec3::ZERO, Vec3::Z, Vec3::X).repeat(3);
    let mut out = vec![0.0; 3 * k::OUTPUT_COLUMNS];
    uplift_rs_snapshots::batch_rows!(k, &geom, &[], &mut out, &Checker { present: 0 });
    assert_eq!(out, [-11.0, -11.0].repeat(3));
}

#[test]
fn struct_uniform_inputs_reads_its_input_rows() {
    use uplift_rs_snapshots::struct_uniform_inputs as k;
    assert_eq!(k::INPUTS, &[("levels", 0, 1), ("value", 1, 1)]);
    let rows = [(3.0f32, 0.6f32), (5.0, 0.33), (2.0, 0.99), (4.0, -0.3)];
    let inputs: Vec<f32> = rows.iter().flat_map(|&(l, v)| [l, v]).collect();
    let geom = geometry_row(Vec2::ZERO, Vec3::ZERO, Vec3::Z, Vec3::X).repeat(rows.len());
    let mut out = vec![0.0; rows.len() * k::OUTPUT_COLUMNS];
    uplift_rs_snapshots::batch_rows!(k, &geom, &inputs, &mut out, &Checker { present: 0 });
    for (i, &(levels, value)) in rows.iter().enumerate() {
        assert_eq!(out[2 * i], (value * levels).floor() / levels);
        assert_eq!(out[2 * i + 1], (value * 4.0).floor() / 4.0);
    }
}

#[test]
fn tex_image_addresses_and_filters_through_the_texture_trait() {
    use uplift_rs_snapshots::tex_image as k;
    assert_eq!(k::TEXTURE_COUNT, 2);
    let uvs = [Vec2::new(0.3, 0.2), Vec2::new(1.5, -0.3), Vec2::new(0.5, 0.5)];
    let geom: Vec<f32> = uvs.iter().flat_map(|&uv| geometry_row(uv, Vec3::ZERO, Vec3::Z, Vec3::X)).collect();
    let mut out = vec![0.0; uvs.len() * k::OUTPUT_COLUMNS];
    uplift_rs_snapshots::batch_rows!(k, &geom, &[], &mut out, &Checker { present: 2 });
    // Texture 0 (4 × 2): color3, u clamped, v mirrored, closest texel; texel (x, y) = (x, y, 0).
    // (0.3, 0.2) → st (1.2, 1.6) → texel (1, 1).
    assert_eq!(&out[0..3], &[1.0, 1.0, 0.0]);
    // (1.5, -0.3) → st (6.0, 2.6) → x clamped to 3, y = 2 mirrored to 1.
    assert_eq!(&out[4..7], &[3.0, 1.0, 0.0]);
    // Texture 1 (5 × 2): float, periodic, linear: (0.5, 0.5) → st (2.5, 1.0) → texels x = 2
    // and 3 with weight 0 on x = 3 → 2.
    assert_eq!(out[11], 2.0);
    // Missing textures give the defaults: color (1, 0, 1), alpha 0.
    uplift_rs_snapshots::batch_rows!(k, &geom, &[], &mut out, &Checker { present: 0 });
    assert_eq!(&out[0..4], &[1.0, 0.0, 1.0, 0.0]);
}

#[test]
fn every_snapshot_kernel_runs_and_writes_every_output() {
    assert!(KERNELS.len() >= 45, "only {} kernels compiled", KERNELS.len());
    let mut rng = Rng(12345);
    let n = 64;
    let geom: Vec<f32> = (0..n)
        .flat_map(|_| {
            let uv = Vec2::new(rng.range(-0.5, 1.5), rng.range(-0.5, 1.5));
            geometry_row(uv, vec3(&mut rng), vec3(&mut rng), vec3(&mut rng))
        })
        .collect();
    for k in KERNELS {
        let inputs: Vec<f32> = (0..n * k.input_stride).map(|_| rng.range(-1.0, 2.0)).collect();
        for present in [0, 8] {
            let sentinel = -123456.78f32;
            let mut out = vec![sentinel; n * k.output_stride];
            (k.batch)(&geom, &inputs, &mut out, &Checker { present });
            assert!(out.iter().all(|v| v.to_bits() != sentinel.to_bits()), "{}: an output was not written", k.name);
        }
    }
}

#[test]
#[should_panic(expected = "mx_pattern_batch: columns of different lengths")]
fn short_geometry_column_is_an_error() {
    use uplift_rs_snapshots::math_float_ops as k;
    let long = [0.0f32; 2];
    let mut geom: Vec<&[f32]> = vec![&long; k::GEOMETRY_COLUMNS];
    geom[7] = &long[..1];
    let (mut a, mut b) = ([0.0f32; 2], [0.0f32; 2]);
    let mut out: Vec<&mut [f32]> = vec![&mut a, &mut b];
    assert_eq!(out.len(), k::OUTPUT_COLUMNS);
    k::mx_pattern_batch(&geom, &[], &mut out, &Checker { present: 0 });
}

#[test]
#[should_panic(expected = "mx_pattern_batch: expected 20 geometry, 0 input and 2 output columns")]
fn wrong_column_count_is_an_error() {
    use uplift_rs_snapshots::math_float_ops as k;
    let long = [0.0f32; 2];
    let geom: Vec<&[f32]> = vec![&long; 3];
    let (mut a, mut b) = ([0.0f32; 2], [0.0f32; 2]);
    let mut out: Vec<&mut [f32]> = vec![&mut a, &mut b];
    k::mx_pattern_batch(&geom, &[], &mut out, &Checker { present: 0 });
}
