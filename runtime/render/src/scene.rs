//! What the renderer traces: the pinhole camera and the geometry behind the `Scene` trait (the
//! preview sphere here; glTF meshes in mesh.rs), with the hit record the shading needs
//! (position, shading frame, uv).
//!
//! Preview setup (lobes.md §5.2): a unit sphere at the origin, the camera on +z looking at it
//! with a 30° vertical field of view from distance 4.8, so the ball spans ≈ 80 % of the image
//! height. Sphere uv: u = φ / 2π with φ = atan2(x, z) + π, v = 1 − θ / π (v = 1 at the top),
//! tangent along +u.

use std::f32::consts::{PI, TAU};

pub type Vec3 = [f32; 3];

pub fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub fn normalize(a: Vec3) -> Vec3 {
    let l = dot(a, a).sqrt().max(1e-30);
    [a[0] / l, a[1] / l, a[2] / l]
}

pub fn add_scaled(a: Vec3, b: Vec3, s: f32) -> Vec3 {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}

/// A surface hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub position: Vec3,
    /// Geometric normal, facing the incoming ray's side.
    pub geometric_normal: Vec3,
    /// Orthonormal shading frame: tangent, bitangent, normal.
    pub frame: [Vec3; 3],
    pub uv: [f32; 2],
}

impl Hit {
    /// World direction → shading frame (normal +z, tangent +x).
    pub fn to_local(&self, d: Vec3) -> Vec3 {
        [dot(d, self.frame[0]), dot(d, self.frame[1]), dot(d, self.frame[2])]
    }

    /// Shading frame → world direction.
    pub fn to_world(&self, l: Vec3) -> Vec3 {
        let f = &self.frame;
        [0, 1, 2].map(|c| f[0][c] * l[0] + f[1][c] * l[1] + f[2][c] * l[2])
    }

    /// The hit with its shading normal replaced by `n` (world space; turned to the geometric
    /// normal's side), the tangent made orthogonal to it.
    pub fn with_shading_normal(&self, n: Vec3) -> Hit {
        let mut n = normalize(n);
        if !n.iter().all(|x| x.is_finite()) || dot(n, n) < 0.5 {
            return *self;
        }
        if dot(n, self.geometric_normal) < 0.0 {
            n = add_scaled(n, self.geometric_normal, -2.0 * dot(n, self.geometric_normal));
        }
        let t = self.frame[0];
        let t = add_scaled(t, n, -dot(t, n));
        let t = if dot(t, t) > 1e-12 { normalize(t) } else { normalize(cross(self.frame[1], n)) };
        Hit { frame: [t, cross(n, t), n], ..*self }
    }

    /// The origin for a ray leaving the surface in direction `d`, offset off the surface.
    pub fn spawn(&self, d: Vec3) -> Vec3 {
        let s = if dot(d, self.geometric_normal) >= 0.0 { 1.0 } else { -1.0 };
        add_scaled(self.position, self.geometric_normal, s * 1e-4 * (1.0 + dot(self.position, self.position).sqrt()))
    }
}

/// Geometry a ray can hit.
pub trait Scene: Sync {
    /// The nearest hit along o + t·d, t > 0.
    fn intersect(&self, o: Vec3, d: Vec3) -> Option<Hit>;

    /// Whether anything lies along o + t·d, t > 0 (a shadow ray: any hit will do).
    fn occluded(&self, o: Vec3, d: Vec3) -> bool {
        self.intersect(o, d).is_some()
    }

    /// Whether the scene is a glTF mesh, whose materials' baked normals (`normal_space`
    /// "world", surface.rs) are world-space directions of this geometry.
    fn world_space_normals(&self) -> bool {
        false
    }
}

/// The preview sphere.
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    pub fn preview() -> Sphere {
        Sphere { center: [0.0; 3], radius: 1.0 }
    }
}

impl Scene for Sphere {
    fn intersect(&self, o: Vec3, d: Vec3) -> Option<Hit> {
        let oc = add_scaled(o, self.center, -1.0);
        let b = dot(oc, d);
        let c = dot(oc, oc) - self.radius * self.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let t = if -b - sq > 1e-6 { -b - sq } else if -b + sq > 1e-6 { -b + sq } else { return None };
        let position = add_scaled(o, d, t);
        let n = normalize(add_scaled(position, self.center, -1.0));
        let theta = n[1].clamp(-1.0, 1.0).acos();
        let phi = n[0].atan2(n[2]) + PI;
        let uv = [phi / TAU, 1.0 - theta / PI];
        // ∂p/∂φ ∝ (cos φ', 0, −sin φ') with φ' = atan2(x, z); at the poles pick +x.
        let t_raw = [n[2], 0.0, -n[0]];
        let tangent = if dot(t_raw, t_raw) > 1e-12 { normalize(t_raw) } else { [1.0, 0.0, 0.0] };
        let bitangent = cross(n, tangent);
        let geometric_normal = if dot(n, d) > 0.0 { [-n[0], -n[1], -n[2]] } else { n };
        Some(Hit { t, position, geometric_normal, frame: [tangent, bitangent, n], uv })
    }
}

/// A pinhole camera (square pixels; the image's vertical field of view is 2·atan(tan_half_fov)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// tan(vertical fov / 2).
    pub tan_half_fov: f32,
}

impl Camera {
    /// The preview camera: on +z at `distance`, looking at the origin.
    pub fn preview(fov_degrees: f32, distance: f32) -> Camera {
        Camera {
            position: [0.0, 0.0, distance],
            forward: [0.0, 0.0, -1.0],
            right: [1.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            tan_half_fov: (fov_degrees.to_radians() * 0.5).tan(),
        }
    }

    /// A camera at `position` looking at `target`, `up` giving the image's vertical.
    pub fn look_at(position: Vec3, target: Vec3, up: Vec3, fov_degrees: f32) -> Camera {
        let forward = normalize(add_scaled(target, position, -1.0));
        let right = normalize(cross(forward, up));
        Camera { position, forward, right, up: cross(right, forward), tan_half_fov: (fov_degrees.to_radians() * 0.5).tan() }
    }

    /// The image point (x, y) in pixels (y down) where world point `p` projects, and its depth
    /// along the view axis; None behind the camera.
    pub fn project(&self, p: Vec3, width: usize, height: usize) -> Option<(f32, f32, f32)> {
        let d = add_scaled(p, self.position, -1.0);
        let z = dot(d, self.forward);
        if z <= 0.0 {
            return None;
        }
        let aspect = width as f32 / height as f32;
        let sx = dot(d, self.right) / z / (self.tan_half_fov * aspect);
        let sy = dot(d, self.up) / z / self.tan_half_fov;
        Some(((sx + 1.0) * 0.5 * width as f32, (1.0 - sy) * 0.5 * height as f32, z))
    }

    /// The ray through image point (x, y) in pixels (y down), for a `width`×`height` image.
    pub fn ray(&self, x: f32, y: f32, width: usize, height: usize) -> (Vec3, Vec3) {
        let aspect = width as f32 / height as f32;
        let sx = (2.0 * x / width as f32 - 1.0) * self.tan_half_fov * aspect;
        let sy = (1.0 - 2.0 * y / height as f32) * self.tan_half_fov;
        let d = normalize([0, 1, 2].map(|c| self.forward[c] + sx * self.right[c] + sy * self.up[c]));
        (self.position, d)
    }
}
