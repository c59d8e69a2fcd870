//! Distances from points to a triangle surface: the nearest point of a triangle, and a uniform grid that finds
//! whether a point lies within a distance of any of many triangles without testing them all.

use super::{add, dot, norm, scale, sub, Vec3};
use std::collections::HashMap;

/// The point of triangle (a, b, c) nearest `p`: the projection onto the plane when it falls inside, else the
/// nearest point of the nearest edge or corner (the Voronoi regions of the corners, then of the edges, as in
/// Ericson, *Real-Time Collision Detection*, 5.1.5). A degenerate triangle gives a point of its segment or corner.
pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return add(a, scale(ab, d1 / (d1 - d3)));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return add(a, scale(ac, d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let sum = va + vb + vc;
    if !(sum.abs() > 0.0) {
        // degenerate (collinear corners): the nearest of the three edges
        let seg = |u: Vec3, v: Vec3| {
            let d = sub(v, u);
            let l = dot(d, d);
            let t = if l > 0.0 { (dot(sub(p, u), d) / l).clamp(0.0, 1.0) } else { 0.0 };
            add(u, scale(d, t))
        };
        return [seg(a, b), seg(b, c), seg(a, c)]
            .into_iter()
            .min_by(|x, y| norm(sub(p, *x)).total_cmp(&norm(sub(p, *y))))
            .unwrap_or(a);
    }
    let (v, w) = (vb / sum, vc / sum);
    add(a, add(scale(ab, v), scale(ac, w)))
}

/// Triangles binned in a uniform grid of cubes, each triangle in every cell its bounding box (grown by the
/// query distance) meets, so that the triangles within that distance of a point are all in the point's cell.
/// A triangle that would meet more than [`SurfaceGrid::MAX_CELLS`] cells (one far larger than the others) is
/// kept in a list that every query tests instead, so that memory stays bounded by the triangle count.
pub struct SurfaceGrid {
    triangles: Vec<[Vec3; 3]>,
    origin: Vec3,
    cell: f64,
    within: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
    large: Vec<u32>,
}

impl SurfaceGrid {
    /// A grid for asking whether points are within `within` of `triangles`. The cell is the larger of the
    /// triangles' mean bounding-box side and 2 `within`, so a triangle meets a few cells.
    pub fn new(triangles: Vec<[Vec3; 3]>, within: f64) -> SurfaceGrid {
        let within = if within.is_finite() { within.max(0.0) } else { 0.0 };
        let (origin, _) = super::bounds(triangles.iter().flatten());
        let mean_side = triangles
            .iter()
            .map(|t| {
                let (lo, hi) = super::bounds(t.iter());
                (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max)
            })
            .sum::<f64>()
            / triangles.len().max(1) as f64;
        let cell = mean_side.max(2.0 * within).max(1e-12);
        let mut grid =
            SurfaceGrid { triangles: Vec::new(), origin, cell, within, cells: HashMap::new(), large: Vec::new() };
        for (i, t) in triangles.iter().enumerate() {
            if !t.iter().flatten().all(|c| c.is_finite()) {
                continue;
            }
            let (lo, hi) = super::bounds(t.iter());
            let (a, b) = (grid.index(sub(lo, [within; 3])), grid.index(add(hi, [within; 3])));
            let count: i64 = (0..3).map(|d| b[d] - a[d] + 1).product();
            if count > Self::MAX_CELLS {
                grid.large.push(i as u32);
                continue;
            }
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        grid.cells.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        grid.triangles = triangles;
        grid
    }

    /// The most cells one triangle is binned in.
    pub const MAX_CELLS: i64 = 64;

    fn index(&self, p: Vec3) -> [i64; 3] {
        // clamped so that a far point (or a huge triangle) cannot ask for an absurd range of cells
        [0, 1, 2].map(|d| ((p[d] - self.origin[d]) / self.cell).floor().clamp(-1e6, 1e6) as i64)
    }

    /// Whether `p` lies within the grid's distance of one of its triangles.
    pub fn near(&self, p: Vec3) -> bool {
        if !p.iter().all(|c| c.is_finite()) {
            return false;
        }
        let binned = self.cells.get(&self.index(p)).map(|l| l.as_slice()).unwrap_or(&[]);
        binned.iter().chain(&self.large).any(|&i| {
            let [a, b, c] = self.triangles[i as usize];
            norm(sub(p, closest_point_on_triangle(p, a, b, c))) <= self.within
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_point_of_a_triangle_in_every_region() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
        let near = |p: Vec3| closest_point_on_triangle(p, a, b, c);
        let close = |x: Vec3, y: Vec3| norm(sub(x, y)) < 1e-12;
        assert!(close(near([0.5, 0.5, 3.0]), [0.5, 0.5, 0.0])); // inside: the projection
        assert!(close(near([-1.0, -1.0, 0.5]), a)); // the corners
        assert!(close(near([3.0, -0.5, 0.0]), b));
        assert!(close(near([-0.5, 3.0, 1.0]), c));
        assert!(close(near([1.0, -2.0, 0.0]), [1.0, 0.0, 0.0])); // the edges
        assert!(close(near([-2.0, 1.0, 0.0]), [0.0, 1.0, 0.0]));
        assert!(close(near([2.0, 2.0, -1.0]), [1.0, 1.0, 0.0]));
        // against brute force over a fine grid of the triangle, for points all around it
        for k in 0..200 {
            let t = k as f64 * 0.7;
            let p = [3.0 * t.sin(), 2.5 * (1.3 * t).cos(), (0.4 * t).sin()];
            let best = (0..=100)
                .flat_map(|i| (0..=100 - i).map(move |j| (i, j)))
                .map(|(i, j)| add(scale(b, i as f64 / 100.0), scale(c, j as f64 / 100.0)))
                .map(|q| norm(sub(p, q)))
                .fold(f64::INFINITY, f64::min);
            let got = norm(sub(p, near(p)));
            assert!(got <= best + 1e-12 && got > best - 0.03, "{p:?}: {got} against {best}");
        }
        // a degenerate triangle: its segment
        let q = closest_point_on_triangle([1.0, 1.0, 0.0], a, b, [1.0, 0.0, 0.0]);
        assert!(close(q, [1.0, 0.0, 0.0]));
    }

    #[test]
    fn the_grid_finds_what_testing_every_triangle_finds() {
        // a bumpy strip of triangles, and points scattered around it
        let height = |x: f64, y: f64| 0.3 * (2.0 * x).sin() * (1.5 * y).cos();
        let mut tris = Vec::new();
        for i in 0..20 {
            for j in 0..10 {
                let (x, y) = (i as f64 * 0.25, j as f64 * 0.25);
                let p = |dx: f64, dy: f64| [x + dx, y + dy, height(x + dx, y + dy)];
                tris.push([p(0.0, 0.0), p(0.25, 0.0), p(0.0, 0.25)]);
                tris.push([p(0.25, 0.0), p(0.25, 0.25), p(0.0, 0.25)]);
            }
        }
        for within in [0.0, 0.01, 0.1, 0.6] {
            let grid = SurfaceGrid::new(tris.clone(), within);
            let mut near = 0;
            for k in 0..2000 {
                let t = k as f64 * 0.37;
                let p = [2.5 + 3.0 * (0.9 * t).sin(), 1.25 + 2.0 * (1.1 * t).cos(), 0.5 * (0.3 * t).sin()];
                let every = tris.iter().any(|&[a, b, c]| norm(sub(p, closest_point_on_triangle(p, a, b, c))) <= within);
                assert_eq!(grid.near(p), every, "{p:?} within {within}");
                near += every as usize;
            }
            // the scattered points test both answers at the larger distances
            assert!(within < 0.1 || (near > 50 && near < 1950), "{near} near at {within}");
            // points just off the surface, inside and outside the distance
            for (k, &[a, b, c]) in tris.iter().enumerate().step_by(7) {
                let normal = crate::geometry::cross(sub(b, a), sub(c, a));
                let normal = scale(normal, 1.0 / norm(normal));
                let centre = scale(add(add(a, b), c), 1.0 / 3.0);
                let off = [0.5, 0.9, 1.1, 2.0][k % 4] * within;
                let p = add(centre, scale(normal, if k % 2 == 0 { off } else { -off }));
                let every = tris.iter().any(|&[a, b, c]| norm(sub(p, closest_point_on_triangle(p, a, b, c))) <= within);
                assert_eq!(grid.near(p), every, "{p:?} within {within}");
            }
        }
        // one triangle a million times the others' size: kept aside, still found, and no vast grid
        let mut with_large = tris.clone();
        with_large.push([[-1e6, -1e6, 5.0], [1e6, -1e6, 5.0], [0.0, 1e6, 5.0]]);
        let grid = SurfaceGrid::new(with_large, 0.1);
        assert_eq!(grid.large.len(), 1);
        assert!(grid.near([3e5, 2e5, 5.05]) && !grid.near([3e5, 2e5, 5.2]) && grid.near(tris[3][0]));
        // a corner is on the surface at distance 0
        assert!(SurfaceGrid::new(tris.clone(), 0.0).near(tris[5][1]));
        assert!(!SurfaceGrid::new(Vec::new(), 1.0).near([0.0; 3]));
    }
}
