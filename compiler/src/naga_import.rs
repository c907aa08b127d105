//! Importing pre-parsed library functions into a kernel's naga Module. The library's WGSL is
//! parsed once per process (`ConstEvaluator`'s module); a kernel's text declares the library
//! functions it calls as stubs (the library's signature with an empty body, [`stub`]), naga
//! parses that short text, and [`import_bodies`] replaces each stub by the library function:
//! locals, expressions and statements copied, and every handle into the module (types,
//! constants, global variables, functions) re-pointed at the kernel module's item of the same
//! name or structure. Function-local handles (expressions, locals) keep their indices, so a
//! copied function is the one naga would have made by parsing its text inside the kernel.
//!
//! The import is exact or refuses: a construct it does not re-point (overrides, ray queries,
//! atomics, subgroup and cooperative operations, …) or an item missing from the kernel module
//! is an `Err`, and lowering then parses the full text instead (lower.rs). Spans of imported
//! code are undefined (they point into the library's text, not the kernel's).

use naga::{Arena, Block, Expression as E, Function, Handle, Module, Span, Statement as S, Type, TypeInner as T};
use std::collections::HashMap;

/// A stub for the library function whose (comment-free) text is `text`: its header with a body
/// that returns the zero value of `result` (WGSL's `T()`), or nothing. `None` when the text has
/// no body to cut.
pub fn stub(text: &str, result: Option<&str>) -> Option<String> {
    let open = text.find('{')?;
    let header = text[..open].trim_end();
    Some(match result {
        Some(r) => format!("{header} {{ return {r}(); }}"),
        None => format!("{header} {{ }}"),
    })
}

/// A stub for a library array constant (`const NAME = array<T, N>(…);`, comment-free): the
/// same constant zero-initialised, `const NAME = array<T, N>();`, whose value
/// [`import_bodies`] then copies from the library. `None` for any other constant.
pub fn const_stub(text: &str) -> Option<String> {
    let eq = text.find('=')?;
    let value = text[eq + 1..].trim_start();
    if !value.starts_with("array<") {
        return None;
    }
    let open = text.len() - value.len() + value.find('(')?;
    Some(format!("{}();", &text[..open]))
}

/// Maps from library handles to kernel handles, filled as items are met.
struct Importer<'a> {
    lib: &'a Module,
    kernel: &'a mut Module,
    types: HashMap<Handle<Type>, Handle<Type>>,
    constants: HashMap<String, Handle<naga::Constant>>,
    globals: HashMap<String, Handle<naga::GlobalVariable>>,
    functions: HashMap<String, Handle<Function>>,
}

type Imported<T> = Result<T, String>;

/// Replaces the body of every kernel function named in `stubs` by the library function of the
/// same name, and the value of every kernel constant named in `const_stubs` by the library
/// constant's. `Err` names the first construct or item the import cannot re-point.
/// `lib_function` finds a library function by name (the library's map, built once).
pub fn import_bodies(lib: &Module, lib_function: impl Fn(&str) -> Option<Handle<Function>>, kernel: &mut Module, stubs: &[&str], const_stubs: &[&str]) -> Imported<()> {
    let constants = kernel.constants.iter().filter_map(|(h, c)| Some((c.name.clone()?, h))).collect();
    let globals = kernel.global_variables.iter().filter_map(|(h, g)| Some((g.name.clone()?, h))).collect();
    let functions = kernel.functions.iter().filter_map(|(h, f)| Some((f.name.clone()?, h))).collect();
    let mut im = Importer { lib, kernel, types: HashMap::new(), constants, globals, functions };
    for name in stubs {
        let from = lib_function(name).ok_or_else(|| format!("`{name}` is not a library function"))?;
        let &to = im.functions.get(*name).ok_or_else(|| format!("the kernel declares no `{name}`"))?;
        let f = im.function(&lib.functions[from])?;
        im.kernel.functions[to] = f;
    }
    for name in const_stubs {
        let from = lib.constants.iter().find(|(_, c)| c.name.as_deref() == Some(*name)).map(|(_, c)| c.init).ok_or_else(|| format!("`{name}` is not a library constant"))?;
        let &to = im.constants.get(*name).ok_or_else(|| format!("the kernel declares no `{name}`"))?;
        let init = im.global_expression(from)?;
        im.kernel.constants[to].init = init;
    }
    Ok(())
}

impl Importer<'_> {
    fn ty(&mut self, h: Handle<Type>) -> Imported<Handle<Type>> {
        if let Some(&k) = self.types.get(&h) {
            return Ok(k);
        }
        let lib = self.lib;
        let ty = &lib.types[h];
        let inner = match &ty.inner {
            T::Scalar(_) | T::Vector { .. } | T::Matrix { .. } | T::Atomic(_) | T::ValuePointer { .. } | T::Image { .. } | T::Sampler { .. } => ty.inner.clone(),
            T::Pointer { base, space } => T::Pointer { base: self.ty(*base)?, space: *space },
            T::Array { base, size: size @ (naga::ArraySize::Constant(_) | naga::ArraySize::Dynamic), stride } => T::Array { base: self.ty(*base)?, size: *size, stride: *stride },
            T::Struct { members, span } => {
                let mut m = members.clone();
                for member in &mut m {
                    member.ty = self.ty(member.ty)?;
                }
                T::Struct { members: m, span: *span }
            }
            other => return Err(format!("type {other:?}")),
        };
        let k = self.kernel.types.insert(Type { name: ty.name.clone(), inner }, Span::UNDEFINED);
        self.types.insert(h, k);
        Ok(k)
    }

    /// A library constant expression copied into the kernel's global expressions (operands
    /// first, as naga's arena order requires).
    fn global_expression(&mut self, h: Handle<E>) -> Imported<Handle<E>> {
        let lib = self.lib;
        let e = match &lib.global_expressions[h] {
            E::Literal(l) => E::Literal(*l),
            E::ZeroValue(ty) => E::ZeroValue(self.ty(*ty)?),
            E::Constant(c) => E::Constant(Self::by_name(&self.constants, &lib.constants[*c].name, "constant")?),
            E::Splat { size, value } => E::Splat { size: *size, value: self.global_expression(*value)? },
            E::Compose { ty, components } => {
                let components = components.iter().map(|&c| self.global_expression(c)).collect::<Imported<Vec<_>>>()?;
                E::Compose { ty: self.ty(*ty)?, components }
            }
            other => return Err(format!("constant expression {other:?}")),
        };
        Ok(self.kernel.global_expressions.append(e, Span::UNDEFINED))
    }

    fn by_name<T: Copy>(map: &HashMap<String, T>, name: &Option<String>, what: &str) -> Imported<T> {
        let name = name.as_deref().ok_or_else(|| format!("an unnamed {what}"))?;
        map.get(name).copied().ok_or_else(|| format!("the kernel has no {what} `{name}`"))
    }

    fn function(&mut self, f: &Function) -> Imported<Function> {
        let lib = self.lib;
        let mut arguments = f.arguments.clone();
        for a in &mut arguments {
            a.ty = self.ty(a.ty)?;
        }
        let mut result = f.result.clone();
        if let Some(r) = &mut result {
            r.ty = self.ty(r.ty)?;
        }
        let mut local_variables = Arena::new();
        for (_, lv) in f.local_variables.iter() {
            let mut lv = lv.clone();
            lv.ty = self.ty(lv.ty)?;
            local_variables.append(lv, Span::UNDEFINED);
        }
        let mut expressions = Arena::new();
        for (_, e) in f.expressions.iter() {
            let e = match e {
                E::Constant(c) => E::Constant(Self::by_name(&self.constants, &lib.constants[*c].name, "constant")?),
                E::GlobalVariable(g) => E::GlobalVariable(Self::by_name(&self.globals, &lib.global_variables[*g].name, "global variable")?),
                E::CallResult(fh) => E::CallResult(Self::by_name(&self.functions, &lib.functions[*fh].name, "function")?),
                E::ZeroValue(ty) => E::ZeroValue(self.ty(*ty)?),
                E::Compose { ty, components } => E::Compose { ty: self.ty(*ty)?, components: components.clone() },
                E::Literal(_)
                | E::Access { .. }
                | E::AccessIndex { .. }
                | E::Splat { .. }
                | E::Swizzle { .. }
                | E::FunctionArgument(_)
                | E::LocalVariable(_)
                | E::Load { .. }
                | E::ImageSample { .. }
                | E::ImageLoad { .. }
                | E::ImageQuery { .. }
                | E::Unary { .. }
                | E::Binary { .. }
                | E::Select { .. }
                | E::Derivative { .. }
                | E::Relational { .. }
                | E::Math { .. }
                | E::As { .. }
                | E::ArrayLength(_) => e.clone(),
                other => return Err(format!("expression {other:?}")),
            };
            expressions.append(e, Span::UNDEFINED);
        }
        let body = self.block(&f.body)?;
        Ok(Function {
            name: f.name.clone(),
            arguments,
            result,
            local_variables,
            expressions,
            named_expressions: f.named_expressions.clone(),
            body,
            diagnostic_filter_leaf: None,
        })
    }

    fn block(&mut self, b: &Block) -> Imported<Block> {
        let mut out = Block::with_capacity(b.len());
        for st in b.iter() {
            let st = match st {
                S::Block(inner) => S::Block(self.block(inner)?),
                S::If { condition, accept, reject } => S::If { condition: *condition, accept: self.block(accept)?, reject: self.block(reject)? },
                S::Switch { selector, cases } => {
                    let mut c = Vec::with_capacity(cases.len());
                    for case in cases {
                        c.push(naga::SwitchCase { value: case.value, body: self.block(&case.body)?, fall_through: case.fall_through });
                    }
                    S::Switch { selector: *selector, cases: c }
                }
                S::Loop { body, continuing, break_if } => S::Loop { body: self.block(body)?, continuing: self.block(continuing)?, break_if: *break_if },
                S::Call { function, arguments, result } => {
                    S::Call { function: Self::by_name(&self.functions, &self.lib.functions[*function].name, "function")?, arguments: arguments.clone(), result: *result }
                }
                S::Emit(_) | S::Break | S::Continue | S::Return { .. } | S::Kill | S::Store { .. } | S::ImageStore { .. } | S::ControlBarrier(_) | S::MemoryBarrier(_) => st.clone(),
                other => return Err(format!("statement {other:?}")),
            };
            out.push(st, Span::UNDEFINED);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stubs_keep_the_header_and_return_a_zero_value() {
        assert_eq!(stub("fn f(a: f32, b: vec2<f32>) -> vec3<f32> { return vec3<f32>(a); }", Some("vec3<f32>")).unwrap(), "fn f(a: f32, b: vec2<f32>) -> vec3<f32> { return vec3<f32>(); }");
        assert_eq!(stub("fn g(p: ptr<function, f32>) { *p = 1.0; }", None).unwrap(), "fn g(p: ptr<function, f32>) { }");
        assert_eq!(stub("const X = 1;", None), None);
        assert_eq!(const_stub("const T = array<f32, 3>(1.0, 2.0, 3.0);").unwrap(), "const T = array<f32, 3>();");
        assert_eq!(const_stub("const X: f32 = 1.0;"), None);
    }

    /// A library with a struct, a constant, a call chain, a loop, a switch and locals: the
    /// kernel built from stubs and imported bodies writes the same WGSL as the kernel parsed
    /// from the full text.
    #[test]
    fn imported_bodies_write_the_same_wgsl_as_parsed_ones() {
        let lib_text = "struct S { a: f32, b: vec3<f32> }\nconst K: f32 = 0.5;\nconst T = array<f32, 3>(1.0, 2.0, 3.0);\n\
            fn inner(x: f32) -> S { var s = S(x, vec3<f32>(x)); for (var i = 0; i < 3; i++) { s.a += K * T[i]; } return s; }\n\
            fn outer(x: f32, m: i32) -> f32 { var r = 0.0; switch m { case 0: { r = inner(x).a; } default: { r = inner(-x).b.y; } } if (r > 1.0) { return r; } return r * 2.0; }\n";
        let entry = "@compute @workgroup_size(1) fn main() { let v = outer(1.0, 0); }\n";
        let lib = naga::front::wgsl::parse_str(lib_text).unwrap();
        let write = |m: &Module| {
            let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default()).validate(m).unwrap();
            naga::back::wgsl::write_string(m, &info, naga::back::wgsl::WriterFlags::empty()).unwrap()
        };
        let parsed = naga::front::wgsl::parse_str(&format!("{lib_text}{entry}")).unwrap();
        let stubs = "struct S { a: f32, b: vec3<f32> }\nconst K: f32 = 0.5;\n".to_string()
            + &const_stub("const T = array<f32, 3>(1.0, 2.0, 3.0);").unwrap()
            + "\n"
            + &stub("fn inner(x: f32) -> S { body }", Some("S")).unwrap()
            + "\n"
            + &stub("fn outer(x: f32, m: i32) -> f32 { body }", Some("f32")).unwrap()
            + "\n"
            + entry;
        let mut kernel = naga::front::wgsl::parse_str(&stubs).unwrap();
        let find = |n: &str| lib.functions.iter().find(|(_, f)| f.name.as_deref() == Some(n)).map(|(h, _)| h);
        import_bodies(&lib, find, &mut kernel, &["inner", "outer"], &["T"]).unwrap();
        assert_eq!(write(&kernel), write(&parsed));
        // A function the kernel does not declare is refused, not skipped.
        let mut kernel = naga::front::wgsl::parse_str(&stubs).unwrap();
        assert!(import_bodies(&lib, find, &mut kernel, &["missing"], &[]).is_err());
    }
}
