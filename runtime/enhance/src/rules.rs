//! The six uplift rules (`mtlx/rules/`, embedded in the binary): which enhancement Type each
//! is, their interface as `uplift enhance` reads it (PBR inputs, per-material random scalars
//! with their ranges and distributions, mask files), and the seeded draws of those scalars.
//!
//! A rule document holds one nodegraph, `uplift_rule`. Its interface inputs are
//! * the PBR inputs [`PBR_INPUTS`] (no `uimin`/`uimax`);
//! * random scalars: every float input with `uimin` and `uimax`, drawn uniformly in that range
//!   unless `uplift_distribution` says `normal(MEAN, SD)` (truncated to the range) or
//!   `optional(P)` (0 with probability 1 − P, else uniform in the range);
//! * mask files: `filename` inputs whose value is `masks/<kind>.png` ([`MaskKind::file_stem`]).
//!
//! Draws are counter-based: the value of an input depends only on the seed and the input's
//! name, never on the order of the inputs or on which other inputs exist.

use crate::masks::MaskKind;
pub use uplift_base::random_scalar::{parse_distribution, uniform, Distribution, RandomScalar};
use mtlx::Document;
use std::sync::Arc;
use uplift_engines::stack::Stack;

/// The interface inputs every rule has that come from the PBR material, with their types.
pub const PBR_INPUTS: [(&str, &str); 5] =
    [("base_color", "color3"), ("roughness", "float"), ("metalness", "float"), ("normal_map", "vector3"), ("object_size", "float")];

/// The rule's nodegraph name.
pub const RULE_GRAPH: &str = "uplift_rule";

/// An enhancement Type (paper §3.1; lobes.md §3.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EnhancementType(u8);

/// (file name, proportion in the paper's dataset, dielectric materials only) per Type.
const TYPES: [(&str, f64, bool); 6] = [
    ("type0_haze.mtlx", 0.10, false),
    ("type1_dust.mtlx", 0.20, false),
    ("type2_clearcoat.mtlx", 0.20, false),
    ("type3_dust_clearcoat.mtlx", 0.20, false),
    ("type4_fuzz_scatter.mtlx", 0.10, true),
    ("type5_fuzz_clearcoat_scatter.mtlx", 0.20, true),
];

/// The rule documents, in Type order.
const RULE_TEXTS: [&str; 6] = [
    include_str!("../../../mtlx/rules/type0_haze.mtlx"),
    include_str!("../../../mtlx/rules/type1_dust.mtlx"),
    include_str!("../../../mtlx/rules/type2_clearcoat.mtlx"),
    include_str!("../../../mtlx/rules/type3_dust_clearcoat.mtlx"),
    include_str!("../../../mtlx/rules/type4_fuzz_scatter.mtlx"),
    include_str!("../../../mtlx/rules/type5_fuzz_clearcoat_scatter.mtlx"),
];

impl EnhancementType {
    pub const ALL: [EnhancementType; 6] =
        [EnhancementType(0), EnhancementType(1), EnhancementType(2), EnhancementType(3), EnhancementType(4), EnhancementType(5)];

    pub fn new(index: u32) -> Result<EnhancementType, String> {
        if index < 6 {
            Ok(EnhancementType(index as u8))
        } else {
            Err(format!("enhancement type {index} does not exist (types are 0 to 5)"))
        }
    }

    pub fn index(self) -> usize {
        self.0 as usize
    }

    /// The rule's file name under `mtlx/rules/`.
    pub fn file_name(self) -> &'static str {
        TYPES[self.index()].0
    }

    /// The rule's name: its file name without `.mtlx`.
    pub fn name(self) -> &'static str {
        self.file_name().trim_end_matches(".mtlx")
    }

    /// The Type's share of the paper's dataset.
    pub fn proportion(self) -> f64 {
        TYPES[self.index()].1
    }

    /// Types 4 and 5 add inner scattering and a subcutaneous lobe: dielectric materials only.
    pub fn dielectric_only(self) -> bool {
        TYPES[self.index()].2
    }

    /// The rule document's text.
    pub fn rule_text(self) -> &'static str {
        RULE_TEXTS[self.index()]
    }

    /// The rule document without its `xi:include` of the uplift library (which the compiler's
    /// builtin library and every written material hold anyway), readable from any folder.
    pub fn standalone_text(self) -> String {
        mtlx::without_includes(self.rule_text())
    }

    /// Draws a Type in the paper's proportions (10/20/20/20/10/20 %) from `u` in [0, 1); for a
    /// metallic material the dielectric-only Types are left out and the rest renormalised.
    pub fn draw(u: f64, metallic: bool) -> EnhancementType {
        let allowed: Vec<EnhancementType> = Self::ALL.into_iter().filter(|t| !(metallic && t.dielectric_only())).collect();
        let total: f64 = allowed.iter().map(|t| t.proportion()).sum();
        let mut acc = 0.0;
        for &t in &allowed {
            acc += t.proportion() / total;
            if u < acc {
                return t;
            }
        }
        *allowed.last().unwrap()
    }
}

/// What `uplift enhance` needs to know of a rule.
#[derive(Clone, Debug)]
pub struct RuleInterface {
    /// The Type its materials count as: a built-in rule's own, a user rule's `uplift_type`.
    pub kind: EnhancementType,
    /// The rule's name: its file name without `.mtlx`.
    pub name: String,
    /// Where it was read from: `mtlx/rules/<file>` for a built-in rule, the path as given for a
    /// user's file.
    pub path: String,
    /// The rule's text without its `xi:include` lines (`standalone_text`).
    text: String,
    /// The rule document (the `xi:include` of the uplift library left out: the written
    /// material embeds the library itself).
    pub document: Document,
    pub random: Vec<RandomScalar>,
    /// (interface input, mask kind), in document order.
    pub masks: Vec<(String, MaskKind)>,
    /// The stack its outputs were checked against (and whose parameters it bakes).
    pub stack: Arc<Stack>,
}

impl RuleInterface {
    /// The rule's text without its `xi:include` lines: readable from any folder, its nodes
    /// resolved by the builtin library (the uplift nodes included).
    pub fn standalone_text(&self) -> &str {
        &self.text
    }

    /// `<name>.mtlx`.
    pub fn file_name(&self) -> String {
        format!("{}.mtlx", self.name)
    }
}

/// Reads a built-in rule's interface. The rules are part of the binary, so an error here is a
/// defect of a rule document; it still comes back as a message naming the rule and the input.
pub fn interface(kind: EnhancementType, stack: &Arc<Stack>) -> Result<RuleInterface, String> {
    let file = format!("mtlx/rules/{}", kind.file_name());
    read_interface(kind.standalone_text(), &file, kind.name(), Some(kind), stack)
}

/// Reads a user-written rule (`uplift enhance --rule FILE`): a document with an `uplift_rule`
/// nodegraph that declares the Type its materials count as (`uplift_type="0"` … `"5"`), whose
/// interface is checked against the stack as every rule's is (`read_interface`). Errors name
/// the file, line and column.
pub fn interface_file(path: &std::path::Path, stack: &Arc<Stack>) -> Result<RuleInterface, String> {
    interface_file_with(path, stack, &mtlx::FileAccess::default())
}

/// [`interface_file`], with the rule's `xi:include`s read as `uplift check` reads them, where
/// `access` allows (`mtlx::file_access`; an include of a library document such as
/// `uplift_defs.mtlx` resolves to the builtin library from any folder): an include outside, or
/// one that cannot be read, is an error naming the rule's line.
pub fn interface_file_with(path: &std::path::Path, stack: &Arc<Stack>, access: &mtlx::FileAccess) -> Result<RuleInterface, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let (_, diags) = mtlx::read_str_with(&text, &path.display().to_string(), access);
    if let Some(d) = diags.iter().find(|d| d.is_error()) {
        return Err(d.to_string());
    }
    let name = path.file_stem().map(|s| s.to_string_lossy().to_string()).filter(|s| !s.is_empty()).ok_or_else(|| format!("{}: not a rule file name", path.display()))?;
    read_interface(mtlx::without_includes(&text), &path.display().to_string(), &name, None, stack)
}

/// A rule's outputs for `stack`: `<input>_out` for each numeric input of `uplift_stack` (from
/// its nodedef) with its type and whether a rule may omit it (`uplift_optional`), then the
/// diffuse colour and the shading normal the renderer reads.
pub fn rule_outputs(stack: &Stack) -> Vec<(String, String, bool)> {
    let mut out: Vec<(String, String, bool)> = stack.inputs().iter().map(|i| (format!("{}_out", i.name), i.ty.clone(), i.optional)).collect();
    out.push(("diffuse_color_out".into(), "color3".into(), false));
    out.push(("normal_out".into(), "vector3".into(), false));
    out
}

/// Reads and checks a rule's interface: the `uplift_rule` nodegraph; its inputs are the PBR
/// inputs (with their types), random scalars (floats with `uimin`/`uimax`) or masks (filename
/// inputs naming `masks/dust.png` or `masks/damage.png`); its outputs are every
/// [`rule_outputs`] of `stack` with its type (those of optional stack inputs may be left
/// out; plus the optional `bsdf_out`), and no other `*_out`. `builtin`: the Type of a built-in
/// rule; otherwise the nodegraph's `uplift_type` says it.
fn read_interface(text: String, file: &str, name: &str, builtin: Option<EnhancementType>, stack: &Arc<Stack>) -> Result<RuleInterface, String> {
    let (document, diags) = mtlx::read_str(&text, file);
    if let Some(d) = diags.iter().find(|d| d.severity == mtlx::Severity::Error) {
        return Err(d.to_string());
    }
    let graph = document
        .top_level()
        .iter()
        .copied()
        .find(|&id| document.get(id).category == "nodegraph" && document.get(id).name() == RULE_GRAPH)
        .ok_or_else(|| format!("{file}: no nodegraph `{RULE_GRAPH}`"))?;
    let at = |id: mtlx::ElementId| {
        let p = &document.get(id).pos;
        format!("{file}:{}:{}", p.line, p.column)
    };
    let kind = match (builtin, document.get(graph).attr("uplift_type")) {
        (Some(k), None) => k,
        (b, Some(t)) => {
            let k = t.trim().parse::<u32>().ok().and_then(|k| EnhancementType::new(k).ok()).ok_or_else(|| format!("{}: `uplift_type` is `{t}`, not a Type 0 to 5", at(graph)))?;
            if b.is_some_and(|b| b != k) {
                return Err(format!("{}: `uplift_type` {t} differs from the built-in rule's Type", at(graph)));
            }
            k
        }
        (None, None) => return Err(format!("{}: nodegraph `{RULE_GRAPH}` declares no `uplift_type` (the Type, 0 to 5, its materials count as in reports)", at(graph))),
    };
    let mut random = Vec::new();
    let mut masks = Vec::new();
    for id in document.children_of(graph, "input") {
        let e = document.get(id);
        let name = e.name().to_string();
        let pos = at(id);
        let ty = e.attr("type").unwrap_or("");
        if ty == "filename" {
            let value = e.attr("value").unwrap_or("");
            let kind = [MaskKind::Dust, MaskKind::Damage]
                .into_iter()
                .find(|k| value == format!("masks/{}.png", k.file_stem()))
                .ok_or_else(|| format!("{pos}: filename input `{name}` names `{value}`, not a mask (masks/dust.png or masks/damage.png)"))?;
            masks.push((name, kind));
            continue;
        }
        if let Some((_, want)) = PBR_INPUTS.iter().find(|(p, _)| *p == name) {
            if ty != *want {
                return Err(format!("{pos}: PBR input `{name}` is {ty}; uplift gives it as {want}"));
            }
            continue;
        }
        let (Some(lo), Some(hi)) = (e.attr("uimin"), e.attr("uimax")) else {
            return Err(format!(
                "{pos}: input `{name}` is neither a PBR input ({}), a random scalar (a float with uimin and uimax) nor a mask (a filename naming masks/dust.png or masks/damage.png)",
                PBR_INPUTS.map(|p| p.0).join(", ")
            ));
        };
        random.push(RandomScalar::from_attributes(&name, ty, lo, hi, e.attr("uplift_distribution")).map_err(|m| format!("{pos}: {m}"))?);
    }
    let required = rule_outputs(stack);
    let outputs: Vec<mtlx::ElementId> = document.children_of(graph, "output").collect();
    for &o in &outputs {
        let e = document.get(o);
        let ty = e.attr("type").unwrap_or("");
        if let Some((_, want, _)) = required.iter().find(|(n, _, _)| n == e.name()) {
            if ty != want {
                return Err(format!("{}: output `{}` is {ty}; the stack's input takes {want}", at(o), e.name()));
            }
        } else if e.name().ends_with("_out") && !(e.name() == "bsdf_out" && ty == "BSDF") {
            return Err(format!("{}: output `{}` is not an input of uplift_stack (its outputs: {})", at(o), e.name(), required.iter().map(|(n, _, _)| n.as_str()).collect::<Vec<_>>().join(", ")));
        }
    }
    for (n, ty, optional) in &required {
        if !optional && !outputs.iter().any(|&o| document.get(o).name() == n) {
            return Err(format!("{}: nodegraph `{RULE_GRAPH}` has no output `{n}` ({ty})", at(graph)));
        }
    }
    Ok(RuleInterface { kind, name: name.to_string(), path: file.to_string(), text, document, random, masks, stack: stack.clone() })
}

/// Every random scalar of a rule, drawn for `seed`, in the rule's order.
pub fn draw_all(random: &[RandomScalar], seed: u64) -> Vec<(String, f64)> {
    random.iter().map(|r| (r.name.clone(), r.draw(seed))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rule_reads_and_declares_its_scalars() {
        for t in EnhancementType::ALL {
            let i = interface(t, &Stack::builtin()).unwrap();
            let names: Vec<&str> = i.random.iter().map(|r| r.name.as_str()).collect();
            for core in ["core_exponent", "haze_exponent", "haze_scale", "haze_boost", "edge_exponent", "specular_ior"] {
                assert!(names.contains(&core), "{}: {core} missing", t.name());
            }
            let dust = i.masks.iter().any(|(_, k)| *k == MaskKind::Dust);
            let damage = i.masks.iter().any(|(_, k)| *k == MaskKind::Damage);
            assert_eq!(dust, matches!(t.index(), 1 | 3), "{}", t.name());
            assert_eq!(damage, matches!(t.index(), 2 | 3 | 5), "{}", t.name());
        }
    }

    #[test]
    fn draws_respect_ranges_and_distributions() {
        let i = interface(EnhancementType::new(5).unwrap(), &Stack::builtin()).unwrap();
        let ior = i.random.iter().find(|r| r.name == "specular_ior").unwrap();
        assert_eq!(ior.distribution, Distribution::Normal { mean: 1.5, sd: 0.08 });
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|s| ior.draw(s)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(xs.iter().all(|x| (1.33..=1.8).contains(x)));
        // N(1.5, 0.08) truncated to [1.33, 1.8] (−2.125σ, +3.75σ) has mean 1.503366 and standard
        // deviation 0.076177 (closed forms with φ and Φ); standard errors here are 5.4e-4 and 4e-4.
        assert!((mean - 1.503366).abs() < 0.002, "mean {mean}");
        assert!((var.sqrt() - 0.076177).abs() < 0.0015, "sd {}", var.sqrt());
        let damage = i.random.iter().find(|r| r.name == "coat_damage").unwrap();
        let zeros = (0..n).filter(|&s| damage.draw(s) == 0.0).count() as f64 / n as f64;
        assert!((zeros - 0.5).abs() < 0.015, "{zeros}");
        for r in &i.random {
            for s in 0..200 {
                let v = r.draw(s);
                assert!(v == 0.0 && r.distribution != Distribution::Uniform || (r.min..=r.max).contains(&v), "{} = {v}", r.name);
            }
        }
    }

    #[test]
    fn draws_depend_on_seed_and_name_only() {
        let i = interface(EnhancementType::new(3).unwrap(), &Stack::builtin()).unwrap();
        let a = draw_all(&i.random, 7);
        let mut reversed = i.random.clone();
        reversed.reverse();
        let mut b = draw_all(&reversed, 7);
        b.reverse();
        assert_eq!(a, b);
        assert_ne!(a, draw_all(&i.random, 8));
    }

    #[test]
    fn types_follow_the_papers_proportions() {
        let n = 100_000;
        let mut counts = [0usize; 6];
        for k in 0..n {
            counts[EnhancementType::draw(uniform(1, 2, k), false).index()] += 1;
        }
        for t in EnhancementType::ALL {
            assert!((counts[t.index()] as f64 / n as f64 - t.proportion()).abs() < 0.005, "{counts:?}");
        }
        assert!((0..1000).all(|k| !EnhancementType::draw(uniform(3, 4, k), true).dielectric_only()));
    }
}
