//! The mesh a viewer shows, named as plain data ([`Shown`]), its positions, and its OBJ text in the
//! population's original units (what the page's "OBJ of the shown mesh" button writes).

use super::obj::write_obj;
use crate::articulate::{Articulation, Options};
use crate::error::{Error, Result};
use crate::geometry::Vec3;
use crate::mesh::Population;
use crate::mfa::Model;
use serde::Deserialize;

/// Which mesh: a training pose, its reconstruction (eq 22), the latent shape (eq 21), the part-wise
/// interpolation (Algorithm 2, corrected) or plain linear vertex blending between poses `from` and `to`
/// (0-based) at `t`. As JSON: `{"kind": "pose", "pose": 2}`, `{"kind": "interpolation", "from": 0, "to": 3,
/// "t": 0.5, "options": {...}}`; unknown fields are refused.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Shown {
    Pose {
        pose: usize,
    },
    Reconstruction {
        pose: usize,
    },
    Latent,
    /// The latent shape with every part moved by its translation b of pose `pose` but not turned
    /// ([`Model::latent_placed`]).
    LatentMoved {
        pose: usize,
    },
    Interpolation {
        from: usize,
        to: usize,
        t: f64,
        #[serde(default)]
        options: Options,
    },
    Linear {
        from: usize,
        to: usize,
        t: f64,
    },
}

impl Shown {
    /// True when the mesh needs a fitted model (everything but a pose and linear blending).
    pub fn needs_model(&self) -> bool {
        !matches!(self, Shown::Pose { .. } | Shown::Linear { .. })
    }

    /// Its positions, unit box. `model` and `articulation` are needed when [`Shown::needs_model`].
    pub fn positions(
        &self,
        pop: &Population,
        model: Option<&Model>,
        articulation: Option<&Articulation>,
    ) -> Result<Vec<Vec3>> {
        let shape = |i: usize| {
            pop.get_shape(i)
                .map(|s| s.to_vec())
                .ok_or_else(|| Error::Request(format!("no pose {i}: the population has {} poses", pop.n_shapes())))
        };
        let need_model = || model.ok_or_else(|| Error::Request("this mesh needs a fitted model".into()));
        match *self {
            Shown::Pose { pose } => shape(pose),
            Shown::Linear { from, to, t } => {
                crate::articulate::interpolate::linear_blend(&shape(from)?, &shape(to)?, t)
            }
            Shown::Reconstruction { pose } => {
                shape(pose)?;
                Ok(need_model()?.reconstruct(pose))
            }
            Shown::Latent => Ok(need_model()?.latent.clone()),
            Shown::LatentMoved { pose } => {
                shape(pose)?;
                Ok(need_model()?.latent_placed(pose))
            }
            Shown::Interpolation { from, to, t, options } => {
                let art =
                    articulation.ok_or_else(|| Error::Request("the interpolation needs a fitted model".into()))?;
                art.interpolate(from, to, t, &options)
            }
        }
    }
}

/// OBJ text of unit-box positions written back in the population's original units (exact round-trip
/// floats, [`write_obj`]), with the population's triangles.
pub fn obj_in_original_units(pop: &Population, positions: &[Vec3], header: &str) -> String {
    let original: Vec<Vec3> = positions.iter().map(|&p| pop.normalization.to_original(p)).collect();
    write_obj(&original, &pop.faces, header)
}

/// One mesh of an OBJ file of several ([`obj_of_meshes`]): its object name, unit-box positions, and optionally a
/// part per vertex (its faces then go in one group per part).
pub struct NamedMesh<'a> {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub labels: Option<&'a [u32]>,
}

/// OBJ text of the meshes shown side by side, each an object (`o NAME`) with the population's triangles,
/// positions written back in the original units (exact round-trip floats). With labels, a mesh's faces are in
/// one group per part (`g NAME_part_1`, ...; a face goes to the part of at least two of its corners, else of its
/// first): the parts as separate pieces in a modelling program.
pub fn obj_of_meshes(pop: &Population, meshes: &[NamedMesh], header: &str) -> Result<String> {
    let mut out = write_obj(&[], &[], header);
    let mut offset = 0u64;
    for m in meshes {
        if m.positions.len() != pop.n_vertices() || m.labels.is_some_and(|l| l.len() != m.positions.len()) {
            return Err(Error::Request(format!(
                "mesh {}: {} positions for {} vertices",
                m.name,
                m.positions.len(),
                pop.n_vertices()
            )));
        }
        let name: String = m.name.chars().map(|c| if c.is_whitespace() { '_' } else { c }).collect();
        out.push_str(&format!("o {name}\n"));
        let original: Vec<Vec3> = m.positions.iter().map(|&p| pop.normalization.to_original(p)).collect();
        out.push_str(&write_obj(&original, &[], ""));
        let part = |f: &[u32; 3]| {
            m.labels.map(|l| {
                let [a, b, c] = f.map(|v| l[v as usize]);
                if b == c {
                    b
                } else {
                    a
                }
            })
        };
        let mut order: Vec<usize> = (0..pop.faces.len()).collect();
        order.sort_by_key(|&i| part(&pop.faces[i]));
        let mut current = None;
        for i in order {
            let f = pop.faces[i];
            if let Some(k) = part(&f) {
                if current != Some(k) {
                    out.push_str(&format!("g {name}_part_{}\n", k + 1));
                    current = Some(k);
                }
            }
            out.push_str(&format!(
                "f {} {} {}\n",
                offset + u64::from(f[0]) + 1,
                offset + u64::from(f[1]) + 1,
                offset + u64::from(f[2]) + 1
            ));
        }
        offset += m.positions.len() as u64;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::population::Normalization;

    fn population() -> Population {
        let shapes = vec![
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.5]],
        ];
        let mut pop = Population::new(crate::mesh::Sources::UnitShapes {
            names: vec!["a.obj".into(), "b.obj".into()],
            faces: vec![[0, 1, 2]],
            shapes,
        })
        .unwrap();
        pop.normalization = Normalization { offset: [100.0, -7.0, 0.25], scale: 0.1 };
        pop
    }

    #[test]
    fn a_pose_is_written_in_original_units_and_reads_back_exactly() {
        let pop = population();
        let p = Shown::Pose { pose: 1 }.positions(&pop, None, None).unwrap();
        let text = obj_in_original_units(&pop, &p, "pose b");
        let v: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| l.starts_with("v "))
            .map(|l| l[2..].split(' ').map(|x| x.parse().unwrap()).collect())
            .collect();
        for (k, q) in pop.shape(1).iter().enumerate() {
            let o = pop.normalization.to_original(q);
            assert_eq!(v[k], o.to_vec(), "exact floats");
        }
        assert_eq!(v[2], vec![100.0, 3.0, 5.25]);
        assert!(text.starts_with("# pose b\n") && text.ends_with("f 1 2 3\n"));
    }

    #[test]
    fn meshes_are_objects_and_parts_are_groups_with_every_face_once() {
        let mut pop = population();
        pop.faces = std::sync::Arc::new(vec![[0, 1, 2], [2, 1, 0], [1, 2, 0]]);
        let p0 = Shown::Pose { pose: 0 }.positions(&pop, None, None).unwrap();
        let p1 = Shown::Pose { pose: 1 }.positions(&pop, None, None).unwrap();
        let labels = [1u32, 1, 0];
        let meshes = [
            NamedMesh { name: "original".into(), positions: p0.clone(), labels: None },
            NamedMesh { name: "coarse parts".into(), positions: p1.clone(), labels: Some(&labels) },
        ];
        let text = obj_of_meshes(&pop, &meshes, "two meshes").unwrap();
        let v = |t: &str| t.lines().filter(|l| l.starts_with("v ")).map(str::to_owned).collect::<Vec<_>>();
        let plain = [obj_in_original_units(&pop, &p0, ""), obj_in_original_units(&pop, &p1, "")];
        assert_eq!(v(&text), [v(&plain[0]), v(&plain[1])].concat(), "both meshes' vertices, exact");
        let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with("v ")).collect();
        // every face has two corners in part 1 (group part_2); faces keep their order within a part
        assert_eq!(
            lines,
            [
                "# two meshes",
                "o original",
                "f 1 2 3",
                "f 3 2 1",
                "f 2 3 1",
                "o coarse_parts",
                "g coarse_parts_part_2",
                "f 4 5 6",
                "f 6 5 4",
                "f 5 6 4"
            ]
        );
        // three corners in three parts: the first corner's part
        let labels = [0u32, 1, 2];
        let one = [NamedMesh { name: "final".into(), positions: p0.clone(), labels: Some(&labels) }];
        let lines: Vec<String> = obj_of_meshes(&pop, &one, "")
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("v "))
            .map(str::to_owned)
            .collect();
        assert_eq!(
            lines,
            ["o final", "g final_part_1", "f 1 2 3", "g final_part_2", "f 2 3 1", "g final_part_3", "f 3 2 1"]
        );
        let short = [NamedMesh { name: "x".into(), positions: p0[..2].to_vec(), labels: None }];
        assert!(obj_of_meshes(&pop, &short, "").is_err());
    }

    #[test]
    fn linear_blend_and_errors() {
        let pop = population();
        let p = Shown::Linear { from: 0, to: 1, t: 0.5 }.positions(&pop, None, None).unwrap();
        assert_eq!(p[2], [0.0, 1.0, 0.25]);
        assert!(Shown::Pose { pose: 2 }.positions(&pop, None, None).unwrap_err().to_string().contains("no pose 2"));
        assert!(Shown::Latent.positions(&pop, None, None).unwrap_err().to_string().contains("fitted model"));
        assert!(Shown::LatentMoved { pose: 0 }
            .positions(&pop, None, None)
            .unwrap_err()
            .to_string()
            .contains("fitted model"));
        let s: Shown = serde_json::from_str(r#"{"kind":"latent-moved","pose":1}"#).unwrap();
        assert_eq!(s, Shown::LatentMoved { pose: 1 });
        assert!(Shown::Latent.needs_model() && !Shown::Pose { pose: 0 }.needs_model());
    }

    #[test]
    fn descriptors_parse_and_unknown_fields_are_refused() {
        let s: Shown = serde_json::from_str(r#"{"kind":"interpolation","from":0,"to":1,"t":0.25}"#).unwrap();
        assert_eq!(s, Shown::Interpolation { from: 0, to: 1, t: 0.25, options: Options::default() });
        let e = serde_json::from_str::<Shown>(r#"{"kind":"pose","pose":1,"poze":2}"#).unwrap_err().to_string();
        assert!(e.contains("poze"), "{e}");
        let e = serde_json::from_str::<Shown>(r#"{"kind":"linear","from":0,"to":1,"t":0.5,"options":{}}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("options"), "{e}");
    }
}
