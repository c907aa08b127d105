//! Parsing MaterialX value strings (`"1, 0.5, 0"`, `"true"`, `"3"`) into typed values,
//! locale-independently, with an error message naming the type on bad text.

use crate::types::DataType;

/// A parsed value. Numeric types keep their components as f32 (row-major for matrices),
/// except booleans and integers which keep their exact value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Boolean(bool),
    Integer(i32),
    Floats(Vec<f32>),
    String(String),
}

impl Value {
    /// Parses `text` as a value of type `ty`.
    pub fn parse(ty: &DataType, text: &str) -> Result<Value, String> {
        let text = text.trim();
        match ty {
            DataType::Boolean => match text {
                "true" => Ok(Value::Boolean(true)),
                "false" => Ok(Value::Boolean(false)),
                _ => Err(format!("`{text}` is not a boolean (true or false)")),
            },
            DataType::Integer => text
                .parse::<i32>()
                .map(Value::Integer)
                .map_err(|_| format!("`{text}` is not an integer")),
            DataType::String | DataType::Filename => Ok(Value::String(text.to_string())),
            t if t.is_numeric() => {
                let n = t.components().unwrap();
                // MaterialX separates components by commas and/or spaces ("1, 2", "1 2").
                let parts: Vec<&str> = text.split([',', ' ', '\t', '\n']).filter(|p| !p.is_empty()).collect();
                let parsed: Result<Vec<f32>, _> = parts.iter().map(|p| p.parse::<f32>()).collect();
                match parsed {
                    // MaterialX reads components with the C++ stream operators, which reject
                    // `nan` and `inf` (Rust's parser accepts them) and values beyond f32's range.
                    Ok(v) if v.iter().any(|x| !x.is_finite()) => {
                        let bad = parts.iter().zip(&v).find(|(_, x)| !x.is_finite()).map_or("", |(p, _)| *p);
                        Err(format!("`{text}` is not a {t} value: `{bad}` is not a finite number"))
                    }
                    Ok(v) if v.len() == n => Ok(Value::Floats(v)),
                    Ok(v) if v.is_empty() => Ok(Value::Floats(vec![0.0; n])),
                    Ok(v) => Err(format!("`{text}` has {} components; {t} needs {n}", v.len())),
                    Err(_) => Err(format!("`{text}` is not a {t} value")),
                }
            }
            t => Err(format!("values of type {t} are not supported")),
        }
    }

    /// The value's numeric components as f32 (booleans 0/1); empty for strings.
    pub fn components(&self) -> Vec<f32> {
        match self {
            Value::Boolean(b) => vec![if *b { 1.0 } else { 0.0 }],
            Value::Integer(i) => vec![*i as f32],
            Value::Floats(v) => v.clone(),
            Value::String(_) => Vec::new(),
        }
    }

    /// The value written back in MaterialX syntax.
    pub fn to_mtlx_string(&self) -> String {
        match self {
            Value::Boolean(b) => b.to_string(),
            Value::Integer(i) => i.to_string(),
            Value::Floats(v) => v.iter().map(|x| format_float(*x)).collect::<Vec<_>>().join(", "),
            Value::String(s) => s.clone(),
        }
    }
}

/// Shortest text that reads back as the same f32.
pub fn format_float(x: f32) -> String {
    let s = format!("{x}");
    if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}
