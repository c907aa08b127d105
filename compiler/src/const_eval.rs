//! Constant folding by interpretation. [`ConstEvaluator`] runs a library WGSL function (`mx_…`)
//! on constant arguments at compile time by interpreting the naga IR that naga's WGSL front end
//! makes of the node library, so node semantics stay written once, in WGSL. This module owns
//! that interpreter (WGSL semantics in f32: wrapping integer arithmetic, `x / 0 == x`,
//! `x % 0 == 0`, truncated float `%`, round half to even, …) and [`Const`], the value type at
//! its interface, with the conversions from and to MaterialX literals. Whatever it does not
//! implement (textures, derivatives, atomics, globals, packing builtins, …), a run over
//! [`STEP_BUDGET`] and NaN/Inf results give `None`; it never panics.

use mtlx::{DataType, Value};
use naga::{
    BinaryOperator as Bin, Expression as E, Function, Handle, Literal, MathFunction as M, Module,
    RelationalFunction as R, Scalar, ScalarKind as K, Statement as S, SwitchValue, TypeInner as T,
    UnaryOperator as U,
};
use std::collections::HashMap;

/// Statements (loop iterations included) that one [`ConstEvaluator::eval`] may execute.
pub const STEP_BUDGET: u64 = 1_000_000;
/// Call nesting limit (WGSL has no recursion; this only bounds the Rust stack).
const MAX_DEPTH: usize = 64;

/// A WGSL value at the evaluator's interface.
#[derive(Clone, Debug, PartialEq)]
pub enum Const {
    Bool(bool),
    I32(i32),
    U32(u32),
    F32(f32),
    /// The components of a `vecN<T>`.
    Vector(Vec<Const>),
    /// A `matCxR<f32>`, `data` column-major.
    Matrix { columns: usize, rows: usize, data: Vec<f32> },
    /// The members of a struct (a multi-output result), in order.
    Struct(Vec<Const>),
}

impl Const {
    /// The argument a library function receives for a MaterialX value of type `ty` (the
    /// README's type mapping; enum strings must already be their `Integer` index). A matrix is
    /// listed row by row and WGSL columns are MaterialX rows, so the list is the column-major data.
    pub fn from_literal(ty: &DataType, value: &Value) -> Option<Const> {
        let floats = |n: usize| match value {
            Value::Floats(v) if v.len() == n => Some(v),
            _ => None,
        };
        Some(match (ty, value) {
            (DataType::Boolean, Value::Boolean(b)) => Const::Bool(*b),
            (DataType::Integer, Value::Integer(i)) => Const::I32(*i),
            (DataType::Float, _) => Const::F32(floats(1)?[0]),
            (DataType::Matrix33 | DataType::Matrix44, _) => {
                let n = if matches!(ty, DataType::Matrix33) { 3 } else { 4 };
                Const::Matrix { columns: n, rows: n, data: floats(n * n)?.clone() }
            }
            (DataType::Vector2 | DataType::Vector3 | DataType::Vector4 | DataType::Color3 | DataType::Color4, _) => {
                Const::Vector(floats(ty.components()?)?.iter().map(|&x| Const::F32(x)).collect())
            }
            _ => return None,
        })
    }

    /// The MaterialX value of type `ty` this result stands for; `None` on a type mismatch or a
    /// non-finite float (which has no WGSL literal).
    pub fn to_literal(&self, ty: &DataType) -> Option<Value> {
        let value = match (ty, self) {
            (DataType::Boolean, Const::Bool(b)) => Value::Boolean(*b),
            (DataType::Integer, Const::I32(i)) => Value::Integer(*i),
            (DataType::Float, Const::F32(x)) => Value::Floats(vec![*x]),
            (DataType::Matrix33 | DataType::Matrix44, Const::Matrix { columns, rows, data }) => {
                (columns == rows && ty.components() == Some(data.len())).then(|| Value::Floats(data.clone()))?
            }
            (DataType::Vector2 | DataType::Vector3 | DataType::Vector4 | DataType::Color3 | DataType::Color4, Const::Vector(c))
                if ty.components() == Some(c.len()) =>
            {
                let f = c.iter().map(|c| if let Const::F32(x) = c { Some(*x) } else { None });
                Value::Floats(f.collect::<Option<_>>()?)
            }
            _ => return None,
        };
        match &value {
            Value::Floats(f) if f.iter().any(|x| !x.is_finite()) => None,
            _ => Some(value),
        }
    }

    /// Member `index` of a struct result (the value of one output of a multi-output node).
    pub fn field(&self, index: usize) -> Option<&Const> {
        match self {
            Const::Struct(members) => members.get(index),
            _ => None,
        }
    }
}

/// The node library parsed once; evaluates its functions on constants.
#[derive(Clone, Debug)]
pub struct ConstEvaluator {
    module: Module,
    functions: HashMap<String, Handle<Function>>,
}

impl ConstEvaluator {
    /// `library_wgsl_text`: the concatenation of all library WGSL sources.
    pub fn new(library_wgsl_text: &str) -> Result<Self, String> {
        let module = naga::front::wgsl::parse_str(library_wgsl_text).map_err(|e| e.emit_to_string(library_wgsl_text))?;
        let functions = module.functions.iter().filter_map(|(h, f)| Some((f.name.clone()?, h))).collect();
        Ok(ConstEvaluator { module, functions })
    }

    /// The library parsed as one module (lowering imports its functions: naga_import.rs).
    pub fn module(&self) -> &Module {
        &self.module
    }

    /// The library function named `name`.
    pub fn function(&self, name: &str) -> Option<Handle<Function>> {
        self.functions.get(name).copied()
    }

    /// The value `function(args…)` returns, or `None` when it cannot be folded (unknown
    /// function, arguments not of the parameter types, unsupported construct, step budget
    /// exceeded, NaN/Inf anywhere in the result).
    pub fn eval(&self, function: &str, args: &[Const]) -> Option<Const> {
        let &fh = self.functions.get(function)?;
        let f = &self.module.functions[fh];
        let ret = f.result.as_ref()?.ty;
        let args: Vec<V> = args.iter().map(V::from_const).collect::<Option<_>>()?;
        if args.len() != f.arguments.len() || !args.iter().zip(&f.arguments).all(|(v, a)| conforms(&self.module, v, a.ty)) {
            return None;
        }
        let mut run = Run { m: &self.module, steps: 0, depth: 0, mem: Vec::new(), consts: HashMap::new() };
        let out = run.call(fh, args)??;
        if !conforms(&self.module, &out, ret) {
            return None;
        }
        out.to_const()
    }
}

/// An interpreter value. Matrices are lists of column vectors; `Agg` is a struct or an array;
/// `Ptr` is a slot of the memory stack plus a path of component indices.
#[derive(Clone, Debug, PartialEq)]
enum V {
    B(bool),
    I(i32),
    U(u32),
    F(f32),
    Vec(Vec<V>),
    Mat(Vec<V>),
    Agg(Vec<V>),
    Ptr(usize, Vec<usize>),
}

impl V {
    fn from_const(c: &Const) -> Option<V> {
        Some(match c {
            Const::Bool(b) => V::B(*b),
            Const::I32(i) => V::I(*i),
            Const::U32(u) => V::U(*u),
            Const::F32(x) => V::F(*x),
            Const::Vector(c) => V::Vec(c.iter().map(V::from_const).collect::<Option<_>>()?),
            Const::Matrix { columns, rows, data } => {
                if *rows == 0 || data.len() != columns * rows {
                    return None;
                }
                V::Mat(data.chunks(*rows).map(|c| V::Vec(c.iter().map(|&x| V::F(x)).collect())).collect())
            }
            Const::Struct(m) => V::Agg(m.iter().map(V::from_const).collect::<Option<_>>()?),
        })
    }

    /// `None` for pointers and non-finite floats.
    fn to_const(&self) -> Option<Const> {
        let all = |c: &[V]| c.iter().map(V::to_const).collect::<Option<Vec<_>>>();
        Some(match self {
            V::B(b) => Const::Bool(*b),
            V::I(i) => Const::I32(*i),
            V::U(u) => Const::U32(*u),
            V::F(x) => Const::F32(x.is_finite().then_some(*x)?),
            V::Vec(c) => Const::Vector(all(c)?),
            V::Agg(c) => Const::Struct(all(c)?),
            V::Mat(cols) => {
                let rows = cols.first().and_then(V::parts)?.len();
                let data = cols.iter().flat_map(|c| c.parts().into_iter().flatten()).map(V::f).collect::<Option<Vec<_>>>()?;
                if data.len() != rows * cols.len() || data.iter().any(|x| !x.is_finite()) {
                    return None;
                }
                Const::Matrix { columns: cols.len(), rows, data }
            }
            V::Ptr(..) => return None,
        })
    }

    fn parts(&self) -> Option<&Vec<V>> {
        match self {
            V::Vec(c) | V::Mat(c) | V::Agg(c) => Some(c),
            _ => None,
        }
    }

    fn parts_mut(&mut self) -> Option<&mut Vec<V>> {
        match self {
            V::Vec(c) | V::Mat(c) | V::Agg(c) => Some(c),
            _ => None,
        }
    }

    fn is_scalar(&self) -> bool {
        matches!(self, V::B(_) | V::I(_) | V::U(_) | V::F(_))
    }

    fn f(&self) -> Option<f32> {
        if let V::F(x) = self { Some(*x) } else { None }
    }

    fn u(&self) -> Option<u32> {
        if let V::U(x) = self { Some(*x) } else { None }
    }

    fn b(&self) -> Option<bool> {
        if let V::B(x) = self { Some(*x) } else { None }
    }

    fn floats(&self) -> Option<Vec<f32>> {
        self.parts()?.iter().map(V::f).collect()
    }
}

fn zero_scalar(s: Scalar) -> Option<V> {
    Some(match (s.kind, s.width) {
        (K::Bool, _) => V::B(false),
        (K::Sint, 4) => V::I(0),
        (K::Uint, 4) => V::U(0),
        (K::Float, 4) => V::F(0.0),
        _ => return None,
    })
}

/// The zero value of a type; `None` for types the interpreter does not represent.
fn zero(m: &Module, ty: Handle<naga::Type>) -> Option<V> {
    Some(match &m.types[ty].inner {
        T::Scalar(s) => zero_scalar(*s)?,
        T::Vector { size, scalar } => V::Vec(vec![zero_scalar(*scalar)?; *size as usize]),
        T::Matrix { columns, rows, scalar } => V::Mat(vec![V::Vec(vec![zero_scalar(*scalar)?; *rows as usize]); *columns as usize]),
        T::Struct { members, .. } => V::Agg(members.iter().map(|mm| zero(m, mm.ty)).collect::<Option<_>>()?),
        T::Array { base, size: naga::ArraySize::Constant(n), .. } => V::Agg(vec![zero(m, *base)?; n.get() as usize]),
        _ => return None,
    })
}

/// Whether `v` is a value of type `ty` (same shape and scalar kinds as its zero value).
fn conforms(m: &Module, v: &V, ty: Handle<naga::Type>) -> bool {
    fn same(a: &V, b: &V) -> bool {
        match (a.parts(), b.parts()) {
            (Some(x), Some(y)) => {
                std::mem::discriminant(a) == std::mem::discriminant(b) && x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
            }
            _ => a.is_scalar() && std::mem::discriminant(a) == std::mem::discriminant(b),
        }
    }
    zero(m, ty).is_some_and(|z| same(&z, v))
}

/// Applies `f` per component: vectors of one length, scalars broadcast. `f` gets the scalars.
fn zipn(args: &[V], f: &dyn Fn(&[V]) -> Option<V>) -> Option<V> {
    let mut len = None;
    for a in args {
        match a {
            V::Vec(c) if len.is_none_or(|n| n == c.len()) => len = Some(c.len()),
            a if a.is_scalar() => {}
            _ => return None,
        }
    }
    let Some(n) = len else { return f(args) };
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let row: Vec<V> = args.iter().map(|a| if let V::Vec(c) = a { c[i].clone() } else { a.clone() }).collect();
        out.push(f(&row)?);
    }
    Some(V::Vec(out))
}

/// `zipn` over an all-f32 function (at most 3 operands).
fn fmap(args: &[V], g: impl Fn([f32; 3]) -> f32) -> Option<V> {
    zipn(args, &|x| {
        let mut a = [0.0; 3];
        for (slot, v) in a.iter_mut().zip(x) {
            *slot = v.f()?;
        }
        Some(V::F(g(a)))
    })
}

fn compare<T: PartialOrd>(op: Bin, x: T, y: T) -> Option<V> {
    Some(V::B(match op {
        Bin::Equal => x == y,
        Bin::NotEqual => x != y,
        Bin::Less => x < y,
        Bin::LessEqual => x <= y,
        Bin::Greater => x > y,
        Bin::GreaterEqual => x >= y,
        _ => return None,
    }))
}

fn scalar_binary(op: Bin, a: &V, b: &V) -> Option<V> {
    use V::{B, F, I, U};
    Some(match (a, b) {
        (&F(x), &F(y)) => F(match op {
            Bin::Add => x + y,
            Bin::Subtract => x - y,
            Bin::Multiply => x * y,
            Bin::Divide => x / y,
            Bin::Modulo => x - y * (x / y).trunc(),
            _ => return compare(op, x, y),
        }),
        (&I(x), &I(y)) => I(match op {
            Bin::Add => x.wrapping_add(y),
            Bin::Subtract => x.wrapping_sub(y),
            Bin::Multiply => x.wrapping_mul(y),
            Bin::Divide => x.checked_div(y).unwrap_or(x),
            Bin::Modulo => x.checked_rem(y).unwrap_or(0),
            Bin::And => x & y,
            Bin::InclusiveOr => x | y,
            Bin::ExclusiveOr => x ^ y,
            _ => return compare(op, x, y),
        }),
        (&I(x), &U(y)) => I(match op {
            Bin::ShiftLeft => x.wrapping_shl(y),
            Bin::ShiftRight => x.wrapping_shr(y),
            _ => return None,
        }),
        (&U(x), &U(y)) => U(match op {
            Bin::Add => x.wrapping_add(y),
            Bin::Subtract => x.wrapping_sub(y),
            Bin::Multiply => x.wrapping_mul(y),
            Bin::Divide => x.checked_div(y).unwrap_or(x),
            Bin::Modulo => x.checked_rem(y).unwrap_or(0),
            Bin::And => x & y,
            Bin::InclusiveOr => x | y,
            Bin::ExclusiveOr => x ^ y,
            Bin::ShiftLeft => x.wrapping_shl(y),
            Bin::ShiftRight => x.wrapping_shr(y),
            _ => return compare(op, x, y),
        }),
        (&B(x), &B(y)) => B(match op {
            Bin::LogicalAnd | Bin::And => x && y,
            Bin::LogicalOr | Bin::InclusiveOr => x || y,
            Bin::Equal => x == y,
            Bin::NotEqual => x != y,
            _ => return None,
        }),
        _ => return None,
    })
}

/// Sum of the component products, accumulated left to right.
fn dot(a: &V, b: &V) -> Option<V> {
    let products = binary(Bin::Multiply, a, b)?;
    let mut terms = products.parts()?.iter();
    let first = terms.next()?.clone();
    terms.try_fold(first, |acc, t| scalar_binary(Bin::Add, &acc, t))
}

/// `m * v`: the columns of `m` weighted by the components of `v`, summed.
fn mat_vec(m: &[V], v: &[V]) -> Option<V> {
    if m.len() != v.len() || m.is_empty() {
        return None;
    }
    let mut acc = binary(Bin::Multiply, &m[0], &v[0])?;
    for (col, s) in m.iter().zip(v).skip(1) {
        acc = binary(Bin::Add, &acc, &binary(Bin::Multiply, col, s)?)?;
    }
    Some(acc)
}

fn binary(op: Bin, a: &V, b: &V) -> Option<V> {
    use V::{Mat, Vec as Vector};
    let cols = |x: &[V], f: &dyn Fn(&V) -> Option<V>| x.iter().map(f).collect::<Option<Vec<_>>>().map(Mat);
    match (op, a, b) {
        (Bin::Add | Bin::Subtract, Mat(x), Mat(y)) if x.len() == y.len() => {
            x.iter().zip(y).map(|(p, q)| binary(op, p, q)).collect::<Option<_>>().map(Mat)
        }
        (Bin::Multiply, Mat(m), s) | (Bin::Multiply, s, Mat(m)) if s.is_scalar() => cols(m, &|c| binary(op, c, s)),
        (Bin::Multiply, Mat(m), Vector(v)) => mat_vec(m, v),
        (Bin::Multiply, Vector(_), Mat(m)) => m.iter().map(|c| dot(a, c)).collect::<Option<_>>().map(Vector),
        (Bin::Multiply, Mat(x), Mat(y)) => cols(y, &|c| mat_vec(x, c.parts()?)),
        _ => zipn(&[a.clone(), b.clone()], &|x| scalar_binary(op, &x[0], &x[1])),
    }
}

fn unary(op: U, a: &V) -> Option<V> {
    if let V::Mat(c) = a {
        return c.iter().map(|c| unary(op, c)).collect::<Option<_>>().map(V::Mat);
    }
    zipn(std::slice::from_ref(a), &|x| match (op, &x[0]) {
        (U::Negate, V::F(v)) => Some(V::F(-v)),
        (U::Negate, V::I(v)) => Some(V::I(v.wrapping_neg())),
        (U::LogicalNot, V::B(v)) => Some(V::B(!v)),
        (U::BitwiseNot, V::I(v)) => Some(V::I(!v)),
        (U::BitwiseNot, V::U(v)) => Some(V::U(!v)),
        _ => None,
    })
}

/// WGSL value conversion (`convert: Some(width)`) or bitcast (`None`) of a scalar or vector.
fn cast(v: &V, kind: K, convert: Option<u8>) -> Option<V> {
    if convert.is_some_and(|w| w != 4 && kind != K::Bool) {
        return None;
    }
    zipn(std::slice::from_ref(v), &|x| {
        Some(match (convert.is_some(), kind, x[0].clone()) {
            (_, K::Float, V::F(f)) => V::F(f),
            (_, K::Sint, V::I(i)) => V::I(i),
            (_, K::Uint, V::U(u)) => V::U(u),
            (_, K::Sint, V::U(u)) => V::I(u as i32),
            (_, K::Uint, V::I(i)) => V::U(i as u32),
            (true, K::Float, V::I(i)) => V::F(i as f32),
            (true, K::Float, V::U(u)) => V::F(u as f32),
            (true, K::Float, V::B(b)) => V::F(f32::from(u8::from(b))),
            // f32 to integer: truncate, clamped to the largest f32 values the type holds.
            (true, K::Sint, V::F(f)) => V::I(f.clamp(-2147483648.0, 2147483520.0) as i32),
            (true, K::Uint, V::F(f)) => V::U(f.clamp(0.0, 4294967040.0) as u32),
            (true, K::Sint, V::B(b)) => V::I(i32::from(b)),
            (true, K::Uint, V::B(b)) => V::U(u32::from(b)),
            (true, K::Bool, V::B(b)) => V::B(b),
            (true, K::Bool, V::F(f)) => V::B(f != 0.0),
            (true, K::Bool, V::I(i)) => V::B(i != 0),
            (true, K::Bool, V::U(u)) => V::B(u != 0),
            (false, K::Float, V::I(i)) => V::F(f32::from_bits(i as u32)),
            (false, K::Float, V::U(u)) => V::F(f32::from_bits(u)),
            (false, K::Sint, V::F(f)) => V::I(f.to_bits() as i32),
            (false, K::Uint, V::F(f)) => V::U(f.to_bits()),
            _ => return None,
        })
    })
}

fn length(v: &V) -> Option<f32> {
    match v {
        V::F(x) => Some(x.abs()),
        _ => dot(v, v)?.f().map(f32::sqrt),
    }
}

/// Determinant by cofactor expansion along the first column (`m`: columns).
fn det(m: &[Vec<f32>]) -> f32 {
    if m.len() == 1 {
        return m[0][0];
    }
    let mut sum = 0.0;
    for r in 0..m.len() {
        let minor: Vec<Vec<f32>> = m[1..].iter().map(|c| c.iter().enumerate().filter(|&(i, _)| i != r).map(|(_, &x)| x).collect()).collect();
        let term = m[0][r] * det(&minor);
        sum += if r % 2 == 0 { term } else { -term };
    }
    sum
}

fn order<N: PartialOrd + Copy>(fun: M, x: &[N]) -> Option<N> {
    let min = |a: N, b: N| if b < a { b } else { a };
    let max = |a: N, b: N| if b > a { b } else { a };
    match (fun, x) {
        (M::Min, &[a, b]) => Some(min(a, b)),
        (M::Max, &[a, b]) => Some(max(a, b)),
        (M::Clamp, &[e, lo, hi]) => Some(min(max(e, lo), hi)),
        _ => None,
    }
}

fn math(fun: M, args: &[V]) -> Option<V> {
    use V::{F, I, U as Uv};
    let a = args.first()?;
    let arg = |i: usize| args.get(i);
    match fun {
        M::Abs => zipn(args, &|x| match x[0] {
            F(v) => Some(F(v.abs())),
            I(v) => Some(I(v.wrapping_abs())),
            Uv(v) => Some(Uv(v)),
            _ => None,
        }),
        M::Min | M::Max | M::Clamp => zipn(args, &|x| match x[0] {
            F(_) => order(fun, &x.iter().map(V::f).collect::<Option<Vec<_>>>()?[..]).map(F),
            I(_) => order(fun, &x.iter().map(|v| if let I(i) = v { Some(*i) } else { None }).collect::<Option<Vec<_>>>()?[..]).map(I),
            Uv(_) => order(fun, &x.iter().map(V::u).collect::<Option<Vec<_>>>()?[..]).map(Uv),
            _ => None,
        }),
        M::Sign => zipn(args, &|x| match x[0] {
            F(v) => Some(F(if v == 0.0 { 0.0 } else { v.signum() })),
            I(v) => Some(I(v.signum())),
            _ => None,
        }),
        M::Saturate => fmap(args, |x| x[0].clamp(0.0, 1.0)),
        M::Cos => fmap(args, |x| x[0].cos()),
        M::Cosh => fmap(args, |x| x[0].cosh()),
        M::Sin => fmap(args, |x| x[0].sin()),
        M::Sinh => fmap(args, |x| x[0].sinh()),
        M::Tan => fmap(args, |x| x[0].tan()),
        M::Tanh => fmap(args, |x| x[0].tanh()),
        M::Acos => fmap(args, |x| x[0].acos()),
        M::Asin => fmap(args, |x| x[0].asin()),
        M::Atan => fmap(args, |x| x[0].atan()),
        M::Atan2 => fmap(args, |x| x[0].atan2(x[1])),
        M::Asinh => fmap(args, |x| x[0].asinh()),
        M::Acosh => fmap(args, |x| x[0].acosh()),
        M::Atanh => fmap(args, |x| x[0].atanh()),
        M::Radians => fmap(args, |x| x[0].to_radians()),
        M::Degrees => fmap(args, |x| x[0].to_degrees()),
        M::Ceil => fmap(args, |x| x[0].ceil()),
        M::Floor => fmap(args, |x| x[0].floor()),
        M::Round => fmap(args, |x| x[0].round_ties_even()),
        M::Fract => fmap(args, |x| x[0] - x[0].floor()),
        M::Trunc => fmap(args, |x| x[0].trunc()),
        M::Exp => fmap(args, |x| x[0].exp()),
        M::Exp2 => fmap(args, |x| x[0].exp2()),
        M::Log => fmap(args, |x| x[0].ln()),
        M::Log2 => fmap(args, |x| x[0].log2()),
        M::Pow => fmap(args, |x| x[0].powf(x[1])),
        M::Sqrt => fmap(args, |x| x[0].sqrt()),
        M::InverseSqrt => fmap(args, |x| 1.0 / x[0].sqrt()),
        M::Fma => fmap(args, |x| x[0].mul_add(x[1], x[2])),
        M::Mix => fmap(args, |x| x[0] * (1.0 - x[2]) + x[1] * x[2]),
        M::Step => fmap(args, |x| if x[0] <= x[1] { 1.0 } else { 0.0 }),
        M::SmoothStep => fmap(args, |x| {
            let t = ((x[2] - x[0]) / (x[1] - x[0])).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        }),
        M::Dot => dot(a, arg(1)?),
        M::Length => length(a).map(F),
        M::Distance => length(&binary(Bin::Subtract, a, arg(1)?)?).map(F),
        M::Normalize => binary(Bin::Divide, a, &F(length(a)?)),
        M::Cross => match (a.floats()?.as_slice(), arg(1)?.floats()?.as_slice()) {
            (&[a0, a1, a2], &[b0, b1, b2]) => Some(V::Vec(vec![F(a1 * b2 - a2 * b1), F(a2 * b0 - a0 * b2), F(a0 * b1 - a1 * b0)])),
            _ => None,
        },
        M::FaceForward => {
            let flip = dot(arg(1)?, arg(2)?)?.f()? < 0.0;
            if flip { Some(a.clone()) } else { unary(U::Negate, a) }
        }
        M::Reflect => {
            let n = arg(1)?;
            let k = scalar_binary(Bin::Multiply, &F(2.0), &dot(n, a)?)?;
            binary(Bin::Subtract, a, &binary(Bin::Multiply, &k, n)?)
        }
        M::Refract => {
            let (n, eta) = (arg(1)?, arg(2)?.f()?);
            let d = dot(n, a)?.f()?;
            let k = 1.0 - eta * eta * (1.0 - d * d);
            if k < 0.0 {
                return binary(Bin::Multiply, a, &F(0.0));
            }
            binary(Bin::Subtract, &binary(Bin::Multiply, a, &F(eta))?, &binary(Bin::Multiply, n, &F(eta * d + k.sqrt()))?)
        }
        M::Transpose => {
            let cols: Vec<Vec<f32>> = a.parts().filter(|_| matches!(a, V::Mat(_)))?.iter().map(V::floats).collect::<Option<_>>()?;
            let rows = cols.first()?.len();
            (0..rows).map(|r| cols.iter().map(|c| c.get(r).map(|&x| F(x))).collect::<Option<_>>().map(V::Vec)).collect::<Option<_>>().map(V::Mat)
        }
        M::Determinant => {
            let cols: Vec<Vec<f32>> = a.parts().filter(|_| matches!(a, V::Mat(_)))?.iter().map(V::floats).collect::<Option<_>>()?;
            (cols.iter().all(|c| c.len() == cols.len())).then(|| F(det(&cols)))
        }
        M::CountOneBits | M::ReverseBits | M::CountLeadingZeros | M::CountTrailingZeros | M::FirstTrailingBit | M::FirstLeadingBit => {
            zipn(args, &|x| {
                let (bits, signed) = match x[0] {
                    I(v) => (v as u32, true),
                    Uv(v) => (v, false),
                    _ => return None,
                };
                let r = match fun {
                    M::CountOneBits => bits.count_ones(),
                    M::ReverseBits => bits.reverse_bits(),
                    M::CountLeadingZeros => bits.leading_zeros(),
                    M::CountTrailingZeros => bits.trailing_zeros(),
                    M::FirstTrailingBit => if bits == 0 { u32::MAX } else { bits.trailing_zeros() },
                    _ => {
                        let b = if signed && (bits as i32) < 0 { !bits } else { bits };
                        b.checked_ilog2().unwrap_or(u32::MAX)
                    }
                };
                Some(if signed { I(r as i32) } else { Uv(r) })
            })
        }
        _ => None,
    }
}

enum Flow {
    Next,
    Break,
    Continue,
    Return(Option<V>),
}

/// One function activation: its arguments, where its locals start on the memory stack, and the
/// values of its expressions evaluated so far.
struct Frame {
    args: Vec<V>,
    base: usize,
    cache: ExprCache,
}

/// The values of a frame's expressions computed so far: dense for a function's expressions,
/// sparse for the module's global expressions (the library's run to ~10⁵ — the albedo tables'
/// literals — of which a constant's initializer reads a handful: a dense cache allocated and
/// dropped per constant met cost a tenth of compile time).
enum ExprCache {
    Dense(Vec<Option<V>>),
    Sparse(HashMap<usize, V>),
}

impl ExprCache {
    /// The cached value of expression `i`: `Err(())` when `i` lies outside a dense cache.
    fn get(&self, i: usize) -> Result<Option<&V>, ()> {
        match self {
            ExprCache::Dense(v) => v.get(i).map(Option::as_ref).ok_or(()),
            ExprCache::Sparse(m) => Ok(m.get(&i)),
        }
    }

    fn set(&mut self, i: usize, value: V) {
        match self {
            ExprCache::Dense(v) => v[i] = Some(value),
            ExprCache::Sparse(m) => {
                m.insert(i, value);
            }
        }
    }
}

/// The state of one `eval`: the memory stack (locals of all active calls, so pointers may
/// cross calls), the step count and the module constants met so far.
struct Run<'a> {
    m: &'a Module,
    steps: u64,
    depth: usize,
    mem: Vec<V>,
    consts: HashMap<Handle<naga::Constant>, V>,
}

type Exprs = naga::Arena<naga::Expression>;

impl<'a> Run<'a> {
    /// Runs a function; `Some(None)` when it returns nothing.
    fn call(&mut self, fh: Handle<Function>, args: Vec<V>) -> Option<Option<V>> {
        let m = self.m;
        let f = &m.functions[fh];
        if self.depth >= MAX_DEPTH || args.len() != f.arguments.len() {
            return None;
        }
        let mut fr = Frame { args, base: self.mem.len(), cache: ExprCache::Dense(vec![None; f.expressions.len()]) };
        for (_, lv) in f.local_variables.iter() {
            let v = match lv.init {
                Some(h) => self.expr(&f.expressions, &mut fr, h)?,
                None => zero(m, lv.ty)?,
            };
            self.mem.push(v);
        }
        self.depth += 1;
        let flow = self.block(f, &mut fr, &f.body)?;
        self.depth -= 1;
        self.mem.truncate(fr.base);
        let value = if let Flow::Return(v) = flow { v } else { None };
        (value.is_some() == f.result.is_some()).then_some(value)
    }

    fn block(&mut self, f: &'a Function, fr: &mut Frame, block: &'a naga::Block) -> Option<Flow> {
        for st in block.iter() {
            self.tick()?;
            let flow = match st {
                S::Emit(range) => {
                    for h in range.clone() {
                        let v = self.compute(&f.expressions, fr, h)?;
                        fr.cache.set(h.index(), v);
                    }
                    Flow::Next
                }
                S::Block(b) => self.block(f, fr, b)?,
                S::If { condition, accept, reject } => {
                    let c = self.expr(&f.expressions, fr, *condition)?.b()?;
                    self.block(f, fr, if c { accept } else { reject })?
                }
                S::Switch { selector, cases } => {
                    let sel = self.expr(&f.expressions, fr, *selector)?;
                    let hit = |c: &naga::SwitchCase| matches!((c.value, &sel), (SwitchValue::I32(a), V::I(b)) if a == *b)
                        || matches!((c.value, &sel), (SwitchValue::U32(a), V::U(b)) if a == *b);
                    let start = cases.iter().position(hit).or_else(|| cases.iter().position(|c| c.value == SwitchValue::Default))?;
                    let mut flow = Flow::Next;
                    for case in &cases[start..] {
                        flow = self.block(f, fr, &case.body)?;
                        if !matches!(flow, Flow::Next) || !case.fall_through {
                            break;
                        }
                    }
                    if matches!(flow, Flow::Break) { Flow::Next } else { flow }
                }
                S::Loop { body, continuing, break_if } => loop {
                    self.tick()?;
                    match self.block(f, fr, body)? {
                        Flow::Break => break Flow::Next,
                        r @ Flow::Return(_) => break r,
                        Flow::Next | Flow::Continue => {}
                    }
                    match self.block(f, fr, continuing)? {
                        Flow::Break => break Flow::Next,
                        r @ Flow::Return(_) => break r,
                        Flow::Next | Flow::Continue => {}
                    }
                    if let Some(c) = break_if {
                        if self.expr(&f.expressions, fr, *c)?.b()? {
                            break Flow::Next;
                        }
                    }
                },
                S::Break => Flow::Break,
                S::Continue => Flow::Continue,
                S::Return { value: None } => Flow::Return(None),
                S::Return { value: Some(h) } => Flow::Return(Some(self.expr(&f.expressions, fr, *h)?)),
                S::Store { pointer, value } => {
                    let p = self.expr(&f.expressions, fr, *pointer)?;
                    let v = self.expr(&f.expressions, fr, *value)?;
                    *self.place(&p)? = v;
                    Flow::Next
                }
                S::Call { function, arguments, result } => {
                    let args = arguments.iter().map(|&a| self.expr(&f.expressions, fr, a)).collect::<Option<Vec<_>>>()?;
                    let r = self.call(*function, args)?;
                    if let Some(h) = result {
                        fr.cache.set(h.index(), r?);
                    }
                    Flow::Next
                }
                _ => return None,
            };
            if !matches!(flow, Flow::Next) {
                return Some(flow);
            }
        }
        Some(Flow::Next)
    }

    fn tick(&mut self) -> Option<()> {
        self.steps += 1;
        (self.steps <= STEP_BUDGET).then_some(())
    }

    /// The memory a pointer value designates.
    fn place(&mut self, p: &V) -> Option<&mut V> {
        let V::Ptr(slot, path) = p else { return None };
        let mut v = self.mem.get_mut(*slot)?;
        for &i in path {
            v = v.parts_mut()?.get_mut(i)?;
        }
        Some(v)
    }

    /// An expression's value: the one its last `Emit` computed, else computed now (constant
    /// expressions, arguments and local variable pointers are never emitted).
    fn expr(&mut self, ex: &'a Exprs, fr: &mut Frame, h: Handle<naga::Expression>) -> Option<V> {
        if let Some(v) = fr.cache.get(h.index()).ok()? {
            return Some(v.clone());
        }
        let v = self.compute(ex, fr, h)?;
        fr.cache.set(h.index(), v.clone());
        Some(v)
    }

    fn compute(&mut self, ex: &'a Exprs, fr: &mut Frame, h: Handle<naga::Expression>) -> Option<V> {
        macro_rules! ev {
            ($h:expr) => {
                self.expr(ex, fr, $h)?
            };
        }
        let m = self.m;
        Some(match &ex[h] {
            E::Literal(l) => match *l {
                Literal::F32(x) => V::F(x),
                Literal::I32(x) => V::I(x),
                Literal::U32(x) => V::U(x),
                Literal::Bool(x) => V::B(x),
                _ => return None,
            },
            E::Constant(c) => match self.consts.get(c) {
                Some(v) => v.clone(),
                None => {
                    let mut global = Frame { args: Vec::new(), base: 0, cache: ExprCache::Sparse(HashMap::new()) };
                    let v = self.expr(&m.global_expressions, &mut global, m.constants[*c].init)?;
                    self.consts.insert(*c, v.clone());
                    v
                }
            },
            E::ZeroValue(ty) => zero(m, *ty)?,
            E::Compose { ty, components } => {
                let cs = components.iter().map(|&c| self.expr(ex, fr, c)).collect::<Option<Vec<_>>>()?;
                match &m.types[*ty].inner {
                    T::Vector { .. } => V::Vec(cs.into_iter().flat_map(|c| if let V::Vec(x) = c { x } else { vec![c] }).collect()),
                    T::Matrix { rows, .. } if cs.iter().all(V::is_scalar) => {
                        V::Mat(cs.chunks(*rows as usize).map(|c| V::Vec(c.to_vec())).collect())
                    }
                    T::Matrix { .. } => V::Mat(cs),
                    T::Struct { .. } | T::Array { .. } => V::Agg(cs),
                    _ => return None,
                }
            }
            E::Access { base, index } => {
                let i = match ev!(*index) {
                    V::I(i) => usize::try_from(i).ok()?,
                    V::U(u) => u as usize,
                    _ => return None,
                };
                index_into(ev!(*base), i)?
            }
            E::AccessIndex { base, index } => index_into(ev!(*base), *index as usize)?,
            E::Splat { size, value } => {
                let v = ev!(*value);
                v.is_scalar().then(|| V::Vec(vec![v; *size as usize]))?
            }
            E::Swizzle { size, vector, pattern } => {
                let V::Vec(c) = ev!(*vector) else { return None };
                V::Vec(pattern[..*size as usize].iter().map(|&p| c.get(p as usize).cloned()).collect::<Option<_>>()?)
            }
            E::FunctionArgument(i) => fr.args.get(*i as usize)?.clone(),
            E::LocalVariable(lv) => V::Ptr(fr.base + lv.index(), Vec::new()),
            E::Load { pointer } => {
                let p = ev!(*pointer);
                self.place(&p)?.clone()
            }
            E::Unary { op, expr } => unary(*op, &ev!(*expr))?,
            E::Binary { op, left, right } => {
                let (a, b) = (ev!(*left), ev!(*right));
                binary(*op, &a, &b)?
            }
            E::Select { condition, accept, reject } => {
                let (c, a, r) = (ev!(*condition), ev!(*accept), ev!(*reject));
                match c {
                    V::B(b) => if b { a } else { r },
                    V::Vec(_) => zipn(&[c, a, r], &|x| Some(if x[0].b()? { x[1].clone() } else { x[2].clone() }))?,
                    _ => return None,
                }
            }
            E::Relational { fun, argument } => {
                let a = ev!(*argument);
                let all: Vec<V> = a.parts().cloned().unwrap_or_else(|| vec![a.clone()]);
                match fun {
                    R::All => V::B(all.iter().map(V::b).collect::<Option<Vec<_>>>()?.into_iter().all(|b| b)),
                    R::Any => V::B(all.iter().map(V::b).collect::<Option<Vec<_>>>()?.into_iter().any(|b| b)),
                    R::IsNan => zipn(&[a], &|x| Some(V::B(x[0].f()?.is_nan())))?,
                    R::IsInf => zipn(&[a], &|x| Some(V::B(x[0].f()?.is_infinite())))?,
                }
            }
            E::Math { fun, arg, arg1, arg2, arg3 } => {
                let mut args = vec![ev!(*arg)];
                for h in [arg1, arg2, arg3].into_iter().flatten() {
                    args.push(ev!(*h));
                }
                math(*fun, &args)?
            }
            E::As { expr, kind, convert } => cast(&ev!(*expr), *kind, *convert)?,
            // Set by its `Call` statement; reaching here means the call did not run.
            _ => return None,
        })
    }
}

/// Component `i` of a value, or the pointer to component `i` of what a pointer designates.
fn index_into(base: V, i: usize) -> Option<V> {
    match base {
        V::Ptr(slot, mut path) => {
            path.push(i);
            Some(V::Ptr(slot, path))
        }
        V::Vec(mut c) | V::Mat(mut c) | V::Agg(mut c) => (i < c.len()).then(|| c.swap_remove(i)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Const::{Bool, Struct, Vector, F32, I32, U32};

    fn ev(src: &str, f: &str, args: &[Const]) -> Option<Const> {
        ConstEvaluator::new(src).unwrap().eval(f, args)
    }

    fn vf(x: &[f32]) -> Const {
        Vector(x.iter().map(|&v| F32(v)).collect())
    }

    fn library() -> ConstEvaluator {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../mtlx/libraries/stdlib/wgsl");
        let mut paths: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "wgsl")).collect();
        paths.sort();
        let text: String = paths.iter().map(|p| std::fs::read_to_string(p).unwrap() + "\n").collect();
        ConstEvaluator::new(&text).unwrap()
    }

    #[test]
    fn const_eval_arithmetic_and_broadcasting() {
        let src = "fn f(a: f32, b: vec3<f32>) -> vec3<f32> { return b * a + vec3<f32>(1.0, 2.0, 3.0) / 2.0 - 1.0; }
                   const mx_k: f32 = 2.5; const mx_v = vec3(1.0, 2.0, 3.0); const mx_n = 4;
                   fn c(x: f32, i: i32) -> vec3<f32> { return mx_v * mx_k + x * f32(mx_n + i); }
                   fn r(x: f32, y: f32) -> f32 { return x % y; }
                   fn g(x: f32) -> vec4<f32> { return vec4<f32>(round(x), sign(x - x), fract(-x), f32(i32(-x))); }
                   fn s(v: vec4<f32>) -> vec2<f32> { var w = v; w.y = 10.0; w[2] += 1.0; return w.zy + vec2(select(1.0, 2.0, v.x > 0.0)); }";
        assert_eq!(ev(src, "f", &[F32(2.0), vf(&[1.0, 2.0, 3.0])]), Some(vf(&[1.5, 4.0, 6.5])));
        assert_eq!(ev(src, "c", &[F32(0.5), I32(2)]), Some(vf(&[5.5, 8.0, 10.5])));
        assert_eq!(ev(src, "r", &[F32(-7.5), F32(2.0)]), Some(F32(-1.5)));
        assert_eq!(ev(src, "r", &[F32(7.5), F32(-2.0)]), Some(F32(1.5)));
        assert_eq!(ev(src, "g", &[F32(2.5)]), Some(vf(&[2.0, 0.0, 0.5, -2.0])));
        assert_eq!(ev(src, "g", &[F32(3.5)]), Some(vf(&[4.0, 0.0, 0.5, -3.0])));
        assert_eq!(ev(src, "s", &[vf(&[1.0, 2.0, 3.0, 4.0])]), Some(vf(&[6.0, 12.0])));
        assert_eq!(ev(src, "s", &[vf(&[-1.0, 2.0, 3.0, 4.0])]), Some(vf(&[5.0, 11.0])));
    }

    #[test]
    fn const_eval_loops_switch_pointers() {
        let src = "fn sum(n: i32) -> i32 { var s = 0; for (var i = 1; i <= n; i++) { if (i % 3 == 0) { continue; } s += i; } return s; }
                   fn collatz(n0: u32) -> u32 { var n = n0; var k = 0u; loop { if (n == 1u) { break; } n = select(3u * n + 1u, n / 2u, n % 2u == 0u); continuing { k++; } } return k; }
                   fn lp(n: i32) -> i32 { var i = 0; loop { i += 2; continuing { break if i >= n; } } return i; }
                   fn sw(x: i32) -> i32 { var r = 0; switch x { case 0, 1: { r = 10; } case 2: { return 20; } default: { r = -1; } } return r + 1; }
                   fn inc(p: ptr<function, i32>, by: i32) { *p += by; }
                   fn ptrs() -> i32 { var x = 4; inc(&x, 1); inc(&x, 2); var v = vec2<i32>(0, 0); for (var i = 0; i < 2; i++) { v[i] = x + i; } return v.x * 100 + v.y; }";
        for n in [0, 1, 10, 1000] {
            let expect: i32 = (1..=n).filter(|i| i % 3 != 0).sum();
            assert_eq!(ev(src, "sum", &[I32(n)]), Some(I32(expect)));
        }
        assert_eq!(ev(src, "collatz", &[U32(27)]), Some(U32(111)));
        assert_eq!(ev(src, "lp", &[I32(7)]), Some(I32(8)));
        assert_eq!(ev(src, "lp", &[I32(-3)]), Some(I32(2)));
        let sw: Vec<_> = (-1..4).map(|x| ev(src, "sw", &[I32(x)])).collect();
        assert_eq!(sw, [Some(I32(0)), Some(I32(11)), Some(I32(11)), Some(I32(20)), Some(I32(0))]);
        assert_eq!(ev(src, "ptrs", &[]), Some(I32(708)));
    }

    #[test]
    fn const_eval_integers_wrap_and_hash() {
        let src = "fn add(a: i32, b: i32) -> i32 { return a + b; }
                   fn div(a: i32, b: i32) -> vec2<i32> { return vec2<i32>(a / b, a % b); }
                   fn sub(a: u32, b: u32) -> u32 { return a - b; }
                   fn bits(x: i32) -> vec4<u32> { return vec4<u32>(u32(x), bitcast<u32>(f32(x)), countOneBits(u32(x)), u32(x >> 1u)); }
                   fn pcg(v: u32) -> u32 { let state = v * 747796405u + 2891336453u; let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u; return (word >> 22u) ^ word; }
                   fn lead(x: i32) -> vec4<i32> { return vec4<i32>(firstLeadingBit(x), firstTrailingBit(x), countLeadingZeros(x), reverseBits(x)); }
                   fn xs(seed: u32) -> u32 { var x = seed; for (var i = 0; i < 5; i++) { x ^= x << 13u; x ^= x >> 17u; x ^= x << 5u; } return x; }";
        assert_eq!(ev(src, "add", &[I32(i32::MAX), I32(1)]), Some(I32(i32::MIN)));
        assert_eq!(ev(src, "div", &[I32(7), I32(0)]), Some(Vector(vec![I32(7), I32(0)])));
        assert_eq!(ev(src, "div", &[I32(-7), I32(2)]), Some(Vector(vec![I32(-3), I32(-1)])));
        assert_eq!(ev(src, "div", &[I32(i32::MIN), I32(-1)]), Some(Vector(vec![I32(i32::MIN), I32(0)])));
        assert_eq!(ev(src, "sub", &[U32(1), U32(3)]), Some(U32(u32::MAX - 1)));
        assert_eq!(ev(src, "bits", &[I32(-3)]), Some(Vector(vec![U32(-3i32 as u32), U32((-3.0f32).to_bits()), U32(31), U32(-2i32 as u32)])));
        assert_eq!(ev(src, "lead", &[I32(40)]), Some(Vector(vec![I32(5), I32(3), I32(26), I32(40i32.reverse_bits())])));
        assert_eq!(ev(src, "lead", &[I32(-5)]), Some(Vector(vec![I32(2), I32(0), I32(0), I32((-5i32).reverse_bits())])));
        assert_eq!(ev(src, "lead", &[I32(0)]), Some(Vector(vec![I32(-1), I32(-1), I32(32), I32(0)])));
        let pcg = |v: u32| {
            let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
            let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
            (word >> 22) ^ word
        };
        let xs = |mut x: u32| {
            for _ in 0..5 {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
            }
            x
        };
        for v in [0, 1, 12345, u32::MAX] {
            assert_eq!(ev(src, "pcg", &[U32(v)]), Some(U32(pcg(v))));
            assert_eq!(ev(src, "xs", &[U32(v)]), Some(U32(xs(v))));
        }
    }

    #[test]
    fn const_eval_structs_and_matrices() {
        let src = "struct mx_s_outputs { a: f32, b: i32, c: vec2<f32> }
                   fn st(x: f32) -> mx_s_outputs { var s: mx_s_outputs; s.a = x * 2.0; s.b = i32(x); s.c.y = x; return s; }
                   fn mv(m: mat2x2<f32>, v: vec2<f32>) -> vec4<f32> { return vec4<f32>(m * v, v * m); }
                   fn mm(a: mat2x2<f32>, b: mat2x2<f32>) -> mat2x2<f32> { return transpose(a * b) + mat2x2<f32>(1.0, 0.0, 0.0, 1.0) * 2.0; }
                   fn dt(m: mat3x3<f32>) -> f32 { return determinant(m); }";
        let s = ev(src, "st", &[F32(3.5)]).unwrap();
        assert_eq!(s, Struct(vec![F32(7.0), I32(3), vf(&[0.0, 3.5])]));
        assert_eq!(s.field(1), Some(&I32(3)));
        assert_eq!(s.field(3), None);
        let m = |d: &[f32]| Const::Matrix { columns: 2, rows: 2, data: d.to_vec() };
        // Columns (1,2) and (3,4): m*v = 1*(1,2)+1*(3,4) ... with v = (1, 10).
        assert_eq!(ev(src, "mv", &[m(&[1.0, 2.0, 3.0, 4.0]), vf(&[1.0, 10.0])]), Some(vf(&[31.0, 42.0, 21.0, 43.0])));
        // a*b columns: a*(5,6) = (23,34), a*(7,8) = (31,46); transposed: (23,31),(34,46); + 2I.
        assert_eq!(ev(src, "mm", &[m(&[1.0, 2.0, 3.0, 4.0]), m(&[5.0, 6.0, 7.0, 8.0])]), Some(m(&[25.0, 31.0, 34.0, 48.0])));
        let m3 = Const::Matrix { columns: 3, rows: 3, data: vec![2.0, 0.0, 1.0, 1.0, 3.0, 0.0, 0.0, 1.0, 4.0] };
        assert_eq!(ev(src, "dt", &[m3]), Some(F32(25.0)));
    }

    #[test]
    fn const_eval_unsupported_is_none() {
        let src = "var<private> g: f32;
                   fn glob(x: f32) -> f32 { g = x; return g; }
                   fn deriv(x: f32) -> f32 { return dpdx(x); }
                   fn forever(x: i32) -> i32 { var i = x; loop { i += 1; } return i; }
                   fn inv(x: f32) -> f32 { return 1.0 / x; }
                   fn nan(x: f32) -> f32 { return sqrt(x); }
                   fn oob(i: i32) -> f32 { var v = vec3<f32>(1.0); return v[i]; }
                   fn tex(t: texture_2d<f32>) -> vec4<f32> { return textureLoad(t, vec2<i32>(0, 0), 0); }
                   fn noret(x: f32) { }";
        for (f, args) in [("glob", vec![F32(1.0)]), ("deriv", vec![F32(1.0)]), ("forever", vec![I32(0)]), ("inv", vec![F32(0.0)]), ("nan", vec![F32(-1.0)]), ("oob", vec![I32(3)]), ("oob", vec![I32(-1)]), ("tex", vec![]), ("noret", vec![F32(1.0)]), ("missing", vec![])] {
            assert_eq!(ev(src, f, &args), None, "{f}");
        }
        // Wrong arity or argument types.
        assert_eq!(ev(src, "inv", &[]), None);
        assert_eq!(ev(src, "inv", &[I32(1)]), None);
        assert_eq!(ev(src, "inv", &[vf(&[1.0, 2.0])]), None);
        assert_eq!(ev(src, "inv", &[F32(4.0)]), Some(F32(0.25)));
        assert_eq!(ev(src, "oob", &[I32(2)]), Some(F32(1.0)));
    }

    #[test]
    fn const_eval_literal_conversions() {
        let m = Value::Floats((1..=9).map(|x| x as f32).collect());
        let c = Const::from_literal(&DataType::Matrix33, &m).unwrap();
        assert_eq!(c, Const::Matrix { columns: 3, rows: 3, data: (1..=9).map(|x| x as f32).collect() });
        assert_eq!(c.to_literal(&DataType::Matrix33), Some(m));
        assert_eq!(Const::from_literal(&DataType::Color3, &Value::Floats(vec![0.1, 0.2, 0.3])), Some(vf(&[0.1, 0.2, 0.3])));
        assert_eq!(Const::from_literal(&DataType::Color3, &Value::Floats(vec![0.1])), None);
        assert_eq!(Const::from_literal(&DataType::Integer, &Value::Integer(-4)), Some(I32(-4)));
        assert_eq!(Const::from_literal(&DataType::Boolean, &Value::Boolean(true)), Some(Bool(true)));
        assert_eq!(Const::from_literal(&DataType::String, &Value::String("x".into())), None);
        assert_eq!(F32(2.0).to_literal(&DataType::Float), Some(Value::Floats(vec![2.0])));
        assert_eq!(vf(&[1.0, 2.0]).to_literal(&DataType::Vector2), Some(Value::Floats(vec![1.0, 2.0])));
        assert_eq!(vf(&[1.0, 2.0]).to_literal(&DataType::Vector3), None);
        assert_eq!(F32(f32::INFINITY).to_literal(&DataType::Float), None);
        assert_eq!(U32(1).to_literal(&DataType::Integer), None);
    }

    #[test]
    fn const_eval_library_functions() {
        let lib = library();
        let lit = |ty: &str, v: Value| Const::from_literal(&DataType::from_name(ty), &v).unwrap();
        assert_eq!(lib.eval("mx_add_float", &[F32(1.5), F32(2.25)]), Some(F32(3.75)));
        assert_eq!(lib.eval("mx_mix_color3", &[vf(&[1.0, 0.0, 0.5]), vf(&[0.0, 1.0, 0.5]), F32(0.25)]), Some(vf(&[0.25, 0.75, 0.5])));
        assert_eq!(lib.eval("mx_smoothstep_float", &[F32(0.25), F32(0.0), F32(1.0)]), Some(F32(0.15625)));
        assert_eq!(lib.eval("mx_smoothstep_float", &[F32(2.0), F32(0.0), F32(1.0)]), Some(F32(1.0)));
        // Integer texel addressing (periodic = 2, mirror = 3) with negative `%`.
        assert_eq!(lib.eval("mx_image_address", &[I32(-3), I32(5), I32(2)]), Some(I32(2)));
        assert_eq!(lib.eval("mx_image_address", &[I32(-1), I32(5), I32(3)]), Some(I32(0)));
        assert_eq!(lib.eval("mx_image_address", &[I32(7), I32(5), I32(1)]), Some(I32(4)));
        // Translation in the last MaterialX row of a matrix44 moves a point.
        let t = lit("matrix44", Value::Floats(vec![1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 5., 6., 7., 1.]));
        assert_eq!(lib.eval("mx_transformmatrix_vector3M4", &[vf(&[1.0, 2.0, 3.0]), t]), Some(vf(&[6.0, 8.0, 10.0])));
        let m = lit("matrix33", Value::Floats(vec![2., 0., 1., 1., 3., 0., 0., 1., 4.]));
        assert_eq!(lib.eval("mx_determinant_matrix33", std::slice::from_ref(&m)), Some(F32(25.0)));
        let inv = lib.eval("mx_invertmatrix_matrix33", &[m]).unwrap().to_literal(&DataType::Matrix33).unwrap();
        let Value::Floats(inv) = inv else { panic!() };
        let expect = [12., 1., -3., -4., 8., 1., 1., -2., 6.].map(|x: f32| x / 25.0);
        assert!(inv.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-6), "{inv:?}");
        // Texture-taking functions cannot be folded.
        assert_eq!(lib.eval("mx_image_sample", &[vf(&[0.0; 4]), vf(&[0.5, 0.5]), I32(0), I32(0), I32(0)]), None);
    }

    /// Every library function on a few argument sets: no panic, and all but the texture,
    /// geometry and NaN-producing cases fold.
    #[test]
    fn const_eval_library_sweep() {
        let lib = library();
        fn fill(v: &mut V, x: f32, n: &mut f32) {
            match v {
                V::F(f) => { *n += 1.0; *f = x * *n; }
                V::I(i) => *i = x as i32 % 5,
                V::U(u) => *u = x.abs() as u32,
                V::B(b) => *b = x > 0.0,
                _ => v.parts_mut().into_iter().flatten().for_each(|c| fill(c, x, n)),
            }
        }
        let (mut folded, mut total) = (0, 0);
        for (_, f) in lib.module.functions.iter() {
            for x in [0.0, 0.37, -1.25, 3.0, 1e6] {
                let Some(mut args) = f.arguments.iter().map(|a| zero(&lib.module, a.ty)).collect::<Option<Vec<_>>>() else { continue };
                let mut n = 0.0;
                args.iter_mut().for_each(|a| fill(a, x, &mut n));
                let args: Vec<Const> = args.iter().map(|a| a.to_const().unwrap()).collect();
                total += 1;
                folded += usize::from(lib.eval(f.name.as_deref().unwrap(), &args).is_some());
            }
        }
        assert!(total > 1500 && folded * 10 > total * 9, "{folded} of {total} folded");
    }

    #[test]
    fn const_eval_library_noise() {
        let lib = library();
        let hash = |k: &[i32]| {
            let f = ["", "mx_hash_int1", "mx_hash_int2", "mx_hash_int3", "mx_hash_int4"][k.len()];
            match lib.eval(f, &k.iter().map(|&x| I32(x)).collect::<Vec<_>>()) {
                Some(U32(h)) => h,
                r => panic!("{f}: {r:?}"),
            }
        };
        // Check values of NOISE.md.
        assert_eq!(hash(&[0, 0]), 0xdc3d74f9);
        assert_eq!(hash(&[0, 0, 0]), 0x9c6eedfb);
        assert_eq!(hash(&[1, 2, 3]), 0xb8d17a0a);
        assert_eq!(hash(&[1, 2, 3, 0]), 0x129dac66);
        assert_eq!(lib.eval("mx_cellnoise3d_float", &[vf(&[1.5, 2.25, 3.75])]), Some(F32(0xb8d17a0au32 as f32 / u32::MAX as f32)));

        // Perlin 3D from NOISE.md's closed form, on the interpreter's own (checked) hash.
        let perlin = |p: [f32; 3]| {
            let i = p.map(|x| x.floor() as i32);
            let f: Vec<f32> = (0..3).map(|k| p[k] - i[k] as f32).collect();
            let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
            let grad = |h: u32, x: f32, y: f32, z: f32| {
                let h = h & 15;
                let u = if h < 8 { x } else { y };
                let v = if h < 4 { y } else if h == 12 || h == 14 { x } else { z };
                (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
            };
            let c: Vec<f32> = (0..8)
                .map(|k| {
                    let d = [k & 1, (k >> 1) & 1, (k >> 2) & 1];
                    grad(hash(&[i[0] + d[0], i[1] + d[1], i[2] + d[2]]), f[0] - d[0] as f32, f[1] - d[1] as f32, f[2] - d[2] as f32)
                })
                .collect();
            let (s, t, r) = (fade(f[0]), fade(f[1]), fade(f[2]));
            let (s1, t1, r1) = (1.0 - s, 1.0 - t, 1.0 - r);
            0.9820 * (r1 * (t1 * (c[0] * s1 + c[1] * s) + t * (c[2] * s1 + c[3] * s)) + r * (t1 * (c[4] * s1 + c[5] * s) + t * (c[6] * s1 + c[7] * s)))
        };
        let noise = |amp: f32, pivot: f32, p: [f32; 3]| match lib.eval("mx_noise3d_float", &[F32(amp), F32(pivot), vf(&p)]) {
            Some(F32(x)) => x,
            r => panic!("{r:?}"),
        };
        assert_eq!(noise(1.0, 0.0, [2.0, -3.0, 5.0]), 0.0);
        for p in [[0.3, 1.7, -2.2], [-10.25, 0.5, 33.125], [7.9, -0.01, 0.99]] {
            let n = noise(1.0, 0.0, p);
            assert!((n - perlin(p)).abs() < 1e-6 && n.abs() <= 1.0 && n != 0.0, "{p:?}: {n} vs {}", perlin(p));
            assert_eq!(noise(2.0, 0.5, p), n * 2.0 + 0.5);
            // fBm with exact powers of two: the octave sum, bit for bit.
            let fbm = lib.eval("mx_fractal3d_noise_float", &[vf(&p), I32(3), F32(2.0), F32(0.5)]);
            let sum = n + 0.5 * noise(1.0, 0.0, p.map(|x| x * 2.0)) + 0.25 * noise(1.0, 0.0, p.map(|x| x * 4.0));
            assert_eq!(fbm, Some(F32(sum)));
        }
        // A million octaves: the loop stops once every later octave adds exactly 0 (the
        // coordinates are lattice integers from octave 24 on here), so the value is the
        // 64-octave sum, finite, within the step budget.
        let many = lib.eval("mx_fractal3d_noise_float", &[vf(&[0.3, 1.7, -2.2]), I32(1_000_000), F32(2.0), F32(0.5)]);
        assert!(matches!(many, Some(F32(x)) if x.is_finite()), "{many:?}");
        assert_eq!(many, lib.eval("mx_fractal3d_noise_float", &[vf(&[0.3, 1.7, -2.2]), I32(64), F32(2.0), F32(0.5)]));
        // Worley: 27 cells, distances sorted and bounded.
        let w = lib.eval("mx_worley_noise_vec3_3d", &[vf(&[0.3, 1.7, -2.2]), F32(1.0), I32(0), I32(0)]).unwrap();
        let Vector(d) = w else { panic!("{w:?}") };
        let d: Vec<f32> = d.iter().map(|c| if let F32(x) = c { *x } else { panic!() }).collect();
        assert!(d[0] >= 0.0 && d[0] <= d[1] && d[1] <= d[2] && d[2] < 3.0, "{d:?}");
    }
}
