//! The parameters of the non-diffuse component (lobes.md §3), in the order of the
//! `uplift_stack` node's inputs, with their ranges and how the encoder sees them — derived at
//! build time from the stack's nodedef (`uisoftmin`/`uisoftmax`, else `uimin`/`uimax`, and
//! `uplift_encoding`; runtime/engines/build/stack_table.rs). One table serves the data
//! generator (ranges for the infill class), the encoder (normalisation), the fitter
//! (`params.exr` channel names), the kernels (input name and component) and the decoder file's
//! stack signature.

/// How a parameter is mapped to the encoder's [0, 1] input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// (x − lo) / (hi − lo).
    Linear,
    /// (√x − √lo) / (√hi − √lo): GGX alphas, so the encoder sees perceptual roughness.
    Sqrt,
}

/// One scalar parameter.
#[derive(Clone, Copy, Debug)]
pub struct Parameter {
    /// The `uplift_stack` input it belongs to.
    pub input: &'static str,
    /// Its component in that input.
    pub component: usize,
    /// Its channel in `params.exr` (`input` or `input.R/G/B`).
    pub channel: &'static str,
    pub lo: f32,
    pub hi: f32,
    pub encoding: Encoding,
}

const fn p(input: &'static str, component: usize, channel: &'static str, lo: f32, hi: f32, encoding: Encoding) -> Parameter {
    Parameter { input, component, channel, lo, hi, encoding }
}

use Encoding::{Linear, Sqrt};

// `PARAMETERS` and `PARAMETER_TABLE`, derived from the stack's nodedef by build.rs.
include!(concat!(env!("OUT_DIR"), "/stack_parameters.rs"));

/// Index of a named parameter in [`PARAMETER_TABLE`] (by its channel name).
pub fn index_of(channel: &str) -> Option<usize> {
    PARAMETER_TABLE.iter().position(|p| p.channel == channel)
}

impl Parameter {
    /// The encoder's input for value `x` (not clamped: values outside the range stay visible).
    pub fn encode(&self, x: f32) -> f32 {
        match self.encoding {
            Encoding::Linear => (x - self.lo) / (self.hi - self.lo),
            Encoding::Sqrt => (x.max(0.0).sqrt() - self.lo.sqrt()) / (self.hi.sqrt() - self.lo.sqrt()),
        }
    }

    /// The value at encoded position `t` ∈ [0, 1] (uniform draws for the infill class).
    pub fn decode(&self, t: f32) -> f32 {
        match self.encoding {
            Encoding::Linear => self.lo + t * (self.hi - self.lo),
            Encoding::Sqrt => {
                let s = self.lo.sqrt() + t * (self.hi.sqrt() - self.lo.sqrt());
                s * s
            }
        }
    }
}

impl Encoding {
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Linear => "linear",
            Encoding::Sqrt => "sqrt",
        }
    }
}

impl Parameter {
    /// `channel[lo,hi]encoding`, the parameter's entry in a stack signature.
    fn signature_entry(&self) -> String {
        format!("{}[{:?},{:?}]{}", self.channel, self.lo, self.hi, self.encoding.name())
    }
}

/// The stack signature a decoder file records (its `stack` metadata): every parameter's
/// channel, encoder range and encoding, in order, space-separated.
pub fn signature() -> String {
    PARAMETER_TABLE.iter().map(Parameter::signature_entry).collect::<Vec<_>>().join(" ")
}

/// Checks a decoder file's recorded signature against this build's stack; the error names the
/// first difference (a parameter changed, added or removed).
pub fn check_signature(recorded: &str) -> Result<(), String> {
    let theirs: Vec<&str> = recorded.split_whitespace().collect();
    let ours: Vec<String> = PARAMETER_TABLE.iter().map(Parameter::signature_entry).collect();
    for k in 0..theirs.len().max(ours.len()) {
        match (theirs.get(k), ours.get(k)) {
            (Some(a), Some(b)) if *a == b.as_str() => {}
            (Some(a), Some(b)) => return Err(format!("it was trained for another uplift_stack: parameter {} is `{a}` there and `{b}` here", k + 1)),
            (Some(a), None) => return Err(format!("it was trained for another uplift_stack: parameter {} `{a}` is not in this stack ({} parameters here, {} there)", k + 1, ours.len(), theirs.len())),
            (None, Some(b)) => return Err(format!("it was trained for another uplift_stack: parameter {} `{b}` of this stack is not there ({} parameters here, {} there)", k + 1, ours.len(), theirs.len())),
            (None, None) => unreachable!(),
        }
    }
    Ok(())
}

/// Encodes rows of [`PARAMETERS`] parameters for the encoder.
pub fn encode_rows(params: &[f32], out: &mut [f32]) {
    assert_eq!(params.len(), out.len());
    for (row, enc) in params.chunks_exact(PARAMETERS).zip(out.chunks_exact_mut(PARAMETERS)) {
        for ((x, e), p) in row.iter().zip(enc.iter_mut()).zip(&PARAMETER_TABLE) {
            *e = p.encode(*x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The build script's table against the nodedef as the runtime's own reader sees it in the
    /// builtin library: the same inputs and components in order, the encoder's range inside
    /// each input's `uimin`/`uimax`, equal to `uisoftmin`/`uisoftmax` where given, and the
    /// encoding from `uplift_encoding`.
    #[test]
    fn a_signature_names_its_first_difference() {
        let ours = signature();
        assert!(check_signature(&ours).is_ok());
        assert!(ours.starts_with("reflectivity.R[0.0,0.99]linear "), "{ours}");
        let changed = ours.replace("haze_weight[0.05,0.6]linear", "haze_weight[0.0,1.0]linear");
        let e = check_signature(&changed).unwrap_err();
        assert!(e.contains("parameter 10 is `haze_weight[0.0,1.0]linear` there and `haze_weight[0.05,0.6]linear` here"), "{e}");
        let e = check_signature(&format!("{ours} film_ior[1.2,2.0]linear")).unwrap_err();
        assert!(e.contains(&format!("parameter {} `film_ior[1.2,2.0]linear` is not in this stack", PARAMETERS + 1)), "{e}");
        let shorter: Vec<&str> = ours.split(' ').take(PARAMETERS - 1).collect();
        let e = check_signature(&shorter.join(" ")).unwrap_err();
        assert!(e.contains(&format!("parameter {PARAMETERS} `subcutaneous_roughness[0.4,1.0]linear` of this stack is not there")), "{e}");
    }

    #[test]
    fn table_is_the_stack_nodedef() {
        let compiler = uplift_compiler::Compiler::builtin();
        let (doc, nd) = compiler
            .library
            .defs
            .documents
            .iter()
            .find_map(|d| d.top_level().iter().find(|&&e| d.get(e).category == "nodedef" && d.get(e).name() == "ND_uplift_stack").map(|&e| (d.clone(), e)))
            .expect("ND_uplift_stack in the builtin library");
        let mut rows = PARAMETER_TABLE.iter();
        for input in doc.children_of(nd, "input").map(|i| doc.get(i)).filter(|i| i.attr("defaultgeomprop").is_none()) {
            let components = mtlx::DataType::from_name(input.attr("type").unwrap()).components().unwrap();
            let list = |a: &str| input.attr(a).map(|t| t.split(',').map(|v| v.trim().parse::<f32>().unwrap()).collect::<Vec<_>>());
            let pick = |v: &Option<Vec<f32>>, c: usize| v.as_ref().map(|v| if v.len() == 1 { v[0] } else { v[c] });
            for c in 0..components {
                let p = rows.next().unwrap_or_else(|| panic!("the table ends before `{}`", input.name()));
                assert_eq!((p.input, p.component), (input.name(), c));
                let (umin, umax) = (pick(&list("uimin"), c).unwrap(), pick(&list("uimax"), c).unwrap());
                assert!(umin <= p.lo && p.hi <= umax, "{}: [{}, {}] outside [{umin}, {umax}]", p.channel, p.lo, p.hi);
                assert_eq!((p.lo, p.hi), (pick(&list("uisoftmin"), c).unwrap_or(umin), pick(&list("uisoftmax"), c).unwrap_or(umax)), "{}", p.channel);
                let sqrt = input.attr("uplift_encoding") == Some("sqrt");
                assert_eq!(p.encoding, if sqrt { Encoding::Sqrt } else { Encoding::Linear }, "{}", p.channel);
            }
        }
        assert!(rows.next().is_none(), "the table has parameters the nodedef does not");
    }

    #[test]
    fn table_follows_the_uplift_stack_inputs() {
        // Each input's components are consecutive, starting at 0.
        let mut previous = "";
        let mut next = 0;
        for p in &PARAMETER_TABLE {
            if p.input != previous {
                previous = p.input;
                next = 0;
            }
            assert_eq!(p.component, next, "{}", p.channel);
            next += 1;
            assert!(p.lo < p.hi);
            assert!((p.decode(p.encode(0.5 * (p.lo + p.hi))) - 0.5 * (p.lo + p.hi)).abs() < 1e-6);
            assert_eq!(index_of(p.channel).map(|i| PARAMETER_TABLE[i].channel), Some(p.channel));
        }
    }
}
