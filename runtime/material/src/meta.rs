//! `meta.json`: what made an enhanced material — the enhancement Type and rule, the seed, the
//! PBR source, the bake resolution and object size, the frame of the baked normals, the rule's
//! drawn scalars and its masks — as a typed serde struct with a format version.

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};

/// The meta.json format this build writes. Format 0 is a file written before the field existed
/// (the same fields otherwise).
pub const META_FORMAT: u32 = 1;

/// The frame params.exr's normals are expressed in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NormalSpace {
    /// The unit square's frame: tangent +X, bitangent −Z, normal +Y (texture inputs; applied
    /// as a tangent-space normal on any surface).
    #[default]
    Plane,
    /// World space of the glTF asset the material was baked on.
    World,
}

/// One procedural mask of the rule: its PNG (relative to the folder) and seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaskRecord {
    pub file: String,
    pub seed: u64,
}

/// meta.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// [`META_FORMAT`] when written by this build; 0 for files that predate the field.
    #[serde(default)]
    pub format: u32,
    /// The enhancement Type, 0–5.
    #[serde(rename = "type")]
    pub kind: u32,
    /// The rule document, relative to the repository (`mtlx/rules/type0_haze.mtlx`).
    pub rule: String,
    /// The material's seed (its rule scalars and masks derive from it).
    pub seed: u64,
    /// Where the PBR material came from (a file, a folder, a glTF material).
    pub source: String,
    pub name: String,
    /// Bake resolution, width and height in texels.
    pub resolution: [usize; 2],
    /// The object's size (bounding-box diagonal; √2 for the unit square).
    pub object_size: f32,
    /// Absent in files older than normal maps: `plane`.
    #[serde(default)]
    pub normal_space: NormalSpace,
    /// The rule's drawn random scalars, in the rule's order.
    pub scalars: IndexMap<String, f32>,
    /// The rule's masks by the input they feed.
    pub masks: IndexMap<String, MaskRecord>,
    /// The uplift version that wrote it.
    pub uplift: String,
    /// Glints on the stack (`uplift enhance --glints`): the `uplift_glint` node's inputs.
    /// Absent without glints (and in files that predate them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glint: Option<GlintRecord>,
}

/// The drawn inputs of a material's `uplift_glint` node (mtlx/libraries/uplift, glint.wgsl).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlintRecord {
    pub density: f32,
    pub size: f32,
    pub angle: f32,
    pub spread: f32,
    pub strength: f32,
    pub seed: f32,
}

impl GlintRecord {
    /// (input name, value) in the nodedef's order.
    pub fn inputs(&self) -> [(&'static str, f32); 6] {
        [("density", self.density), ("size", self.size), ("angle", self.angle), ("spread", self.spread), ("strength", self.strength), ("seed", self.seed)]
    }
}
