//! Inference code for a trained decoder (a dense network of known widths, activations and
//! weights), emitted through askama for both engines: Rust (`templates/neural_decoder.rs`:
//! weights as a `static` array, one function per row, fixed-size loops LLVM vectorises) and
//! WGSL (`templates/neural_decoder.wgsl`: weights in a storage buffer, one invocation per row).
//! Both evaluate exactly the trainer's forward pass: per layer y = W·x + b, then the activation.
//! The WGSL is parsed and validated by naga before it is returned. For latent fitting on a GPU,
//! `templates/neural_fit.wgsl` adds the paper's Eq. 3 and the backward pass to the decoder's
//! input (`write_wgsl_fitter`); for training, `templates/neural_train.wgsl` runs the encoder and
//! decoder forward and backward, sums the weight gradients and steps Adam, all on the device
//! (`write_wgsl_trainer`), fed by `templates/neural_batch.wgsl`'s kernels, which assemble a
//! training batch from the compiled stack kernels' outputs on the device (`write_wgsl_batch`);
//! a fit's step keeps its data, latents and Adam's moments there with
//! `templates/neural_fit_step.wgsl` (`write_wgsl_fit_step`).

use askama::Template;

/// A layer activation, as the runtime's trainer defines it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NeuralActivation {
    Identity,
    LeakyRelu { slope: f64 },
    Sigmoid,
    /// exp(min(x, clamp) − shift).
    ExpHead { shift: f64, clamp: f64 },
}

impl NeuralActivation {
    fn rust(self, x: &str) -> String {
        match self {
            NeuralActivation::Identity => x.to_string(),
            NeuralActivation::LeakyRelu { slope } => format!("if {x} > 0.0 {{ {x} }} else {{ {x} * {:?}f32 }}", slope as f32),
            NeuralActivation::Sigmoid => format!("1.0 / (1.0 + (-{x}).exp())"),
            NeuralActivation::ExpHead { shift, clamp } => format!("({x}.min({:?}f32) - {:?}f32).exp()", clamp as f32, shift as f32),
        }
    }

    fn wgsl(self, x: &str) -> String {
        match self {
            NeuralActivation::Identity => x.to_string(),
            NeuralActivation::LeakyRelu { slope } => format!("select({x} * {}, {x}, {x} > 0.0)", wgsl_float(slope as f32)),
            NeuralActivation::Sigmoid => format!("1.0 / (1.0 + exp(-{x}))"),
            NeuralActivation::ExpHead { shift, clamp } => format!("exp(min({x}, {}) - {})", wgsl_float(clamp as f32), wgsl_float(shift as f32)),
        }
    }

    /// d activation / dx from the activation's output `a`, as the trainer computes it
    /// (`Activation::derivative_from_output`).
    fn wgsl_derivative(self, a: &str) -> String {
        match self {
            NeuralActivation::Identity => "1.0".into(),
            NeuralActivation::LeakyRelu { slope } => format!("select({}, 1.0, {a} > 0.0)", wgsl_float(slope as f32)),
            NeuralActivation::Sigmoid => format!("({a} * (1.0 - {a}))"),
            NeuralActivation::ExpHead { shift, clamp } => format!("select(0.0, {a}, {a} < {})", wgsl_float((clamp - shift).exp() as f32)),
        }
    }
}

/// A WGSL float literal (always with a decimal point or exponent).
fn wgsl_float(v: f32) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') { s } else { format!("{s}.0") }
}

/// The decoder to emit.
#[derive(Clone, Debug)]
pub struct DecoderSpec {
    /// Layer widths, input first.
    pub widths: Vec<usize>,
    pub hidden: NeuralActivation,
    pub output: NeuralActivation,
    /// Per layer: weights (row-major `out × in`), then biases.
    pub params: Vec<f32>,
    /// Where the weights come from (named in the generated file's first line).
    pub source: String,
}

/// One layer as the templates see it.
struct Layer {
    index: usize,
    inputs: usize,
    outputs: usize,
    weights: usize,
    biases: usize,
    /// The activation applied to `s` (Rust and WGSL).
    rust_act: String,
    wgsl_act: String,
}

#[derive(Template)]
#[template(path = "neural_decoder.rs", escape = "none")]
struct RustDecoder<'a> {
    source: &'a str,
    inputs: usize,
    outputs: usize,
    max_width: usize,
    param_count: usize,
    layers: Vec<Layer>,
    params: String,
}

#[derive(Template)]
#[template(path = "neural_decoder.wgsl", escape = "none")]
struct WgslDecoder<'a> {
    source: &'a str,
    inputs: usize,
    outputs: usize,
    max_width: usize,
    layers: Vec<Layer>,
}

/// One layer of the fitter's backward pass.
struct BackLayer {
    index: usize,
    inputs: usize,
    outputs: usize,
    weights: usize,
    /// The inputs whose gradient is needed: all of them, but the latent ones of layer 0.
    needed_inputs: usize,
    wgsl_dact: String,
}

#[derive(Template)]
#[template(path = "neural_fit.wgsl", escape = "none")]
struct WgslFitter<'a> {
    source: &'a str,
    inputs: usize,
    latent: usize,
    max_width: usize,
    layer_count: usize,
    outputs_per_row: usize,
    layers: Vec<Layer>,
    backward: Vec<BackLayer>,
}

/// Entry point and workgroup size of the emitted fitting shader.
pub const FITTER_ENTRY_POINT: &str = "nf_main";
pub const FITTER_WORKGROUP_SIZE: u32 = 64;

/// Latent fitting against the decoder as a WGSL compute shader (`templates/neural_fit.wgsl`),
/// validated by naga: per row the forward pass, Eq. 3 and ∂loss/∂latent for the first `latent`
/// inputs. Bindings: 0 weights, 1 input rows, 2 targets (rows × 8: f·μl RGB, T RGB, R, μl), 3
/// output rows (3 loss sums, then `latent` gradients), 4 uniform (rows, then λf/(3·batch),
/// λt/(3·batch), λr/batch as f32 bits). The decoder has 7 outputs (f RGB, T RGB, R).
pub fn write_wgsl_fitter(spec: &DecoderSpec, latent: usize) -> Result<String, String> {
    let layers = layers(spec)?;
    if *spec.widths.last().unwrap() != 7 {
        return Err(format!("a decoder for Eq. 3 has 7 outputs (f RGB, T RGB, R), not {}", spec.widths.last().unwrap()));
    }
    if latent == 0 || latent > spec.widths[0] {
        return Err(format!("a latent of {latent} in a decoder of {} inputs", spec.widths[0]));
    }
    let n = spec.widths.len() - 1;
    let backward = layers
        .iter()
        .rev()
        .map(|l| {
            let act = if l.index + 1 == n { spec.output } else { spec.hidden };
            BackLayer { index: l.index, inputs: l.inputs, outputs: l.outputs, weights: l.weights, needed_inputs: if l.index == 0 { latent } else { l.inputs }, wgsl_dact: act.wgsl_derivative("a") }
        })
        .collect();
    let t = WgslFitter { source: &spec.source, inputs: spec.widths[0], latent, max_width: *spec.widths.iter().max().unwrap(), layer_count: n, outputs_per_row: 3 + latent, layers, backward };
    let text = t.render().map_err(|e| e.to_string())?;
    validated(text, "fitting")
}

/// One layer of the training shader, with where its input, output and ∂loss/∂s live in a
/// row's activations and deltas.
struct TrainLayer {
    net: &'static str,
    index: usize,
    inputs: usize,
    outputs: usize,
    /// Offsets in the weight buffer (the encoder's parameters, then the decoder's).
    weights: usize,
    biases: usize,
    act_in: usize,
    act_out: usize,
    delta: usize,
    /// The decoder's first layer: its input is assembled from the latent, the jitter and the
    /// features.
    decoder_input: bool,
    needed_inputs: usize,
    wgsl_act: String,
    wgsl_dact: String,
}

#[derive(Template)]
#[template(path = "neural_train.wgsl", escape = "none")]
struct WgslTrainer<'a> {
    source: &'a str,
    parameters: usize,
    latent: usize,
    row_stride: usize,
    acts: usize,
    deltas: usize,
    max_width: usize,
    latent_at: usize,
    output_at: usize,
    encoder_params: usize,
    decoder_params: usize,
    total_params: usize,
    forward: Vec<TrainLayer>,
    backward: Vec<TrainLayer>,
}

/// Entry points and workgroup size of the emitted training shader.
pub const TRAINER_ROWS_ENTRY_POINT: &str = "nt_rows";
pub const TRAINER_GRADS_ENTRY_POINT: &str = "nt_grads";
pub const TRAINER_ADAM_ENTRY_POINT: &str = "nt_adam";
pub const TRAINER_WORKGROUP_SIZE: u32 = 64;

/// The training step of `encoder` (parameters → latent) and `decoder` (latent + 9 direction
/// features → 7 outputs) as a WGSL shader of three entry points (`templates/neural_train.wgsl`;
/// its header documents the bindings), validated by naga. Row layout of the input buffer:
/// the encoder's inputs, the latent's jitter, the 9 features, f·μl RGB, T RGB, R and μl.
pub fn write_wgsl_trainer(encoder: &DecoderSpec, decoder: &DecoderSpec, source: &str) -> Result<String, String> {
    let (enc, dec) = (layers(encoder)?, layers(decoder)?);
    let latent = *encoder.widths.last().unwrap();
    let parameters = encoder.widths[0];
    if decoder.widths[0] != latent + 9 || *decoder.widths.last().unwrap() != 7 {
        return Err(format!("an encoder of widths {:?} and a decoder of widths {:?} do not make the paper's model (latent + 9 features → 7)", encoder.widths, decoder.widths));
    }
    let ne = encoder.params.len();
    let (mut acts, mut deltas) = (parameters, 0);
    let mut forward = Vec::new();
    let (ne_layers, nd_layers) = (enc.len(), dec.len());
    for (net, list, base, spec, count) in [("encoder", &enc, 0, encoder, ne_layers), ("decoder", &dec, ne, decoder, nd_layers)] {
        for l in list.iter() {
            let act = if l.index + 1 == count { spec.output } else { spec.hidden };
            let decoder_input = net == "decoder" && l.index == 0;
            let act_in = if decoder_input {
                acts += l.inputs;
                acts - l.inputs
            } else if l.index == 0 {
                0
            } else {
                acts - l.inputs
            };
            let layer = TrainLayer {
                net,
                index: l.index,
                inputs: l.inputs,
                outputs: l.outputs,
                weights: base + l.weights,
                biases: base + l.biases,
                act_in,
                act_out: acts,
                delta: deltas,
                decoder_input,
                needed_inputs: match (net, l.index) {
                    ("encoder", 0) => 0,
                    ("decoder", 0) => latent,
                    _ => l.inputs,
                },
                wgsl_act: act.wgsl("s"),
                wgsl_dact: act.wgsl_derivative("a"),
            };
            acts += l.outputs;
            deltas += l.outputs;
            forward.push(layer);
        }
    }
    let latent_at = forward[ne_layers - 1].act_out;
    let output_at = forward.last().unwrap().act_out;
    let backward = forward
        .iter()
        .rev()
        .map(|l| TrainLayer { net: l.net, index: l.index, inputs: l.inputs, outputs: l.outputs, weights: l.weights, biases: l.biases, act_in: l.act_in, act_out: l.act_out, delta: l.delta, decoder_input: l.decoder_input, needed_inputs: l.needed_inputs, wgsl_act: l.wgsl_act.clone(), wgsl_dact: l.wgsl_dact.clone() })
        .collect();
    let max_width = encoder.widths.iter().chain(&decoder.widths).copied().max().unwrap();
    let t = WgslTrainer {
        source,
        parameters,
        latent,
        row_stride: parameters + latent + 9 + 8,
        acts,
        deltas,
        max_width,
        latent_at,
        output_at,
        encoder_params: ne,
        decoder_params: decoder.params.len(),
        total_params: ne + decoder.params.len(),
        forward,
        backward,
    };
    let text = t.render().map_err(|e| e.to_string())?;
    validated(text, "training")
}

/// `text`, the emitted WGSL of a `what` shader, once naga has parsed and validated it.
fn validated(text: String, what: &str) -> Result<String, String> {
    let module = naga::front::wgsl::parse_str(&text).map_err(|e| format!("generated {what} WGSL does not parse: {}", e.emit_to_string(&text)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
        .validate(&module)
        .map_err(|e| format!("generated {what} WGSL does not validate: {}", e.emit_to_string(&text)))?;
    Ok(text)
}

#[derive(Template)]
#[template(path = "neural_batch.wgsl", escape = "none")]
struct WgslBatch {
    parameters: usize,
    dir_stride: usize,
}

/// Entry points, workgroup size and direction-slot stride of the batch-assembly shader.
pub const BATCH_SCATTER_ENTRY_POINT: &str = "nb_scatter";
pub const BATCH_GATHER_ENTRY_POINT: &str = "nb_gather";
pub const BATCH_SELECT_ENTRY_POINT: &str = "nb_select";
pub const BATCH_ASSEMBLE_ENTRY_POINT: &str = "nb_assemble";
pub const BATCH_WORKGROUP_SIZE: u32 = 64;
pub const BATCH_DIRECTION_STRIDE: usize = 16;

/// The kernels that assemble a training batch of a stack of `parameters` parameters on a
/// device from the compiled kernels' outputs (`templates/neural_batch.wgsl`; its header
/// documents the layouts and bindings), validated by naga. Rows come out in
/// [`write_wgsl_trainer`]'s input layout.
pub fn write_wgsl_batch(parameters: usize) -> Result<String, String> {
    if parameters == 0 {
        return Err("a stack of no parameters".into());
    }
    let text = WgslBatch { parameters, dir_stride: BATCH_DIRECTION_STRIDE }.render().map_err(|e| e.to_string())?;
    validated(text, "batch")
}

#[derive(Template)]
#[template(path = "neural_fit_step.wgsl", escape = "none")]
struct WgslFitStep {
    parameters: usize,
    latent: usize,
    inputs: usize,
    row_stride: usize,
}

/// Entry points and workgroup size of the fitting step's gather and Adam kernels.
pub const FIT_STEP_GATHER_ENTRY_POINT: &str = "nfs_gather";
pub const FIT_STEP_ADAM_ENTRY_POINT: &str = "nfs_adam";
pub const FIT_STEP_WORKGROUP_SIZE: u32 = 64;

/// The kernels around [`write_wgsl_fitter`]'s that keep a latent fit on the device
/// (`templates/neural_fit_step.wgsl`: the fitting kernel's rows gathered from a batch that
/// [`write_wgsl_batch`]'s kernels assembled for a stack of `parameters` parameters, and Adam on
/// the groups' `latent`-wide latents), validated by naga.
pub fn write_wgsl_fit_step(parameters: usize, latent: usize) -> Result<String, String> {
    if parameters == 0 || latent == 0 {
        return Err(format!("a fitting step for {parameters} parameters and a latent of {latent}"));
    }
    let text = WgslFitStep { parameters, latent, inputs: latent + 9, row_stride: parameters + latent + 17 }.render().map_err(|e| e.to_string())?;
    validated(text, "fitting-step")
}

/// Entry point, bindings and workgroup size of the emitted WGSL compute shader.
pub const DECODER_ENTRY_POINT: &str = "nd_main";
pub const DECODER_WORKGROUP_SIZE: u32 = 64;

fn layers(spec: &DecoderSpec) -> Result<Vec<Layer>, String> {
    if spec.widths.len() < 2 || spec.widths.contains(&0) {
        return Err(format!("a decoder needs at least two non-zero widths, got {:?}", spec.widths));
    }
    let mut at = 0;
    let mut out = Vec::new();
    let n = spec.widths.len() - 1;
    for l in 0..n {
        let (i, o) = (spec.widths[l], spec.widths[l + 1]);
        let act = if l + 1 == n { spec.output } else { spec.hidden };
        out.push(Layer { index: l, inputs: i, outputs: o, weights: at, biases: at + i * o, rust_act: act.rust("s"), wgsl_act: act.wgsl("s") });
        at += (i + 1) * o;
    }
    if at != spec.params.len() {
        return Err(format!("{} weights for a network of widths {:?}, which has {at}", spec.params.len(), spec.widths));
    }
    if let Some(bad) = spec.params.iter().find(|x| !x.is_finite()) {
        return Err(format!("the weights hold a non-finite value ({bad})"));
    }
    Ok(out)
}

/// The decoder as a Rust module (`decode(&[f32; INPUTS]) -> [f32; OUTPUTS]`, `decode_rows`).
pub fn write_rust_decoder(spec: &DecoderSpec) -> Result<String, String> {
    let layers = layers(spec)?;
    let mut params = String::new();
    for (k, v) in spec.params.iter().enumerate() {
        params += &format!("{v:?}, ");
        if k % 8 == 7 {
            params += "\n    ";
        }
    }
    let t = RustDecoder {
        source: &spec.source,
        inputs: spec.widths[0],
        outputs: *spec.widths.last().unwrap(),
        max_width: *spec.widths.iter().max().unwrap(),
        param_count: spec.params.len(),
        layers,
        params: params.trim_end().to_string(),
    };
    t.render().map_err(|e| e.to_string())
}

/// The decoder as a WGSL compute shader (`nd_decode` and the entry point `nd_main`), validated
/// by naga. Bindings: 0 weights, 1 input rows, 2 output rows, 3 uniform (rows, 0, 0, 0).
pub fn write_wgsl_decoder(spec: &DecoderSpec) -> Result<String, String> {
    let layers = layers(spec)?;
    let t = WgslDecoder { source: &spec.source, inputs: spec.widths[0], outputs: *spec.widths.last().unwrap(), max_width: *spec.widths.iter().max().unwrap(), layers };
    let text = t.render().map_err(|e| e.to_string())?;
    validated(text, "decoder")
}
