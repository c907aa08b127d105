//! MaterialX data types by name: which are numeric, their component counts, which are
//! closures or shaders.

/// A MaterialX data type, as written in `type` attributes.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum DataType {
    Boolean,
    Integer,
    Float,
    Vector2,
    Vector3,
    Vector4,
    Color3,
    Color4,
    Matrix33,
    Matrix44,
    String,
    Filename,
    /// Closure and shader types: BSDF, EDF, VDF, surfaceshader, volumeshader,
    /// displacementshader, lightshader, material.
    Closure(std::string::String),
    /// The `type` of a node with several outputs.
    Multioutput,
    /// Anything else (arrays, struct typedefs, unknown names).
    Other(std::string::String),
}

const CLOSURE_TYPES: [&str; 8] =
    ["BSDF", "EDF", "VDF", "surfaceshader", "volumeshader", "displacementshader", "lightshader", "material"];

impl DataType {
    pub fn from_name(name: &str) -> DataType {
        match name {
            "boolean" => DataType::Boolean,
            "integer" => DataType::Integer,
            "float" => DataType::Float,
            "vector2" => DataType::Vector2,
            "vector3" => DataType::Vector3,
            "vector4" => DataType::Vector4,
            "color3" => DataType::Color3,
            "color4" => DataType::Color4,
            "matrix33" => DataType::Matrix33,
            "matrix44" => DataType::Matrix44,
            "string" => DataType::String,
            "filename" => DataType::Filename,
            "multioutput" => DataType::Multioutput,
            n if CLOSURE_TYPES.contains(&n) => DataType::Closure(n.to_string()),
            n => DataType::Other(n.to_string()),
        }
    }

    pub fn name(&self) -> &str {
        match self {
            DataType::Boolean => "boolean",
            DataType::Integer => "integer",
            DataType::Float => "float",
            DataType::Vector2 => "vector2",
            DataType::Vector3 => "vector3",
            DataType::Vector4 => "vector4",
            DataType::Color3 => "color3",
            DataType::Color4 => "color4",
            DataType::Matrix33 => "matrix33",
            DataType::Matrix44 => "matrix44",
            DataType::String => "string",
            DataType::Filename => "filename",
            DataType::Multioutput => "multioutput",
            DataType::Closure(n) | DataType::Other(n) => n,
        }
    }

    /// Number of scalar components of a numeric type (booleans and integers count 1);
    /// `None` for strings, filenames, closures and others.
    pub fn components(&self) -> Option<usize> {
        Some(match self {
            DataType::Boolean | DataType::Integer | DataType::Float => 1,
            DataType::Vector2 => 2,
            DataType::Vector3 | DataType::Color3 => 3,
            DataType::Vector4 | DataType::Color4 => 4,
            DataType::Matrix33 => 9,
            DataType::Matrix44 => 16,
            _ => return None,
        })
    }

    pub fn is_numeric(&self) -> bool {
        self.components().is_some()
    }

    pub fn is_closure(&self) -> bool {
        matches!(self, DataType::Closure(_))
    }

    pub fn is_color(&self) -> bool {
        matches!(self, DataType::Color3 | DataType::Color4)
    }

    /// Suffixes naming each component in CSV columns and dumps: `_x/_y/_z/_w` for vectors,
    /// `_r/_g/_b/_a` for colors, `_0 …` for matrices, none for scalars.
    pub fn component_suffixes(&self) -> Vec<std::string::String> {
        let n = self.components().unwrap_or(0);
        match self {
            DataType::Color3 | DataType::Color4 => ["_r", "_g", "_b", "_a"][..n].iter().map(|s| s.to_string()).collect(),
            DataType::Vector2 | DataType::Vector3 | DataType::Vector4 => {
                ["_x", "_y", "_z", "_w"][..n].iter().map(|s| s.to_string()).collect()
            }
            DataType::Matrix33 | DataType::Matrix44 => (0..n).map(|i| format!("_{i}")).collect(),
            _ => vec![std::string::String::new()],
        }
    }
}

impl std::fmt::Display for DataType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
