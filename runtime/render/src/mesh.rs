//! Triangle meshes for the renderer: a glTF scene's world-space triangles
//! (enhance::gltf_input::WorldTriangle), moved and scaled into the preview ball's unit sphere
//! (bounding-box centre at the origin, farthest vertex at distance 1) so the preview camera
//! frames them like the ball, behind a bounding-volume hierarchy.
//!
//! BVH: binary, built top-down with the surface area heuristic (16 bins of centroids along the
//! longest axis of the centroids' box; the median when every centroid falls in one bin), leaves
//! of at most 4 triangles; traversal is ordered (the nearer child first, each child's entry
//! distance kept on an explicit stack so that a subtree behind the nearest hit so far is
//! skipped), and a shadow ray stops at its first hit (`Scene::occluded`). Ray–triangle:
//! Möller–Trumbore. A hit interpolates the vertex normals, tangents and uvs
//! barycentrically; the shading frame is the interpolated normal (turned to the geometric
//! normal's side) with the tangent made orthogonal to it. uv is converted from glTF's
//! convention ((0, 0) at the image's top-left) to MaterialX's (v = 1 at the top), which the
//! surface textures use.

use crate::scene::{add_scaled, cross, dot, normalize, Hit, Scene, Vec3};
use uplift_enhance::gltf_input::WorldTriangle;

/// A BVH node: its box, and either two children or a range of `order`.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: first index into `order` and count; inner: left child index and 0 (the right
    /// child is at `left + 1`).
    start: u32,
    count: u32,
}

/// A triangle mesh in the unit sphere.
pub struct Mesh {
    /// Where the source's bounding-box centre was, and its farthest vertex's distance from
    /// there: a source point p is at (p − centre) / radius here.
    pub centre: Vec3,
    pub radius: f32,
    triangles: Vec<WorldTriangle>,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF: usize = 4;
/// Centroid bins of the surface area heuristic.
const BINS: usize = 16;

/// Half the surface area of a box (the heuristic's measure).
fn half_area(lo: Vec3, hi: Vec3) -> f32 {
    let e = [0, 1, 2].map(|c| (hi[c] - lo[c]).max(0.0));
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

/// Where o + t·d enters the box (`inv` = 1/d), if it does before `t_max`.
#[inline(always)]
fn enter(node: &Node, o: Vec3, inv: Vec3, t_max: f32) -> Option<f32> {
    let (mut t0, mut t1) = (0.0f32, t_max);
    for c in 0..3 {
        let (a, b) = ((node.lo[c] - o[c]) * inv[c], (node.hi[c] - o[c]) * inv[c]);
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        // NaN (0·∞ on a box face) keeps the interval: `max`/`min` ignore NaN.
        t0 = t0.max(a);
        t1 = t1.min(b);
    }
    (t0 <= t1).then_some(t0)
}

fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (lo, hi)
}

fn centroid(t: &WorldTriangle) -> Vec3 {
    [0, 1, 2].map(|c| (t.position[0][c] + t.position[1][c] + t.position[2][c]) / 3.0)
}

impl Mesh {
    /// The mesh of `triangles`, moved and scaled so that its bounding box's centre is the
    /// origin and its farthest vertex from there is at distance 1 (directions, hence normals and
    /// tangents, are unchanged; a unit sphere stays the preview ball).
    pub fn new(mut triangles: Vec<WorldTriangle>) -> Result<Mesh, String> {
        if triangles.is_empty() {
            return Err("the mesh has no triangles".into());
        }
        let (lo, hi) = bounds(triangles.iter().flat_map(|t| t.position));
        let centre = [0, 1, 2].map(|c| 0.5 * (lo[c] + hi[c]));
        let radius = triangles.iter().flat_map(|t| t.position).map(|p| dot(add_scaled(p, centre, -1.0), add_scaled(p, centre, -1.0))).fold(0.0f32, f32::max).sqrt();
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!("the mesh's bounding box is degenerate ({lo:?} – {hi:?})"));
        }
        for t in &mut triangles {
            for p in &mut t.position {
                *p = [0, 1, 2].map(|c| (p[c] - centre[c]) / radius);
            }
        }
        let mut mesh = Mesh { centre, radius, order: (0..triangles.len() as u32).collect(), triangles, nodes: Vec::new() };
        let n = mesh.order.len();
        let centroids: Vec<Vec3> = mesh.triangles.iter().map(centroid).collect();
        mesh.nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], start: 0, count: 0 });
        mesh.build(&centroids, 0, 0, n, 0);
        Ok(mesh)
    }

    /// The bounding box of the moved and scaled mesh (lo, hi).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        bounds(self.triangles.iter().flat_map(|t| t.position))
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Fills node `at`, `depth` below the root, with `order[start..end]`, splitting
    /// recursively (`centroids` per triangle). Below depth 40 the split is the median, so the
    /// tree stays within the traversal's stack of 64 whatever the heuristic does.
    fn build(&mut self, centroids: &[Vec3], at: usize, start: usize, end: usize, depth: usize) {
        let tris = &self.triangles;
        let (lo, hi) = bounds(self.order[start..end].iter().flat_map(|&i| tris[i as usize].position));
        self.nodes[at].lo = lo;
        self.nodes[at].hi = hi;
        if end - start <= LEAF {
            self.nodes[at].start = start as u32;
            self.nodes[at].count = (end - start) as u32;
            return;
        }
        let (clo, chi) = bounds(self.order[start..end].iter().map(|&i| centroids[i as usize]));
        let axis = (0..3).max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b]))).unwrap_or(0);
        let sah = if depth < 40 { self.sah_split(centroids, start, end, axis, clo[axis], chi[axis]) } else { None };
        let mid = sah.unwrap_or_else(|| {
            let mid = (start + end) / 2;
            self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]));
            mid
        });
        let left = self.nodes.len();
        self.nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], start: 0, count: 0 });
        self.nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], start: 0, count: 0 });
        self.nodes[at].start = left as u32;
        self.nodes[at].count = 0;
        self.build(centroids, left, start, mid, depth + 1);
        self.build(centroids, left + 1, mid, end, depth + 1);
    }

    /// Partitions `order[start..end]` at the cheapest of the bin boundaries along `axis` (centroid
    /// extent `lo..hi`) by the surface area heuristic; the partition point, or `None` when the
    /// centroids do not spread over two bins.
    fn sah_split(&mut self, centroids: &[Vec3], start: usize, end: usize, axis: usize, lo: f32, hi: f32) -> Option<usize> {
        if !(hi > lo) {
            return None;
        }
        let scale = BINS as f32 / (hi - lo);
        let bin = |i: u32| (((centroids[i as usize][axis] - lo) * scale) as usize).min(BINS - 1);
        let mut boxes = [([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]); BINS];
        let mut counts = [0usize; BINS];
        for &i in &self.order[start..end] {
            let b = bin(i);
            counts[b] += 1;
            for p in self.triangles[i as usize].position {
                for c in 0..3 {
                    boxes[b].0[c] = boxes[b].0[c].min(p[c]);
                    boxes[b].1[c] = boxes[b].1[c].max(p[c]);
                }
            }
        }
        let grow = |acc: &mut (Vec3, Vec3), b: &(Vec3, Vec3)| {
            for c in 0..3 {
                acc.0[c] = acc.0[c].min(b.0[c]);
                acc.1[c] = acc.1[c].max(b.1[c]);
            }
        };
        // Cost of splitting after bin k: left and right areas times their counts.
        let mut right = vec![0.0f32; BINS];
        let mut acc = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let mut n = 0;
        for k in (1..BINS).rev() {
            grow(&mut acc, &boxes[k]);
            n += counts[k];
            right[k] = if n > 0 { half_area(acc.0, acc.1) * n as f32 } else { 0.0 };
        }
        let mut acc = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let (mut n, mut best) = (0, None::<(f32, usize)>);
        for k in 0..BINS - 1 {
            grow(&mut acc, &boxes[k]);
            n += counts[k];
            if n == 0 || n == end - start {
                continue;
            }
            let cost = half_area(acc.0, acc.1) * n as f32 + right[k + 1];
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, k));
            }
        }
        let (_, k) = best?;
        // Partition: bins ≤ k to the left.
        let (mut i, mut j) = (start, end);
        while i < j {
            if bin(self.order[i]) <= k {
                i += 1;
            } else {
                j -= 1;
                self.order.swap(i, j);
            }
        }
        Some(i)
    }

    /// Ray–triangle (Möller–Trumbore): (t, b1, b2) for a hit with t in (t_min, t_max).
    fn hit_triangle(&self, i: usize, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
        let p = &self.triangles[i].position;
        let e1 = add_scaled(p[1], p[0], -1.0);
        let e2 = add_scaled(p[2], p[0], -1.0);
        let q = cross(d, e2);
        let det = dot(e1, q);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = add_scaled(o, p[0], -1.0);
        let b1 = dot(s, q) * inv;
        if !(0.0..=1.0).contains(&b1) {
            return None;
        }
        let r = cross(s, e1);
        let b2 = dot(d, r) * inv;
        if b2 < 0.0 || b1 + b2 > 1.0 {
            return None;
        }
        let t = dot(e2, r) * inv;
        (t > 1e-6 && t < t_max).then_some((t, b1, b2))
    }

    /// The nearest (triangle, t, b1, b2) along o + t·d; with `any`, the first hit found.
    #[inline(always)]
    fn traverse(&self, o: Vec3, d: Vec3, any: bool) -> Option<(usize, f32, f32, f32)> {
        let inv = d.map(|x| 1.0 / x);
        let mut best: Option<(usize, f32, f32, f32)> = None;
        let mut t_max = f32::INFINITY;
        // (node, its entry distance): a node behind the nearest hit so far is skipped.
        let mut stack = [(0u32, 0.0f32); 64];
        let mut top = 0;
        let mut at = match enter(&self.nodes[0], o, inv, t_max) {
            Some(_) => 0u32,
            None => return None,
        };
        loop {
            let node = &self.nodes[at as usize];
            if node.count > 0 {
                for k in node.start..node.start + node.count {
                    let i = self.order[k as usize] as usize;
                    if let Some((t, b1, b2)) = self.hit_triangle(i, o, d, t_max) {
                        t_max = t;
                        best = Some((i, t, b1, b2));
                        if any {
                            return best;
                        }
                    }
                }
            } else {
                let (l, r) = (node.start, node.start + 1);
                match (enter(&self.nodes[l as usize], o, inv, t_max), enter(&self.nodes[r as usize], o, inv, t_max)) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, t_far) = if tl <= tr { (l, r, tr) } else { (r, l, tl) };
                        if top < stack.len() {
                            stack[top] = (far, t_far);
                            top += 1;
                        }
                        at = near;
                        continue;
                    }
                    (Some(_), None) => {
                        at = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        at = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // The next subtree on the stack that starts before the nearest hit.
            loop {
                if top == 0 {
                    return best;
                }
                top -= 1;
                if stack[top].1 <= t_max {
                    at = stack[top].0;
                    break;
                }
            }
        }
    }

    /// The nearest (triangle, t, b1, b2) along o + t·d.
    fn nearest(&self, o: Vec3, d: Vec3) -> Option<(usize, f32, f32, f32)> {
        self.traverse(o, d, false)
    }

    /// The nearest hit by testing every triangle (the BVH's reference in tests).
    pub fn intersect_brute_force(&self, o: Vec3, d: Vec3) -> Option<(usize, f32)> {
        let mut best = None;
        let mut t_max = f32::INFINITY;
        for i in 0..self.triangles.len() {
            if let Some((t, _, _)) = self.hit_triangle(i, o, d, t_max) {
                t_max = t;
                best = Some((i, t));
            }
        }
        best
    }

    /// The nearest hit's triangle and distance through the BVH.
    pub fn intersect_triangle(&self, o: Vec3, d: Vec3) -> Option<(usize, f32)> {
        self.nearest(o, d).map(|(i, t, _, _)| (i, t))
    }
}

impl Scene for Mesh {
    fn intersect(&self, o: Vec3, d: Vec3) -> Option<Hit> {
        let (i, t, b1, b2) = self.nearest(o, d)?;
        let tri = &self.triangles[i];
        let b0 = 1.0 - b1 - b2;
        let lerp3 = |v: &[Vec3; 3]| [0, 1, 2].map(|c| b0 * v[0][c] + b1 * v[1][c] + b2 * v[2][c]);
        let p = &tri.position;
        let face = normalize(cross(add_scaled(p[1], p[0], -1.0), add_scaled(p[2], p[0], -1.0)));
        let geometric_normal = if dot(face, d) > 0.0 { face.map(|x| -x) } else { face };
        let mut n = normalize(lerp3(&tri.normal));
        if dot(n, geometric_normal) < 0.0 {
            n = n.map(|x| -x);
        }
        let t_raw = lerp3(&tri.tangent);
        let t_orth = add_scaled(t_raw, n, -dot(t_raw, n));
        let tangent = if dot(t_orth, t_orth) > 1e-12 { normalize(t_orth) } else { any_orthonormal(n) };
        let bitangent = cross(n, tangent);
        let uv = [0, 1].map(|c| b0 * tri.uv[0][c] + b1 * tri.uv[1][c] + b2 * tri.uv[2][c]);
        Some(Hit { t, position: add_scaled(o, d, t), geometric_normal, frame: [tangent, bitangent, n], uv: [uv[0], 1.0 - uv[1]] })
    }

    fn occluded(&self, o: Vec3, d: Vec3) -> bool {
        self.traverse(o, d, true).is_some()
    }

    fn world_space_normals(&self) -> bool {
        true
    }
}

fn any_orthonormal(n: Vec3) -> Vec3 {
    let a = if n[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    normalize(add_scaled(a, n, -dot(a, n)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(k: u64) -> f32 {
        uplift_base::rng::unit_from_key(uplift_base::rng::mix64(k))
    }

    /// A soup of random small triangles in a box.
    fn soup(n: usize) -> Vec<WorldTriangle> {
        (0..n)
            .map(|i| {
                let c = [0, 1, 2].map(|a| 4.0 * unit((i * 16 + a) as u64) - 2.0);
                let position = [0, 1, 2].map(|v| [0, 1, 2].map(|a| c[a] + 0.6 * (unit((i * 16 + 3 + v * 3 + a) as u64) - 0.5)));
                WorldTriangle { position, normal: [[0.0, 0.0, 1.0]; 3], tangent: [[1.0, 0.0, 0.0]; 3], uv: [[0.0; 2]; 3] }
            })
            .collect()
    }

    #[test]
    fn bvh_finds_the_same_nearest_hit_as_testing_every_triangle() {
        let mesh = Mesh::new(soup(2000)).unwrap();
        let mut hits = 0;
        for r in 0..4000u64 {
            let o = [0, 1, 2].map(|a| 3.0 * (unit(r * 8 + a) - 0.5));
            // Half the rays aim at a triangle's centroid (the nearest hit may be another one).
            let d = if r % 2 == 0 {
                normalize(add_scaled(centroid(&mesh.triangles[(r as usize * 7) % mesh.triangles.len()]), o, -1.0))
            } else {
                normalize([0, 1, 2].map(|a| unit(r * 8 + 3 + a) - 0.5))
            };
            let (a, b) = (mesh.intersect_triangle(o, d), mesh.intersect_brute_force(o, d));
            assert_eq!(a.map(|x| x.0), b.map(|x| x.0), "ray {r}");
            assert_eq!(mesh.occluded(o, d), b.is_some(), "ray {r}: the shadow ray");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.1 - b.1).abs() <= 1e-6 * b.1.max(1.0));
                hits += 1;
            }
        }
        assert!(hits > 2000, "only {hits} of 4000 rays hit: the test would prove little");
    }

    #[test]
    fn mesh_is_scaled_into_the_unit_sphere() {
        let mesh = Mesh::new(soup(50)).unwrap();
        let r = mesh.triangles.iter().flat_map(|t| t.position).map(|p| dot(p, p).sqrt()).fold(0.0f32, f32::max);
        assert!((r - 1.0).abs() < 1e-4, "{r}");
        assert!(Mesh::new(vec![]).is_err());
    }
}
