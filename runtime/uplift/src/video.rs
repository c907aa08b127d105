//! Lossless MP4 per modality (`uplift export --mp4`): each PNG modality's frames as one H.264
//! video, the form video models' data loaders read. Debian's ffmpeg encodes them (libx264rgb at
//! qp 0: lossless, RGB — no chroma subsampling, for data channels least of all); uplift only
//! speaks its command line and says so when it is missing.
//!
//! Videos hold 8 bits per channel: an 8-bit modality (mask, shaded) exactly as its PNGs (a grey
//! mask replicated into R, G and B), a 16-bit one (normals, positions, base colour, latents)
//! rounded to the nearest of 255 steps, v8 = round(v16 / 257) — the same v, so `meta.json`'s
//! affines decode it. The PNG16 frames stay the lossless record; the video is lossless with
//! respect to that 8-bit rounding. Encoding is deterministic (one thread, bit-exact flags, no
//! metadata): exporting twice gives identical files.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Frames per second of the videos.
pub const VIDEO_FPS: u32 = 16;

/// The modalities with PNG frames, hence videos.
pub const VIDEO_MODALITIES: [&str; 8] = ["normal_camera", "normal_world", "position", "base_color", "latent0", "latent1", "mask", "shaded"];

/// Whether ffmpeg with the libx264rgb encoder is on PATH; the error says how to get it.
pub fn check_ffmpeg() -> Result<(), String> {
    let out = Command::new("ffmpeg").args(["-hide_banner", "-encoders"]).stdin(Stdio::null()).output();
    match out {
        Err(e) => Err(format!("--mp4 needs ffmpeg on PATH ({e}; on Debian: apt-get install ffmpeg)")),
        Ok(o) if !String::from_utf8_lossy(&o.stdout).contains("libx264rgb") => Err("--mp4 needs ffmpeg's libx264rgb encoder, which this ffmpeg lacks (Debian's ffmpeg has it)".into()),
        Ok(_) => Ok(()),
    }
}

/// A PNG frame as 8-bit RGB (width, height, rows of R, G, B): 16-bit values rounded to
/// v16 / 257, grey replicated.
pub fn frame_rgb8(path: &Path) -> Result<(u32, u32, Vec<u8>), String> {
    let img = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (w, h) = (img.width(), img.height());
    let data = match img.color() {
        image::ColorType::L16 | image::ColorType::La16 | image::ColorType::Rgb16 | image::ColorType::Rgba16 => img.into_rgb16().into_raw().into_iter().map(|v| ((v as u32 + 128) / 257) as u8).collect(),
        _ => img.into_rgb8().into_raw(),
    };
    Ok((w, h, data))
}

/// Where modality `name`'s video goes in an export folder.
pub fn video_path(out: &Path, name: &str) -> PathBuf {
    out.join(format!("{name}.mp4"))
}

/// Encodes `out/name/0000.png …` (`frames` of them) into `out/name.mp4`, atomically (a hidden
/// temporary file renamed into place).
pub fn write_modality_video(out: &Path, name: &str, frames: usize) -> Result<(), String> {
    let mut rgb = Vec::new();
    let mut size = None;
    for k in 0..frames {
        let path = crate::export::frame_path(out, name, k, "png");
        let (w, h, data) = frame_rgb8(&path)?;
        if *size.get_or_insert((w, h)) != (w, h) {
            return Err(format!("{}: {w}×{h}, unlike the modality's first frame", path.display()));
        }
        rgb.push(data);
    }
    let (w, h) = size.ok_or_else(|| format!("{}: no frames for a video", out.join(name).display()))?;
    let tmp = out.join(format!(".{name}.mp4.tmp"));
    let mut child = uplift_base::child_process::tie_to_parent(&mut Command::new("ffmpeg"))
        .args(["-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", &format!("{w}x{h}"), "-framerate", &VIDEO_FPS.to_string(), "-i", "pipe:0"])
        .args(["-c:v", "libx264rgb", "-qp", "0", "-preset", "medium", "-pix_fmt", "rgb24", "-threads", "1", "-fflags", "+bitexact", "-flags:v", "+bitexact", "-map_metadata", "-1", "-f", "mp4"])
        .arg(&tmp)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("ffmpeg: {e} (on Debian: apt-get install ffmpeg)"))?;
    let mut stdin = child.stdin.take().ok_or("ffmpeg's stdin")?;
    let written = rgb.iter().try_for_each(|f| stdin.write_all(f));
    drop(stdin);
    let result = child.wait_with_output().map_err(|e| format!("ffmpeg: {e}"))?;
    if !result.status.success() || written.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return Err(format!("ffmpeg could not encode {}: {}", video_path(out, name).display(), String::from_utf8_lossy(&result.stderr).trim()));
    }
    std::fs::rename(&tmp, video_path(out, name)).map_err(|e| format!("{}: {e}", video_path(out, name).display()))
}
