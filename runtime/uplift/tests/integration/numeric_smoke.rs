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
