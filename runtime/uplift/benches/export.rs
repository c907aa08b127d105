//! Benchmark of `uplift export` and `uplift project` (docs/export.md): frames per second of the
//! intrinsic modalities (one ray per pixel centre, every buffer) and of shaded frames (the path
//! tracer at `--spp`, 3 bounces, reference stack), at 512² by default, and texels per second of
//! the projection of 16 frames into a 512² texture; then the wall time of one whole export
//! (16 frames, intrinsic and shaded, files written), the figure issue 28 sets at ≤ 60 s for
//! 64 spp on 2 cores.
//!
//! `cargo bench -p uplift --bench export` (options after `--`: `--size N`, `--spp S`,
//! `--frames F`, `--full` to time the whole export at the given spp; without it, one shaded
//! frame is timed and the export's time is projected from the per-frame figures).
use std::path::Path;
use std::time::Instant;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::stack::Stack;
use uplift_render::environment::Environment;
use uplift_render::integrator::{render, RenderOptions};
use uplift_render::intrinsics::{colour_texture, intrinsic_frame};
use uplift_render::orbit::{orbit, OrbitOptions};
use uplift_render::shading::{Model, Shading};
use uplift_render::surface::SurfaceTextures;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let value = |name: &str, default: usize| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).map_or(default, |v| v.parse().expect("a number"));
    let (size, spp, frames, full) = (value("--size", 512), value("--spp", 64), value("--frames", 16), args.iter().any(|a| a == "--full"));
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    // A UV sphere with a constant fitted-like material: 6 latent values, the stack's defaults.
    let root = std::env::temp_dir().join(format!("uplift-export-bench-{}", std::process::id()));
    let mesh_path = uplift_enhance::uv_sphere::write_uv_sphere_gltf(&root, 96, 48).unwrap();
    let asset = uplift_enhance::gltf_input::load(&mesh_path).unwrap();
    let mesh = uplift_render::mesh::Mesh::new(asset.world_triangles()).unwrap();
    let stack = Stack::builtin();
    let mut params = stack.defaults();
    params[stack.index_of("coat_weight").unwrap()] = 1.0;
    let surface = SurfaceTextures::uniform(&params, [0.5, 0.3, 0.2], Some(&[0.5; 6]));
    let base = colour_texture(1, 1, vec![0.5, 0.3, 0.2]);
    let cams = orbit(&OrbitOptions { frames, width: size, height: size, ..Default::default() }).unwrap();
    println!("export benchmark: {size}² frames, {threads} threads, {}", uplift_simd_isa());

    let start = Instant::now();
    for c in &cams {
        std::hint::black_box(intrinsic_frame(&mesh, &surface, &base, c, size, size));
    }
    let intrinsic = frames as f64 / start.elapsed().as_secs_f64();
    println!("intrinsic modalities (buffers, not files)   {intrinsic:>8.2} frames/s");

    let shading = Shading::new(CpuEngine::with_threads(threads).unwrap(), &stack, Model::Reference).unwrap();
    let env = Environment::studio();
    let shade = |c: &uplift_render::scene::Camera, spp: usize| render(&mesh, &env, &surface, &shading, &RenderOptions { width: size, height: size, spp, bounces: 3, camera: Some(*c), ..Default::default() }, None).unwrap();
    let start = Instant::now();
    shade(&cams[0], spp);
    let shaded = 1.0 / start.elapsed().as_secs_f64();
    println!("shaded frame, {spp} spp, 3 bounces            {shaded:>8.3} frames/s ({:.0} k paths/s)", shaded * (size * size * spp) as f64 / 1e3);

    // Projection: 16 exported frames of a fitted 512² material back into a 512² texture.
    let material = root.join("material");
    fitted_material(&material, &stack);
    let exported = root.join("exported");
    let o = uplift::export::ExportOptions { orbit: OrbitOptions { frames, width: size, height: size, ..Default::default() }, spp: 1, bounces: 0, exposure: 1.0, threads, neural: None, latent_affine: uplift::export::UNIT_LATENT_AFFINE, mp4: false };
    uplift::export::export_asset(&material, &mesh, &env, &stack, &exported, &o, false).unwrap();
    let start = Instant::now();
    let s = uplift::project::project(&exported, &asset, &stack, &root.join("projected"), &uplift::project::ProjectOptions { width: 512, height: 512, material: 0, fill: None }).unwrap();
    let secs = start.elapsed().as_secs_f64();
    println!("projection of {frames} frames into 512²       {:>8.0} k texels/s ({:.2} s; {} of {} chart texels seen)", s.texels as f64 / secs / 1e3, secs, s.projected, s.in_charts);
    if full {
        let start = Instant::now();
        for c in &cams {
            std::hint::black_box(intrinsic_frame(&mesh, &surface, &base, c, size, size));
            std::hint::black_box(shade(c, spp));
        }
        println!("one export: {frames} frames at {spp} spp: {:.1} s (target ≤ 60 s)", start.elapsed().as_secs_f64());
    } else {
        println!("one export, projected from the figures above: {frames} frames at {spp} spp ≈ {:.1} s (target ≤ 60 s; --full times it)", frames as f64 * (1.0 / intrinsic + 1.0 / shaded));
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// A fitted 512² material (a constant Type 2 input: one texel group, fitted in a few steps).
fn fitted_material(dir: &Path, stack: &std::sync::Arc<Stack>) {
    use uplift_enhance::pbr_input::{PbrChannel, PbrMaterial, Surface};
    let material = PbrMaterial { name: "bench".into(), source: "bench".into(), base_color: PbrChannel::Constant(vec![0.6, 0.35, 0.2]), roughness: PbrChannel::Constant(vec![0.4]), metalness: PbrChannel::Constant(vec![0.0]), normal_map: None, surface: Surface::Plane };
    let options = uplift_enhance::pipeline::EnhanceOptions { kind: Some(uplift_enhance::rules::EnhancementType::new(2).unwrap()), rules: Vec::new(), seed: 1, resolution: Some((512, 512)), mask_size: 64, glints: false, stack: stack.clone(), rule_options: Vec::new() };
    uplift_enhance::pipeline::enhance(&material, &options, dir, &CpuEngine::new().unwrap()).unwrap();
    let folder = uplift_material::MaterialFolder::open(dir).unwrap();
    let p = folder.read_params(stack).unwrap();
    let model = uplift_neural::weights::load_model(Path::new(uplift_neural::weights::SHIPPED_DECODER), stack).unwrap();
    let g = uplift_neural::datagen::DataGenerator::new(CpuEngine::new().unwrap(), stack, uplift_neural::datagen::ClassMix::All, 1).unwrap();
    let o = uplift_neural::fit::FitOptions { steps: 5, threads: 2, ..Default::default() };
    let r = uplift_neural::fit::fit_material(&model, &g, &p.params, p.diffuse.as_deref(), p.width, p.height, &o, false).unwrap();
    folder.write_latents(&r.latent_image()).unwrap();
    folder.write_fit(&r.record(Path::new(uplift_neural::weights::SHIPPED_DECODER), &o)).unwrap();
}

fn uplift_simd_isa() -> String {
    if std::is_x86_feature_detected!("avx512f") { "AVX-512".into() } else if std::is_x86_feature_detected!("avx2") { "AVX2".into() } else { "no AVX2".into() }
}
