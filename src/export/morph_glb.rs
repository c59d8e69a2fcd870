//! A population as one binary glTF 2.0 file with morph targets: the first pose is the mesh, every further
//! pose k is morph target k (its positions minus the first pose's, float32), and an animation "Poses" with
//! one keyframe per pose at 24 fps (STEP: at frame 0 every weight is 0, at frame k weight k is 1 and the
//! others 0). posemfa's glTF reader ([`crate::mesh::gltf`]) gives back the poses from the animation (by
//! default) or from the morph targets; other tools play the animation or show the targets (named after
//! the poses in the mesh's `extras.targetNames`, the convention of Blender and three.js).
//!
//! Written with `serde_json` into the GLB container (JSON chunk, BIN chunk); the layout of every buffer
//! view is fixed by the counts, so the file is checked by reading it back in the tests.

use crate::error::{Error, Result};
use serde_json::json;

/// Frames per second of the "Poses" animation.
pub const FPS: f64 = 24.0;

fn f32s(bin: &mut Vec<u8>, values: impl IntoIterator<Item = f32>) {
    for v in values {
        bin.extend_from_slice(&v.to_le_bytes());
    }
}

/// min and max of each coordinate of float32 positions (glTF requires them on POSITION accessors).
fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

/// Writes `poses` (each one position per vertex, all the same length) with triangles `faces` as a .glb.
/// `names` name the poses (target names); `mesh_name` names the mesh. Errors: no poses, poses of different
/// lengths, a face out of range, a coordinate that is not finite in float32.
pub fn write_morph_glb(
    mesh_name: &str,
    names: &[String],
    poses: &[Vec<[f64; 3]>],
    faces: &[[u32; 3]],
) -> Result<Vec<u8>> {
    let base = poses.first().ok_or_else(|| Error::Data("no poses to write".into()))?;
    let n = base.len();
    if n == 0 || faces.is_empty() {
        return Err(Error::Data("a mesh with vertices and triangles is needed to write a .glb".into()));
    }
    if let Some((k, p)) = poses.iter().enumerate().find(|(_, p)| p.len() != n) {
        return Err(Error::Data(format!("pose {} has {} vertices, pose 1 has {n}", k + 1, p.len())));
    }
    if let Some(f) = faces.iter().find(|f| f.iter().any(|&v| v as usize >= n)) {
        return Err(Error::Data(format!("triangle {f:?} is out of range for {n} vertices")));
    }
    let to32 = |p: &[f64; 3]| p.map(|c| c as f32);
    let base32: Vec<[f32; 3]> = base.iter().map(to32).collect();
    let targets: Vec<Vec<[f32; 3]>> = poses[1..]
        .iter()
        .map(|pose| pose.iter().zip(base).map(|(p, b)| [0, 1, 2].map(|d| (p[d] - b[d]) as f32)).collect())
        .collect();
    if base32.iter().chain(targets.iter().flatten()).flatten().any(|c| !c.is_finite()) {
        return Err(Error::Data("a coordinate is not a finite float32 number".into()));
    }
    let n_targets = targets.len();

    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push_view = |bin: &mut Vec<u8>, start: usize, target: Option<u32>| {
        let mut v = json!({"buffer": 0, "byteOffset": start, "byteLength": bin.len() - start});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        views.push(v);
        views.len() - 1
    };
    // 0: base positions
    let start = bin.len();
    f32s(&mut bin, base32.iter().flatten().copied());
    let view = push_view(&mut bin, start, Some(34962));
    let (lo, hi) = bounds(&base32);
    accessors
        .push(json!({"bufferView": view, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi}));
    // 1: indices
    let start = bin.len();
    for v in faces.iter().flatten() {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let view = push_view(&mut bin, start, Some(34963));
    accessors.push(json!({"bufferView": view, "componentType": 5125, "count": 3 * faces.len(), "type": "SCALAR"}));
    // 2..: one accessor per target
    let mut target_refs = Vec::new();
    for t in &targets {
        let start = bin.len();
        f32s(&mut bin, t.iter().flatten().copied());
        let view = push_view(&mut bin, start, Some(34962));
        let (lo, hi) = bounds(t);
        target_refs.push(json!({"POSITION": accessors.len()}));
        accessors
            .push(json!({"bufferView": view, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi}));
    }
    let mut animations = Vec::new();
    if n_targets > 0 {
        // keyframe times, then weights: key f has weight 1 on target f (f >= 1), 0 elsewhere
        let keys = n_targets + 1;
        let start = bin.len();
        f32s(&mut bin, (0..keys).map(|f| (f as f64 / FPS) as f32));
        let view = push_view(&mut bin, start, None);
        let time_acc = accessors.len();
        accessors.push(json!({"bufferView": view, "componentType": 5126, "count": keys, "type": "SCALAR",
                              "min": [0.0], "max": [((keys - 1) as f64 / FPS) as f32]}));
        let start = bin.len();
        f32s(&mut bin, (0..keys).flat_map(|f| (0..n_targets).map(move |k| if k + 1 == f { 1.0 } else { 0.0 })));
        let view = push_view(&mut bin, start, None);
        let weight_acc = accessors.len();
        accessors.push(json!({"bufferView": view, "componentType": 5126, "count": keys * n_targets, "type": "SCALAR"}));
        animations.push(json!({
            "name": "Poses",
            "samplers": [{"input": time_acc, "output": weight_acc, "interpolation": "STEP"}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]
        }));
    }
    let mut primitive = json!({"attributes": {"POSITION": 0}, "indices": 1, "mode": 4});
    let mut mesh = json!({"name": mesh_name, "primitives": []});
    if n_targets > 0 {
        primitive["targets"] = json!(target_refs);
        mesh["weights"] = json!(vec![0.0; n_targets]);
        mesh["extras"] = json!({"targetNames": names.iter().skip(1).take(n_targets).collect::<Vec<_>>()});
    }
    mesh["primitives"] = json!([primitive]);
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "posemfa (morph targets, one per pose)"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": mesh_name, "mesh": 0}],
        "meshes": [mesh],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    if !animations.is_empty() {
        doc["animations"] = json!(animations);
    }
    let mut json_bytes = serde_json::to_vec(&doc).map_err(|e| Error::Data(format!("glTF JSON: {e}")))?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json_bytes.len() + 8 + bin.len();
    let total32 =
        u32::try_from(total).map_err(|_| Error::Data(format!("the .glb would take {total} bytes, more than 4 GiB")))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::gltf::{read, Options, PoseSource};

    fn tetra_poses() -> (Vec<Vec<[f64; 3]>>, Vec<[u32; 3]>) {
        let base = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let poses = (0..4)
            .map(|k| {
                base.iter()
                    .enumerate()
                    .map(|(j, p): (usize, &[f64; 3])| if j == 3 { [0.25 * k as f64, 0.0, 1.0] } else { *p })
                    .collect()
            })
            .collect();
        (poses, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    #[test]
    fn poses_read_back_from_the_animation_and_from_the_targets() {
        let (poses, faces) = tetra_poses();
        let names: Vec<String> = (1..=4).map(|k| format!("pose{k}")).collect();
        let glb = write_morph_glb("tetra", &names, &poses, &faces).unwrap();
        assert_eq!(glb.len() % 4, 0);
        for source in [PoseSource::Auto, PoseSource::MorphTargets] {
            let g = read("t.glb", &glb, &[], &Options { source, ..Options::default() }).unwrap();
            assert_eq!(g.poses.len(), 4, "{}", g.source);
            for (got, want) in g.poses.iter().zip(&poses) {
                assert_eq!(got.1.faces, faces);
                for (p, q) in got.1.positions.iter().zip(want) {
                    assert!((0..3).all(|d| (p[d] - q[d]).abs() < 1e-6), "{p:?} {q:?}");
                }
            }
            if source == PoseSource::Auto {
                assert!(
                    g.source.starts_with(
                        "4 frames of animation 'Poses' (sampled at its keyframes, 24 fps) of mesh 'tetra'"
                    ),
                    "{}",
                    g.source
                );
            } else {
                assert!(g.source.starts_with("3 morph targets of mesh 'tetra'"), "{}", g.source);
                assert!(g.poses[2].0.ends_with("pose3"), "{}", g.poses[2].0);
            }
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let (mut poses, faces) = tetra_poses();
        assert!(write_morph_glb("m", &[], &[], &faces).is_err());
        assert!(write_morph_glb("m", &[], &poses, &[[0, 1, 4]]).unwrap_err().to_string().contains("out of range"));
        poses[2].pop();
        assert!(write_morph_glb("m", &[], &poses, &faces).unwrap_err().to_string().contains("pose 3 has 3 vertices"));
        let huge = vec![vec![[1e300, 0.0, 0.0]; 3]; 2];
        assert!(write_morph_glb("m", &[], &huge, &[[0, 1, 2]]).is_err());
    }

    /// One pose: a mesh without targets or animation (which the reader refuses as a population: one pose).
    #[test]
    fn one_pose_is_a_plain_mesh() {
        let (poses, faces) = tetra_poses();
        let glb = write_morph_glb("m", &[], &poses[..1], &faces).unwrap();
        let e = read("t.glb", &glb, &[], &Options::default()).unwrap_err().to_string();
        assert!(e.contains("no morph targets and no animation"), "{e}");
    }
}
