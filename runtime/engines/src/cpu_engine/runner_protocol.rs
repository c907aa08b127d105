//! The wire format between the CPU engine and the kernel runners it builds (`external.rs`): a
//! request on the runner's stdin, the output columns on its stdout, all little-endian. Copied
//! verbatim into every runner crate, like `driver.rs`; std only.
//!
//! Request: `b"UPLK"`, version (u32), points n (u64), geometry, input and output column counts,
//! threads, texture count (u32 each); per texture width, height (u32) and `width × height × 4`
//! floats; then the geometry columns and the input columns (column-major f32). Response: the
//! output columns (column-major f32).

use std::borrow::Cow;

pub const MAGIC: [u8; 4] = *b"UPLK";
pub const VERSION: u32 = 1;

/// A request: borrowed from the caller's batch when encoding, owned when decoded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Request<'a> {
    pub n: usize,
    pub geometry_columns: usize,
    pub input_columns: usize,
    pub output_columns: usize,
    pub threads: usize,
    /// (width, height, RGBA floats) per texture.
    pub textures: Vec<(u32, u32, Cow<'a, [f32]>)>,
    pub geometry: Cow<'a, [f32]>,
    pub inputs: Cow<'a, [f32]>,
}

pub fn encode_request(r: &Request<'_>) -> Vec<u8> {
    let floats = r.geometry.len() + r.inputs.len() + r.textures.iter().map(|t| t.2.len()).sum::<usize>();
    let mut out = Vec::with_capacity(40 + 4 * floats);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(r.n as u64).to_le_bytes());
    for v in [r.geometry_columns, r.input_columns, r.output_columns, r.threads, r.textures.len()] {
        out.extend_from_slice(&(v as u32).to_le_bytes());
    }
    for (w, h, rgba) in &r.textures {
        out.extend_from_slice(&w.to_le_bytes());
        out.extend_from_slice(&h.to_le_bytes());
        encode_floats_into(rgba, &mut out);
    }
    encode_floats_into(&r.geometry, &mut out);
    encode_floats_into(&r.inputs, &mut out);
    out
}

pub fn decode_request(bytes: &[u8]) -> Result<Request<'static>, String> {
    let mut at = 0usize;
    let mut take = |k: usize| -> Result<&[u8], String> {
        let s = bytes.get(at..at + k).ok_or_else(|| format!("request truncated at byte {at}"))?;
        at += k;
        Ok(s)
    };
    if take(4)? != MAGIC {
        return Err("not an uplift kernel request".into());
    }
    let version = u32::from_le_bytes(take(4)?.try_into().unwrap());
    if version != VERSION {
        return Err(format!("request version {version}; this runner reads {VERSION}"));
    }
    let n = u64::from_le_bytes(take(8)?.try_into().unwrap()) as usize;
    let mut u = [0usize; 5];
    for v in u.iter_mut() {
        *v = u32::from_le_bytes(take(4)?.try_into().unwrap()) as usize;
    }
    let [geometry_columns, input_columns, output_columns, threads, texture_count] = u;
    let mut textures = Vec::with_capacity(texture_count);
    for _ in 0..texture_count {
        let w = u32::from_le_bytes(take(4)?.try_into().unwrap());
        let h = u32::from_le_bytes(take(4)?.try_into().unwrap());
        let k = w as usize * h as usize * 4;
        textures.push((w, h, Cow::Owned(decode_floats(take(4 * k)?)?)));
    }
    let geometry = Cow::Owned(decode_floats(take(4 * n * geometry_columns)?)?);
    let inputs = Cow::Owned(decode_floats(take(4 * n * input_columns)?)?);
    if at != bytes.len() {
        return Err(format!("{} bytes after the request", bytes.len() - at));
    }
    Ok(Request { n, geometry_columns, input_columns, output_columns, threads, textures, geometry, inputs })
}

/// Appends `values` as little-endian f32s. On a little-endian machine that is their memory
/// as it is: one copy, fast even in the runner's opt-level-0 builds (a per-float loop there
/// took minutes for a request carrying textures).
pub fn encode_floats_into(values: &[f32], out: &mut Vec<u8>) {
    if cfg!(target_endian = "little") {
        // SAFETY: the slice's memory is 4 · len initialised bytes, and u8 has no alignment
        // or validity requirements.
        out.extend_from_slice(unsafe { std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), std::mem::size_of_val(values)) });
    } else {
        out.reserve(4 * values.len());
        for v in values {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
}

pub fn decode_floats(bytes: &[u8]) -> Result<Vec<f32>, String> {
    if !bytes.len().is_multiple_of(4) {
        return Err(format!("{} bytes are not whole floats", bytes.len()));
    }
    if cfg!(target_endian = "little") {
        let mut out = vec![0.0f32; bytes.len() / 4];
        // SAFETY: `out` owns exactly bytes.len() bytes, the two do not overlap, and every bit
        // pattern is a valid f32.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), out.as_mut_ptr().cast::<u8>(), bytes.len()) };
        return Ok(out);
    }
    Ok(bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip_and_truncation_is_an_error() {
        let r = Request {
            n: 2,
            geometry_columns: 1,
            input_columns: 2,
            output_columns: 3,
            threads: 1,
            textures: vec![(1, 1, Cow::Borrowed(&[0.5, 0.25, 0.125, 1.0][..]))],
            geometry: Cow::Borrowed(&[1.0, 2.0]),
            inputs: Cow::Borrowed(&[3.0, 4.0, 5.0, 6.0]),
        };
        let bytes = encode_request(&r);
        assert_eq!(decode_request(&bytes).unwrap(), r);
        let err = decode_request(&bytes[..bytes.len() - 2]).unwrap_err();
        assert!(err.contains("truncated"), "{err}");
    }
}
