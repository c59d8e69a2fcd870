//! Figures that check an articulation on a population: endpoint errors, volume and edge stretch at t.
//!
//! Definitions (all unit-box units):
//! - **Endpoint error**: the largest vertex distance between the output at t = 0 (t = 1) and its target:
//!   the training shape i (j) with the residual on, its rigid reconstruction (eq 22) with it off.
//! - **Volume**: signed volume of the closed mesh (divergence theorem). Ratio = V(t) / ((1-t) V^i + t V^j)
//!   of the training shapes, reported as ratio - 1.
//! - **Edge stretch** of mesh edge e at t: |L_e(t) / L_e^ref - 1| with L_e^ref = (1-t) L_e^i + t L_e^j, the
//!   linear mix of its lengths in the two training shapes. Percentiles over all edges and over the edges
//!   crossing a part boundary (endpoints with different labels). A perfect interpolation keeps every edge
//!   at its mixed length (0 %); the rigid parts open or overlap at joints.

use super::{Articulation, Blend, Options, RootRule, Skin};
use crate::error::Result;
use crate::geometry::{cross, dot, norm, sub, Vec3};
use serde::Serialize;

/// Signed volume enclosed by a closed, consistently oriented triangle mesh.
pub fn signed_volume(positions: &[Vec3], faces: &[[u32; 3]]) -> f64 {
    faces
        .iter()
        .map(|f| {
            let (a, b, c) = (positions[f[0] as usize], positions[f[1] as usize], positions[f[2] as usize]);
            dot(a, cross(b, c))
        })
        .sum::<f64>()
        / 6.0
}

/// Largest distance between corresponding points.
pub fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| norm(sub(*p, *q))).fold(0.0, f64::max)
}

/// The q-quantile (0..=1) of the values by nearest rank; 0 for none.
pub fn percentile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    // the rank-th smallest, without sorting the rest
    *v.select_nth_unstable_by(rank - 1, f64::total_cmp).1
}

/// Edge stretch figures of one output shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Stretch {
    /// p99 over edges crossing a part boundary.
    pub boundary_p99: f64,
    /// p99 over all edges.
    pub all_p99: f64,
    /// Largest over edges crossing a part boundary.
    pub boundary_max: f64,
    /// Largest over all edges.
    pub all_max: f64,
}

/// Edge stretch (module doc) of `positions` at t between training shapes i and j.
pub fn edge_stretch(art: &Articulation, positions: &[Vec3], i: usize, j: usize, t: f64) -> Stretch {
    let edges = &art.edges; // (the mesh's edges, made once with the articulation)
    let (mut all, mut boundary) = (Vec::with_capacity(edges.len()), Vec::new());
    let (yi, yj) = (art.shape(i), art.shape(j));
    for e in edges {
        let (a, b) = (e[0] as usize, e[1] as usize);
        let li = norm(sub(yi[a], yi[b]));
        let lj = norm(sub(yj[a], yj[b]));
        let reference = (1.0 - t) * li + t * lj;
        if !(reference > 0.0) {
            continue;
        }
        let s = (norm(sub(positions[a], positions[b])) / reference - 1.0).abs();
        all.push(s);
        if art.model.labels[a] != art.model.labels[b] {
            boundary.push(s);
        }
    }
    Stretch {
        boundary_p99: percentile(&boundary, 0.99),
        all_p99: percentile(&all, 0.99),
        boundary_max: boundary.iter().cloned().fold(0.0, f64::max),
        all_max: all.iter().cloned().fold(0.0, f64::max),
    }
}

/// One interpolation method's figures.
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct MethodFigures {
    pub name: String,
    pub options: Option<Options>,
    /// Endpoint errors at t = 0 and t = 1 (targets in the module doc).
    pub endpoint_error: [f64; 2],
    /// V(t)/V_ref - 1 at the report's t.
    pub volume_change: f64,
    pub stretch: Stretch,
}

/// Everything [`report`] measures.
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Report {
    pub shapes: usize,
    pub vertices: usize,
    pub parts: usize,
    pub rmse: f64,
    /// 1-based poses.
    pub from: usize,
    pub to: usize,
    pub t: f64,
    /// Anchor root: part index, its share of the surface area.
    pub anchor_root: usize,
    pub anchor_area_share: f64,
    /// The paper's root for this pair of poses, its share of the surface area and its rotation (degrees).
    pub paper_root: usize,
    pub paper_root_area_share: f64,
    pub paper_root_rotation_deg: f64,
    /// Depth of the default tree.
    pub tree_depth: usize,
    /// Training shapes' volumes, and the reference (1-t) V^i + t V^j.
    pub volume_from: f64,
    pub volume_to: f64,
    pub volume_reference: f64,
    pub methods: Vec<MethodFigures>,
}

fn figures(
    art: &Articulation,
    name: &str,
    opts: Option<Options>,
    i: usize,
    j: usize,
    t: f64,
    v_ref: f64,
) -> Result<MethodFigures> {
    let at = |t: f64| -> Result<Vec<Vec3>> {
        match &opts {
            Some(o) => art.interpolate(i, j, t, o),
            None => art.linear(i, j, t),
        }
    };
    let residual = opts.map_or(true, |o| o.residual);
    let (target_i, target_j) = if residual { (art.shape(i), art.shape(j)) } else { (art.rigid(i), art.rigid(j)) };
    let endpoint_error = [max_distance(&at(0.0)?, &target_i), max_distance(&at(1.0)?, &target_j)];
    let mid = at(t)?;
    Ok(MethodFigures {
        name: name.to_string(),
        options: opts,
        endpoint_error,
        volume_change: signed_volume(&mid, &art.faces) / v_ref - 1.0,
        stretch: edge_stretch(art, &mid, i, j, t),
    })
}

/// Interpolates poses i -> j (0-based) with every method and measures them at t.
pub fn report(art: &Articulation, i: usize, j: usize, t: f64) -> Result<Report> {
    art.check_shape(i)?;
    art.check_shape(j)?;
    let vi = signed_volume(&art.shape(i), &art.faces);
    let vj = signed_volume(&art.shape(j), &art.faces);
    let v_ref = (1.0 - t) * vi + t * vj;
    let d = Options::default();
    let smooth = Options { skin: Skin::Smooth, ..d };
    let methods = vec![
        figures(art, "rigid (default: anchor root, exact ends, residual)", Some(d), i, j, t, v_ref)?,
        figures(art, "rigid, residual off", Some(Options { residual: false, ..d }), i, j, t, v_ref)?,
        figures(art, "smooth dual-quaternion skin", Some(smooth), i, j, t, v_ref)?,
        figures(
            art,
            "smooth dual-quaternion skin, residual off",
            Some(Options { residual: false, ..smooth }),
            i,
            j,
            t,
            v_ref,
        )?,
        figures(
            art,
            "smooth dual-quaternion skin, ends averaged by position (no edge blend)",
            Some(Options { edge_blend: false, ..smooth }),
            i,
            j,
            t,
            v_ref,
        )?,
        figures(art, "smooth linear-blend skin", Some(Options { blend: Blend::Linear, ..smooth }), i, j, t, v_ref)?,
        figures(art, "rigid, paper root, exact ends", Some(Options { root: RootRule::Paper, ..d }), i, j, t, v_ref)?,
        figures(
            art,
            "Algorithm 2 as printed (paper root, BFS, no offset blending), residual off",
            Some(Options { residual: false, ..Options::paper() }),
            i,
            j,
            t,
            v_ref,
        )?,
        figures(art, "linear vertex interpolation", None, i, j, t, v_ref)?,
    ];
    let total_area: f64 = art.part_area.iter().sum();
    let paper_root = art.root(RootRule::Paper, i, j);
    let tree = art.tree(&d, i, j);
    Ok(Report {
        shapes: art.n_shapes(),
        vertices: art.n_vertices(),
        parts: art.n_parts(),
        rmse: art.model.rmse(&art.population),
        from: i + 1,
        to: j + 1,
        t,
        anchor_root: art.anchor,
        anchor_area_share: art.part_area[art.anchor] / total_area,
        paper_root,
        paper_root_area_share: art.part_area[paper_root] / total_area,
        paper_root_rotation_deg: art.rotation_angle(paper_root, i, j).to_degrees(),
        tree_depth: tree.depths().iter().flatten().copied().max().unwrap_or(0),
        volume_from: vi,
        volume_to: vj,
        volume_reference: v_ref,
        methods,
    })
}
