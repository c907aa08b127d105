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

/// Namespaces end to end: a library included with `namespace="site_ops"` defines `mynoise`
/// (a nodegraph, 2f as a colour); the document uses `<site_ops:mynoise>`; a nodedef with its
/// own `namespace="mine"` and its nodegraph referring to it as `mine:ND_twice` (the spec's
/// example) is used as `<mine:twice>`. Values against the closed forms, on wgpu.
#[test]
fn namespaced_nodes_compile_and_evaluate() {
    let dir = common::cli::temp_dir("numeric_smoke", "namespaces");
    std::fs::write(
        dir.join("site_ops.mtlx"),
        r#"<materialx version="1.39" namespace="site_ops">
        <nodedef name="ND_mynoise" node="mynoise"><input name="f" type="float" value="0.5"/><output name="out" type="color3"/></nodedef>
        <nodegraph name="NG_mynoise" nodedef="ND_mynoise">
          <multiply name="m" type="float"><input name="in1" type="float" interfacename="f"/><input name="in2" type="float" value="2"/></multiply>
          <convert name="c" type="color3"><input name="in" type="float" nodename="m"/></convert>
          <output name="out" type="color3" nodename="c"/>
        </nodegraph></materialx>"#,
    )
    .unwrap();
    let text = r#"<materialx version="1.39"><xi:include href="site_ops.mtlx"/>
        <nodedef name="ND_twice" node="twice" namespace="mine"><input name="in" type="float" value="0"/><output name="out" type="float"/></nodedef>
        <nodegraph name="NG_twice" nodedef="mine:ND_twice" namespace="mine">
          <add name="a" type="float"><input name="in1" type="float" interfacename="in"/><input name="in2" type="float" interfacename="in"/></add>
          <output name="out" type="float" nodename="a"/>
        </nodegraph>
        <nodegraph name="g"><input name="x" type="float" value="0"/>
          <site_ops:mynoise name="mn1" type="color3"><input name="f" type="float" interfacename="x"/></site_ops:mynoise>
          <site_ops:mynoise name="mn2" type="color3"/>
          <add name="sum" type="color3"><input name="in1" type="color3" nodename="mn1"/><input name="in2" type="color3" nodename="mn2"/></add>
          <mine:twice name="t" type="float"><input name="in" type="float" interfacename="x"/></mine:twice>
          <output name="noise" type="color3" nodename="sum"/><output name="twice" type="float" nodename="t"/>
        </nodegraph></materialx>"#;
    let path = dir.join("main.mtlx");
    std::fs::write(&path, text).unwrap();
    let (doc, diags) = mtlx::read_file(&path);
    let c = compiler().compile_document(doc, diags, &path.display().to_string(), &uplift_compiler::OutputSelection::AllNumeric);
    let errors: Vec<String> = c.diagnostics.iter().map(|d| d.to_string()).collect();
    let k = c.kernel.unwrap_or_else(|| panic!("does not compile:\n{}", errors.join("\n")));
    let rows: Vec<Vec<f32>> = [-1.5f32, 0.0, 0.25, 3.0].iter().map(|&x| vec![x]).collect();
    let out = run(&k, &vec![Geometry::default(); rows.len()], &rows, vec![]);
    for (o, r) in out.iter().zip(&rows) {
        let n = 2.0 * r[0] + 1.0;
        assert_close("site_ops:mynoise(x) + site_ops:mynoise()", &o[0..3], &[n, n, n], 1e-6);
        assert_close("mine:twice(x)", &o[3..4], &[2.0 * r[0]], 1e-6);
    }
    // Without the include the category is unknown, and the error names it as written.
    let (doc, diags) = mtlx::read_str(&text.replace(r#"<xi:include href="site_ops.mtlx"/>"#, ""), "alone.mtlx");
    let c = compiler().compile_document(doc, diags, "alone.mtlx", &uplift_compiler::OutputSelection::AllNumeric);
    assert!(c.kernel.is_none());
    assert!(c.diagnostics.iter().any(|d| d.to_string().contains("unknown node category `site_ops:mynoise`")), "{:?}", c.diagnostics);
}

/// `heighttonormal` of h(u, v) = sin 3u + v² (UV0 through the `texcoord` node): MaterialX's
/// n = (dT, s·dH)ₓ × (dT, s·dH)ᵧ, s = scale/16, is normalize(−s·∂h/∂u, −s·∂h/∂v, 1) encoded
/// as n/2 + 1/2 for the node's default texcoord, and normalize(−s·∂h/∂u/2, −s·∂h/∂v/2, 1)
/// when its `texcoord` is 2·UV0 — closed forms against the compiler's central differences.
#[test]
fn heighttonormal_matches_the_height_fields_normal() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g"><input name="scale" type="float" value="1"/>
        <texcoord name="tc" type="vector2"/>
        <separate2 name="sp" type="multioutput"><input name="in" type="vector2" nodename="tc"/></separate2>
        <multiply name="u3" type="float"><input name="in1" type="float" nodename="sp" output="outx"/><input name="in2" type="float" value="3"/></multiply>
        <sin name="su" type="float"><input name="in" type="float" nodename="u3"/></sin>
        <multiply name="vv" type="float"><input name="in1" type="float" nodename="sp" output="outy"/><input name="in2" type="float" nodename="sp" output="outy"/></multiply>
        <add name="h" type="float"><input name="in1" type="float" nodename="su"/><input name="in2" type="float" nodename="vv"/></add>
        <heighttonormal name="n1" type="vector3"><input name="in" type="float" nodename="h"/><input name="scale" type="float" interfacename="scale"/></heighttonormal>
        <multiply name="tc2" type="vector2"><input name="in1" type="vector2" nodename="tc"/><input name="in2" type="float" value="2"/></multiply>
        <heighttonormal name="n2" type="vector3"><input name="in" type="float" nodename="h"/><input name="scale" type="float" interfacename="scale"/><input name="texcoord" type="vector2" nodename="tc2"/></heighttonormal>
        <constant name="flat" type="float"><input name="value" type="float" value="0.7"/></constant>
        <heighttonormal name="n3" type="vector3"><input name="in" type="float" nodename="flat"/></heighttonormal>
        <output name="out1" type="vector3" nodename="n1"/><output name="out2" type="vector3" nodename="n2"/><output name="out3" type="vector3" nodename="n3"/>
        </nodegraph></materialx>"#,
    );
    let mut rng = Rng::new(5);
    let (mut geom, mut rows) = (Vec::new(), Vec::new());
    for _ in 0..256 {
        geom.push(Geometry { texcoord: [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)], ..Default::default() });
        rows.push(vec![rng.range(0.0, 64.0)]);
    }
    let out = run(&k, &geom, &rows, vec![]);
    let encoded = |n: [f32; 3]| {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        n.map(|c| c / l * 0.5 + 0.5)
    };
    for ((o, r), g) in out.iter().zip(&rows).zip(&geom) {
        let [u, v] = g.texcoord;
        let s = r[0] / 16.0;
        let (hu, hv) = (3.0 * (3.0 * u).cos(), 2.0 * v);
        let what = format!("uv ({u}, {v}), scale {}", r[0]);
        assert_close(&format!("{what}: UV0"), &o[0..3], &encoded([-s * hu, -s * hv, 1.0]), 5e-4);
        assert_close(&format!("{what}: 2·UV0"), &o[3..6], &encoded([-s * hu / 2.0, -s * hv / 2.0, 1.0]), 5e-4);
        assert_close(&format!("{what}: a constant height is flat"), &o[6..9], &[0.5, 0.5, 1.0], 1e-6);
    }
}
