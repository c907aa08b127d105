//! OpenEXR files of float channels, through the `exr` crate (the ecosystem's pure-Rust
//! OpenEXR: every compression, HALF/FLOAT/UINT samples, scanline and tiled files). This module
//! is the runtime's one view of them: an [`ExrImage`] is a single-part image of named f32
//! channels (row 0 at the top) plus `string` header attributes.
//!
//! Writing: FLOAT channels sorted by name, scanline blocks, NO_COMPRESSION or ZIP (16 lines),
//! deterministic bytes, written atomically. Reading: the first part (layer) of any file the
//! `exr` crate reads, its largest resolution level, every channel converted to f32; deep data
//! and subsampled channels are errors. Bad or truncated input is an error naming the file,
//! never a panic.

use exr::prelude::{self as x, ReadChannels, ReadLayers, WritableImage};
use std::io::Cursor;
use std::path::Path;

/// Header attributes the format owns; an [`ExrImage`] attribute may not use these names.
const STANDARD: [&str; 9] = ["channels", "compression", "dataWindow", "displayWindow", "lineOrder",
    "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth", "type"];

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExrImage {
    pub width: usize,
    pub height: usize,
    pub channels: Vec<ExrChannel>,
    /// Extra header attributes of type `string` (name, value), in name order when read.
    pub attributes: Vec<(String, String)>,
}

/// One channel: row-major, row 0 = top, `data.len() == width * height`.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrChannel {
    pub name: String,
    pub data: Vec<f32>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression { None, Zip }

impl ExrImage {
    pub fn new(width: usize, height: usize) -> Self {
        ExrImage { width, height, ..Default::default() }
    }

    pub fn push(&mut self, name: &str, data: Vec<f32>) -> Result<(), String> {
        check_name(name, "channel")?;
        if self.channel(name).is_some() {
            return Err(format!("EXR: duplicate channel {name:?}"));
        }
        if data.len() != self.width * self.height {
            return Err(format!("EXR: channel {name:?} has {} values, expected {}x{} = {}",
                data.len(), self.width, self.height, self.width * self.height));
        }
        self.channels.push(ExrChannel { name: name.to_string(), data });
        Ok(())
    }

    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels.iter().find(|c| c.name == name).map(|c| c.data.as_slice())
    }
}

fn check_name(name: &str, what: &str) -> Result<(), String> {
    if name.is_empty() || name.len() > 255 || name.contains('\0') {
        return Err(format!("EXR: bad {what} name {name:?} (must be 1..=255 bytes without NUL)"));
    }
    Ok(())
}

/// The image as OpenEXR bytes.
pub fn encode(img: &ExrImage, compression: Compression) -> Result<Vec<u8>, String> {
    let (w, h) = (img.width, img.height);
    if w == 0 || h == 0 || w > i32::MAX as usize || h > i32::MAX as usize {
        return Err(format!("EXR: cannot encode a {w}x{h} image"));
    }
    if img.channels.is_empty() {
        return Err("EXR: cannot encode an image without channels".into());
    }
    for (i, c) in img.channels.iter().enumerate() {
        check_name(&c.name, "channel")?;
        if img.channels[..i].iter().any(|d| d.name == c.name) {
            return Err(format!("EXR: duplicate channel {:?}", c.name));
        }
        if c.data.len() != w * h {
            return Err(format!("EXR: channel {:?} has {} values, expected {}", c.name, c.data.len(), w * h));
        }
    }
    let mut attributes = x::LayerAttributes::default();
    for (i, (k, v)) in img.attributes.iter().enumerate() {
        check_name(k, "attribute")?;
        if STANDARD.contains(&k.as_str()) || img.attributes[..i].iter().any(|(k2, _)| k2 == k) {
            return Err(format!("EXR: attribute {k:?} is reserved or duplicated"));
        }
        let value = x::Text::new_or_none(v.as_str()).ok_or_else(|| format!("EXR: attribute {k:?} is not representable as an EXR string"))?;
        let key = x::Text::new_or_none(k.as_str()).ok_or_else(|| format!("EXR: attribute name {k:?} is not representable"))?;
        attributes.other.insert(key, x::AttributeValue::Text(value));
    }
    let channels: x::SmallVec<[x::AnyChannel<x::FlatSamples>; 4]> = img
        .channels
        .iter()
        .map(|c| {
            let name = x::Text::new_or_none(c.name.as_str()).ok_or_else(|| format!("EXR: channel name {:?} is not representable", c.name))?;
            Ok(x::AnyChannel::new(name, x::FlatSamples::F32(c.data.clone())))
        })
        .collect::<Result<_, String>>()?;
    let encoding = x::Encoding {
        compression: match compression {
            Compression::None => x::Compression::Uncompressed,
            Compression::Zip => x::Compression::ZIP16,
        },
        blocks: x::Blocks::ScanLines,
        line_order: x::LineOrder::Increasing,
    };
    let layer = x::Layer::new((w, h), attributes, encoding, x::AnyChannels::sort(channels));
    let mut bytes = Cursor::new(Vec::new());
    x::Image::from_layer(layer).write().non_parallel().to_buffered(&mut bytes).map_err(|e| format!("EXR: {e}"))?;
    let mut bytes = bytes.into_inner();
    sort_header_attributes(&mut bytes)?;
    Ok(bytes)
}

/// Puts the header's attributes in name order. The `exr` crate keeps extra attributes in a
/// `HashMap` and writes them in its (per-process random) order, so with two or more the same
/// image would not give the same bytes twice; reordering entries within the header keeps its
/// size, so the offset table after it stays valid. (A single-part file: magic, version, then
/// `name\0 type\0 size:i32 value` entries up to an empty name.)
fn sort_header_attributes(bytes: &mut [u8]) -> Result<(), String> {
    let bad = || "EXR: malformed header written".to_string();
    let mut at = 8;
    let mut entries: Vec<(Vec<u8>, std::ops::Range<usize>)> = Vec::new();
    loop {
        let name_end = at + bytes.get(at..).ok_or_else(bad)?.iter().position(|&b| b == 0).ok_or_else(bad)?;
        if name_end == at {
            break;
        }
        let type_end = name_end + 1 + bytes.get(name_end + 1..).ok_or_else(bad)?.iter().position(|&b| b == 0).ok_or_else(bad)?;
        let size_bytes: [u8; 4] = bytes.get(type_end + 1..type_end + 5).ok_or_else(bad)?.try_into().map_err(|_| bad())?;
        let end = type_end + 5 + usize::try_from(i32::from_le_bytes(size_bytes)).map_err(|_| bad())?;
        if end > bytes.len() {
            return Err(bad());
        }
        entries.push((bytes[at..name_end].to_vec(), at..end));
        at = end;
    }
    let start = entries.first().map_or(8, |e| e.1.start);
    let mut sorted = entries.clone();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    let header: Vec<u8> = sorted.iter().flat_map(|(_, r)| bytes[r.clone()].to_vec()).collect();
    bytes[start..start + header.len()].copy_from_slice(&header);
    Ok(())
}

/// An image from OpenEXR bytes (the first part, its largest resolution level).
pub fn decode(bytes: &[u8]) -> Result<ExrImage, String> {
    // A corrupt header can claim any size, and the `exr` crate allocates what it claims before
    // reading (an abort, not an error, when that fails). Deflate expands at most 1032:1, so no
    // valid file holds more sample bytes than about 1100 times its own size.
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), true).map_err(|e| format!("EXR: {e}"))?;
    for header in &meta.headers {
        let samples = (header.layer_size.0 as u128) * (header.layer_size.1 as u128) * (header.channels.list.len() as u128) * 4;
        if samples > (bytes.len() as u128) * 1100 {
            return Err(format!("EXR: the header claims {}x{} pixels of {} channels, more than a {}-byte file can hold", header.layer_size.0, header.layer_size.1, header.channels.list.len(), bytes.len()));
        }
    }
    let image = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .pedantic()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| format!("EXR: {e}"))?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let mut channels = Vec::with_capacity(layer.channel_data.list.len());
    for c in &layer.channel_data.list {
        if c.sampling != x::Vec2(1, 1) {
            return Err(format!("EXR: channel {:?} is subsampled ({}x{}); uplift reads full-resolution channels", c.name.to_string(), c.sampling.0, c.sampling.1));
        }
        let data: Vec<f32> = c.sample_data.values_as_f32().collect();
        if data.len() != w * h {
            return Err(format!("EXR: channel {:?} has {} values for {w}x{h} pixels", c.name.to_string(), data.len()));
        }
        channels.push(ExrChannel { name: c.name.to_string(), data });
    }
    let mut attributes: Vec<(String, String)> = layer
        .attributes
        .other
        .iter()
        .chain(image.attributes.other.iter())
        .filter_map(|(k, v)| match v {
            x::AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    attributes.sort();
    Ok(ExrImage { width: w, height: h, channels, attributes })
}

pub fn write(path: &Path, img: &ExrImage, compression: Compression) -> Result<(), String> {
    let bytes = encode(img, compression).map_err(|e| format!("{}: {e}", path.display()))?;
    crate::atomic_write::write_atomically(path, &bytes).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

pub fn read(path: &Path) -> Result<ExrImage, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    decode(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_attributes_give_the_same_bytes_every_time() {
        // The exr crate's attribute map has a random order per instance; the header is sorted.
        let mut img = ExrImage::new(3, 2);
        img.push("a", vec![1.0; 6]).unwrap();
        for k in 0..6 {
            img.attributes.push((format!("attr{k}"), format!("value {k}")));
        }
        let first = encode(&img, Compression::Zip).unwrap();
        for _ in 0..4 {
            assert_eq!(encode(&img, Compression::Zip).unwrap(), first);
        }
        let back = decode(&first).unwrap();
        assert_eq!(back.attributes.len(), 6);
        assert_eq!(back.channel("a").unwrap(), &[1.0; 6]);
    }

    fn sample(w: usize, h: usize, names: &[&str]) -> ExrImage {
        let mut img = ExrImage::new(w, h);
        let specials = [0.0, -0.0, 1.0, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE / 8.0, 3.4e38, f32::NAN];
        for (k, name) in names.iter().enumerate() {
            let data = (0..w * h).map(|i| if i % 23 == 5 { specials[(i / 23 + k) % 8] } else {
                ((i * 2654435761 + k * 97) % 10007) as f32 * 0.37 - 1500.0 }).collect();
            img.push(name, data).unwrap();
        }
        img
    }

    fn bits(v: &[f32]) -> Vec<u32> { v.iter().map(|x| x.to_bits()).collect() }

    fn assert_same(a: &ExrImage, b: &ExrImage) {
        assert_eq!((a.width, a.height, a.channels.len()), (b.width, b.height, b.channels.len()));
        for c in &a.channels {
            assert_eq!(bits(&c.data), bits(b.channel(&c.name).unwrap()), "channel {}", c.name);
        }
    }

    /// The 2x1 single-channel "Y" image, NO_COMPRESSION, written byte by byte from the spec.
    fn tiny(pixel_type: u8, pixels: &[u8]) -> Vec<u8> {
        let mut b: Vec<u8> = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
        b.extend(b"channels\0chlist\0\x13\0\0\0Y\0"); // size 19 = "Y\0" + 16 + terminating 0
        b.extend([pixel_type, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0]);
        b.extend(b"compression\0compression\0\x01\0\0\0\0");
        for name in [&b"dataWindow\0"[..], b"displayWindow\0"] {
            b.extend(name);
            b.extend(b"box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x01\0\0\0\0\0\0\0"); // (0,0)-(1,0)
        }
        b.extend(b"lineOrder\0lineOrder\0\x01\0\0\0\0");
        b.extend(b"pixelAspectRatio\0float\0\x04\0\0\0\0\0\x80\x3f");
        b.extend(b"screenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0\0\0\0");
        b.extend(b"screenWindowWidth\0float\0\x04\0\0\0\0\0\x80\x3f\0");
        assert_eq!(b.len(), 277);
        b.extend([0x1d, 0x01, 0, 0, 0, 0, 0, 0]); // offset table: the one chunk starts at 285
        b.extend([0, 0, 0, 0, pixels.len() as u8, 0, 0, 0]); // y = 0, data size
        b.extend(pixels);
        b
    }

    #[test]
    fn known_good_tiny_exr_from_the_spec_is_read() {
        let file = tiny(2, &[0, 0, 0xc0, 0x3f, 0, 0, 0, 0xc0]); // 1.5, -2.0
        let img = decode(&file).unwrap();
        assert_eq!((img.width, img.height, img.channels.len()), (2, 1, 1));
        assert_eq!((img.channels[0].name.as_str(), img.channel("Y").unwrap()), ("Y", &[1.5f32, -2.0][..]));
        assert_same(&img, &decode(&encode(&img, Compression::None).unwrap()).unwrap());
        // HALF samples: 1.5, -2.0, and the edge cases of the half → f32 conversion.
        let half = decode(&tiny(1, &[0x00, 0x3e, 0x00, 0xc0])).unwrap();
        assert_eq!(half.channel("Y").unwrap(), &[1.5f32, -2.0]);
        for (h, f) in [(0x3c00u16, 1.0f32), (0x8000, -0.0), (0x0001, 5.960_464_5e-8), (0x7bff, 65504.0), (0x03ff, 6.097_555e-5), (0xfc00, f32::NEG_INFINITY)] {
            let [a, b] = h.to_le_bytes();
            let img = decode(&tiny(1, &[a, b, a, b])).unwrap();
            assert_eq!(img.channel("Y").unwrap()[0].to_bits(), f.to_bits(), "{h:#x}");
        }
    }

    #[test]
    fn round_trip_none_and_zip_odd_sizes() {
        for (w, h) in [(37, 19), (1, 1), (300, 17), (5, 32), (2, 33)] {
            let img = sample(w, h, &["reflectivity.R", "metalness", "a"]);
            for comp in [Compression::None, Compression::Zip] {
                let back = decode(&encode(&img, comp).unwrap()).unwrap();
                assert_same(&img, &back);
            }
        }
    }

    #[test]
    fn zip_compresses_smooth_data_and_stores_noise_raw() {
        let mut smooth = ExrImage::new(64, 40);
        smooth.push("Y", (0..64 * 40).map(|i| (i % 64) as f32 * 0.5).collect()).unwrap();
        let (none, zip) = (encode(&smooth, Compression::None).unwrap(), encode(&smooth, Compression::Zip).unwrap());
        assert!(zip.len() * 4 < none.len(), "{} vs {}", zip.len(), none.len());
        assert_same(&smooth, &decode(&zip).unwrap());
        let mut noise = ExrImage::new(16, 3);
        let mut s = 1u32;
        noise.push("N", (0..48).map(|_| { s = s.wrapping_mul(1664525).wrapping_add(1013904223); f32::from_bits(s >> 2) }).collect()).unwrap();
        let zip = encode(&noise, Compression::Zip).unwrap();
        assert_same(&noise, &decode(&zip).unwrap());
    }

    #[test]
    fn zips_single_line_blocks_are_read() {
        let img = sample(9, 1, &["B", "G", "R"]);
        let mut file = encode(&img, Compression::Zip).unwrap();
        let at = file.windows(15).position(|w| w == b"compression\0com").unwrap() + 28;
        assert_eq!(file[at], 3);
        file[at] = 2; // with one scanline a ZIP file is also a valid ZIPS file
        assert_same(&img, &decode(&file).unwrap());
    }

    #[test]
    fn deterministic_bytes_and_channel_order() {
        let img = sample(37, 19, &["b", "A", "reflectivity.R", "a", "metalness"]);
        let copy = img.clone();
        assert_eq!(encode(&img, Compression::Zip).unwrap(), encode(&copy, Compression::Zip).unwrap());
        assert_eq!(encode(&img, Compression::None).unwrap(), encode(&copy, Compression::None).unwrap());
        let back = decode(&encode(&img, Compression::Zip).unwrap()).unwrap();
        let names: Vec<&str> = back.channels.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["A", "a", "b", "metalness", "reflectivity.R"]);
    }

    #[test]
    fn attributes_and_long_names_round_trip() {
        let mut img = sample(3, 2, &["a.very.long.channel.name.over.thirty.one.bytes"]);
        img.attributes.push(("uplift.source".into(), "scene.mtlx, seed 7".into()));
        let back = decode(&encode(&img, Compression::Zip).unwrap()).unwrap();
        assert_eq!(back.attributes, img.attributes);
        assert_same(&img, &back);
        img.attributes.push(("compression".into(), "x".into()));
        assert!(encode(&img, Compression::None).is_err());
    }

    #[test]
    fn bad_images_are_rejected_on_encode_and_push() {
        let mut img = ExrImage::new(2, 2);
        assert!(img.push("Y", vec![0.0; 3]).unwrap_err().contains("expected 2x2"));
        assert!(img.push("", vec![0.0; 4]).is_err());
        img.push("Y", vec![0.0; 4]).unwrap();
        assert!(img.push("Y", vec![0.0; 4]).unwrap_err().contains("duplicate"));
        assert!(encode(&ExrImage::new(2, 2), Compression::Zip).is_err());
        assert!(encode(&ExrImage::new(0, 3), Compression::Zip).is_err());
        img.channels[0].data.pop();
        assert!(encode(&img, Compression::None).is_err());
    }

    #[test]
    fn truncated_and_corrupt_input_errors() {
        for comp in [Compression::None, Compression::Zip] {
            let file = encode(&sample(7, 18, &["G", "R"]), comp).unwrap();
            for n in 0..file.len() {
                assert!(decode(&file[..n]).is_err(), "truncated to {n} bytes decoded");
            }
            let mut s = 7u32; // flipped bytes must not panic (errors or garbage values are both fine)
            for _ in 0..3000 {
                let mut f = file.clone();
                for _ in 0..3 {
                    s = s.wrapping_mul(1664525).wrapping_add(1013904223);
                    let i = (s >> 8) as usize % f.len();
                    f[i] ^= 1 << (s % 8);
                }
                let _ = decode(&f);
            }
        }
        let file = encode(&sample(4, 3, &["Y"]), Compression::Zip).unwrap();
        let mut bad = file.clone();
        bad[0] = b'P';
        assert!(decode(&bad).is_err(), "a file without the magic number");
    }

    #[test]
    fn write_and_read_files_name_the_path() {
        let dir = std::env::temp_dir().join(format!("uplift_exr_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.exr");
        let img = sample(5, 4, &["Y"]);
        write(&path, &img, Compression::Zip).unwrap();
        assert_same(&img, &read(&path).unwrap());
        std::fs::write(&path, b"v/1\x01junk").unwrap();
        let e = read(&path).unwrap_err();
        assert!(e.contains("a.exr") && e.contains("EXR"), "{e}");
        assert!(read(&dir.join("missing.exr")).unwrap_err().contains("missing.exr"));
        assert!(write(&path, &ExrImage::new(1, 1), Compression::None).unwrap_err().contains("a.exr"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
    const PY: &str = r#"
import sys, OpenEXR, numpy as np
if sys.argv[1] == "read":
    for p in sys.argv[2:]:
        for name, ch in sorted(OpenEXR.File(p, separate_channels=True).channels().items()):
            a = ch.pixels
            print(p, name, a.dtype.name, a.shape[0], a.shape[1], a.astype("<f4").tobytes().hex())
else:
    h, w = 21, 23
    i = np.arange(h * w).reshape(h, w)
    chans = {"Y": (i * 0.25 - 3.0).astype(np.float32), "H": ((i % 200 - 100) * 0.125).astype(np.float16)}
    hdr = {"compression": getattr(OpenEXR, sys.argv[3]), "type": OpenEXR.scanlineimage}
    OpenEXR.File(hdr, chans).write(sys.argv[2])
"#;

    #[test]
    fn python_openexr_reads_our_files() {
        let Some(py) = std::env::var_os("UPLIFT_PYTHON_EXR") else {
            crate::test_env::skip("python_openexr_reads_our_files", "set UPLIFT_PYTHON_EXR to a python3 with OpenEXR>=3 and numpy (.ci/run does)");
            return;
        };
        let dir = std::env::temp_dir().join(format!("uplift_exr_py_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let run = |args: &[&std::ffi::OsStr]| {
            let out = std::process::Command::new(&py).arg("-c").arg(PY).args(args).output().unwrap();
            assert!(out.status.success(), "python failed: {}", String::from_utf8_lossy(&out.stderr));
            String::from_utf8(out.stdout).unwrap()
        };
        let img = sample(37, 19, &["reflectivity.R", "metalness", "a"]);
        let paths = [dir.join("zip.exr"), dir.join("none.exr")];
        write(&paths[0], &img, Compression::Zip).unwrap();
        write(&paths[1], &img, Compression::None).unwrap();
        let out = run(&["read".as_ref(), paths[0].as_os_str(), paths[1].as_os_str()]);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 6, "{out}");
        for line in lines {
            let f: Vec<&str> = line.split(' ').collect();
            assert_eq!(f[2..5], ["float32", "19", "37"], "{line}");
            let want: String = img.channel(f[1]).unwrap().iter().map(|v| v.to_le_bytes().iter().map(|b| format!("{b:02x}")).collect::<String>()).collect();
            assert_eq!(f[5], want, "channel {} of {}", f[1], f[0]);
        }
        for comp in ["ZIP_COMPRESSION", "ZIPS_COMPRESSION", "NO_COMPRESSION"] {
            let path = dir.join(format!("{comp}.exr"));
            run(&["write".as_ref(), path.as_os_str(), comp.as_ref()]);
            let back = read(&path).unwrap();
            assert_eq!((back.width, back.height), (23, 21));
            let names: Vec<&str> = back.channels.iter().map(|c| c.name.as_str()).collect();
            assert_eq!(names, ["H", "Y"]);
            for i in 0..23 * 21 {
                assert_eq!(back.channel("Y").unwrap()[i], i as f32 * 0.25 - 3.0, "{comp} Y[{i}]");
                assert_eq!(back.channel("H").unwrap()[i], ((i % 200) as f32 - 100.0) * 0.125, "{comp} H[{i}]");
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
