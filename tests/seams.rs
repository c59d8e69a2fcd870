//! A mesh split along a seam (every vertex on it twice, the two copies at the same point in every pose, each
//! side's faces on its own copy: what exporters that split vertices at UV seams or per face corner write, and
//! meshes made of pieces that meet) gives the parts it gives whole (`Population::graph_faces`). Before, the
//! parts ended at the seam: the lion cut down its middle fitted at adjusted Rand 0.47 against its whole fit.

#[macro_use]
mod common;

use posemfa::mesh::Population;
use posemfa::metrics::adjusted_rand_index;
use posemfa::mfa::Params;
use posemfa::parts::hierarchy::fit;
use posemfa::synth::{generate, Preset, Spec};

/// `pop` cut along the plane through its first pose's median `axis` coordinate: each face goes to the side of
/// its centroid, and every vertex used by both sides gets a copy for the far side's faces. Returns the cut
/// population and, for each copy, the vertex it copies.
fn cut(pop: &Population, axis: usize) -> (Population, Vec<usize>) {
    let first = pop.shape(0).to_vec();
    let mut along: Vec<f64> = first.iter().map(|p| p[axis]).collect();
    along.sort_by(f64::total_cmp);
    let plane = along[along.len() / 2];
    let far: Vec<bool> =
        pop.faces.iter().map(|f| f.iter().map(|&v| first[v as usize][axis]).sum::<f64>() / 3.0 > plane).collect();
    let mut sides = vec![[false; 2]; pop.n_vertices()];
    for (f, &s) in pop.faces.iter().zip(&far) {
        f.iter().for_each(|&v| sides[v as usize][s as usize] = true);
    }
    let copied: Vec<usize> = (0..pop.n_vertices()).filter(|&j| sides[j] == [true, true]).collect();
    let mut copy = vec![u32::MAX; pop.n_vertices()];
    for (k, &j) in copied.iter().enumerate() {
        copy[j] = (pop.n_vertices() + k) as u32;
    }
    let faces = pop
        .faces
        .iter()
        .zip(&far)
        .map(|(f, &s)| f.map(|v| if s && copy[v as usize] != u32::MAX { copy[v as usize] } else { v }))
        .collect();
    let shapes = pop
        .shapes()
        .map(|s| {
            let mut v = s.to_vec();
            let twins: Vec<[f64; 3]> = copied.iter().map(|&j| v[j]).collect();
            v.extend(twins);
            v
        })
        .collect();
    (Population::new(posemfa::mesh::Sources::UnitShapes { names: pop.names.clone(), faces, shapes }).unwrap(), copied)
}

dual_test! {
    fn a_mesh_cut_along_a_seam_gets_the_parts_it_gets_whole() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 1500, poses: 8, ..Spec::default() }).unwrap();
        let whole = fit(&g.population, &Params::default(), &mut |_| true).unwrap();
        for axis in [0, 2] {
            let (seamed, copied) = cut(&g.population, axis);
            assert!(copied.len() > 10, "axis {axis}: a seam of {} vertices", copied.len());
            assert!(seamed.graph_faces().len() > seamed.faces.len(), "the seam is bridged");
            let r = fit(&seamed, &Params::default(), &mut |_| true).unwrap();
            let n = g.population.n_vertices();
            let ari = adjusted_rand_index(&r.model.labels[..n], &whole.model.labels);
            assert!(ari > 0.95, "axis {axis}: adjusted Rand {ari:.3} against the whole mesh's parts ({} / {} parts)", r.model.n_parts(), whole.model.n_parts());
            // each copy is in its vertex's part, and no part ends at the seam
            let apart = copied.iter().enumerate().filter(|&(k, &j)| r.model.labels[n + k] != r.model.labels[j]).count();
            assert!(apart * 20 <= copied.len(), "axis {axis}: {apart} of {} copies in another part than their vertex", copied.len());
            assert_eq!(posemfa::parts::islands::island_count(&r.model.labels, seamed.graph_faces()), 0);
        }
    }
}
