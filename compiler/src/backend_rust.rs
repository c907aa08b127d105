//! The naga → Rust writer: walks a validated naga `Module` (the same one naga's WGSL writer
//! turns into the WGSL kernel) and writes Rust source with WGSL semantics, so that the CPU
//! engine runs exactly the node library's WGSL. Besides lowering, this is the only module that
//! touches naga's IR.
//!
//! What it owns:
//! - types: `f32`/`i32`/`u32`/`bool`, glam `Vec2`–`Vec4`, `IVec*`, `UVec*`, `BVec*`,
//!   `Mat2`–`Mat4` (never `Vec3A`: it does not vectorise across samples), fixed-size arrays, and
//!   every struct type as a `#[derive(Clone, Copy, Debug, Default, PartialEq)]` struct (note:
//!   glam's `Default` for matrices is the identity; the generated code never relies on
//!   `Default`, zero values are written out);
//! - every non-entry-point function as an `#[inline(always)] pub fn` (the CPU kernel shape in
//!   ARCHITECTURE.md: a call left in the batch loop stops vectorisation); module constants as
//!   `pub const`;
//! - WGSL semantics where Rust differs: wrapping integer arithmetic, `x / 0 == x` and
//!   `x % 0 == 0` for integers, float `%` as `a - b * trunc(a / b)`, `round` to even, saturating
//!   float → integer casts, `clamp` as `min(max(x, lo), hi)` (never panics), `sign(0) == 0`,
//!   `fract(x) == x - floor(x)`, shifts by the amount modulo the bit width, dynamic indices
//!   clamped into range (never a panic);
//! - textures: `texture_2d<f32>` values become a `usize` texture index (a global
//!   `@binding(4 + K)` is index K); `textureLoad` and `textureDimensions` go through the
//!   `MxTextures` trait that the runtime implements, passed as a first `tex` parameter to every
//!   function that reads a texture (directly or through a call);
//! - the batch entry point of a pattern kernel (`write_rust_kernel`, askama template
//!   `templates/pattern_kernel.rs`): a tight loop over structure-of-arrays slices that calls
//!   `mx_pattern` once per point; the compute entry point and its buffers are not written.
//!
//! Operations whose Rust form is not a single glam method are written through small private
//! helpers (`wgsl_*`), lane by lane, emitted once per file and only when used. Anything outside
//! this subset (pointers as arguments, private globals, samplers, atomics, derivatives, …) is a
//! [`RustError`] naming the construct; the writer never panics.

use crate::kernel::{PatternKernel, BINDING_FIRST_TEXTURE, GEOMETRY_LAYOUT, GEOMETRY_STRIDE};
use crate::node_library::TABLE_DATA;
use askama::Template;
use mtlx::DataType;
use naga::proc::{CaseInsensitiveKeywordSet, KeywordSet, NameKey, Namer};
use naga::valid::{FunctionInfo, ModuleInfo};
use naga::{
    BinaryOperator as Bo, Expression as E, Function, Handle, ImageClass, ImageDimension, Literal, MathFunction as Mf,
    Module, RelationalFunction, Scalar, ScalarKind, Statement as S, TypeInner, UnaryOperator, VectorSize,
};
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::fmt::{self, Write as _};
use std::sync::OnceLock;

/// How the Rust is written.
#[derive(Clone, Debug)]
pub struct RustOptions {
    /// A path (for instance `crate::MxTextures`) of a texture trait that the generated code uses
    /// instead of declaring its own `MxTextures` (same methods). `None` declares the trait in
    /// the generated module.
    pub textures_trait: Option<String>,
    /// The binding of texture index 0 (group 0); a global texture at binding `b` is index
    /// `b - first_texture_binding`.
    pub first_texture_binding: u32,
    /// A path (for instance `crate::MX_ALBEDO_TABLE_DATA`) of a `static [f32; N]` holding the
    /// library's albedo tables (`node_library::TABLE_DATA`), which a kernel reading them then
    /// uses instead of writing its own copy of the array: a crate that ships many BSDF kernels
    /// holds the tables once ([`write_albedo_table_static`] writes that static). `None` writes
    /// the array into the module as a constant.
    pub albedo_table_data: Option<String>,
}

impl Default for RustOptions {
    fn default() -> Self {
        RustOptions { textures_trait: None, first_texture_binding: BINDING_FIRST_TEXTURE, albedo_table_data: None }
    }
}

/// IR the Rust writer cannot express: names the construct (and the function it sits in).
#[derive(Clone, Debug, PartialEq)]
pub struct RustError {
    pub construct: String,
    pub function: Option<String>,
}

impl fmt::Display for RustError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the Rust backend does not support {}", self.construct)?;
        if let Some(func) = &self.function {
            write!(f, " (in function `{func}`)")?;
        }
        Ok(())
    }
}

impl std::error::Error for RustError {}

type R<T> = Result<T, RustError>;

fn unsupported(what: impl Into<String>) -> RustError {
    RustError { construct: what.into(), function: None }
}

/// The naga version whose IR this writer reads (pinned in the workspace).
pub(crate) const NAGA_VERSION: &str = "30.0.1";

/// The texture trait the generated code calls (declared unless `RustOptions::textures_trait`).
const TEXTURES_TRAIT: &str = "/// Textures of a kernel, by index (binding − 4 in the WGSL kernel), implemented by the runtime.
/// Coordinates are texel indices and may lie outside the texture: return zero there, as
/// wgpu's robust access does. A missing texture has dimensions (0, 0).
pub trait MxTextures {
    /// The texel at column `x`, row `y` (row 0 is the first row of the image) of mip level 0.
    fn load(&self, texture: usize, x: i32, y: i32) -> Vec4;
    /// Width and height of mip level 0.
    fn dimensions(&self, texture: usize) -> UVec2;
}
";

/// Identifiers naga names must not take: Rust keywords, primitive and glam type names, and the
/// names the writer and the kernel template use themselves (a naga name equal to one of these
/// gets a trailing `_`, as `in` → `in_`).
pub(crate) const RESERVED: &[&str] = &[
    // Rust keywords (strict, reserved, and weak ones that cannot be plain identifiers).
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for", "if", "impl", "in",
    "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return", "self", "Self", "static", "struct", "super",
    "trait", "true", "type", "unsafe", "use", "where", "while", "async", "await", "dyn", "abstract", "become", "box",
    "do", "final", "macro", "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "gen", "union",
    "macro_rules", "raw", "safe", // primitive types
    "bool", "char", "str", "f32", "f64", "i8", "i16", "i32", "i64", "i128", "isize", "u8", "u16", "u32", "u64",
    "u128", "usize", // std prelude names a type or value could shadow
    "Option", "Some", "None", "Result", "Ok", "Err", "Default", "Clone", "Copy", "Debug", "PartialEq", "Vec",
    "String", "Box", "core", "std", "glam", // glam names the generated code uses
    "Vec2", "Vec3", "Vec4", "IVec2", "IVec3", "IVec4", "UVec2", "UVec3", "UVec4", "BVec2", "BVec3", "BVec4", "BVec4A", "Mat2",
    "Mat3", "Mat4", // the writer's and the template's own names
    "MxTextures", "tex", "GEOMETRY_COLUMNS", "INPUT_COLUMNS", "OUTPUT_COLUMNS", "TEXTURE_COUNT", "INPUTS",
    "OUTPUTS", "mx_pattern_batch", "mx_n", "mx_i", "mx_geom", "mx_inputs", "mx_out",
];

pub(crate) fn reserved_set() -> &'static KeywordSet {
    static SET: OnceLock<KeywordSet> = OnceLock::new();
    SET.get_or_init(|| KeywordSet::from_iter(RESERVED))
}

/// The scalar conversion of one lane: the lane's expression in, the converted one out.
type LaneConversion = Box<dyn Fn(&str) -> (String, Prec)>;

/// Operator precedence of a written expression (higher binds tighter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Prec {
    /// `if … { … } else { … }` and blocks: parenthesised anywhere but a full expression slot.
    Lowest,
    Or,
    And,
    Cmp,
    BitOr,
    BitXor,
    BitAnd,
    Shift,
    Add,
    Mul,
    Cast,
    Unary,
    Atom,
}

/// A written expression and its precedence.
#[derive(Clone, Debug)]
struct Ex {
    s: String,
    p: Prec,
}

impl Ex {
    fn new(s: impl Into<String>, p: Prec) -> Ex {
        Ex { s: s.into(), p }
    }
    fn atom(s: impl Into<String>) -> Ex {
        Ex::new(s, Prec::Atom)
    }
    /// The text, parenthesised when it binds looser than `need`.
    fn at(&self, need: Prec) -> String {
        if self.p < need {
            format!("({})", self.s)
        } else {
            self.s.clone()
        }
    }
}

/// Whether `s` is a plain place path (`a`, `a.b.c`): cheap to repeat in a lane-wise form.
fn is_path(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.')
        && !s.contains("..")
}

const LANES: [&str; 4] = ["x", "y", "z", "w"];

fn vsize(size: VectorSize) -> usize {
    size as usize
}

/// The Rust name of a scalar type.
fn scalar_name(s: Scalar) -> R<&'static str> {
    Ok(match (s.kind, s.width) {
        (ScalarKind::Float, 4) => "f32",
        (ScalarKind::Sint, 4) => "i32",
        (ScalarKind::Uint, 4) => "u32",
        (ScalarKind::Bool, _) => "bool",
        (ScalarKind::AbstractInt | ScalarKind::AbstractFloat, _) => return Err(unsupported("abstract numeric types")),
        (k, w) => return Err(unsupported(format!("{k:?} scalars of {} bits", w * 8))),
    })
}

/// The glam prefix of vectors of `s` (`""`, `I`, `U`, `B`).
fn vector_prefix(s: Scalar) -> R<&'static str> {
    Ok(match scalar_name(s)? {
        "f32" => "",
        "i32" => "I",
        "u32" => "U",
        _ => "B",
    })
}

/// The zero of a scalar type, as a Rust literal.
fn scalar_zero(s: Scalar) -> R<&'static str> {
    Ok(match scalar_name(s)? {
        "f32" => "0.0f32",
        "i32" => "0i32",
        "u32" => "0u32",
        _ => "false",
    })
}

/// A Rust literal for `l`, with its precedence (negative numbers are unary expressions).
fn literal(l: &Literal) -> R<Ex> {
    let num = |s: String| if s.starts_with('-') { Ex::new(s, Prec::Unary) } else { Ex::atom(s) };
    Ok(match *l {
        Literal::F32(v) if v.is_nan() => Ex::atom("f32::NAN"),
        Literal::F32(v) if v.is_infinite() => {
            if v > 0.0 {
                Ex::atom("f32::INFINITY")
            } else {
                Ex::atom("f32::NEG_INFINITY")
            }
        }
        Literal::F32(v) => {
            let s = format!("{v:?}");
            num(if s.contains('.') || s.contains('e') { format!("{s}f32") } else { format!("{s}.0f32") })
        }
        Literal::I32(v) => num(format!("{v}i32")),
        Literal::U32(v) => Ex::atom(format!("{v}u32")),
        Literal::Bool(b) => Ex::atom(b.to_string()),
        ref other => return Err(unsupported(format!("the literal {other:?}"))),
    })
}

/// A literal integer value, if `e` is one.
fn literal_int(e: &E) -> Option<i64> {
    match *e {
        E::Literal(Literal::I32(v)) => Some(v as i64),
        E::Literal(Literal::U32(v)) => Some(v as i64),
        _ => None,
    }
}

/// Whether a `Statement::Break` in `block` (not nested in a loop or switch) targets the
/// enclosing switch; a trailing break of the case body itself is excluded by the caller.
fn block_breaks(block: &naga::Block) -> bool {
    block.iter().any(|s| match s {
        S::Break => true,
        S::Block(b) => block_breaks(b),
        S::If { accept, reject, .. } => block_breaks(accept) || block_breaks(reject),
        _ => false,
    })
}

/// Whether a `Statement::Continue` of the enclosing loop occurs in `block` (inside ifs, blocks
/// and switches; a nested loop's own `continue`s do not count).
fn block_continues(block: &naga::Block) -> bool {
    block.iter().any(|s| match s {
        S::Continue => true,
        S::Block(b) => block_continues(b),
        S::If { accept, reject, .. } => block_continues(accept) || block_continues(reject),
        S::Switch { cases, .. } => cases.iter().any(|c| block_continues(&c.body)),
        _ => false,
    })
}

/// One entry of the breakable-construct stack while writing a function body.
enum Breakable {
    /// A loop; `label` is set once a `break`/`continue` inside a labelled switch needs it.
    Loop { label: String, used: bool },
    /// A switch written inside a labelled block (its inner `break`s leave the block).
    Switch { label: Option<String> },
}

/// Per-function state.
struct FnCtx<'m> {
    handle: Option<Handle<Function>>,
    func: &'m Function,
    info: &'m FunctionInfo,
    /// Names of expressions bound by `let`, in scope now.
    baked: HashMap<Handle<E>, String>,
    /// Handles baked per open block, to drop them when the block closes.
    scopes: Vec<Vec<Handle<E>>>,
    /// Expressions covered by `Emit` statements (the others are written where used).
    emitted: HashSet<Handle<E>>,
    /// Whether this function takes the `tex` parameter.
    tex: bool,
    breakables: Vec<Breakable>,
}

/// Names and signature facts the kernel template needs.
struct ModuleFacts {
    /// Rust type names by naga type name (structs).
    struct_names: HashMap<String, (Handle<naga::Type>, String)>,
    names: HashMap<NameKey, String>,
    needs_tex: Vec<bool>,
}

struct Writer<'m> {
    module: &'m Module,
    info: &'m ModuleInfo,
    options: &'m RustOptions,
    names: HashMap<NameKey, String>,
    namer: Namer,
    /// Helper functions by name.
    helpers: BTreeMap<String, String>,
    /// glam items the text uses.
    glam: BTreeSet<String>,
    /// Per function: takes the `tex` parameter.
    needs_tex: Vec<bool>,
    /// Whether anything reads a texture.
    any_texture: bool,
}

/// Writes `module` as Rust source (see the module documentation). The text starts with a
/// header line; `info` must be the validation info of `module`.
pub fn write_rust(module: &Module, info: &ModuleInfo, options: &RustOptions) -> Result<String, RustError> {
    let (body, _) = write_module(module, info, options, false)?;
    Ok(format!(
        "// Generated by uplift (writer: uplift_compiler::backend_rust from a naga {NAGA_VERSION} module). Do not edit.\n{body}\n"
    ))
}

/// Writes the module body (no header line) and returns the facts the kernel template needs.
fn write_module(module: &Module, info: &ModuleInfo, options: &RustOptions, force_trait: bool) -> R<(String, ModuleFacts)> {
    let mut names = naga::FastHashMap::default();
    let mut namer = Namer::default();
    namer.reset(module, reserved_set(), KeywordSet::empty(), CaseInsensitiveKeywordSet::empty(), &["_e", "wgsl_"], &mut names);
    let mut w = Writer {
        module,
        info,
        options,
        names: names.into_iter().collect(),
        namer,
        helpers: BTreeMap::new(),
        glam: BTreeSet::new(),
        needs_tex: Vec::new(),
        any_texture: false,
    };
    let body = w.write_all(force_trait)?;
    let facts = ModuleFacts {
        struct_names: module
            .types
            .iter()
            .filter(|(_, t)| matches!(t.inner, TypeInner::Struct { .. }))
            .filter_map(|(h, t)| Some((t.name.clone()?, (h, w.names[&NameKey::Type(h)].clone()))))
            .collect(),
        names: std::mem::take(&mut w.names),
        needs_tex: w.needs_tex.clone(),
    };
    Ok((body, facts))
}

impl<'m> Writer<'m> {
    fn use_glam(&mut self, name: &str) {
        self.glam.insert(name.to_string());
    }

    /// The conversions between glam's SIMD `Vec4` mask (`BVec4A`, what `Vec4` compares to and
    /// selects with) and `BVec4` (WGSL's `vec4<bool>` everywhere else): their names.
    fn mask4_helpers(&mut self) -> R<(&'static str, &'static str)> {
        let b = self.inner_name(&TypeInner::Vector { size: naga::VectorSize::Quad, scalar: Scalar::BOOL })?;
        self.use_glam("BVec4A");
        self.helper("wgsl_bvec4_from_mask", || format!("#[inline(always)]\nfn wgsl_bvec4_from_mask(m: BVec4A) -> {b} {{\n    {b}::from(<[bool; 4]>::from(m))\n}}\n"));
        self.helper("wgsl_mask_from_bvec4", || format!("#[inline(always)]\nfn wgsl_mask_from_bvec4(b: {b}) -> BVec4A {{\n    BVec4A::from(<[bool; 4]>::from(b))\n}}\n"));
        Ok(("wgsl_bvec4_from_mask", "wgsl_mask_from_bvec4"))
    }

    /// Registers a helper function (once).
    fn helper(&mut self, name: &str, code: impl FnOnce() -> String) {
        if !self.helpers.contains_key(name) {
            let c = code();
            self.helpers.insert(name.to_string(), c);
        }
    }

    fn write_all(&mut self, force_trait: bool) -> R<String> {
        let module = self.module;
        // Which functions read textures (callees precede callers in the arena).
        let mut needs = vec![false; module.functions.len()];
        for (h, f) in module.functions.iter() {
            let direct = f.expressions.iter().any(|(_, e)| matches!(e, E::ImageLoad { .. } | E::ImageQuery { .. } | E::ImageSample { .. }));
            let mut calls = Vec::new();
            collect_calls(&f.body, &mut calls);
            needs[h.index()] = direct || calls.iter().any(|c| needs.get(c.index()).copied().unwrap_or(false));
        }
        self.any_texture = needs.iter().any(|b| *b);
        self.needs_tex = needs;

        let mut items = String::new();
        // Structs.
        for (h, ty) in module.types.iter() {
            if let TypeInner::Struct { members, .. } = &ty.inner {
                let name = self.names[&NameKey::Type(h)].clone();
                let mut allows = Vec::new();
                if !is_camel(&name) {
                    allows.push("non_camel_case_types");
                }
                if (0..members.len()).any(|k| self.names[&NameKey::StructMember(h, k as u32)].chars().any(|c| c.is_ascii_uppercase())) {
                    allows.push("non_snake_case");
                }
                if !allows.is_empty() {
                    let _ = writeln!(items, "#[allow({})]", allows.join(", "));
                }
                items.push_str("#[derive(Clone, Copy, Debug, Default, PartialEq)]\n");
                let _ = writeln!(items, "pub struct {name} {{");
                for (k, m) in members.iter().enumerate() {
                    let t = self.type_name(m.ty)?;
                    let field = &self.names[&NameKey::StructMember(h, k as u32)];
                    let _ = writeln!(items, "    pub {field}: {t},");
                }
                items.push_str("}\n\n");
            }
        }
        // Constants.
        for (h, c) in module.constants.iter() {
            let name = self.names[&NameKey::Constant(h)].clone();
            if let (Some(TABLE_DATA), Some(path)) = (c.name.as_deref(), &self.options.albedo_table_data) {
                let _ = writeln!(items, "#[allow(unused_imports)]\npub use {path} as {name};\n");
                continue;
            }
            let t = self.type_name(c.ty)?;
            let v = self.const_expr(c.init)?;
            if name.chars().any(|c| c.is_ascii_lowercase()) {
                items.push_str("#[allow(non_upper_case_globals)]\n");
            }
            let _ = writeln!(items, "pub const {name}: {t} = {};\n", v.s);
        }
        if !module.overrides.is_empty() {
            return Err(unsupported("pipeline-overridable constants (`override`)"));
        }
        // Functions.
        for (h, f) in module.functions.iter() {
            let name = self.names[&NameKey::Function(h)].clone();
            self.write_function(h, f, &mut items).map_err(|mut e| {
                e.function.get_or_insert(name);
                e
            })?;
        }
        // Assemble: imports, trait, helpers, items.
        let mut out = String::new();
        let needs_trait = (self.any_texture || force_trait) && self.options.textures_trait.is_none();
        if needs_trait {
            self.use_glam("Vec4");
            self.use_glam("UVec2");
        }
        if !self.glam.is_empty() {
            let list: Vec<&str> = self.glam.iter().map(|s| s.as_str()).collect();
            match list.as_slice() {
                [one] => {
                    let _ = writeln!(out, "use glam::{one};\n");
                }
                _ => {
                    let _ = writeln!(out, "use glam::{{{}}};\n", list.join(", "));
                }
            }
        }
        if let (Some(path), true) = (&self.options.textures_trait, self.any_texture || force_trait) {
            let _ = writeln!(out, "use {path} as MxTextures;\n");
        }
        if needs_trait {
            out.push_str(TEXTURES_TRAIT);
            out.push('\n');
        }
        out.push_str(&items);
        for code in self.helpers.values() {
            out.push_str(code);
            out.push('\n');
        }
        while out.ends_with('\n') {
            out.pop();
        }
        Ok(out)
    }

    // ---------------------------------------------------------------- types

    /// The Rust type of a type handle.
    fn type_name(&mut self, h: Handle<naga::Type>) -> R<String> {
        match &self.module.types[h].inner {
            TypeInner::Struct { .. } => Ok(self.names[&NameKey::Type(h)].clone()),
            inner => self.inner_name(&inner.clone()),
        }
    }

    /// The Rust type of a non-struct type.
    fn inner_name(&mut self, inner: &TypeInner) -> R<String> {
        Ok(match *inner {
            TypeInner::Scalar(s) => scalar_name(s)?.to_string(),
            TypeInner::Vector { size, scalar } => {
                let n = format!("{}Vec{}", vector_prefix(scalar)?, vsize(size));
                self.use_glam(&n);
                n
            }
            TypeInner::Matrix { columns, rows, scalar } => {
                if columns != rows || scalar != Scalar::F32 {
                    return Err(unsupported(format!("{}x{} matrices of {:?}", vsize(columns), vsize(rows), scalar.kind)));
                }
                let n = format!("Mat{}", vsize(columns));
                self.use_glam(&n);
                n
            }
            TypeInner::Array { base, size: naga::ArraySize::Constant(n), .. } => format!("[{}; {n}]", self.type_name(base)?),
            TypeInner::Array { .. } => return Err(unsupported("runtime-sized or override-sized arrays")),
            TypeInner::Image { dim: ImageDimension::D2, arrayed: false, class: ImageClass::Sampled { kind: ScalarKind::Float, multi: false } } => {
                "usize".to_string()
            }
            TypeInner::Image { .. } => return Err(unsupported("textures other than `texture_2d<f32>`")),
            TypeInner::Struct { .. } => return Err(unsupported("anonymous struct types")),
            TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. } => return Err(unsupported("pointer values")),
            ref other => return Err(unsupported(format!("the type {other:?}"))),
        })
    }

    /// The zero value of a type, written out (never `Default`, which is the identity for glam
    /// matrices).
    fn zero(&mut self, h: Handle<naga::Type>) -> R<String> {
        let module = self.module;
        match &module.types[h].inner {
            TypeInner::Struct { members, .. } => {
                let name = self.names[&NameKey::Type(h)].clone();
                let mut fields = Vec::new();
                for (k, m) in members.iter().enumerate() {
                    let z = self.zero(m.ty)?;
                    fields.push(format!("{}: {z}", self.names[&NameKey::StructMember(h, k as u32)]));
                }
                Ok(format!("{name} {{ {} }}", fields.join(", ")))
            }
            TypeInner::Array { base, size: naga::ArraySize::Constant(n), .. } => Ok(format!("[{}; {n}]", self.zero(*base)?)),
            inner => self.zero_inner(&inner.clone()),
        }
    }

    fn zero_inner(&mut self, inner: &TypeInner) -> R<String> {
        Ok(match *inner {
            TypeInner::Scalar(s) => scalar_zero(s)?.to_string(),
            TypeInner::Vector { scalar, .. } if scalar.kind == ScalarKind::Bool => format!("{}::FALSE", self.inner_name(inner)?),
            TypeInner::Vector { .. } | TypeInner::Matrix { .. } => format!("{}::ZERO", self.inner_name(inner)?),
            ref other => return Err(unsupported(format!("a zero value of {other:?}"))),
        })
    }

    /// The type of a function expression.
    fn ty(&self, ctx: &FnCtx<'m>, h: Handle<E>) -> &'m TypeInner {
        let module: &'m Module = self.module;
        let info: &'m FunctionInfo = ctx.info;
        info[h].ty.inner_with(&module.types)
    }

    // ---------------------------------------------------------------- helpers

    /// A lane-wise helper: `ret` is computed lane by lane by `body` from the arguments' lanes
    /// (scalar arguments are broadcast). Returns its name.
    fn lanewise(&mut self, op: &str, args: &[&TypeInner], ret: &TypeInner, body: &dyn Fn(&[String]) -> String) -> R<String> {
        let mut arg_names = Vec::new();
        for a in args {
            arg_names.push(self.inner_name(a)?);
        }
        let ret_name = self.inner_name(ret)?;
        let name = format!("wgsl_{op}_{}", arg_names.iter().map(|s| s.to_ascii_lowercase()).collect::<Vec<_>>().join("_"));
        let params = ["a", "b", "c", "d"];
        let lanes = match *ret {
            TypeInner::Vector { size, .. } => Some(vsize(size)),
            _ => None,
        };
        let code_body = match lanes {
            None => body(&params[..args.len()].iter().map(|s| s.to_string()).collect::<Vec<_>>()),
            Some(n) => {
                let mut parts = Vec::new();
                for lane in LANES.iter().take(n) {
                    let lane_args: Vec<String> = args
                        .iter()
                        .enumerate()
                        .map(|(k, a)| if matches!(a, TypeInner::Vector { .. }) { format!("{}.{lane}", params[k]) } else { params[k].to_string() })
                        .collect();
                    parts.push(body(&lane_args));
                }
                format!("{ret_name}::new({})", parts.join(", "))
            }
        };
        let sig: Vec<String> = arg_names.iter().enumerate().map(|(k, t)| format!("{}: {t}", params[k])).collect();
        self.helper(&name, || format!("#[inline(always)]\nfn {name}({}) -> {ret_name} {{\n    {code_body}\n}}\n", sig.join(", ")));
        Ok(name)
    }

    /// Calls a lane-wise helper on written arguments.
    fn call_lanewise(&mut self, op: &str, args: &[(&Ex, &TypeInner)], ret: &TypeInner, body: &dyn Fn(&[String]) -> String) -> R<Ex> {
        let tys: Vec<&TypeInner> = args.iter().map(|a| a.1).collect();
        let name = self.lanewise(op, &tys, ret, body)?;
        let list: Vec<String> = args.iter().map(|a| a.0.s.clone()).collect();
        Ok(Ex::atom(format!("{name}({})", list.join(", "))))
    }

    // ---------------------------------------------------------------- constants

    /// A module constant expression (in `module.global_expressions`).
    fn const_expr(&mut self, h: Handle<E>) -> R<Ex> {
        let module = self.module;
        match &module.global_expressions[h] {
            E::Literal(l) => literal(l),
            E::Constant(c) => Ok(Ex::atom(self.names[&NameKey::Constant(*c)].clone())),
            E::ZeroValue(t) => Ok(Ex::atom(self.zero(*t)?)),
            E::Compose { ty, components } => {
                let mut parts = Vec::new();
                for c in components {
                    let inner = self.info[*c].inner_with(&module.types).clone();
                    parts.push((self.const_expr(*c)?, inner));
                }
                self.compose(*ty, parts)
            }
            E::Splat { size, value } => {
                let inner = self.info[*value].inner_with(&module.types).clone();
                let TypeInner::Scalar(scalar) = inner else { return Err(unsupported("a splat of a non-scalar")) };
                let v = self.const_expr(*value)?;
                let t = self.inner_name(&TypeInner::Vector { size: *size, scalar })?;
                Ok(Ex::atom(format!("{t}::splat({})", v.s)))
            }
            other => Err(unsupported(format!("the constant expression {other:?}"))),
        }
    }

    /// `Compose` of a vector, matrix, struct or array from written components.
    fn compose(&mut self, ty: Handle<naga::Type>, parts: Vec<(Ex, TypeInner)>) -> R<Ex> {
        let module = self.module;
        match &module.types[ty].inner {
            TypeInner::Vector { size, scalar } => {
                let t = self.inner_name(&TypeInner::Vector { size: *size, scalar: *scalar })?;
                if parts.iter().all(|(e, i)| matches!(i, TypeInner::Scalar(_)) || is_path(&e.s)) {
                    let mut lanes = Vec::new();
                    for (e, i) in &parts {
                        match i {
                            TypeInner::Vector { size, .. } => lanes.extend(LANES[..vsize(*size)].iter().map(|l| format!("{}.{l}", e.s))),
                            _ => lanes.push(e.s.clone()),
                        }
                    }
                    if lanes.len() != vsize(*size) {
                        return Err(unsupported("a vector constructor with the wrong number of components"));
                    }
                    return Ok(Ex::atom(format!("{t}::new({})", lanes.join(", "))));
                }
                // A component that is not a plain path: a const helper takes the parts.
                let tys: Vec<TypeInner> = parts.iter().map(|p| p.1.clone()).collect();
                let mut arg_names = Vec::new();
                for i in &tys {
                    arg_names.push(self.inner_name(i)?);
                }
                let name = format!("wgsl_{}_from_{}", t.to_ascii_lowercase(), arg_names.iter().map(|s| s.to_ascii_lowercase()).collect::<Vec<_>>().join("_"));
                let params = ["a", "b", "c", "d"];
                let mut lanes = Vec::new();
                for (k, i) in tys.iter().enumerate() {
                    match i {
                        TypeInner::Vector { size, .. } => lanes.extend(LANES[..vsize(*size)].iter().map(|l| format!("{}.{l}", params[k]))),
                        _ => lanes.push(params[k].to_string()),
                    }
                }
                let sig: Vec<String> = arg_names.iter().enumerate().map(|(k, a)| format!("{}: {a}", params[k])).collect();
                let t2 = t.clone();
                self.helper(&name, || format!("#[inline(always)]\nconst fn {name}({}) -> {t2} {{\n    {t2}::new({})\n}}\n", sig.join(", "), lanes.join(", ")));
                let args: Vec<String> = parts.iter().map(|p| p.0.s.clone()).collect();
                Ok(Ex::atom(format!("{name}({})", args.join(", "))))
            }
            TypeInner::Matrix { .. } => {
                let t = self.type_name(ty)?;
                let cols: Vec<String> = parts.iter().map(|p| p.0.s.clone()).collect();
                if parts.iter().any(|p| !matches!(p.1, TypeInner::Vector { .. })) {
                    return Err(unsupported("a matrix constructor from scalars"));
                }
                Ok(Ex::atom(format!("{t}::from_cols({})", cols.join(", "))))
            }
            TypeInner::Struct { .. } => {
                let t = self.type_name(ty)?;
                let fields: Vec<String> =
                    parts.iter().enumerate().map(|(k, p)| format!("{}: {}", self.names[&NameKey::StructMember(ty, k as u32)], p.0.s)).collect();
                Ok(Ex::atom(format!("{t} {{ {} }}", fields.join(", "))))
            }
            TypeInner::Array { .. } => {
                let items: Vec<String> = parts.iter().map(|p| p.0.s.clone()).collect();
                Ok(Ex::atom(format!("[{}]", items.join(", "))))
            }
            other => Err(unsupported(format!("a constructor of {other:?}"))),
        }
    }

    // ---------------------------------------------------------------- functions

    fn write_function(&mut self, h: Handle<Function>, f: &'m Function, out: &mut String) -> R<()> {
        let module = self.module;
        let minfo: &'m ModuleInfo = self.info;
        let info = &minfo[h];
        let name = self.names[&NameKey::Function(h)].clone();
        let tex = self.needs_tex[h.index()];
        let mut emitted = HashSet::new();
        collect_emitted(&f.body, &mut emitted);
        let mut ctx = FnCtx { handle: Some(h), func: f, info, baked: HashMap::new(), scopes: vec![Vec::new()], emitted, tex, breakables: Vec::new() };

        // Which arguments are read.
        let mut arg_used = vec![false; f.arguments.len()];
        for (eh, e) in f.expressions.iter() {
            if let E::FunctionArgument(i) = e {
                if info[eh].ref_count > 0 {
                    arg_used[*i as usize] = true;
                }
            }
        }
        let mut params = Vec::new();
        if tex {
            params.push("tex: &(impl MxTextures + ?Sized)".to_string());
        }
        let mut mixed_case = !name.chars().all(|c| !c.is_ascii_uppercase());
        for (k, a) in f.arguments.iter().enumerate() {
            if a.binding.is_some() {
                return Err(unsupported("arguments with bindings (entry-point inputs)"));
            }
            if let TypeInner::Pointer { .. } = module.types[a.ty].inner {
                return Err(unsupported("pointer arguments"));
            }
            let t = self.type_name(a.ty)?;
            let n = &self.names[&NameKey::FunctionArgument(h, k as u32)];
            mixed_case |= n.chars().any(|c| c.is_ascii_uppercase());
            params.push(if arg_used[k] { format!("{n}: {t}") } else { format!("_{n}: {t}") });
        }
        let ret = match &f.result {
            Some(r) => {
                if r.binding.is_some() {
                    return Err(unsupported("results with bindings (entry-point outputs)"));
                }
                format!(" -> {}", self.type_name(r.ty)?)
            }
            None => String::new(),
        };

        // Locals: stored (→ mut) and loaded (→ read).
        let mut stored = HashSet::new();
        collect_stores(&f.body, &f.expressions, &mut stored);
        let mut loaded = HashSet::new();
        for (eh, e) in f.expressions.iter() {
            if let E::Load { pointer } = e {
                if info[eh].ref_count > 0 {
                    if let Some(l) = local_root(&f.expressions, *pointer) {
                        loaded.insert(l);
                    }
                }
            }
        }
        let mut body = String::new();
        for (lh, l) in f.local_variables.iter() {
            let n = self.names[&NameKey::FunctionLocal(h, lh)].clone();
            mixed_case |= n.chars().any(|c| c.is_ascii_uppercase());
            let t = self.type_name(l.ty)?;
            let init = match l.init {
                Some(i) => self.expr(&ctx, i)?.s,
                None => self.zero(l.ty)?,
            };
            let m = if stored.contains(&lh) { "mut " } else { "" };
            let u = if loaded.contains(&lh) { "" } else { "_" };
            let _ = writeln!(body, "    let {m}{u}{n}: {t} = {init};");
        }
        let has_locals = !f.local_variables.is_empty();
        // The body; a final `return v;` becomes the tail expression.
        let stmts: Vec<&S> = f.body.iter().collect();
        let (last, rest) = match stmts.split_last() {
            Some((S::Return { value }, rest)) => (Some(*value), rest),
            _ => (None, &stmts[..]),
        };
        for s in rest {
            self.statement(&mut ctx, s, 1, &mut body)?;
        }
        if let Some(Some(v)) = last {
            let e = self.expr(&ctx, v)?;
            let _ = writeln!(body, "    {}", e.s);
        }
        mixed_case |= f.named_expressions.values().any(|v| v.chars().any(|c| c.is_ascii_uppercase()));

        out.push_str("#[inline(always)]\n");
        let mut allows = Vec::new();
        if mixed_case {
            allows.push("non_snake_case");
        }
        if has_locals {
            allows.push("unused_assignments");
        }
        if !allows.is_empty() {
            let _ = writeln!(out, "#[allow({})]", allows.join(", "));
        }
        let _ = writeln!(out, "pub fn {name}({}){ret} {{", params.join(", "));
        out.push_str(&body);
        out.push_str("}\n\n");
        Ok(())
    }

    /// Writes a block's statements at `indent` levels; names baked inside go out of scope.
    fn block(&mut self, ctx: &mut FnCtx<'m>, block: &'m naga::Block, indent: usize, out: &mut String) -> R<()> {
        ctx.scopes.push(Vec::new());
        let mut r = Ok(());
        for s in block.iter() {
            r = self.statement(ctx, s, indent, out);
            if r.is_err() {
                break;
            }
        }
        for h in ctx.scopes.pop().unwrap_or_default() {
            ctx.baked.remove(&h);
        }
        r
    }

    /// Whether an emitted expression is bound by `let` (as naga's own writers decide: named,
    /// or referenced at least `bake_ref_count` times).
    fn should_bake(&self, ctx: &FnCtx<'m>, h: Handle<E>) -> bool {
        let e = &ctx.func.expressions[h];
        if matches!(self.ty(ctx, h), TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }) {
            return false;
        }
        if ctx.info[h].ref_count == 0 {
            return false;
        }
        ctx.func.named_expressions.contains_key(&h) || ctx.info[h].ref_count >= e.bake_ref_count()
    }

    fn bind(&mut self, ctx: &mut FnCtx<'m>, h: Handle<E>) -> String {
        let name = match ctx.func.named_expressions.get(&h) {
            Some(n) => self.namer.call(n),
            None => format!("_e{}", h.index()),
        };
        ctx.baked.insert(h, name.clone());
        if let Some(s) = ctx.scopes.last_mut() {
            s.push(h);
        }
        name
    }

    /// A loop's continuing block and its `break_if`, at `indent`, in one scope (`break_if` sees
    /// the continuing block's values; they go out of scope after it).
    fn continuing(&mut self, ctx: &mut FnCtx<'m>, continuing: &'m naga::Block, break_if: Option<Handle<E>>, indent: usize, out: &mut String) -> R<()> {
        let pad = "    ".repeat(indent);
        ctx.scopes.push(Vec::new());
        let mut r = Ok(());
        for s in continuing.iter() {
            r = self.statement(ctx, s, indent, out);
            if r.is_err() {
                break;
            }
        }
        if let (Ok(()), Some(b)) = (&r, break_if) {
            r = self.expr(ctx, b).map(|c| {
                let _ = writeln!(out, "{pad}if {} {{\n{pad}    break;\n{pad}}}", c.s);
            });
        }
        for h in ctx.scopes.pop().unwrap_or_default() {
            ctx.baked.remove(&h);
        }
        r
    }

    fn statement(&mut self, ctx: &mut FnCtx<'m>, s: &'m S, indent: usize, out: &mut String) -> R<()> {
        let pad = "    ".repeat(indent);
        match s {
            S::Emit(range) => {
                for h in range.clone() {
                    if !self.should_bake(ctx, h) {
                        continue;
                    }
                    let e = self.expr_inner(ctx, h)?;
                    let name = self.bind(ctx, h);
                    let _ = writeln!(out, "{pad}let {name} = {};", e.s);
                }
            }
            S::Block(b) => {
                let _ = writeln!(out, "{pad}{{");
                self.block(ctx, b, indent + 1, out)?;
                let _ = writeln!(out, "{pad}}}");
            }
            S::If { condition, accept, reject } => {
                let c = self.expr(ctx, *condition)?;
                let _ = writeln!(out, "{pad}if {} {{", c.s);
                self.block(ctx, accept, indent + 1, out)?;
                if reject.is_empty() {
                    let _ = writeln!(out, "{pad}}}");
                } else {
                    let _ = writeln!(out, "{pad}}} else {{");
                    self.block(ctx, reject, indent + 1, out)?;
                    let _ = writeln!(out, "{pad}}}");
                }
            }
            S::Switch { selector, cases } => self.switch(ctx, *selector, cases, indent, out)?,
            S::Loop { body, continuing, break_if } => {
                let pad1 = "    ".repeat(indent + 1);
                let simple = continuing.is_empty() && break_if.is_none();
                // Without a `continue` in the body, the continuing block runs at the end of the
                // body: `loop { body; continuing; if break_if { break } }`, the rotated shape
                // whose trip count LLVM computes, so that it fully unrolls a library's constant
                // loops and vectorises the batch loop around them. Otherwise a flag runs the
                // continuing block at the top of every iteration but the first.
                let at_end = !simple && !block_continues(body);
                let flag = if simple || at_end { None } else { Some(self.namer.call("loop_init")) };
                if let Some(flag) = &flag {
                    let _ = writeln!(out, "{pad}let mut {flag} = true;");
                }
                let loop_at = out.len();
                let _ = writeln!(out, "{pad}loop {{");
                ctx.breakables.push(Breakable::Loop { label: String::new(), used: false });
                // WGSL: `continue` runs the continuing block; so it runs at the top of every
                // iteration but the first.
                if let Some(flag) = &flag {
                    let _ = writeln!(out, "{pad1}if !{flag} {{");
                    // The continuing block may use values emitted in `body`: not supported
                    // (reported by `expr` as a value out of scope).
                    self.continuing(ctx, continuing, *break_if, indent + 2, out)?;
                    let _ = writeln!(out, "{pad1}}}\n{pad1}{flag} = false;");
                }
                self.block(ctx, body, indent + 1, out)?;
                if at_end {
                    self.continuing(ctx, continuing, *break_if, indent + 1, out)?;
                }
                let _ = writeln!(out, "{pad}}}");
                if let Some(Breakable::Loop { label, used: true }) = ctx.breakables.pop() {
                    out.insert_str(loop_at + pad.len(), &format!("'{label}: "));
                }
            }
            S::Break => match ctx.breakables.last() {
                Some(Breakable::Switch { label: Some(l) }) => {
                    let _ = writeln!(out, "{pad}break '{l};");
                }
                Some(Breakable::Switch { label: None }) => {}
                _ => {
                    let _ = writeln!(out, "{pad}break{};", self.loop_label(ctx));
                }
            },
            S::Continue => {
                let _ = writeln!(out, "{pad}continue{};", self.loop_label(ctx));
            }
            S::Return { value } => match value {
                Some(v) => {
                    let e = self.expr(ctx, *v)?;
                    let _ = writeln!(out, "{pad}return {};", e.s);
                }
                None => {
                    let _ = writeln!(out, "{pad}return;");
                }
            },
            S::Store { pointer, value } => {
                let p = self.place(ctx, *pointer)?;
                let v = self.expr(ctx, *value)?;
                let _ = writeln!(out, "{pad}{p} = {};", v.s);
            }
            S::Call { function, arguments, result } => {
                let call = self.call(ctx, *function, arguments)?;
                match result {
                    Some(r) if ctx.info[*r].ref_count > 0 => {
                        let name = self.bind(ctx, *r);
                        let _ = writeln!(out, "{pad}let {name} = {call};");
                    }
                    _ => {
                        let _ = writeln!(out, "{pad}{call};");
                    }
                }
            }
            S::Kill => return Err(unsupported("`discard`")),
            S::ControlBarrier(_) | S::MemoryBarrier(_) => return Err(unsupported("barriers")),
            S::ImageStore { .. } => return Err(unsupported("texture stores")),
            S::Atomic { .. } | S::ImageAtomic { .. } => return Err(unsupported("atomics")),
            S::WorkGroupUniformLoad { .. } => return Err(unsupported("workgroupUniformLoad")),
            S::RayQuery { .. } | S::RayPipelineFunction(_) => return Err(unsupported("ray tracing")),
            S::SubgroupBallot { .. } | S::SubgroupGather { .. } | S::SubgroupCollectiveOperation { .. } => {
                return Err(unsupported("subgroup operations"))
            }
            S::CooperativeStore { .. } => return Err(unsupported("cooperative matrices")),
        }
        Ok(())
    }

    /// `""`, or `" 'label"` when a labelled switch block lies between here and the innermost
    /// loop (Rust forbids an unlabelled `break`/`continue` there).
    fn loop_label(&mut self, ctx: &mut FnCtx<'m>) -> String {
        let mut crossed = false;
        for b in ctx.breakables.iter_mut().rev() {
            match b {
                Breakable::Switch { label: Some(_) } => crossed = true,
                Breakable::Switch { label: None } => {}
                Breakable::Loop { label, used } => {
                    if !crossed {
                        return String::new();
                    }
                    if label.is_empty() {
                        *label = self.namer.call("l");
                    }
                    *used = true;
                    return format!(" '{label}");
                }
            }
        }
        String::new()
    }

    fn switch(&mut self, ctx: &mut FnCtx<'m>, selector: Handle<E>, cases: &'m [naga::SwitchCase], indent: usize, out: &mut String) -> R<()> {
        let pad = "    ".repeat(indent);
        let sel = self.expr(ctx, selector)?;
        // Group fall-through runs of empty cases with the case that has the body.
        let mut groups: Vec<(Vec<naga::SwitchValue>, &'m naga::Block)> = Vec::new();
        let mut pending: Vec<naga::SwitchValue> = Vec::new();
        for c in cases {
            pending.push(c.value);
            if c.fall_through {
                if !c.body.is_empty() {
                    return Err(unsupported("switch cases that fall through after statements"));
                }
                continue;
            }
            groups.push((std::mem::take(&mut pending), &c.body));
        }
        if !pending.is_empty() {
            return Err(unsupported("a switch whose last case falls through"));
        }
        // `default` last: Rust matches in order.
        groups.sort_by_key(|g| g.0.contains(&naga::SwitchValue::Default));
        // Case bodies: a trailing `break` is dropped; any other break leaves a labelled block.
        let trimmed: Vec<(&Vec<naga::SwitchValue>, &'m [S])> = groups
            .iter()
            .map(|(v, b)| {
                let stmts: &'m [S] = &b[..];
                let stmts = match stmts.split_last() {
                    Some((S::Break, rest)) => rest,
                    _ => stmts,
                };
                (v, stmts)
            })
            .collect();
        let needs_label = groups.iter().any(|(_, b)| {
            let stmts: Vec<&S> = b.iter().collect();
            let inner = match stmts.split_last() {
                Some((S::Break, rest)) => rest.to_vec(),
                _ => stmts,
            };
            inner.iter().any(|s| match s {
                S::Break => true,
                S::Block(b) => block_breaks(b),
                S::If { accept, reject, .. } => block_breaks(accept) || block_breaks(reject),
                _ => false,
            })
        });
        let label = if needs_label { Some(self.namer.call("sw")) } else { None };
        match &label {
            Some(l) => {
                let _ = writeln!(out, "{pad}'{l}: {{\n{pad}    match {} {{", sel.s);
            }
            None => {
                let _ = writeln!(out, "{pad}match {} {{", sel.s);
            }
        }
        let inner = if label.is_some() { indent + 1 } else { indent };
        let ipad = "    ".repeat(inner);
        ctx.breakables.push(Breakable::Switch { label: label.clone() });
        let mut has_default = false;
        for (values, stmts) in trimmed {
            let pat = if values.contains(&naga::SwitchValue::Default) {
                has_default = true;
                "_".to_string()
            } else {
                values
                    .iter()
                    .map(|v| match v {
                        naga::SwitchValue::I32(i) => format!("{i}i32"),
                        naga::SwitchValue::U32(u) => format!("{u}u32"),
                        naga::SwitchValue::Default => "_".into(),
                    })
                    .collect::<Vec<_>>()
                    .join(" | ")
            };
            let _ = writeln!(out, "{ipad}    {pat} => {{");
            ctx.scopes.push(Vec::new());
            let mut r = Ok(());
            for s in stmts {
                r = self.statement(ctx, s, inner + 2, out);
                if r.is_err() {
                    break;
                }
            }
            for h in ctx.scopes.pop().unwrap_or_default() {
                ctx.baked.remove(&h);
            }
            r?;
            let _ = writeln!(out, "{ipad}    }}");
        }
        if !has_default {
            let _ = writeln!(out, "{ipad}    _ => {{}}");
        }
        ctx.breakables.pop();
        let _ = writeln!(out, "{ipad}}}");
        if label.is_some() {
            let _ = writeln!(out, "{pad}}}");
        }
        Ok(())
    }

    /// A call of `function` with written arguments (texture arguments are indices).
    fn call(&mut self, ctx: &FnCtx<'m>, function: Handle<Function>, arguments: &[Handle<E>]) -> R<String> {
        let name = self.names[&NameKey::Function(function)].clone();
        let mut args = Vec::new();
        if self.needs_tex.get(function.index()).copied().unwrap_or(false) {
            if !ctx.tex {
                return Err(unsupported("a texture read outside a function that takes the textures"));
            }
            args.push("tex".to_string());
        }
        for a in arguments {
            args.push(self.expr(ctx, *a)?.s);
        }
        Ok(format!("{name}({})", args.join(", ")))
    }

    /// A place (assignable path) for a pointer expression.
    fn place(&mut self, ctx: &FnCtx<'m>, h: Handle<E>) -> R<String> {
        let f = ctx.func;
        match &f.expressions[h] {
            E::LocalVariable(l) => Ok(self.names[&NameKey::FunctionLocal(ctx.handle.ok_or_else(|| unsupported("locals here"))?, *l)].clone()),
            E::GlobalVariable(g) => {
                let gv = &self.module.global_variables[*g];
                Err(unsupported(format!("the global variable `{}` ({:?} address space)", gv.name.as_deref().unwrap_or("?"), gv.space)))
            }
            E::FunctionArgument(_) => Err(unsupported("pointer arguments")),
            E::AccessIndex { base, index } => {
                let b = self.place(ctx, *base)?;
                if let TypeInner::Pointer { base: th, .. } = *self.ty(ctx, *base) {
                    if let TypeInner::Struct { .. } = self.module.types[th].inner {
                        return Ok(format!("{b}.{}", self.names[&NameKey::StructMember(th, *index)]));
                    }
                }
                let pointee = self.pointee(ctx, *base)?;
                self.access_index(&Ex::atom(b), &pointee, *index)
            }
            E::Access { base, index } => {
                let b = self.place(ctx, *base)?;
                let pointee = self.pointee(ctx, *base)?;
                let i = self.expr(ctx, *index)?;
                self.access_dynamic(&Ex::atom(b), &pointee, &i, true).map(|e| e.s)
            }
            other => Err(unsupported(format!("the pointer expression {other:?}"))),
        }
    }

    /// The type a pointer expression points to.
    fn pointee(&self, ctx: &FnCtx<'m>, h: Handle<E>) -> R<TypeInner> {
        match self.ty(ctx, h) {
            TypeInner::Pointer { base, .. } => Ok(self.module.types[*base].inner.clone()),
            TypeInner::ValuePointer { size: Some(size), scalar, .. } => Ok(TypeInner::Vector { size: *size, scalar: *scalar }),
            TypeInner::ValuePointer { size: None, scalar, .. } => Ok(TypeInner::Scalar(*scalar)),
            _ => Err(unsupported("a pointer of unknown type")),
        }
    }

    /// `base.<index>` for a constant index into a vector, matrix or array value (or place).
    fn access_index(&mut self, base: &Ex, base_ty: &TypeInner, index: u32) -> R<String> {
        let b = base.at(Prec::Atom);
        Ok(match base_ty {
            TypeInner::Vector { size, .. } if (index as usize) < vsize(*size) => format!("{b}.{}", LANES[index as usize]),
            TypeInner::Matrix { columns, .. } if (index as usize) < vsize(*columns) => format!("{b}.{}_axis", LANES[index as usize]),
            TypeInner::Array { .. } => format!("{b}[{index}]"),
            other => return Err(unsupported(format!("a constant index into {other:?}"))),
        })
    }

    /// `base[index]` with a runtime index, clamped into range (never panics). WGSL indices are
    /// i32 or u32; clamping as u32 (a negative index wraps past the end, as `as usize` would)
    /// lets LLVM gather with 32-bit lane indices when it vectorises a batch loop.
    fn access_dynamic(&mut self, base: &Ex, base_ty: &TypeInner, index: &Ex, place: bool) -> R<Ex> {
        let b = base.at(Prec::Atom);
        let clamp = |n: usize| format!("({} as u32).min({}) as usize", index.at(Prec::Unary), n - 1);
        Ok(match *base_ty {
            TypeInner::Vector { size, scalar } if scalar.kind == ScalarKind::Bool => {
                if place {
                    return Err(unsupported("a store into a boolean vector at a runtime index"));
                }
                Ex::atom(format!("{b}.test({})", clamp(vsize(size))))
            }
            TypeInner::Vector { size, .. } => Ex::atom(format!("{b}[{}]", clamp(vsize(size)))),
            TypeInner::Matrix { columns, .. } => {
                if place {
                    Ex::atom(format!("(*{b}.col_mut({}))", clamp(vsize(columns))))
                } else {
                    Ex::atom(format!("{b}.col({})", clamp(vsize(columns))))
                }
            }
            TypeInner::Array { size: naga::ArraySize::Constant(n), .. } => Ex::atom(format!("{b}[{}]", clamp(n.get() as usize))),
            ref other => return Err(unsupported(format!("a runtime index into {other:?}"))),
        })
    }

    // ---------------------------------------------------------------- expressions

    /// Writes a use of a function expression: its `let` name, or the expression itself.
    fn expr(&mut self, ctx: &FnCtx<'m>, h: Handle<E>) -> R<Ex> {
        if let Some(n) = ctx.baked.get(&h) {
            return Ok(Ex::atom(n.clone()));
        }
        let e = &ctx.func.expressions[h];
        if (ctx.emitted.contains(&h) && self.should_bake(ctx, h)) || matches!(e, E::CallResult(_)) {
            return Err(unsupported("a value used outside the block that computes it (for instance a loop's continuing block reading a value of the loop body)"));
        }
        self.expr_inner(ctx, h)
    }

    /// Writes a function expression itself.
    fn expr_inner(&mut self, ctx: &FnCtx<'m>, h: Handle<E>) -> R<Ex> {
        let f = ctx.func;
        let e = &f.expressions[h];
        let module = self.module;
        Ok(match e {
            E::Literal(l) => literal(l)?,
            E::Constant(c) => Ex::atom(self.names[&NameKey::Constant(*c)].clone()),
            E::Override(_) => return Err(unsupported("pipeline-overridable constants (`override`)")),
            E::ZeroValue(t) => Ex::atom(self.zero(*t)?),
            E::Compose { ty, components } => {
                let mut parts = Vec::new();
                for c in components {
                    parts.push((self.expr(ctx, *c)?, self.ty(ctx, *c).clone()));
                }
                self.compose(*ty, parts)?
            }
            E::Access { base, index } => {
                if matches!(self.ty(ctx, *base), TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }) {
                    return Err(unsupported("a pointer value"));
                }
                let b = self.expr(ctx, *base)?;
                let i = self.expr(ctx, *index)?;
                let bt = self.ty(ctx, *base).clone();
                self.access_dynamic(&b, &bt, &i, false)?
            }
            E::AccessIndex { base, index } => {
                let bt = self.ty(ctx, *base).clone();
                if matches!(bt, TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }) {
                    return Err(unsupported("a pointer value"));
                }
                let b = self.expr(ctx, *base)?;
                if let TypeInner::Struct { .. } = bt {
                    let th = match &ctx.info[*base].ty {
                        naga::proc::TypeResolution::Handle(t) => *t,
                        _ => return Err(unsupported("an anonymous struct")),
                    };
                    return Ok(Ex::atom(format!("{}.{}", b.at(Prec::Atom), self.names[&NameKey::StructMember(th, *index)])));
                }
                Ex::atom(self.access_index(&b, &bt, *index)?)
            }
            E::Splat { size, value } => {
                let v = self.expr(ctx, *value)?;
                let TypeInner::Scalar(scalar) = *self.ty(ctx, *value) else { return Err(unsupported("a splat of a non-scalar")) };
                let t = self.inner_name(&TypeInner::Vector { size: *size, scalar })?;
                Ex::atom(format!("{t}::splat({})", v.s))
            }
            E::Swizzle { size, vector, pattern } => {
                let v = self.expr(ctx, *vector)?;
                let vt = self.ty(ctx, *vector).clone();
                let TypeInner::Vector { scalar, .. } = vt else { return Err(unsupported("a swizzle of a non-vector")) };
                let rt = TypeInner::Vector { size: *size, scalar };
                let t = self.inner_name(&rt)?;
                let lanes: Vec<&str> = pattern[..vsize(*size)].iter().map(|c| LANES[*c as usize]).collect();
                if is_path(&v.s) {
                    Ex::atom(format!("{t}::new({})", lanes.iter().map(|l| format!("{}.{l}", v.s)).collect::<Vec<_>>().join(", ")))
                } else {
                    let sw = lanes.concat();
                    let name = self.lanewise_swizzle(&sw, &vt, &rt, &lanes)?;
                    Ex::atom(format!("{name}({})", v.s))
                }
            }
            E::FunctionArgument(i) => {
                let fh = ctx.handle.ok_or_else(|| unsupported("arguments here"))?;
                Ex::atom(self.names[&NameKey::FunctionArgument(fh, *i)].clone())
            }
            E::GlobalVariable(g) => {
                let gv = &module.global_variables[*g];
                match (&module.types[gv.ty].inner, &gv.binding) {
                    (TypeInner::Image { .. }, Some(b)) => {
                        self.inner_name(&module.types[gv.ty].inner.clone())?;
                        let k = b.binding.checked_sub(self.options.first_texture_binding).filter(|_| b.group == 0).ok_or_else(|| {
                            unsupported(format!("the texture `{}` at group {} binding {}", gv.name.as_deref().unwrap_or("?"), b.group, b.binding))
                        })?;
                        Ex::atom(format!("{k}usize"))
                    }
                    _ => {
                        return Err(unsupported(format!(
                            "the global variable `{}` ({:?} address space)",
                            gv.name.as_deref().unwrap_or("?"),
                            gv.space
                        )))
                    }
                }
            }
            E::LocalVariable(_) => return Err(unsupported("a pointer value")),
            E::Load { pointer } => Ex::atom(self.place(ctx, *pointer)?),
            E::ImageSample { .. } => return Err(unsupported("texture sampling with a sampler (textureSample*)")),
            E::ImageLoad { image, coordinate, array_index, sample, level } => {
                if array_index.is_some() || sample.is_some() {
                    return Err(unsupported("textureLoad of arrayed or multisampled textures"));
                }
                if let Some(l) = level {
                    if literal_int(&f.expressions[*l]) != Some(0) {
                        return Err(unsupported("textureLoad of a mip level other than a literal 0"));
                    }
                }
                if !ctx.tex {
                    return Err(unsupported("a texture read outside a function that takes the textures"));
                }
                let img = self.expr(ctx, *image)?;
                let ct = self.ty(ctx, *coordinate).clone();
                let cast = match ct {
                    TypeInner::Vector { size: VectorSize::Bi, scalar } if scalar.kind == ScalarKind::Sint => "",
                    TypeInner::Vector { size: VectorSize::Bi, scalar } if scalar.kind == ScalarKind::Uint => " as i32",
                    _ => return Err(unsupported("textureLoad with coordinates other than vec2<i32> or vec2<u32>")),
                };
                // Coordinates written as `vec2(x, y)` pass their components directly.
                let comps = match (&f.expressions[*coordinate], ctx.baked.get(coordinate)) {
                    (E::Compose { components, .. }, None) if components.len() == 2 => Some((components[0], components[1])),
                    _ => None,
                };
                match comps {
                    Some((x, y)) => {
                        let x = self.expr(ctx, x)?;
                        let y = self.expr(ctx, y)?;
                        let (x, y) = if cast.is_empty() { (x.s, y.s) } else { (format!("{}{cast}", x.at(Prec::Unary)), format!("{}{cast}", y.at(Prec::Unary))) };
                        Ex::atom(format!("tex.load({}, {x}, {y})", img.s))
                    }
                    None => {
                        let c = self.expr(ctx, *coordinate)?;
                        let cn = self.inner_name(&ct)?;
                        self.use_glam("Vec4");
                        let name = format!("wgsl_texture_load_{}", cn.to_ascii_lowercase());
                        self.helper(&name, || {
                            format!(
                                "#[inline(always)]\nfn {name}(tex: &(impl MxTextures + ?Sized), texture: usize, c: {cn}) -> Vec4 {{\n    tex.load(texture, c.x{cast}, c.y{cast})\n}}\n"
                            )
                        });
                        Ex::atom(format!("{name}(tex, {}, {})", img.s, c.s))
                    }
                }
            }
            E::ImageQuery { image, query } => {
                if !ctx.tex {
                    return Err(unsupported("a texture query outside a function that takes the textures"));
                }
                match query {
                    naga::ImageQuery::Size { level } => {
                        if let Some(l) = level {
                            if literal_int(&f.expressions[*l]) != Some(0) {
                                return Err(unsupported("textureDimensions of a mip level other than a literal 0"));
                            }
                        }
                        let img = self.expr(ctx, *image)?;
                        Ex::atom(format!("tex.dimensions({})", img.s))
                    }
                    other => return Err(unsupported(format!("the texture query {other:?}"))),
                }
            }
            E::Unary { op, expr } => self.unary(ctx, *op, *expr)?,
            E::Binary { op, left, right } => self.binary(ctx, *op, *left, *right)?,
            E::Select { condition, accept, reject } => {
                let c = self.expr(ctx, *condition)?;
                let a = self.expr(ctx, *accept)?;
                let r = self.expr(ctx, *reject)?;
                let ct = self.ty(ctx, *condition).clone();
                let vt = self.ty(ctx, *accept).clone();
                match (&ct, &vt) {
                    (TypeInner::Scalar(_), _) => Ex::new(format!("if {} {{ {} }} else {{ {} }}", c.s, a.s, r.s), Prec::Lowest),
                    (TypeInner::Vector { .. }, TypeInner::Vector { scalar, size }) if scalar.kind != ScalarKind::Bool => {
                        let t = self.inner_name(&vt)?;
                        if scalar.kind == ScalarKind::Float && *size == naga::VectorSize::Quad {
                            // glam's SIMD `Vec4::select` takes a `BVec4A`.
                            let name = self.mask4_helpers()?.1;
                            Ex::atom(format!("{t}::select({name}({}), {}, {})", c.s, a.s, r.s))
                        } else {
                            Ex::atom(format!("{t}::select({}, {}, {})", c.s, a.s, r.s))
                        }
                    }
                    _ => self.call_lanewise("select", &[(&c, &ct), (&a, &vt), (&r, &vt)], &vt, &|x| format!("if {} {{ {} }} else {{ {} }}", x[0], x[1], x[2]))?,
                }
            }
            E::Derivative { .. } => return Err(unsupported("derivatives (dpdx, dpdy, fwidth)")),
            E::Relational { fun, argument } => {
                let a = self.expr(ctx, *argument)?;
                let at = self.ty(ctx, *argument).clone();
                match (fun, &at) {
                    (RelationalFunction::All | RelationalFunction::Any, TypeInner::Scalar(_)) => a,
                    (RelationalFunction::All, _) => Ex::atom(format!("{}.all()", a.at(Prec::Atom))),
                    (RelationalFunction::Any, _) => Ex::atom(format!("{}.any()", a.at(Prec::Atom))),
                    (RelationalFunction::IsNan | RelationalFunction::IsInf, _) => {
                        let m = if *fun == RelationalFunction::IsNan { "is_nan" } else { "is_infinite" };
                        let rt = bool_like(&at);
                        self.call_lanewise(m, &[(&a, &at)], &rt, &|x| format!("{}.{m}()", x[0]))?
                    }
                }
            }
            E::Math { fun, arg, arg1, arg2, arg3 } => self.math(ctx, h, *fun, *arg, *arg1, *arg2, *arg3)?,
            E::As { expr, kind, convert } => self.cast(ctx, *expr, *kind, *convert)?,
            E::CallResult(_) => unreachable_call_result()?,
            E::AtomicResult { .. } => return Err(unsupported("atomics")),
            E::WorkGroupUniformLoadResult { .. } => return Err(unsupported("workgroupUniformLoad")),
            E::ArrayLength(_) => return Err(unsupported("arrayLength (runtime-sized arrays)")),
            E::RayQueryVertexPositions { .. } | E::RayQueryProceedResult | E::RayQueryGetIntersection { .. } => {
                return Err(unsupported("ray tracing"))
            }
            E::SubgroupBallotResult | E::SubgroupOperationResult { .. } => return Err(unsupported("subgroup operations")),
            E::CooperativeLoad { .. } | E::CooperativeMultiplyAdd { .. } => return Err(unsupported("cooperative matrices")),
        })
    }

    /// A swizzle of a non-path vector through a helper.
    fn lanewise_swizzle(&mut self, sw: &str, vt: &TypeInner, rt: &TypeInner, lanes: &[&str]) -> R<String> {
        let vn = self.inner_name(vt)?;
        let rn = self.inner_name(rt)?;
        let name = format!("wgsl_swizzle_{sw}_{}", vn.to_ascii_lowercase());
        let parts: Vec<String> = lanes.iter().map(|l| format!("v.{l}")).collect();
        self.helper(&name, || format!("#[inline(always)]\nfn {name}(v: {vn}) -> {rn} {{\n    {rn}::new({})\n}}\n", parts.join(", ")));
        Ok(name)
    }

    fn unary(&mut self, ctx: &FnCtx<'m>, op: UnaryOperator, h: Handle<E>) -> R<Ex> {
        let a = self.expr(ctx, h)?;
        let t = self.ty(ctx, h).clone();
        let kind = scalar_of(&t).map(|s| s.kind);
        Ok(match (op, kind, &t) {
            (UnaryOperator::Negate, Some(ScalarKind::Float), TypeInner::Scalar(_) | TypeInner::Vector { .. } | TypeInner::Matrix { .. }) => {
                Ex::new(format!("-{}", a.at(Prec::Unary)), Prec::Unary)
            }
            (UnaryOperator::Negate, Some(ScalarKind::Sint), TypeInner::Scalar(_)) => Ex::atom(format!("{}.wrapping_neg()", a.at(Prec::Atom))),
            (UnaryOperator::Negate, Some(ScalarKind::Sint), TypeInner::Vector { .. }) => {
                self.call_lanewise("neg", &[(&a, &t)], &t, &|x| format!("{}.wrapping_neg()", x[0]))?
            }
            (UnaryOperator::LogicalNot | UnaryOperator::BitwiseNot, _, TypeInner::Scalar(_)) => Ex::new(format!("!{}", a.at(Prec::Unary)), Prec::Unary),
            (UnaryOperator::LogicalNot | UnaryOperator::BitwiseNot, _, TypeInner::Vector { .. }) => {
                self.call_lanewise("not", &[(&a, &t)], &t, &|x| format!("!{}", x[0]))?
            }
            _ => return Err(unsupported(format!("the unary operator {op:?} on {t:?}"))),
        })
    }

    fn binary(&mut self, ctx: &FnCtx<'m>, op: Bo, lh: Handle<E>, rh: Handle<E>) -> R<Ex> {
        let l = self.expr(ctx, lh)?;
        let r = self.expr(ctx, rh)?;
        let lt = self.ty(ctx, lh).clone();
        let rt = self.ty(ctx, rh).clone();
        let kind = scalar_of(&lt).map(|s| s.kind).ok_or_else(|| unsupported(format!("the operator {op:?} on {lt:?}")))?;
        let both_scalar = matches!(lt, TypeInner::Scalar(_)) && matches!(rt, TypeInner::Scalar(_));
        let is_vec = |t: &TypeInner| matches!(t, TypeInner::Vector { .. });
        // The type of the result for lane-wise forms (the wider operand).
        let wide = if is_vec(&lt) { lt.clone() } else { rt.clone() };
        let infix = |sym: &str, p: Prec| -> Ex {
            // Left-associative: the right operand must bind tighter. `x as T < y` and
            // `x as T << y` read as generics: parenthesise a cast there.
            let left_need = if p == Prec::Cmp { Prec::BitOr } else { p };
            let left = if l.p == Prec::Cast && (sym == "<" || sym == "<<") { format!("({})", l.s) } else { l.at(left_need) };
            let right_need = match p {
                Prec::Cmp => Prec::BitOr,
                _ => next_prec(p),
            };
            Ex::new(format!("{left} {sym} {}", r.at(right_need)), p)
        };
        let cmp_method = |m: &str| Ex::atom(format!("{}.{m}({})", l.at(Prec::Atom), r.s));
        Ok(match op {
            Bo::Add | Bo::Subtract | Bo::Multiply | Bo::Divide if kind == ScalarKind::Float => {
                match (op, &lt, &rt) {
                    // WGSL `v * M` is `transpose(M) * v`.
                    (Bo::Multiply, TypeInner::Vector { .. }, TypeInner::Matrix { .. }) => {
                        Ex::new(format!("{}.transpose() * {}", r.at(Prec::Atom), l.at(Prec::Cast)), Prec::Mul)
                    }
                    _ => {
                        let (sym, p) = match op {
                            Bo::Add => ("+", Prec::Add),
                            Bo::Subtract => ("-", Prec::Add),
                            Bo::Multiply => ("*", Prec::Mul),
                            _ => ("/", Prec::Mul),
                        };
                        infix(sym, p)
                    }
                }
            }
            Bo::Modulo if kind == ScalarKind::Float => {
                let args = [(&l, &lt), (&r, &rt)];
                self.call_lanewise("rem", &args, &wide, &|x| format!("{a} - {b} * ({a} / {b}).trunc()", a = x[0], b = x[1]))?
            }
            Bo::Add | Bo::Subtract | Bo::Multiply if matches!(kind, ScalarKind::Sint | ScalarKind::Uint) => {
                let m = match op {
                    Bo::Add => "wrapping_add",
                    Bo::Subtract => "wrapping_sub",
                    _ => "wrapping_mul",
                };
                if both_scalar || (is_vec(&lt) && is_vec(&rt)) {
                    Ex::atom(format!("{}.{m}({})", l.at(Prec::Atom), r.s))
                } else if is_vec(&lt) {
                    let t = self.inner_name(&lt)?;
                    Ex::atom(format!("{}.{m}({t}::splat({}))", l.at(Prec::Atom), r.s))
                } else {
                    let t = self.inner_name(&rt)?;
                    Ex::atom(format!("{t}::splat({}).{m}({})", l.s, r.s))
                }
            }
            Bo::Divide | Bo::Modulo if matches!(kind, ScalarKind::Sint | ScalarKind::Uint) => {
                let (op_name, body): (&str, fn(&[String]) -> String) = if op == Bo::Divide {
                    ("div", |x| format!("{a}.checked_div({b}).unwrap_or({a})", a = x[0], b = x[1]))
                } else {
                    ("rem", |x| format!("{}.checked_rem({}).unwrap_or(0)", x[0], x[1]))
                };
                self.call_lanewise(op_name, &[(&l, &lt), (&r, &rt)], &wide, &body)?
            }
            Bo::Equal | Bo::NotEqual | Bo::Less | Bo::LessEqual | Bo::Greater | Bo::GreaterEqual => {
                let (sym, m) = match op {
                    Bo::Equal => ("==", "cmpeq"),
                    Bo::NotEqual => ("!=", "cmpne"),
                    Bo::Less => ("<", "cmplt"),
                    Bo::LessEqual => ("<=", "cmple"),
                    Bo::Greater => (">", "cmpgt"),
                    _ => (">=", "cmpge"),
                };
                if both_scalar {
                    infix(sym, Prec::Cmp)
                } else if kind == ScalarKind::Float && matches!(lt, TypeInner::Vector { size: naga::VectorSize::Quad, .. }) && is_vec(&rt) {
                    // glam's SIMD `Vec4` compares to a `BVec4A`; WGSL's `vec4<bool>` is `BVec4`.
                    let name = self.mask4_helpers()?.0;
                    Ex::atom(format!("{name}({})", cmp_method(m).s))
                } else if kind != ScalarKind::Bool && is_vec(&lt) && is_vec(&rt) {
                    cmp_method(m)
                } else {
                    let ret = bool_like(&wide);
                    self.call_lanewise(m, &[(&l, &lt), (&r, &rt)], &ret, &|x| format!("{} {sym} {}", x[0], x[1]))?
                }
            }
            Bo::And | Bo::InclusiveOr | Bo::ExclusiveOr => {
                let (sym, p, name) = match op {
                    Bo::And => ("&", Prec::BitAnd, "and"),
                    Bo::InclusiveOr => ("|", Prec::BitOr, "or"),
                    _ => ("^", Prec::BitXor, "xor"),
                };
                if both_scalar {
                    infix(sym, p)
                } else {
                    self.call_lanewise(name, &[(&l, &lt), (&r, &rt)], &wide, &|x| format!("{} {sym} {}", x[0], x[1]))?
                }
            }
            Bo::LogicalAnd if both_scalar => infix("&&", Prec::And),
            Bo::LogicalOr if both_scalar => infix("||", Prec::Or),
            Bo::ShiftLeft | Bo::ShiftRight if matches!(kind, ScalarKind::Sint | ScalarKind::Uint) => {
                let m = if op == Bo::ShiftLeft { "wrapping_shl" } else { "wrapping_shr" };
                if both_scalar {
                    Ex::atom(format!("{}.{m}({})", l.at(Prec::Atom), r.s))
                } else {
                    let name = if op == Bo::ShiftLeft { "shl" } else { "shr" };
                    self.call_lanewise(name, &[(&l, &lt), (&r, &rt)], &wide, &|x| format!("{}.{m}({})", x[0], x[1]))?
                }
            }
            _ => return Err(unsupported(format!("the operator {op:?} on {lt:?} and {rt:?}"))),
        })
    }

    fn cast(&mut self, ctx: &FnCtx<'m>, h: Handle<E>, kind: ScalarKind, convert: Option<u8>) -> R<Ex> {
        let a = self.expr(ctx, h)?;
        let t = self.ty(ctx, h).clone();
        let from = scalar_of(&t).ok_or_else(|| unsupported(format!("a conversion of {t:?}")))?;
        if matches!(t, TypeInner::Matrix { .. }) {
            return Err(unsupported("matrix conversions"));
        }
        let to = match (kind, convert) {
            (ScalarKind::Bool, _) => Scalar::BOOL,
            (k, Some(w)) => Scalar { kind: k, width: w },
            (k, None) => Scalar { kind: k, width: from.width },
        };
        let to_name = scalar_name(to)?;
        let from_name = scalar_name(from)?;
        let rt = match t {
            TypeInner::Vector { size, .. } => TypeInner::Vector { size, scalar: to },
            _ => TypeInner::Scalar(to),
        };
        // The scalar conversion of one lane (`x` is written so that a method call or a cast may
        // follow it).
        let lane: LaneConversion = match (from_name, to_name, convert.is_some()) {
            (f, t, _) if f == t => Box::new(|x: &str| (x.to_string(), Prec::Atom)),
            // Bitcasts.
            ("f32", "u32", false) => Box::new(|x: &str| (format!("{x}.to_bits()"), Prec::Atom)),
            ("f32", "i32", false) => Box::new(|x: &str| (format!("{x}.to_bits() as i32"), Prec::Cast)),
            ("u32", "f32", false) => Box::new(|x: &str| (format!("f32::from_bits({x})"), Prec::Atom)),
            ("i32", "f32", false) => Box::new(|x: &str| (format!("f32::from_bits({x} as u32)"), Prec::Atom)),
            ("i32", "u32", _) | ("u32", "i32", _) => {
                let t = to_name;
                Box::new(move |x: &str| (format!("{x} as {t}"), Prec::Cast))
            }
            // Numeric conversions: Rust's `as` truncates toward zero and saturates (NaN → 0),
            // as WGSL's f32 → integer conversions do.
            ("f32", "i32" | "u32", true) | ("i32" | "u32", "f32", true) => {
                let t = to_name;
                Box::new(move |x: &str| (format!("{x} as {t}"), Prec::Cast))
            }
            ("bool", "f32", _) => Box::new(|x: &str| (format!("if {x} {{ 1.0 }} else {{ 0.0 }}"), Prec::Lowest)),
            ("bool", "i32" | "u32", _) => {
                let t = to_name;
                Box::new(move |x: &str| (format!("{x} as {t}"), Prec::Cast))
            }
            ("f32", "bool", _) => Box::new(|x: &str| (format!("{x} != 0.0"), Prec::Cmp)),
            ("i32" | "u32", "bool", _) => Box::new(|x: &str| (format!("{x} != 0"), Prec::Cmp)),
            (f, t, _) => return Err(unsupported(format!("the conversion {f} → {t}"))),
        };
        match t {
            TypeInner::Scalar(_) => {
                // `f32::from_bits(x)` takes any expression; the other forms need an atom.
                let need = if (from_name, to_name, convert.is_some()) == ("u32", "f32", false) { Prec::Lowest } else { Prec::Atom };
                let (s, p) = lane(&a.at(need));
                Ok(Ex::new(s, p))
            }
            TypeInner::Vector { .. } => {
                if from_name == to_name {
                    return Ok(a);
                }
                // glam's `as_*` conversions are Rust `as` casts lane by lane.
                if convert.is_some() && from_name != "bool" && to_name != "bool" {
                    let method = format!("as_{}vec{}", vector_prefix(to)?.to_ascii_lowercase(), match rt {
                        TypeInner::Vector { size, .. } => vsize(size),
                        _ => 0,
                    });
                    self.inner_name(&rt)?;
                    return Ok(Ex::atom(format!("{}.{method}()", a.at(Prec::Atom))));
                }
                let op = format!("{}_{}", if convert.is_some() { "convert" } else { "bitcast" }, to_name);
                self.call_lanewise(&op, &[(&a, &t)], &rt, &|x| lane(&x[0]).0)
            }
            _ => Err(unsupported(format!("a conversion of {t:?}"))),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn math(&mut self, ctx: &FnCtx<'m>, _h: Handle<E>, fun: Mf, arg: Handle<E>, arg1: Option<Handle<E>>, arg2: Option<Handle<E>>, arg3: Option<Handle<E>>) -> R<Ex> {
        let mut args = Vec::new();
        for a in [Some(arg), arg1, arg2, arg3].into_iter().flatten() {
            args.push((self.expr(ctx, a)?, self.ty(ctx, a).clone()));
        }
        let t0 = args[0].1.clone();
        let kind = scalar_of(&t0).map(|s| s.kind).ok_or_else(|| unsupported(format!("{fun:?} on {t0:?}")))?;
        let is_scalar = matches!(t0, TypeInner::Scalar(_));
        let is_vec = matches!(t0, TypeInner::Vector { .. });
        let float = kind == ScalarKind::Float;
        let recv = args[0].0.at(Prec::Atom);
        let arg_s = |k: usize| args[k].0.s.clone();
        // A method of f32 (scalar) or a glam method of the same name and semantics (vectors).
        let method = |name: &str, n: usize| -> Ex {
            let rest: Vec<String> = (1..n).map(arg_s).collect();
            Ex::atom(format!("{recv}.{name}({})", rest.join(", ")))
        };
        let wide = args.iter().map(|a| a.1.clone()).find(|t| matches!(t, TypeInner::Vector { .. })).unwrap_or(t0.clone());
        macro_rules! lanewise {
            ($op:expr, $ret:expr, $body:expr) => {{
                let refs: Vec<(&Ex, &TypeInner)> = args.iter().map(|(e, t)| (e, t)).collect();
                self.call_lanewise($op, &refs, $ret, &$body)?
            }};
        }
        // Scalar: a method call inline; vector: lane by lane.
        macro_rules! per_lane_method {
            ($op:expr, $m:expr) => {{
                if is_scalar {
                    method($m, args.len())
                } else {
                    let m = $m;
                    lanewise!($op, &wide, |x: &[String]| format!("{}.{m}({})", x[0], x[1..].join(", ")))
                }
            }};
        }
        let fname = format!("{fun:?}").to_ascii_lowercase();
        Ok(match fun {
            Mf::Abs if kind == ScalarKind::Uint => args[0].0.clone(),
            Mf::Abs if kind == ScalarKind::Sint => per_lane_method!("abs", "wrapping_abs"),
            Mf::Abs if float => method("abs", 1),
            Mf::Min | Mf::Max if kind != ScalarKind::Bool => method(if fun == Mf::Min { "min" } else { "max" }, 2),
            // clamp(e, lo, hi) = min(max(e, lo), hi): never panics when lo > hi.
            Mf::Clamp if kind != ScalarKind::Bool => Ex::atom(format!("{recv}.max({}).min({})", arg_s(1), arg_s(2))),
            Mf::Saturate if float => {
                if is_scalar {
                    Ex::atom(format!("{recv}.max(0.0).min(1.0)"))
                } else {
                    let t = self.inner_name(&t0)?;
                    Ex::atom(format!("{recv}.max({t}::ZERO).min({t}::ONE)"))
                }
            }
            Mf::Cos | Mf::Cosh | Mf::Sin | Mf::Sinh | Mf::Tan | Mf::Tanh | Mf::Acos | Mf::Asin | Mf::Atan | Mf::Asinh | Mf::Acosh | Mf::Atanh
            | Mf::Sqrt | Mf::Exp | Mf::Exp2 | Mf::Log2 | Mf::Trunc | Mf::Ceil | Mf::Floor
                if float =>
            {
                if is_vec && matches!(fun, Mf::Floor | Mf::Ceil | Mf::Trunc) {
                    method(&fname, 1)
                } else {
                    per_lane_method!(&fname, fname.as_str())
                }
            }
            Mf::Log if float => per_lane_method!("log", "ln"),
            Mf::Radians if float => per_lane_method!("radians", "to_radians"),
            Mf::Degrees if float => per_lane_method!("degrees", "to_degrees"),
            Mf::Atan2 if float => per_lane_method!("atan2", "atan2"),
            Mf::Pow if float => per_lane_method!("pow", "powf"),
            // WGSL rounds halfway cases to even.
            Mf::Round if float => per_lane_method!("round", "round_ties_even"),
            // WGSL: fract(x) = x - floor(x) (Rust's f32::fract uses trunc).
            Mf::Fract if float => lanewise!("fract", &wide, |x: &[String]| format!("{a} - {a}.floor()", a = x[0])),
            Mf::InverseSqrt if float => lanewise!("inverse_sqrt", &wide, |x: &[String]| format!("1.0 / {}.sqrt()", x[0])),
            // WGSL: sign(0) = 0 (Rust's signum(0.0) is 1.0).
            Mf::Sign if float => {
                lanewise!("sign", &wide, |x: &[String]| format!("if {a} > 0.0 {{ 1.0 }} else if {a} < 0.0 {{ -1.0 }} else {{ 0.0 }}", a = x[0]))
            }
            Mf::Sign if kind == ScalarKind::Sint => per_lane_method!("sign", "signum"),
            Mf::Fma if float => per_lane_method!("fma", "mul_add"),
            // WGSL: mix(a, b, t) = a * (1 - t) + b * t.
            Mf::Mix if float => lanewise!("mix", &wide, |x: &[String]| format!("{} * (1.0 - {t}) + {} * {t}", x[0], x[1], t = x[2])),
            // WGSL: step(edge, x) = 1 if edge <= x else 0.
            Mf::Step if float => lanewise!("step", &wide, |x: &[String]| format!("if {} <= {} {{ 1.0 }} else {{ 0.0 }}", x[0], x[1])),
            Mf::SmoothStep if float => lanewise!("smoothstep", &wide, |x: &[String]| format!(
                "{{\n        let t = (({x} - {lo}) / ({hi} - {lo})).max(0.0).min(1.0);\n        t * t * (3.0 - 2.0 * t)\n    }}",
                lo = x[0],
                hi = x[1],
                x = x[2]
            )),
            Mf::Dot if float && is_vec => method("dot", 2),
            Mf::Dot if is_vec => {
                let n = match t0 {
                    TypeInner::Vector { size, .. } => vsize(size),
                    _ => 0,
                };
                let TypeInner::Vector { scalar, .. } = t0 else { return Err(unsupported("dot of non-vectors")) };
                let ret = TypeInner::Scalar(scalar);
                let name = self.lanewise(&format!("dot{n}"), &[&t0, &t0], &ret, &|_x| {
                    let mut s = "a.x.wrapping_mul(b.x)".to_string();
                    for l in &LANES[1..n] {
                        s = format!("{s}.wrapping_add(a.{l}.wrapping_mul(b.{l}))");
                    }
                    s
                })?;
                Ex::atom(format!("{name}({}, {})", arg_s(0), arg_s(1)))
            }
            Mf::Cross if float => method("cross", 2),
            Mf::Length if float && is_scalar => method("abs", 1),
            Mf::Length if float => method("length", 1),
            Mf::Distance if float && is_scalar => Ex::atom(format!("({} - {}).abs()", args[0].0.at(Prec::Add), args[1].0.at(Prec::Mul))),
            Mf::Distance if float => method("distance", 2),
            // WGSL: normalize(v) = v / length(v).
            Mf::Normalize if float && is_vec => {
                let t = self.inner_name(&t0)?;
                let name = format!("wgsl_normalize_{}", t.to_ascii_lowercase());
                self.helper(&name, || format!("#[inline(always)]\nfn {name}(a: {t}) -> {t} {{\n    a / a.length()\n}}\n"));
                Ex::atom(format!("{name}({})", arg_s(0)))
            }
            Mf::FaceForward if float && is_vec => {
                let t = self.inner_name(&t0)?;
                let name = format!("wgsl_faceforward_{}", t.to_ascii_lowercase());
                self.helper(&name, || {
                    format!("#[inline(always)]\nfn {name}(a: {t}, b: {t}, c: {t}) -> {t} {{\n    if b.dot(c) < 0.0 {{ a }} else {{ -a }}\n}}\n")
                });
                Ex::atom(format!("{name}({}, {}, {})", arg_s(0), arg_s(1), arg_s(2)))
            }
            Mf::Reflect if float && is_vec => {
                let t = self.inner_name(&t0)?;
                let name = format!("wgsl_reflect_{}", t.to_ascii_lowercase());
                self.helper(&name, || format!("#[inline(always)]\nfn {name}(a: {t}, b: {t}) -> {t} {{\n    a - 2.0 * b.dot(a) * b\n}}\n"));
                Ex::atom(format!("{name}({}, {})", arg_s(0), arg_s(1)))
            }
            Mf::Refract if float && is_vec => {
                let t = self.inner_name(&t0)?;
                let name = format!("wgsl_refract_{}", t.to_ascii_lowercase());
                self.helper(&name, || {
                    format!(
                        "#[inline(always)]\nfn {name}(a: {t}, b: {t}, eta: f32) -> {t} {{\n    let d = b.dot(a);\n    let k = 1.0 - eta * eta * (1.0 - d * d);\n    if k < 0.0 {{\n        {t}::ZERO\n    }} else {{\n        eta * a - (eta * d + k.sqrt()) * b\n    }}\n}}\n"
                    )
                });
                Ex::atom(format!("{name}({}, {}, {})", arg_s(0), arg_s(1), arg_s(2)))
            }
            Mf::Transpose | Mf::Determinant | Mf::Inverse if matches!(t0, TypeInner::Matrix { .. }) => method(&fname, 1),
            Mf::CountOneBits | Mf::ReverseBits | Mf::CountLeadingZeros | Mf::CountTrailingZeros if matches!(kind, ScalarKind::Sint | ScalarKind::Uint) => {
                let m = match fun {
                    Mf::CountOneBits => "count_ones",
                    Mf::ReverseBits => "reverse_bits",
                    Mf::CountLeadingZeros => "leading_zeros",
                    _ => "trailing_zeros",
                };
                let cast = if kind == ScalarKind::Sint && fun != Mf::ReverseBits { " as i32" } else { "" };
                if is_scalar {
                    Ex::new(format!("{recv}.{m}(){cast}"), if cast.is_empty() { Prec::Atom } else { Prec::Cast })
                } else {
                    lanewise!(&fname, &wide, |x: &[String]| format!("{}.{m}(){cast}", x[0]))
                }
            }
            Mf::FirstTrailingBit if matches!(kind, ScalarKind::Sint | ScalarKind::Uint) => {
                let (none, ty) = if kind == ScalarKind::Sint { ("-1", "i32") } else { ("u32::MAX", "u32") };
                lanewise!("first_trailing_bit", &wide, |x: &[String]| format!(
                    "if {a} == 0 {{ {none} }} else {{ {a}.trailing_zeros() as {ty} }}",
                    a = x[0]
                ))
            }
            Mf::FirstLeadingBit if kind == ScalarKind::Uint => {
                lanewise!("first_leading_bit", &wide, |x: &[String]| format!("if {a} == 0 {{ u32::MAX }} else {{ 31 - {a}.leading_zeros() }}", a = x[0]))
            }
            Mf::FirstLeadingBit if kind == ScalarKind::Sint => lanewise!("first_leading_bit", &wide, |x: &[String]| format!(
                "{{\n        let v = if {a} < 0 {{ !{a} }} else {{ {a} }};\n        if v == 0 {{ -1 }} else {{ 31 - v.leading_zeros() as i32 }}\n    }}",
                a = x[0]
            )),
            _ => return Err(unsupported(format!("the builtin {fun:?} on {t0:?}"))),
        })
    }
}

// ---------------------------------------------------------------- pattern kernels

struct Field {
    name: String,
    expr: String,
}

struct Slot {
    name: String,
    offset: usize,
    components: usize,
}

#[derive(Template)]
#[template(path = "pattern_kernel.rs", escape = "none")]
struct RustKernelTemplate<'a> {
    source: &'a str,
    naga_version: &'a str,
    module: &'a str,
    geometry_stride: usize,
    input_stride: usize,
    output_stride: usize,
    /// Column indices of the geometry and input buffers, and the output column names.
    geometry_columns: Vec<usize>,
    input_columns: Vec<usize>,
    output_columns: Vec<String>,
    texture_count: usize,
    inputs: Vec<Slot>,
    outputs: Vec<Slot>,
    geometry_struct: String,
    geometry_fields: Vec<Field>,
    inputs_struct: Option<String>,
    input_fields: Vec<Field>,
    call: String,
    uses_tex: bool,
    output_stores: Vec<String>,
}

/// Writes a pattern kernel as Rust: [`write_rust`] of its module (with the `MxTextures` trait
/// always declared) followed by `mx_pattern_batch`, the structure-of-arrays loop over points
/// (askama template `templates/pattern_kernel.rs`).
pub fn write_rust_kernel(kernel: &PatternKernel) -> Result<String, RustError> {
    write_rust_kernel_with(kernel, &RustOptions::default())
}

/// The library's albedo tables as one Rust item, `pub static {name}: [f32; N] = [...];`, for
/// the kernels written with [`RustOptions::albedo_table_data`] naming it (each value printed
/// so that it reads back to the same f32).
pub fn write_albedo_table_static(name: &str, data: &[f32]) -> String {
    let mut s = format!("pub static {name}: [f32; {}] = [\n", data.len());
    for row in data.chunks(16) {
        s.push_str("    ");
        for v in row {
            let _ = write!(s, "{v:?}, ");
        }
        s.push('\n');
    }
    s.push_str("];\n");
    s
}

/// [`write_rust_kernel`] with options (for instance a shared texture trait).
pub fn write_rust_kernel_with(kernel: &PatternKernel, options: &RustOptions) -> Result<String, RustError> {
    // Kernels that read the albedo tables have a CPU form reading them as a constant array.
    let (module, info) = match &kernel.cpu_module {
        Some((m, i)) => (m, i),
        None => (&kernel.module, &kernel.info),
    };
    let (body, facts) = write_module(module, info, options, true)?;
    let kernel_err = |what: String| RustError { construct: what, function: Some("mx_pattern".into()) };
    let (ph, pf) = module
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some("mx_pattern"))
        .ok_or_else(|| kernel_err("a pattern kernel without an `mx_pattern` function".into()))?;
    let struct_of = |name: &str| facts.struct_names.get(name).cloned();
    let member_names = |h: Handle<naga::Type>| -> Vec<(String, String)> {
        match &module.types[h].inner {
            TypeInner::Struct { members, .. } => members
                .iter()
                .enumerate()
                .map(|(k, m)| (m.name.clone().unwrap_or_default(), facts.names[&NameKey::StructMember(h, k as u32)].clone()))
                .collect(),
            _ => Vec::new(),
        }
    };
    // Geometry: every field of `mx_geometry` from its place in a geometry row; bitangents are
    // normal × tangent, as in the WGSL kernel.
    let (gh, geometry_struct) = struct_of("mx_geometry").ok_or_else(|| kernel_err("a pattern kernel without `mx_geometry`".into()))?;
    let geometry_members = member_names(gh);
    let load3 = |buf: &str, o: usize| format!("Vec3::new({buf}{o}[mx_i], {buf}{}[mx_i], {buf}{}[mx_i])", o + 1, o + 2);
    let prop_offset = |field: &str| GEOMETRY_LAYOUT.iter().find(|(p, _)| p.field() == field).map(|(_, o)| *o);
    let mut geometry_fields = Vec::new();
    for (wgsl_name, rust_name) in &geometry_members {
        let expr = match (prop_offset(wgsl_name), wgsl_name.strip_prefix("bitangent_")) {
            (Some(o), _) if wgsl_name == "texcoord" => format!("Vec2::new(mx_g{o}[mx_i], mx_g{}[mx_i])", o + 1),
            (Some(o), _) => load3("mx_g", o),
            (None, Some(space)) => {
                let n = prop_offset(&format!("normal_{space}")).ok_or_else(|| kernel_err(format!("the geometry field `{wgsl_name}`")))?;
                let t = prop_offset(&format!("tangent_{space}")).ok_or_else(|| kernel_err(format!("the geometry field `{wgsl_name}`")))?;
                format!("{}.cross({})", load3("mx_g", n), load3("mx_g", t))
            }
            _ => return Err(kernel_err(format!("the geometry field `{wgsl_name}`"))),
        };
        geometry_fields.push(Field { name: rust_name.clone(), expr });
    }
    // Interface inputs, in the order of `MxInputs`.
    let (inputs_struct, input_fields) = match struct_of("MxInputs") {
        Some((ih, name)) => {
            let members = member_names(ih);
            if members.len() != kernel.inputs.len() {
                return Err(kernel_err("`MxInputs` that does not match the kernel's inputs".into()));
            }
            let mut fields = Vec::new();
            for ((_, rust_name), inp) in members.iter().zip(&kernel.inputs) {
                fields.push(Field { name: rust_name.clone(), expr: load_row(&inp.input.ty, "mx_x", inp.offset).map_err(kernel_err)? });
            }
            (Some(name), fields)
        }
        None if kernel.inputs.is_empty() => (None, Vec::new()),
        None => return Err(kernel_err("a kernel with inputs but no `MxInputs`".into())),
    };
    let (oh, _) = struct_of("MxOutputs").ok_or_else(|| kernel_err("a pattern kernel without `MxOutputs`".into()))?;
    let out_members = member_names(oh);
    if out_members.len() != kernel.outputs.len() {
        return Err(kernel_err("`MxOutputs` that does not match the kernel's outputs".into()));
    }
    let mut output_stores = Vec::new();
    for ((_, rust_name), out) in out_members.iter().zip(&kernel.outputs) {
        output_stores.extend(store_row(&out.ty, &format!("mx_out.{rust_name}"), out.offset).map_err(kernel_err)?);
    }
    // The call: `tex` first when the pattern reads textures, then geometry and inputs.
    let pattern_name = facts.names[&NameKey::Function(ph)].clone();
    let mut args = Vec::new();
    if facts.needs_tex[ph.index()] {
        args.push("tex".to_string());
    }
    for a in &pf.arguments {
        match facts.struct_names.iter().find(|(_, (h, _))| *h == a.ty).map(|(n, _)| n.as_str()) {
            Some("mx_geometry") => args.push("mx_geom".into()),
            Some("MxInputs") => args.push("mx_inputs".into()),
            _ => return Err(kernel_err("an `mx_pattern` argument other than the geometry and the inputs".into())),
        }
    }
    let uses_tex = args.first().is_some_and(|a| a == "tex");
    let call = format!("{pattern_name}({})", args.join(", "));
    let slots = |v: Vec<(String, usize, usize)>| v.into_iter().map(|(name, offset, components)| Slot { name: format!("{name:?}"), offset, components }).collect();
    let source = kernel.source_name();
    let template = RustKernelTemplate {
        source,
        naga_version: NAGA_VERSION,
        module: &body,
        geometry_stride: GEOMETRY_STRIDE,
        input_stride: kernel.input_stride,
        output_stride: kernel.output_stride,
        geometry_columns: (0..GEOMETRY_STRIDE).collect(),
        input_columns: (0..kernel.input_stride).collect(),
        output_columns: (0..kernel.output_stride).map(|k| format!("mx_o{k}")).collect(),
        texture_count: kernel.textures.len(),
        inputs: slots(kernel.inputs.iter().map(|i| (i.input.name.clone(), i.offset, i.input.ty.components().unwrap_or(0))).collect()),
        outputs: slots(kernel.outputs.iter().map(|o| (o.name.clone(), o.offset, o.ty.components().unwrap_or(0))).collect()),
        geometry_struct,
        geometry_fields,
        inputs_struct,
        input_fields,
        call,
        uses_tex,
        output_stores,
    };
    let mut text = template.render().map_err(|e| unsupported(format!("(template error) {e}")))?;
    if !text.ends_with('\n') {
        text.push('\n');
    }
    Ok(text)
}

/// Reads a value of MaterialX type `ty` from point `mx_i` of columns `offset..` (column `c` is
/// the local `{buf}{c}`), as the WGSL kernel does.
fn load_row(ty: &DataType, buf: &str, offset: usize) -> Result<String, String> {
    let at = |k: usize| format!("{buf}{}[mx_i]", offset + k);
    let list = |n: usize| (0..n).map(at).collect::<Vec<_>>().join(", ");
    Ok(match ty {
        DataType::Boolean => format!("{} != 0.0", at(0)),
        DataType::Integer => format!("{} as i32", at(0)),
        DataType::Float => at(0),
        DataType::Vector2 => format!("Vec2::new({})", list(2)),
        DataType::Vector3 | DataType::Color3 => format!("Vec3::new({})", list(3)),
        DataType::Vector4 | DataType::Color4 => format!("Vec4::new({})", list(4)),
        DataType::Matrix33 => format!("Mat3::from_cols_array(&[{}])", list(9)),
        DataType::Matrix44 => format!("Mat4::from_cols_array(&[{}])", list(16)),
        other => return Err(format!("an interface input of type {other}")),
    })
}

/// Stores `value` (of MaterialX type `ty`) into point `mx_i` of output columns `offset..` (column
/// `c` is the local `mx_o{c}`), one statement per component.
fn store_row(ty: &DataType, value: &str, offset: usize) -> Result<Vec<String>, String> {
    let at = |k: usize| format!("mx_o{}[mx_i]", offset + k);
    Ok(match ty {
        DataType::Boolean => vec![format!("{} = if {value} {{ 1.0 }} else {{ 0.0 }};", at(0))],
        DataType::Integer => vec![format!("{} = {value} as f32;", at(0))],
        DataType::Float => vec![format!("{} = {value};", at(0))],
        DataType::Matrix33 | DataType::Matrix44 => {
            let n = if *ty == DataType::Matrix33 { 3 } else { 4 };
            (0..n * n).map(|k| format!("{} = {value}.{}_axis.{};", at(k), LANES[k / n], LANES[k % n])).collect()
        }
        t => match t.components() {
            Some(n) if n <= 4 => (0..n).map(|k| format!("{} = {value}.{};", at(k), LANES[k])).collect(),
            _ => return Err(format!("an output of type {t}")),
        },
    })
}

fn unreachable_call_result() -> R<Ex> {
    Err(unsupported("a call result used before its call"))
}

/// The operator precedence one step tighter than `p`.
fn next_prec(p: Prec) -> Prec {
    match p {
        Prec::Lowest => Prec::Or,
        Prec::Or => Prec::And,
        Prec::And => Prec::Cmp,
        Prec::Cmp => Prec::BitOr,
        Prec::BitOr => Prec::BitXor,
        Prec::BitXor => Prec::BitAnd,
        Prec::BitAnd => Prec::Shift,
        Prec::Shift => Prec::Add,
        Prec::Add => Prec::Mul,
        Prec::Mul => Prec::Cast,
        Prec::Cast => Prec::Unary,
        Prec::Unary | Prec::Atom => Prec::Atom,
    }
}

/// The scalar of a scalar, vector or matrix type.
fn scalar_of(t: &TypeInner) -> Option<Scalar> {
    match *t {
        TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } | TypeInner::Matrix { scalar: s, .. } => Some(s),
        _ => None,
    }
}

/// The boolean type of the same shape as `t`.
fn bool_like(t: &TypeInner) -> TypeInner {
    match *t {
        TypeInner::Vector { size, .. } => TypeInner::Vector { size, scalar: Scalar::BOOL },
        _ => TypeInner::Scalar(Scalar::BOOL),
    }
}

/// Whether `s` is UpperCamelCase as rustc's `non_camel_case_types` lint wants it.
fn is_camel(s: &str) -> bool {
    let t = s.trim_matches('_');
    t.chars().next().is_some_and(|c| c.is_ascii_uppercase()) && !t.contains('_')
}

/// Functions called anywhere in `block`.
fn collect_calls(block: &naga::Block, out: &mut Vec<Handle<Function>>) {
    for s in block.iter() {
        match s {
            S::Call { function, .. } => out.push(*function),
            S::Block(b) => collect_calls(b, out),
            S::If { accept, reject, .. } => {
                collect_calls(accept, out);
                collect_calls(reject, out);
            }
            S::Switch { cases, .. } => cases.iter().for_each(|c| collect_calls(&c.body, out)),
            S::Loop { body, continuing, .. } => {
                collect_calls(body, out);
                collect_calls(continuing, out);
            }
            _ => {}
        }
    }
}

/// The local variable a pointer expression points into.
fn local_root(exprs: &naga::Arena<E>, mut h: Handle<E>) -> Option<Handle<naga::LocalVariable>> {
    loop {
        match exprs[h] {
            E::LocalVariable(l) => return Some(l),
            E::Access { base, .. } | E::AccessIndex { base, .. } => h = base,
            _ => return None,
        }
    }
}

/// Local variables stored to anywhere in `block`.
fn collect_stores(block: &naga::Block, exprs: &naga::Arena<E>, out: &mut HashSet<Handle<naga::LocalVariable>>) {
    for s in block.iter() {
        match s {
            S::Store { pointer, .. } => {
                if let Some(l) = local_root(exprs, *pointer) {
                    out.insert(l);
                }
            }
            S::Block(b) => collect_stores(b, exprs, out),
            S::If { accept, reject, .. } => {
                collect_stores(accept, exprs, out);
                collect_stores(reject, exprs, out);
            }
            S::Switch { cases, .. } => cases.iter().for_each(|c| collect_stores(&c.body, exprs, out)),
            S::Loop { body, continuing, .. } => {
                collect_stores(body, exprs, out);
                collect_stores(continuing, exprs, out);
            }
            _ => {}
        }
    }
}

/// Expressions covered by `Emit` statements anywhere in `block`.
fn collect_emitted(block: &naga::Block, out: &mut HashSet<Handle<E>>) {
    for s in block.iter() {
        match s {
            S::Emit(range) => out.extend(range.clone()),
            S::Block(b) => collect_emitted(b, out),
            S::If { accept, reject, .. } => {
                collect_emitted(accept, out);
                collect_emitted(reject, out);
            }
            S::Switch { cases, .. } => cases.iter().for_each(|c| collect_emitted(&c.body, out)),
            S::Loop { body, continuing, .. } => {
                collect_emitted(body, out);
                collect_emitted(continuing, out);
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    //! Text-level checks of the WGSL semantics the writer keeps; the same constructs are
    //! compiled and run by the test crate `tests/rs_compile` (tests/wgsl/semantics.wgsl).
    use super::*;

    fn rust_of(wgsl: &str) -> Result<String, RustError> {
        let module = naga::front::wgsl::parse_str(wgsl).unwrap_or_else(|e| panic!("{}", e.emit_to_string(wgsl)));
        let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(wgsl)));
        write_rust(&module, &info, &RustOptions::default())
    }

    fn rust(wgsl: &str) -> String {
        rust_of(wgsl).unwrap_or_else(|e| panic!("{e}"))
    }

    #[track_caller]
    fn has(text: &str, needle: &str) {
        assert!(text.contains(needle), "expected `{needle}` in:\n{text}");
    }

    #[test]
    fn header_and_inline_always_on_every_function() {
        let t = rust("fn f(a: f32) -> f32 { return a; }\nfn g(a: f32) -> f32 { return f(a) * 2.0; }");
        assert!(t.starts_with("// Generated by uplift (writer: uplift_compiler::backend_rust"), "{t}");
        assert_eq!(t.matches("#[inline(always)]").count(), t.matches("fn ").count(), "{t}");
        has(&t, "pub fn g(a_1: f32) -> f32 {\n    let _e1 = f(a_1);\n    _e1 * 2.0f32\n}");
        assert!(!t.contains("unsafe"));
    }

    #[test]
    fn integer_arithmetic_wraps_and_division_by_zero_is_defined() {
        let t = rust(
            "fn f(a: i32, b: i32) -> i32 { return (a + b) * a - b; }
             fn d(a: i32, b: i32) -> i32 { return a / b + a % b; }
             fn u(a: vec3<u32>, b: u32) -> vec3<u32> { return (a + b) / a; }",
        );
        has(&t, "a.wrapping_add(b).wrapping_mul(a).wrapping_sub(b)");
        has(&t, "a.checked_div(b).unwrap_or(a)");
        has(&t, "a.checked_rem(b).unwrap_or(0)");
        has(&t, "wrapping_add(UVec3::splat(b_2))");
        has(&t, "fn wgsl_div_uvec3_uvec3(a: UVec3, b: UVec3) -> UVec3 {\n    UVec3::new(a.x.checked_div(b.x).unwrap_or(a.x),");
    }

    #[test]
    fn float_remainder_truncates_and_round_is_half_to_even() {
        let t = rust("fn f(a: f32, b: f32) -> f32 { return round(a % b) + fract(a) + sign(b); }");
        has(&t, "a - b * (a / b).trunc()");
        has(&t, ".round_ties_even()");
        has(&t, "a - a.floor()");
        has(&t, "if a > 0.0 { 1.0 } else if a < 0.0 { -1.0 } else { 0.0 }");
    }

    #[test]
    fn casts() {
        let t = rust(
            "fn f(x: f32, b: bool, v: vec2<f32>) -> i32 { return i32(x) + i32(bitcast<u32>(x)) + i32(f32(b)) + vec2<i32>(v).x; }
             fn g(x: i32) -> bool { return f32(x) < 1.0 && u32(x) < 2u; }",
        );
        has(&t, "x as i32");
        has(&t, "x.to_bits() as i32");
        has(&t, "(if b { 1.0 } else { 0.0 }) as i32");
        has(&t, "v.as_ivec2().x");
        // `x as T < y` would parse as generics: the cast is parenthesised.
        has(&t, "if (x_1 as f32) < 1.0f32 {\n        local = (x_1 as u32) < 2u32;");
    }

    #[test]
    fn precedence_is_kept_with_minimal_parentheses() {
        let t = rust("fn f(a: f32, b: f32, c: f32) -> f32 { return (a + b) * c - (a - (b - c)) + -a * abs(-b); }");
        has(&t, "(a + b) * c - (a - (b - c)) + -a * (-b).abs()");
    }

    #[test]
    fn vector_scalar_broadcast_and_builtins() {
        let t = rust(
            "fn f(v: vec3<f32>, s: f32) -> vec3<f32> { return clamp(v * s + 1.0, vec3(0.0), vec3(1.0)) + mix(v, v, s) + smoothstep(vec3(0.0), vec3(1.0), v); }",
        );
        has(&t, "(v * s + Vec3::splat(1.0f32)).max(");
        has(&t, ".max(Vec3::splat(0.0f32)).min(Vec3::splat(1.0f32))");
        has(&t, "fn wgsl_mix_vec3_vec3_f32(a: Vec3, b: Vec3, c: f32) -> Vec3");
        has(&t, "fn wgsl_smoothstep_vec3_vec3_vec3");
    }

    #[test]
    fn rust_keywords_are_renamed() {
        let t = rust("fn f(in: f32, mut_: f32) -> f32 { let match_ = in; return match_ + mut_; }\nfn move_it(box: f32) -> f32 { return f(box, box); }");
        has(&t, "pub fn f(in_: f32, mut_: f32) -> f32");
        has(&t, "fn move_it(box_: f32)");
    }

    #[test]
    fn textures_become_indices_through_the_trait() {
        let t = rust(
            "@group(0) @binding(6) var img: texture_2d<f32>;
             fn texel(t: texture_2d<f32>, p: vec2<i32>) -> vec4<f32> { return textureLoad(t, p, 0); }
             fn f(p: vec2<i32>) -> vec4<f32> { let d = textureDimensions(img); return texel(img, p + vec2<i32>(d)); }",
        );
        has(&t, "pub trait MxTextures");
        has(&t, "pub fn texel(tex: &(impl MxTextures + ?Sized), t: usize, p: IVec2) -> Vec4");
        has(&t, "wgsl_texture_load_ivec2(tex, t, p)");
        has(&t, "let d = tex.dimensions(2usize);");
        has(&t, "texel(tex, 2usize, ");
    }

    #[test]
    fn unsupported_constructs_are_named_errors() {
        let e = rust_of("var<private> counter: f32;\nfn f() -> f32 { counter += 1.0; return counter; }").unwrap_err();
        assert!(e.construct.contains("global variable `counter`"), "{e}");
        assert_eq!(e.function.as_deref(), Some("f"));
        let e = rust_of("fn f(p: ptr<function, f32>) -> f32 { return *p; }").unwrap_err();
        assert!(e.to_string().contains("pointer arguments"), "{e}");
        let e = rust_of(
            "@group(0) @binding(4) var t: texture_2d<f32>;\n@group(0) @binding(5) var s: sampler;\nfn f(uv: vec2<f32>) -> vec4<f32> { return textureSampleLevel(t, s, uv, 0.0); }",
        )
        .unwrap_err();
        assert!(e.to_string().contains("sampler"), "{e}");
        let e = rust_of("fn f(a: f32) -> f32 { return dpdx(a); }").unwrap_err();
        assert!(e.to_string().contains("derivatives"), "{e}");
    }

    #[test]
    fn switch_break_and_loop_continue() {
        let t = rust(
            "fn f(n: i32) -> i32 { var s = 0; for (var i = 0; i < n; i++) { switch i { case 0, 1: { if (i == 1) { break; } s += 1; } default: { continue; } } } return s; }",
        );
        has(&t, "'sw: {");
        has(&t, "0i32 | 1i32 => {");
        has(&t, "break 'sw;");
        has(&t, "continue 'l;");
        has(&t, "'l: loop {");
    }
}
