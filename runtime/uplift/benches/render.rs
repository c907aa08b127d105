//! Preview-ball rendering speed (issue 7): paths per second for the reference material (the
//! `uplift_stack` kernels) and the neural material (the decoder), on the CPU engine and the
//! wgpu engine, 192² at 16 spp with MIS and 2 bounces under the studio environment; and the
//! same ball tessellated into 128 × 64 quads, rendered through the BVH (CPU, reference).
//! `cargo bench -p uplift --bench render`.

use std::time::Instant;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_render::environment::Environment;
use uplift_render::integrator::{render, RenderOptions};
use uplift_enhance::gltf_input::WorldTriangle;
use uplift_render::mesh::Mesh;
use uplift_render::scene::{Scene, Sphere};
use uplift_render::shading::{Model, Shading};
use uplift_render::surface::SurfaceTextures;
use uplift_engines::wgpu_engine::WgpuEngine;

fn main() {
    let values = [
        ("reflectivity.R", 0.8), ("reflectivity.G", 0.6), ("reflectivity.B", 0.5), ("edge_color.R", 1.0), ("edge_color.G", 1.0), ("edge_color.B", 1.0),
        ("metalness", 0.0), ("core_roughness", 0.2), ("haze_roughness", 0.5), ("haze_weight", 0.3), ("specular_ior", 1.5), ("fuzz_weight", 0.3),
        ("fuzz_thickness", 0.5), ("coat_weight", 0.5), ("coat_ior", 1.5), ("inner_weight", 0.0), ("inner_thickness", 0.5), ("scatter_color.R", 0.5),
        ("scatter_color.G", 0.5), ("scatter_color.B", 0.5), ("subcutaneous_weight", 0.0), ("subcutaneous_roughness", 0.64),
    ];
    let stack = uplift_engines::stack::Stack::builtin();
    let mut params = stack.defaults();
    for (name, v) in values {
        params[stack.index_of(name).expect("a stack parameter")] = v;
    }
    let surface = SurfaceTextures::uniform(&params, [0.5, 0.35, 0.25], Some(&[0.5, 0.4, 0.6, 0.3, 0.2, 0.5]));
    let decoder = uplift_neural::weights::load_model(std::path::Path::new(uplift_neural::weights::SHIPPED_DECODER), &uplift_engines::stack::Stack::builtin()).unwrap().decoder;
    let env = Environment::studio();
    let o = RenderOptions { width: 192, height: 192, spp: 16, bounces: 2, ..Default::default() };
    let mut engines: Vec<(&str, &str, Shading)> = vec![
        ("CPU", "reference", Shading::new(CpuEngine::new().unwrap(), &uplift_engines::stack::Stack::builtin(), Model::Reference).unwrap()),
        ("CPU", "neural", Shading::new(CpuEngine::new().unwrap(), &uplift_engines::stack::Stack::builtin(), Model::Neural(decoder.clone())).unwrap()),
    ];
    match (WgpuEngine::new(), WgpuEngine::new()) {
        (Ok(a), Ok(b)) => {
            engines.push(("wgpu", "reference", Shading::new_wgpu(a, &uplift_engines::stack::Stack::builtin(), Model::Reference).unwrap()));
            engines.push(("wgpu", "neural", Shading::new_wgpu(b, &uplift_engines::stack::Stack::builtin(), Model::Neural(decoder)).unwrap()));
        }
        (Err(e), _) | (_, Err(e)) => println!("wgpu engine unavailable ({e}); CPU only"),
    }
    println!("preview ball {}×{} at {} spp, MIS, {} bounces, studio environment", o.width, o.height, o.spp, o.bounces);
    println!("| engine | material | seconds | paths/s | shading points/s |");
    println!("|---|---|---|---|---|");
    for (engine, material, shading) in &engines {
        // One warm-up pass, then the measured render.
        render(&Sphere::preview(), &env, &surface, shading, &RenderOptions { spp: 1, ..o.clone() }, None).unwrap();
        let t = Instant::now();
        let img = render(&Sphere::preview(), &env, &surface, shading, &o, None).unwrap();
        let s = t.elapsed().as_secs_f64();
        let paths = (o.width * o.height * o.spp) as f64;
        let hits: f64 = img.coverage.iter().map(|&c| c as f64).sum::<f64>() * o.spp as f64;
        println!("| {engine} | {material} | {s:.2} | {:.0} k | {:.0} k |", paths / s / 1e3, hits / s / 1e3);
    }
    let mesh = Mesh::new(uv_sphere(128, 64)).unwrap();
    let shading = &engines[0].2;
    let scene: &dyn Scene = &mesh;
    render(scene, &env, &surface, shading, &RenderOptions { spp: 1, ..o.clone() }, None).unwrap();
    let t = Instant::now();
    let img = render(scene, &env, &surface, shading, &o, None).unwrap();
    let s = t.elapsed().as_secs_f64();
    let hits: f64 = img.coverage.iter().map(|&c| c as f64).sum::<f64>() * o.spp as f64;
    println!("| CPU, {}-triangle mesh | reference | {s:.2} | {:.0} k | {:.0} k |", mesh.triangle_count(), (o.width * o.height * o.spp) as f64 / s / 1e3, hits / s / 1e3);
}

/// The unit ball as `nu` × `nv` quads (the pole rows as triangles).
fn uv_sphere(nu: usize, nv: usize) -> Vec<WorldTriangle> {
    use std::f32::consts::{PI, TAU};
    let vertex = |i: usize, j: usize| {
        let (theta, phi) = (PI * j as f32 / nv as f32, TAU * i as f32 / nu as f32);
        let (st, ct) = if j == 0 || j == nv { (0.0, if j == 0 { 1.0 } else { -1.0 }) } else { (theta.sin(), theta.cos()) };
        ([st * phi.sin(), ct, st * phi.cos()], [i as f32 / nu as f32, j as f32 / nv as f32], [phi.cos(), 0.0, -phi.sin()])
    };
    let mut out = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            for tri in [[(i, j), (i, j + 1), (i + 1, j + 1)], [(i, j), (i + 1, j + 1), (i + 1, j)]] {
                let v = tri.map(|(a, b)| vertex(a, b));
                out.push(WorldTriangle { position: v.map(|x| x.0), normal: v.map(|x| x.0), tangent: v.map(|x| x.2), uv: v.map(|x| x.1) });
            }
        }
    }
    out
}
