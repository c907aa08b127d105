//! The training-data classes (paper §4.2; lobes.md §3.3) as data: MaterialX documents, one per
//! class, next to the rules (`mtlx/rules/classes/*.mtlx`, embedded), plus any class documents
//! in the `--stack` folders (a class of the same name replaces the builtin one). A class is an
//! `uplift_class` nodegraph with the rules' output contract — `<input>_out` for inputs of
//! `uplift_stack`; an input it leaves out keeps its nodedef value, so a decorator the class
//! does not mention stays off — whose interface inputs are random scalars (`uimin`/`uimax`,
//! `uplift_distribution`, as a rule's) drawn once per base material (`uplift_scope="tile"`) or
//! once per row (`uplift_scope="cell"`); `uplift_share` is its share of the training rows;
//! `uplift_draw="uniform"` instead draws every parameter uniformly in the encoder's range (the
//! infill class). A class's graph runs as a pattern kernel on the CPU engine (the builtin
//! classes' are shipped); parameter rows are never stored, only regenerated from (seed, class,
//! tile, cell).

use std::sync::Arc;
use uplift_base::random_scalar::RandomScalar;
use uplift_base::rng::{hash_str, mix64};
use uplift_compiler::{OutputSelection, PatternKernel};
use uplift_engines::batch::{Columns, Geometry, PatternBatch};
use uplift_engines::prepared_kernel::{Engine, PreparedKernel};
use uplift_engines::stack::Stack;

/// Cells per tile edge: a tile (base material) holds `TILE²` cells.
pub const TILE: u64 = 128;

/// The nodegraph a class document defines.
pub const CLASS_GRAPH: &str = "uplift_class";

/// The builtin classes (name, source, text), in order.
const BUILTIN: [(&str, &str, &str); 5] = [
    ("haze", "mtlx/rules/classes/haze.mtlx", include_str!("../../../mtlx/rules/classes/haze.mtlx")),
    ("dust", "mtlx/rules/classes/dust.mtlx", include_str!("../../../mtlx/rules/classes/dust.mtlx")),
    ("clearcoat", "mtlx/rules/classes/clearcoat.mtlx", include_str!("../../../mtlx/rules/classes/clearcoat.mtlx")),
    ("inner", "mtlx/rules/classes/inner.mtlx", include_str!("../../../mtlx/rules/classes/inner.mtlx")),
    ("infill", "mtlx/rules/classes/infill.mtlx", include_str!("../../../mtlx/rules/classes/infill.mtlx")),
];

/// When a class's random scalar is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scope {
    /// Once per base material (tile).
    Tile,
    /// Once per row (cell).
    Cell,
}

/// A class's random scalar and the kernel input column it feeds.
#[derive(Clone, Debug)]
struct ClassScalar {
    scalar: RandomScalar,
    scope: Scope,
    column: usize,
}

enum Draw {
    /// Every parameter uniform in the encoder's range.
    Uniform,
    /// The class graph's kernel; `outputs[k]`: the output column of stack parameter k, if the
    /// class sets it.
    Graph { kernel: PreparedKernel, scalars: Vec<ClassScalar>, outputs: Vec<Option<usize>> },
}

/// One training class.
pub struct TrainingClass {
    pub name: String,
    /// Where it was read from.
    pub source: String,
    /// Its share of the training rows (relative to the other classes').
    pub share: f64,
    draw: Draw,
}

/// A class as read, its graph's kernel not yet prepared.
struct ReadClass {
    name: String,
    source: String,
    share: f64,
    /// The graph's kernel (`None`: `uplift_draw="uniform"`), its scalars and each stack parameter's output column.
    graph: Option<(PatternKernel, Vec<ClassScalar>, Vec<Option<usize>>)>,
}

/// The classes of a stack, their kernels prepared on a CPU engine.
pub struct TrainingClasses {
    stack: Arc<Stack>,
    classes: Vec<TrainingClass>,
}

impl TrainingClasses {
    /// The builtin classes and the class documents of `stack`'s folders, prepared on `engine`.
    pub fn load<'e>(stack: &Arc<Stack>, engine: impl Into<Engine<'e>>) -> Result<TrainingClasses, String> {
        let engine: Engine<'e> = engine.into();
        let mut docs: Vec<(String, String, String)> = BUILTIN.iter().map(|(n, s, t)| (n.to_string(), s.to_string(), t.to_string())).collect();
        for dir in stack.library() {
            for file in mtlx::library::files_under(dir).into_iter().filter(|f| f.extension().is_some_and(|e| e == "mtlx")) {
                let text = std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
                if !text.contains(CLASS_GRAPH) {
                    continue;
                }
                let name = file.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
                let entry = (name.clone(), file.display().to_string(), text);
                match docs.iter_mut().find(|d| d.0 == name) {
                    Some(d) => *d = entry,
                    None => docs.push(entry),
                }
            }
        }
        let mut read = Vec::new();
        for (name, source, text) in docs {
            read.extend(read_class(stack, &name, &source, &text)?);
        }
        if read.is_empty() {
            return Err("no training classes".into());
        }
        // The graphs' kernels prepared together: classes not shipped build in one runner.
        let mut kernels = Vec::new();
        let read: Vec<_> = read
            .into_iter()
            .map(|c| {
                let wiring = c.graph.map(|(kernel, scalars, outputs)| {
                    kernels.push(kernel);
                    (scalars, outputs)
                });
                (c.name, c.source, c.share, wiring)
            })
            .collect();
        let tables = stack.compiler().library.albedo_table_data.clone();
        let mut prepared = PreparedKernel::all(engine, kernels, tables.as_deref())?.into_iter();
        let classes = read
            .into_iter()
            .map(|(name, source, share, wiring)| {
                let draw = match wiring {
                    None => Draw::Uniform,
                    Some((scalars, outputs)) => Draw::Graph { kernel: prepared.next().expect("a kernel per graph class"), scalars, outputs },
                };
                TrainingClass { name, source, share, draw }
            })
            .collect();
        Ok(TrainingClasses { stack: stack.clone(), classes })
    }

    pub fn len(&self) -> usize {
        self.classes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.classes.is_empty()
    }

    pub fn get(&self, index: usize) -> &TrainingClass {
        &self.classes[index]
    }

    pub fn iter(&self) -> impl Iterator<Item = &TrainingClass> {
        self.classes.iter()
    }

    /// The index of the class named `name`.
    pub fn index_of(&self, name: &str) -> Result<usize, String> {
        self.classes.iter().position(|c| c.name == name).ok_or_else(|| format!("unknown data class `{name}` (the classes: {})", self.names().join(", ")))
    }

    pub fn names(&self) -> Vec<&str> {
        self.classes.iter().map(|c| c.name.as_str()).collect()
    }

    /// The class a uniform number `u` ∈ [0, 1) picks, in proportion to the shares.
    pub fn pick(&self, u: f64) -> usize {
        self.pick_weighted(u, &vec![1.0; self.classes.len()])
    }

    /// [`pick`](Self::pick) with each class's share multiplied by its factor.
    pub fn pick_weighted(&self, u: f64, factors: &[f64]) -> usize {
        let total: f64 = self.classes.iter().zip(factors).map(|(c, f)| c.share * f).sum();
        let mut acc = 0.0;
        for (k, (c, f)) in self.classes.iter().zip(factors).enumerate() {
            acc += c.share * f / total;
            if u < acc {
                return k;
            }
        }
        self.classes.len() - 1
    }

    /// The parameter rows (`tiles.len()` × the stack's parameters) of class `class` at the
    /// given (tile, cell) pairs, for generator seed `seed`.
    pub fn parameters<'e>(&self, engine: impl Into<Engine<'e>>, class: usize, seed: u64, tiles: &[u64], cells: &[u64]) -> Result<Vec<f32>, String> {
        let n = tiles.len();
        let np = self.stack.len();
        match self.draw(class, seed, tiles, cells) {
            ClassDraw::Rows(rows) => Ok(rows),
            ClassDraw::Kernel { kernel, inputs, outputs } => {
                let batch = PatternBatch { geometry: Geometry::default().repeated(n), inputs, textures: vec![], points_per_group: 1 };
                let out = kernel.run(engine.into(), &batch)?;
                let mut rows = self.stack.defaults().repeat(n);
                for (k, o) in outputs.iter().enumerate() {
                    if let Some(at) = o {
                        for (r, v) in out.column(*at).iter().enumerate() {
                            rows[r * np + k] = *v;
                        }
                    }
                }
                Ok(rows)
            }
        }
    }

    /// The random draws of class `class` at the given (tile, cell) pairs: its parameter rows
    /// themselves (a uniform class), or its graph kernel's input columns (the kernel then
    /// computes them: [`parameters`](Self::parameters) on the host, `wgpu_batch` on a device).
    pub fn draw(&self, class: usize, seed: u64, tiles: &[u64], cells: &[u64]) -> ClassDraw<'_> {
        assert_eq!(tiles.len(), cells.len());
        let c = &self.classes[class];
        let np = self.stack.len();
        let n = tiles.len();
        let class_key = mix64(seed ^ hash_str(&c.name));
        let tile_key = |tile: u64| class_key ^ mix64(tile.wrapping_mul(0x2545_f491_4f6c_dd1d));
        let cell_key = |tile: u64, cell: u64| tile_key(tile) ^ mix64(cell.wrapping_add(0x51ed_27));
        match &c.draw {
            Draw::Uniform => {
                let mut out = Vec::with_capacity(n * np);
                for (&t, &cell) in tiles.iter().zip(cells) {
                    let key = cell_key(t, cell);
                    out.extend(self.stack.parameters().iter().enumerate().map(|(k, p)| p.decode(uplift_base::random_scalar::uniform(key, hash_str(&p.channel), k as u64) as f32)));
                }
                ClassDraw::Rows(out)
            }
            Draw::Graph { kernel, scalars, outputs } => {
                let mut inputs = Columns::zeros(n, kernel.kernel.input_stride);
                for s in scalars {
                    let col = inputs.column_mut(s.column);
                    for (r, x) in col.iter_mut().enumerate() {
                        let key = match s.scope {
                            Scope::Tile => tile_key(tiles[r]),
                            Scope::Cell => cell_key(tiles[r], cells[r]),
                        };
                        *x = s.scalar.draw(key) as f32;
                    }
                }
                ClassDraw::Kernel { kernel, inputs, outputs }
            }
        }
    }
}

/// A class's draws for some (tile, cell) pairs ([`TrainingClasses::draw`]).
pub enum ClassDraw<'a> {
    /// The parameter rows (pairs × the stack's parameters).
    Rows(Vec<f32>),
    /// The class graph's kernel and its input columns; `outputs[k]`: the output column of stack
    /// parameter k, if the class sets it (the stack's default otherwise).
    Kernel { kernel: &'a PreparedKernel, inputs: Columns, outputs: &'a [Option<usize>] },
}

/// Reads one class document (`None`: it defines no `uplift_class`, a stack folder's other
/// document). Errors name the file, line and column.
fn read_class(stack: &Arc<Stack>, name: &str, source: &str, text: &str) -> Result<Option<ReadClass>, String> {
    let text = mtlx::without_includes(text);
    let (doc, diags) = mtlx::read_str(&text, source);
    if let Some(d) = diags.iter().find(|d| d.is_error()) {
        return Err(d.to_string());
    }
    let Some(graph) = doc.top_level().iter().copied().find(|&id| doc.get(id).category == "nodegraph" && doc.get(id).name() == CLASS_GRAPH) else { return Ok(None) };
    let at = |id: mtlx::ElementId| {
        let p = &doc.get(id).pos;
        format!("{source}:{}:{}", p.line, p.column)
    };
    let g = doc.get(graph);
    let share = match g.attr("uplift_share") {
        None => 1.0,
        Some(s) => s.trim().parse::<f64>().ok().filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| format!("{}: `uplift_share` is `{s}`, not a positive number", at(graph)))?,
    };
    let graph = match g.attr("uplift_draw") {
        Some("uniform") => None,
        Some(other) => return Err(format!("{}: `uplift_draw` is `{other}`; the one kind is `uniform`", at(graph))),
        None => {
            let mut declared = Vec::new();
            for id in doc.children_of(graph, "input") {
                let e = doc.get(id);
                let (Some(lo), Some(hi)) = (e.attr("uimin"), e.attr("uimax")) else {
                    return Err(format!("{}: input `{}` is not a random scalar (a float with uimin and uimax)", at(id), e.name()));
                };
                let scalar = RandomScalar::from_attributes(e.name(), e.attr("type").unwrap_or(""), lo, hi, e.attr("uplift_distribution")).map_err(|m| format!("{}: {m}", at(id)))?;
                let scope = match e.attr("uplift_scope") {
                    Some("tile") => Scope::Tile,
                    Some("cell") => Scope::Cell,
                    Some(other) => return Err(format!("{}: `{}` has uplift_scope `{other}`: a class's random scalar is drawn per `tile` or per `cell`", at(id), e.name())),
                    None => return Err(format!("{}: `{}` has no uplift_scope: a class's random scalar is drawn per `tile` or per `cell`", at(id), e.name())),
                };
                declared.push((scalar, scope));
            }
            let stack_inputs = stack.inputs();
            let mut selected = Vec::new();
            for id in doc.children_of(graph, "output") {
                let e = doc.get(id);
                let input = e.name().strip_suffix("_out").and_then(|n| stack_inputs.iter().find(|i| i.name == n));
                match input {
                    Some(i) if e.attr("type") == Some(i.ty.as_str()) => selected.push(format!("{CLASS_GRAPH}/{}", e.name())),
                    Some(i) => return Err(format!("{}: output `{}` is {}; the stack's input takes {}", at(id), e.name(), e.attr("type").unwrap_or("untyped"), i.ty)),
                    None => return Err(format!("{}: output `{}` is not `<input>_out` of an uplift_stack input ({})", at(id), e.name(), stack_inputs.iter().map(|i| i.name.as_str()).collect::<Vec<_>>().join(", "))),
                }
            }
            if selected.is_empty() {
                return Err(format!("{}: class `{name}` sets no stack input (give outputs, or uplift_draw=\"uniform\")", at(graph)));
            }
            let c = stack.compiler().compile_document(doc.clone(), diags, source, &OutputSelection::Named(selected));
            if let Some(d) = c.diagnostics.iter().find(|d| d.is_error()) {
                return Err(d.to_string());
            }
            let kernel = c.kernel.ok_or_else(|| format!("{source}: class `{name}` compiled to no kernel"))?;
            let mut scalars = Vec::new();
            for input in &kernel.inputs {
                let (scalar, scope) = declared.iter().find(|(s, _)| s.name == input.input.name).cloned().ok_or_else(|| format!("{source}: the class kernel reads `{}`, which is not a declared random scalar", input.input.name))?;
                scalars.push(ClassScalar { scalar, scope, column: input.offset });
            }
            let outputs = stack
                .parameters()
                .iter()
                .map(|p| kernel.outputs.iter().find(|o| o.name.rsplit('/').next() == Some(&format!("{}_out", p.input))).map(|o| o.offset + p.component))
                .collect();
            Some((kernel, scalars, outputs))
        }
    };
    Ok(Some(ReadClass { name: name.to_string(), source: source.to_string(), share, graph }))
}

impl TrainingClass {
    /// Whether the class runs a graph (else it draws uniformly).
    pub fn has_graph(&self) -> bool {
        matches!(self.draw, Draw::Graph { .. })
    }

    /// Where its kernel comes from (shipped or built), for a graph class.
    pub fn describe(&self) -> String {
        match &self.draw {
            Draw::Uniform => "uniform in the encoder's ranges".into(),
            Draw::Graph { kernel, .. } => kernel.describe(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use uplift_engines::cpu_engine::CpuEngine;

    #[test]
    fn every_class_stays_in_range_and_is_deterministic() {
        let stack = Stack::builtin();
        let engine = CpuEngine::with_threads(1).unwrap();
        let classes = TrainingClasses::load(&stack, &engine).unwrap();
        assert_eq!(classes.names(), ["haze", "dust", "clearcoat", "inner", "infill"]);
        let cells: Vec<u64> = (0..TILE * TILE).step_by(97).collect();
        let tiles: Vec<u64> = cells.iter().map(|c| c / 13).collect();
        for k in 0..classes.len() {
            let c = classes.get(k);
            assert!(!c.has_graph() || c.describe().starts_with("built-in kernel"), "{}: {}", c.name, c.describe());
            let p = classes.parameters(&engine, k, 7, &tiles, &cells).unwrap();
            assert_eq!(p, classes.parameters(&engine, k, 7, &tiles, &cells).unwrap());
            for row in p.chunks(stack.len()) {
                for (x, spec) in row.iter().zip(stack.parameters()) {
                    assert!(x.is_finite() && *x >= spec.lo - 1e-6 && *x <= spec.hi + 1e-6, "{} {}: {x}", c.name, spec.channel);
                }
            }
        }
    }
}
