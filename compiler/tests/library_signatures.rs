//! Every atomic nodedef of the stdlib categories uplift implements has a WGSL function whose
//! signature matches what the nodedef implies (mtlx/libraries/README.md rules 1–5), and every
//! WGSL function named after a nodedef matches it. Nodedefs without WGSL are listed with the
//! reason, so a missing implementation fails here rather than at a user's node.

use uplift_compiler::node_library::NodeLibrary;
use uplift_compiler::Compiler;

/// Node categories the issue asks for (math, channel, conditional, geometric, texture,
/// procedural, adjustment, compositing).
const REQUIRED: &[&str] = &[
    "absval", "acos", "add", "asin", "atan2", "ceil", "clamp", "cos", "creatematrix", "crossproduct", "determinant",
    "divide", "dotproduct", "exp", "floor", "fract", "invert", "invertmatrix", "ln", "magnitude", "max", "min", "modulo",
    "multiply", "normalize", "normalmap", "power", "rotate2d", "rotate3d", "round", "sign", "sin", "sqrt", "subtract",
    "tan", "transformmatrix", "transformpoint", "transformvector", "transformnormal", "transpose", "convert", "combine2",
    "combine3", "combine4", "extract", "ifgreater", "ifgreatereq", "ifequal", "and", "or", "not", "position", "normal",
    "tangent", "bitangent", "texcoord", "image", "constant", "ramplr", "ramptb", "splitlr", "splittb", "noise2d",
    "noise3d", "fractal3d", "cellnoise2d", "cellnoise3d", "worleynoise2d", "worleynoise3d", "remap", "smoothstep",
    "luminance", "rgbtohsv", "hsvtorgb", "mix", "premult", "unpremult", "plus", "minus", "dot",
];

/// Atomic nodedefs of those categories with no WGSL function, and why.
const WITHOUT_WGSL: &[(&str, &str)] = &[
    ("ND_constant_string", "string value: compile-time only"),
    ("ND_constant_filename", "filename value: a texture binding, not a WGSL value"),
    ("ND_dot_string", "string pass-through: folded at compile time (defaultinput)"),
    ("ND_dot_filename", "filename pass-through: folded at compile time (defaultinput)"),
    ("ND_mix_surfaceshader", "shader type: closures are issue 4"),
    ("ND_mix_displacementshader", "shader type"),
    ("ND_mix_volumeshader", "shader type"),
    ("ND_dot_surfaceshader", "shader type"),
    ("ND_dot_displacementshader", "shader type"),
    ("ND_dot_volumeshader", "shader type"),
    ("ND_dot_lightshader", "shader type"),
    ("ND_mix_edf", "EDF: uplift's kernels evaluate surface scattering only"),
    ("ND_mix_vdf", "VDF: uplift's kernels evaluate surface scattering only"),
    ("ND_add_edf", "EDF: uplift's kernels evaluate surface scattering only"),
    ("ND_add_vdf", "VDF: uplift's kernels evaluate surface scattering only"),
    ("ND_multiply_edfC", "EDF: uplift's kernels evaluate surface scattering only"),
    ("ND_multiply_edfF", "EDF: uplift's kernels evaluate surface scattering only"),
    ("ND_multiply_vdfC", "VDF: uplift's kernels evaluate surface scattering only"),
    ("ND_multiply_vdfF", "VDF: uplift's kernels evaluate surface scattering only"),
];

#[test]
fn atomic_nodedefs_have_matching_wgsl() {
    let c = Compiler::builtin();
    let lib = &c.library;
    assert!(lib.diagnostics.is_empty(), "library diagnostics: {:?}", lib.diagnostics);
    let mut problems = Vec::new();
    let mut checked = 0;
    for nd in lib.atomic_nodedefs() {
        let has_fn = lib.function(&nd.name).is_some();
        let required = REQUIRED.contains(&nd.node.as_str());
        let excused = WITHOUT_WGSL.iter().any(|(n, _)| *n == nd.name);
        match (has_fn, required, excused) {
            (true, _, true) => problems.push(format!("{}: listed as without WGSL but has `{}`", nd.name, NodeLibrary::function_name(&nd.name))),
            (true, _, false) => match lib.check_signature(nd) {
                Ok(()) => checked += 1,
                Err(m) => problems.push(m),
            },
            (false, true, false) => problems.push(format!("{}: required category `{}` but no WGSL `{}`", nd.name, nd.node, NodeLibrary::function_name(&nd.name))),
            _ => {}
        }
    }
    assert!(problems.is_empty(), "{} problems:\n{}", problems.len(), problems.join("\n"));
    assert!(checked >= 400, "only {checked} signatures checked");
}
