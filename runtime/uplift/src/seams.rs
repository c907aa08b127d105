//! UV seams for `uplift project`'s inpainting: the texels on either side of a seam — the chart
//! borders where one surface point has two places in texture space (a sphere's u = 0 and
//! u = 1, a shaderball's cut between charts) — are made neighbours, so that inpainting carries
//! values across a seam as the surface does instead of stopping at the chart's border.
//!
//! Found from the bake alone, without the mesh's topology: a chart-border texel (covered, with
//! an uncovered 8-neighbour or at the image's edge) is a seam partner of another border texel
//! when their surface points lie within 1.5 texels' surface size of each other (the larger of
//! the two texels' distances to their covered 4-neighbours) while the texels are not grid
//! neighbours. A spatial hash of the border texels' points finds them; each texel keeps its
//! [`MAX_PARTNERS`] nearest.

use std::collections::HashMap;

/// Partners kept per border texel.
pub const MAX_PARTNERS: usize = 4;

/// Per texel of a `width` × `height` bake (`covered`, surface `position` per texel), its seam
/// partners (texel indices, nearest first; empty for texels off the charts' borders).
pub fn seam_partners(covered: &[bool], position: &[[f32; 3]], width: usize, height: usize) -> Vec<Vec<u32>> {
    let n = width * height;
    let mut partners = vec![Vec::new(); n];
    let at = |x: i64, y: i64| (x >= 0 && y >= 0 && x < width as i64 && y < height as i64).then(|| y as usize * width + x as usize);
    let dist = |a: [f32; 3], b: [f32; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    // Border texels and their surface size.
    let mut border: Vec<(usize, f32)> = Vec::new();
    for t in 0..n {
        if !covered[t] {
            continue;
        }
        let (x, y) = ((t % width) as i64, (t / width) as i64);
        let on_border = [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)].iter().any(|(dx, dy)| at(x + dx, y + dy).is_none_or(|u| !covered[u]));
        if !on_border {
            continue;
        }
        let size = [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().filter_map(|(dx, dy)| at(x + dx, y + dy).filter(|&u| covered[u])).map(|u| dist(position[t], position[u])).fold(0.0f32, f32::max);
        if size > 0.0 && size.is_finite() {
            border.push((t, size));
        }
    }
    if border.is_empty() {
        return partners;
    }
    // A hash grid of cells of the largest search radius.
    let cell = border.iter().map(|b| 1.5 * b.1).fold(0.0f32, f32::max);
    let key = |p: [f32; 3]| p.map(|c| (c / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (k, &(t, _)) in border.iter().enumerate() {
        grid.entry(key(position[t])).or_default().push(k);
    }
    for &(t, size) in &border {
        let (x, y) = ((t % width) as i64, (t / width) as i64);
        let c = key(position[t]);
        let mut found: Vec<(f32, u32)> = Vec::new();
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else { continue };
                    for &k in list {
                        let (u, usize_) = border[k];
                        let (ux, uy) = ((u % width) as i64, (u / width) as i64);
                        if (ux - x).abs() <= 1 && (uy - y).abs() <= 1 {
                            continue;
                        }
                        let d = dist(position[t], position[u]);
                        if d <= 1.5 * size.max(usize_) {
                            found.push((d, u as u32));
                        }
                    }
                }
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        partners[t] = found.into_iter().take(MAX_PARTNERS).map(|f| f.1).collect();
    }
    partners
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cylinder unrolled into a 16 × 8 texture: u wraps, so column 0 and column 15 are each
    /// other's seam partners (one texel apart on the surface) and no other texels are.
    #[test]
    fn a_wrapped_cylinders_seam_columns_are_partners() {
        let (w, h) = (16usize, 8usize);
        let position: Vec<[f32; 3]> = (0..w * h)
            .map(|t| {
                let (x, y) = (t % w, t / w);
                let a = std::f32::consts::TAU * (x as f32 + 0.5) / w as f32;
                [a.cos(), y as f32 * 0.4, a.sin()]
            })
            .collect();
        let covered = vec![true; w * h];
        let p = seam_partners(&covered, &position, w, h);
        for y in 0..h {
            let (left, right) = (y * w, y * w + w - 1);
            assert_eq!(p[left].first().copied(), Some(right as u32), "row {y}: {:?}", p[left]);
            assert_eq!(p[right].first().copied(), Some(left as u32), "row {y}: {:?}", p[right]);
            assert!(p[left].iter().chain(&p[right]).all(|&u| (u as usize % w == 0) != (u as usize % w == w - 1) && (u as usize % w == 0 || u as usize % w == w - 1)), "row {y}: {:?} {:?}", p[left], p[right]);
        }
        // Interior texels and the top and bottom rows' interiors have no partners across u.
        for t in 0..w * h {
            if t % w != 0 && t % w != w - 1 {
                assert!(p[t].is_empty(), "texel {t}: {:?}", p[t]);
            }
        }
    }
}
