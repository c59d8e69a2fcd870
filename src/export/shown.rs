//! The mesh a viewer shows, named as plain data ([`Shown`]), its positions, and its OBJ text in the
//! population's original units (what the page's "OBJ of the shown mesh" button writes).

use super::obj::write_obj;
use crate::articulate::{Articulation, Options};
use crate::error::{Error, Result};
use crate::geometry::Vec3;
use crate::mesh::Population;
use crate::model::Model;
use serde::Deserialize;

/// Which mesh: a training pose, its reconstruction (eq 22), the latent shape (eq 21), the part-wise
/// interpolation (Algorithm 2, corrected) or plain linear vertex blending between poses `from` and `to`
/// (0-based) at `t`. As JSON: `{"kind": "pose", "pose": 2}`, `{"kind": "interpolation", "from": 0, "to": 3,
/// "t": 0.5, "options": {...}}`; unknown fields are refused.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Shown {
    Pose { pose: usize },
    Reconstruction { pose: usize },
    Latent,
    Interpolation { from: usize, to: usize, t: f64, #[serde(default)] options: Options },
    Linear { from: usize, to: usize, t: f64 },
}

impl Shown {
    /// True when the mesh needs a fitted model (everything but a pose and linear blending).
    pub fn needs_model(&self) -> bool {
        !matches!(self, Shown::Pose { .. } | Shown::Linear { .. })
    }

    /// Its positions, unit box. `model` and `articulation` are needed when [`Shown::needs_model`].
    pub fn positions(&self, pop: &Population, model: Option<&Model>, articulation: Option<&Articulation>) -> Result<Vec<Vec3>> {
        let shape = |i: usize| {
            pop.shapes.get(i).ok_or_else(|| Error::Request(format!("no pose {i}: the population has {} poses", pop.shapes.len())))
        };
        let need_model = || model.ok_or_else(|| Error::Request("this mesh needs a fitted model".into()));
        match *self {
            Shown::Pose { pose } => Ok(shape(pose)?.clone()),
            Shown::Linear { from, to, t } => crate::articulate::interpolate::linear_blend(shape(from)?, shape(to)?, t),
            Shown::Reconstruction { pose } => {
                shape(pose)?;
                Ok(need_model()?.reconstruct(pose))
            }
            Shown::Latent => Ok(need_model()?.latent.clone()),
            Shown::Interpolation { from, to, t, options } => {
                let art = articulation.ok_or_else(|| Error::Request("the interpolation needs a fitted model".into()))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::population::Normalization;

    fn population() -> Population {
        let shapes = vec![vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.5]]];
        let mut pop = Population::from_unit_shapes(vec!["a.obj".into(), "b.obj".into()], vec![[0, 1, 2]], shapes).unwrap();
        pop.normalization = Normalization { offset: [100.0, -7.0, 0.25], scale: 0.1 };
        pop
    }

    #[test]
    fn a_pose_is_written_in_original_units_and_reads_back_exactly() {
        let pop = population();
        let p = Shown::Pose { pose: 1 }.positions(&pop, None, None).unwrap();
        let text = obj_in_original_units(&pop, &p, "pose b");
        let v: Vec<Vec<f64>> = text.lines().filter(|l| l.starts_with("v ")).map(|l| l[2..].split(' ').map(|x| x.parse().unwrap()).collect()).collect();
        for (k, q) in pop.shapes[1].iter().enumerate() {
            let o = pop.normalization.to_original(*q);
            assert_eq!(v[k], o.to_vec(), "exact floats");
        }
        assert_eq!(v[2], vec![100.0, 3.0, 5.25]);
        assert!(text.starts_with("# pose b\n") && text.ends_with("f 1 2 3\n"));
    }

    #[test]
    fn linear_blend_and_errors() {
        let pop = population();
        let p = Shown::Linear { from: 0, to: 1, t: 0.5 }.positions(&pop, None, None).unwrap();
        assert_eq!(p[2], [0.0, 1.0, 0.25]);
        assert!(Shown::Pose { pose: 2 }.positions(&pop, None, None).unwrap_err().to_string().contains("no pose 2"));
        assert!(Shown::Latent.positions(&pop, None, None).unwrap_err().to_string().contains("fitted model"));
        assert!(Shown::Latent.needs_model() && !Shown::Pose { pose: 0 }.needs_model());
    }

    #[test]
    fn descriptors_parse_and_unknown_fields_are_refused() {
        let s: Shown = serde_json::from_str(r#"{"kind":"interpolation","from":0,"to":1,"t":0.25}"#).unwrap();
        assert_eq!(s, Shown::Interpolation { from: 0, to: 1, t: 0.25, options: Options::default() });
        let e = serde_json::from_str::<Shown>(r#"{"kind":"pose","pose":1,"poze":2}"#).unwrap_err().to_string();
        assert!(e.contains("poze"), "{e}");
        let e = serde_json::from_str::<Shown>(r#"{"kind":"linear","from":0,"to":1,"t":0.5,"options":{}}"#).unwrap_err().to_string();
        assert!(e.contains("options"), "{e}");
    }
}
