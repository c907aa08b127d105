//! `uplift demo`, the main job: from a procedural PBR set (`pbr_set`), enhance every material
//! with its Type, fit its latents against the shipped decoder, render reference vs neural
//! preview balls, measure FLIP and the white furnace, and write `report/index.html`
//! (`report`). Each stage shows progress; enhanced and fitted materials already on disk are
//! reused, so an interrupted run resumes.

pub mod orbit_section;
pub mod pbr_set;
pub mod report;

use uplift_material::{MaterialFolder, ParamsImage};
use uplift_neural::weights::load_model;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_enhance::pbr_input::PbrChannel;
use uplift_enhance::pipeline::{enhance, EnhanceOptions};
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::fit::{fit_material, FitOptions};
use uplift_neural::weights::TensorFile;
use uplift_render::environment::Environment;
use uplift_render::evaluation::{evaluate_material, per_type, write_eval_images, TypeRow};
use uplift_render::furnace::{white_furnace, FurnaceOptions};
use uplift_render::image_files::write_png;
use uplift_render::sampler_error::{per_type_ratios, sampler_error, SamplerErrorOptions, SamplerRow, SamplerShadings};
use uplift_render::integrator::RenderOptions;
use uplift_render::shading::{Model, Shading};
use uplift_render::surface::SurfaceTextures;
use uplift_base::atomic_write::write_atomically;
use indicatif::{ProgressBar, ProgressStyle};
use report::{parse_history, render_html, TwinMaterial, Report, ReportMaterial};
use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub struct DemoOptions {
    pub out: PathBuf,
    pub decoder: PathBuf,
    pub per_type: usize,
    pub texture_size: usize,
    pub render_size: usize,
    pub spp: usize,
    pub fit_steps: u64,
    pub seed: u64,
    pub threads: usize,
    /// The sampling decoder's study (image size, spp, the converged render's spp; the seed is
    /// the demo's).
    pub sampler_study: SamplerErrorOptions,
}

/// What the demo measured.
pub struct DemoSummary {
    pub table: Vec<TypeRow>,
    pub materials: usize,
    pub furnace_reference_passed: usize,
    pub furnace_neural_passed: usize,
    /// The iridescent twins of the coated Types, per Type.
    pub iridescent_table: Vec<TypeRow>,
    /// Per Type, the sampling decoder's variance reduction over cosine sampling (empty when the
    /// decoder file has no sampling decoder).
    pub sampler_table: Vec<SamplerRow>,
    pub report: PathBuf,
}

fn bar(len: usize, stage: &str) -> ProgressBar {
    let style = ProgressStyle::with_template("{prefix:>8} [{bar:30}] {pos}/{len} {msg} {elapsed}").expect("valid template").progress_chars("=> ");
    let b = ProgressBar::new(len as u64).with_style(style);
    b.set_prefix(stage.to_string());
    b
}

fn srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let v = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (v * 255.0 + 0.5) as u8
}

/// The PBR input as an image: base colour (sRGB) on the left half, roughness on the right.
fn pbr_image(base: &PbrChannel, rough: &PbrChannel, size: usize) -> Vec<u8> {
    let sample = |c: &PbrChannel, u: f32, v: f32| -> [f32; 3] {
        match c {
            PbrChannel::Pixels(t) => {
                let (w, h) = (t.width as usize, t.height as usize);
                let (x, y) = (((u * w as f32) as usize).min(w - 1), ((v * h as f32) as usize).min(h - 1));
                let p = &t.rgba[4 * (y * w + x)..];
                [p[0], p[1], p[2]]
            }
            PbrChannel::Constant(v) => [v[0], v[v.len().min(2) - 1], v[v.len() - 1]],
            PbrChannel::File { .. } => [0.5; 3],
        }
    };
    let mut px = Vec::with_capacity(size * size * 3);
    for y in 0..size {
        for x in 0..size {
            let half = size / 2;
            let (u, v) = (((x % half.max(1)) as f32 + 0.5) / half.max(1) as f32, (y as f32 + 0.5) / size as f32);
            if x < half {
                px.extend(sample(base, u, v).map(srgb));
            } else {
                px.extend(sample(rough, u, v).map(|r| (r.clamp(0.0, 1.0) * 255.0 + 0.5) as u8));
            }
        }
    }
    px
}

/// Runs the demo.
pub fn run_demo(o: &DemoOptions) -> Result<DemoSummary, String> {
    let start = std::time::Instant::now();
    if o.per_type == 0 || o.texture_size < 4 || o.render_size < 8 || o.spp == 0 || o.fit_steps == 0 {
        return Err("demo: --per-type, --spp and --fit-steps must be at least 1, --texture-size at least 4, --render-size at least 8".into());
    }
    let materials_dir = o.out.join("materials");
    let img_dir = o.out.join("report").join("img");
    std::fs::create_dir_all(&img_dir).map_err(|e| format!("{}: {e}", img_dir.display()))?;
    let set = pbr_set::procedural_set(o.per_type, o.texture_size, o.seed);
    let engine = CpuEngine::with_threads(o.threads)?;
    let stack = uplift_engines::stack::Stack::builtin();

    // 1. Enhance.
    let b = bar(set.len(), "enhance");
    let mut dirs = Vec::new();
    for m in &set {
        let dir = materials_dir.join(&m.material.name);
        b.set_message(m.material.name.clone());
        if !MaterialFolder::is_finished(&dir) {
            let options = EnhanceOptions { kind: Some(m.kind), rules: Vec::new(), seed: o.seed ^ uplift_base::rng::mix64(dirs.len() as u64), resolution: Some((o.texture_size, o.texture_size)), mask_size: o.texture_size.max(64), glints: false, stack: stack.clone(), rule_options: Vec::new() };
            enhance(&m.material, &options, &dir, &engine)?;
        }
        dirs.push(dir);
        b.inc(1);
    }
    b.finish();

    // 2. Fit.
    let model = load_model(&o.decoder, &stack)?;
    let generator = DataGenerator::new(CpuEngine::with_threads(o.threads)?, &stack, ClassMix::All, o.seed)?;
    let fit_options = FitOptions { steps: o.fit_steps, seed: o.seed, threads: o.threads, ..Default::default() };
    // Fits a material folder unless it has its fit already.
    let fit = |dir: &Path| -> Result<(), String> {
        let folder = MaterialFolder::open(dir)?;
        if !folder.has_fit() {
            let ParamsImage { width: w, height: h, params, diffuse, .. } = folder.read_params(&stack)?;
            let r = fit_material(&model, &generator, &params, diffuse.as_deref(), w, h, &fit_options, false)?;
            folder.write_latents(&r.latent_image())?;
            folder.write_fit(&r.record(&o.decoder, &fit_options))?;
        }
        Ok(())
    };
    let b = bar(dirs.len(), "fit");
    for dir in &dirs {
        b.set_message(dir.file_name().unwrap_or_default().to_string_lossy().to_string());
        fit(dir)?;
        b.inc(1);
    }
    b.finish();

    // 3. Render and compare; 4. white furnace.
    let env = Environment::studio();
    let reference = Shading::new(CpuEngine::with_threads(o.threads)?, &stack, Model::Reference)?;
    let neural = Shading::new(CpuEngine::with_threads(o.threads)?, &stack, Model::Neural(model.decoder.clone()))?;
    let ro = RenderOptions { width: o.render_size, height: o.render_size, spp: o.spp, seed: o.seed, ..Default::default() };
    let fo = FurnaceOptions { directions: 512, max_texels: 64, seed: o.seed, ..Default::default() };
    let b = bar(dirs.len(), "evaluate");
    let mut rows = Vec::new();
    for (m, dir) in set.iter().zip(&dirs) {
        let name = m.material.name.clone();
        b.set_message(name.clone());
        let (eval, images) = evaluate_material(dir, &reference, &neural, &env, &ro, 1.0)?;
        write_eval_images(&img_dir, &name, &images, (ro.width, ro.height))?;
        write_png(&img_dir.join(format!("{name}_pbr.png")), &pbr_image(&m.material.base_color, &m.material.roughness, o.render_size), o.render_size, o.render_size)?;
        let surface = SurfaceTextures::load(dir, &stack, true)?;
        let fr = white_furnace(&surface, &reference, &fo)?;
        let fneu = white_furnace(&surface, &neural, &fo)?;
        let fit = MaterialFolder::open(dir)?.read_fit()?;
        rows.push(ReportMaterial {
            eval,
            pbr_image: format!("{name}_pbr.png"),
            reference_image: format!("{name}_reference.png"),
            neural_image: format!("{name}_neural.png"),
            flip_image: format!("{name}_flip.png"),
            furnace_reference: fr.passed,
            furnace_neural: fneu.passed,
            furnace_neural_worst: fneu.worst,
            fit_before: fit.eq3_encoder_only.total,
            fit_after: fit.eq3_fitted.total,
        });
        b.inc(1);
    }
    b.finish();

    // 4b. Glints: the first material of each of Types 0 and 1 again with glints, on the same
    // fitted latents (the rule's draws are the same, so params.exr is too).
    let mut glints = Vec::new();
    for (index, (m, dir)) in set.iter().zip(&dirs).enumerate().filter(|(_, (m, _))| m.kind.index() <= 1) {
        if glints.iter().any(|g: &(usize, usize)| g.1 == m.kind.index()) {
            continue;
        }
        glints.push((index, m.kind.index()));
        let twin = materials_dir.join(format!("{}_glints", m.material.name));
        if !MaterialFolder::is_finished(&twin) || !MaterialFolder::open(&twin)?.has_fit() {
            let options = EnhanceOptions { kind: Some(m.kind), rules: Vec::new(), seed: o.seed ^ uplift_base::rng::mix64(index as u64), resolution: Some((o.texture_size, o.texture_size)), mask_size: o.texture_size.max(64), glints: true, stack: stack.clone(), rule_options: Vec::new() };
            enhance(&m.material, &options, &twin, &engine)?;
            let (from, to) = (MaterialFolder::open(dir)?, MaterialFolder::open(&twin)?);
            if from.read_params(&stack)?.params != to.read_params(&stack)?.params {
                return Err(format!("{}: the glint twin's parameters differ from {}'s", twin.display(), dir.display()));
            }
            to.write_latents(&from.read_latents()?)?;
            to.write_fit(&from.read_fit()?)?;
        }
    }
    let mut glint_rows = Vec::new();
    for (index, _) in glints {
        let name = format!("{}_glints", set[index].material.name);
        let (eval, images) = evaluate_material(&materials_dir.join(&name), &reference, &neural, &env, &ro, 1.0)?;
        write_eval_images(&img_dir, &name, &images, (ro.width, ro.height))?;
        glint_rows.push(TwinMaterial {
            name: name.clone(),
            flip_object: eval.flip_object,
            reference_image: format!("{name}_reference.png"),
            neural_image: format!("{name}_neural.png"),
            flip_image: format!("{name}_flip.png"),
        });
    }

    // 4c. An iridescent clearcoat: every material of the coated Types (2, 3, 5) again with the
    // iridescence option, fitted on its own (the film is two more stack parameters); a median
    // per Type, as for the Types themselves.
    let iridescence = uplift_enhance::rule_option::read_option("iridescence", &stack)?;
    let mut iridescent = Vec::new();
    for (index, m) in set.iter().enumerate().filter(|(_, m)| [2, 3, 5].contains(&m.kind.index())) {
        let twin = materials_dir.join(format!("{}_iridescent", m.material.name));
        if !MaterialFolder::is_finished(&twin) {
            let options = EnhanceOptions { kind: Some(m.kind), rules: Vec::new(), seed: o.seed ^ uplift_base::rng::mix64(index as u64), resolution: Some((o.texture_size, o.texture_size)), mask_size: o.texture_size.max(64), glints: false, stack: stack.clone(), rule_options: vec![iridescence.clone()] };
            enhance(&m.material, &options, &twin, &engine)?;
        }
        fit(&twin)?;
        iridescent.push(twin);
    }
    let (mut iridescent_rows, mut iridescent_evals) = (Vec::new(), Vec::new());
    for twin in &iridescent {
        let name = twin.file_name().unwrap_or_default().to_string_lossy().to_string();
        let (eval, images) = evaluate_material(twin, &reference, &neural, &env, &ro, 1.0)?;
        iridescent_evals.push(eval.clone());
        write_eval_images(&img_dir, &name, &images, (ro.width, ro.height))?;
        iridescent_rows.push(TwinMaterial {
            name: name.clone(),
            flip_object: eval.flip_object,
            reference_image: format!("{name}_reference.png"),
            neural_image: format!("{name}_neural.png"),
            flip_image: format!("{name}_flip.png"),
        });
    }

    // 4d. The sampling decoder (when the decoder file has one): per material, direct-lighting
    // renders at equal spp sampled by it and by the cosine lobe, against a converged render.
    let mut sampler_errors = Vec::new();
    if let Some(sampler) = uplift_neural::weights::load_sampler(&o.decoder)? {
        let shadings = SamplerShadings::new(&stack, &model.decoder, &sampler, o.threads)?;
        let so = SamplerErrorOptions { seed: o.seed, ..o.sampler_study };
        let b = bar(dirs.len(), "sampler");
        for (m, dir) in set.iter().zip(&dirs) {
            b.set_message(m.material.name.clone());
            let surface = SurfaceTextures::load(dir, &stack, true)?;
            sampler_errors.push((m.kind.index(), sampler_error(&surface, &env, &shadings, &so)?));
            b.inc(1);
        }
        b.finish();
    }

    // 4e. Data for generative models: the first material's orbit on a UV sphere (export) and its
    // own frames projected back (project), when the decoder file has a sampling decoder (the
    // projected material renders with it).
    let mut orbit = None;
    if let Some(sampler) = uplift_neural::weights::load_sampler(&o.decoder)? {
        let shading = Shading::new(CpuEngine::with_threads(o.threads)?, &stack, Model::Neural(model.decoder.clone()))?.with_sampler(sampler)?;
        let b = bar(1, "export");
        let name = set[0].material.name.clone();
        orbit = Some(orbit_section::orbit_section(&dirs[0], &name, &o.out, &img_dir, &stack, &shading, o.render_size.clamp(96, 128), o.texture_size.max(64), o.spp, o.seed, o.threads)?);
        b.inc(1);
        b.finish();
    }

    // 5. Report.
    let evals: Vec<_> = rows.iter().map(|r| r.eval.clone()).collect();
    let table = per_type(&evals);
    let weights = TensorFile::read(&o.decoder)?;
    let history = weights.metadata.get("history").map(|h| parse_history(h)).unwrap_or_default();
    let summary = DemoSummary {
        table: table.clone(),
        materials: rows.len(),
        furnace_reference_passed: rows.iter().filter(|r| r.furnace_reference).count(),
        furnace_neural_passed: rows.iter().filter(|r| r.furnace_neural).count(),
        iridescent_table: per_type(&iridescent_evals),
        sampler_table: per_type_ratios(&sampler_errors),
        report: o.out.join("report").join("index.html"),
    };
    let report = Report {
        materials: rows,
        glints: glint_rows,
        iridescent: iridescent_rows,
        iridescent_table: summary.iridescent_table.clone(),
        sampler_table: summary.sampler_table.clone(),
        orbit,
        sampler_settings: format!("{}² direct lighting at {} spp against the stack sampler's {} spp", o.sampler_study.size, o.sampler_study.spp, o.sampler_study.converged_spp),
        table,
        history,
        decoder: weights.metadata.get("command").cloned().unwrap_or_else(|| o.decoder.display().to_string()),
        settings: format!(
            "{} procedural PBR materials per Type ({}² textures, seed {}), fitted with {} Adam steps; preview balls {}² at {} spp under the built-in studio environment, AgX; FLIP: LDR-FLIP at 67 pixels per degree.",
            o.per_type, o.texture_size, o.seed, o.fit_steps, o.render_size, o.spp
        ),
        seconds: start.elapsed().as_secs_f64(),
    };
    write_atomically(&summary.report, render_html(&report).as_bytes()).map_err(|e| format!("{}: {e}", summary.report.display()))?;
    Ok(summary)
}

/// Where the demo's report is under `out`.
pub fn report_path(out: &Path) -> PathBuf {
    out.join("report").join("index.html")
}
