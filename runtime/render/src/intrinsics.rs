//! Intrinsic frames of an object for generative models (paper §5.2, `uplift export`): per
//! pixel, from one ray through the pixel centre (no filtering, no noise), the coverage mask,
//! depth along the view axis, the world position, the shading normal in world and in camera
//! space (OpenGL axes: x right, y up, z towards the viewer), the base colour and the fitted
//! latent at the hit's texture coordinates (bilinear, as the renderer reads them). Pixels the
//! object does not cover hold zeros.

use crate::scene::{dot, Camera, Scene, Vec3};
use crate::surface::SurfaceTextures;
use rayon::prelude::*;

/// One frame's intrinsic buffers (row-major, row 0 at the top).
pub struct IntrinsicFrame {
    pub width: usize,
    pub height: usize,
    pub mask: Vec<bool>,
    /// Distance along the camera's view axis.
    pub depth: Vec<f32>,
    pub position: Vec<Vec3>,
    pub normal_world: Vec<Vec3>,
    pub normal_camera: Vec<Vec3>,
    /// Linear RGB base colour.
    pub base_color: Vec<[f32; 3]>,
    /// `latents` values per pixel.
    pub latent: Vec<f32>,
    pub latents: usize,
}

/// The frame seen by `camera`; `base_color` is a texture read for its diffuse colour (see
/// [`colour_texture`]).
pub fn intrinsic_frame(scene: &dyn Scene, surface: &SurfaceTextures, base_color: &SurfaceTextures, camera: &Camera, width: usize, height: usize) -> IntrinsicFrame {
    let k = surface.latents;
    let pixels: Vec<Option<(f32, Vec3, Vec3, [f32; 3], Vec<f32>)>> = (0..width * height)
        .into_par_iter()
        .map(|p| {
            let (x, y) = ((p % width) as f32 + 0.5, (p / width) as f32 + 0.5);
            let (o, d) = camera.ray(x, y, width, height);
            let hit = scene.intersect(o, d)?;
            let depth = hit.t * dot(d, camera.forward);
            let s = surface.lookup(hit.uv);
            Some((depth, hit.position, hit.frame[2], base_color.lookup(hit.uv).diffuse, s.latent().to_vec()))
        })
        .collect();
    let n = width * height;
    let mut f = IntrinsicFrame {
        width,
        height,
        mask: vec![false; n],
        depth: vec![0.0; n],
        position: vec![[0.0; 3]; n],
        normal_world: vec![[0.0; 3]; n],
        normal_camera: vec![[0.0; 3]; n],
        base_color: vec![[0.0; 3]; n],
        latent: vec![0.0; n * k],
        latents: k,
    };
    for (p, v) in pixels.into_iter().enumerate() {
        if let Some((depth, position, normal, colour, latent)) = v {
            f.mask[p] = true;
            f.depth[p] = depth;
            f.position[p] = position;
            f.normal_world[p] = normal;
            f.normal_camera[p] = [dot(normal, camera.right), dot(normal, camera.up), -dot(normal, camera.forward)];
            f.base_color[p] = colour;
            f.latent[p * k..(p + 1) * k].copy_from_slice(&latent);
        }
    }
    f
}

/// An RGB texture (linear values, row-major, row 0 at the top) as surface textures whose
/// diffuse colour is the texture: read with the renderer's own bilinear lookup and uv
/// convention.
pub fn colour_texture(width: usize, height: usize, rgb: Vec<f32>) -> SurfaceTextures {
    SurfaceTextures { width, height, parameters: 0, values: rgb, has_latents: false, latents: 0, normals: Vec::new(), normal_space: crate::surface::NormalSpace::Plane, glint: None }
}
