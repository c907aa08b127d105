//! Guarded calls for the packet writer (issue 24): a call whose result feeds only one side of
//! `select`s on one condition — directly or through pure expressions and pure calls — is
//! needed only by the lanes that take that side. WGSL's `select` evaluates both sides, so
//! without this every lane pays for the side it discards: `mx_conductor_fresnel` computes the
//! thin-film Airy reflectance on every lane although the film thickness is 0. The packet
//! writer runs a guarded call only when some active lane takes its side (`if (m & c).any()`),
//! giving the result's zero value otherwise — a value only discarded lanes see.
//!
//! The analysis is exact or silent: a use it does not understand (a statement other than the
//! ones listed, a pointer argument, a condition that cannot be computed at the call) leaves
//! the call unguarded.

use naga::{Expression as E, Function, Handle, Module, Statement, TypeInner};
use std::collections::{HashMap, HashSet};

type H = Handle<E>;

/// The lanes that need a guarded call's result: those where `condition` is `take`.
#[derive(Debug, Clone)]
pub struct Guard {
    pub condition: H,
    pub take: bool,
    /// The expressions bound (emitted, or call results) where the call stands: the condition
    /// is written from these, and from arguments, literals and pure expressions over them.
    pub visible: HashSet<H>,
}

/// Where an expression is used.
#[derive(Clone, Copy)]
enum Use {
    Expression(H),
    /// An argument of a pure call with this result.
    PureCall(H),
    /// Anything else: a store, a return, a branch condition, an impure call.
    Other,
}

/// The operands of an expression (`None`: a kind this analysis does not know).
fn operands(e: &E) -> Option<Vec<H>> {
    Some(match e {
        E::Literal(_) | E::Constant(_) | E::Override(_) | E::ZeroValue(_) | E::FunctionArgument(_) | E::GlobalVariable(_) | E::LocalVariable(_) | E::CallResult(_) => vec![],
        E::Compose { components, .. } => components.clone(),
        E::Access { base, index } => vec![*base, *index],
        E::AccessIndex { base, .. } => vec![*base],
        E::Splat { value, .. } => vec![*value],
        E::Swizzle { vector, .. } => vec![*vector],
        E::Load { pointer } => vec![*pointer],
        E::Unary { expr, .. } => vec![*expr],
        E::Binary { left, right, .. } => vec![*left, *right],
        E::Select { condition, accept, reject } => vec![*condition, *accept, *reject],
        E::Relational { argument, .. } => vec![*argument],
        E::Math { arg, arg1, arg2, arg3, .. } => [Some(*arg), *arg1, *arg2, *arg3].into_iter().flatten().collect(),
        E::As { expr, .. } => vec![*expr],
        E::ArrayLength(e) => vec![*e],
        _ => return None,
    })
}

/// Pure expressions: the same operands give the same value wherever they are evaluated.
fn is_pure(e: &E) -> bool {
    matches!(
        e,
        E::Literal(_) | E::Constant(_) | E::ZeroValue(_) | E::FunctionArgument(_) | E::Compose { .. } | E::Access { .. } | E::AccessIndex { .. } | E::Splat { .. } | E::Swizzle { .. } | E::Unary { .. } | E::Binary { .. } | E::Select { .. } | E::Relational { .. } | E::Math { .. } | E::As { .. }
    )
}

/// A call is pure when no argument is a pointer and its callee, and everything it calls,
/// stores only into its own locals.
pub fn pure_functions(module: &Module) -> HashSet<Handle<Function>> {
    let mut impure: HashSet<Handle<Function>> = HashSet::new();
    // Functions appear after their callees in naga's arena: one pass in order suffices.
    for (h, f) in module.functions.iter() {
        let pointer_arg = f.arguments.iter().any(|a| matches!(module.types[a.ty].inner, TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }));
        if pointer_arg || !block_is_pure(f, &f.body, &impure) {
            impure.insert(h);
        }
    }
    module.functions.iter().map(|(h, _)| h).filter(|h| !impure.contains(h)).collect()
}

fn block_is_pure(f: &Function, block: &naga::Block, impure: &HashSet<Handle<Function>>) -> bool {
    block.iter().all(|s| match s {
        Statement::Emit(_) | Statement::Break | Statement::Continue | Statement::Return { .. } => true,
        Statement::Block(b) => block_is_pure(f, b, impure),
        Statement::If { accept, reject, .. } => block_is_pure(f, accept, impure) && block_is_pure(f, reject, impure),
        Statement::Switch { cases, .. } => cases.iter().all(|c| block_is_pure(f, &c.body, impure)),
        Statement::Loop { body, continuing, .. } => block_is_pure(f, body, impure) && block_is_pure(f, continuing, impure),
        Statement::Store { pointer, .. } => stores_into_local(f, *pointer),
        Statement::Call { function, .. } => !impure.contains(function),
        _ => false,
    })
}

fn stores_into_local(f: &Function, mut p: H) -> bool {
    loop {
        match &f.expressions[p] {
            E::LocalVariable(_) => return true,
            E::Access { base, .. } | E::AccessIndex { base, .. } => p = *base,
            _ => return false,
        }
    }
}

/// Every guarded call of `f`, by its result expression; `pure` is the module's
/// [`pure_functions`] (computed once per module).
pub fn guarded_calls(f: &Function, pure: &HashSet<Handle<Function>>) -> HashMap<H, Guard> {
    let mut uses: HashMap<H, Vec<Use>> = HashMap::new();
    for (h, e) in f.expressions.iter() {
        let Some(ops) = operands(e) else { return HashMap::new() };
        for o in ops {
            uses.entry(o).or_default().push(Use::Expression(h));
        }
    }
    if !statement_uses(&f.body, pure, &mut uses) {
        return HashMap::new();
    }
    let mut finder = Finder { f, uses: &uses, memo: HashMap::new() };
    let mut guards = HashMap::new();
    let mut scopes: Vec<HashSet<H>> = vec![HashSet::new()];
    finder.block(&f.body, &mut scopes, pure, &mut guards);
    guards
}

/// Records the expressions each statement uses; false for a statement this analysis does not know.
fn statement_uses(block: &naga::Block, pure: &HashSet<Handle<Function>>, uses: &mut HashMap<H, Vec<Use>>) -> bool {
    let other = |h: H, uses: &mut HashMap<H, Vec<Use>>| uses.entry(h).or_default().push(Use::Other);
    for s in block.iter() {
        match s {
            Statement::Emit(_) | Statement::Break | Statement::Continue | Statement::Return { value: None } => {}
            Statement::Return { value: Some(v) } => other(*v, uses),
            Statement::Block(b) => {
                if !statement_uses(b, pure, uses) {
                    return false;
                }
            }
            Statement::If { condition, accept, reject } => {
                other(*condition, uses);
                if !statement_uses(accept, pure, uses) || !statement_uses(reject, pure, uses) {
                    return false;
                }
            }
            Statement::Switch { selector, cases } => {
                other(*selector, uses);
                if !cases.iter().all(|c| statement_uses(&c.body, pure, uses)) {
                    return false;
                }
            }
            Statement::Loop { body, continuing, break_if } => {
                if let Some(b) = break_if {
                    other(*b, uses);
                }
                if !statement_uses(body, pure, uses) || !statement_uses(continuing, pure, uses) {
                    return false;
                }
            }
            Statement::Store { pointer, value } => {
                other(*pointer, uses);
                other(*value, uses);
            }
            Statement::Call { function, arguments, result } => {
                for a in arguments {
                    let u = match result {
                        Some(r) if pure.contains(function) => Use::PureCall(*r),
                        _ => Use::Other,
                    };
                    uses.entry(*a).or_default().push(u);
                }
            }
            _ => return false,
        }
    }
    true
}

struct Finder<'a> {
    f: &'a Function,
    uses: &'a HashMap<H, Vec<Use>>,
    memo: HashMap<H, Option<(H, bool)>>,
}

impl Finder<'_> {
    /// The one (condition, side) of `select`s every use of `h` ends in, if there is one.
    fn side(&mut self, h: H) -> Option<(H, bool)> {
        if let Some(m) = self.memo.get(&h) {
            return *m;
        }
        self.memo.insert(h, None);
        let mut found: Option<(H, bool)> = None;
        let mut ok = true;
        for u in self.uses.get(&h).map(Vec::as_slice).unwrap_or(&[]) {
            let this = match *u {
                Use::Expression(e) => match &self.f.expressions[e] {
                    E::Select { condition, accept, reject } if *condition != h && (*accept == h) != (*reject == h) => Some((*condition, *accept == h)),
                    other if is_pure(other) => self.side(e),
                    _ => None,
                },
                Use::PureCall(r) => self.side(r),
                Use::Other => None,
            };
            match (this, found) {
                (None, _) => ok = false,
                (Some(t), None) => found = Some(t),
                (Some(t), Some(f)) if t == f => {}
                _ => ok = false,
            }
            if !ok {
                break;
            }
        }
        let r = if ok { found } else { None };
        self.memo.insert(h, r);
        r
    }

    /// Whether `h` can be written where `visible` are bound.
    fn computable(&self, h: H, visible: &[HashSet<H>]) -> bool {
        if visible.iter().any(|s| s.contains(&h)) {
            return true;
        }
        let e = &self.f.expressions[h];
        is_pure(e) && operands(e).is_some_and(|ops| ops.iter().all(|o| self.computable(*o, visible)))
    }

    fn block(&mut self, block: &naga::Block, scopes: &mut Vec<HashSet<H>>, pure: &HashSet<Handle<Function>>, guards: &mut HashMap<H, Guard>) {
        scopes.push(HashSet::new());
        for s in block.iter() {
            match s {
                Statement::Emit(range) => scopes.last_mut().unwrap().extend(range.clone()),
                Statement::Block(b) => self.block(b, scopes, pure, guards),
                Statement::If { accept, reject, .. } => {
                    self.block(accept, scopes, pure, guards);
                    self.block(reject, scopes, pure, guards);
                }
                Statement::Switch { cases, .. } => cases.iter().for_each(|c| self.block(&c.body, scopes, pure, guards)),
                Statement::Loop { body, continuing, .. } => {
                    self.block(body, scopes, pure, guards);
                    self.block(continuing, scopes, pure, guards);
                }
                Statement::Call { function, result: Some(r), .. } => {
                    if pure.contains(function) {
                        if let Some((condition, take)) = self.side(*r) {
                            if self.computable(condition, scopes) {
                                let visible = scopes.iter().flatten().copied().collect();
                                guards.insert(*r, Guard { condition, take, visible });
                            }
                        }
                    }
                    scopes.last_mut().unwrap().insert(*r);
                }
                _ => {}
            }
        }
        scopes.pop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn guards(src: &str, name: &str) -> (Module, HashMap<H, Guard>) {
        let m = naga::front::wgsl::parse_str(src).unwrap();
        let (_, f) = m.functions.iter().find(|(_, f)| f.name.as_deref() == Some(name)).unwrap();
        let g = guarded_calls(f, &pure_functions(&m));
        (m.clone(), g)
    }

    #[test]
    fn a_call_feeding_one_side_of_a_select_is_guarded_by_its_condition() {
        let (_, g) = guards(
            "fn cheap(x: f32) -> f32 { return x; }
             fn dear(x: f32) -> f32 { var a = x; for (var i = 0; i < 9; i++) { a = sin(a); } return a; }
             fn f(x: f32, t: f32) -> f32 { return select(cheap(x), 2.0 * dear(x), t > 0.0); }",
            "f",
        );
        let takes: Vec<bool> = g.values().map(|g| g.take).collect();
        // `dear` (through `2.0 * …`) is needed where t > 0, `cheap` where it is not.
        assert_eq!(g.len(), 2, "{g:?}");
        assert!(takes.contains(&true) && takes.contains(&false));
    }

    #[test]
    fn a_call_used_elsewhere_too_is_not_guarded() {
        let src = "fn dear(x: f32) -> f32 { return sin(x); }
             fn f(x: f32, t: f32) -> f32 { let d = dear(x); return select(0.0, d, t > 0.0) + d; }
             fn h(x: f32, t: f32) -> f32 { let d = dear(x); return select(0.0, d, t > 0.0) + select(d, 0.0, t > 1.0); }
             fn p(x: ptr<function, f32>) -> f32 { *x = 1.0; return 2.0; }
             fn q(t: f32) -> f32 { var v = 0.0; let d = p(&v); return select(0.0, d, t > 0.0) + v; }";
        for name in ["f", "h", "q"] {
            let (_, g) = guards(src, name);
            assert!(g.is_empty(), "{name}: {g:?}");
        }
    }

    #[test]
    fn a_condition_computed_only_after_the_call_is_not_used() {
        // The condition depends on the call's own result: it cannot guard it.
        let (_, g) = guards("fn dear(x: f32) -> f32 { return sin(x); } fn f(x: f32) -> f32 { let d = dear(x); return select(0.0, d, d > 0.0); }", "f");
        assert!(g.is_empty(), "{g:?}");
    }
}
