//! Neural materials (paper §4, lobes.md §3.3–4; docs/neural.md), over the parameters of
//! `uplift_engines::stack`: direction features (`features`), training data generated on the fly from the compiled
//! `uplift_stack` kernels (`classes`, `datagen`), the hand-written networks and their training
//! (`mlp`, `model`, `loss`, `adam`, `trainer`), weights as safetensors (`weights`), held-out
//! errors (`evaluate`), per-material latent fitting (`fit`) and its energy bound (`energy_bound`), inference (`inference`; the
//! shipped decoder's generated Rust in `shipped_decoder`) and the sampling decoder (`sampler`;
//! its shipped network's generated Rust in `shipped_sampler`), and a decoder's "diffuse" latent
//! (`diffuse_latent`: the fill of texels no generated view saw).

pub mod adam;
pub mod classes;
pub mod datagen;
pub mod diffuse_latent;
pub mod dense;
pub mod energy_bound;
pub mod evaluate;
pub mod features;
pub mod fit;
pub mod inference;
pub mod loss;
pub mod mlp;
pub mod model;
pub mod sampler;
pub mod shipped_decoder;
pub mod shipped_sampler;
pub mod trainer;
pub mod weights;
pub mod wgpu_batch;
pub mod wgpu_fit;
pub mod wgpu_train;
