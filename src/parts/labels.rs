//! Small operations on part labels and per-part values that the part rules and the merge tree share.

/// Labels renumbered 0.. in order of first appearance of each used value.
pub fn compact(labels: &[u32]) -> Vec<u32> {
    let mut map = std::collections::HashMap::new();
    labels
        .iter()
        .map(|&l| {
            let n = map.len() as u32;
            *map.entry(l).or_insert(n)
        })
        .collect()
}

/// The parts adjacent to each part (sharing a mesh edge), sorted, and each part's vertices, for at least
/// `n_parts` parts (a part may have no vertex left).
pub(crate) fn adjacency(labels: &[u32], faces: &[[u32; 3]], n_parts: usize) -> (Vec<Vec<usize>>, Vec<Vec<usize>>) {
    let m = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0).max(n_parts);
    let mut adjacent = vec![Vec::new(); m];
    let mut members = vec![Vec::new(); m];
    for (j, &l) in labels.iter().enumerate() {
        members[l as usize].push(j);
    }
    for f in faces {
        for e in 0..3 {
            let (a, b) = (labels[f[e] as usize] as usize, labels[f[(e + 1) % 3] as usize] as usize);
            if a != b {
                adjacent[a].push(b);
                adjacent[b].push(a);
            }
        }
    }
    for a in adjacent.iter_mut() {
        a.sort_unstable();
        a.dedup();
    }
    (adjacent, members)
}

/// The vertex-weighted median of per-part values.
pub fn weighted_median(values: &[f64], weights: &[usize]) -> f64 {
    let mut by: Vec<(f64, usize)> = values.iter().copied().zip(weights.iter().copied()).collect();
    by.sort_by(|x, y| x.0.total_cmp(&y.0));
    let half = by.iter().map(|x| x.1).sum::<usize>().div_ceil(2);
    let mut acc = 0;
    for (v, w) in &by {
        acc += w;
        if acc >= half {
            return *v;
        }
    }
    by.last().map_or(0.0, |x| x.0)
}
