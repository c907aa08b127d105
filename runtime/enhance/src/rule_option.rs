//! Rule options (`uplift enhance --option NAME|FILE`, `--iridescence`): an `uplift_rule_option`
//! nodegraph — random scalars on its interface, drawn per material as a rule's are, and outputs
//! `<input>_out` for inputs of `uplift_stack` — applied on top of whichever rule a material
//! gets. Its outputs replace the rule's own for those inputs (or add ones the rule leaves out):
//! in the written material the option's inputs and nodes join the rule's graph and feed its
//! `uplift_stack` node; in params.exr its channels come from the option's own kernel, so an
//! option's outputs read only its own inputs. The builtin options are `mtlx/rules/options/`.

use crate::rules::{rule_outputs, RuleInterface};
use mtlx::{Document, ElementId, SourcePos};
use uplift_base::random_scalar::RandomScalar;
use uplift_engines::stack::Stack;

/// The nodegraph an option document defines.
pub const OPTION_GRAPH: &str = "uplift_rule_option";

/// The builtin options (name, source, text).
const BUILTIN: [(&str, &str, &str); 1] = [("iridescence", "mtlx/rules/options/iridescence.mtlx", include_str!("../../../mtlx/rules/options/iridescence.mtlx"))];

/// A rule option, read and checked against a stack.
#[derive(Clone, Debug)]
pub struct RuleOption {
    pub name: String,
    /// Where it was read from.
    pub path: String,
    pub document: Document,
    /// Its random scalars.
    pub random: Vec<RandomScalar>,
    /// Its outputs (`<input>_out`) with their types.
    pub outputs: Vec<(String, String)>,
}

/// The builtin option names.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|b| b.0).collect()
}

/// An option by builtin name, or a document file. Errors name the file, line and column.
pub fn read_option(name_or_file: &str, stack: &Stack) -> Result<RuleOption, String> {
    if let Some((name, source, text)) = BUILTIN.iter().find(|b| b.0 == name_or_file) {
        return parse(name, source, text, stack);
    }
    let path = std::path::Path::new(name_or_file);
    if !path.is_file() {
        return Err(format!("rule option `{name_or_file}`: neither a builtin option ({}) nor a file", builtin_names().join(", ")));
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let name = path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
    parse(&name, &path.display().to_string(), &text, stack)
}

fn parse(name: &str, source: &str, text: &str, stack: &Stack) -> Result<RuleOption, String> {
    let (document, diags) = mtlx::read_str(text, source);
    if let Some(d) = diags.iter().find(|d| d.is_error()) {
        return Err(d.to_string());
    }
    let graph = document
        .top_level()
        .iter()
        .copied()
        .find(|&id| document.get(id).category == "nodegraph" && document.get(id).name() == OPTION_GRAPH)
        .ok_or_else(|| format!("{source}: no nodegraph `{OPTION_GRAPH}`"))?;
    let at = |id: ElementId| {
        let p = &document.get(id).pos;
        format!("{source}:{}:{}", p.line, p.column)
    };
    let mut random = Vec::new();
    for id in document.children_of(graph, "input") {
        let e = document.get(id);
        let (Some(lo), Some(hi)) = (e.attr("uimin"), e.attr("uimax")) else {
            return Err(format!("{}: input `{}` is not a random scalar (a float with uimin and uimax)", at(id), e.name()));
        };
        random.push(RandomScalar::from_attributes(e.name(), e.attr("type").unwrap_or(""), lo, hi, e.attr("uplift_distribution")).map_err(|m| format!("{}: {m}", at(id)))?);
    }
    let allowed = rule_outputs(stack);
    let mut outputs = Vec::new();
    for id in document.children_of(graph, "output") {
        let e = document.get(id);
        let ty = e.attr("type").unwrap_or("");
        match allowed.iter().find(|(n, _, _)| n == e.name()) {
            Some((_, want, _)) if want == ty => outputs.push((e.name().to_string(), ty.to_string())),
            Some((_, want, _)) => return Err(format!("{}: output `{}` is {ty}; the stack's input takes {want}", at(id), e.name())),
            None => return Err(format!("{}: output `{}` is not a rule output of this stack ({})", at(id), e.name(), allowed.iter().map(|(n, _, _)| n.as_str()).collect::<Vec<_>>().join(", "))),
        }
    }
    if outputs.is_empty() {
        return Err(format!("{}: the option has no outputs", at(graph)));
    }
    Ok(RuleOption { name: name.to_string(), path: source.to_string(), document, random, outputs })
}

impl RuleOption {
    /// The option's graph element.
    fn graph(&self) -> ElementId {
        let d = &self.document;
        d.top_level().iter().copied().find(|&id| d.get(id).name() == OPTION_GRAPH).expect("checked when read")
    }

    /// The option's text (its kernel's document).
    pub fn text(&self) -> String {
        mtlx::write_string(&self.document)
    }

    /// Its outputs as kernel output names (`uplift_rule_option/<x>_out`).
    pub fn kernel_outputs(&self) -> Vec<String> {
        self.outputs.iter().map(|(n, _)| format!("{OPTION_GRAPH}/{n}")).collect()
    }

    /// Checks that its random scalars do not clash with the rule's.
    pub fn check_against(&self, rule: &RuleInterface) -> Result<(), String> {
        for r in &self.random {
            if rule.random.iter().any(|s| s.name == r.name) || rule.document.top_level().iter().any(|&g| rule.document.children_of(g, "input").any(|i| rule.document.get(i).name() == r.name)) {
                return Err(format!("{}: option `{}`'s input `{}` is also an input of rule {}", self.path, self.name, r.name, rule.name));
            }
        }
        Ok(())
    }

    /// Merges the option into `doc`'s graph `graph` (a rule's graph, renamed or not): its inputs
    /// and nodes join the graph, its outputs replace the graph's outputs of the same name, and
    /// every `uplift_stack` node of the graph reads the option's value for those inputs.
    pub fn merge_into(&self, doc: &mut Document, graph: ElementId) -> Result<(), String> {
        let opt = &self.document;
        let og = self.graph();
        let taken = |doc: &Document, name: &str| doc.children(graph).iter().any(|&c| doc.get(c).name() == name);
        for &c in opt.children(og) {
            let e = opt.get(c);
            if e.category == "output" {
                continue;
            }
            if taken(doc, e.name()) {
                return Err(format!("{}: option `{}` defines `{}`, which the rule's graph already has", self.path, self.name, e.name()));
            }
            doc.import_subtree(graph, opt, c);
        }
        let pos = || SourcePos::synthetic("uplift enhance");
        for o in opt.children_of(og, "output") {
            let e = opt.get(o);
            let (name, ty) = (e.name().to_string(), e.attr("type").unwrap_or("").to_string());
            let source = e.attr("nodename").ok_or_else(|| format!("{}: option output `{name}` names no node", self.path))?.to_string();
            let existing: Option<ElementId> = doc.children_of(graph, "output").find(|&k| doc.get(k).name() == name);
            let out = match existing {
                Some(k) => k,
                None => doc.add_child(graph, "output", vec![("name".into(), name.clone()), ("type".into(), ty.clone())], pos()),
            };
            for attr in ["interfacename", "output", "value"] {
                doc.get_mut(out).remove_attr(attr);
            }
            doc.get_mut(out).set_attr("nodename", source.clone());
            let input = name.trim_end_matches("_out").to_string();
            let stacks: Vec<ElementId> = doc.children(graph).iter().copied().filter(|&k| doc.get(k).category == "uplift_stack").collect();
            for s in stacks {
                let found = doc.children_of(s, "input").find(|&k| doc.get(k).name() == input);
                let slot = match found {
                    Some(k) => k,
                    None => doc.add_child(s, "input", vec![("name".into(), input.clone()), ("type".into(), ty.clone())], pos()),
                };
                for attr in ["interfacename", "output", "value"] {
                    doc.get_mut(slot).remove_attr(attr);
                }
                doc.get_mut(slot).set_attr("nodename", source.clone());
            }
        }
        Ok(())
    }
}

