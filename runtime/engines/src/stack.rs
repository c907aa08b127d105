//! The `uplift_stack` a run shades with, read from its nodedef at run time: the node library it
//! comes from (the builtin one, or library folders given with `--stack DIR` whose definitions
//! win over the builtin ones — a stack with another lobe needs no Rust change), the table of
//! its parameters (one per component of each numeric input, in input order; the encoder's range
//! is `uisoftmin`/`uisoftmax` where given, else `uimin`/`uimax`; `uplift_encoding="sqrt"` maps a
//! GGX alpha to perceptual roughness for the encoder; `uplift_optional="true"` lets rules omit
//! the input, which then keeps its nodedef value), the stack signature every decoder file and
//! params.exr records, and the document its closure kernels compile from. The data generator,
//! the encoder, the fitter (`params.exr` channels), the kernels, the rules' interface check and
//! the renderer all read this table.

use mtlx::{Document, ElementId};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use uplift_compiler::Compiler;

/// The stack's nodedef.
pub const STACK_NODEDEF: &str = "ND_uplift_stack";

/// The most parameters a stack may have (the renderer keeps a surface point's parameters in a
/// fixed array).
pub const MAX_PARAMETERS: usize = 64;

/// How a parameter is mapped to the encoder's [0, 1] input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// (x − lo) / (hi − lo).
    Linear,
    /// (√x − √lo) / (√hi − √lo): GGX alphas, so the encoder sees perceptual roughness.
    Sqrt,
}

impl Encoding {
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Linear => "linear",
            Encoding::Sqrt => "sqrt",
        }
    }
}

/// One scalar parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// The `uplift_stack` input it belongs to.
    pub input: String,
    /// Its component in that input.
    pub component: usize,
    /// Its channel in `params.exr` (`input` or `input.R/G/B`, `input.X/Y/Z`).
    pub channel: String,
    pub lo: f32,
    pub hi: f32,
    pub encoding: Encoding,
    /// The nodedef's value of this component (what a rule that omits an optional input bakes).
    pub default: f32,
}

/// One numeric input of the stack's nodedef.
#[derive(Clone, Debug, PartialEq)]
pub struct StackInput {
    pub name: String,
    /// Its MaterialX type (`float`, `color3`, `vector2`, `vector3`).
    pub ty: String,
    /// Its nodedef value, as written.
    pub value: String,
    /// Rules may omit it (`uplift_optional="true"`): its lobe stays as the nodedef sets it.
    pub optional: bool,
}

/// The stack of a run.
pub struct Stack {
    compiler: Compiler,
    /// The folders given with `--stack` (empty: the builtin library's stack).
    library: Vec<PathBuf>,
    inputs: Vec<StackInput>,
    parameters: Vec<Parameter>,
    /// Where the nodedef is (`file:line:col`).
    nodedef_at: String,
}

impl std::fmt::Debug for Stack {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stack").field("nodedef", &self.nodedef_at).field("library", &self.library).field("parameters", &self.parameters.len()).finish()
    }
}

impl Parameter {
    /// The encoder's input for value `x` (not clamped: values outside the range stay visible).
    pub fn encode(&self, x: f32) -> f32 {
        match self.encoding {
            Encoding::Linear => (x - self.lo) / (self.hi - self.lo),
            Encoding::Sqrt => (x.max(0.0).sqrt() - self.lo.sqrt()) / (self.hi.sqrt() - self.lo.sqrt()),
        }
    }

    /// The value at encoded position `t` ∈ [0, 1] (uniform draws for the infill class).
    pub fn decode(&self, t: f32) -> f32 {
        match self.encoding {
            Encoding::Linear => self.lo + t * (self.hi - self.lo),
            Encoding::Sqrt => {
                let s = self.lo.sqrt() + t * (self.hi.sqrt() - self.lo.sqrt());
                s * s
            }
        }
    }

    /// `channel[lo,hi]encoding`, the parameter's entry in a stack signature.
    fn signature_entry(&self) -> String {
        format!("{}[{:?},{:?}]{}", self.channel, self.lo, self.hi, self.encoding.name())
    }
}

impl Stack {
    /// The builtin library's stack (read once per process).
    pub fn builtin() -> Arc<Stack> {
        static BUILTIN: OnceLock<Arc<Stack>> = OnceLock::new();
        BUILTIN.get_or_init(|| Arc::new(Stack::read(Compiler::builtin(), Vec::new()).unwrap_or_else(|e| panic!("the builtin library's uplift_stack: {e}")))).clone()
    }

    /// The stack of the library folders `dirs` (loaded before the builtin library, so that a
    /// folder redefining `ND_uplift_stack` and its nodegraph replaces it); the builtin stack when
    /// `dirs` is empty. Errors name the folder, or the file and position of the fault.
    pub fn load(dirs: &[PathBuf]) -> Result<Arc<Stack>, String> {
        if dirs.is_empty() {
            return Ok(Stack::builtin());
        }
        for d in dirs {
            if !d.is_dir() {
                return Err(format!("--stack {}: not a folder", d.display()));
            }
        }
        let compiler = Compiler::overriding(dirs);
        if let Some(d) = compiler.library.diagnostics.iter().find(|d| d.is_error()) {
            return Err(d.to_string());
        }
        Ok(Arc::new(Stack::read(compiler, dirs.to_vec())?))
    }

    fn read(compiler: Compiler, library: Vec<PathBuf>) -> Result<Stack, String> {
        let (doc, nd) = nodedef_element(&compiler).ok_or_else(|| format!("the node library has no nodedef `{STACK_NODEDEF}`"))?;
        let at = |id: ElementId| {
            let p = &doc.get(id).pos;
            format!("{}:{}:{}", p.file, p.line, p.column)
        };
        let mut inputs = Vec::new();
        let mut parameters = Vec::new();
        for id in doc.children_of(nd, "input") {
            let input = doc.get(id);
            let name = input.name().to_string();
            if input.attr("defaultgeomprop").is_some() {
                continue;
            }
            let ty = input.attr("type").unwrap_or("");
            let suffixes: &[&str] = match ty {
                "float" => &[""],
                "color3" => &[".R", ".G", ".B"],
                "vector2" => &[".X", ".Y"],
                "vector3" => &[".X", ".Y", ".Z"],
                other => return Err(format!("{}: input `{name}` of type `{other}`: stack parameters are float, color3, vector2 or vector3", at(id))),
            };
            let list = |attr: &str| -> Result<Option<Vec<f32>>, String> {
                let Some(text) = input.attr(attr) else { return Ok(None) };
                let values = text.split(',').map(|v| v.trim().parse::<f32>().ok().filter(|x| x.is_finite())).collect::<Option<Vec<f32>>>();
                match values {
                    Some(v) if v.len() == 1 => Ok(Some(vec![v[0]; suffixes.len()])),
                    Some(v) if v.len() == suffixes.len() => Ok(Some(v)),
                    _ => Err(format!("{}: `{attr}` of `{name}` is `{text}`, not {} number(s)", at(id), suffixes.len())),
                }
            };
            let bound = |soft: &str, hard: &str| -> Result<Vec<f32>, String> {
                list(soft)?.or(list(hard)?).ok_or_else(|| format!("{}: input `{name}` has neither `{soft}` nor `{hard}` (every stack input needs its range)", at(id)))
            };
            let (lo, hi) = (bound("uisoftmin", "uimin")?, bound("uisoftmax", "uimax")?);
            let default = list("value")?.ok_or_else(|| format!("{}: input `{name}` has no `value`", at(id)))?;
            let encoding = match input.attr("uplift_encoding").unwrap_or("linear") {
                "linear" => Encoding::Linear,
                "sqrt" => Encoding::Sqrt,
                other => return Err(format!("{}: `uplift_encoding` of `{name}` is `{other}`: expected linear or sqrt", at(id))),
            };
            let optional = match input.attr("uplift_optional").unwrap_or("false") {
                "true" => true,
                "false" => false,
                other => return Err(format!("{}: `uplift_optional` of `{name}` is `{other}`: expected true or false", at(id))),
            };
            for (c, suffix) in suffixes.iter().enumerate() {
                if lo[c].partial_cmp(&hi[c]) != Some(std::cmp::Ordering::Less) || (encoding == Encoding::Sqrt && lo[c] < 0.0) {
                    return Err(format!("{}: the encoder's range of `{name}{suffix}` is [{}, {}]: it must be non-empty (and non-negative for sqrt)", at(id), lo[c], hi[c]));
                }
                parameters.push(Parameter { input: name.clone(), component: c, channel: format!("{name}{suffix}"), lo: lo[c], hi: hi[c], encoding, default: default[c] });
            }
            inputs.push(StackInput { name, ty: ty.to_string(), value: input.attr("value").unwrap_or("").to_string(), optional });
        }
        if parameters.is_empty() || parameters.len() > MAX_PARAMETERS {
            return Err(format!("{}: `{STACK_NODEDEF}` has {} parameters (one per component of its numeric inputs): 1 to {MAX_PARAMETERS} are supported", at(nd), parameters.len()));
        }
        let nodedef_at = at(nd);
        Ok(Stack { compiler, library, inputs, parameters, nodedef_at })
    }

    /// The compiler of the stack's library (rules, the stack's kernels, glints compile with it).
    pub fn compiler(&self) -> &Compiler {
        &self.compiler
    }

    /// The `--stack` folders (empty for the builtin stack).
    pub fn library(&self) -> &[PathBuf] {
        &self.library
    }

    pub fn is_builtin(&self) -> bool {
        self.library.is_empty()
    }

    /// `file:line:col` of the stack's nodedef.
    pub fn nodedef_at(&self) -> &str {
        &self.nodedef_at
    }

    /// The numeric inputs, in nodedef order.
    pub fn inputs(&self) -> &[StackInput] {
        &self.inputs
    }

    /// The parameters, in nodedef order.
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// Parameters per texel.
    pub fn len(&self) -> usize {
        self.parameters.len()
    }

    pub fn is_empty(&self) -> bool {
        self.parameters.is_empty()
    }

    /// Index of a parameter by its channel name.
    pub fn index_of(&self, channel: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p.channel == channel)
    }

    /// A parameter row holding every nodedef value.
    pub fn defaults(&self) -> Vec<f32> {
        self.parameters.iter().map(|p| p.default).collect()
    }

    /// The stack signature a decoder file and a params.exr record: every parameter's channel,
    /// encoder range and encoding, in order, space-separated.
    pub fn signature(&self) -> String {
        self.parameters.iter().map(Parameter::signature_entry).collect::<Vec<_>>().join(" ")
    }

    /// Checks a recorded signature against this stack; the error names the first difference
    /// (a parameter changed, added or removed).
    pub fn check_signature(&self, recorded: &str) -> Result<(), String> {
        let theirs: Vec<&str> = recorded.split_whitespace().collect();
        let ours: Vec<String> = self.parameters.iter().map(Parameter::signature_entry).collect();
        for k in 0..theirs.len().max(ours.len()) {
            match (theirs.get(k), ours.get(k)) {
                (Some(a), Some(b)) if *a == b.as_str() => {}
                (Some(a), Some(b)) => return Err(format!("it was made for another uplift_stack: parameter {} is `{a}` there and `{b}` here", k + 1)),
                (Some(a), None) => return Err(format!("it was made for another uplift_stack: parameter {} `{a}` is not in this stack ({} parameters here, {} there)", k + 1, ours.len(), theirs.len())),
                (None, Some(b)) => return Err(format!("it was made for another uplift_stack: parameter {} `{b}` of this stack is not there ({} parameters here, {} there)", k + 1, ours.len(), theirs.len())),
                (None, None) => unreachable!(),
            }
        }
        Ok(())
    }

    /// Encodes rows of [`len`](Self::len) parameters for the encoder.
    pub fn encode_rows(&self, params: &[f32], out: &mut [f32]) {
        assert_eq!(params.len(), out.len());
        let n = self.len();
        for (row, enc) in params.chunks_exact(n).zip(out.chunks_exact_mut(n)) {
            for ((x, e), p) in row.iter().zip(enc.iter_mut()).zip(&self.parameters) {
                *e = p.encode(*x);
            }
        }
    }

    /// The document the stack's closure kernels compile from (source name, text): a nodegraph
    /// with every numeric input of the stack on its interface feeding one `uplift_stack` node.
    /// The builtin stack's is the shipped graph (runtime/kernels/graphs/bsdf/uplift_stack.mtlx),
    /// whose kernels the CPU engine runs in-process.
    pub fn kernel_document(&self) -> (String, String) {
        if self.is_builtin() {
            let (source, text) = uplift_kernels::shipped::UPLIFT_STACK_GRAPH;
            return (source.to_string(), text.to_string());
        }
        (format!("<uplift_stack of {}>", self.nodedef_at), self.generated_kernel_document())
    }

    /// [`kernel_document`](Self::kernel_document)'s text, generated from the nodedef.
    pub fn generated_kernel_document(&self) -> String {
        let mut s = String::from("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <nodegraph name=\"uplift_stack\">\n");
        for i in &self.inputs {
            s.push_str(&format!("    <input name=\"{}\" type=\"{}\" value=\"{}\" />\n", i.name, i.ty, i.value));
        }
        s.push_str("    <uplift_stack name=\"stack\" type=\"BSDF\">\n");
        for i in &self.inputs {
            s.push_str(&format!("      <input name=\"{0}\" type=\"{1}\" interfacename=\"{0}\" />\n", i.name, i.ty));
        }
        s.push_str("    </uplift_stack>\n    <output name=\"out\" type=\"BSDF\" nodename=\"stack\" />\n  </nodegraph>\n</materialx>\n");
        s
    }

    /// The documents that define the stack for a written material: every document of the
    /// `--stack` folders, then the builtin uplift library's (`mtlx/libraries/uplift/`). An
    /// element defined twice is the first one's (as the library resolves it).
    pub fn definition_documents(&self) -> Vec<Arc<Document>> {
        self.compiler
            .library
            .defs
            .documents
            .iter()
            .filter(|d| {
                let file = d.get(d.root()).pos.file.to_string();
                file.starts_with("<builtin>/uplift/") || self.library.iter().any(|l| Path::new(&file).starts_with(l))
            })
            .cloned()
            .collect()
    }
}

/// The stack's nodedef element, as the library resolves it (the first definition).
fn nodedef_element(compiler: &Compiler) -> Option<(Arc<Document>, ElementId)> {
    compiler.library.defs.documents.iter().find_map(|d| {
        d.top_level().iter().find(|&&e| d.get(e).category == "nodedef" && d.get(e).name() == STACK_NODEDEF).map(|&e| (d.clone(), e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_signature_names_its_first_difference() {
        let stack = Stack::builtin();
        let ours = stack.signature();
        assert!(stack.check_signature(&ours).is_ok());
        assert!(ours.starts_with("reflectivity.R[0.0,0.99]linear "), "{ours}");
        let changed = ours.replace("haze_weight[0.05,0.6]linear", "haze_weight[0.0,1.0]linear");
        let e = stack.check_signature(&changed).unwrap_err();
        assert!(e.contains("parameter 10 is `haze_weight[0.0,1.0]linear` there and `haze_weight[0.05,0.6]linear` here"), "{e}");
        let n = stack.len();
        let e = stack.check_signature(&format!("{ours} film_ior[1.2,2.0]linear")).unwrap_err();
        assert!(e.contains(&format!("parameter {} `film_ior[1.2,2.0]linear` is not in this stack", n + 1)), "{e}");
        let shorter: Vec<&str> = ours.split(' ').take(n - 1).collect();
        let e = stack.check_signature(&shorter.join(" ")).unwrap_err();
        assert!(e.contains(&format!("parameter {n} `subcutaneous_roughness[0.4,1.0]linear` of this stack is not there")), "{e}");
    }

    #[test]
    fn table_follows_the_uplift_stack_inputs() {
        // Each input's components are consecutive, starting at 0; encode and decode invert.
        let stack = Stack::builtin();
        let mut previous = String::new();
        let mut next = 0;
        for p in stack.parameters() {
            if p.input != previous {
                previous = p.input.clone();
                next = 0;
            }
            assert_eq!(p.component, next, "{}", p.channel);
            next += 1;
            assert!(p.lo < p.hi);
            assert!((p.decode(p.encode(0.5 * (p.lo + p.hi))) - 0.5 * (p.lo + p.hi)).abs() < 1e-6);
            assert_eq!(stack.index_of(&p.channel).map(|i| stack.parameters()[i].channel.clone()), Some(p.channel.clone()));
        }
        assert_eq!(stack.inputs().iter().map(|i| mtlx::DataType::from_name(&i.ty).components().unwrap_or(1)).sum::<usize>(), stack.len());
    }
}
