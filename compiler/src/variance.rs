//! Variance analysis of a naga Module (issue 24, the packet writer's first pass): for each
//! function and each signature of argument variances, how every expression, local variable and
//! the result vary across the points of a batch.
//!
//! A value is [`Variance::Uniform`] (one value for the whole batch: literals, constants,
//! tables, a material parameter shared by the batch), [`Variance::PerGroup`] (one value per
//! group of points: material parameters and the view direction, in a BSDF kernel's grouped
//! layout) or [`Variance::PerPoint`] (a light direction, a sample's random numbers, a
//! pattern's geometry). The variances form a chain and combine by `max`: an expression varies
//! like its most varying operand. Control flow adds its own: a store under an `if` whose
//! condition is per point makes the local per point (different lanes keep different values),
//! whatever it stores; a `return` under such control flow makes the result per point; a loop
//! whose exit (a `break`, `continue` or `return` under varying control flow, or `break if`)
//! varies runs its whole body under that variance, since lanes run different numbers of
//! iterations. Locals are solved to a fixed point (a store later in a loop can reach a load
//! earlier in it); callees are analysed per signature of their arguments' variances. The
//! packet writer keeps uniform values and uniform loops scalar, and hoists per-group values
//! out of the inner loop over a group's points.

use naga::{Block, Expression, Function, Handle, Module, Statement};
use std::collections::HashMap;

/// How a value varies across a batch (ordered: a combination is the maximum).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Variance {
    Uniform,
    PerGroup,
    PerPoint,
}

/// An argument's variance: one for the whole value, or one per member of a struct argument (a
/// kernel's inputs struct: material parameters per group, the light direction per point).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ArgumentVariance {
    Whole(Variance),
    Members(Vec<Variance>),
}

impl ArgumentVariance {
    /// The variance of the whole value.
    pub fn whole(&self) -> Variance {
        match self {
            ArgumentVariance::Whole(v) => *v,
            ArgumentVariance::Members(m) => m.iter().copied().max().unwrap_or(Variance::Uniform),
        }
    }

}

/// The analysis of one function for one signature.
#[derive(Clone, Debug)]
pub struct FunctionVariance {
    /// Per expression handle (index order).
    pub expressions: Vec<Variance>,
    /// Per local variable handle.
    pub locals: Vec<Variance>,
    /// The result's (`Uniform` for a function without one).
    pub result: Variance,
    /// Per member, for struct values built in place, passed in or returned (expression index →
    /// member variances): a closure struct keeps `wv` per group and `wl` per point through
    /// the constructors it passes through.
    pub members: HashMap<usize, Vec<Variance>>,
    /// The result's members, when the function returns such struct values.
    pub result_members: Option<Vec<Variance>>,
}

/// `a` raised to `b`, member by member.
fn join_members(a: &mut Vec<Variance>, b: &[Variance]) {
    if a.len() < b.len() {
        a.resize(b.len(), Variance::Uniform);
    }
    for (x, y) in a.iter_mut().zip(b) {
        *x = (*x).max(*y);
    }
}

impl FunctionVariance {
    pub fn expression(&self, h: Handle<Expression>) -> Variance {
        self.expressions[h.index()]
    }
}

/// Analyses of a module's functions, memoised per (function, argument variances).
pub struct ModuleVariance<'m> {
    module: &'m Module,
    cache: HashMap<(Handle<Function>, Vec<ArgumentVariance>), FunctionVariance>,
}

impl<'m> ModuleVariance<'m> {
    pub fn new(module: &'m Module) -> Self {
        ModuleVariance { module, cache: HashMap::new() }
    }

    /// The analysis of `function` called with arguments of these variances.
    pub fn function(&mut self, function: Handle<Function>, arguments: &[Variance]) -> &FunctionVariance {
        let arguments: Vec<ArgumentVariance> = arguments.iter().map(|&v| ArgumentVariance::Whole(v)).collect();
        self.function_with(function, &arguments)
    }

    /// The analysis of `function` with per-member variances for struct arguments.
    pub fn function_with(&mut self, function: Handle<Function>, arguments: &[ArgumentVariance]) -> &FunctionVariance {
        let key = (function, arguments.to_vec());
        if !self.cache.contains_key(&key) {
            let f = &self.module.functions[function];
            let result = self.analyse(f, arguments);
            self.cache.insert(key.clone(), result);
        }
        &self.cache[&key]
    }

    /// Analyses a function body (also entry points' and those not in `module.functions`).
    pub fn analyse(&mut self, f: &Function, arguments: &[ArgumentVariance]) -> FunctionVariance {
        let mut state = FunctionVariance {
            expressions: vec![Variance::Uniform; f.expressions.len()],
            locals: vec![Variance::Uniform; f.local_variables.len()],
            result: Variance::Uniform,
            members: HashMap::new(),
            result_members: None,
        };
        let mut calls: HashMap<Handle<Expression>, (Variance, Option<Vec<Variance>>)> = HashMap::new();
        // Every pass only raises variances, which are bounded: this ends.
        loop {
            let before = (state.expressions.clone(), state.locals.clone(), state.result, state.members.clone(), state.result_members.clone(), calls.clone());
            for (h, e) in f.expressions.iter() {
                let (v, members) = Self::expression(self.module, f, h, e, arguments, &state, &calls);
                state.expressions[h.index()] = state.expressions[h.index()].max(v);
                if let Some(m) = members {
                    join_members(state.members.entry(h.index()).or_default(), &m);
                }
            }
            let mut walk = Walk { analysis: self, f, state: &mut state, calls: &mut calls };
            walk.block(&f.body, Variance::Uniform);
            if before == (state.expressions.clone(), state.locals.clone(), state.result, state.members.clone(), state.result_members.clone(), calls.clone()) {
                return state;
            }
        }
    }

    /// An expression's variance, and its members' for a struct value whose members are known.
    fn expression(
        module: &Module,
        f: &Function,
        h: Handle<Expression>,
        e: &Expression,
        arguments: &[ArgumentVariance],
        state: &FunctionVariance,
        calls: &HashMap<Handle<Expression>, (Variance, Option<Vec<Variance>>)>,
    ) -> (Variance, Option<Vec<Variance>>) {
        let of = |h: &Handle<Expression>| state.expressions[h.index()];
        let max = |hs: &[Handle<Expression>]| hs.iter().map(of).max().unwrap_or(Variance::Uniform);
        match e {
            Expression::Compose { ty, components } if matches!(module.types[*ty].inner, naga::TypeInner::Struct { .. }) => {
                return (max(components), Some(components.iter().map(of).collect()));
            }
            Expression::FunctionArgument(i) => {
                return match arguments.get(*i as usize) {
                    Some(ArgumentVariance::Members(m)) => (ArgumentVariance::Members(m.clone()).whole(), Some(m.clone())),
                    Some(a) => (a.whole(), None),
                    None => (Variance::PerPoint, None),
                };
            }
            Expression::AccessIndex { base, index } => {
                if let Some(m) = state.members.get(&base.index()) {
                    return (m.get(*index as usize).copied().unwrap_or(Variance::PerPoint), None);
                }
            }
            // Set by its `Call` statement (on the previous pass).
            Expression::CallResult(_) => return calls.get(&h).cloned().unwrap_or((Variance::Uniform, None)),
            _ => {}
        }
        let _ = f;
        (match e {
            Expression::Literal(_) | Expression::Constant(_) | Expression::Override(_) | Expression::ZeroValue(_) | Expression::GlobalVariable(_) => Variance::Uniform,
            Expression::LocalVariable(l) => state.locals[l.index()],
            Expression::Compose { components, .. } => max(components),
            Expression::Access { base, index } => of(base).max(of(index)),
            Expression::AccessIndex { base, .. } => of(base),
            Expression::Splat { value, .. } => of(value),
            Expression::Swizzle { vector, .. } => of(vector),
            Expression::Load { pointer } => of(pointer),
            Expression::Unary { expr, .. } => of(expr),
            Expression::Binary { left, right, .. } => of(left).max(of(right)),
            Expression::Select { condition, accept, reject } => max(&[*condition, *accept, *reject]),
            Expression::Relational { argument, .. } => of(argument),
            Expression::Math { arg, arg1, arg2, arg3, .. } => {
                let mut v = of(arg);
                for a in [arg1, arg2, arg3].into_iter().flatten() {
                    v = v.max(of(a));
                }
                v
            }
            Expression::As { expr, .. } => of(expr),
            Expression::ArrayLength(e) => of(e),
            Expression::ImageQuery { image, .. } => of(image),
            Expression::ImageLoad { image, coordinate, array_index, sample, level } => {
                let mut v = of(image).max(of(coordinate));
                for a in [array_index, sample, level].into_iter().flatten() {
                    v = v.max(of(a));
                }
                v
            }
            // Anything else (image sampling, derivatives, atomics, …) is taken as per point.
            _ => Variance::PerPoint,
        }, None)
    }
}

/// One pass over a function's statements under a control variance.
struct Walk<'a, 'm> {
    analysis: &'a mut ModuleVariance<'m>,
    f: &'a Function,
    state: &'a mut FunctionVariance,
    calls: &'a mut HashMap<Handle<Expression>, (Variance, Option<Vec<Variance>>)>,
}

impl Walk<'_, '_> {
    fn of(&self, h: Handle<Expression>) -> Variance {
        self.state.expressions[h.index()]
    }

    /// How a call argument varies: per member for a struct value whose members are known (the
    /// closure struct carrying `wv` and `wl`), else whole.
    fn argument(&self, h: Handle<Expression>) -> ArgumentVariance {
        match self.state.members.get(&h.index()) {
            Some(m) => ArgumentVariance::Members(m.clone()),
            None => ArgumentVariance::Whole(self.of(h)),
        }
    }

    /// The local variable a pointer expression points into, if any.
    fn root_local(&self, mut p: Handle<Expression>) -> Option<usize> {
        loop {
            match &self.f.expressions[p] {
                Expression::LocalVariable(l) => return Some(l.index()),
                Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => p = *base,
                _ => return None,
            }
        }
    }

    fn block(&mut self, block: &Block, control: Variance) {
        for s in block.iter() {
            self.statement(s, control);
        }
    }

    fn statement(&mut self, s: &Statement, control: Variance) {
        match s {
            Statement::Block(b) => self.block(b, control),
            Statement::If { condition, accept, reject } => {
                let c = control.max(self.of(*condition));
                self.block(accept, c);
                self.block(reject, c);
            }
            Statement::Switch { selector, cases } => {
                let c = control.max(self.of(*selector));
                for case in cases {
                    self.block(&case.body, c);
                }
            }
            Statement::Loop { body, continuing, break_if } => {
                let mut exit = break_if.map_or(Variance::Uniform, |b| self.of(b));
                exit = exit.max(self.exits(body, Variance::Uniform, false)).max(self.exits(continuing, Variance::Uniform, false));
                let c = control.max(exit);
                self.block(body, c);
                self.block(continuing, c);
            }
            Statement::Store { pointer, value } => {
                let v = control.max(self.of(*value)).max(self.of(*pointer));
                if let Some(l) = self.root_local(*pointer) {
                    self.state.locals[l] = self.state.locals[l].max(v);
                }
            }
            Statement::Return { value } => {
                let v = control.max(value.map_or(Variance::Uniform, |h| self.of(h)));
                self.state.result = self.state.result.max(v);
                if let Some(m) = value.and_then(|h| self.state.members.get(&h.index()).cloned()) {
                    let m: Vec<Variance> = m.iter().map(|&x| x.max(control)).collect();
                    join_members(self.state.result_members.get_or_insert_with(Vec::new), &m);
                } else if let Some(r) = &self.f.result {
                    // A struct returned whole (a loaded local, a call's result): every member
                    // varies as it does, or member-wise uses of the result would be unsound.
                    if let naga::TypeInner::Struct { members, .. } = &self.analysis.module.types[r.ty].inner {
                        join_members(self.state.result_members.get_or_insert_with(Vec::new), &vec![v; members.len()]);
                    }
                }
            }
            Statement::Call { function, arguments, result } => {
                let args: Vec<ArgumentVariance> = arguments.iter().map(|a| self.argument(*a)).collect();
                let callee = self.analysis.function_with(*function, &args);
                let (r, members) = (callee.result, callee.result_members.clone());
                if let Some(h) = result {
                    let e = self.calls.entry(*h).or_insert((Variance::Uniform, None));
                    e.0 = e.0.max(r);
                    if let Some(m) = members {
                        join_members(e.1.get_or_insert_with(Vec::new), &m);
                    }
                }
            }
            _ => {}
        }
    }

    /// The variance of the control flow under which `block` leaves the enclosing loop early
    /// (`break` and `continue` of this loop, `return`): lanes that leave while others stay
    /// make everything the loop stores vary as that control flow does. `in_switch`: a `break`
    /// here ends a switch, not the loop.
    fn exits(&self, block: &Block, control: Variance, in_switch: bool) -> Variance {
        let mut v = Variance::Uniform;
        for s in block.iter() {
            v = v.max(match s {
                Statement::Break if !in_switch => control,
                Statement::Continue | Statement::Return { .. } => control,
                Statement::Block(b) => self.exits(b, control, in_switch),
                Statement::If { condition, accept, reject } => {
                    let c = control.max(self.of(*condition));
                    self.exits(accept, c, in_switch).max(self.exits(reject, c, in_switch))
                }
                Statement::Switch { selector, cases } => {
                    let c = control.max(self.of(*selector));
                    cases.iter().map(|case| self.exits(&case.body, c, true)).max().unwrap_or(Variance::Uniform)
                }
                // A nested loop's break and continue are its own; its returns leave this one too.
                Statement::Loop { body, continuing, .. } => self.returns(body, control).max(self.returns(continuing, control)),
                _ => Variance::Uniform,
            });
        }
        v
    }

    /// The variance of the control flow under which `block` returns.
    fn returns(&self, block: &Block, control: Variance) -> Variance {
        let mut v = Variance::Uniform;
        for s in block.iter() {
            v = v.max(match s {
                Statement::Return { .. } => control,
                Statement::Block(b) => self.returns(b, control),
                Statement::If { condition, accept, reject } => {
                    let c = control.max(self.of(*condition));
                    self.returns(accept, c).max(self.returns(reject, c))
                }
                Statement::Switch { selector, cases } => {
                    let c = control.max(self.of(*selector));
                    cases.iter().map(|case| self.returns(&case.body, c)).max().unwrap_or(Variance::Uniform)
                }
                Statement::Loop { body, continuing, break_if } => {
                    let c = control.max(break_if.map_or(Variance::Uniform, |b| self.of(b)));
                    self.returns(body, c).max(self.returns(continuing, c))
                }
                _ => Variance::Uniform,
            });
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Variance::{PerGroup, PerPoint, Uniform};

    fn module(src: &str) -> Module {
        naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)))
    }

    fn function(m: &Module, name: &str) -> Handle<Function> {
        m.functions.iter().find(|(_, f)| f.name.as_deref() == Some(name)).unwrap().0
    }

    /// The variance of local `name` in `f`.
    fn local(m: &Module, fv: &FunctionVariance, f: Handle<Function>, name: &str) -> Variance {
        let (h, _) = m.functions[f].local_variables.iter().find(|(_, l)| l.name.as_deref() == Some(name)).unwrap_or_else(|| panic!("no local {name}"));
        fv.locals[h.index()]
    }

    #[test]
    fn a_constant_trip_counter_stays_uniform() {
        let m = module("fn f(x: f32) -> f32 { var acc = x; for (var i = 0; i < 4; i++) { acc += f32(i); } return acc; }");
        let f = function(&m, "f");
        let mut a = ModuleVariance::new(&m);
        let fv = a.function(f, &[PerPoint]).clone();
        assert_eq!(local(&m, &fv, f, "i"), Uniform);
        assert_eq!(local(&m, &fv, f, "acc"), PerPoint);
        assert_eq!(fv.result, PerPoint);
        // With a uniform argument everything is uniform.
        assert_eq!(a.function(f, &[Uniform]).result, Uniform);
    }

    #[test]
    fn a_store_under_a_varying_if_makes_the_local_vary() {
        let m = module("fn f(x: f32, u: f32) -> f32 { var t = 0.0; if (x > 0.0) { t = 1.0; } var s = 0.0; if (u > 0.0) { s = 2.0; } return t + s; }");
        let f = function(&m, "f");
        let mut a = ModuleVariance::new(&m);
        let fv = a.function(f, &[PerPoint, Uniform]).clone();
        assert_eq!(local(&m, &fv, f, "t"), PerPoint, "stored a constant under a per-point condition");
        assert_eq!(local(&m, &fv, f, "s"), Uniform, "stored a constant under a uniform condition");
        let fv = a.function(f, &[PerPoint, PerGroup]).clone();
        assert_eq!(local(&m, &fv, f, "s"), PerGroup);
    }

    #[test]
    fn a_return_under_a_varying_if_makes_the_result_vary() {
        let m = module("fn g(x: f32) -> f32 { if (x > 0.0) { return 1.0; } return 2.0; }");
        let g = function(&m, "g");
        let mut a = ModuleVariance::new(&m);
        assert_eq!(a.function(g, &[PerPoint]).result, PerPoint);
        assert_eq!(a.function(g, &[PerGroup]).result, PerGroup);
        assert_eq!(a.function(g, &[Uniform]).result, Uniform);
    }

    #[test]
    fn a_loop_with_a_varying_exit_runs_its_body_under_that_variance() {
        // `n` counts iterations with a constant step, but lanes leave at different times.
        let m = module(
            "fn f(x: f32) -> i32 { var n = 0; var i = 0; loop { if (f32(i) > x) { break; } n += 2; i++; } return n; }
             fn g(x: f32) -> f32 { var acc = 0.0; for (var i = 0; i < 8; i++) { if (x > f32(i)) { continue; } acc += 1.0; } return acc; }
             fn h(x: f32) -> f32 { var acc = 0.0; for (var i = 0; i < 8; i++) { switch (i) { case 3: { break; } default: { acc += x; } } } return 1.0; }",
        );
        let mut a = ModuleVariance::new(&m);
        let f = function(&m, "f");
        let fv = a.function(f, &[PerPoint]).clone();
        assert_eq!((local(&m, &fv, f, "n"), local(&m, &fv, f, "i")), (PerPoint, PerPoint));
        let g = function(&m, "g");
        let gv = a.function(g, &[PerPoint]).clone();
        assert_eq!(local(&m, &gv, g, "acc"), PerPoint, "a per-point continue");
        // A switch's break on a uniform selector ends the switch, not the loop: `i` stays uniform.
        let h = function(&m, "h");
        let hv = a.function(h, &[PerPoint]).clone();
        assert_eq!((local(&m, &hv, h, "i"), local(&m, &hv, h, "acc"), hv.result), (Uniform, PerPoint, Uniform));
    }

    #[test]
    fn a_call_varies_as_the_callee_does_for_its_arguments() {
        let m = module(
            "fn first(a: f32, b: f32) -> f32 { return a + 1.0; }
             fn caller(u: f32, x: f32) -> f32 { let k = first(u, x); let j = first(x, u); return k; }",
        );
        let mut a = ModuleVariance::new(&m);
        let caller = function(&m, "caller");
        assert_eq!(a.function(caller, &[Uniform, PerPoint]).result, Uniform);
        assert_eq!(a.function(caller, &[PerPoint, Uniform]).result, PerPoint);
        assert_eq!(a.function(caller, &[PerGroup, PerPoint]).result, PerGroup);
    }

    #[test]
    fn a_conductor_kernel_splits_into_view_and_light_work() {
        // The shipped conductor BSDF in the eval context, its material and view per group and
        // its light direction per point: the view-only work (the energy-compensation albedo
        // lookup and its Fresnel average) is per group, the lobe's value per point.
        let graph = concat!(env!("CARGO_MANIFEST_DIR"), "/../runtime/kernels/graphs/bsdf/bsdf_conductor.mtlx");
        let c = crate::Compiler::builtin().compile_file_in(std::path::Path::new(graph), &crate::OutputSelection::AllNumeric, Some(crate::ClosureContext::Eval));
        let kernel = c.kernel.expect("the conductor kernel compiles");
        let m = &kernel.module;
        let pattern = function(m, "mx_pattern");
        let f = &m.functions[pattern];
        let members = |ty: Handle<naga::Type>, point: &[&str]| match &m.types[ty].inner {
            naga::TypeInner::Struct { members, .. } => ArgumentVariance::Members(
                members.iter().map(|x| if point.contains(&x.name.as_deref().unwrap_or("")) { PerPoint } else { PerGroup }).collect(),
            ),
            _ => ArgumentVariance::Whole(PerGroup),
        };
        let args: Vec<ArgumentVariance> = f.arguments.iter().map(|a| members(a.ty, &["wl"])).collect();
        let mut a = ModuleVariance::new(m);
        assert_eq!(a.function_with(pattern, &args).result, PerPoint);
        let by_name = |a: &ModuleVariance, name: &str| -> Vec<Variance> {
            a.cache.iter().filter(|((h, _), _)| m.functions[*h].name.as_deref() == Some(name)).map(|(_, fv)| fv.result).collect()
        };
        // (The memo also holds the signatures of the fixed point's earlier passes, lower ones.)
        let setup = by_name(&a, "mx_ggx_energy_compensation");
        assert!(setup.contains(&PerGroup) && setup.iter().all(|&v| v <= PerGroup), "energy compensation: {setup:?}");
        let reflection = by_name(&a, "mx_ggx_reflection");
        assert!(reflection.contains(&PerPoint), "the lobe: {reflection:?}");
        // With every member per point, nothing is per group.
        let all_point: Vec<ArgumentVariance> = f.arguments.iter().map(|a| members(a.ty, &["wl", "wv", "ior", "extinction", "roughness", "weight", "position", "normal", "tangent", "texcoord"])).collect();
        let mut b = ModuleVariance::new(m);
        b.function_with(pattern, &all_point);
        assert!(by_name(&b, "mx_ggx_energy_compensation").contains(&PerPoint));
    }

    #[test]
    fn a_store_reaching_an_earlier_load_through_the_loop_is_found() {
        // `prev` is read before the store that makes it per point, one iteration later.
        let m = module("fn f(x: f32) -> f32 { var prev = 0.0; var out = 0.0; for (var i = 0; i < 3; i++) { out = prev; prev = x; } return out; }");
        let f = function(&m, "f");
        let mut a = ModuleVariance::new(&m);
        let fv = a.function(f, &[PerPoint]).clone();
        assert_eq!((local(&m, &fv, f, "prev"), local(&m, &fv, f, "out"), fv.result), (PerPoint, PerPoint, PerPoint));
    }
}
