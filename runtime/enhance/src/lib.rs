//! `uplift enhance`: turning a PBR material (texture files, a glTF material or a MaterialX
//! material) into an uplifted one by an uplift rule (`mtlx/rules/`): the rule's random scalars,
//! the procedural masks, the inputs' readers, the baked parameter textures and the written
//! document; and a UV-sphere glTF writer (`uv_sphere`), the mesh of the demo's exported orbit.

pub mod masks;
pub mod glints;
pub mod fuzz_entry;
pub mod gltf_input;
pub mod material_writer;
pub mod pbr_input;
pub mod pipeline;
pub mod rule_option;
pub mod rules;
pub mod uv_sphere;
