//! The one table mapping MaterialX data types to WGSL types (mtlx/libraries/README.md, rule 3),
//! and the WGSL literal syntax for constant values.

use mtlx::{DataType, Value};

/// The WGSL type of a value of MaterialX type `ty` as a function parameter or result.
/// `has_enum` says a string input carries an `enum` list (it is then passed as its index).
pub fn wgsl_type(ty: &DataType, has_enum: bool) -> Option<&'static str> {
    Some(match ty {
        DataType::Boolean => "bool",
        DataType::Integer => "i32",
        DataType::Float => "f32",
        DataType::Vector2 => "vec2<f32>",
        DataType::Vector3 | DataType::Color3 => "vec3<f32>",
        DataType::Vector4 | DataType::Color4 => "vec4<f32>",
        DataType::Matrix33 => "mat3x3<f32>",
        DataType::Matrix44 => "mat4x4<f32>",
        DataType::String if has_enum => "i32",
        DataType::Filename => "texture_2d<f32>",
        DataType::Closure(name) => closure_type(name)?.0,
        _ => return None,
    })
}

/// (WGSL type, WGSL expression of the empty value) of a closure or shader type
/// (pbrlib/wgsl/closure.wgsl): a BSDF is a `BSDF` value; surface shaders and materials (a
/// material's value is its front surface shader) are `mx_surfaceshader` values, a BSDF and the
/// radiance emitted.
pub fn closure_type(name: &str) -> Option<(&'static str, &'static str)> {
    Some(match name {
        "BSDF" => ("BSDF", "mx_bsdf_empty()"),
        "surfaceshader" | "material" => ("mx_surfaceshader", "mx_surfaceshader_empty()"),
        "EDF" => ("EDF", "EDF(vec3<f32>(0.0))"),
        "VDF" => ("VDF", "VDF(vec3<f32>(0.0), vec3<f32>(0.0))"),
        "volumeshader" => ("mx_volumeshader", "mx_volumeshader(VDF(vec3<f32>(0.0), vec3<f32>(0.0)))"),
        "displacementshader" => ("mx_displacementshader", "mx_displacementshader(vec3<f32>(0.0))"),
        "lightshader" => ("mx_lightshader", "mx_lightshader(vec3<f32>(0.0))"),
        _ => return None,
    })
}

/// Whether a closure kernel can be compiled for a value of type `ty`: it scatters (a BSDF, a
/// surface shader or a material).
pub fn is_scattering(ty: &DataType) -> bool {
    matches!(wgsl_type(ty, false), Some("BSDF" | "mx_surfaceshader"))
}

/// Whether a value of type `ty` carries emission besides its BSDF (surface shaders, materials):
/// its closure kernels write an `emission` output too.
pub fn has_emission(ty: &DataType) -> bool {
    wgsl_type(ty, false) == Some("mx_surfaceshader")
}

/// A WGSL float literal that reads back as exactly `x`.
pub fn float_literal(x: f32) -> String {
    if x.is_nan() || x.is_infinite() {
        // WGSL has no literals for these; they only arise from bad input values, which the
        // value parser rejects, so a neutral 0 is never reached in practice.
        return "0.0".into();
    }
    let s = format!("{x:?}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

/// A WGSL expression for a constant of MaterialX type `ty`.
pub fn constant_expr(ty: &DataType, value: &Value) -> Option<String> {
    let comps = value.components();
    let list = |v: &[f32]| v.iter().map(|x| float_literal(*x)).collect::<Vec<_>>().join(", ");
    Some(match (ty, value) {
        (DataType::Boolean, Value::Boolean(b)) => b.to_string(),
        (DataType::Integer, Value::Integer(i)) => format!("i32({i})"),
        (DataType::Float, _) => float_literal(*comps.first()?),
        (t, _) if t.is_numeric() => format!("{}({})", wgsl_type(t, false)?, list(&comps)),
        (DataType::Closure(name), _) => closure_type(name)?.1.to_string(),
        _ => return None,
    })
}
