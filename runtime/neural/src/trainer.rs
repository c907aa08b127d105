//! Universal training (paper §4.2–4.3, lobes.md §4.3): encoder and decoder trained together on
//! generated batches with Eq. 3, latent jitter ±0.005 and Adam with cosine learning-rate decay.
//! Data-parallel: a batch is split into one contiguous slice per thread, each slice runs
//! single-threaded GEMMs into its own gradient buffers, and the sums feed one Adam step. Every
//! random number is a function of (seed, step, row), so a run resumed from its checkpoint
//! (written atomically every `checkpoint_every` steps) ends bit-identical to an uninterrupted one.

use crate::adam::{cosine_lr, Adam};
use crate::datagen::{ClassMix, DataGenerator, TrainingBatch};
use crate::loss::{LossParts, LossWeights};
use crate::model::{ModelWorkspace, NeuralModel, Slice};
use crate::weights::TensorFile;
use uplift_engines::stack::Stack;
use uplift_base::rng::mix64;
use std::path::{Path, PathBuf};

/// How to train.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainOptions {
    pub steps: u64,
    pub batch: usize,
    pub seed: u64,
    pub lr_start: f64,
    pub lr_end: f64,
    /// Half-width of the uniform latent jitter.
    pub jitter: f32,
    pub threads: usize,
    pub mix: ClassMix,
    pub checkpoint_every: u64,
    /// Steps per loss record (the training curve).
    pub log_every: u64,
    /// Stop at this step with a checkpoint (a time-boxed run; the next run resumes).
    pub stop_after: Option<u64>,
    /// Start from this weights file's encoder and decoder instead of a fresh initialisation (a
    /// fine-tune; Adam's moments start at zero).
    pub init: Option<std::path::PathBuf>,
    /// The training views' distribution (recorded; the generator draws them).
    pub views: super::datagen::ViewDistribution,
    /// The latent width; `None`: the `init` file's, or the paper's 6 ([`crate::model::LATENT`]).
    /// Wider than `init`'s: its latent is widened (`weights::widen_latent`).
    pub latent: Option<usize>,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions {
            steps: 1000,
            batch: 16384,
            seed: 1,
            lr_start: 1e-3,
            lr_end: 1e-5,
            jitter: 0.005,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            mix: ClassMix::All,
            checkpoint_every: 200,
            log_every: 20,
            stop_after: None,
            init: None,
            views: super::datagen::ViewDistribution::Cosine,
            latent: None,
        }
    }
}

/// One point of the training curve: mean losses over `log_every` steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LossRecord {
    pub step: u64,
    pub loss: LossParts,
    pub lr: f32,
    pub seconds: f64,
}

/// The training state: networks, optimiser, position and curve.
#[derive(Clone, Debug)]
pub struct TrainState {
    pub model: NeuralModel<f32>,
    pub adam_enc: Adam,
    pub adam_dec: Adam,
    pub step: u64,
    pub history: Vec<LossRecord>,
    /// Wall time spent training so far (over resumptions).
    pub seconds: f64,
    /// The losses summed over the steps since the last history record, and their count: kept
    /// in checkpoints, so that a run resumed between two records records the same means.
    pub window: (LossParts, u64),
}

impl TrainState {
    /// A fresh state for a stack of `parameters` parameters and a latent of `latent` values.
    pub fn new(parameters: usize, latent: usize, seed: u64) -> TrainState {
        let model = NeuralModel::<f32>::new(parameters, latent, seed);
        TrainState { adam_enc: Adam::new(model.encoder.params.len()), adam_dec: Adam::new(model.decoder.params.len()), model, step: 0, history: Vec::new(), seconds: 0.0, window: (LossParts::default(), 0) }
    }
}

/// Per-thread buffers, reused across steps.
#[derive(Default)]
pub struct StepBuffers {
    slices: Vec<(ModelWorkspace<f32>, Vec<f32>, Vec<f32>)>,
    jitter: Vec<f32>,
}

/// The latent jitter of `values` latent values (rows × the latent width) at `step`: uniform in ±`half`.
pub fn jitter(seed: u64, step: u64, values: usize, half: f32, out: &mut Vec<f32>) {
    out.clear();
    let key = mix64(seed ^ 0x6a69_7474_6572) ^ mix64(step);
    out.extend((0..values).map(|k| {
        let u = ((mix64(key.wrapping_add(k as u64)) >> 40) as f32) / (1u64 << 24) as f32;
        (2.0 * u - 1.0) * half
    }));
}

/// One training step on `batch`: forward, Eq. 3, backward over `threads` slices, Adam.
pub fn train_step(state: &mut TrainState, batch: &TrainingBatch, opts: &TrainOptions, buf: &mut StepBuffers) -> LossParts {
    let rows = batch.rows;
    let threads = opts.threads.clamp(1, rows.max(1));
    let latent = state.model.latent();
    jitter(opts.seed, state.step, rows * latent, opts.jitter, &mut buf.jitter);
    let (ne, nd) = (state.model.encoder.params.len(), state.model.decoder.params.len());
    let np = state.model.encoder.shape.widths[0];
    buf.slices.resize_with(threads, || (ModelWorkspace::default(), Vec::new(), Vec::new()));
    let per = rows.div_ceil(threads);
    let model = &state.model;
    let jit = &buf.jitter;
    let parts: Vec<LossParts> = std::thread::scope(|scope| {
        let handles: Vec<_> = buf
            .slices
            .iter_mut()
            .enumerate()
            .map(|(t, (ws, ge, gd))| {
                let (a, b) = ((t * per).min(rows), ((t + 1) * per).min(rows));
                scope.spawn(move || {
                    ge.clear();
                    ge.resize(ne, 0.0);
                    gd.clear();
                    gd.resize(nd, 0.0);
                    if a == b {
                        return LossParts::default();
                    }
                    let s = Slice {
                        input: &batch.encoded[a * np..b * np],
                        jitter: &jit[a * latent..b * latent],
                        features: &batch.features[a * 9..b * 9],
                        target: &batch.target[a * 7..b * 7],
                        mu_l: &batch.mu_l[a..b],
                        batch: rows,
                    };
                    model.train_slice(&s, LossWeights::PAPER, ws, ge, gd)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("a training thread panicked")).collect()
    });
    let mut loss = LossParts::default();
    for p in &parts {
        loss.add(p);
    }
    let (first, rest) = buf.slices.split_at_mut(1);
    for (_, ge, gd) in rest.iter() {
        first[0].1.iter_mut().zip(ge).for_each(|(a, b)| *a += b);
        first[0].2.iter_mut().zip(gd).for_each(|(a, b)| *a += b);
    }
    let lr = cosine_lr(state.step, opts.steps, opts.lr_start, opts.lr_end);
    state.adam_enc.step(&mut state.model.encoder.params, &first[0].1, lr);
    state.adam_dec.step(&mut state.model.decoder.params, &first[0].2, lr);
    state.step += 1;
    loss
}

/// `out`'s checkpoint: `decoder.safetensors` → `decoder.checkpoint.safetensors`.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "decoder".into());
    out.with_file_name(format!("{stem}.checkpoint.safetensors"))
}

/// The options a checkpoint must share with the run that resumes it.
fn option_fingerprint(o: &TrainOptions) -> String {
    let mut f = format!("steps={} batch={} seed={} lr={}..{} jitter={} mix={}", o.steps, o.batch, o.seed, o.lr_start, o.lr_end, o.jitter, o.mix.name());
    if o.views != super::datagen::ViewDistribution::Cosine {
        f += &format!(" views={}", o.views.name());
    }
    if let Some(init) = &o.init {
        f += &format!(" init={}", init.display());
    }
    if let Some(latent) = o.latent.filter(|&l| l != crate::model::LATENT) {
        f += &format!(" latent={latent}");
    }
    f
}

fn history_csv(history: &[LossRecord]) -> String {
    let mut s = String::from("step,loss,loss_f,loss_t,loss_r,lr,seconds\n");
    for h in history {
        s += &format!("{},{:.6e},{:.6e},{:.6e},{:.6e},{:.3e},{:.1}\n", h.step, h.loss.total, h.loss.f, h.loss.t, h.loss.r, h.lr, h.seconds);
    }
    s
}

/// Parses the `history` metadata entry.
pub fn parse_history(csv: &str) -> Result<Vec<LossRecord>, String> {
    csv.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|x| x.parse::<f64>().map_err(|_| format!("history: `{line}` is not a number row"))).collect::<Result<_, _>>()?;
            if v.len() != 7 {
                return Err(format!("history: `{line}` does not have 7 columns"));
            }
            Ok(LossRecord { step: v[0] as u64, loss: LossParts { total: v[1], f: v[2], t: v[3], r: v[4] }, lr: v[5] as f32, seconds: v[6] })
        })
        .collect()
}

/// The networks with their training record (what `uplift train` writes).
pub fn weights_file(state: &TrainState, stack: &Stack, opts: &TrainOptions, extra: &[(&str, String)]) -> TensorFile {
    let mut f = TensorFile::default();
    f.put_mlp("encoder", &state.model.encoder);
    f.put_mlp("decoder", &state.model.decoder);
    let m = &mut f.metadata;
    m.insert("format".into(), "uplift-neural-material-1".into());
    m.insert(super::weights::STACK_KEY.into(), stack.signature());
    m.insert("features".into(), "sin_theta_v,mu_v,wl'x,|wl'y|,wl'z,h'x,|h'y|,h'z,c_d (lobes.md 4.1 variant B)".into());
    m.insert("outputs".into(), "f.R,f.G,f.B,T.R,T.G,T.B,R".into());
    m.insert("loss".into(), "Eq.3: 0.95*L1(log1p(mu_l*f)) + 0.04*L1(T) + 0.01*L1(R)".into());
    m.insert("options".into(), option_fingerprint(opts));
    m.insert("step".into(), state.step.to_string());
    m.insert("seconds".into(), format!("{:.1}", state.seconds));
    m.insert("history".into(), history_csv(&state.history));
    for (k, v) in extra {
        m.insert(k.to_string(), v.clone());
    }
    f
}

fn write_checkpoint(path: &Path, state: &TrainState, stack: &Stack, opts: &TrainOptions) -> Result<(), String> {
    let mut f = weights_file(state, stack, opts, &[]);
    // Rust prints floats in the shortest form that reads back to the same value.
    let (w, n) = &state.window;
    f.metadata.insert("window".into(), format!("{n},{},{},{},{}", w.total, w.f, w.t, w.r));
    f.put_adam("encoder", &state.adam_enc);
    f.put_adam("decoder", &state.adam_dec);
    f.write(path)
}

/// Loads a checkpoint made with the same options.
pub fn read_checkpoint(path: &Path, stack: &Stack, opts: &TrainOptions) -> Result<TrainState, String> {
    let f = TensorFile::read(path)?;
    let at = |e: String| format!("{}: {e}", path.display());
    let made_with = f.meta("options").map_err(at)?;
    if made_with != option_fingerprint(opts) {
        return Err(format!("{}: the checkpoint was made with other options ({made_with}); this run has {} — delete it or use the same options", path.display(), option_fingerprint(opts)));
    }
    let encoder = f.mlp("encoder").map_err(at)?;
    let decoder = f.mlp("decoder").map_err(at)?;
    super::weights::check_stack(&f, &encoder, stack).map_err(at)?;
    let model = NeuralModel { encoder, decoder };
    model.check().map_err(at)?;
    Ok(TrainState {
        adam_enc: f.adam("encoder", model.encoder.params.len()).map_err(at)?,
        adam_dec: f.adam("decoder", model.decoder.params.len()).map_err(at)?,
        model,
        step: f.meta("step").map_err(at)?.parse().map_err(|_| at("`step` is not a number".into()))?,
        history: parse_history(f.meta("history").map_err(at)?).map_err(at)?,
        seconds: f.meta("seconds").map_err(at)?.parse().unwrap_or(0.0),
        // Checkpoints written before the window was kept resume with an empty one.
        window: match f.metadata.get("window") {
            None => (LossParts::default(), 0),
            Some(w) => {
                let bad = || at(format!("`window` {w}: expected steps,total,f,t,r"));
                let v: Vec<&str> = w.split(',').collect();
                let x = |k: usize| v.get(k).and_then(|s| s.parse::<f64>().ok()).ok_or_else(bad);
                (LossParts { total: x(1)?, f: x(2)?, t: x(3)?, r: x(4)? }, v[0].parse().map_err(|_| bad())?)
            }
        },
    })
}

/// Trains to `opts.steps` (or `opts.stop_after`), resuming from `out`'s checkpoint when it
/// exists, writing checkpoints on the way and, at the end, the final weights to `out` (with
/// `extra` metadata).
pub fn train(generator: &DataGenerator, opts: &TrainOptions, out: &Path, extra: &[(&str, String)], progress: bool) -> Result<TrainState, String> {
    let state = train_checkpointed(generator, opts, out, progress)?;
    if state.step == opts.steps {
        weights_file(&state, generator.stack(), opts, extra).write(out)?;
        finish(out);
    }
    Ok(state)
}

/// Removes `out`'s checkpoint (and what a killed writer left of one) once the caller has
/// written the final weights to `out`.
pub fn finish(out: &Path) {
    let ckpt = checkpoint_path(out);
    let _ = std::fs::remove_file(&ckpt);
    let dir = ckpt.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = ckpt.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    uplift_base::atomic_write::remove_stale(dir, &format!(".{name}."), ".tmp");
}

/// `train` without its end: trains to `opts.steps` (or `opts.stop_after`), resuming from
/// `out`'s checkpoint when it exists, and leaves a checkpoint of the last step, finished or
/// not, so that a process killed before its caller writes the final weights (and calls
/// `finish`) resumes without training again. Says on stderr where it resumes when `progress`.
pub fn train_checkpointed(generator: &DataGenerator, opts: &TrainOptions, out: &Path, progress: bool) -> Result<TrainState, String> {
    if opts.steps == 0 || opts.batch == 0 {
        return Err("--steps and --batch must be at least 1".into());
    }
    let ckpt = checkpoint_path(out);
    let mut state = if ckpt.exists() {
        read_checkpoint(&ckpt, generator.stack(), opts)?
    } else {
        let latent = opts.latent.unwrap_or(crate::model::LATENT);
        if latent == 0 || latent > crate::model::MAX_LATENT {
            return Err(format!("--latent {latent}: a latent has 1 to {} values", crate::model::MAX_LATENT));
        }
        let mut s = TrainState::new(generator.stack().len(), latent, opts.seed);
        if let Some(init) = &opts.init {
            let f = super::weights::TensorFile::read(init)?;
            let at = |e: String| format!("{}: {e}", init.display());
            s.model = NeuralModel { encoder: f.mlp("encoder").map_err(at)?, decoder: f.mlp("decoder").map_err(at)? };
            s.model.check().map_err(at)?;
            match opts.latent {
                Some(wide) if wide > s.model.latent() => {
                    if progress {
                        eprintln!("{}: a latent of {}; widened to {wide} (the decoder's new inputs' weights 0, so it starts as the file's)", init.display(), s.model.latent());
                    }
                    s.model = super::weights::widen_latent(&s.model, wide, opts.seed);
                }
                Some(narrow) if narrow != s.model.latent() => return Err(at(format!("a latent of {} values; --latent {narrow} cannot start from it (only a wider latent can)", s.model.latent()))),
                _ => {}
            }
            if let Err(e) = super::weights::check_stack(&f, &s.model.encoder, generator.stack()) {
                // A decoder for a stack this one extends: its encoder widened, new inputs at 0.
                s.model.encoder = super::weights::widen_encoder(&f, &s.model.encoder, generator.stack()).map_err(|w| at(format!("{e}; and it cannot be widened to this stack: {w}")))?;
                if progress {
                    eprintln!("{}: made for a stack with fewer parameters; its encoder is widened to this stack's {} (new inputs' weights 0)", init.display(), generator.stack().len());
                }
            }
        }
        s.adam_enc = Adam::new(s.model.encoder.params.len());
        s.adam_dec = Adam::new(s.model.decoder.params.len());
        s
    };
    let bar = if progress { indicatif::ProgressBar::new(opts.steps) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps, {elapsed} elapsed, eta {eta} · {msg}").unwrap());
    bar.set_position(state.step);
    let mut buf = StepBuffers::default();
    if progress && state.step > 0 {
        eprintln!("resuming from {} at step {} of {}", ckpt.display(), state.step, opts.steps);
    }
    let mut clock = std::time::Instant::now();
    // A generator on the wgpu engine trains there too: the networks and Adam's moments live on
    // the device (wgpu_train.rs) and come back for each checkpoint; each batch is assembled
    // there from the generator's kernels (wgpu_batch.rs), so no batch crosses to the host.
    let mut device = match generator.engine() {
        uplift_engines::stack_kernel::Engine::Wgpu(e) => Some((e, crate::wgpu_train::WgpuTrainer::new(e, &state)?, crate::wgpu_batch::DeviceBatches::new(e, generator, state.model.latent())?)),
        uplift_engines::stack_kernel::Engine::Cpu(_) => None,
    };
    let mut jit = Vec::new();
    while state.step < opts.steps {
        let lr = cosine_lr(state.step, opts.steps, opts.lr_start, opts.lr_end);
        let loss = match &mut device {
            Some((e, t, batches)) => {
                jitter(opts.seed, state.step, opts.batch * state.model.latent(), opts.jitter, &mut jit);
                state.adam_enc.t += 1;
                state.adam_dec.t += 1;
                let index = state.step;
                let l = t.step_on_device(e, opts.batch, lr, state.adam_dec.t, LossWeights::PAPER, |encoder, rows| batches.record(e, generator, index, opts.batch, &jit, encoder, rows))?;
                state.step += 1;
                l
            }
            None => {
                let batch = generator.batch(state.step, opts.batch)?;
                train_step(&mut state, &batch, opts, &mut buf)
            }
        };
        if !loss.total.is_finite() {
            return Err(format!("the loss became {} at step {}", loss.total, state.step));
        }
        state.window.0.add(&loss);
        state.window.1 += 1;
        let now = std::time::Instant::now();
        state.seconds += (now - clock).as_secs_f64();
        clock = now;
        if state.step % opts.log_every.max(1) == 0 || state.step == opts.steps {
            let (sum, n) = (state.window.0, state.window.1 as f64);
            let mean = LossParts { total: sum.total / n, f: sum.f / n, t: sum.t / n, r: sum.r / n };
            state.history.push(LossRecord { step: state.step, loss: mean, lr, seconds: state.seconds });
            bar.set_message(format!("loss {:.4} (f {:.4}, T {:.4}, R {:.4})", mean.total, mean.f, mean.t, mean.r));
            state.window = (LossParts::default(), 0);
        }
        bar.set_position(state.step);
        let stop = opts.stop_after == Some(state.step) && state.step < opts.steps;
        if state.step % opts.checkpoint_every.max(1) == 0 || state.step == opts.steps || stop {
            if let Some((e, t, _)) = &device {
                t.download(e, &mut state)?;
            }
            write_checkpoint(&ckpt, &state, generator.stack(), opts)?;
        }
        if stop {
            bar.abandon();
            return Ok(state);
        }
    }
    bar.finish();
    Ok(state)
}
