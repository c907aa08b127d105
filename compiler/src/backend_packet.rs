//! naga → packet Rust (issue 24, first stage): every WGSL function becomes a Rust function
//! generic over a SIMD level `S: uplift_simd::Simd`, computing one packet of points per call —
//! a WGSL `f32` is an `S::F` (lane k = point k), `i32`/`u32` are `S::I`/`S::U`, `bool` is a
//! mask `S::M`, and `vecN<f32>` is `[S::F; N]` (structure of arrays). Operations are the SIMD
//! layer's (`uplift_simd`), whose semantics are WGSL's, so the packet functions compute what
//! the scalar writer's (`backend_rust.rs`, the oracle) compute, lane by lane.
//!
//! This stage covers straight-line code: literals and constants (splatted), arguments, scalar
//! and f32-vector arithmetic, comparisons, `select`, conversions between f32, i32 and u32,
//! swizzles and component access, local variables, calls between the module's functions, and
//! the math built-ins the layer has (transcendentals run lane by lane through `F32s::map`).
//! Float division is `x · rcp(y)` and `inverseSqrt` is `rsqrt`, each the hardware estimate
//! refined by one Newton step (`uplift_simd`: 2 ulp), within WGSL's precision (2.5 ulp for
//! `x / y` with |y| in [2⁻¹²⁶, 2¹²⁶], 2 ulp for `inverseSqrt`); `sqrt` stays correctly rounded.
//! An `if` runs ISPC's mask-mixed way: each side under the mask of the lanes that take it,
//! skipped when none does, its stores blended into the locals; a `return` inside one stores its
//! lanes' result into `_ret` and marks them done (`_done`, ISPC's return mask), later returns
//! leave done lanes alone, and the function leaves as soon as every lane is done. A loop runs
//! while some lane still loops, `break` and `continue` lanes recorded in masks and stores
//! blended under the looping lanes'. A `switch` runs each case under the mask of the lanes its
//! values pick. A call whose result only one side of `select`s needs runs only where some
//! active lane takes that side (`packet_guards.rs`): WGSL's `select` evaluates both sides, and
//! a kernel would otherwise pay for the thin-film Airy Fresnel at film thickness 0. The next stage is the variance analysis of `variance.rs` keeping uniform
//! branches and loop counters scalar (today every loop and branch is treated as varying:
//! correct, but slower, and a masked loop's trip count is unknown to LLVM). Matrices, local
//! arrays, textures and integer or boolean vectors are a [`PacketError`] naming the construct.
//! Generated code has no `unsafe`.

use naga::proc::{CaseInsensitiveKeywordSet, KeywordSet, NameKey, Namer};
use naga::{BinaryOperator as Bo, Expression as E, Function, Handle, Literal, MathFunction as Mf, Module, ScalarKind, Statement, TypeInner, UnaryOperator as Uo, VectorSize};
use std::collections::HashMap;
use std::fmt::{self, Write as _};

/// A construct this stage of the packet writer does not handle.
#[derive(Debug, Clone, PartialEq)]
pub struct PacketError {
    pub construct: String,
    pub function: Option<String>,
}

impl fmt::Display for PacketError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.function {
            Some(func) => write!(f, "the packet writer does not handle {} (in `{func}`)", self.construct),
            None => write!(f, "the packet writer does not handle {}", self.construct),
        }
    }
}

impl std::error::Error for PacketError {}

type R<T> = Result<T, PacketError>;

pub(crate) fn unsupported(what: impl Into<String>) -> PacketError {
    PacketError { construct: what.into(), function: None }
}

/// The packet kind of a WGSL type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Ty {
    /// A scalar of this kind (`S::F`, `S::I`, `S::U`, `S::M`).
    Scalar(ScalarKind),
    /// `vecN<f32>`: `[S::F; N]`.
    Vec(usize),
    /// A struct: `Name<S>`, its members packets.
    Struct(Handle<naga::Type>),
}

fn vsize(s: VectorSize) -> usize {
    match s {
        VectorSize::Bi => 2,
        VectorSize::Tri => 3,
        VectorSize::Quad => 4,
    }
}

pub(crate) fn ty_of(inner: &TypeInner) -> R<Ty> {
    match *inner {
        TypeInner::Scalar(s) if s.width == 4 || s.kind == ScalarKind::Bool => Ok(Ty::Scalar(s.kind)),
        TypeInner::Vector { size, scalar } if scalar.kind == ScalarKind::Float && scalar.width == 4 => Ok(Ty::Vec(vsize(size))),
        ref other => Err(unsupported(format!("the type {other:?}"))),
    }
}

/// The packet kind of the type `th` (structs by handle).
pub(crate) fn ty_of_handle(module: &Module, th: Handle<naga::Type>) -> R<Ty> {
    match &module.types[th].inner {
        TypeInner::Struct { .. } => Ok(Ty::Struct(th)),
        inner => ty_of(inner),
    }
}

pub(crate) fn rust_type(t: Ty, names: &naga::FastHashMap<NameKey, String>) -> String {
    match t {
        Ty::Scalar(ScalarKind::Float) => "S::F".into(),
        Ty::Scalar(ScalarKind::Sint) => "S::I".into(),
        Ty::Scalar(ScalarKind::Uint) => "S::U".into(),
        Ty::Scalar(_) => "S::M".into(),
        Ty::Vec(n) => format!("[S::F; {n}]"),
        Ty::Struct(th) => format!("{}<S>", names[&NameKey::Type(th)]),
    }
}

/// `on` where mask `m` is on, else `off`, for a value of type `t`.
fn blend(m: &str, on: &str, off: &str, t: Ty, names: &naga::FastHashMap<NameKey, String>) -> String {
    match t {
        Ty::Scalar(ScalarKind::Float) => format!("{m}.select({on}, {off})"),
        Ty::Scalar(ScalarKind::Sint) => format!("{m}.select_i({on}, {off})"),
        Ty::Scalar(ScalarKind::Uint) => format!("{m}.select_u({on}, {off})"),
        Ty::Scalar(_) => format!("(({m} & {on}) | (!{m} & {off}))"),
        Ty::Vec(n) => format!("uplift_simd::vector::select_all::<S, {n}>({m}, {on}, {off})"),
        Ty::Struct(th) => format!("{}::<S>::select({m}, {on}, {off})", names[&NameKey::Type(th)]),
    }
}

/// The packet struct for a WGSL struct whose members the writer handles: the struct, and its
/// lane blend (stores and returns under masks). `None` for others.
fn write_struct(module: &Module, th: Handle<naga::Type>, names: &naga::FastHashMap<NameKey, String>) -> Option<String> {
    let TypeInner::Struct { members, .. } = &module.types[th].inner else { return None };
    let name = &names[&NameKey::Type(th)];
    let mut fields = String::new();
    let mut blends = Vec::new();
    for (k, m) in members.iter().enumerate() {
        let t = ty_of_handle(module, m.ty).ok()?;
        if t == Ty::Struct(th) {
            return None;
        }
        let field = &names[&NameKey::StructMember(th, k as u32)];
        let _ = writeln!(fields, "    pub {field}: {},", rust_type(t, names));
        blends.push(format!("{field}: {}", blend("m", &format!("on.{field}"), &format!("off.{field}"), t, names)));
    }
    Some(format!(
        "#[derive(Clone, Copy, Debug)]\n#[allow(non_camel_case_types)]\npub struct {name}<S: Simd> {{\n{fields}}}\n\nimpl<S: Simd> {name}<S> {{\n    #[inline(always)]\n    #[allow(unused_parens)]\n    pub fn select(m: S::M, on: Self, off: Self) -> Self {{\n        {name} {{ {} }}\n    }}\n}}\n",
        blends.join(", ")
    ))
}

/// The scalar writer's reserved names, and the level token `s` every packet function takes.
fn reserved_set() -> &'static KeywordSet {
    static SET: std::sync::OnceLock<KeywordSet> = std::sync::OnceLock::new();
    SET.get_or_init(|| KeywordSet::from_iter(crate::backend_rust::RESERVED.iter().copied().chain(["s", "S"])))
}

/// Prefixes of the writer's own names (bound expressions, masks, loop and return state).
const RESERVED_PREFIXES: &[&str] = &["_e", "_m", "_lm", "_brk", "_sbrk", "_cont", "_ret", "_done", "wgsl_"];

/// The Rust names of `module`'s items, clear of the writer's own names.
pub(crate) fn packet_names(module: &Module) -> naga::FastHashMap<NameKey, String> {
    let mut names = naga::FastHashMap::default();
    Namer::default().reset(module, reserved_set(), KeywordSet::empty(), CaseInsensitiveKeywordSet::empty(), RESERVED_PREFIXES, &mut names);
    names
}

/// Options of the packet writer.
#[derive(Clone, Debug, Default)]
pub struct PacketOptions {
    /// A path to a `static [f32; N]` holding the albedo tables (`mx_albedo_table_data`), as the
    /// scalar writer's `RustOptions::albedo_table_data`: written as a `use` instead of the
    /// array's values. `None` writes every constant array as a `static`.
    pub table_data: Option<String>,
    /// A kernel's packet module has only its grouped batch entry (`packet_kernel.rs`), not
    /// the unsplit one.
    pub grouped_only: bool,
}

/// Writes every function of `module` as a packet function, with default options.
pub fn write_packet(module: &Module) -> R<String> {
    write_packet_with(module, &PacketOptions::default())
}

/// Writes `module`'s structs, constant f32 arrays (`static`s, read by gathers) and functions.
pub fn write_packet_with(module: &Module, options: &PacketOptions) -> R<String> {
    let names = packet_names(module);
    let mut out = String::new();
    out += "#[allow(unused_imports)]\nuse uplift_simd::{F32s, I32s, M32s, Simd, U32s};\n";
    for (th, t) in module.types.iter() {
        if matches!(t.inner, TypeInner::Struct { .. }) {
            if let Some(text) = write_struct(module, th, &names) {
                out += "\n";
                out += &text;
            }
        }
    }
    for (h, c) in module.constants.iter() {
        let TypeInner::Array { base, size: naga::ArraySize::Constant(n), .. } = module.types[c.ty].inner else { continue };
        if module.types[base].inner != TypeInner::Scalar(naga::Scalar::F32) {
            continue;
        }
        let name = &names[&NameKey::Constant(h)];
        match (&options.table_data, c.name.as_deref()) {
            (Some(path), Some(crate::node_library::TABLE_DATA)) => out += &format!("\n#[allow(unused_imports)]\npub use {path} as {name};\n"),
            _ => {
                let E::Compose { components, .. } = &module.global_expressions[c.init] else {
                    return Err(unsupported(format!("the constant array `{name}` (not a list of values)")));
                };
                let mut values = Vec::new();
                for v in components {
                    match module.global_expressions[*v] {
                        E::Literal(Literal::F32(x)) => values.push(format!("{x:?}")),
                        _ => return Err(unsupported(format!("the constant array `{name}` (not a list of literals)"))),
                    }
                }
                out += &format!("\n#[allow(non_upper_case_globals)]\npub static {name}: [f32; {n}] = [{}];\n", values.join(", "));
            }
        }
    }
    let outlined = outlined_functions(module);
    let pure = crate::packet_guards::pure_functions(module);
    for (h, f) in module.functions.iter() {
        out += "\n";
        out += &write_function(module, &names, h, f, &outlined, &pure)?;
    }
    Ok(out)
}

/// [`write_packet_with`], followed by the dependence-split passes of the function named
/// `entry` (`packet_split.rs`), the members of its struct arguments named in `point_members`
/// per point and everything else per group; the entry's passes, `None` where it does not split.
pub fn write_packet_split(module: &Module, options: &PacketOptions, entry: &str, point_members: &[&str]) -> R<(String, Option<crate::packet_split::SplitInstance>)> {
    let mut out = write_packet_with(module, options)?;
    let Some((eh, _)) = module.functions.iter().find(|(_, f)| f.name.as_deref() == Some(entry)) else {
        return Err(unsupported(format!("a split entry `{entry}` the module lacks")));
    };
    let names = packet_names(module);
    let outlined = outlined_functions(module);
    let pure = crate::packet_guards::pure_functions(module);
    let (text, instance, _refused) = crate::packet_split::split_entry(module, &names, &outlined, &pure, eh, point_members);
    out += &text;
    Ok((out, instance))
}

/// Whether `block` holds a `return` (at any depth).
fn returns_in(block: &naga::Block) -> bool {
    block.iter().any(|s| match s {
        Statement::Return { .. } => true,
        Statement::Block(b) => returns_in(b),
        Statement::If { accept, reject, .. } => returns_in(accept) || returns_in(reject),
        Statement::Switch { cases, .. } => cases.iter().any(|c| returns_in(&c.body)),
        Statement::Loop { body, continuing, .. } => returns_in(body) || returns_in(continuing),
        _ => false,
    })
}

/// Whether `block` leaves its loop or function early (`break`, `continue`, `return`), outside
/// nested loops for the first two.
fn jumps_in(block: &naga::Block) -> bool {
    block.iter().any(|s| match s {
        Statement::Break | Statement::Continue | Statement::Return { .. } => true,
        Statement::Block(b) => jumps_in(b),
        Statement::If { accept, reject, .. } => jumps_in(accept) || jumps_in(reject),
        Statement::Loop { body, continuing, .. } => returns_in(body) || returns_in(continuing),
        Statement::Switch { cases, .. } => cases.iter().any(|c| continues_or_returns(&c.body)),
        _ => false,
    })
}

/// Whether `block` holds a `continue` of the enclosing loop or a `return` (a switch case: its
/// `break` ends the switch only).
fn continues_or_returns(block: &naga::Block) -> bool {
    block.iter().any(|s| match s {
        Statement::Continue | Statement::Return { .. } => true,
        Statement::Block(b) => continues_or_returns(b),
        Statement::If { accept, reject, .. } => continues_or_returns(accept) || continues_or_returns(reject),
        Statement::Switch { cases, .. } => cases.iter().any(|c| continues_or_returns(&c.body)),
        Statement::Loop { body, continuing, .. } => returns_in(body) || returns_in(continuing),
        _ => false,
    })
}

/// Whether `block` returns from inside an `if` (`inside`: `block` is inside one).
pub(crate) fn masked_return(block: &naga::Block, inside: bool) -> bool {
    block.iter().any(|s| match s {
        Statement::Return { .. } => inside,
        Statement::Block(b) => masked_return(b, inside),
        Statement::If { accept, reject, .. } => masked_return(accept, true) || masked_return(reject, true),
        Statement::Switch { cases, .. } => cases.iter().any(|c| masked_return(&c.body, true)),
        Statement::Loop { body, continuing, .. } => masked_return(body, true) || masked_return(continuing, true),
        _ => false,
    })
}

/// One function as a packet function.
/// Expressions (counting everything a function inlines) from which a function is outlined.
const OUTLINE_SIZE: usize = 400;

/// The functions whose calls are written as `s.outline(|| f(…))` (`uplift_simd::Simd::outline`):
/// those that, with every function they inline, hold at least [`OUTLINE_SIZE`] expressions —
/// the lobes, the albedo lookups and the thin-film Fresnel of a BSDF kernel. Everything else is
/// `#[inline(always)]`. Each outlined call site is a function of its own per SIMD level, with
/// the arguments known at the call (literals) folded into it. Without this a kernel is one
/// function per level: the 8-lobe stack's took 150 s of release build for two levels and the
/// scalar one; with it, 6.5 s. Speed, one thread, AVX-512 (Xeon), eval context: conductor 122
/// → 148 M evals/s (rarely taken calls such as the Airy Fresnel stay out of the hot code), stack
/// 30.3 → 23.7 (with one material per batch, a whole kernel lets LLVM hoist the material's work
/// out of the point loop; outlined lobes recompute it per packet — the dependence split of issue
/// 24 is the way to hoist it). Thresholds of 200 and 1,200 were slower for the stack (18.1 and
/// 18.7).
pub(crate) fn outlined_functions(module: &Module) -> std::collections::HashSet<Handle<Function>> {
    fn calls(block: &naga::Block, out: &mut Vec<Handle<Function>>) {
        for s in block.iter() {
            match s {
                Statement::Call { function, .. } => out.push(*function),
                Statement::Block(b) => calls(b, out),
                Statement::If { accept, reject, .. } => {
                    calls(accept, out);
                    calls(reject, out);
                }
                Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls(&c.body, out)),
                Statement::Loop { body, continuing, .. } => {
                    calls(body, out);
                    calls(continuing, out);
                }
                _ => {}
            }
        }
    }
    let mut size: HashMap<Handle<Function>, usize> = HashMap::new();
    let mut outlined = std::collections::HashSet::new();
    // Callees come before their callers in naga's arena.
    for (h, f) in module.functions.iter() {
        let mut callees = Vec::new();
        calls(&f.body, &mut callees);
        let n = f.expressions.len() + callees.iter().map(|c| if outlined.contains(c) { 1 } else { size.get(c).copied().unwrap_or(0) }).sum::<usize>();
        size.insert(h, n);
        if n >= OUTLINE_SIZE && f.name.as_deref() != Some("mx_pattern") {
            outlined.insert(h);
        }
    }
    outlined
}

fn write_function(
    module: &Module,
    names: &naga::FastHashMap<NameKey, String>,
    h: Handle<Function>,
    f: &Function,
    outlined: &std::collections::HashSet<Handle<Function>>,
    pure: &std::collections::HashSet<Handle<Function>>,
) -> R<String> {
    Ok(write_function_with(module, names, h, f, outlined, pure, None)?.0)
}

/// [`write_function`], or one pass of its dependence split (`split`, returned as the pass
/// left it: what it recorded).
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_function_with(
    module: &Module,
    names: &naga::FastHashMap<NameKey, String>,
    h: Handle<Function>,
    f: &Function,
    outlined: &std::collections::HashSet<Handle<Function>>,
    pure: &std::collections::HashSet<Handle<Function>>,
    split: Option<crate::packet_split::SplitState>,
) -> R<(String, Option<crate::packet_split::SplitState>)> {
    let ctx = naga::proc::ResolveContext::with_locals(module, &f.local_variables, &f.arguments);
    let mut typifier = naga::front::Typifier::new();
    for (eh, _) in f.expressions.iter() {
        typifier.grow(eh, &f.expressions, &ctx).map_err(|e| PacketError { construct: format!("an expression whose type naga cannot resolve ({e})"), function: f.name.clone() })?;
    }
    let mut w = FunctionWriter { module, f, names, handle: h, typifier, body: String::new(), mask: None, depth: 1, masks: 0, returns_masked: masked_return(&f.body, false), loops: Vec::new(), loop_count: 0, inline_all: false, switch_breaks: Vec::new(), calls: HashMap::new(), guards: crate::packet_guards::guarded_calls(f, pure), early: None, outlined, split };
    let text = w.function().map_err(|mut e| {
        e.function = f.name.clone();
        e
    })?;
    Ok((text, w.split))
}

/// Every function of `module` the writer cannot write yet, with the reason (the next stages'
/// work list).
pub fn unsupported_functions(module: &Module) -> Vec<PacketError> {
    let names = packet_names(module);
    let pure = crate::packet_guards::pure_functions(module);
    module.functions.iter().filter_map(|(h, f)| write_function(module, &names, h, f, &Default::default(), &pure).err()).collect()
}

pub(crate) struct FunctionWriter<'a> {
    pub(crate) module: &'a Module,
    pub(crate) f: &'a Function,
    pub(crate) names: &'a naga::FastHashMap<NameKey, String>,
    pub(crate) handle: Handle<Function>,
    /// The type of every expression.
    pub(crate) typifier: naga::front::Typifier,
    pub(crate) body: String,
    /// The mask of the active lanes (a Rust expression), inside a varying `if`.
    pub(crate) mask: Option<String>,
    /// Nesting of the current block (indentation, and fresh mask names).
    pub(crate) depth: usize,
    pub(crate) masks: usize,
    /// The function returns under a mask somewhere: results gather in `_ret`, and `_done`
    /// holds the lanes that have returned.
    pub(crate) returns_masked: bool,
    /// The loops around the current statement, innermost last: (break lanes, continue lanes,
    /// looping lanes) variable names.
    loops: Vec<(String, String, String)>,
    loop_count: usize,
    /// Writing a local's constant initialiser: operands are written out, not referenced.
    inline_all: bool,
    /// The switch cases around the current statement: the loop depth at each (a `break` at
    /// that depth ends the case) and its break-lanes variable.
    switch_breaks: Vec<(usize, String)>,
    /// Call results: the name of the `let` holding each.
    pub(crate) calls: HashMap<Handle<naga::Expression>, String>,
    /// Calls run only where a lane needs their result (`packet_guards.rs`), by result.
    pub(crate) guards: HashMap<Handle<naga::Expression>, crate::packet_guards::Guard>,
    /// Writing a guard's condition: expressions not bound here are written out.
    early: Option<std::collections::HashSet<Handle<naga::Expression>>>,
    /// Functions whose calls run in `s.outline(…)` (`outlined_functions`).
    pub(crate) outlined: &'a std::collections::HashSet<Handle<Function>>,
    /// Writing one pass of a dependence-split function (`packet_split.rs`).
    pub(crate) split: Option<crate::packet_split::SplitState>,
}

impl FunctionWriter<'_> {
    pub(crate) fn function(&mut self) -> R<String> {
        let name = match &self.split {
            Some(sp) => sp.name.clone(),
            None => self.names[&NameKey::Function(self.handle)].clone(),
        };
        let mut params = vec!["s: S".to_string()];
        for (i, a) in self.f.arguments.iter().enumerate() {
            let t = ty_of_handle(self.module, a.ty)?;
            params.push(format!("{}: {}", self.names[&NameKey::FunctionArgument(self.handle, i as u32)], rust_type(t, self.names)));
        }
        if let Some(sp) = &self.split {
            params.push(sp.tape_parameter().into());
            if let Some(line) = sp.entry_line() {
                self.body += &line;
            }
        }
        let ret = match &self.f.result {
            Some(r) => format!(" -> {}", rust_type(ty_of_handle(self.module, r.ty)?, self.names)),
            None => String::new(),
        };
        for (lh, l) in self.f.local_variables.iter() {
            let t = ty_of_handle(self.module, l.ty)?;
            let init = match l.init {
                // A constant expression, never emitted: written out whole.
                Some(e) => {
                    self.inline_all = true;
                    let r = self.expr_inline(e);
                    self.inline_all = false;
                    r?
                }
                None => self.zero(t),
            };
            let _ = writeln!(self.body, "    let mut {}: {} = {init};", self.names[&NameKey::FunctionLocal(self.handle, lh)], rust_type(t, self.names));
        }
        if self.returns_masked {
            if let Some(r) = &self.f.result {
                let t = ty_of_handle(self.module, r.ty)?;
                let _ = writeln!(self.body, "    let mut _ret: {} = {};", rust_type(t, self.names), self.zero(t));
            }
            let _ = writeln!(self.body, "    let mut _done = s.first_lanes(0);");
        }
        for s in self.f.body.iter() {
            self.statement(s)?;
        }
        Ok(format!("#[inline(always)]\n#[allow(unused_variables, unused_mut, unused_parens, unused_assignments, clippy::all)]\npub fn {name}<S: Simd>({}){ret} {{\n{}}}\n", params.join(", "), self.body))
    }

    pub(crate) fn ty(&self, h: Handle<naga::Expression>) -> R<Ty> {
        match &self.typifier[h] {
            naga::proc::TypeResolution::Handle(th) => ty_of_handle(self.module, *th),
            naga::proc::TypeResolution::Value(inner) => ty_of(inner),
        }
    }

    /// The type of an expression.
    pub(crate) fn resolve(&self, h: Handle<naga::Expression>) -> R<TypeInner> {
        Ok(self.typifier.get(h, &self.module.types).clone())
    }

    pub(crate) fn zero(&self, t: Ty) -> String {
        match t {
            Ty::Struct(th) => {
                let TypeInner::Struct { members, .. } = &self.module.types[th].inner else { unreachable!("a struct type") };
                let fields: Vec<String> = members
                    .iter()
                    .enumerate()
                    .map(|(k, m)| {
                        let z = ty_of_handle(self.module, m.ty).map(|t| self.zero(t)).unwrap_or_default();
                        format!("{}: {z}", self.names[&NameKey::StructMember(th, k as u32)])
                    })
                    .collect();
                format!("{} {{ {} }}", self.names[&NameKey::Type(th)], fields.join(", "))
            }
            Ty::Scalar(ScalarKind::Float) => "s.splat(0.0)".into(),
            Ty::Scalar(ScalarKind::Sint) => "s.splat_i(0)".into(),
            Ty::Scalar(ScalarKind::Uint) => "s.splat_u(0)".into(),
            Ty::Scalar(_) => "s.first_lanes(0)".into(),
            Ty::Vec(n) => format!("[s.splat(0.0); {n}]"),
        }
    }

    pub(crate) fn statement(&mut self, s: &Statement) -> R<()> {
        if self.split.as_ref().is_some_and(|sp| sp.region == 0) {
            return self.split_statement(s);
        }
        self.plain_statement(s)
    }

    /// A statement as the unsplit packet writer writes it (inside a split function: in a
    /// per-point region, whose statements the point pass writes whole).
    pub(crate) fn plain_statement(&mut self, s: &Statement) -> R<()> {
        match s {
            Statement::Emit(range) => {
                for h in range.clone() {
                    if matches!(self.resolve(h)?, TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }) {
                        continue;
                    }
                    let e = self.expr_inline(h)?;
                    self.line(&format!("let _e{} = {e};", h.index()));
                }
            }
            Statement::Block(b) => {
                for s in b.iter() {
                    self.statement(s)?;
                }
            }
            Statement::Store { pointer, value } => {
                let place = self.place(*pointer)?;
                let v = self.expr(*value)?;
                // Under a mask only the active lanes take the stored value.
                let v = match &self.mask {
                    None => v,
                    Some(m) => blend(m, &v, &place, self.ty(*value)?, self.names),
                };
                self.line(&format!("{place} = {v};"));
            }
            // A return under a mask: its lanes take their result now and are done (ISPC's
            // return mask); later returns leave them alone.
            Statement::Return { value } if self.mask.is_some() => {
                let m = self.mask.clone().unwrap();
                if let Some(v) = value {
                    let t = self.ty(*v)?;
                    let v = self.expr(*v)?;
                    let on = blend(&format!("({m} & !_done)"), &v, "_ret", t, self.names);
                    self.line(&format!("_ret = {on};"));
                }
                self.line(&format!("_done = _done | {m};"));
            }
            Statement::Return { value: Some(v) } if self.returns_masked => {
                let t = self.ty(*v)?;
                let v = self.expr(*v)?;
                let on = blend("(!_done)", &v, "_ret", t, self.names);
                self.line(&format!("return {on};"));
            }
            Statement::Return { value: Some(v) } => {
                let v = self.expr(*v)?;
                self.line(&format!("return {v};"));
            }
            Statement::Return { value: None } => self.line("return;"),
            Statement::If { condition, accept, reject } => {
                // ISPC's mask-mixed `if`: each side runs under its lanes' mask, and is skipped
                // when no lane takes it; stores inside blend (above).
                let c = self.expr(*condition)?;
                let outer = self.mask.clone();
                for (block, test) in [(accept, c.clone()), (reject, format!("!{c}"))] {
                    if block.is_empty() {
                        continue;
                    }
                    let value = match &outer {
                        Some(o) => format!("{o} & {test}"),
                        None => test,
                    };
                    let m = self.fresh_mask(&value);
                    self.line(&format!("if {m}.any() {{"));
                    self.mask = Some(m);
                    self.depth += 1;
                    for st in block.iter() {
                        self.statement(st)?;
                    }
                    self.depth -= 1;
                    self.line("}");
                }
                self.mask = outer;
                if self.returns_masked && (returns_in(accept) || returns_in(reject)) {
                    self.leave_if_all_done();
                }
                // Lanes that left the loop (break), its iteration (continue), their switch case
                // or the function inside the `if` sit out the rest of this block.
                if jumps_in(accept) || jumps_in(reject) {
                    self.exclude_left_lanes();
                }
            }
            Statement::Loop { body, continuing, break_if } => {
                // A varying loop: it runs while some lane still loops; `break` and `continue`
                // lanes are recorded in masks (ISPC's loop bookkeeping), stores blend under the
                // looping lanes' mask.
                self.loop_count += 1;
                let k = self.loop_count;
                let (lm, brk, cont) = (format!("_lm{k}"), format!("_brk{k}"), format!("_cont{k}"));
                let done = if self.returns_masked { " & !_done" } else { "" };
                let entry = match &self.mask {
                    Some(m) => m.clone(),
                    None if self.returns_masked => "!_done".to_string(),
                    None => "s.first_lanes(usize::MAX)".to_string(),
                };
                self.line(&format!("let mut {lm} = {entry};"));
                self.line(&format!("let mut {brk} = s.first_lanes(0);"));
                self.line("loop {");
                self.depth += 1;
                self.line(&format!("let mut {cont} = s.first_lanes(0);"));
                let outer = self.mask.clone();
                self.loops.push((brk.clone(), cont.clone(), lm.clone()));
                self.mask = Some(lm.clone());
                for st in body.iter() {
                    self.statement(st)?;
                }
                // The continuing block: every lane still looping, `continue` ones included.
                let mc = self.fresh_mask(&format!("{lm} & !{brk}{done}"));
                self.mask = Some(mc.clone());
                for st in continuing.iter() {
                    self.statement(st)?;
                }
                if let Some(b) = break_if {
                    let c = self.expr(*b)?;
                    self.line(&format!("{brk} = {brk} | ({mc} & {c});"));
                }
                self.line(&format!("{lm} = {lm} & !{brk}{done};"));
                self.line(&format!("if !{lm}.any() {{ break; }}"));
                self.depth -= 1;
                self.line("}");
                self.loops.pop();
                self.mask = outer;
                if self.returns_masked && (returns_in(body) || returns_in(continuing)) {
                    self.leave_if_all_done();
                }
            }
            Statement::Break | Statement::Continue => {
                // A switch's `break` only ends its case: the lanes sit out the rest of it.
                let m = self.mask.clone().unwrap_or_else(|| "s.first_lanes(usize::MAX)".into());
                let switch = self.switch_breaks.last().filter(|(depth, _)| *depth == self.loops.len()).map(|(_, v)| v.clone());
                if let (true, Some(v)) = (matches!(s, Statement::Break), switch) {
                    self.line(&format!("{v} = {v} | {m};"));
                } else {
                    let Some((brk, cont, _)) = self.loops.last().cloned() else {
                        return Err(unsupported("`break` or `continue` outside a loop"));
                    };
                    let set = if matches!(s, Statement::Break) { brk } else { cont };
                    self.line(&format!("{set} = {set} | {m};"));
                }
                // Whatever follows in this block runs for no lane.
                self.mask = Some(self.fresh_mask("s.first_lanes(0)"));
            }
            Statement::Call { function, arguments, result } => {
                let name = self.names[&NameKey::Function(*function)].clone();
                self.write_call(*function, &name, arguments, *result, None, true)?;
            }
            Statement::Switch { selector, cases } => {
                // Each case body under the mask of the lanes whose selector picks it (values of
                // fall-through cases gathered into the body that follows them), skipped when
                // none does; the default takes the lanes no value picks.
                let sel = self.expr(*selector)?;
                let splat = match self.ty(*selector)? {
                    Ty::Scalar(ScalarKind::Sint) => "splat_i",
                    _ => "splat_u",
                };
                let outer = self.mask.clone();
                // The lanes a case value picks (`None` for the default).
                let picks = |value: naga::SwitchValue| match value {
                    naga::SwitchValue::I32(v) => Some(format!("{sel}.eq(s.{splat}({v}i32))")),
                    naga::SwitchValue::U32(v) => Some(format!("{sel}.eq(s.{splat}({v}u32))")),
                    naga::SwitchValue::Default => None,
                };
                let all_values: Vec<String> = cases.iter().filter_map(|c| picks(c.value)).collect();
                let mut pending: Vec<String> = Vec::new();
                let mut default_pending = false;
                for case in cases {
                    match picks(case.value) {
                        Some(p) => pending.push(p),
                        None => default_pending = true,
                    }
                    if case.fall_through && case.body.is_empty() {
                        continue;
                    }
                    if case.fall_through {
                        return Err(unsupported("a switch case falling through into the next"));
                    }
                    let mut tests = pending.clone();
                    if default_pending {
                        tests.push(if all_values.is_empty() { "s.first_lanes(usize::MAX)".to_string() } else { format!("!({})", all_values.join(" | ")) });
                    }
                    pending.clear();
                    default_pending = false;
                    let test = format!("({})", tests.join(" | "));
                    let value = match &outer {
                        Some(o) => format!("{o} & {test}"),
                        None => test,
                    };
                    let m = self.fresh_mask(&value);
                    self.line(&format!("if {m}.any() {{"));
                    self.mask = Some(m.clone());
                    self.depth += 1;
                    let sbrk = format!("_sbrk{}", &m[2..]);
                    self.line(&format!("let mut {sbrk} = s.first_lanes(0);"));
                    self.switch_breaks.push((self.loops.len(), sbrk));
                    for st in case.body.iter() {
                        self.statement(st)?;
                    }
                    self.switch_breaks.pop();
                    self.depth -= 1;
                    self.line("}");
                    self.mask = outer.clone();
                }
                if self.returns_masked && cases.iter().any(|c| returns_in(&c.body)) {
                    self.leave_if_all_done();
                }
                if cases.iter().any(|c| continues_or_returns(&c.body)) {
                    self.exclude_left_lanes();
                }
            }
            other => return Err(unsupported(format!("the statement {other:?}"))),
        }
        Ok(())
    }

    /// A call of `function` written as `callee` (its name, or a split pass's), with `extra`
    /// appended to its arguments (a split pass's tape) and its result bound to `_e<result>`;
    /// run only where lanes need it when `guarded` and the call is guarded.
    pub(crate) fn write_call(&mut self, function: Handle<Function>, callee: &str, arguments: &[Handle<naga::Expression>], result: Option<Handle<naga::Expression>>, extra: Option<String>, guarded: bool) -> R<()> {
        let mut args = vec!["s".to_string()];
        for a in arguments {
            args.push(self.expr(*a)?);
        }
        args.extend(extra);
        let mut call = format!("{callee}({})", args.join(", "));
        // A split kernel's point pass is one function (its callees inlined): LLVM keeps its
        // values in registers across lobes (stack, AVX-512, 16 points per view: 24.1 → 29.9
        // M evals/s on one thread).
        let point_pass = self.split.as_ref().is_some_and(|sp| sp.pass == crate::packet_split::Pass::Point);
        if self.outlined.contains(&function) && !point_pass {
            // The call, with the arguments known here (literals fold into it), in a
            // function of its own for the level.
            call = format!("s.outline(#[inline(always)] || {call})");
        }
        match result {
            Some(r) => {
                let name = format!("_e{}", r.index());
                match if guarded { self.guard(r)? } else { None } {
                    Some(lanes) => {
                        let zero = self.zero(self.ty(r)?);
                        self.line(&format!("let {name} = if ({lanes}).any() {{ {call} }} else {{ {zero} }};"));
                    }
                    None => self.line(&format!("let {name} = {call};")),
                }
                self.calls.insert(r, name);
            }
            None => self.line(&format!("{call};")),
        }
        Ok(())
    }

    /// The lanes that need the call with result `r`, if it is guarded (`packet_guards.rs`).
    pub(crate) fn guard(&mut self, r: Handle<naga::Expression>) -> R<Option<String>> {
        let Some(g) = self.guards.get(&r).cloned() else { return Ok(None) };
        if self.ty(g.condition)? != Ty::Scalar(ScalarKind::Bool) {
            return Ok(None);
        }
        self.early = Some(g.visible);
        let c = self.expr(g.condition);
        self.early = None;
        let c = if g.take { c? } else { format!("!({})", c?) };
        Ok(Some(match &self.mask {
            Some(m) => format!("{m} & {c}"),
            None => c,
        }))
    }

    /// Binds `value` to a fresh mask variable; returns its name.
    pub(crate) fn fresh_mask(&mut self, value: &str) -> String {
        self.masks += 1;
        let m = format!("_m{}", self.masks);
        self.line(&format!("let {m} = {value};"));
        m
    }

    /// After a statement some lanes may have returned in: leave as soon as every lane has.
    pub(crate) fn leave_if_all_done(&mut self) {
        let done = if self.f.result.is_some() { "return _ret;" } else { "return;" };
        self.line(&format!("if _done.all() {{ {done} }}"));
    }

    /// After a statement some lanes may have left by: the current mask minus the lanes that
    /// broke out of or continued the innermost loop, broke out of the current switch case, or
    /// returned.
    pub(crate) fn exclude_left_lanes(&mut self) {
        let Some(m) = self.mask.clone() else { return };
        let mut ex = String::new();
        if let Some((brk, cont, _)) = self.loops.last() {
            ex += &format!(" & !{brk} & !{cont}");
        }
        if let Some((depth, v)) = self.switch_breaks.last() {
            if *depth == self.loops.len() {
                ex += &format!(" & !{v}");
            }
        }
        if self.returns_masked {
            ex += " & !_done";
        }
        if ex.is_empty() {
            return;
        }
        self.mask = Some(self.fresh_mask(&format!("{m}{ex}")));
    }

    pub(crate) fn line(&mut self, text: &str) {
        let _ = writeln!(self.body, "{}{text}", "    ".repeat(self.depth));
    }

    /// A local variable, or one component of a vector local, as an assignable place.
    pub(crate) fn place(&self, pointer: Handle<naga::Expression>) -> R<String> {
        match &self.f.expressions[pointer] {
            E::LocalVariable(l) => Ok(self.names[&NameKey::FunctionLocal(self.handle, *l)].clone()),
            E::AccessIndex { base, index } => {
                let b = self.place(*base)?;
                match self.resolve(*base)? {
                    TypeInner::Pointer { base: th, .. } if matches!(self.module.types[th].inner, TypeInner::Struct { .. }) => {
                        Ok(format!("{b}.{}", self.names[&NameKey::StructMember(th, *index)]))
                    }
                    _ => Ok(format!("{b}[{index}]")),
                }
            }
            other => Err(unsupported(format!("a store through {other:?}"))),
        }
    }

    /// A reference to an expression already bound (by `Emit` or a call), or written in place
    /// for those naga never emits (literals, constants, arguments, zero values).
    pub(crate) fn expr(&mut self, h: Handle<naga::Expression>) -> R<String> {
        if self.inline_all {
            return self.expr_inline(h);
        }
        if let Some(visible) = &self.early {
            let leaf = matches!(self.f.expressions[h], E::Literal(_) | E::Constant(_) | E::ZeroValue(_) | E::FunctionArgument(_) | E::LocalVariable(_));
            if !leaf && !visible.contains(&h) {
                return self.expr_inline(h);
            }
        }
        if self.split.is_some() {
            if let Some(text) = self.split_reference(h)? {
                return Ok(text);
            }
        }
        match &self.f.expressions[h] {
            E::Literal(_) | E::Constant(_) | E::ZeroValue(_) | E::FunctionArgument(_) | E::LocalVariable(_) => self.expr_inline(h),
            E::CallResult(_) => self.calls.get(&h).cloned().ok_or_else(|| unsupported("a call result used before its call")),
            _ => Ok(format!("_e{}", h.index())),
        }
    }

    fn literal(&self, l: &Literal) -> R<String> {
        Ok(match *l {
            Literal::F32(x) => format!("s.splat({x:?}f32)"),
            Literal::I32(x) => format!("s.splat_i({x}i32)"),
            Literal::U32(x) => format!("s.splat_u({x}u32)"),
            Literal::Bool(b) => format!("s.first_lanes({})", if b { "usize::MAX" } else { "0" }),
            other => return Err(unsupported(format!("the literal {other:?}"))),
        })
    }

    /// A module constant, written as a packet value.
    fn constant(&self, h: Handle<naga::Expression>) -> R<String> {
        match &self.module.global_expressions[h] {
            E::Literal(l) => self.literal(l),
            E::Constant(c) => self.constant(self.module.constants[*c].init),
            E::Compose { components, .. } => {
                let parts: R<Vec<String>> = components.iter().map(|c| self.constant(*c)).collect();
                Ok(format!("[{}]", parts?.join(", ")))
            }
            E::Splat { size, value } => Ok(format!("[{}; {}]", self.constant(*value)?, vsize(*size))),
            E::ZeroValue(t) => Ok(self.zero(ty_of_handle(self.module, *t)?)),
            other => Err(unsupported(format!("the constant expression {other:?}"))),
        }
    }

    /// The expression `h` written out (its operands by reference).
    pub(crate) fn expr_inline(&mut self, h: Handle<naga::Expression>) -> R<String> {
        let e = self.f.expressions[h].clone();
        Ok(match e {
            E::Literal(l) => self.literal(&l)?,
            E::Constant(c) => self.constant(self.module.constants[c].init)?,
            E::ZeroValue(t) => self.zero(ty_of_handle(self.module, t)?),
            E::FunctionArgument(i) => self.names[&NameKey::FunctionArgument(self.handle, i)].clone(),
            E::LocalVariable(l) => self.names[&NameKey::FunctionLocal(self.handle, l)].clone(),
            E::Load { pointer } => self.place(pointer)?,
            E::Compose { ty, components } if matches!(self.module.types[ty].inner, TypeInner::Struct { .. }) => {
                let mut fields = Vec::new();
                for (k, c) in components.iter().enumerate() {
                    fields.push(format!("{}: {}", self.names[&NameKey::StructMember(ty, k as u32)], self.expr(*c)?));
                }
                format!("{} {{ {} }}", self.names[&NameKey::Type(ty)], fields.join(", "))
            }
            E::Compose { components, .. } => {
                let mut lanes = Vec::new();
                for c in components {
                    let v = self.expr(c)?;
                    match self.ty(c)? {
                        Ty::Vec(n) => lanes.extend((0..n).map(|k| format!("{v}[{k}]"))),
                        _ => lanes.push(v),
                    }
                }
                format!("[{}]", lanes.join(", "))
            }
            E::Splat { size, value } => format!("[{}; {}]", self.expr(value)?, vsize(size)),
            E::Swizzle { size, vector, pattern } => {
                let v = self.expr(vector)?;
                let parts: Vec<String> = pattern[..vsize(size)].iter().map(|c| format!("{v}[{}]", *c as usize)).collect();
                format!("[{}]", parts.join(", "))
            }
            // A runtime index into a constant f32 array: a gather, the index clamped as the scalar
            // writer clamps it (`(i as u32).min(n − 1)`).
            E::Access { base, index } if matches!(self.f.expressions[base], E::Constant(_)) => {
                let E::Constant(c) = self.f.expressions[base] else { unreachable!() };
                let TypeInner::Array { size: naga::ArraySize::Constant(n), .. } = self.module.types[self.module.constants[c].ty].inner else {
                    return Err(unsupported("a runtime index into a constant that is no sized array"));
                };
                let i = self.expr(index)?;
                let as_u32 = match self.ty(index)? {
                    Ty::Scalar(ScalarKind::Sint) => format!("{i}.to_u32_bits()"),
                    _ => i,
                };
                format!("s.gather(&{}, {as_u32}.min(s.splat_u({})).to_i32_bits())", self.names[&NameKey::Constant(c)], n.get() - 1)
            }
            E::AccessIndex { base, index } => match self.resolve(base)? {
                TypeInner::Vector { .. } => format!("{}[{index}]", self.expr(base)?),
                TypeInner::Struct { .. } => {
                    let Ty::Struct(th) = self.ty(base)? else { return Err(unsupported("a member of an anonymous struct")) };
                    format!("{}.{}", self.expr(base)?, self.names[&NameKey::StructMember(th, index)])
                }
                other => return Err(unsupported(format!("a component of {other:?}"))),
            },
            E::Unary { op, expr } => {
                let a = self.expr(expr)?;
                match (op, self.ty(expr)?) {
                    (Uo::Negate, Ty::Vec(n)) => format!("uplift_simd::vector::neg::<S, {n}>({a})"),
                    (Uo::Negate, _) => format!("-{a}"),
                    (Uo::LogicalNot | Uo::BitwiseNot, Ty::Scalar(_)) => format!("!{a}"),
                    (op, t) => return Err(unsupported(format!("{op:?} on {t:?}"))),
                }
            }
            E::Binary { op, left, right } => self.binary(op, left, right)?,
            E::Select { condition, accept, reject } => {
                let (c, a, r) = (self.expr(condition)?, self.expr(accept)?, self.expr(reject)?);
                match (self.ty(condition)?, self.ty(accept)?) {
                    (Ty::Scalar(_), Ty::Scalar(ScalarKind::Float)) => format!("{c}.select({a}, {r})"),
                    (Ty::Scalar(_), Ty::Scalar(ScalarKind::Sint)) => format!("{c}.select_i({a}, {r})"),
                    (Ty::Scalar(_), Ty::Scalar(ScalarKind::Uint)) => format!("{c}.select_u({a}, {r})"),
                    (Ty::Scalar(_), Ty::Scalar(_)) => format!("(({c} & {a}) | (!{c} & {r}))"),
                    (Ty::Scalar(_), Ty::Vec(n)) => format!("uplift_simd::vector::select_all::<S, {n}>({c}, {a}, {r})"),
                    (c, v) => return Err(unsupported(format!("select of {v:?} by {c:?}"))),
                }
            }
            E::As { expr, kind, convert } => {
                let a = self.expr(expr)?;
                let from = match self.ty(expr)? {
                    Ty::Scalar(k) => k,
                    t => return Err(unsupported(format!("a conversion of {t:?}"))),
                };
                match (from, kind, convert) {
                    (ScalarKind::Float, ScalarKind::Sint, Some(4)) => format!("{a}.to_i32()"),
                    (ScalarKind::Float, ScalarKind::Uint, Some(4)) => format!("{a}.to_u32()"),
                    (ScalarKind::Sint | ScalarKind::Uint, ScalarKind::Float, Some(4)) => format!("{a}.to_f32()"),
                    (ScalarKind::Float, ScalarKind::Uint, None) => format!("{a}.to_bits()"),
                    (ScalarKind::Uint, ScalarKind::Float, None) => format!("{a}.to_f32_bits()"),
                    (ScalarKind::Sint, ScalarKind::Uint, _) => format!("{a}.to_u32_bits()"),
                    (ScalarKind::Uint, ScalarKind::Sint, _) => format!("{a}.to_i32_bits()"),
                    (f, t, _) if f == t => a,
                    (f, t, c) => return Err(unsupported(format!("the conversion {f:?} → {t:?} ({c:?})"))),
                }
            }
            E::Relational { fun, argument } => {
                let a = self.expr(argument)?;
                let n = match self.resolve(argument)? {
                    TypeInner::Vector { size, .. } => vsize(size),
                    _ => 1,
                };
                let sym = match fun {
                    naga::RelationalFunction::All => " & ",
                    naga::RelationalFunction::Any => " | ",
                    other => return Err(unsupported(format!("{other:?}"))),
                };
                if n == 1 {
                    a
                } else {
                    format!("({})", (0..n).map(|k| format!("{a}[{k}]")).collect::<Vec<_>>().join(sym))
                }
            }
            E::Math { fun, arg, arg1, arg2, .. } => self.math(fun, arg, arg1, arg2)?,
            E::CallResult(_) => self.expr(h)?,
            other => return Err(unsupported(format!("the expression {other:?}"))),
        })
    }

    fn binary(&mut self, op: Bo, left: Handle<naga::Expression>, right: Handle<naga::Expression>) -> R<String> {
        let (l, r) = (self.expr(left)?, self.expr(right)?);
        let (lt, rt) = (self.ty(left)?, self.ty(right)?);
        if let Some(fused) = self.contracted(op, left, right, &l, &r)? {
            return Ok(fused);
        }
        let vector_op = match op {
            Bo::Add => Some("add"),
            Bo::Subtract => Some("sub"),
            Bo::Multiply => Some("mul"),
            Bo::Divide => Some("div"),
            _ => None,
        };
        if let (Some("div"), Ty::Vec(_) | Ty::Scalar(ScalarKind::Float), Ty::Vec(_) | Ty::Scalar(ScalarKind::Float)) = (vector_op, lt, rt) {
            // x / y as x · rcp(y), rcp the hardware estimate and one Newton step (2 ulp):
            // within WGSL's 2.5 ulp for |y| in [2⁻¹²⁶, 2¹²⁶], ±0, ±∞ and NaN as division gives
            // them. A divider runs a 16-lane division in ≈ 16 cycles; this, in ≈ 4 pipelined.
            return Ok(match (lt, rt) {
                (Ty::Vec(n), Ty::Vec(_)) => format!("uplift_simd::vector::zip::<S, {n}>({l}, {r}, |x, y| x * y.rcp())"),
                (Ty::Vec(n), _) => format!("{{ let k = ({r}).rcp(); uplift_simd::vector::mul::<S, {n}>({l}, [k; {n}]) }}"),
                (_, Ty::Vec(n)) => format!("uplift_simd::vector::zip::<S, {n}>([{l}; {n}], {r}, |x, y| x * y.rcp())"),
                _ => format!("({l} * ({r}).rcp())"),
            });
        }
        if let (Some(name), Ty::Vec(_) | Ty::Scalar(ScalarKind::Float), Ty::Vec(_) | Ty::Scalar(ScalarKind::Float)) = (vector_op, lt, rt) {
            return Ok(match (lt, rt) {
                (Ty::Vec(n), Ty::Vec(_)) => format!("uplift_simd::vector::{name}::<S, {n}>({l}, {r})"),
                (Ty::Vec(n), _) => format!("uplift_simd::vector::{name}::<S, {n}>({l}, [{r}; {n}])"),
                (_, Ty::Vec(n)) => format!("uplift_simd::vector::{name}::<S, {n}>([{l}; {n}], {r})"),
                _ => format!("({l} {} {r})", ["+", "-", "*", "/"][["add", "sub", "mul", "div"].iter().position(|x| *x == name).unwrap()]),
            });
        }
        let (Ty::Scalar(kind), Ty::Scalar(_)) = (lt, rt) else {
            return Err(unsupported(format!("{op:?} on {lt:?} and {rt:?}")));
        };
        let float = kind == ScalarKind::Float;
        Ok(match op {
            Bo::Add | Bo::Subtract | Bo::Multiply if !float && kind != ScalarKind::Bool => {
                format!("({l} {} {r})", match op {
                    Bo::Add => "+",
                    Bo::Subtract => "-",
                    _ => "*",
                })
            }
            Bo::Divide if !float => format!("{l}.div({r})"),
            Bo::Modulo if !float => format!("{l}.rem({r})"),
            Bo::Modulo => format!("({l} - {r} * ({l} / {r}).trunc())"),
            Bo::Equal if kind == ScalarKind::Bool => format!("!({l} ^ {r})"),
            Bo::NotEqual if kind == ScalarKind::Bool => format!("({l} ^ {r})"),
            Bo::Equal => format!("{l}.eq({r})"),
            Bo::NotEqual if float => format!("{l}.ne({r})"),
            Bo::NotEqual => format!("!{l}.eq({r})"),
            Bo::Less => format!("{l}.lt({r})"),
            Bo::Greater => format!("{l}.gt({r})"),
            Bo::LessEqual if float => format!("{l}.le({r})"),
            Bo::GreaterEqual if float => format!("{l}.ge({r})"),
            Bo::LessEqual => format!("!{l}.gt({r})"),
            Bo::GreaterEqual => format!("!{l}.lt({r})"),
            Bo::And | Bo::LogicalAnd => format!("({l} & {r})"),
            Bo::InclusiveOr | Bo::LogicalOr => format!("({l} | {r})"),
            Bo::ExclusiveOr => format!("({l} ^ {r})"),
            Bo::ShiftLeft => format!("{l}.shl({r})"),
            Bo::ShiftRight => format!("{l}.shr({r})"),
            other => return Err(unsupported(format!("{other:?} on {kind:?}"))),
        })
    }

    /// A float scalar `a·b ± c` or `c ± a·b` as one fused multiply-add (`F32s::mul_add`:
    /// one rounding where the scalar writer rounds twice, within the agreement tests' 1e-4).
    /// `None` for anything else. The product stays bound to its own name for other uses.
    fn contracted(&mut self, op: Bo, left: Handle<naga::Expression>, right: Handle<naga::Expression>, l: &str, r: &str) -> R<Option<String>> {
        let float = Ty::Scalar(ScalarKind::Float);
        if !matches!(op, Bo::Add | Bo::Subtract) || self.ty(left)? != float || self.ty(right)? != float {
            return Ok(None);
        }
        let product = |w: &mut Self, h: Handle<naga::Expression>| -> R<Option<(String, String)>> {
            match w.f.expressions[h] {
                E::Binary { op: Bo::Multiply, left: a, right: b } if w.ty(a)? == float && w.ty(b)? == float => Ok(Some((w.expr(a)?, w.expr(b)?))),
                _ => Ok(None),
            }
        };
        Ok(match (op, product(self, left)?, product(self, right)?) {
            (Bo::Add, Some((a, b)), _) => Some(format!("{a}.mul_add({b}, {r})")),
            (Bo::Add, None, Some((a, b))) => Some(format!("{a}.mul_add({b}, {l})")),
            (Bo::Subtract, Some((a, b)), _) => Some(format!("{a}.mul_add({b}, -{r})")),
            (Bo::Subtract, None, Some((a, b))) => Some(format!("(-{a}).mul_add({b}, {l})")),
            _ => None,
        })
    }

    fn math(&mut self, fun: Mf, arg: Handle<naga::Expression>, arg1: Option<Handle<naga::Expression>>, arg2: Option<Handle<naga::Expression>>) -> R<String> {
        let a = self.expr(arg)?;
        let b = arg1.map(|h| self.expr(h)).transpose()?;
        let c = arg2.map(|h| self.expr(h)).transpose()?;
        let t = self.ty(arg)?;
        let b = || b.clone().ok_or_else(|| unsupported(format!("{fun:?} without its second argument")));
        let c = || c.clone().ok_or_else(|| unsupported(format!("{fun:?} without its third argument")));
        // Lane-wise on a scalar: the expression over `x` (and `y`, `z`).
        let unary = |body: &str| -> String {
            match t {
                Ty::Vec(n) => format!("uplift_simd::vector::map::<S, {n}>({a}, |x| {body})"),
                _ => format!("{{ let x = {a}; {body} }}"),
            }
        };
        if t == Ty::Scalar(ScalarKind::Sint) || t == Ty::Scalar(ScalarKind::Uint) {
            return Ok(match fun {
                Mf::Abs if t == Ty::Scalar(ScalarKind::Sint) => format!("{a}.abs()"),
                Mf::Abs => a,
                Mf::Min => format!("{a}.min({})", b()?),
                Mf::Max => format!("{a}.max({})", b()?),
                Mf::Clamp => format!("{a}.max({}).min({})", b()?, c()?),
                other => return Err(unsupported(format!("{other:?} on integers"))),
            });
        }
        let binary = |body: &str, second: String| -> String {
            match t {
                Ty::Vec(n) => format!("uplift_simd::vector::zip::<S, {n}>({a}, {second}, |x, y| {body})"),
                _ => format!("{{ let (x, y) = ({a}, {second}); {body} }}"),
            }
        };
        // A second operand of a vector function may be a scalar (WGSL's overloads): splat it.
        let widen = |h: Option<Handle<naga::Expression>>, v: String, w: &Self| -> R<String> {
            Ok(match (t, h.map(|h| w.ty(h)).transpose()?) {
                (Ty::Vec(n), Some(Ty::Scalar(_))) => format!("[{v}; {n}]"),
                _ => v,
            })
        };
        Ok(match fun {
            Mf::Abs => unary("x.abs()"),
            Mf::Floor => unary("x.floor()"),
            Mf::Ceil => unary("x.ceil()"),
            Mf::Round => unary("x.round()"),
            Mf::Trunc => unary("x.trunc()"),
            Mf::Fract => unary("x.fract()"),
            Mf::Sqrt => unary("x.sqrt()"),
            // The hardware estimate and one Newton step: within WGSL's 2 ulp.
            Mf::InverseSqrt => unary("x.rsqrt()"),
            Mf::Saturate => unary("x.max(s.splat(0.0)).min(s.splat(1.0))"),
            Mf::Sin => unary("x.map(f32::sin)"),
            Mf::Cos => unary("x.map(f32::cos)"),
            Mf::Tan => unary("x.map(f32::tan)"),
            Mf::Asin => unary("x.map(f32::asin)"),
            Mf::Acos => unary("x.map(f32::acos)"),
            Mf::Atan => unary("x.map(f32::atan)"),
            Mf::Exp => unary("x.map(f32::exp)"),
            Mf::Exp2 => unary("x.map(f32::exp2)"),
            Mf::Log => unary("x.map(f32::ln)"),
            Mf::Log2 => unary("x.map(f32::log2)"),
            Mf::Min => binary("x.min(y)", widen(arg1, b()?, self)?),
            Mf::Max => binary("x.max(y)", widen(arg1, b()?, self)?),
            Mf::Step => binary("x.le(y).select(s.splat(1.0), s.splat(0.0))", widen(arg1, b()?, self)?),
            Mf::Clamp => match t {
                Ty::Vec(n) => format!(
                    "uplift_simd::vector::zip::<S, {n}>(uplift_simd::vector::zip::<S, {n}>({a}, {}, |x, y| x.max(y)), {}, |x, y| x.min(y))",
                    widen(arg1, b()?, self)?,
                    widen(arg2, c()?, self)?
                ),
                _ => format!("{a}.max({}).min({})", b()?, c()?),
            },
            Mf::Fma => match t {
                Ty::Vec(n) => format!("{{ let (p, q, r) = ({a}, {}, {}); std::array::from_fn::<_, {n}, _>(|k| p[k].mul_add(q[k], r[k])) }}", b()?, c()?),
                _ => format!("{a}.mul_add({}, {})", b()?, c()?),
            },
            Mf::Mix => match t {
                Ty::Vec(n) => format!("uplift_simd::vector::mix::<S, {n}>(s, {a}, {}, {})", widen(arg1, b()?, self)?, widen(arg2, c()?, self)?),
                _ => format!("{{ let t = {}; {}.mul_add(t, {a} * (s.splat(1.0) - t)) }}", c()?, b()?),
            },
            Mf::Dot => match t {
                Ty::Vec(n) => format!("uplift_simd::vector::dot::<S, {n}>({a}, {})", b()?),
                _ => return Err(unsupported("dot of scalars")),
            },
            Mf::Length => match t {
                Ty::Vec(n) => format!("uplift_simd::vector::length::<S, {n}>({a})"),
                _ => format!("{a}.abs()"),
            },
            Mf::Distance => match t {
                Ty::Vec(n) => format!("uplift_simd::vector::length::<S, {n}>(uplift_simd::vector::sub::<S, {n}>({a}, {}))", b()?),
                _ => format!("({a} - {}).abs()", b()?),
            },
            Mf::Normalize => match t {
                Ty::Vec(n) => format!("uplift_simd::vector::normalize::<S, {n}>({a})"),
                _ => return Err(unsupported("normalize of a scalar")),
            },
            Mf::Cross => format!("uplift_simd::vector::cross::<S>({a}, {})", b()?),
            other => return Err(unsupported(format!("the built-in {other:?}"))),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packet(src: &str) -> R<String> {
        let m = naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)));
        write_packet(&m)
    }

    #[test]
    fn straight_line_functions_become_generic_packet_functions() {
        let rs = packet("fn f(a: f32, v: vec3<f32>) -> vec3<f32> { let d = dot(v, v); return v * a + vec3(d); }").unwrap();
        assert!(rs.contains("pub fn f<S: Simd>(s: S, a: S::F, v: [S::F; 3]) -> [S::F; 3]"), "{rs}");
        assert!(rs.contains("uplift_simd::vector::dot::<S, 3>(v, v)"), "{rs}");
        assert!(!rs.contains("unsafe"), "{rs}");
    }

    #[test]
    fn control_flow_beyond_this_stage_is_named() {
        let e = packet("fn g(a: vec2<i32>) -> i32 { return a.x; }").unwrap_err();
        assert_eq!(e.function.as_deref(), Some("g"));
        assert!(e.to_string().contains("the type"), "{e}");
    }

    #[test]
    fn a_varying_if_runs_both_sides_under_masks() {
        let rs = packet("fn f(a: f32) -> f32 { var r = 0.0; if (a > 0.0) { r = a; } else { r = -a; } return r; }").unwrap();
        assert!(rs.contains("if _m1.any() {") && rs.contains("let _m2 = !"), "{rs}");
        assert!(rs.contains("r = _m1.select("), "{rs}");
    }
}

#[cfg(test)]
mod library {
    /// The shipped BSDF graphs' CPU modules (the pbrlib closures, the albedo tables, the
    /// 8-lobe stack) in every closure context: the packet writer handles every function.
    #[test]
    fn the_shipped_bsdf_kernels_are_written_whole() {
        for graph in ["bsdf_conductor", "uplift_stack"] {
            for ctx in [crate::ClosureContext::Eval, crate::ClosureContext::Albedo, crate::ClosureContext::Sample, crate::ClosureContext::Pdf] {
                let path = format!("{}/../runtime/kernels/graphs/bsdf/{graph}.mtlx", env!("CARGO_MANIFEST_DIR"));
                let c = crate::Compiler::builtin().compile_file_in(std::path::Path::new(&path), &crate::OutputSelection::AllNumeric, Some(ctx));
                let k = c.kernel.expect("a shipped graph compiles");
                let module = k.cpu_module.as_ref().map_or(&k.module, |m| &m.0);
                let errors: Vec<String> = super::unsupported_functions(module).iter().map(|e| e.to_string()).collect();
                assert!(errors.is_empty(), "{graph} ({}): {errors:?}", ctx.name());
                let options = super::PacketOptions { table_data: Some("crate::TABLE".into()), ..Default::default() };
                let rs = super::write_packet_with(module, &options).unwrap();
                assert!(rs.contains("pub fn mx_pattern<S: Simd>") && rs.contains("pub use crate::TABLE as"), "{graph}");
                // The lobes run in functions of their own; the kernel's top never does.
                assert!(rs.contains("s.outline(#[inline(always)] || mx_") && !rs.contains("|| mx_pattern("), "{graph}");
            }
        }
    }
}
