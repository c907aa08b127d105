//! Rendering and evaluation (docs/render.md): the preview-ball path tracer with environment and
//! BSDF importance sampling combined by MIS (`integrator`), its environments (`environment`),
//! geometry and camera (`scene`; glTF meshes behind a BVH in `mesh`), the material data it reads (`surface`) and the two ways of
//! shading it — the compiled reference kernels or the neural decoder (`shading`) — the AgX
//! display transform (`tonemap`; Blender's exact AgX for exported frames in `agx_blender`) and the image metrics, FLIP and PSNR (`metrics`); what the
//! sampling decoder buys in variance (`sampler_error`); the camera orbit and intrinsic frames
//! of `uplift export` (`orbit`, `intrinsics`).

pub mod agx_blender;
pub mod environment;
pub mod evaluation;
pub mod furnace;
pub mod glint;
pub mod integrator;
pub mod intrinsics;
pub mod material;
pub mod mesh;
pub mod mtlx_material;
pub mod orbit;
pub mod metrics;
pub mod sampler_error;
pub mod scene;
pub mod shading;
pub mod surface;
pub mod surface_model;
pub mod image_files;
pub mod tonemap;
