//! Dependence-split packet functions (issue 24, deliverable 2): a kernel function whose result
//! varies per point but much of whose work depends only on its group (a material and a view)
//! is written twice, as a **group pass** and a **point pass**, from the variance analysis of
//! `variance.rs`.
//!
//! The group pass runs once per packet of `S::LANES` groups. It computes every value that the
//! analysis finds per group (or uniform) — table lookups, Fresnel at the view, energy
//! compensation, frames — skipping all per-point work, and stores those the point pass reads
//! into the slots of a tape (`uplift_simd::tape`). The point pass runs over packets of one
//! group's points: it computes the per-point work only, reading each per-group value it needs
//! from the tape as a broadcast of its group's lane. With K points per group, the per-group
//! work costs 1/K of what it cost per point.
//!
//! How each construct splits (a function that is not split runs whole in the point pass, and,
//! where the group pass needs members of its struct result, in the group pass with its
//! per-point arguments zero):
//! - an expression: per group → group pass (and a tape slot when the point pass uses it;
//!   arguments and their members are passed to both passes and not taped); per point → point
//!   pass. In the group pass a per-point operand of a struct value (a closure's light
//!   direction) is zero: by the analysis no per-group value depends on it;
//! - a store: into a per-group local → group pass; a per-point local → point pass;
//! - an `if`/`switch` on a per-group condition: both passes (the point pass reads the
//!   condition from the tape, and skips one without per-point work); on a per-point condition,
//!   and a loop with per-point work: a *per-point region*, written whole by the point pass,
//!   skipped by the group pass. A region that reads or writes a per-group local makes the
//!   function unsplittable (the group pass does not keep the point pass's locals);
//! - a call with a per-group result → group pass (its result taped); with a per-point result →
//!   the callee's own split passes, each call site with its own range of slots;
//! - a `return`: both passes (the group pass returns the per-group members of the result).
//!
//! Slots are numbered statically (expressions, then callees' ranges), so that a side of a
//! per-group `if` skipped by one pass is skipped by the other for the same group: a slot is
//! read only by the points of groups whose pass wrote it.

use crate::backend_packet::{ty_of_handle, unsupported, write_function_with, FunctionWriter, PacketError, Ty};
use crate::variance::{ArgumentVariance, FunctionVariance, ModuleVariance, Variance};
use naga::proc::NameKey;
use naga::{Expression as E, Function, Handle, Module, ScalarKind, Statement, TypeInner};
use std::collections::{BTreeMap, HashMap, HashSet};

type H = Handle<E>;
type R<T> = Result<T, PacketError>;

/// Which pass of a split function is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pass {
    Group,
    Point,
}

/// A split call site: the callee's passes and its first slot in the caller's range.
#[derive(Clone, Debug)]
struct CallSite {
    group: String,
    point: String,
    base: usize,
}

/// One pass of a split function being written.
pub(crate) struct SplitState {
    pub(crate) pass: Pass,
    /// The pass's function name.
    pub(crate) name: String,
    fv: FunctionVariance,
    /// The first point pass: records what the point pass reads; slots are not known yet.
    recording: bool,
    /// Per-group expressions the point pass reads, with their slot counts (recorded).
    referenced: BTreeMap<H, usize>,
    /// Calls with a per-point result, as met: (result, callee, argument variances) (recorded).
    pending: Vec<(H, Handle<Function>, Vec<ArgumentVariance>)>,
    /// Taped expressions' first slots.
    slots: HashMap<H, usize>,
    /// Call sites by result: the callee's passes, or `None` where it runs whole.
    sites: HashMap<H, Option<CallSite>>,
    /// Depth of per-point regions being written (point pass).
    pub(crate) region: usize,
    /// Expressions bound inside the regions being written (not taped).
    region_defined: HashSet<H>,
    /// Why the function cannot be split, when writing found out.
    invalid: Option<String>,
    /// Slots of the function's range, its callees' included (known after the first pass).
    total: usize,
}

impl SplitState {
    fn new(pass: Pass, name: String, fv: FunctionVariance) -> Self {
        SplitState { pass, name, fv, recording: false, referenced: BTreeMap::new(), pending: Vec::new(), slots: HashMap::new(), sites: HashMap::new(), region: 0, region_defined: HashSet::new(), invalid: None, total: 0 }
    }

    /// The pass's extra parameter: the tape it writes or reads.
    pub(crate) fn tape_parameter(&self) -> &'static str {
        match self.pass {
            Pass::Group => "tg: &mut [f32]",
            Pass::Point => "tp: uplift_simd::tape::TapeRow<'_>",
        }
    }

    /// A line opening the pass's body: the point pass checks its tape row's length once.
    pub(crate) fn entry_line(&self) -> Option<String> {
        match (self.pass, self.recording) {
            (Pass::Point, false) => Some(format!("    let tp = tp.fit::<S>({});\n", self.total)),
            // The group pass's stores need no bounds check of their own either.
            (Pass::Group, _) => Some(format!("    assert!(tg.len() >= {} * S::LANES, \"the tape is shorter than the pass's slots\");\n", self.total)),
            _ => None,
        }
    }

    fn group_level(&self, h: H) -> bool {
        self.fv.expressions[h.index()] <= Variance::PerGroup
    }

    fn local_group_level(&self, l: Handle<naga::LocalVariable>) -> bool {
        self.fv.locals[l.index()] <= Variance::PerGroup
    }
}

/// Slots a value of type `t` takes.
fn slot_count(module: &Module, t: Ty) -> R<usize> {
    Ok(match t {
        Ty::Scalar(_) => 1,
        Ty::Vec(n) => n,
        Ty::Struct(th) => {
            let TypeInner::Struct { members, .. } = &module.types[th].inner else { return Err(unsupported("a struct type that is none")) };
            let mut n = 0;
            for m in members {
                n += slot_count(module, ty_of_handle(module, m.ty)?)?;
            }
            n
        }
    })
}

impl FunctionWriter<'_> {
    fn sp(&self) -> &SplitState {
        self.split.as_ref().expect("writing a split pass")
    }

    fn sp_mut(&mut self) -> &mut SplitState {
        self.split.as_mut().expect("writing a split pass")
    }

    /// Arguments, their members and components, and values computed from literals only
    /// (which the Rust compiler folds): both passes compute them in place, untaped.
    fn cheap(&self, h: H) -> bool {
        match &self.f.expressions[h] {
            E::FunctionArgument(_) => true,
            E::AccessIndex { base, .. } => self.cheap(*base),
            E::Swizzle { vector, .. } => self.cheap(*vector),
            E::Splat { value, .. } => self.cheap(*value),
            E::Compose { components, .. } => components.iter().all(|c| self.cheap(*c)),
            _ => self.constant_like(h),
        }
    }

    /// Computed from literals and constants only.
    fn constant_like(&self, h: H) -> bool {
        match &self.f.expressions[h] {
            E::Literal(_) | E::Constant(_) | E::ZeroValue(_) => true,
            E::AccessIndex { base, .. } => self.constant_like(*base),
            E::Swizzle { vector, .. } => self.constant_like(*vector),
            E::Splat { value, .. } => self.constant_like(*value),
            E::Compose { components, .. } => components.iter().all(|c| self.constant_like(*c)),
            E::Unary { expr, .. } | E::As { expr, .. } => self.constant_like(*expr),
            E::Binary { left, right, .. } => self.constant_like(*left) && self.constant_like(*right),
            E::Select { condition, accept, reject } => [condition, accept, reject].iter().all(|c| self.constant_like(**c)),
            E::Math { arg, arg1, arg2, arg3, .. } => [Some(arg), arg1.as_ref(), arg2.as_ref(), arg3.as_ref()].into_iter().flatten().all(|c| self.constant_like(*c)),
            _ => false,
        }
    }

    /// Whether the group pass binds `h`: per-group values, and struct values (whose per-point
    /// members it leaves zero) except loads of per-point locals.
    fn group_binds(&self, h: H) -> R<bool> {
        if self.sp().group_level(h) {
            return Ok(true);
        }
        Ok(matches!(self.ty(h)?, Ty::Struct(_)) && !matches!(self.f.expressions[h], E::Load { .. } | E::CallResult(_)))
    }

    /// How a split pass refers to `h` where it differs from the unsplit writer (`None`: as
    /// that writer does).
    pub(crate) fn split_reference(&mut self, h: H) -> R<Option<String>> {
        if matches!(self.f.expressions[h], E::Literal(_) | E::Constant(_) | E::ZeroValue(_) | E::FunctionArgument(_) | E::LocalVariable(_)) {
            return Ok(None);
        }
        match self.sp().pass {
            Pass::Group => {
                let bound = match self.f.expressions[h] {
                    E::CallResult(_) => self.calls.contains_key(&h),
                    _ => self.group_binds(h)?,
                };
                if bound {
                    Ok(None)
                } else {
                    Ok(Some(self.zero(self.ty(h)?)))
                }
            }
            Pass::Point => {
                let sp = self.sp();
                if (sp.region > 0 && sp.region_defined.contains(&h)) || !sp.group_level(h) || self.cheap(h) {
                    return Ok(None);
                }
                if self.sp().recording {
                    let n = slot_count(self.module, self.ty(h)?)?;
                    self.sp_mut().referenced.insert(h, n);
                } else if !self.sp().slots.contains_key(&h) {
                    return Err(unsupported("a per-group value that the first pass did not see"));
                }
                Ok(Some(format!("_e{}", h.index())))
            }
        }
    }

    /// The statements storing `value` (type `t`) into slots `k..` of the group pass's tape.
    fn tape_put(&self, t: Ty, value: &str, k: usize, out: &mut Vec<String>) -> R<()> {
        match t {
            Ty::Scalar(kind) => {
                let f = match kind {
                    ScalarKind::Float => "put",
                    ScalarKind::Sint => "put_i",
                    ScalarKind::Uint => "put_u",
                    _ => "put_m",
                };
                out.push(format!("uplift_simd::tape::{f}(s, tg, {k}, {value});"));
            }
            Ty::Vec(n) => (0..n).for_each(|c| out.push(format!("uplift_simd::tape::put(s, tg, {}, {value}[{c}]);", k + c))),
            Ty::Struct(th) => {
                let TypeInner::Struct { members, .. } = &self.module.types[th].inner else { return Err(unsupported("a struct type that is none")) };
                let mut at = k;
                for (i, m) in members.iter().enumerate() {
                    let mt = ty_of_handle(self.module, m.ty)?;
                    self.tape_put(mt, &format!("{value}.{}", self.names[&NameKey::StructMember(th, i as u32)]), at, out)?;
                    at += slot_count(self.module, mt)?;
                }
            }
        }
        Ok(())
    }

    /// A value of type `t` read from slots `k..` of the point pass's tape row.
    fn tape_read(&self, t: Ty, k: usize) -> R<String> {
        Ok(match t {
            Ty::Scalar(ScalarKind::Float) => format!("tp.f(s, {k})"),
            Ty::Scalar(ScalarKind::Sint) => format!("tp.i(s, {k})"),
            Ty::Scalar(ScalarKind::Uint) => format!("tp.u(s, {k})"),
            Ty::Scalar(_) => format!("tp.m(s, {k})"),
            Ty::Vec(n) => format!("[{}]", (0..n).map(|c| format!("tp.f(s, {})", k + c)).collect::<Vec<_>>().join(", ")),
            Ty::Struct(th) => {
                let TypeInner::Struct { members, .. } = &self.module.types[th].inner else { return Err(unsupported("a struct type that is none")) };
                let mut at = k;
                let mut fields = Vec::new();
                for (i, m) in members.iter().enumerate() {
                    let mt = ty_of_handle(self.module, m.ty)?;
                    fields.push(format!("{}: {}", self.names[&NameKey::StructMember(th, i as u32)], self.tape_read(mt, at)?));
                    at += slot_count(self.module, mt)?;
                }
                format!("{} {{ {} }}", self.names[&NameKey::Type(th)], fields.join(", "))
            }
        })
    }

    /// Stores `_e<h>` into its slots, if it has any (group pass).
    fn put_if_taped(&mut self, h: H) -> R<()> {
        if let Some(&k) = self.sp().slots.get(&h) {
            let mut lines = Vec::new();
            self.tape_put(self.ty(h)?, &format!("_e{}", h.index()), k, &mut lines)?;
            for l in lines {
                self.line(&l);
            }
        }
        Ok(())
    }

    /// The local a pointer points into.
    fn root_local(&self, mut p: H) -> Option<Handle<naga::LocalVariable>> {
        loop {
            match &self.f.expressions[p] {
                E::LocalVariable(l) => return Some(*l),
                E::Access { base, .. } | E::AccessIndex { base, .. } => p = *base,
                _ => return None,
            }
        }
    }

    /// Whether `block` holds work of the point pass.
    fn point_work(&self, block: &naga::Block) -> R<bool> {
        for s in block.iter() {
            let work = match s {
                Statement::Emit(range) => {
                    let mut any = false;
                    for h in range.clone() {
                        if !matches!(self.resolve(h)?, TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }) && !self.sp().group_level(h) {
                            any = true;
                        }
                    }
                    any
                }
                Statement::Block(b) => self.point_work(b)?,
                Statement::Store { pointer, .. } => self.root_local(*pointer).is_none_or(|l| !self.sp().local_group_level(l)),
                Statement::Call { result, .. } => result.is_none_or(|r| !self.sp().group_level(r)),
                Statement::Return { .. } => true,
                Statement::If { accept, reject, .. } => self.point_work(accept)? || self.point_work(reject)?,
                Statement::Switch { cases, .. } => {
                    let mut any = false;
                    for c in cases {
                        any |= self.point_work(&c.body)?;
                    }
                    any
                }
                Statement::Loop { body, continuing, .. } => self.point_work(body)? || self.point_work(continuing)?,
                Statement::Break | Statement::Continue => false,
                _ => true,
            };
            if work {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The expressions bound inside `block`, and whether it touches a per-group local.
    fn region_contents(&self, block: &naga::Block, out: &mut HashSet<H>) -> bool {
        let mut touches = false;
        for s in block.iter() {
            match s {
                Statement::Emit(range) => {
                    for h in range.clone() {
                        out.insert(h);
                        if let E::Load { pointer } = self.f.expressions[h] {
                            touches |= self.root_local(pointer).is_some_and(|l| self.sp().local_group_level(l));
                        }
                    }
                }
                Statement::Block(b) => touches |= self.region_contents(b, out),
                Statement::Store { pointer, .. } => touches |= self.root_local(*pointer).is_some_and(|l| self.sp().local_group_level(l)),
                Statement::Call { result, .. } => {
                    out.extend(*result);
                }
                Statement::If { accept, reject, .. } => {
                    touches |= self.region_contents(accept, out);
                    touches |= self.region_contents(reject, out);
                }
                Statement::Switch { cases, .. } => cases.iter().for_each(|c| touches |= self.region_contents(&c.body, out)),
                Statement::Loop { body, continuing, .. } => {
                    touches |= self.region_contents(body, out);
                    touches |= self.region_contents(continuing, out);
                }
                _ => {}
            }
        }
        touches
    }

    /// A per-point region (a statement under per-point control, or a loop with per-point
    /// work): written whole by the point pass, skipped by the group pass.
    fn split_region(&mut self, s: &Statement) -> R<()> {
        if self.sp().pass == Pass::Group {
            return Ok(());
        }
        let mut inside = HashSet::new();
        let block = naga::Block::from_vec(vec![s.clone()]);
        if self.region_contents(&block, &mut inside) {
            self.sp_mut().invalid = Some("a per-point region that reads or writes a per-group local".into());
        }
        self.sp_mut().region += 1;
        self.sp_mut().region_defined.extend(inside);
        let r = self.plain_statement(s);
        self.sp_mut().region -= 1;
        r
    }

    /// Whether a guarded call's guard may run in the group pass (its condition is per group).
    fn group_guard(&self, r: H) -> bool {
        self.guards.get(&r).is_none_or(|g| self.sp().group_level(g.condition))
    }

    /// One statement of a split pass, outside per-point regions (module doc).
    pub(crate) fn split_statement(&mut self, s: &Statement) -> R<()> {
        let pass = self.sp().pass;
        match s {
            Statement::Emit(range) => {
                for h in range.clone() {
                    if matches!(self.resolve(h)?, TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. }) {
                        continue;
                    }
                    match pass {
                        Pass::Group => {
                            if self.group_binds(h)? {
                                let e = self.expr_inline(h)?;
                                self.line(&format!("let _e{} = {e};", h.index()));
                                self.put_if_taped(h)?;
                            }
                        }
                        Pass::Point => {
                            if !self.sp().group_level(h) || self.cheap(h) {
                                let e = self.expr_inline(h)?;
                                self.line(&format!("let _e{} = {e};", h.index()));
                            } else if let Some(&k) = self.sp().slots.get(&h) {
                                let read = self.tape_read(self.ty(h)?, k)?;
                                self.line(&format!("let _e{} = {read};", h.index()));
                            }
                        }
                    }
                }
                Ok(())
            }
            Statement::Block(b) => {
                for st in b.iter() {
                    self.statement(st)?;
                }
                Ok(())
            }
            Statement::Store { pointer, .. } => {
                let group_local = self.root_local(*pointer).is_some_and(|l| self.sp().local_group_level(l));
                if group_local == (pass == Pass::Group) {
                    self.plain_statement(s)?;
                }
                Ok(())
            }
            Statement::If { condition: c, accept, reject } => self.split_branch(s, *c, &[accept, reject]),
            Statement::Switch { selector, cases } => {
                let bodies: Vec<&naga::Block> = cases.iter().map(|c| &c.body).collect();
                self.split_branch(s, *selector, &bodies)
            }
            Statement::Loop { body, continuing, .. } => {
                if self.point_work(body)? || self.point_work(continuing)? {
                    self.split_region(s)
                } else if pass == Pass::Group {
                    self.plain_statement(s)
                } else {
                    Ok(())
                }
            }
            Statement::Call { function, arguments, result } => self.split_call(*function, arguments, *result),
            _ => self.plain_statement(s),
        }
    }

    /// An `if` or `switch` on `condition` with these bodies.
    fn split_branch(&mut self, s: &Statement, condition: H, bodies: &[&naga::Block]) -> R<()> {
        if !self.sp().group_level(condition) {
            return self.split_region(s);
        }
        if self.sp().pass == Pass::Point {
            let mut work = false;
            for b in bodies {
                work |= self.point_work(b)?;
            }
            if !work {
                return Ok(());
            }
        }
        self.plain_statement(s)
    }

    /// A call statement of a split pass.
    fn split_call(&mut self, function: Handle<Function>, arguments: &[H], result: Option<H>) -> R<()> {
        let pass = self.sp().pass;
        let plain = self.names[&NameKey::Function(function)].clone();
        let Some(r) = result else {
            if pass == Pass::Point {
                self.write_call(function, &plain, arguments, None, None, true)?;
            }
            return Ok(());
        };
        if self.sp().group_level(r) {
            match pass {
                Pass::Group => {
                    let guarded = self.group_guard(r);
                    self.write_call(function, &plain, arguments, Some(r), None, guarded)?;
                    self.put_if_taped(r)?;
                }
                Pass::Point => {
                    if self.sp().recording || self.sp().slots.contains_key(&r) {
                        let name = format!("_e{}", r.index());
                        if let Some(&k) = self.sp().slots.get(&r) {
                            let read = self.tape_read(self.ty(r)?, k)?;
                            self.line(&format!("let {name} = {read};"));
                        }
                        self.calls.insert(r, name);
                    }
                }
            }
            return Ok(());
        }
        if self.sp().recording {
            let args: Vec<ArgumentVariance> = arguments
                .iter()
                .map(|a| match self.sp().fv.members.get(&a.index()) {
                    Some(m) => ArgumentVariance::Members(m.clone()),
                    None => ArgumentVariance::Whole(self.sp().fv.expressions[a.index()]),
                })
                .collect();
            self.sp_mut().pending.push((r, function, args));
        }
        let site = self.sp().sites.get(&r).cloned().flatten();
        match (pass, site) {
            (Pass::Point, Some(cs)) => self.write_call(function, &cs.point, arguments, Some(r), Some(format!("tp.at::<S>({})", cs.base)), true),
            (Pass::Point, None) => self.write_call(function, &plain, arguments, Some(r), None, true),
            (Pass::Group, Some(cs)) => {
                let guarded = self.group_guard(r);
                self.write_call(function, &cs.group, arguments, Some(r), Some(format!("&mut tg[{} * S::LANES..]", cs.base)), guarded)
            }
            (Pass::Group, None) => {
                // Run whole for the per-group members of its result, if the group pass may
                // read them (a struct); per-point arguments are zero.
                if matches!(self.ty(r)?, Ty::Struct(_)) {
                    let guarded = self.group_guard(r);
                    self.write_call(function, &plain, arguments, Some(r), None, guarded)?;
                }
                Ok(())
            }
        }
    }
}

/// A split function's two passes.
#[derive(Clone, Debug)]
pub struct SplitInstance {
    /// The group pass: the function's arguments (per-point ones zero), then the tape it
    /// writes (`&mut [f32]`, `slots · S::LANES` long); returns the result's per-group members.
    pub group: String,
    /// The point pass: the function's arguments, then its group's `TapeRow`.
    pub point: String,
    /// Slots per group, the callees' included.
    pub slots: usize,
}

/// Writes the split passes of functions, callees first, memoised per argument variances.
pub(crate) struct Splitter<'m> {
    module: &'m Module,
    names: &'m naga::FastHashMap<NameKey, String>,
    outlined: &'m HashSet<Handle<Function>>,
    pure: &'m HashSet<Handle<Function>>,
    variance: ModuleVariance<'m>,
    memo: HashMap<(Handle<Function>, Vec<ArgumentVariance>), Option<SplitInstance>>,
    count: usize,
    /// The passes written so far.
    pub(crate) text: String,
    /// Functions that could not be split, with the reason (for tests and the note).
    pub(crate) refused: Vec<(String, String)>,
}

impl<'m> Splitter<'m> {
    pub(crate) fn new(module: &'m Module, names: &'m naga::FastHashMap<NameKey, String>, outlined: &'m HashSet<Handle<Function>>, pure: &'m HashSet<Handle<Function>>) -> Self {
        Splitter { module, names, outlined, pure, variance: ModuleVariance::new(module), memo: HashMap::new(), count: 0, text: String::new(), refused: Vec::new() }
    }

    /// The split passes of `function` called with arguments of these variances (written on
    /// first use); `None` when its result is per group (it is not split: the group pass runs
    /// it whole) or it cannot be split.
    pub(crate) fn instance(&mut self, function: Handle<Function>, args: Vec<ArgumentVariance>) -> Option<SplitInstance> {
        let key = (function, args.clone());
        if let Some(i) = self.memo.get(&key) {
            return i.clone();
        }
        let fv = self.variance.function_with(function, &args).clone();
        let result = if fv.result <= Variance::PerGroup {
            None
        } else {
            match self.write(function, fv) {
                Ok(i) => Some(i),
                Err(e) => {
                    let name = self.module.functions[function].name.clone().unwrap_or_default();
                    self.refused.push((name, e.construct));
                    None
                }
            }
        };
        self.memo.insert(key, result.clone());
        result
    }

    fn write(&mut self, function: Handle<Function>, fv: FunctionVariance) -> R<SplitInstance> {
        let base = &self.names[&NameKey::Function(function)];
        let base = base.clone();
        let point_first = format!("{base}_p");
        let f = &self.module.functions[function];
        let pass = |w: &mut Self, state: SplitState| write_function_with(w.module, w.names, function, f, w.outlined, w.pure, Some(state));
        // First point pass: what it reads, and whom it calls.
        let mut first = SplitState::new(Pass::Point, point_first, fv.clone());
        first.recording = true;
        let (_, first) = pass(self, first)?;
        let first = first.expect("the split state comes back");
        if let Some(why) = first.invalid {
            return Err(unsupported(why));
        }
        let mut slots = HashMap::new();
        let mut next = 0;
        for (h, n) in &first.referenced {
            slots.insert(*h, next);
            next += n;
        }
        let mut sites = HashMap::new();
        for (r, callee, args) in first.pending {
            let site = self.instance(callee, args).map(|i| {
                let cs = CallSite { group: i.group, point: i.point, base: next };
                next += i.slots;
                cs
            });
            sites.insert(r, site);
        }
        if next == 0 {
            // Nothing per group to hand over: the point pass runs it whole, cheaper than a
            // group pass that computes nothing it keeps.
            return Err(unsupported("a function without per-group work (run whole)"));
        }
        self.count += 1;
        let (group, point) = (format!("{base}_g{}", self.count), format!("{base}_p{}", self.count));
        let mut out = String::new();
        for p in [Pass::Point, Pass::Group] {
            let mut state = SplitState::new(p, if p == Pass::Point { point.clone() } else { group.clone() }, fv.clone());
            state.slots = slots.clone();
            state.sites = sites.clone();
            state.total = next;
            let (text, _) = pass(self, state)?;
            out += "\n";
            out += &text;
        }
        self.text += &out;
        Ok(SplitInstance { group, point, slots: next })
    }
}

/// The split passes of `entry` (a kernel's `mx_pattern`) with its struct arguments' members
/// named in `point_members` per point and every other member, and every other argument, per
/// group; the text of every pass written (callees included) and the entry's passes, `None`
/// when it does not split (its result is per group, or a construct prevents it: the reasons
/// are in the third value).
pub(crate) fn split_entry(module: &Module, names: &naga::FastHashMap<NameKey, String>, outlined: &HashSet<Handle<Function>>, pure: &HashSet<Handle<Function>>, entry: Handle<Function>, point_members: &[&str]) -> (String, Option<SplitInstance>, Vec<(String, String)>) {
    let args: Vec<ArgumentVariance> = module.functions[entry]
        .arguments
        .iter()
        .map(|a| match &module.types[a.ty].inner {
            TypeInner::Struct { members, .. } => ArgumentVariance::Members(members.iter().map(|m| if point_members.contains(&m.name.as_deref().unwrap_or("")) { Variance::PerPoint } else { Variance::PerGroup }).collect()),
            _ => ArgumentVariance::Whole(Variance::PerGroup),
        })
        .collect();
    let mut splitter = Splitter::new(module, names, outlined, pure);
    let instance = splitter.instance(entry, args);
    (splitter.text, instance, splitter.refused)
}
