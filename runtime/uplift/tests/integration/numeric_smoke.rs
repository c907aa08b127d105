//! The smallest end-to-end check: a nodegraph with interface inputs compiles, runs on wgpu, and
//! gives the closed-form results for 256 random rows.

use crate::common;
use common::*;
use uplift_engines::batch::Geometry;

#[test]
fn add_and_multiply_through_interface_inputs() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g">
        <input name="a" type="float" value="0"/><input name="c" type="color3" value="0,0,0"/>
        <add name="s" type="float"><input name="in1" type="float" interfacename="a"/><input name="in2" type="float" value="2"/></add>
        <multiply name="m" type="color3"><input name="in1" type="color3" interfacename="c"/><input name="in2" type="float" nodename="s"/></multiply>
        <position name="p" type="vector3"><input name="space" type="string" value="world"/></position>
        <output name="sum" type="float" nodename="s"/><output name="prod" type="color3" nodename="m"/><output name="pos" type="vector3" nodename="p"/>
        </nodegraph></materialx>"#,
    );
    let mut rng = Rng::new(1);
    let mut geom = Vec::new();
    let mut rows = Vec::new();
    for _ in 0..256 {
        geom.push(Geometry { position: [rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0)], ..Default::default() });
        rows.push((0..4).map(|_| rng.range(-10.0, 10.0)).collect::<Vec<f32>>());
    }
    let out = run(&k, &geom, &rows, vec![]);
    for ((o, r), g) in out.iter().zip(&rows).zip(&geom) {
        let s = r[0] + 2.0;
        assert_close("sum", &o[0..1], &[s], 1e-5);
        assert_close("prod", &o[1..4], &[r[1] * s, r[2] * s, r[3] * s], 1e-4);
        assert_close("pos", &o[4..7], &g.position, 0.0);
    }
}

/// The application nodes `time` and `frame` are the kernel's interface inputs `time` and
/// `frame` (one each, however many nodes read them), defaulting to their nodedefs' 0 and 1.
#[test]
fn time_and_frame_are_interface_inputs() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g">
        <time name="t" type="float"/><time name="t2" type="float"><input name="fps" type="float" value="30"/></time><frame name="f" type="float"/>
        <multiply name="m" type="float"><input name="in1" type="float" nodename="t"/><input name="in2" type="float" nodename="f"/></multiply>
        <add name="a" type="float"><input name="in1" type="float" nodename="m"/><input name="in2" type="float" nodename="t2"/></add>
        <output name="out" type="float" nodename="a"/>
        </nodegraph></materialx>"#,
    );
    let names: Vec<&str> = k.inputs.iter().map(|i| i.input.name.as_str()).collect();
    assert_eq!(
        names,
        ["time", "frame"],
        "one interface input per application node category"
    );
    assert_eq!(
        (
            k.inputs[0].input.default.as_slice(),
            k.inputs[1].input.default.as_slice()
        ),
        (&[0.0f32][..], &[1.0f32][..])
    );
    let rows = vec![vec![2.5f32, 4.0], vec![-1.0, 0.5], vec![0.0, 7.0]];
    let out = run(&k, &vec![Geometry::default(); rows.len()], &rows, vec![]);
    for (o, r) in out.iter().zip(&rows) {
        assert_close("time·frame + time", o, &[r[0] * r[1] + r[0]], 1e-6);
    }
}

/// nprlib's `facingratio` (a nodegraph over `viewdirection`, whose value is the kernel's
/// `viewdirection` input): |V·N| facing forward, 1 − |V·N| inverted, −V·N otherwise.
#[test]
fn facingratio_reads_the_viewdirection_input() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g">
        <facingratio name="f" type="float"/>
        <facingratio name="fi" type="float"><input name="invert" type="boolean" value="true"/></facingratio>
        <facingratio name="fb" type="float"><input name="faceforward" type="boolean" value="false"/></facingratio>
        <output name="f_out" type="float" nodename="f"/><output name="fi_out" type="float" nodename="fi"/><output name="fb_out" type="float" nodename="fb"/>
        </nodegraph></materialx>"#,
    );
    assert_eq!(
        k.inputs
            .iter()
            .map(|i| i.input.name.as_str())
            .collect::<Vec<_>>(),
        ["viewdirection"]
    );
    let mut rng = Rng::new(7);
    let unit = |rng: &mut Rng| {
        let v = [
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-3);
        v.map(|x| x / l)
    };
    let mut geom = Vec::new();
    let mut rows = Vec::new();
    for _ in 0..64 {
        geom.push(Geometry {
            normal: unit(&mut rng),
            ..Default::default()
        });
        rows.push(unit(&mut rng).to_vec());
    }
    let out = run(&k, &geom, &rows, vec![]);
    for ((o, v), g) in out.iter().zip(&rows).zip(&geom) {
        let d = v[0] * g.normal[0] + v[1] * g.normal[1] + v[2] * g.normal[2];
        assert_close("facingratio", o, &[d.abs(), 1.0 - d.abs(), -d], 1e-5);
    }
}

/// pbrlib's hair helpers against their closed forms (Chiang et al. 2016; d'Eon et al. 2011),
/// written here in f64 from the papers' equations.
#[test]
fn hair_helpers_match_their_closed_forms() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g">
        <input name="l" type="float" value="0.1"/><input name="a" type="float" value="0.2"/><input name="c" type="color3" value="0.5,0.5,0.5"/>
        <input name="mc" type="float" value="0.25"/><input name="mr" type="float" value="0.5"/>
        <chiang_hair_roughness name="r" type="multioutput"><input name="longitudinal" type="float" interfacename="l"/><input name="azimuthal" type="float" interfacename="a"/></chiang_hair_roughness>
        <chiang_hair_absorption_from_color name="ac" type="vector3"><input name="color" type="color3" interfacename="c"/><input name="azimuthal_roughness" type="float" interfacename="a"/></chiang_hair_absorption_from_color>
        <deon_hair_absorption_from_melanin name="am" type="vector3"><input name="melanin_concentration" type="float" interfacename="mc"/><input name="melanin_redness" type="float" interfacename="mr"/></deon_hair_absorption_from_melanin>
        <output name="rr" type="vector2" nodename="r" output="roughness_R"/><output name="rtt" type="vector2" nodename="r" output="roughness_TT"/><output name="rtrt" type="vector2" nodename="r" output="roughness_TRT"/>
        <output name="ac_out" type="vector3" nodename="ac"/><output name="am_out" type="vector3" nodename="am"/>
        </nodegraph></materialx>"#,
    );
    let mut rng = Rng::new(5);
    let rows: Vec<Vec<f32>> = (0..64)
        .map(|_| {
            vec![
                rng.range(0.0, 1.0),
                rng.range(0.0, 1.0),
                rng.range(0.0, 1.0),
                rng.range(0.0, 1.0),
                rng.range(0.0, 1.0),
                rng.range(0.0, 0.99),
                rng.range(0.0, 1.0),
            ]
        })
        .collect();
    let out = run(&k, &vec![Geometry::default(); rows.len()], &rows, vec![]);
    for (o, r) in out.iter().zip(&rows) {
        let (l, a) = (
            (r[0] as f64).clamp(0.001, 1.0),
            (r[1] as f64).clamp(0.001, 1.0),
        );
        let v = (0.726 * l + 0.812 * l * l + 3.7 * l.powi(20)).powi(2);
        let s = 0.265 * a + 1.194 * a * a + 5.372 * a.powi(22);
        let want_r = [v, s, v * 0.25, s, v * 4.0, s].map(|x| x as f32);
        assert_close(
            "chiang_hair_roughness",
            &o[0..6],
            &want_r,
            1e-4 * want_r.iter().fold(1.0f32, |m, x| m.max(x.abs())),
        );
        let b = r[1] as f64;
        let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3)
            + 5.574 * b.powi(4)
            + 0.245 * b.powi(5);
        let want_c = [2, 3, 4].map(|i| ((r[i] as f64).clamp(0.001, 1.0).ln() / d).powi(2) as f32);
        assert_close("chiang_hair_absorption_from_color", &o[6..9], &want_c, 1e-4);
        let m = -(1.0 - r[5] as f64).max(1e-4).ln();
        let (eu, ph) = (m * (1.0 - r[6] as f64), m * r[6] as f64);
        let (ce, cp) = (
            [0.657704f64, 0.498077, 0.254107],
            [0.829444f64, 0.67032, 0.349938],
        );
        let want_m = [0, 1, 2].map(|i| (eu * -ce[i].ln() + ph * -cp[i].ln()).max(0.0) as f32);
        assert_close(
            "deon_hair_absorption_from_melanin",
            &o[9..12],
            &want_m,
            1e-4 * want_m.iter().fold(1.0f32, |m, x| m.max(x.abs())),
        );
    }
}

/// Named geometry streams are interface inputs: `geompropvalue` named by its `geomprop` (its
/// `default` the input's default), `geomcolor` as `geomcolor<index>`.
#[test]
fn geometry_streams_are_interface_inputs() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g">
        <geompropvalue name="w" type="float"><input name="geomprop" type="string" value="wetness"/><input name="default" type="float" value="0.25"/></geompropvalue>
        <geomcolor name="c" type="color3"><input name="index" type="integer" value="1"/></geomcolor>
        <multiply name="m" type="color3"><input name="in1" type="color3" nodename="c"/><input name="in2" type="float" nodename="w"/></multiply>
        <output name="out" type="color3" nodename="m"/>
        </nodegraph></materialx>"#,
    );
    let names: Vec<&str> = k.inputs.iter().map(|i| i.input.name.as_str()).collect();
    assert_eq!(names, ["wetness", "geomcolor1"]);
    assert_eq!(k.inputs[0].input.default, vec![0.25]);
    let rows = vec![vec![2.0f32, 0.1, 0.2, 0.3], vec![0.5, 1.0, -1.0, 0.5]];
    let out = run(&k, &vec![Geometry::default(); rows.len()], &rows, vec![]);
    for (o, r) in out.iter().zip(&rows) {
        assert_close(
            "geomcolor·geompropvalue",
            o,
            &[r[1] * r[0], r[2] * r[0], r[3] * r[0]],
            1e-6,
        );
    }
}
