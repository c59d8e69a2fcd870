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

/// For each part of `labels`, the part of `before` (labels of the same vertices) that is the same part: the
/// one holding more than half of its vertices, and more than half of whose vertices it holds (at most one).
pub fn same_parts(labels: &[u32], before: &[u32]) -> Vec<Option<u32>> {
    let count = |l: &[u32]| {
        let mut n = vec![0usize; l.iter().map(|&x| x as usize + 1).max().unwrap_or(0)];
        l.iter().for_each(|&x| n[x as usize] += 1);
        n
    };
    let (size, before_size) = (count(labels), count(before));
    let mut shared: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
    for (&l, &b) in labels.iter().zip(before) {
        *shared.entry((l, b)).or_insert(0) += 1;
    }
    let mut same = vec![None; size.len()];
    for ((l, b), n) in shared {
        if 2 * n > size[l as usize] && 2 * n > before_size[b as usize] {
            same[l as usize] = Some(b);
        }
    }
    same
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

/// The geometric mean of `values` over the weight between the quantiles `lo` and `hi` (0 <= lo < hi <= 1),
/// each value counted by the part of its weight inside that band. Values of 0 (or below) have no logarithm and are
/// left out; with none left, the weighted median.
pub fn weighted_log_mean_between(values: &[f64], weights: &[usize], lo: f64, hi: f64) -> f64 {
    let mut by: Vec<(f64, usize)> = values.iter().copied().zip(weights.iter().copied()).collect();
    by.sort_by(|x, y| x.0.total_cmp(&y.0));
    let total = by.iter().map(|x| x.1).sum::<usize>() as f64;
    let (a, b) = (lo * total, hi * total);
    let (mut acc, mut sum, mut mass) = (0.0, 0.0, 0.0);
    for (v, w) in &by {
        let (s, e) = (acc, acc + *w as f64);
        acc = e;
        let inside = (e.min(b) - s.max(a)).max(0.0);
        if inside > 0.0 && *v > 0.0 {
            sum += inside * v.ln();
            mass += inside;
        }
    }
    if mass > 0.0 {
        (sum / mass).exp()
    } else {
        weighted_median(values, weights)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_middle_log_mean_counts_each_value_by_its_weight_inside_the_band() {
        // 4 vertices: the band 0.3-0.7 takes 0.8 of the second and 0.8 of the third
        let m = weighted_log_mean_between(&[1.0, 10.0, 100.0, 1000.0], &[1, 1, 1, 1], 0.3, 0.7);
        assert!((m - 1000f64.sqrt()).abs() < 1e-9, "{m}");
        // weights: 1 (x 2 vertices) and 100 (x 8): the band 2-8 of 10 is all on 100
        let m = weighted_log_mean_between(&[100.0, 1.0], &[8, 2], 0.2, 0.8);
        assert!((m - 100.0).abs() < 1e-9, "{m}");
    }

    #[test]
    fn the_middle_log_mean_moves_little_where_the_median_jumps() {
        // half the vertices in parts of variance 1e-7, half in 1e-5: a vertex more on one side moves the median
        // by 100 times, the middle band's mean by 10^0.1
        let (a, b) = (weighted_median(&[1e-7, 1e-5], &[51, 49]), weighted_median(&[1e-7, 1e-5], &[49, 51]));
        assert!((b / a - 100.0).abs() < 1e-9);
        let a = weighted_log_mean_between(&[1e-7, 1e-5], &[51, 49], 0.3, 0.7);
        let b = weighted_log_mean_between(&[1e-7, 1e-5], &[49, 51], 0.3, 0.7);
        assert!((b / a - 10f64.powf(0.1)).abs() < 1e-9, "{}", b / a);
    }

    #[test]
    fn a_part_is_the_same_part_when_most_of_each_is_shared() {
        // before: parts 0 (4 vertices), 1 (4), 2 (2); now part 2 went into part 1 (renumbered 0), and part 0 of
        // before was cut in halves (1 and 2)
        let before = [0, 0, 0, 0, 1, 1, 1, 1, 2, 2];
        let now = [1, 1, 2, 2, 0, 0, 0, 0, 0, 0];
        // part 0 now holds all of before's part 1 and 4 of its own 6 vertices: the same part; the halves hold half
        // of before's part 0 each, not more: new parts
        assert_eq!(same_parts(&now, &before), vec![Some(1), None, None]);
        assert_eq!(same_parts(&before, &before), vec![Some(0), Some(1), Some(2)]);
    }
}
