//! A UV sphere of radius 1 written as a glTF 2.0 file (`.gltf` + `.bin`): smooth normals, one
//! UV chart with a seam where u wraps (u = φ/2π, v = θ/π from the top, glTF's convention), the
//! same parameterisation as the renderer's analytic preview ball. The mesh the demo exports its
//! orbit on, and the tests' and benchmarks' mesh with a seam.

use std::path::{Path, PathBuf};
use uplift_base::atomic_write::write_atomically;

/// Writes `sphere.gltf` and `sphere.bin` (`nu` × `nv` quads) into `dir`; returns the .gltf path.
pub fn write_uv_sphere_gltf(dir: &Path, nu: usize, nv: usize) -> Result<PathBuf, String> {
    use std::f32::consts::{PI, TAU};
    if nu < 3 || nv < 2 {
        return Err(format!("a UV sphere needs at least 3 × 2 quads (got {nu} × {nv})"));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let (mut pos, mut nrm, mut uv, mut idx) = (vec![], vec![], vec![], vec![]);
    for j in 0..=nv {
        for i in 0..=nu {
            let (theta, phi) = (PI * j as f32 / nv as f32, TAU * i as f32 / nu as f32);
            // The analytic sphere's φ = atan2(x, z) + π.
            let (st, ct) = if j == 0 || j == nv { (0.0, if j == 0 { 1.0 } else { -1.0 }) } else { (theta.sin(), theta.cos()) };
            let p = [st * (phi - PI).sin(), ct, st * (phi - PI).cos()];
            pos.extend_from_slice(&p);
            nrm.extend_from_slice(&p);
            uv.extend_from_slice(&[i as f32 / nu as f32, j as f32 / nv as f32]);
        }
    }
    let at = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    for j in 0..nv {
        for i in 0..nu {
            // Counter-clockwise seen from outside.
            idx.extend_from_slice(&[at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    let floats = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut bin: Vec<u8> = vec![];
    let mut views = vec![];
    for chunk in [floats(&pos), floats(&nrm), floats(&uv), idx.iter().flat_map(|x| x.to_le_bytes()).collect()] {
        views.push((bin.len(), chunk.len()));
        bin.extend_from_slice(&chunk);
    }
    write_atomically(&dir.join("sphere.bin"), &bin).map_err(|e| format!("{}: {e}", dir.join("sphere.bin").display()))?;
    let n = (nu + 1) * (nv + 1);
    let view_json: Vec<String> = views.iter().map(|(o, l)| format!("{{\"buffer\":0,\"byteOffset\":{o},\"byteLength\":{l}}}")).collect();
    let json = format!(
        "{{\"asset\":{{\"version\":\"2.0\"}},\"scene\":0,\"scenes\":[{{\"nodes\":[0]}}],\"nodes\":[{{\"mesh\":0}}],\
         \"meshes\":[{{\"primitives\":[{{\"attributes\":{{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2}},\"indices\":3,\"material\":0}}]}}],\
         \"materials\":[{{\"name\":\"ball\"}}],\
         \"accessors\":[{{\"bufferView\":0,\"componentType\":5126,\"count\":{n},\"type\":\"VEC3\",\"min\":[-1,-1,-1],\"max\":[1,1,1]}},\
         {{\"bufferView\":1,\"componentType\":5126,\"count\":{n},\"type\":\"VEC3\"}},{{\"bufferView\":2,\"componentType\":5126,\"count\":{n},\"type\":\"VEC2\"}},\
         {{\"bufferView\":3,\"componentType\":5125,\"count\":{},\"type\":\"SCALAR\"}}],\
         \"bufferViews\":[{}],\"buffers\":[{{\"uri\":\"sphere.bin\",\"byteLength\":{}}}]}}",
        idx.len(),
        view_json.join(","),
        bin.len()
    );
    let path = dir.join("sphere.gltf");
    write_atomically(&path, json.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}
