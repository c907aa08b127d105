//! A small OpenEXR 2.0 reader/writer for float images: single-part scanline files only.
//! Writing: FLOAT (pixel type 2) channels, compression NO_COMPRESSION (0) or ZIP (3: blocks of 16
//! scanlines, zlib over the EXR predictor + byte interleaving; a block that would not shrink is
//! stored raw, as the spec says), deterministic bytes, optional `string` attributes.
//! Reading: NO_COMPRESSION, ZIPS (2, 1 line), ZIP (3); HALF (converted to f32) and FLOAT channels.
//! Everything else (tiled, multipart, deep, UINT, subsampled, other compressions) is an error
//! naming what is unsupported; bad or truncated input is an error with a byte offset, never a panic.

use std::path::Path;

const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
const STANDARD: [&str; 9] = ["channels", "compression", "dataWindow", "displayWindow", "lineOrder",
    "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth", "type"];
const COMPRESSIONS: [&str; 10] = ["NO", "RLE", "ZIPS", "ZIP", "PIZ", "PXR24", "B44", "B44A", "DWAA", "DWAB"];

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExrImage {
    pub width: usize,
    pub height: usize,
    pub channels: Vec<ExrChannel>,
    /// Extra header attributes of type `string` (name, value); written after the standard ones.
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

fn attr(out: &mut Vec<u8>, name: &str, ty: &str, value: &[u8]) {
    for s in [name, ty] {
        out.extend_from_slice(s.as_bytes());
        out.push(0);
    }
    out.extend_from_slice(&(value.len() as i32).to_le_bytes());
    out.extend_from_slice(value);
}

pub fn encode(img: &ExrImage, compression: Compression) -> Result<Vec<u8>, String> {
    let (w, h) = (img.width, img.height);
    if w == 0 || h == 0 || w > i32::MAX as usize || h > i32::MAX as usize {
        return Err(format!("EXR: cannot encode a {w}x{h} image"));
    }
    if img.channels.is_empty() {
        return Err("EXR: cannot encode an image without channels".into());
    }
    let mut chans: Vec<&ExrChannel> = img.channels.iter().collect();
    chans.sort_by(|a, b| a.name.as_bytes().cmp(b.name.as_bytes()));
    for (i, c) in chans.iter().enumerate() {
        check_name(&c.name, "channel")?;
        if i > 0 && chans[i - 1].name == c.name {
            return Err(format!("EXR: duplicate channel {:?}", c.name));
        }
        if c.data.len() != w * h {
            return Err(format!("EXR: channel {:?} has {} values, expected {}", c.name, c.data.len(), w * h));
        }
    }
    for (i, (k, v)) in img.attributes.iter().enumerate() {
        check_name(k, "attribute")?;
        if STANDARD.contains(&k.as_str()) || img.attributes[..i].iter().any(|(k2, _)| k2 == k) {
            return Err(format!("EXR: attribute {k:?} is reserved or duplicated"));
        }
        if v.len() > i32::MAX as usize {
            return Err(format!("EXR: attribute {k:?} is too long"));
        }
    }
    let long = chans.iter().map(|c| &c.name).chain(img.attributes.iter().map(|(k, _)| k)).any(|n| n.len() > 31);
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&(2u32 | if long { 0x400 } else { 0 }).to_le_bytes());
    let mut chlist = Vec::new();
    for c in &chans {
        chlist.extend_from_slice(c.name.as_bytes());
        chlist.push(0);
        for v in [2i32, 0, 1, 1] {
            chlist.extend_from_slice(&v.to_le_bytes()); // FLOAT, pLinear + reserved, xSampling, ySampling
        }
    }
    chlist.push(0);
    attr(&mut out, "channels", "chlist", &chlist);
    let (code, lines) = match compression { Compression::None => (0u8, 1), Compression::Zip => (3, 16) };
    attr(&mut out, "compression", "compression", &[code]);
    let window: Vec<u8> = [0, 0, w as i32 - 1, h as i32 - 1].iter().flat_map(|v| v.to_le_bytes()).collect();
    attr(&mut out, "dataWindow", "box2i", &window);
    attr(&mut out, "displayWindow", "box2i", &window);
    attr(&mut out, "lineOrder", "lineOrder", &[0]);
    attr(&mut out, "pixelAspectRatio", "float", &1f32.to_le_bytes());
    attr(&mut out, "screenWindowCenter", "v2f", &[0; 8]);
    attr(&mut out, "screenWindowWidth", "float", &1f32.to_le_bytes());
    for (k, v) in &img.attributes {
        attr(&mut out, k, "string", v.as_bytes());
    }
    out.push(0);
    if w.checked_mul(chans.len() * 4 * lines).is_none_or(|n| n > i32::MAX as usize) {
        return Err(format!("EXR: a {w}-pixel-wide block of {} channels is too large", chans.len()));
    }
    let blocks = h.div_ceil(lines);
    let table = out.len();
    out.resize(table + 8 * blocks, 0);
    for b in 0..blocks {
        let (y0, y1) = (b * lines, h.min(b * lines + lines));
        let mut raw = Vec::with_capacity((y1 - y0) * w * chans.len() * 4);
        for y in y0..y1 {
            for c in &chans {
                raw.extend(c.data[y * w..(y + 1) * w].iter().flat_map(|v| v.to_le_bytes()));
            }
        }
        let data = match compression {
            Compression::Zip => Some(zip_compress(&raw)).filter(|z| z.len() < raw.len()).unwrap_or(raw),
            Compression::None => raw,
        };
        let at = out.len() as u64;
        out[table + 8 * b..table + 8 * b + 8].copy_from_slice(&at.to_le_bytes());
        out.extend_from_slice(&(y0 as i32).to_le_bytes());
        out.extend_from_slice(&(data.len() as i32).to_le_bytes());
        out.extend_from_slice(&data);
    }
    Ok(out)
}

fn zip_compress(raw: &[u8]) -> Vec<u8> {
    let (n, half) = (raw.len(), raw.len().div_ceil(2));
    let mut t = vec![0u8; n];
    for (i, &b) in raw.iter().enumerate() {
        t[if i % 2 == 0 { i / 2 } else { half + i / 2 }] = b;
    }
    for i in (1..n).rev() {
        t[i] = t[i].wrapping_sub(t[i - 1]).wrapping_add(128);
    }
    miniz_oxide::deflate::compress_to_vec_zlib(&t, 6)
}

fn zip_decompress(data: &[u8], n: usize, at: usize) -> Result<Vec<u8>, String> {
    let mut t = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(data, n)
        .map_err(|e| format!("EXR: bad zlib data in block at byte offset {at}: {:?}", e.status))?;
    if t.len() != n {
        return Err(format!("EXR: block at byte offset {at} inflates to {} bytes, expected {n}", t.len()));
    }
    for i in 1..n {
        t[i] = t[i - 1].wrapping_add(t[i]).wrapping_sub(128);
    }
    let half = n.div_ceil(2);
    Ok((0..n).map(|i| t[if i % 2 == 0 { i / 2 } else { half + i / 2 }]).collect())
}

fn half_to_f32(h: u16) -> f32 {
    let (sign, exp, man) = (((h & 0x8000) as u32) << 16, ((h >> 10) & 0x1f) as u32, (h & 0x3ff) as u32);
    match exp {
        0 => f32::from_bits(sign | (man as f32 * 2f32.powi(-24)).to_bits()),
        31 => f32::from_bits(sign | 0x7f80_0000 | (man << 13)),
        _ => f32::from_bits(sign | ((exp + 112) << 23) | (man << 13)),
    }
}

struct Cursor<'a> { b: &'a [u8], pos: usize }

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if n > self.b.len().saturating_sub(self.pos) {
            return Err(format!("EXR: truncated: {what} needs {n} bytes at byte offset {} (file has {})",
                self.pos, self.b.len()));
        }
        self.pos += n;
        Ok(&self.b[self.pos - n..self.pos])
    }
    fn i32(&mut self, what: &str) -> Result<i32, String> {
        Ok(i32::from_le_bytes(self.take(4, what)?.try_into().unwrap()))
    }
    fn cstr(&mut self, what: &str) -> Result<String, String> {
        let rest = &self.b[self.pos.min(self.b.len())..];
        let n = rest.iter().take(256).position(|&c| c == 0)
            .ok_or_else(|| format!("EXR: unterminated or over-long {what} at byte offset {}", self.pos))?;
        let s = String::from_utf8_lossy(&rest[..n]).into_owned();
        self.pos += n + 1;
        Ok(s)
    }
}

pub fn decode(bytes: &[u8]) -> Result<ExrImage, String> {
    let mut c = Cursor { b: bytes, pos: 0 };
    if c.take(4, "magic number")? != MAGIC {
        return Err("EXR: bad magic number at byte offset 0 (not an OpenEXR file)".into());
    }
    let version = u32::from_le_bytes(c.take(4, "version")?.try_into().unwrap());
    for (bit, what) in [(0x200, "tiled images"), (0x800, "deep data"), (0x1000, "multipart files")] {
        if version & bit != 0 {
            return Err(format!("EXR: {what} are not supported (version field {version:#x} at byte offset 4)"));
        }
    }
    if version & 0xff != 2 || version & !0x4ff != 0 {
        return Err(format!("EXR: unsupported version field {version:#x} at byte offset 4"));
    }
    let (mut chans, mut comp, mut window, mut attributes) = (None, None, None, Vec::new());
    loop {
        let name = c.cstr("attribute name")?;
        if name.is_empty() {
            break;
        }
        let ty = c.cstr("attribute type")?;
        let at = c.pos;
        let size = usize::try_from(c.i32("attribute size")?)
            .map_err(|_| format!("EXR: negative size of attribute {name:?} at byte offset {at}"))?;
        let value = c.take(size, &format!("attribute {name:?}"))?;
        let at = c.pos - size;
        let want = match name.as_str() {
            "channels" => "chlist", "compression" => "compression", "dataWindow" => "box2i", "type" => "string",
            _ => &ty,
        };
        if ty != want {
            return Err(format!("EXR: attribute {name:?} at byte offset {at} has type {ty:?}, expected {want:?}"));
        }
        let bad = || format!("EXR: malformed attribute {name:?} at byte offset {at}");
        match name.as_str() {
            "channels" => {
                let mut v = Cursor { b: value, pos: 0 };
                let mut list = Vec::new();
                loop {
                    let cname = v.cstr("channel name").map_err(|_| bad())?;
                    if cname.is_empty() {
                        break;
                    }
                    let f: Vec<i32> = (0..4).map(|_| v.i32("channel")).collect::<Result<_, _>>().map_err(|_| bad())?;
                    if f[0] != 1 && f[0] != 2 {
                        let t = if f[0] == 0 { "UINT".to_string() } else { format!("pixel type {}", f[0]) };
                        return Err(format!("EXR: channel {cname:?} has unsupported {t} (only HALF and FLOAT)"));
                    }
                    if f[2] != 1 || f[3] != 1 {
                        return Err(format!("EXR: channel {cname:?} is subsampled ({}, {}): not supported", f[2], f[3]));
                    }
                    list.push((cname, f[0] == 1));
                }
                if list.is_empty() {
                    return Err(format!("EXR: no channels in attribute at byte offset {at}"));
                }
                chans = Some(list);
            }
            "compression" => comp = Some(*value.first().filter(|_| size == 1).ok_or_else(bad)?),
            "dataWindow" if size == 16 => {
                let v: Vec<i64> = value.chunks(4).map(|b| i32::from_le_bytes(b.try_into().unwrap()) as i64).collect();
                window = Some((v[0], v[1], v[2] - v[0] + 1, v[3] - v[1] + 1));
            }
            "dataWindow" => return Err(bad()),
            "type" if value != b"scanlineimage" => {
                return Err(format!("EXR: image type {:?} is not supported", String::from_utf8_lossy(value)));
            }
            _ if ty == "string" && !STANDARD.contains(&name.as_str()) => {
                attributes.push((name, String::from_utf8_lossy(value).into_owned()));
            }
            _ => {}
        }
    }
    let missing = |what: &str| format!("EXR: header lacks the {what} attribute");
    let chans = chans.ok_or_else(|| missing("channels"))?;
    let comp = comp.ok_or_else(|| missing("compression"))?;
    let (_, y_min, w, h) = window.ok_or_else(|| missing("dataWindow"))?;
    let lines = match comp {
        0 | 2 => 1,
        3 => 16,
        _ => return Err(format!("EXR: compression {} is not supported (only NO, ZIPS, ZIP)",
            COMPRESSIONS.get(comp as usize).map_or(format!("code {comp}"), |s| format!("{s}_COMPRESSION")))),
    };
    if w < 1 || h < 1 {
        return Err(format!("EXR: empty data window ({w}x{h})"));
    }
    let line_bytes: u64 = chans.iter().map(|&(_, half)| if half { 2 } else { 4 }).sum::<u64>() * w as u64;
    // Deflate expands at most ~1032:1, so a real file cannot hold more pixel bytes than this.
    if line_bytes.saturating_mul(h as u64) > (bytes.len() as u64).saturating_mul(if comp == 0 { 1 } else { 1100 }) {
        return Err(format!("EXR: a {w}x{h} data window is implausibly large for a {}-byte file", bytes.len()));
    }
    let (w, h) = (w as usize, h as usize);
    let blocks = h.div_ceil(lines);
    let table: Vec<u64> = (0..blocks).map(|_| c.take(8, "offset table").map(|b| u64::from_le_bytes(b.try_into().unwrap())))
        .collect::<Result<_, _>>()?;
    let mut data: Vec<Vec<f32>> = chans.iter().map(|_| vec![0f32; w * h]).collect();
    let mut seen = vec![false; blocks];
    for (b, &off) in table.iter().enumerate() {
        let mut k = Cursor { b: bytes, pos: usize::try_from(off).unwrap_or(usize::MAX) };
        if k.pos >= bytes.len() {
            return Err(format!("EXR: offset table entry {b} points to byte offset {off}, past the end ({})", bytes.len()));
        }
        let y = k.i32("block y")? as i64 - y_min;
        let at = k.pos - 4;
        if y < 0 || y >= h as i64 || !(y as usize).is_multiple_of(lines) || seen[y as usize / lines] {
            return Err(format!("EXR: bad or repeated block y coordinate {} at byte offset {at}", y + y_min));
        }
        let y = y as usize;
        seen[y / lines] = true;
        let n = (lines.min(h - y) as u64 * line_bytes) as usize;
        let size = k.i32("block size")?;
        let bad_size = || format!("EXR: block size {size} at byte offset {} (expected {}{n})", at + 4, if comp == 0 { "" } else { "<= " });
        let size = usize::try_from(size).ok().filter(|&s| s == n || (comp != 0 && s < n)).ok_or_else(bad_size)?;
        let payload = k.take(size, "block data")?;
        let raw = if size < n { zip_decompress(payload, n, at + 8)? } else { payload.to_vec() };
        let mut p = 0;
        for row in y..y + lines.min(h - y) {
            for (ch, &(_, half)) in data.iter_mut().zip(&chans) {
                let dst = &mut ch[row * w..(row + 1) * w];
                if half {
                    raw[p..p + 2 * w].chunks_exact(2).zip(dst).for_each(|(s, d)| *d = half_to_f32(u16::from_le_bytes([s[0], s[1]])));
                } else {
                    raw[p..p + 4 * w].chunks_exact(4).zip(dst).for_each(|(s, d)| *d = f32::from_le_bytes(s.try_into().unwrap()));
                }
                p += if half { 2 } else { 4 } * w;
            }
        }
    }
    let channels = chans.into_iter().zip(data).map(|((name, _), data)| ExrChannel { name, data }).collect();
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
    fn known_good_tiny_exr_matches_spec() {
        let file = tiny(2, &[0, 0, 0xc0, 0x3f, 0, 0, 0, 0xc0]); // 1.5, -2.0
        let img = decode(&file).unwrap();
        assert_eq!((img.width, img.height, img.channels.len()), (2, 1, 1));
        assert_eq!((img.channels[0].name.as_str(), img.channel("Y").unwrap()), ("Y", &[1.5f32, -2.0][..]));
        assert_eq!(encode(&img, Compression::None).unwrap(), file);
        let half = decode(&tiny(1, &[0x00, 0x3e, 0x00, 0xc0])).unwrap(); // HALF 1.5, -2.0
        assert_eq!(half.channel("Y").unwrap(), &[1.5f32, -2.0]);
    }

    #[test]
    fn half_conversion() {
        for (h, f) in [(0x3c00u16, 1.0f32), (0x8000, -0.0), (0x0001, 5.960_464_5e-8), (0x7bff, 65504.0),
            (0x03ff, 6.097_555e-5), (0xfc00, f32::NEG_INFINITY), (0x3555, 0.333_251_95)] {
            assert_eq!(half_to_f32(h).to_bits(), f.to_bits(), "{h:#x}");
        }
        assert!(half_to_f32(0x7e00).is_nan());
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
        let raw = encode(&noise, Compression::None).unwrap();
        // One ZIP block stored raw: same size as the NONE file (which has 3 one-line blocks, 2 more table entries
        // and chunk headers = 2 * 16 bytes more).
        assert_eq!(zip.len() + 32, raw.len());
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
        let mut smooth = ExrImage::new(4, 3);
        smooth.push("Y", vec![0.5; 12]).unwrap();
        let file = encode(&smooth, Compression::Zip).unwrap();
        assert!(file.len() < encode(&smooth, Compression::None).unwrap().len()); // the block is compressed
        let err = |f: &dyn Fn(&mut Vec<u8>)| { let mut b = file.clone(); f(&mut b); decode(&b).unwrap_err() };
        assert!(err(&|b| b[0] = b'P').contains("magic"));
        assert!(err(&|b| b[5] = 0x02).contains("tiled"));
        assert!(err(&|b| b[5] = 0x10).contains("multipart"));
        assert!(err(&|b| b[5] = 0x08).contains("deep"));
        let comp_at = file.windows(15).position(|w| w == b"compression\0com").unwrap() + 28;
        assert!(err(&|b| b[comp_at] = 4).contains("PIZ_COMPRESSION"));
        let chan_at = file.windows(3).position(|w| w == b"Y\0\x02").unwrap() + 2;
        assert!(err(&|b| b[chan_at] = 0).contains("UINT"));
        let hdr_end = file.windows(22).position(|w| w == b"screenWindowWidth\0floa").unwrap() + 33;
        assert!(err(&|b| b[hdr_end..hdr_end + 8].copy_from_slice(&u64::MAX.to_le_bytes())).contains("past the end"));
        assert!(err(&|b| b[hdr_end] = b[hdr_end].wrapping_add(1)).contains("block y"));
        let size_at = u64::from_le_bytes(file[hdr_end..hdr_end + 8].try_into().unwrap()) as usize + 4;
        assert!(err(&|b| b[size_at] = b[size_at].wrapping_add(100)).contains("block size"));
        assert!(err(&|b| b[size_at + 6] ^= 0xff).contains("offset"));
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
        assert!(e.contains("a.exr") && e.contains("byte offset"), "{e}");
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
            println!("python_openexr_reads_our_files: skipped: set UPLIFT_PYTHON_EXR to a python3 with OpenEXR>=3 and numpy");
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
