//! The camera orbit of `uplift export` (paper §5.2: intrinsic videos of an object): `frames`
//! pinhole cameras on a circle around the object (the mesh's unit sphere, centred at the
//! origin), a full turn in azimuth from a seeded start, the elevation varying smoothly (one
//! sine period over the turn), each looking at the origin with +Y up (glTF's up axis); and the
//! cameras in nerfstudio's `transforms.json` layout (OpenGL axes: x right, y up, the camera
//! looking down −z; camera-to-world 4×4 per frame; intrinsics in pixels).

use crate::scene::{Camera, Vec3};
use uplift_base::rng::{mix64, unit_from_key as unit};

/// The orbit's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitOptions {
    pub frames: usize,
    pub width: usize,
    pub height: usize,
    /// Draws the start azimuth and the elevation's phase.
    pub seed: u64,
    /// The field of view across the image's smaller side, degrees.
    pub fov_degrees: f32,
    /// Mean elevation and its swing (degrees above the equator).
    pub elevation_degrees: f32,
    pub elevation_swing_degrees: f32,
    /// Margin around the unit sphere in the smaller side (1: the sphere touches the border).
    pub margin: f32,
}

impl Default for OrbitOptions {
    fn default() -> Self {
        OrbitOptions { frames: 16, width: 512, height: 512, seed: 1, fov_degrees: 40.0, elevation_degrees: 20.0, elevation_swing_degrees: 12.0, margin: 1.1 }
    }
}

impl OrbitOptions {
    pub fn check(&self) -> Result<(), String> {
        if self.frames == 0 || self.width == 0 || self.height == 0 {
            return Err(format!("an orbit needs at least one frame of at least 1×1 pixels (got {} frames of {}×{})", self.frames, self.width, self.height));
        }
        if !(self.fov_degrees > 1.0 && self.fov_degrees < 170.0) {
            return Err(format!("field of view {}°: between 1° and 170°", self.fov_degrees));
        }
        if (self.elevation_degrees.abs() + self.elevation_swing_degrees.abs()) >= 89.0 {
            return Err(format!("elevation {}° ± {}° reaches the pole", self.elevation_degrees, self.elevation_swing_degrees));
        }
        Ok(())
    }

    /// The vertical field of view (degrees) that gives `fov_degrees` across the smaller side.
    pub fn vertical_fov_degrees(&self) -> f32 {
        if self.width >= self.height {
            self.fov_degrees
        } else {
            let t = (self.fov_degrees.to_radians() * 0.5).tan() * self.height as f32 / self.width as f32;
            2.0 * t.atan().to_degrees()
        }
    }

    /// The camera distance at which the unit sphere, times the margin, fills the smaller side.
    pub fn distance(&self) -> f32 {
        self.margin / (self.fov_degrees.to_radians() * 0.5).sin()
    }
}

/// The orbit's cameras.
pub fn orbit(o: &OrbitOptions) -> Result<Vec<Camera>, String> {
    o.check()?;
    let key = mix64(o.seed ^ 0x6f72_6269_74);
    let start = std::f32::consts::TAU * unit(key);
    let phase = std::f32::consts::TAU * unit(key ^ 1);
    let d = o.distance();
    Ok((0..o.frames)
        .map(|k| {
            let turn = std::f32::consts::TAU * k as f32 / o.frames as f32;
            let az = start + turn;
            let el = (o.elevation_degrees + o.elevation_swing_degrees * (turn + phase).sin()).to_radians();
            let position = [d * el.cos() * az.sin(), d * el.sin(), d * el.cos() * az.cos()];
            Camera::look_at(position, [0.0; 3], [0.0, 1.0, 0.0], o.vertical_fov_degrees())
        })
        .collect())
}

/// Camera-to-world in nerfstudio's (OpenGL) convention: columns x = right, y = up, z = −forward,
/// then the position; rows of the 4×4.
pub fn camera_to_world(c: &Camera) -> [[f32; 4]; 4] {
    let col: [Vec3; 4] = [c.right, c.up, c.forward.map(|x| -x), c.position];
    [[col[0][0], col[1][0], col[2][0], col[3][0]], [col[0][1], col[1][1], col[2][1], col[3][1]], [col[0][2], col[1][2], col[2][2], col[3][2]], [0.0, 0.0, 0.0, 1.0]]
}

/// Pinhole intrinsics (fl_x, fl_y, cx, cy) in pixels of a `width`×`height` image from `c`
/// (pixel centres at half-integers, as nerfstudio has them).
pub fn intrinsics(c: &Camera, width: usize, height: usize) -> (f32, f32, f32, f32) {
    let f = 0.5 * height as f32 / c.tan_half_fov;
    (f, f, 0.5 * width as f32, 0.5 * height as f32)
}

/// The cameras as nerfstudio's `transforms.json` (`frame_path(k)` names frame k's image), with
/// the scene's bounding box and up axis.
pub fn nerfstudio_json(cameras: &[Camera], width: usize, height: usize, frame_path: impl Fn(usize) -> String, bounds: (Vec3, Vec3)) -> serde_json::Value {
    let (fl_x, fl_y, cx, cy) = cameras.first().map_or((0.0, 0.0, 0.0, 0.0), |c| intrinsics(c, width, height));
    serde_json::json!({
        "camera_model": "OPENCV",
        "fl_x": fl_x, "fl_y": fl_y, "cx": cx, "cy": cy, "w": width, "h": height,
        "k1": 0.0, "k2": 0.0, "p1": 0.0, "p2": 0.0,
        "up_axis": "+Y",
        "aabb": [bounds.0, bounds.1],
        "frames": cameras.iter().enumerate().map(|(k, c)| serde_json::json!({
            "file_path": frame_path(k),
            "transform_matrix": camera_to_world(c),
        })).collect::<Vec<_>>(),
    })
}

/// Cameras from nerfstudio's `transforms.json` layout (as [`nerfstudio_json`] writes it: square
/// pixels, principal point at the centre): the cameras, the image size and each frame's
/// `file_path`.
pub fn cameras_from_json(v: &serde_json::Value) -> Result<(Vec<Camera>, usize, usize, Vec<String>), String> {
    let num = |k: &str| v[k].as_f64().ok_or_else(|| format!("cameras.json: no number `{k}`"));
    let (w, h, fl_y) = (num("w")? as usize, num("h")? as usize, num("fl_y")?);
    if w == 0 || h == 0 || !(fl_y > 0.0) {
        return Err(format!("cameras.json: w {w}, h {h}, fl_y {fl_y}: not an image"));
    }
    if (num("fl_x")? - fl_y).abs() > 1e-3 * fl_y || (num("cx")? - 0.5 * w as f64).abs() > 1e-3 || (num("cy")? - 0.5 * h as f64).abs() > 1e-3 {
        return Err("cameras.json: only square pixels with the principal point at the image centre are read".into());
    }
    let frames = v["frames"].as_array().ok_or("cameras.json: no `frames`")?;
    let mut cams = Vec::new();
    let mut paths = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        let m = |r: usize, c: usize| f["transform_matrix"][r][c].as_f64().map(|x| x as f32).ok_or_else(|| format!("cameras.json: frame {k}: no transform_matrix[{r}][{c}]"));
        let col = |c: usize| -> Result<Vec3, String> { Ok([m(0, c)?, m(1, c)?, m(2, c)?]) };
        let back = col(2)?;
        cams.push(Camera { position: col(3)?, right: col(0)?, up: col(1)?, forward: back.map(|x| -x), tan_half_fov: (0.5 * h as f64 / fl_y) as f32 });
        paths.push(f["file_path"].as_str().unwrap_or_default().to_string());
    }
    Ok((cams, w, h, paths))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cameras_look_at_the_origin_and_project_it_to_the_centre() {
        let o = OrbitOptions { width: 64, height: 48, ..Default::default() };
        let cams = orbit(&o).unwrap();
        assert_eq!(cams.len(), 16);
        for c in &cams {
            let (x, y, z) = c.project([0.0; 3], 64, 48).unwrap();
            assert!((x - 32.0).abs() < 1e-3 && (y - 24.0).abs() < 1e-3, "{x} {y}");
            assert!((z - o.distance()).abs() < 1e-4);
            // The ray through a pixel projects back onto that pixel.
            let (p, d) = c.ray(10.5, 7.5, 64, 48);
            let (x, y, _) = c.project([p[0] + 3.0 * d[0], p[1] + 3.0 * d[1], p[2] + 3.0 * d[2]], 64, 48).unwrap();
            assert!((x - 10.5).abs() < 1e-3 && (y - 7.5).abs() < 1e-3, "{x} {y}");
            // OpenGL axes: the matrix's third column points away from where the camera looks.
            let m = camera_to_world(c);
            let back = [m[0][2], m[1][2], m[2][2]];
            assert!((back[0] * c.forward[0] + back[1] * c.forward[1] + back[2] * c.forward[2] + 1.0).abs() < 1e-6);
        }
        // The same seed gives the same orbit, another seed another start.
        assert_eq!(orbit(&o).unwrap(), cams);
        assert_ne!(orbit(&OrbitOptions { seed: 2, ..o }).unwrap()[0], cams[0]);
        assert!(orbit(&OrbitOptions { frames: 0, ..o }).is_err());
        // cameras.json reads back as the same cameras.
        let (read, w, h, paths) = cameras_from_json(&nerfstudio_json(&cams, 64, 48, |k| format!("f{k}"), ([-1.0; 3], [1.0; 3]))).unwrap();
        assert_eq!((w, h, paths[3].as_str()), (64, 48, "f3"));
        for (a, b) in read.iter().zip(&cams) {
            let far = [a.position, a.forward, a.right, a.up].iter().zip([b.position, b.forward, b.right, b.up]).map(|(x, y)| (0..3).map(|c| (x[c] - y[c]).abs()).fold(0.0f32, f32::max)).fold(0.0f32, f32::max);
            assert!(far < 1e-6 && (a.tan_half_fov - b.tan_half_fov).abs() < 1e-6, "{a:?} vs {b:?}");
        }
    }
}
