//! Networks and their training state as safetensors (loadable by PyTorch's `safetensors`):
//! each layer as `<net>.layers.<l>.weight` (`out × in`, PyTorch `nn.Linear` layout) and
//! `<net>.layers.<l>.bias`, f32 little-endian; the shapes and activations in the header's
//! metadata (`<net>.widths`, `<net>.hidden`, `<net>.output`), with any other string entries the
//! caller adds (training command, losses). A checkpoint also holds Adam's moments
//! (`adam.<net>.m`, `adam.<net>.v`) and its step count.

use crate::adam::Adam;
use crate::mlp::{Activation, Mlp, MlpShape};
use uplift_base::atomic_write::write_atomically;
use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use std::collections::BTreeMap;
use std::path::Path;
use uplift_engines::stack::Stack;

/// Metadata entries of a decoder file: the affine from a latent's stored value v ∈ [0, 1] (a
/// PNG16 texel, a video frame) to the latent, latent = offset + scale · (2v − 1), per latent
/// channel (JSON arrays). The encoder's sigmoid and the fitter's clamp keep latents in [0, 1],
/// so today's decoders record scale ½ and offset ½; export's `meta.json` copies them.
pub const LATENT_SCALE_KEY: &str = "latent.scale";
pub const LATENT_OFFSET_KEY: &str = "latent.offset";

/// Named f32 tensors and string metadata, read from or written to one file.
#[derive(Clone, Debug, Default)]
pub struct TensorFile {
    pub tensors: BTreeMap<String, (Vec<usize>, Vec<f32>)>,
    pub metadata: BTreeMap<String, String>,
}

impl TensorFile {
    pub fn put(&mut self, name: &str, shape: Vec<usize>, data: Vec<f32>) {
        assert_eq!(shape.iter().product::<usize>(), data.len(), "{name}: shape {shape:?}");
        self.tensors.insert(name.to_string(), (shape, data));
    }

    pub fn get(&self, name: &str) -> Result<&(Vec<usize>, Vec<f32>), String> {
        self.tensors.get(name).ok_or_else(|| format!("no tensor `{name}`"))
    }

    pub fn meta(&self, key: &str) -> Result<&str, String> {
        self.metadata.get(key).map(String::as_str).ok_or_else(|| format!("no metadata entry `{key}`"))
    }

    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let bytes: Vec<(String, Vec<usize>, Vec<u8>)> = self.tensors.iter().map(|(n, (s, d))| (n.clone(), s.clone(), d.iter().flat_map(|x| x.to_le_bytes()).collect())).collect();
        let views: Vec<(String, TensorView<'_>)> =
            bytes.iter().map(|(n, s, b)| TensorView::new(Dtype::F32, s.clone(), b).map(|v| (n.clone(), v)).map_err(|e| format!("{n}: {e}"))).collect::<Result<_, _>>()?;
        // safetensors writes the metadata from a HashMap, in an order that changes from run to
        // run; write the header's metadata in key order instead, so that the same tensors and
        // metadata are always the same bytes (a resumed run's files equal an uninterrupted one's).
        let plain = safetensors::serialize(views, None).map_err(|e| e.to_string())?;
        let n = u64::from_le_bytes(plain[..8].try_into().unwrap()) as usize;
        let header = std::str::from_utf8(&plain[8..8 + n]).map_err(|e| e.to_string())?.trim_end();
        let tensors = header.strip_prefix('{').ok_or("safetensors wrote a header that is not a JSON object")?;
        let mut h = String::from("{");
        if !self.metadata.is_empty() {
            let json = |s: &String| serde_json::to_string(s).expect("a string serialises");
            let entries: Vec<String> = self.metadata.iter().map(|(k, v)| format!("{}:{}", json(k), json(v))).collect();
            h += &format!("\"__metadata__\":{{{}}}", entries.join(","));
            if tensors != "}" {
                h.push(',');
            }
        }
        h += tensors;
        // The header is padded with spaces to a multiple of 8 bytes, as safetensors does.
        while h.len() % 8 != 0 {
            h.push(' ');
        }
        let mut out = Vec::with_capacity(8 + h.len() + plain.len() - 8 - n);
        out.extend((h.len() as u64).to_le_bytes());
        out.extend(h.as_bytes());
        out.extend(&plain[8 + n..]);
        Ok(out)
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<TensorFile, String> {
        let st = SafeTensors::deserialize(bytes).map_err(|e| format!("not a safetensors file: {e}"))?;
        let (_, header) = SafeTensors::read_metadata(bytes).map_err(|e| e.to_string())?;
        let mut file = TensorFile::default();
        if let Some(m) = header.metadata() {
            file.metadata = m.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        }
        for (name, view) in st.tensors() {
            if view.dtype() != Dtype::F32 {
                return Err(format!("tensor `{name}` is {:?}; uplift reads f32 tensors", view.dtype()));
            }
            let data = view.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
            file.tensors.insert(name, (view.shape().to_vec(), data));
        }
        Ok(file)
    }

    pub fn write(&self, path: &Path) -> Result<(), String> {
        write_atomically(path, &self.to_bytes()?).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn read(path: &Path) -> Result<TensorFile, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        TensorFile::from_bytes(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Stores `net` under `prefix`.
    pub fn put_mlp(&mut self, prefix: &str, net: &Mlp<f32>) {
        let s = &net.shape;
        for l in 0..s.layers() {
            let (w, b) = net.layer(l);
            self.put(&format!("{prefix}.layers.{l}.weight"), vec![s.widths[l + 1], s.widths[l]], w.to_vec());
            self.put(&format!("{prefix}.layers.{l}.bias"), vec![s.widths[l + 1]], b.to_vec());
        }
        self.metadata.insert(format!("{prefix}.widths"), s.widths.iter().map(|w| w.to_string()).collect::<Vec<_>>().join(","));
        self.metadata.insert(format!("{prefix}.hidden"), s.hidden.name());
        self.metadata.insert(format!("{prefix}.output"), s.output.name());
    }

    /// The network stored under `prefix`.
    pub fn mlp(&self, prefix: &str) -> Result<Mlp<f32>, String> {
        let widths: Vec<usize> = self.meta(&format!("{prefix}.widths"))?.split(',').map(|w| w.trim().parse().map_err(|_| format!("{prefix}.widths: `{w}` is not a width"))).collect::<Result<_, _>>()?;
        if widths.len() < 2 {
            return Err(format!("{prefix}.widths: a network needs at least two widths"));
        }
        let act = |k: &str| -> Result<Activation, String> {
            let text = self.meta(&format!("{prefix}.{k}"))?;
            Activation::parse(text).ok_or_else(|| format!("{prefix}.{k}: unknown activation `{text}`"))
        };
        let shape = MlpShape { widths, hidden: act("hidden")?, output: act("output")? };
        let mut params = Vec::with_capacity(shape.parameter_count());
        for l in 0..shape.layers() {
            for (part, want) in [("weight", vec![shape.widths[l + 1], shape.widths[l]]), ("bias", vec![shape.widths[l + 1]])] {
                let name = format!("{prefix}.layers.{l}.{part}");
                let (s, d) = self.get(&name)?;
                if *s != want {
                    return Err(format!("{name}: shape {s:?}, expected {want:?}"));
                }
                if let Some(bad) = d.iter().find(|x| !x.is_finite()) {
                    return Err(format!("{name}: holds a non-finite value ({bad})"));
                }
                params.extend_from_slice(d);
            }
        }
        Mlp::from_params(shape, params)
    }

    pub fn put_adam(&mut self, prefix: &str, adam: &Adam) {
        self.put(&format!("adam.{prefix}.m"), vec![adam.m.len()], adam.m.clone());
        self.put(&format!("adam.{prefix}.v"), vec![adam.v.len()], adam.v.clone());
        self.metadata.insert(format!("adam.{prefix}.t"), adam.t.to_string());
    }

    pub fn adam(&self, prefix: &str, n: usize) -> Result<Adam, String> {
        let mut adam = Adam::new(n);
        for (part, dst) in [("m", &mut adam.m), ("v", &mut adam.v)] {
            let (_, d) = self.get(&format!("adam.{prefix}.{part}"))?;
            if d.len() != n {
                return Err(format!("adam.{prefix}.{part}: {} values for {n} parameters", d.len()));
            }
            dst.copy_from_slice(d);
        }
        adam.t = self.meta(&format!("adam.{prefix}.t"))?.parse().map_err(|_| format!("adam.{prefix}.t is not a step count"))?;
        Ok(adam)
    }
}

/// The decoder the repository ships (`runtime/weights/`).
pub const SHIPPED_DECODER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../weights/decoder.safetensors");

/// The encoder and decoder of a weights file, checked against this build's stack.
pub fn load_model(path: &Path, stack: &Stack) -> Result<crate::model::NeuralModel<f32>, String> {
    let f = TensorFile::read(path)?;
    let at = |e: String| format!("{}: {e}", path.display());
    let model = crate::model::NeuralModel { encoder: f.mlp("encoder").map_err(at)?, decoder: f.mlp("decoder").map_err(at)? };
    model.check().map_err(at)?;
    check_stack(&f, &model.encoder, stack).map_err(at)?;
    Ok(model)
}

/// The sampling decoder of a weights file (`uplift train-sampler`), if it has one.
pub fn load_sampler(path: &Path) -> Result<Option<Mlp<f32>>, String> {
    let f = TensorFile::read(path)?;
    if !f.metadata.contains_key("sampler.widths") {
        return Ok(None);
    }
    f.mlp("sampler").map(Some).map_err(|e| format!("{}: {e}", path.display()))
}

/// The metadata key of the stack signature (`Stack::signature`).
pub const STACK_KEY: &str = "stack";

/// Whether a weights file was trained for `stack`: its recorded signature
/// (`stack`), or — in files written before signatures were recorded — its encoder's input
/// width.
pub fn check_stack(f: &TensorFile, encoder: &Mlp<f32>, stack: &Stack) -> Result<(), String> {
    match f.metadata.get(STACK_KEY) {
        Some(recorded) => stack.check_signature(recorded).map_err(|e| format!("{e}{}", if stack.is_builtin() { " (was it trained with --stack DIR? pass the same folder)" } else { "" })),
        None => {
            let width = encoder.shape.widths[0];
            let ours = stack.len();
            if width == ours {
                Ok(())
            } else {
                Err(format!("it was trained for another uplift_stack: its encoder reads {width} parameters, this stack has {ours} (the file records no stack signature)"))
            }
        }
    }
}

/// The encoder of a weights file made for a stack whose parameters are a subset of `stack`'s
/// (the file's recorded signature entries all appear in this stack): its first layer widened
/// to `stack`'s parameters, each recorded parameter's weights moved to its new column and the
/// new parameters' weights zero, so the encoder computes the same latents wherever the new
/// parameters' encoded values are 0. `uplift train --init` starts from it when a stack gains a
/// lobe (a decorator added as graph nodes), instead of training from scratch.
pub fn widen_encoder(f: &TensorFile, encoder: &Mlp<f32>, stack: &Stack) -> Result<Mlp<f32>, String> {
    let recorded = f.metadata.get(STACK_KEY).ok_or("the file records no stack signature, so its parameters cannot be matched to this stack's")?;
    let ours: Vec<String> = stack.signature().split(' ').map(str::to_string).collect();
    let theirs: Vec<&str> = recorded.split_whitespace().collect();
    if theirs.len() != encoder.shape.widths[0] {
        return Err(format!("its encoder reads {} parameters but its signature lists {}", encoder.shape.widths[0], theirs.len()));
    }
    let mut column = Vec::with_capacity(theirs.len());
    for t in &theirs {
        column.push(ours.iter().position(|o| o == t).ok_or_else(|| format!("its parameter `{t}` is not in this stack (only a stack that adds parameters can start from it)"))?);
    }
    let mut shape = encoder.shape.clone();
    let (old_in, new_in, out) = (shape.widths[0], ours.len(), shape.widths[1]);
    shape.widths[0] = new_in;
    let mut widened = Mlp::<f32>::new(shape, 0);
    let (w_old, b_old) = encoder.shape.offsets(0);
    let (w_new, b_new) = widened.shape.offsets(0);
    for o in 0..out {
        for j in 0..new_in {
            widened.params[w_new + o * new_in + j] = 0.0;
        }
        for (i, &j) in column.iter().enumerate() {
            widened.params[w_new + o * new_in + j] = encoder.params[w_old + o * old_in + i];
        }
        widened.params[b_new + o] = encoder.params[b_old + o];
    }
    let (rest_old, rest_new) = (encoder.shape.offsets(1).0, widened.shape.offsets(1).0);
    widened.params[rest_new..].copy_from_slice(&encoder.params[rest_old..]);
    Ok(widened)
}

/// `model` with a latent of `latent` values (wider than its own): the encoder's new outputs
/// get fresh Xavier weights (seeded; distinct, so the new latent values differ from one
/// another), the decoder's new inputs weights 0, so the widened model decodes exactly as
/// `model` and training moves the new values into use. `uplift train --init F --latent N`.
pub fn widen_latent(model: &crate::model::NeuralModel<f32>, latent: usize, seed: u64) -> crate::model::NeuralModel<f32> {
    let old = model.latent();
    assert!(latent >= old, "a latent is only widened");
    let fresh = crate::model::NeuralModel::<f32>::new(model.encoder.shape.inputs(), latent, seed);
    // Encoder: every layer as before; the last layer's rows for the new outputs from `fresh`.
    let mut encoder = fresh.encoder.clone();
    let last = encoder.shape.layers() - 1;
    let (w_last, b_last) = encoder.shape.offsets(last);
    let (w_old, b_old) = model.encoder.shape.offsets(last);
    encoder.params[..w_last].copy_from_slice(&model.encoder.params[..w_old]);
    let k = encoder.shape.widths[last];
    encoder.params[w_last..w_last + old * k].copy_from_slice(&model.encoder.params[w_old..w_old + old * k]);
    encoder.params[b_last..b_last + old].copy_from_slice(&model.encoder.params[b_old..b_old + old]);
    // Decoder: the first layer's columns for the new latent values 0; every other weight as before.
    let mut decoder = fresh.decoder.clone();
    let (old_in, new_in, out) = (model.decoder.shape.inputs(), decoder.shape.inputs(), decoder.shape.widths[1]);
    let (w0_new, b0_new) = decoder.shape.offsets(0);
    let (w0_old, b0_old) = model.decoder.shape.offsets(0);
    for o in 0..out {
        let row = &mut decoder.params[w0_new + o * new_in..w0_new + (o + 1) * new_in];
        let from = &model.decoder.params[w0_old + o * old_in..w0_old + (o + 1) * old_in];
        row.fill(0.0);
        row[..old].copy_from_slice(&from[..old]);
        row[latent..].copy_from_slice(&from[old..]);
        decoder.params[b0_new + o] = model.decoder.params[b0_old + o];
    }
    let (rest_new, rest_old) = (decoder.shape.offsets(1).0, model.decoder.shape.offsets(1).0);
    decoder.params[rest_new..].copy_from_slice(&model.decoder.params[rest_old..]);
    crate::model::NeuralModel { encoder, decoder }
}

/// How generated files name the weights: relative to the repository when inside it.
pub fn source_name(path: &Path) -> String {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (abs, repo) = (std::fs::canonicalize(path).unwrap_or(path.to_path_buf()), std::fs::canonicalize(&repo).unwrap_or(repo));
    abs.strip_prefix(&repo).map(|p| p.to_string_lossy().replace('\\', "/")).unwrap_or_else(|_| path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A weights file records the stack it was trained for; one trained for another stack is
    /// refused with the difference named, whether it records a signature or (an old file) only
    /// its encoder's width. The shipped decoder records this build's stack.
    #[test]
    fn a_decoder_for_another_stack_is_refused() {
        let stack = Stack::builtin();
        let encoder = Mlp::<f32>::new(crate::model::encoder_shape(stack.len(), crate::model::LATENT), 1);
        let mut f = TensorFile::default();
        assert!(check_stack(&f, &encoder, &stack).is_ok(), "an old file of the right width");
        f.metadata.insert(STACK_KEY.into(), stack.signature());
        assert!(check_stack(&f, &encoder, &stack).is_ok());
        f.metadata.insert(STACK_KEY.into(), format!("{} film_ior[1.2,2.0]linear", stack.signature()));
        let e = check_stack(&f, &encoder, &stack).unwrap_err();
        assert!(e.contains("another uplift_stack") && e.contains("`film_ior[1.2,2.0]linear` is not in this stack"), "{e}");
        let mut wide = crate::model::encoder_shape(stack.len(), crate::model::LATENT);
        wide.widths[0] += 2;
        let e = check_stack(&TensorFile::default(), &Mlp::<f32>::new(wide, 1), &stack).unwrap_err();
        assert!(e.contains(&format!("reads {} parameters", stack.len() + 2)), "{e}");
        let shipped = TensorFile::read(Path::new(SHIPPED_DECODER)).unwrap();
        assert_eq!(shipped.meta(STACK_KEY).unwrap(), stack.signature());
    }

    /// The shipped decoder file records its latent space: the storage affine and the diffuse
    /// latent, equal to the one the search finds for it now. `UPLIFT_BLESS=1` writes them into
    /// the file (metadata only: the weights, and so the generated decoder, are unchanged).
    #[test]
    fn the_shipped_decoder_records_its_latent_space() {
        let stack = Stack::builtin();
        let path = Path::new(SHIPPED_DECODER);
        let model = crate::weights::load_model(path, &stack).unwrap();
        let mut file = TensorFile::read(path).unwrap();
        if std::env::var_os("UPLIFT_BLESS").is_some_and(|v| !v.is_empty() && v != "0") {
            record_latent_space(&mut file, &model);
            file.write(path).unwrap();
        }
        let (d, stored) = crate::diffuse_latent::diffuse_latent_of(&file, &model).unwrap();
        assert!(stored, "{SHIPPED_DECODER} stores no diffuse latent (UPLIFT_BLESS=1 writes it)");
        assert_eq!(d, crate::diffuse_latent::find_diffuse_latent(&model, crate::diffuse_latent::SEED), "the stored diffuse latent is not the decoder's");
        assert!(d.fcos < 0.01 && d.t_error < 0.05, "{d:?}");
        assert_eq!(latent_affine(&file, model.latent()).unwrap(), (vec![0.5; model.latent()], vec![0.5; model.latent()]));
        // Bad entries are errors naming the entry.
        let mut bad = file.clone();
        bad.metadata.insert(LATENT_SCALE_KEY.into(), "[0.5, 0.5]".into());
        assert!(latent_affine(&bad, 6).unwrap_err().contains("`latent.scale`: 6 finite values"));
        bad.metadata.insert(crate::diffuse_latent::METADATA_KEY.into(), r#"{"latent":[2,0,0,0,0,0],"fcos":0,"t_error":0}"#.into());
        assert!(crate::diffuse_latent::diffuse_latent_of(&bad, &model).unwrap_err().contains("in [0, 1]"));
    }

    /// A latent widened from 6 to 8 decodes exactly as before (the decoder's new inputs are
    /// unused) and keeps the encoder's first 6 outputs, while its 2 new outputs differ from each
    /// other (so training can tell them apart).
    #[test]
    fn a_widened_latent_decodes_as_before() {
        use crate::model::{NeuralModel, LATENT};
        let stack = Stack::builtin();
        let model = crate::weights::load_model(Path::new(SHIPPED_DECODER), &stack).unwrap();
        let wide = widen_latent(&model, 8, 5);
        wide.check().unwrap();
        assert_eq!((wide.latent(), wide.encoder.shape.outputs(), wide.decoder.shape.inputs()), (8, 8, 17));
        let rows = 64;
        let mut rng = uplift_base::rng::SplitMix64::new(9);
        let encoded: Vec<f32> = (0..rows * stack.len()).map(|_| rng.unit()).collect();
        let features: Vec<f32> = (0..rows * crate::features::FEATURES).map(|_| rng.range(-1.0, 1.0)).collect();
        let (z6, z8) = (crate::evaluate::encode(&model, &encoded), crate::evaluate::encode(&wide, &encoded));
        let mut differs = 0;
        for r in 0..rows {
            assert_eq!(&z8[r * 8..r * 8 + LATENT], &z6[r * LATENT..(r + 1) * LATENT], "row {r}: the first six latent values");
            differs += (z8[r * 8 + 6] != z8[r * 8 + 7]) as usize;
        }
        assert!(differs > rows / 2, "the new latent values are alike in {} of {rows} rows", rows - differs);
        let (o6, o8) = (crate::evaluate::decode(&model, &z6, &features), crate::evaluate::decode(&wide, &z8, &features));
        for (k, (a, b)) in o6.iter().zip(&o8).enumerate() {
            assert!((a - b).abs() <= 1e-6 * a.abs().max(1e-3), "output {k}: {a} widened to {b}");
        }
        let fresh = NeuralModel::<f32>::new(stack.len(), 8, 1);
        assert_eq!(fresh.latent(), 8);
    }

    #[test]
    fn the_same_file_is_the_same_bytes_and_reads_back() {
        let mut f = TensorFile::default();
        f.put("b", vec![2], vec![1.0, -2.5]);
        f.put("a", vec![1, 1], vec![3.0]);
        for k in 0..20 {
            f.metadata.insert(format!("key{k}"), format!("value {k}"));
        }
        f.metadata.insert("odd".into(), "quote \" backslash \\ newline \n tab \t bell \u{7} é".into());
        let bytes = f.to_bytes().unwrap();
        // A HashMap's order differs between instances; twenty entries in the same order twice
        // by chance is 1 in 20!.
        for _ in 0..3 {
            assert_eq!(f.clone().to_bytes().unwrap(), bytes);
        }
        let back = TensorFile::from_bytes(&bytes).unwrap();
        assert_eq!((back.tensors, back.metadata), (f.tensors.clone(), f.metadata.clone()));
        let empty = TensorFile::from_bytes(&TensorFile::default().to_bytes().unwrap()).unwrap();
        assert!(empty.tensors.is_empty() && empty.metadata.is_empty());
    }
}

/// Records in a decoder file what a generator trained on its latents needs: the latents'
/// storage affine and the decoder's diffuse latent (found now: about a second).
pub fn record_latent_space(file: &mut TensorFile, model: &crate::model::NeuralModel<f32>) {
    let l = model.latent();
    let array = |x: f32| serde_json::to_string(&vec![x; l]).expect("floats serialise");
    file.metadata.insert(LATENT_SCALE_KEY.into(), array(0.5));
    file.metadata.insert(LATENT_OFFSET_KEY.into(), array(0.5));
    let d = crate::diffuse_latent::find_diffuse_latent(model, crate::diffuse_latent::SEED);
    file.metadata.insert(crate::diffuse_latent::METADATA_KEY.into(), d.to_metadata());
}

/// The latents' storage affine (scale, offset per channel) a decoder file records; ½ and ½
/// for files written before it was recorded (the range their latents were fitted in).
pub fn latent_affine(file: &TensorFile, latent: usize) -> Result<(Vec<f32>, Vec<f32>), String> {
    let read = |key: &str| -> Result<Vec<f32>, String> {
        match file.metadata.get(key) {
            None => Ok(vec![0.5; latent]),
            Some(text) => {
                let v: Vec<f32> = serde_json::from_str(text).map_err(|e| format!("metadata `{key}`: {e}"))?;
                if v.len() != latent || v.iter().any(|x| !x.is_finite()) {
                    return Err(format!("metadata `{key}`: {latent} finite values expected, found {text}"));
                }
                Ok(v)
            }
        }
    };
    Ok((read(LATENT_SCALE_KEY)?, read(LATENT_OFFSET_KEY)?))
}
