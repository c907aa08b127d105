//! Inference code for a trained decoder (a dense network of known widths, activations and
//! weights), emitted through askama for both engines: Rust (`templates/neural_decoder.rs`:
//! weights as a `static` array, one function per row, fixed-size loops LLVM vectorises) and
//! WGSL (`templates/neural_decoder.wgsl`: weights in a storage buffer, one invocation per row).
//! Both evaluate exactly the trainer's forward pass: per layer y = W·x + b, then the activation.
//! The WGSL is parsed and validated by naga before it is returned. For latent fitting on a GPU,
//! `templates/neural_fit.wgsl` adds the paper's Eq. 3 and the backward pass to the decoder's
//! input (`write_wgsl_fitter`).

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
    let module = naga::front::wgsl::parse_str(&text).map_err(|e| format!("generated fitting WGSL does not parse: {}", e.emit_to_string(&text)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
        .validate(&module)
        .map_err(|e| format!("generated fitting WGSL does not validate: {}", e.emit_to_string(&text)))?;
    Ok(text)
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
    let module = naga::front::wgsl::parse_str(&text).map_err(|e| format!("generated decoder WGSL does not parse: {}", e.emit_to_string(&text)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
        .validate(&module)
        .map_err(|e| format!("generated decoder WGSL does not validate: {}", e.emit_to_string(&text)))?;
    Ok(text)
}
