//! The version upgrades run by the reader (MaterialX's Version.cpp chain), one small document
//! per step, each compared element by element and attribute by attribute with the expected
//! 1.39 document.

use mtlx::{read_str, write_string, Diagnostic, Document, Severity};

fn upgrade(text: &str) -> (Document, Vec<Diagnostic>) {
    read_str(text, "upgrade_test.mtlx")
}

/// Asserts that `doc` has exactly the content of the (1.39, so not upgraded) `expected` text.
#[track_caller]
fn assert_doc(doc: &Document, expected: &str) {
    let (exp, diags) = read_str(expected, "expected.mtlx");
    assert!(diags.is_empty(), "the expected document itself reads with diagnostics: {diags:?}");
    assert!(
        doc.same_content(&exp),
        "upgraded document:\n{}\nexpected:\n{}",
        write_string(doc),
        write_string(&exp)
    );
}

#[track_caller]
fn assert_no_diagnostics(diags: &[Diagnostic]) {
    assert!(diags.is_empty(), "unexpected diagnostics:\n{}", diags.iter().map(|d| format!("  {d}\n")).collect::<String>());
}

/// The diagnostics as `line:col: severity: message` (the file name left out).
fn lines(diags: &[Diagnostic]) -> Vec<String> {
    diags
        .iter()
        .map(|d| {
            let sev = if d.severity == Severity::Error { "error" } else { "warning" };
            format!("{}:{}: {sev}: {}", d.pos.line, d.pos.column, d.message)
        })
        .collect()
}

fn find(doc: &Document, name: &str) -> mtlx::ElementId {
    doc.descendants(doc.root())
        .into_iter()
        .find(|&e| doc.get(e).name() == name && doc.get(e).category != "input")
        .unwrap_or_else(|| panic!("no element named `{name}` in\n{}", write_string(doc)))
}

// ---------------------------------------------------------------------------------------------
// Versions
// ---------------------------------------------------------------------------------------------

#[test]
fn a_document_without_version_reads_as_1_39() {
    let (doc, diags) = upgrade(r#"<materialx><add name="a" type="float" /></materialx>"#);
    assert_no_diagnostics(&diags);
    assert_eq!(doc.get(doc.root()).attr("version"), Some("1.39"));
    assert_eq!(doc.version(), (1, 39));
}

#[test]
fn every_older_version_ends_at_1_39() {
    for v in ["1.22", "1.23", "1.24", "1.25", "1.26", "1.30", "1.34", "1.35", "1.36", "1.37", "1.38", "1.38.10"] {
        let (doc, diags) = upgrade(&format!(r#"<materialx version="{v}" colorspace="lin_rec709"><add name="a" type="float" /></materialx>"#));
        assert_no_diagnostics(&diags);
        assert_eq!(doc.get(doc.root()).attributes, vec![
            ("version".to_string(), "1.39".to_string()),
            ("colorspace".to_string(), "lin_rec709".to_string())
        ], "from {v}");
    }
}

#[test]
fn a_1_39_document_is_left_alone() {
    let text = r#"<materialx version="1.39"><atan2 name="a" type="float"><input name="in1" type="float" value="1" /></atan2></materialx>"#;
    let (doc, diags) = upgrade(text);
    assert_no_diagnostics(&diags);
    assert_doc(&doc, text);
}

#[test]
fn newer_and_unreadable_versions_are_reported() {
    let (doc, diags) = upgrade("<materialx version=\"1.40\">\n  <add name=\"a\" type=\"float\" />\n</materialx>");
    assert_eq!(doc.get(doc.root()).attr("version"), Some("1.40"));
    assert_eq!(lines(&diags), ["1:1: warning: document version 1.40 is newer than 1.39, the newest this reader knows; read as is"]);

    let (doc, diags) = upgrade(r#"<materialx version="one"/>"#);
    assert_eq!(doc.get(doc.root()).attr("version"), Some("1.39"));
    assert_eq!(lines(&diags), ["1:1: warning: unrecognised MaterialX version `one`; read as 1.39 without upgrades"]);

    let (doc, diags) = upgrade(r#"<materialx version="1.10"/>"#);
    assert_eq!(doc.get(doc.root()).attr("version"), Some("1.39"));
    assert_eq!(lines(&diags), ["1:1: warning: document version 1.10 predates MaterialX 1.22; upgraded as if it were 1.22"]);
}

// ---------------------------------------------------------------------------------------------
// 1.22 … 1.36
// ---------------------------------------------------------------------------------------------

#[test]
fn v1_22_opgraphs_shaders_and_materials() {
    let (doc, diags) = upgrade(
        r#"<?xml version="1.0"?>
<materialx version="1.22">
  <opgraph name="g" colorspace="lin_rec709">
    <constant name="c" type="color3">
      <parameter name="color" type="color3" value="0.1, 0.2, 0.3" />
    </constant>
    <constant name="v" type="vector">
      <parameter name="color" type="vector" value="1, 2, 3" />
    </constant>
    <output name="c_out" type="color3">
      <parameter name="in" type="opgraphnode" value="c" />
    </output>
    <add name="plus" type="color3">
      <parameter name="in1" type="opgraphnode" value="c" />
    </add>
  </opgraph>
  <shader name="sh" shadertype="surface" shadername="standard_surface">
    <input name="base_color" type="color3" graphname="g" graphoutput="c_out" />
    <input name="base" type="float" value="0.8" />
  </shader>
  <material name="mat">
    <shaderref name="sh" shadertype="surface" />
  </material>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        ["19:5: warning: the default `base` = \"0.8\" of legacy shader `sh` is dropped with its declaration; \
          the shader's library definition supplies the default instead"]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodegraph name="g" colorspace="lin_rec709">
    <constant name="c" type="color3">
      <input name="value" type="color3" value="0.1, 0.2, 0.3" />
    </constant>
    <constant name="v" type="vector3">
      <input name="value" type="vector3" value="1, 2, 3" />
    </constant>
    <output name="c_out" type="color3" nodename="c" />
    <add name="plus" type="color3">
      <input name="in1" type="color3" nodename="c" />
    </add>
  </nodegraph>
  <standard_surface name="sh" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="g" output="c_out" />
  </standard_surface>
  <surfacematerial name="mat" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="sh" />
  </surfacematerial>
</materialx>"#,
    );
}

#[test]
fn v1_25_material_overrides_become_shader_inputs() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.25">
  <shader name="ss" shadertype="surface" shaderprogram="standard_surface">
    <input name="base" type="float" value="1.0" publicname="base_public" />
    <input name="coat" type="float" value="0.0" publicname="coat_public" />
  </shader>
  <material name="paint">
    <shaderref name="ss" shadertype="surface" />
    <override name="base_public" type="float" value="0.5" />
    <override name="nobody" type="float" value="0.25" />
  </material>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        [
            "9:5: warning: override `nobody` matches no publicname of the material's shader; dropped",
            "4:5: warning: the default `coat` = \"0.0\" of legacy shader `ss` is dropped with its declaration; \
             the shader's library definition supplies the default instead",
        ]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <standard_surface name="ss" type="surfaceshader">
    <input name="base" type="float" value="0.5" />
  </standard_surface>
  <surfacematerial name="paint" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="ss" />
  </surfacematerial>
</materialx>"#,
    );
}

#[test]
fn v1_26_to_1_36_attribute_renames() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.26">
  <nodedef name="ND_m" node="m" type="matrix" defaultinput="in">
    <input name="in" type="matrix" default="1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1" />
  </nodedef>
  <image name="img" type="color3">
    <parameter name="file" type="filename" value="tex.%UDIM.%UVTILE.png" />
  </image>
  <geominfo name="g1" geom="/a">
    <geomattr name="udim" type="string" value="1002" />
  </geominfo>
  <geominfo name="g2" geom="/b">
    <geomattr name="udim" type="string" value="1001" />
    <geomattr name="all" type="geomname" value="*" />
  </geominfo>
  <look name="L">
    <materialassign name="M1" geom="/a" />
  </look>
</materialx>"#,
    );
    assert_no_diagnostics(&diags);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodedef name="ND_m" node="m">
    <input name="in" type="matrix44" value="1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1" />
    <output name="out" type="matrix44" defaultinput="in" />
  </nodedef>
  <image name="img" type="color3">
    <input name="file" type="filename" value="tex.&lt;UDIM&gt;.&lt;UVTILE&gt;.png" />
  </image>
  <geominfo name="g1" geom="/a">
    <geomprop name="udim" type="string" value="1002" />
  </geominfo>
  <geominfo name="g2" geom="/b">
    <geomprop name="udim" type="string" value="1001" />
    <geomprop name="all" type="geomname" value="/" />
  </geominfo>
  <look name="L">
    <materialassign name="M1" geom="/a" material="M1" />
  </look>
  <geominfo name="geominfo1" geom="/">
    <geomprop name="udimset" type="stringarray" value="1001, 1002" />
  </geominfo>
</materialx>"#,
    );
}

#[test]
fn v1_36_node_renames() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.36">
  <nodedef name="ND_legacy" node="legacy" type="multioutput">
    <output name="a" type="float" />
  </nodedef>
  <invert name="im" type="matrix33"><input name="in" type="matrix33" /></invert>
  <invert name="iv" type="vector2"><input name="in" type="vector2" /></invert>
  <rotate name="r2" type="vector2" />
  <rotate name="r3" type="vector3"><parameter name="axis" type="vector3" value="0, 1, 0" /></rotate>
  <compare name="cmp" type="float">
    <input name="intest" type="float" value="0.5" />
    <parameter name="cutoff" type="float" value="0.6" />
    <input name="in1" type="float" value="1" />
    <input name="in2" type="float" value="0" />
  </compare>
  <transformpoint name="tm" type="vector3"><input name="mat" type="matrix44" /></transformpoint>
  <transformnormal name="ts" type="vector3"><parameter name="tospace" type="string" value="world" /></transformnormal>
  <combine name="c2" type="color2"><input name="in1" type="float" /><input name="in2" type="float" /></combine>
  <combine name="c4" type="vector4"><input name="in4" type="float" /></combine>
  <separate name="s3" type="multioutput"><input name="in" type="vector3" /></separate>
  <separate name="s4" type="multioutput"><input name="in" type="color4" /></separate>
  <backdrop name="bd">
    <parameter name="contains" type="string" value="r2,r3" />
    <parameter name="width" type="float" value="20" />
  </backdrop>
  <geomattrvalue name="gv" type="integer" attrname="id" />
</materialx>"#,
    );
    assert_no_diagnostics(&diags);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodedef name="ND_legacy" node="legacy">
    <output name="a" type="float" />
  </nodedef>
  <invertmatrix name="im" type="matrix33"><input name="in" type="matrix33" /></invertmatrix>
  <invert name="iv" type="vector2"><input name="in" type="vector2" /></invert>
  <rotate2d name="r2" type="vector2" />
  <rotate3d name="r3" type="vector3"><input name="axis" type="vector3" value="0, 1, 0" /></rotate3d>
  <ifgreatereq name="cmp" type="float">
    <input name="value1" type="float" value="0.5" />
    <input name="value2" type="float" value="0.6" />
    <input name="in2" type="float" value="1" />
    <input name="in1" type="float" value="0" />
  </ifgreatereq>
  <transformmatrix name="tm" type="vector3"><input name="mat" type="matrix44" /></transformmatrix>
  <transformnormal name="ts" type="vector3"><input name="tospace" type="string" value="world" /></transformnormal>
  <combine2 name="c2" type="vector2"><input name="in1" type="float" /><input name="in2" type="float" /></combine2>
  <combine4 name="c4" type="vector4"><input name="in4" type="float" /></combine4>
  <separate3 name="s3" type="multioutput"><input name="in" type="vector3" /></separate3>
  <separate4 name="s4" type="multioutput"><input name="in" type="color4" /></separate4>
  <backdrop name="bd" contains="r2,r3" width="20" />
  <geompropvalue name="gv" type="integer" geomprop="id" />
</materialx>"#,
    );
}

// ---------------------------------------------------------------------------------------------
// 1.37 → 1.38
// ---------------------------------------------------------------------------------------------

#[test]
fn v1_37_color2_becomes_vector2_and_channel_letters_follow() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.37">
  <constant name="c2" type="color2">
    <input name="value" type="color2" value="0.25, 0.75" />
  </constant>
  <add name="use_alpha" type="float">
    <input name="in1" type="float" nodename="c2" channels="a" />
  </add>
  <separate2 name="sep" type="multioutput">
    <input name="in" type="color2" value="0.1, 0.9" />
  </separate2>
  <multiply name="use_outa" type="float">
    <input name="in1" type="float" nodename="sep" output="outa" />
  </multiply>
</materialx>"#,
    );
    assert_no_diagnostics(&diags);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <constant name="c2" type="vector2">
    <input name="value" type="vector2" value="0.25, 0.75" />
  </constant>
  <extract name="swizzle" type="float">
    <input name="in" type="vector2" nodename="c2" />
    <input name="index" type="integer" value="1" />
  </extract>
  <add name="use_alpha" type="float">
    <input name="in1" type="float" nodename="swizzle" />
  </add>
  <separate2 name="sep" type="multioutput">
    <input name="in" type="vector2" value="0.1, 0.9" />
  </separate2>
  <multiply name="use_outa" type="float">
    <input name="in1" type="float" nodename="sep" output="outy" />
  </multiply>
</materialx>"#,
    );
}

#[test]
fn v1_37_materials_become_nodes() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.37">
  <nodedef name="ND_example" node="example">
    <input name="diffuseColor" type="color3" value="0.18, 0.18, 0.18" />
    <output name="out" type="surfaceshader" />
  </nodedef>
  <material name="M_example" look="hero">
    <shaderref name="SR_example" node="example">
      <bindinput name="diffuseColor" type="color3" value="0.2, 0.2, 0.6" />
    </shaderref>
  </material>
  <material name="M_vol">
    <shaderref name="SR_vol" node="volume" type="volumeshader" version="2.0">
      <bindparam name="density" type="float" value="0.5" />
      <bindtoken name="tok" value="x" />
    </shaderref>
  </material>
  <material name="M_empty" />
  <material name="M_two">
    <shaderref name="SR_a" node="standard_surface" />
    <shaderref name="SR_b" node="standard_surface" />
    <shaderref name="SR_d" node="displace" type="displacementshader" />
  </material>
  <material name="M_anon">
    <shaderref name="SR_anon" />
  </material>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        [
            "17:3: warning: material `M_empty` has no shaderref; removed (materials are nodes since 1.38)",
            "20:5: warning: material `M_two` has a second surfaceshader shaderref `SR_b`; the surfacematerial connects only the first",
            "24:5: error: shaderref `SR_anon` of material `M_anon` names no shader node (no `node` attribute and no nodedef in this document); dropped",
        ]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodedef name="ND_example" node="example">
    <input name="diffuseColor" type="color3" value="0.18, 0.18, 0.18" />
    <output name="out" type="surfaceshader" />
  </nodedef>
  <example name="SR_example" type="surfaceshader">
    <input name="diffuseColor" type="color3" value="0.2, 0.2, 0.6" />
  </example>
  <surfacematerial name="M_example" type="material" look="hero">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_example" />
  </surfacematerial>
  <volume name="SR_vol" type="volumeshader" version="2.0">
    <input name="density" type="float" value="0.5" />
    <token name="tok" value="x" />
  </volume>
  <volumematerial name="M_vol" type="material">
    <input name="volumeshader" type="volumeshader" nodename="SR_vol" />
  </volumematerial>
  <standard_surface name="SR_a" type="surfaceshader" />
  <standard_surface name="SR_b" type="surfaceshader" />
  <displace name="SR_d" type="displacementshader" />
  <surfacematerial name="M_two" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_a" />
    <input name="displacementshader" type="displacementshader" nodename="SR_d" />
  </surfacematerial>
</materialx>"#,
    );
}

#[test]
fn v1_37_bsdf_nodes_layers_and_artistic_ior() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.37">
  <nodedef name="ND_thing" node="thing">
    <parameter name="mode" type="string" value="a" />
    <input name="amount" type="float" value="0.5" />
    <output name="out" type="BSDF" />
  </nodedef>
  <nodegraph name="NG" nodedef="ND_thing" version="2.0">
    <constant name="amount" type="float">
      <input name="value" type="float" interfacename="amount" />
    </constant>
    <dielectric_btdf name="btdf" type="BSDF">
      <input name="ior" type="float" nodename="amount" />
      <input name="interior" type="VDF" value="" />
    </dielectric_btdf>
    <sheen_brdf name="sheen" type="BSDF">
      <input name="base" type="BSDF" nodename="btdf" />
    </sheen_brdf>
    <conductor_brdf name="metal" type="BSDF">
      <input name="reflectivity" type="color3" value="0.9, 0.8, 0.5" />
      <input name="edge_color" type="color3" interfacename="tint" />
      <input name="base" type="BSDF" nodename="sheen" />
    </conductor_brdf>
    <diffuse_brdf name="d" type="BSDF" />
    <burley_diffuse_brdf name="bd" type="BSDF" />
    <diffuse_btdf name="t" type="BSDF" />
    <subsurface_brdf name="ss" type="BSDF" />
    <dielectric_brdf name="coat" type="BSDF">
      <input name="base" type="BSDF" interfacename="under" />
    </dielectric_brdf>
    <artistic_ior name="aior" type="multioutput">
      <output name="ior" type="vector3" />
      <output name="extinction" type="vector3" />
    </artistic_ior>
    <conductor_bsdf name="cond" type="BSDF">
      <input name="ior" type="vector3" nodename="aior" output="ior" />
      <input name="extinction" type="vector3" nodename="aior" output="extinction" />
    </conductor_bsdf>
    <atan2 name="at" type="float">
      <input name="in1" type="float" value="1" />
      <input name="in2" type="float" value="2" />
    </atan2>
    <rotate3d name="rot" type="vector3">
      <parameter name="axis" type="vector3" value="0, 0, 1" />
    </rotate3d>
    <output name="out" type="BSDF" nodename="metal" />
  </nodegraph>
</materialx>"#,
    );
    assert_no_diagnostics(&diags);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodedef name="ND_thing" node="thing">
    <input name="mode" type="string" value="a" uniform="true" />
    <input name="amount" type="float" value="0.5" />
    <output name="out" type="BSDF" />
  </nodedef>
  <nodegraph name="NG" nodedef="ND_thing">
    <constant name="amount2" type="float">
      <input name="value" type="float" interfacename="amount" />
    </constant>
    <dielectric_bsdf name="btdf" type="BSDF">
      <input name="ior" type="float" nodename="amount2" />
      <input name="scatter_mode" type="string" value="T" />
    </dielectric_bsdf>
    <sheen_bsdf name="sheen__layer_top" type="BSDF" />
    <conductor_bsdf name="metal" type="BSDF">
      <input name="base" type="BSDF" nodename="sheen" />
      <input name="ior" type="color3" nodename="metal__artistic_ior" output="ior" />
      <input name="extinction" type="color3" nodename="metal__artistic_ior" output="extinction" />
    </conductor_bsdf>
    <oren_nayar_diffuse_bsdf name="d" type="BSDF" />
    <burley_diffuse_bsdf name="bd" type="BSDF" />
    <translucent_bsdf name="t" type="BSDF" />
    <subsurface_bsdf name="ss" type="BSDF" />
    <dielectric_bsdf name="coat__layer_top" type="BSDF" />
    <artistic_ior name="aior" type="multioutput">
      <output name="ior" type="color3" />
      <output name="extinction" type="color3" />
    </artistic_ior>
    <conductor_bsdf name="cond" type="BSDF">
      <input name="ior" type="vector3" nodename="cond__convert_ior" />
      <input name="extinction" type="vector3" nodename="cond__convert_extinction" />
    </conductor_bsdf>
    <atan2 name="at" type="float">
      <input name="inx" type="float" value="1" />
      <input name="iny" type="float" value="2" />
    </atan2>
    <rotate3d name="rot" type="vector3">
      <input name="axis" type="vector3" value="0, 0, 1" />
    </rotate3d>
    <output name="out" type="BSDF" nodename="metal" />
    <layer name="sheen" type="BSDF">
      <input name="top" type="BSDF" nodename="sheen__layer_top" />
      <input name="base" type="BSDF" nodename="btdf" />
    </layer>
    <artistic_ior name="metal__artistic_ior" type="multioutput">
      <output name="ior" type="color3" />
      <output name="extinction" type="color3" />
      <input name="reflectivity" type="color3" value="0.9, 0.8, 0.5" />
      <input name="edge_color" type="color3" interfacename="tint" />
    </artistic_ior>
    <layer name="coat" type="BSDF">
      <input name="top" type="BSDF" nodename="coat__layer_top" />
      <input name="base" type="BSDF" interfacename="under" />
    </layer>
    <convert name="cond__convert_ior" type="vector3">
      <input name="in" type="color3" nodename="aior" output="ior" />
    </convert>
    <convert name="cond__convert_extinction" type="vector3">
      <input name="in" type="color3" nodename="aior" output="extinction" />
    </convert>
  </nodegraph>
</materialx>"#,
    );
}

// ---------------------------------------------------------------------------------------------
// 1.38 → 1.39
// ---------------------------------------------------------------------------------------------

#[test]
fn v1_38_channels_attributes_become_nodes() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <image name="img" type="color4" />
  <image name="img3" type="color3" />
  <nodegraph name="NG">
    <input name="tint" type="color3" value="1, 0, 0" />
    <multiply name="m" type="float">
      <input name="in1" type="float" interfacename="tint" channels="g" />
      <input name="in2" type="float" value="2" />
    </multiply>
    <output name="out_r" type="float" nodename="m" />
    <output name="out_rgb" type="vector3" nodename="m" channels="xxx" />
  </nodegraph>
  <standard_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" nodename="img" channels="rgb" />
    <input name="opacity" type="color3" nodename="img" channels="aaa" />
    <input name="specular" type="float" value="0.5" nodename="img" channels="r" />
    <input name="coat_color" type="color3" nodename="img3" channels="bgr" />
    <input name="emission_color" type="color3" nodename="img3" channels="r01" />
    <input name="base" type="float" nodegraph="NG" output="out_r" channels="x" />
  </standard_surface>
</materialx>"#,
    );
    assert_no_diagnostics(&diags);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <image name="img" type="color4" />
  <image name="img3" type="color3" />
  <nodegraph name="NG">
    <input name="tint" type="color3" value="1, 0, 0" />
    <extract name="swizzle" type="float">
      <input name="in" type="color3" interfacename="tint" />
      <input name="index" type="integer" value="1" />
    </extract>
    <multiply name="m" type="float">
      <input name="in1" type="float" nodename="swizzle" />
      <input name="in2" type="float" value="2" />
    </multiply>
    <output name="out_r" type="float" nodename="m" />
    <convert name="swizzle2" type="vector3">
      <input name="in" type="float" nodename="m" />
    </convert>
    <output name="out_rgb" type="vector3" nodename="swizzle2" />
  </nodegraph>
  <convert name="swizzle" type="color3">
    <input name="in" type="color4" nodename="img" />
  </convert>
  <separate4 name="separate" type="multioutput">
    <input name="in" type="color4" nodename="img" />
  </separate4>
  <combine3 name="swizzle2" type="color3">
    <input name="in1" type="float" nodename="separate" output="outa" />
    <input name="in2" type="float" nodename="separate" output="outa" />
    <input name="in3" type="float" nodename="separate" output="outa" />
  </combine3>
  <extract name="swizzle3" type="float">
    <input name="in" type="color4" nodename="img" />
    <input name="index" type="integer" value="0" />
  </extract>
  <separate3 name="separate2" type="multioutput">
    <input name="in" type="color3" nodename="img3" />
  </separate3>
  <combine3 name="swizzle4" type="color3">
    <input name="in1" type="float" nodename="separate2" output="outb" />
    <input name="in2" type="float" nodename="separate2" output="outg" />
    <input name="in3" type="float" nodename="separate2" output="outr" />
  </combine3>
  <separate3 name="separate3" type="multioutput">
    <input name="in" type="color3" nodename="img3" />
  </separate3>
  <combine3 name="swizzle5" type="color3">
    <input name="in1" type="float" nodename="separate3" output="outr" />
    <input name="in2" type="float" value="0" />
    <input name="in3" type="float" value="1" />
  </combine3>
  <standard_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" nodename="swizzle" />
    <input name="opacity" type="color3" nodename="swizzle2" />
    <input name="specular" type="float" nodename="swizzle3" />
    <input name="coat_color" type="color3" nodename="swizzle4" />
    <input name="emission_color" type="color3" nodename="swizzle5" />
    <input name="base" type="float" nodegraph="NG" output="out_r" />
  </standard_surface>
</materialx>"#,
    );
}

#[test]
fn v1_38_channels_with_an_unknown_upstream_type_are_guessed_and_reported() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <nodegraph name="NG_lib" nodedef="ND_elsewhere">
    <add name="a" type="float">
      <input name="in1" type="float" interfacename="v" channels="y" />
    </add>
    <output name="out" type="float" nodename="a" />
  </nodegraph>
</materialx>"#,
    );
    assert_eq!(lines(&diags), ["4:7: warning: the type upstream of `channels=\"y\"` on `in1` is unknown here; assumed vector3"]);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodegraph name="NG_lib" nodedef="ND_elsewhere">
    <extract name="swizzle" type="float">
      <input name="in" type="vector3" interfacename="v" />
      <input name="index" type="integer" value="1" />
    </extract>
    <add name="a" type="float">
      <input name="in1" type="float" nodename="swizzle" />
    </add>
    <output name="out" type="float" nodename="a" />
  </nodegraph>
</materialx>"#,
    );
}

#[test]
fn v1_38_channels_where_nothing_connects_are_dropped_with_a_warning() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <nodedef name="ND_x" node="x">
    <input name="i" type="color3" value="1, 2, 3" channels="bgr" />
    <output name="out" type="color3" />
  </nodedef>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        ["3:5: warning: `channels` on `i` of a <nodedef> selects nothing (only node inputs and graph outputs connect); dropped"]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodedef name="ND_x" node="x">
    <input name="i" type="color3" value="1, 2, 3" />
    <output name="out" type="color3" />
  </nodedef>
</materialx>"#,
    );
}

#[test]
fn v1_38_swizzle_nodes() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <image name="img3" type="color3" />
  <multiply name="f" type="float" />
  <swizzle name="sw_const" type="color3">
    <input name="in" type="color4" value="1, 2, 3, 4" />
    <input name="channels" type="string" value="a0r" />
  </swizzle>
  <swizzle name="sw_allconst" type="vector2" nodedef="ND_swizzle_vector3_vector2">
    <input name="in" type="vector3" nodename="img3" />
    <input name="channels" type="string" value="10" />
  </swizzle>
  <swizzle name="sw_noin" type="vector3" />
  <swizzle name="sw_extract" type="float" nodedef="ND_swizzle_color3_float">
    <input name="in" type="color3" nodename="img3" value="0, 0, 0" />
    <input name="channels" type="string" value="b" />
  </swizzle>
  <swizzle name="sw_convert" type="color4" nodedef="ND_swizzle_color3_color4">
    <input name="in" type="color3" nodename="img3" />
    <input name="channels" type="string" value="rgb" />
  </swizzle>
  <swizzle name="sw_float" type="color3" nodedef="ND_swizzle_float_color3">
    <input name="in" type="float" nodename="f" />
    <input name="channels" type="string" value="r0r" />
  </swizzle>
  <swizzle name="sw_split" type="vector2" nodedef="ND_swizzle_color3_vector2">
    <input name="in" type="color3" nodename="img3" />
    <input name="channels" type="string" value="br" />
  </swizzle>
  <swizzle name="sw_bad" type="vector2">
    <input name="in" type="vector3" nodename="img3" />
    <input name="channels" type="string" value="xq" />
  </swizzle>
  <swizzle name="sw_bool" type="boolean">
    <input name="in" type="boolean" value="true" />
    <input name="channels" type="string" value="x" />
  </swizzle>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        [
            "12:3: warning: swizzle `sw_noin`: channels \"\" do not name 3 channels of a float; missing or invalid ones take the first channel",
            "29:3: warning: swizzle `sw_bad`: channels \"xq\" do not name 2 channels of a vector3; missing or invalid ones take the first channel",
            "33:3: warning: swizzle `sw_bool` from boolean to boolean has no 1.39 equivalent (swizzle nodes were removed); left as is",
        ]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <image name="img3" type="color3" />
  <multiply name="f" type="float" />
  <constant name="sw_const" type="color3">
    <input name="value" type="color3" value="4, 0, 1" />
  </constant>
  <constant name="sw_allconst" type="vector2" nodedef="ND_constant_vector2">
    <input name="value" type="vector2" value="1, 0" />
  </constant>
  <constant name="sw_noin" type="vector3">
    <input name="value" type="vector3" value="0, 0, 0" />
  </constant>
  <extract name="sw_extract" type="float" nodedef="ND_extract_color3">
    <input name="in" type="color3" nodename="img3" />
    <input name="index" type="integer" value="2" />
  </extract>
  <convert name="sw_convert" type="color4" nodedef="ND_convert_color3_color4">
    <input name="in" type="color3" nodename="img3" />
  </convert>
  <combine3 name="sw_float" type="color3" nodedef="ND_combine3_color3">
    <input name="in1" type="float" nodename="f" />
    <input name="in2" type="float" value="0" />
    <input name="in3" type="float" nodename="f" />
  </combine3>
  <separate3 name="separate" type="multioutput">
    <input name="in" type="color3" nodename="img3" />
  </separate3>
  <combine2 name="sw_split" type="vector2" nodedef="ND_combine2_vector2">
    <input name="in1" type="float" nodename="separate" output="outb" />
    <input name="in2" type="float" nodename="separate" output="outr" />
  </combine2>
  <separate3 name="separate2" type="multioutput">
    <input name="in" type="vector3" nodename="img3" />
  </separate3>
  <combine2 name="sw_bad" type="vector2">
    <input name="in1" type="float" nodename="separate2" output="outx" />
    <input name="in2" type="float" nodename="separate2" output="outx" />
  </combine2>
  <swizzle name="sw_bool" type="boolean">
    <input name="in" type="boolean" value="true" />
    <input name="channels" type="string" value="x" />
  </swizzle>
</materialx>"#,
    );
}

#[test]
fn v1_38_thin_film_layers_become_bsdf_inputs() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <nodegraph name="TF">
    <input name="film_ior" type="float" value="1.3" />
    <thin_film_bsdf name="film" type="BSDF">
      <input name="thickness" type="float" value="550" />
      <input name="ior" type="float" interfacename="film_ior" />
    </thin_film_bsdf>
    <dielectric_bsdf name="diel" type="BSDF" />
    <dielectric_bsdf name="diel_t" type="BSDF">
      <input name="scatter_mode" type="string" value="T" />
    </dielectric_bsdf>
    <generalized_schlick_bsdf name="gs" type="BSDF" />
    <oren_nayar_diffuse_bsdf name="diffuse" type="BSDF" />
    <mix name="mx" type="BSDF">
      <input name="fg" type="BSDF" nodename="diel" />
      <input name="bg" type="BSDF" nodename="gs" />
    </mix>
    <add name="ad" type="BSDF">
      <input name="in1" type="BSDF" nodename="mx" />
      <input name="in2" type="BSDF" nodename="diel_t" />
    </add>
    <thin_film_bsdf name="default_film" type="BSDF" />
    <conductor_bsdf name="metal" type="BSDF" />
    <layer name="metal_film" type="BSDF">
      <input name="top" type="BSDF" nodename="default_film" />
      <input name="base" type="BSDF" nodename="metal" />
    </layer>
    <output name="metal_out" type="BSDF" nodename="metal_film" />
    <layer name="lay" type="BSDF">
      <input name="top" type="BSDF" nodename="film" />
      <input name="base" type="BSDF" nodename="ad" />
    </layer>
    <surface name="surf" type="surfaceshader">
      <input name="bsdf" type="BSDF" nodename="lay" />
    </surface>
    <output name="out" type="surfaceshader" nodename="surf" />
    <output name="bsdf_out" type="BSDF" nodename="lay" />
    <thin_film_bsdf name="stray" type="BSDF" />
    <layer name="stray_layer" type="BSDF">
      <input name="top" type="BSDF" nodename="stray" />
    </layer>
  </nodegraph>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        ["38:5: warning: thin_film_bsdf `stray` is not the top of a layer; MaterialX 1.39 has no thin_film_bsdf node \
          (thin films are the thinfilm_thickness/thinfilm_ior inputs of the BSDFs below them)"]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <nodegraph name="TF">
    <input name="film_ior" type="float" value="1.3" />
    <dielectric_bsdf name="diel" type="BSDF">
      <input name="thinfilm_thickness" type="float" value="550" />
      <input name="thinfilm_ior" type="float" interfacename="film_ior" />
    </dielectric_bsdf>
    <dielectric_bsdf name="diel_t" type="BSDF">
      <input name="scatter_mode" type="string" value="T" />
    </dielectric_bsdf>
    <generalized_schlick_bsdf name="gs" type="BSDF">
      <input name="thinfilm_thickness" type="float" value="550" />
      <input name="thinfilm_ior" type="float" interfacename="film_ior" />
    </generalized_schlick_bsdf>
    <oren_nayar_diffuse_bsdf name="diffuse" type="BSDF" />
    <mix name="mx" type="BSDF">
      <input name="fg" type="BSDF" nodename="diel" />
      <input name="bg" type="BSDF" nodename="gs" />
    </mix>
    <add name="ad" type="BSDF">
      <input name="in1" type="BSDF" nodename="mx" />
      <input name="in2" type="BSDF" nodename="diel_t" />
    </add>
    <conductor_bsdf name="metal" type="BSDF">
      <input name="thinfilm_thickness" type="float" value="550" />
    </conductor_bsdf>
    <output name="metal_out" type="BSDF" nodename="metal" />
    <surface name="surf" type="surfaceshader">
      <input name="bsdf" type="BSDF" nodename="ad" />
    </surface>
    <output name="out" type="surfaceshader" nodename="surf" />
    <output name="bsdf_out" type="BSDF" nodename="ad" />
    <thin_film_bsdf name="stray" type="BSDF" />
    <layer name="stray_layer" type="BSDF">
      <input name="top" type="BSDF" nodename="stray" />
    </layer>
  </nodegraph>
</materialx>"#,
    );
}

#[test]
fn v1_38_normalmaps() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <image name="img" type="vector3" />
  <normal name="n" type="vector3" />
  <normalmap name="object_space" type="vector3" nodedef="ND_normalmap">
    <input name="in" type="vector3" nodename="img" />
    <input name="scale" type="float" value="2" />
    <input name="space" type="string" value="object" />
  </normalmap>
  <normalmap name="bound_normal" type="vector3" nodedef="ND_normalmap">
    <input name="in" type="vector3" nodename="img" />
    <input name="space" type="string" value="tangent" />
    <input name="normal" type="vector3" nodename="n" />
    <input name="tangent" type="vector3" value="1, 0, 0" />
  </normalmap>
  <normalmap name="plain" type="vector3">
    <input name="in" type="vector3" nodename="img" />
    <input name="scale" type="float" value="1.1" />
    <input name="normal" type="vector3" value="0, 0, 1" />
  </normalmap>
</materialx>"#,
    );
    assert_no_diagnostics(&diags);
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <image name="img" type="vector3" />
  <normal name="n" type="vector3" />
  <normalize name="object_space" type="vector3" nodedef="ND_normalize_vector3">
    <input name="in" type="vector3" nodename="subtract" />
  </normalize>
  <normalmap name="bound_normal" type="vector3" nodedef="ND_normalmap_float">
    <input name="in" type="vector3" nodename="img" />
    <input name="normal" type="vector3" nodename="n" />
    <input name="bitangent" type="vector3" nodename="normalmap_cross_norm" />
  </normalmap>
  <normalmap name="plain" type="vector3">
    <input name="in" type="vector3" nodename="img" />
    <input name="scale" type="float" value="1.1" />
  </normalmap>
  <multiply name="multiply" type="vector3">
    <input name="in1" type="vector3" nodename="img" />
    <input name="in2" type="float" value="2" />
  </multiply>
  <subtract name="subtract" type="vector3">
    <input name="in1" type="vector3" nodename="multiply" />
    <input name="in2" type="float" value="1" />
  </subtract>
  <crossproduct name="normalmap_cross" type="vector3">
    <input name="in1" type="vector3" nodename="n" />
    <input name="in2" type="vector3" nodename="normalmap_tangent" />
  </crossproduct>
  <tangent name="normalmap_tangent" type="vector3">
    <input name="space" type="string" value="world" />
  </tangent>
  <normalize name="normalmap_cross_norm" type="vector3">
    <input name="in" type="vector3" nodename="normalmap_cross" />
  </normalize>
</materialx>"#,
    );
}

#[test]
fn v1_38_switch_atan2_subsurface_and_double_bindings() {
    let (doc, diags) = upgrade(
        r#"<materialx version="1.38">
  <constant name="k" type="float" />
  <switch name="sw_int" type="float">
    <input name="which" type="integer" value="7" />
  </switch>
  <switch name="sw_float" type="float">
    <input name="which" type="float" value="3" />
  </switch>
  <switch name="sw_high" type="float">
    <input name="which" type="float" value="5.5" />
  </switch>
  <switch name="sw_connected" type="float">
    <input name="which" type="float" nodename="k" />
  </switch>
  <atan2 name="at" type="float">
    <input name="in1" type="float" value="1" />
    <input name="in2" type="float" value="2" />
  </atan2>
  <subsurface_bsdf name="sss" type="BSDF">
    <input name="radius" type="vector3" value="1, 0.5, 0.25" />
  </subsurface_bsdf>
  <add name="both" type="float">
    <input name="in1" type="float" value="3" nodename="k" />
    <input name="in2" type="float" value="4" />
  </add>
  <nodedef name="ND_keep" node="keep">
    <input name="in" type="float" value="1" />
    <output name="out" type="float" />
  </nodedef>
</materialx>"#,
    );
    assert_eq!(
        lines(&diags),
        ["13:5: warning: `which` of switch `sw_connected` is connected: where it reaches 5 or more, 1.38 fell back to in1 while \
          1.39 selects in6..in10 (unset here)"]
    );
    assert_doc(
        &doc,
        r#"<materialx version="1.39">
  <constant name="k" type="float" />
  <switch name="sw_int" type="float">
    <input name="which" type="integer" value="0" />
  </switch>
  <switch name="sw_float" type="float">
    <input name="which" type="float" value="3" />
  </switch>
  <switch name="sw_high" type="float">
    <input name="which" type="float" value="0" />
  </switch>
  <switch name="sw_connected" type="float">
    <input name="which" type="float" nodename="k" />
  </switch>
  <atan2 name="at" type="float">
    <input name="iny" type="float" value="1" />
    <input name="inx" type="float" value="2" />
  </atan2>
  <subsurface_bsdf name="sss" type="BSDF">
    <input name="radius" type="color3" nodename="convert" />
  </subsurface_bsdf>
  <add name="both" type="float">
    <input name="in1" type="float" nodename="k" />
    <input name="in2" type="float" value="4" />
  </add>
  <nodedef name="ND_keep" node="keep">
    <input name="in" type="float" value="1" />
    <output name="out" type="float" />
  </nodedef>
  <convert name="convert" type="color3">
    <input name="in" type="vector3" value="1, 0.5, 0.25" />
  </convert>
</materialx>"#,
    );
}

// ---------------------------------------------------------------------------------------------
// Positions and robustness
// ---------------------------------------------------------------------------------------------

#[test]
fn created_elements_take_the_position_of_their_source() {
    let text = "<materialx version=\"1.37\">\n\
                <image name=\"img\" type=\"color3\" />\n\
                <add name=\"a\" type=\"color3\">\n\
                  <input name=\"in1\" type=\"color3\" nodename=\"img\" channels=\"bgr\" />\n\
                </add>\n\
                <nodegraph name=\"g\">\n\
                  <dielectric_brdf name=\"coat\" type=\"BSDF\"><input name=\"base\" type=\"BSDF\" nodename=\"d\" /></dielectric_brdf>\n\
                  <diffuse_brdf name=\"d\" type=\"BSDF\" />\n\
                </nodegraph>\n\
                <material name=\"M\">\n\
                  <shaderref name=\"SR\" node=\"standard_surface\" />\n\
                </material>\n\
                </materialx>";
    let (doc, diags) = upgrade(text);
    assert_no_diagnostics(&diags);
    let at = |name: &str| {
        let p = &doc.get(find(&doc, name)).pos;
        (p.line, p.column)
    };
    // The swizzle made from `channels` sits where the input was; the nodes it becomes too.
    assert_eq!(at("swizzle"), (4, 1));
    assert_eq!(at("separate"), (4, 1));
    let swizzle_inputs: Vec<(u32, u32)> =
        doc.children(find(&doc, "swizzle")).iter().map(|&i| (doc.get(i).pos.line, doc.get(i).pos.column)).collect();
    assert!(swizzle_inputs.iter().all(|&p| p == (4, 1)), "{swizzle_inputs:?}");
    // The layer made from `base` sits where the BSDF was.
    assert_eq!(doc.get(find(&doc, "coat")).category, "layer");
    assert_eq!(at("coat"), (7, 1));
    assert_eq!(at("coat__layer_top"), (7, 1));
    // The shader node sits where the shaderref was, the material node where the material was.
    assert_eq!(at("SR"), (11, 1));
    assert_eq!(at("M"), (10, 1));
    for e in doc.descendants(doc.root()) {
        assert!(doc.get(e).pos.line > 0, "{} has no position", doc.get(e).name());
        assert_eq!(&*doc.get(e).pos.file, "upgrade_test.mtlx");
    }
}

#[test]
fn odd_legacy_documents_upgrade_without_panicking() {
    let docs = [
        // Compare without inputs, combine/separate without inputs, an empty swizzle.
        r#"<materialx version="1.36"><compare name="c" type="float" /><combine name="x" type="color3" /><separate name="s" type="multioutput" /><swizzle name="z" type="color3" /></materialx>"#,
        // Nodes connected in a cycle, with channels on the cycle.
        r#"<materialx version="1.38"><add name="a" type="color3"><input name="in1" type="color3" nodename="b" channels="rgb" /></add><add name="b" type="color3"><input name="in1" type="color3" nodename="a" channels="bgr" /></add></materialx>"#,
        // Dangling references everywhere.
        r#"<materialx version="1.37"><dielectric_brdf name="d" type="BSDF"><input name="base" type="BSDF" nodename="nowhere" /></dielectric_brdf><conductor_brdf name="c" type="BSDF" /><material name="m"><shaderref name="s" nodedef="ND_nowhere" /><bindinput name="stray" /></material></materialx>"#,
        // A layer whose inputs are missing, a thin film with no base, channels on a nodedef input.
        r#"<materialx version="1.38"><layer name="l" type="BSDF" /><thin_film_bsdf name="t" type="BSDF" /><layer name="l2" type="BSDF"><input name="top" type="BSDF" nodename="t" /></layer><nodedef name="ND" node="x"><input name="i" type="color3" channels="rrr" /></nodedef></materialx>"#,
        // Outputs with channels and a nodegraph reference that does not exist.
        r#"<materialx version="1.38"><nodegraph name="g"><output name="o" type="color3" nodegraph="missing" channels="rgb" /></nodegraph><surface name="s" type="surfaceshader"><input name="bsdf" type="BSDF" nodegraph="missing" output="x" channels="r" /></surface></materialx>"#,
        // Elements without names; parameters at odd places; a 1.22 output parameter without value.
        r#"<materialx version="1.22"><opgraph><output><parameter name="in" type="opgraphnode" /></output><constant><parameter name="color" /></constant></opgraph><shader /><material><shaderref /></material></materialx>"#,
        // Normalmap with a connected space, switch with unreadable which.
        r#"<materialx version="1.38"><normalmap name="n" type="vector3"><input name="space" type="string" interfacename="sp" /></normalmap><switch name="s" type="float"><input name="which" type="integer" value="many" /></switch></materialx>"#,
    ];
    for text in docs {
        let (doc, _diags) = upgrade(text);
        assert_eq!(doc.get(doc.root()).attr("version"), Some("1.39"), "{text}");
        // Whatever came out is writable and reads back unchanged.
        let written = write_string(&doc);
        let (again, _) = read_str(&written, "again.mtlx");
        assert!(doc.same_content(&again), "{written}");
    }
}
