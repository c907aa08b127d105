//! The graph IR: a flattened, typed DAG, one value per node output, in a topologically ordered
//! arena. Nodegraphs are already inlined, defaults and geometric properties bound, identity
//! nodes folded and equal values shared. `Graph::dump` is the textual form snapshot tests read.

use crate::arena::{Arena, Handle};
use mtlx::{DataType, SourcePos, Value as Literal};
use std::fmt::Write;
use std::path::PathBuf;

/// A geometric property a kernel receives per shading point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum GeomProp {
    Texcoord,
    PositionObject,
    PositionWorld,
    NormalObject,
    NormalWorld,
    TangentObject,
    TangentWorld,
    BitangentObject,
    BitangentWorld,
}

/// (MaterialX geomprop name, property, WGSL field of `mx_geometry`, type).
pub const GEOMPROPS: [(&str, GeomProp, &str, DataType); 9] = [
    ("UV0", GeomProp::Texcoord, "texcoord", DataType::Vector2),
    ("Pobject", GeomProp::PositionObject, "position_object", DataType::Vector3),
    ("Pworld", GeomProp::PositionWorld, "position_world", DataType::Vector3),
    ("Nobject", GeomProp::NormalObject, "normal_object", DataType::Vector3),
    ("Nworld", GeomProp::NormalWorld, "normal_world", DataType::Vector3),
    ("Tobject", GeomProp::TangentObject, "tangent_object", DataType::Vector3),
    ("Tworld", GeomProp::TangentWorld, "tangent_world", DataType::Vector3),
    ("Bobject", GeomProp::BitangentObject, "bitangent_object", DataType::Vector3),
    ("Bworld", GeomProp::BitangentWorld, "bitangent_world", DataType::Vector3),
];

impl GeomProp {
    pub fn from_name(name: &str) -> Option<GeomProp> {
        GEOMPROPS.iter().find(|g| g.0 == name).map(|g| g.1)
    }

    fn row(self) -> &'static (&'static str, GeomProp, &'static str, DataType) {
        GEOMPROPS.iter().find(|g| g.1 == self).unwrap()
    }

    pub fn name(self) -> &'static str {
        self.row().0
    }

    pub fn field(self) -> &'static str {
        self.row().2
    }

    pub fn data_type(self) -> DataType {
        self.row().3.clone()
    }
}

/// What a value is.
#[derive(Clone, Debug, PartialEq)]
pub enum ValueKind {
    Constant(Literal),
    Geometry(GeomProp),
    /// The kernel's interface input with this index.
    Input(usize),
    /// The kernel's texture binding with this index.
    Texture(usize),
    /// A call of a library function. `geometry` says it receives `mx_geometry` first,
    /// `closure` that it receives the closure context (`mx_closure`, after the geometry).
    Call { function: String, args: Vec<Handle<Value>>, geometry: bool, closure: bool },
    /// One output of a multi-output call.
    Field { base: Handle<Value>, field: String },
}

/// One value of the graph, with the element it came from.
#[derive(Clone, Debug)]
pub struct Value {
    pub kind: ValueKind,
    pub ty: DataType,
    /// Path of the node that produced it (`graph/node`), for dumps and messages.
    pub origin: String,
    pub pos: SourcePos,
}

/// An input of the kernel's interface (a nodegraph `<input>` left free), varying per point.
#[derive(Clone, Debug)]
pub struct InterfaceInput {
    pub name: String,
    pub ty: DataType,
    /// Its value in the document (or the type's zero), used when a caller gives none.
    pub default: Vec<f32>,
    pub pos: SourcePos,
}

/// A texture the kernel reads: the resolved file and its colour space.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureBinding {
    pub path: PathBuf,
    /// The `colorspace` in scope for the filename input (recorded; the runtime converts).
    pub colorspace: Option<String>,
    pub pos: SourcePos,
}

/// A requested output of the kernel.
#[derive(Clone, Debug)]
pub struct GraphOutput {
    pub name: String,
    pub ty: DataType,
    pub value: Handle<Value>,
    pub pos: SourcePos,
}

/// A flattened, typed graph ready for lowering.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    pub values: Arena<Value>,
    pub inputs: Vec<InterfaceInput>,
    pub textures: Vec<TextureBinding>,
    pub outputs: Vec<GraphOutput>,
    /// Files that texture nodes name but that do not exist (as written, with their position):
    /// those nodes return their `default`, as MaterialX does. Graphs are built from their
    /// outputs up, so these are files the built outputs would read.
    pub missing_files: Vec<(String, SourcePos)>,
}

impl Graph {
    /// Removes values no output depends on, and interface inputs and textures no value uses,
    /// renumbering everything in order.
    pub fn remove_dead(&mut self) {
        let n = self.values.len();
        let mut live = vec![false; n];
        for o in &self.outputs {
            live[o.value.index()] = true;
        }
        for i in (0..n).rev() {
            if !live[i] {
                continue;
            }
            match &self.values[Handle::from_index(i)].kind {
                ValueKind::Call { args, .. } => args.iter().for_each(|a| live[a.index()] = true),
                ValueKind::Field { base, .. } => live[base.index()] = true,
                _ => {}
            }
        }
        let mut remap = vec![None; n];
        let mut values = Arena::default();
        let mut input_remap = vec![None; self.inputs.len()];
        let mut inputs = Vec::new();
        let mut texture_remap = vec![None; self.textures.len()];
        let mut textures = Vec::new();
        for (h, v) in self.values.iter() {
            if !live[h.index()] {
                continue;
            }
            let mut v = v.clone();
            match &mut v.kind {
                ValueKind::Call { args, .. } => args.iter_mut().for_each(|a| *a = remap[a.index()].unwrap()),
                ValueKind::Field { base, .. } => *base = remap[base.index()].unwrap(),
                ValueKind::Input(i) => {
                    *i = *input_remap[*i].get_or_insert_with(|| {
                        inputs.push(self.inputs[*i].clone());
                        inputs.len() - 1
                    })
                }
                ValueKind::Texture(t) => {
                    *t = *texture_remap[*t].get_or_insert_with(|| {
                        textures.push(self.textures[*t].clone());
                        textures.len() - 1
                    })
                }
                _ => {}
            }
            remap[h.index()] = Some(values.append(v));
        }
        for o in &mut self.outputs {
            o.value = remap[o.value.index()].unwrap();
        }
        // Interface inputs in document order, whatever order they were first used in.
        let mut order: Vec<usize> = (0..inputs.len()).collect();
        order.sort_by_key(|&i| (inputs[i].pos.file.clone(), inputs[i].pos.line, inputs[i].pos.column));
        let mut rank = vec![0; inputs.len()];
        for (r, &i) in order.iter().enumerate() {
            rank[i] = r;
        }
        for (_, v) in values.iter_mut() {
            if let ValueKind::Input(i) = &mut v.kind {
                *i = rank[*i];
            }
        }
        self.inputs = order.iter().map(|&i| inputs[i].clone()).collect();
        self.values = values;
        self.textures = textures;
    }

    /// The textual form of the graph: one line per value, then interface and outputs.
    pub fn dump(&self) -> String {
        let mut s = String::new();
        for (i, inp) in self.inputs.iter().enumerate() {
            let d: Vec<String> = inp.default.iter().map(|x| mtlx::value::format_float(*x)).collect();
            let _ = writeln!(s, "input   #{i} {}: {} = {}", inp.name, inp.ty, d.join(", "));
        }
        for (i, t) in self.textures.iter().enumerate() {
            let cs = t.colorspace.as_deref().unwrap_or("-");
            let file = t.path.file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default();
            let _ = writeln!(s, "texture #{i} {file} colorspace={cs}");
        }
        for (h, v) in self.values.iter() {
            let rhs = match &v.kind {
                ValueKind::Constant(l) => format!("const {}", l.to_mtlx_string()),
                ValueKind::Geometry(g) => format!("geom {}", g.name()),
                ValueKind::Input(i) => format!("input #{i}"),
                ValueKind::Texture(t) => format!("texture #{t}"),
                ValueKind::Call { function, args, geometry, closure } => {
                    let mut a: Vec<String> = args.iter().map(|a| format!("{a:?}")).collect();
                    if *closure {
                        a.insert(0, "cl".into());
                    }
                    if *geometry {
                        a.insert(0, "geom".into());
                    }
                    format!("call {function}({})", a.join(", "))
                }
                ValueKind::Field { base, field } => format!("field {base:?}.{field}"),
            };
            let _ = writeln!(s, "{h:?}: {} = {rhs}    ; {}", v.ty, v.origin);
        }
        for o in &self.outputs {
            let _ = writeln!(s, "output  {}: {} = {:?}", o.name, o.ty, o.value);
        }
        s
    }
}
