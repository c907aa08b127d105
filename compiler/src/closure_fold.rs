//! Specialisation of closures (issue 24, deliverable 3): a lobe whose `weight` input is a
//! compile-time constant at or below 0 (or NaN) becomes the empty BSDF (`mx_bsdf_empty`), and
//! its whole evaluation leaves the kernel; the operators around it (`layer`, `mix`, `add`)
//! then combine with the empty BSDF exactly as they did with the dead lobe.
//!
//! Whether a lobe at weight 0 *is* the empty BSDF is not assumed from its name: the library's
//! own WGSL function is interpreted (`const_eval.rs`) at weight 0 in every closure context, on
//! several draws of its other arguments and of the directions, and its result compared with
//! `mx_bsdf_empty()` (`equivalent`: as every operator and kernel output sees it). A lobe that differs anywhere (a conductor stays opaque at
//! weight 0: its throughput is 0, not 1) or that the interpreter cannot run is not folded. The
//! verdict is memoised per function, in the library it is about.

use crate::const_eval::{Const, ConstEvaluator};
use crate::node_library::NodeLibrary;

/// `MX_CONTEXT_SAMPLE` (closure.wgsl).
const SAMPLE: i32 = 2;

/// Whether BSDF values `a` and `b` (response, throughput, lobe) are the same to every
/// operator and kernel output: response and throughput bit for bit; the lobe's pdf terms
/// (`xy`) outside the sample context (`mx_lobe_combine` drops `zw` there, and the eval and
/// albedo outputs never read the lobe); in the sample context, the lobe itself, or both never
/// chosen (their keys at `MX_LOBE_NEVER`, the empty BSDF's: a choice among lobes none of which
/// can be chosen has pdf 0, whichever direction it carries).
fn equivalent(a: &Const, b: &Const, sample: bool) -> bool {
    let (Const::Struct(a), Const::Struct(b)) = (a, b) else { return false };
    let ([ra, ta, Const::Vector(la)], [rb, tb, Const::Vector(lb)]) = (a.as_slice(), b.as_slice()) else { return false };
    if ra != rb || ta != tb || la.len() != 4 || lb.len() != 4 {
        return false;
    }
    let never = |l: &[Const]| matches!(l[3], Const::F32(w) if w >= 3.0e38);
    match sample {
        true => la == lb || (never(la) && never(lb)),
        false => la[..2] == lb[..2],
    }
}

/// A value of WGSL type `ty` for draw `k` (0, 1, 2), or `None` for a type this check does not
/// make (then the lobe is not folded).
fn sample(ty: &str, k: usize) -> Option<Const> {
    let x = [0.31f32, 0.74, 0.05][k];
    let f = |i: usize| Const::F32((x + 0.17 * i as f32).fract().max(0.02));
    Some(match ty {
        "f32" => f(0),
        "i32" => Const::I32(0),
        "u32" => Const::U32(0),
        "bool" => Const::Bool(k == 1),
        "vec2<f32>" => Const::Vector(vec![f(0), f(1)]),
        "vec3<f32>" => Const::Vector(vec![f(0), f(1), f(2)]),
        "vec4<f32>" => Const::Vector(vec![f(0), f(1), f(2), f(3)]),
        _ => return None,
    })
}

/// A closure struct (`mx_closure`: context, wv, wl, u, lobe_id) for `context` and draw `k`.
fn closure(context: i32, k: usize) -> Const {
    let unit = |v: [f32; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        Const::Vector(v.iter().map(|c| Const::F32(c / n)).collect())
    };
    let (wv, wl) = [([0.3, -0.2, 0.9], [-0.4, 0.1, 0.8]), ([0.0, 0.0, 1.0], [0.6, 0.5, 0.2]), ([-0.7, 0.1, 0.15], [0.2, -0.3, -0.6])][k];
    let u = Const::Vector([0.3f32, 0.6, 0.2].iter().map(|c| Const::F32((c + 0.29 * k as f32).fract())).collect());
    Const::Struct(vec![Const::I32(context), unit(wv), unit(wl), u, Const::U32(k as u32)])
}

/// Whether `library`'s function `function` (parameters `params`: name and WGSL type, the
/// closure struct first, the weight at `weight`) returns the empty BSDF at weight 0 (module
/// doc); `false` where the library has no interpreter.
pub fn vanishes_at_zero_weight(library: &NodeLibrary, function: &str, params: &[(String, String)], weight: usize) -> bool {
    let Some(evaluator) = &library.evaluator else { return false };
    if let Some(&v) = library.zero_weight_verdicts.lock().unwrap().get(function) {
        return v;
    }
    let verdict = check(evaluator, function, params, weight);
    library.zero_weight_verdicts.lock().unwrap().insert(function.to_string(), verdict);
    verdict
}

fn check(evaluator: &ConstEvaluator, function: &str, params: &[(String, String)], weight: usize) -> bool {
    let Some(empty) = evaluator.eval("mx_bsdf_empty", &[]) else { return false };
    if params.first().map(|(_, t)| t.as_str()) != Some("mx_closure") || params.get(weight).map(|(_, t)| t.as_str()) != Some("f32") {
        return false;
    }
    for context in 0..4 {
        for k in 0..3 {
            let mut args = vec![closure(context, k)];
            for (i, (_, ty)) in params.iter().enumerate().skip(1) {
                match (i == weight, sample(ty, k)) {
                    (true, _) => args.push(Const::F32(0.0)),
                    (false, Some(v)) => args.push(v),
                    (false, None) => return false,
                }
            }
            match evaluator.eval(function, &args) {
                Some(r) if equivalent(&r, &empty, context == SAMPLE) => {}
                _ => return false,
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn library() -> crate::Compiler {
        crate::Compiler::builtin()
    }

    fn verdict(c: &crate::Compiler, function: &str) -> bool {
        let sig = c.library.wgsl.items[function].signature.clone().expect("a function");
        let weight = sig.params.iter().position(|(n, _)| n == "weight").expect("a weight parameter");
        check(c.library.evaluator.as_ref().unwrap(), function, &sig.params, weight)
    }

    #[test]
    fn transparent_lobes_vanish_at_weight_zero_and_a_conductor_does_not() {
        let c = library();
        assert!(verdict(&c, "mx_sheen_bsdf"), "sheen at weight 0");
        assert!(verdict(&c, "mx_dielectric_bsdf"), "dielectric at weight 0");
        // A conductor at weight 0 still hides what lies below it (throughput 0).
        assert!(!verdict(&c, "mx_conductor_bsdf"), "conductor at weight 0");
    }
}
