//! The glint decorator of `uplift enhance --glints` (paper §5.3): its inputs drawn per material
//! like a rule's random scalars — uniformly in the `uisoftmin`/`uisoftmax` of the
//! `ND_uplift_glint_bsdf` nodedef (the flake size relative to the object's size, the seed an
//! integer) — and its place in the written material: an `uplift_glint` node between the rule's
//! `uplift_stack` and everything that consumed it, so the glints modulate the non-diffuse part
//! exactly as the renderer applies them (f_nd · N, to the reference and the neural material).

use crate::rules::{Distribution, RandomScalar};
use mtlx::{Document, ElementId, SourcePos};
use uplift_material::GlintRecord;

/// The nodedef whose inputs the draw reads.
const GLINT_NODEDEF: &str = "ND_uplift_glint_bsdf";

/// The glint inputs as random scalars (`glint_<input>`), from the builtin library's nodedef.
pub fn glint_scalars() -> Result<Vec<RandomScalar>, String> {
    let compiler = uplift_compiler::Compiler::builtin();
    let (doc, nd) = compiler
        .library
        .defs
        .documents
        .iter()
        .find_map(|d| d.top_level().iter().find(|&&e| d.get(e).category == "nodedef" && d.get(e).name() == GLINT_NODEDEF).map(|&e| (d.clone(), e)))
        .ok_or_else(|| format!("the builtin library has no `{GLINT_NODEDEF}`"))?;
    let mut out = Vec::new();
    for i in doc.children_of(nd, "input") {
        let e = doc.get(i);
        let (Some(lo), Some(hi)) = (e.attr("uisoftmin"), e.attr("uisoftmax")) else { continue };
        let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("{}: `{}` of `{}` is not a number", e.pos, t, e.name()));
        out.push(RandomScalar { name: format!("glint_{}", e.name()), min: num(lo)?, max: num(hi)?, distribution: Distribution::Uniform });
    }
    Ok(out)
}

/// The glint inputs for a material of `object_size` drawn from `seed`.
pub fn draw(seed: u64, object_size: f32) -> Result<GlintRecord, String> {
    let scalars = glint_scalars()?;
    let value = |name: &str| -> Result<f32, String> {
        scalars.iter().find(|s| s.name == format!("glint_{name}")).map(|s| s.draw(seed) as f32).ok_or_else(|| format!("`{GLINT_NODEDEF}` gives no draw range (uisoftmin/uisoftmax) for `{name}`"))
    };
    Ok(GlintRecord {
        density: value("density")?,
        size: value("size")? * object_size,
        angle: value("angle")?,
        spread: value("spread")?,
        strength: value("strength")?,
        seed: value("seed")?.floor(),
    })
}

/// Puts an `uplift_glint` node with `glint`'s inputs after the `uplift_stack` node of `graph`,
/// re-pointing every consumer of the stack to it.
pub fn insert(doc: &mut Document, graph: ElementId, glint: &GlintRecord) -> Result<(), String> {
    let stack = doc.children(graph).iter().copied().find(|&c| doc.get(c).category == "uplift_stack").ok_or("the rule has no `uplift_stack` node to put glints on")?;
    let stack_name = doc.get(stack).name().to_string();
    let name = "uplift_glints";
    let consumers: Vec<ElementId> = doc.descendants(graph).into_iter().filter(|&id| matches!(doc.get(id).category.as_str(), "input" | "output") && doc.get(id).attr("nodename") == Some(stack_name.as_str())).collect();
    let pos = SourcePos::synthetic("uplift enhance --glints");
    let at = doc.children(graph).iter().position(|&c| c == stack).map_or(0, |i| i + 1);
    let node = doc.insert_child(graph, at, "uplift_glint", vec![("name".into(), name.into()), ("type".into(), "BSDF".into())], pos.clone());
    doc.add_child(node, "input", vec![("name".into(), "in".into()), ("type".into(), "BSDF".into()), ("nodename".into(), stack_name.clone())], pos.clone());
    for (input, value) in glint.inputs() {
        doc.add_child(node, "input", vec![("name".into(), input.into()), ("type".into(), "float".into()), ("value".into(), format!("{value:?}"))], pos.clone());
    }
    for c in consumers {
        doc.get_mut(c).set_attr("nodename", name);
    }
    Ok(())
}
