//! Smooth 1-D building blocks of the generator: a Catmull-Rom centre line with an arc-length table, and
//! monotone cubic interpolation (Fritsch-Carlson) for radius profiles (no overshoot, so radii stay positive).

use crate::geometry::{add, norm, scale, sub, Vec3};

/// Uniform Catmull-Rom spline through `points` (parameter t in [0, n-1], knot k at t = k), with phantom end
/// points mirrored so the curve starts and ends along its first and last chords.
#[derive(Debug, Clone)]
pub struct Spline {
    points: Vec<Vec3>,
    /// Dense table: t values and the arc length at each.
    table_t: Vec<f64>,
    table_s: Vec<f64>,
}

const SAMPLES_PER_SPAN: usize = 256;

impl Spline {
    pub fn new(points: Vec<Vec3>) -> Spline {
        assert!(points.len() >= 2, "a spline needs two points");
        let mut sp = Spline { points, table_t: Vec::new(), table_s: Vec::new() };
        let spans = sp.points.len() - 1;
        let n = spans * SAMPLES_PER_SPAN;
        let mut prev = sp.position(0.0);
        let mut s = 0.0;
        sp.table_t.push(0.0);
        sp.table_s.push(0.0);
        for k in 1..=n {
            let t = spans as f64 * k as f64 / n as f64;
            let p = sp.position(t);
            s += norm(sub(p, prev));
            prev = p;
            sp.table_t.push(t);
            sp.table_s.push(s);
        }
        sp
    }

    pub fn t_max(&self) -> f64 {
        (self.points.len() - 1) as f64
    }

    pub fn length(&self) -> f64 {
        *self.table_s.last().expect("table is never empty")
    }

    fn control(&self, i: isize) -> Vec3 {
        let n = self.points.len() as isize;
        if i < 0 {
            sub(scale(self.points[0], 2.0), self.points[1])
        } else if i >= n {
            sub(scale(self.points[(n - 1) as usize], 2.0), self.points[(n - 2) as usize])
        } else {
            self.points[i as usize]
        }
    }

    /// Position and derivative d/dt at parameter t.
    pub fn eval(&self, t: f64) -> (Vec3, Vec3) {
        let t = t.clamp(0.0, self.t_max());
        let i = (t.floor() as isize).min(self.points.len() as isize - 2);
        let u = t - i as f64;
        let (p0, p1, p2, p3) = (self.control(i - 1), self.control(i), self.control(i + 1), self.control(i + 2));
        let mut pos = [0.0; 3];
        let mut der = [0.0; 3];
        for d in 0..3 {
            let a = 2.0 * p1[d];
            let b = p2[d] - p0[d];
            let c = 2.0 * p0[d] - 5.0 * p1[d] + 4.0 * p2[d] - p3[d];
            let e = -p0[d] + 3.0 * p1[d] - 3.0 * p2[d] + p3[d];
            pos[d] = 0.5 * (a + u * (b + u * (c + u * e)));
            der[d] = 0.5 * (b + u * (2.0 * c + u * 3.0 * e));
        }
        (pos, der)
    }

    pub fn position(&self, t: f64) -> Vec3 {
        self.eval(t).0
    }

    /// Unit tangent at parameter t.
    pub fn tangent(&self, t: f64) -> Vec3 {
        let d = self.eval(t).1;
        let l = norm(d);
        if l > 0.0 {
            scale(d, 1.0 / l)
        } else {
            let a = self.position((t - 1e-3).max(0.0));
            let b = self.position((t + 1e-3).min(self.t_max()));
            let v = sub(b, a);
            scale(v, 1.0 / norm(v))
        }
    }

    /// Arc length from t = 0 (from the dense table, linear between samples).
    pub fn s_of_t(&self, t: f64) -> f64 {
        interp(&self.table_t, &self.table_s, t)
    }

    /// Parameter at arc length s (inverse of [`Spline::s_of_t`]).
    pub fn t_of_s(&self, s: f64) -> f64 {
        interp(&self.table_s, &self.table_t, s)
    }

    pub fn point_at_s(&self, s: f64) -> Vec3 {
        self.position(self.t_of_s(s))
    }
}

/// Piecewise-linear interpolation of y(x) on increasing xs, clamped at the ends.
pub fn interp(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    if x <= xs[0] {
        return ys[0];
    }
    let last = xs.len() - 1;
    if x >= xs[last] {
        return ys[last];
    }
    let k = xs.partition_point(|&v| v <= x).clamp(1, last);
    let (x0, x1) = (xs[k - 1], xs[k]);
    let f = if x1 > x0 { (x - x0) / (x1 - x0) } else { 0.0 };
    ys[k - 1] + f * (ys[k] - ys[k - 1])
}

/// Monotone cubic Hermite interpolation (Fritsch-Carlson): C1, and never leaves the range of two neighbouring
/// knots, so positive knot values give a positive profile.
#[derive(Debug, Clone)]
pub struct Monotone {
    x: Vec<f64>,
    y: Vec<f64>,
    m: Vec<f64>,
}

impl Monotone {
    pub fn new(x: Vec<f64>, y: Vec<f64>) -> Monotone {
        assert!(x.len() == y.len() && x.len() >= 2, "monotone interpolation needs two knots");
        let n = x.len();
        let d: Vec<f64> = (0..n - 1).map(|k| (y[k + 1] - y[k]) / (x[k + 1] - x[k])).collect();
        let mut m = vec![0.0; n];
        m[0] = d[0];
        m[n - 1] = d[n - 2];
        for k in 1..n - 1 {
            m[k] = if d[k - 1] * d[k] <= 0.0 { 0.0 } else { (d[k - 1] + d[k]) / 2.0 };
        }
        for k in 0..n - 1 {
            if d[k] == 0.0 {
                m[k] = 0.0;
                m[k + 1] = 0.0;
                continue;
            }
            let a = m[k] / d[k];
            let b = m[k + 1] / d[k];
            let h = a * a + b * b;
            if h > 9.0 {
                let tau = 3.0 / h.sqrt();
                m[k] = tau * a * d[k];
                m[k + 1] = tau * b * d[k];
            }
        }
        Monotone { x, y, m }
    }

    pub fn eval(&self, x: f64) -> f64 {
        let n = self.x.len();
        if x <= self.x[0] {
            return self.y[0];
        }
        if x >= self.x[n - 1] {
            return self.y[n - 1];
        }
        let k = self.x.partition_point(|&v| v <= x).clamp(1, n - 1) - 1;
        let h = self.x[k + 1] - self.x[k];
        let t = (x - self.x[k]) / h;
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * self.y[k]
            + (t3 - 2.0 * t2 + t) * h * self.m[k]
            + (-2.0 * t3 + 3.0 * t2) * self.y[k + 1]
            + (t3 - t2) * h * self.m[k + 1]
    }
}

/// Point on the straight line a + u d.
pub fn along(a: Vec3, d: Vec3, u: f64) -> Vec3 {
    add(a, scale(d, u))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spline_interpolates_knots_and_arc_length_inverts() {
        let sp = Spline::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [3.0, 1.0, 0.5]]);
        for (k, p) in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [3.0, 1.0, 0.5]].iter().enumerate() {
            let q = sp.position(k as f64);
            assert!(norm(sub(q, *p)) < 1e-12, "knot {k}: {q:?}");
        }
        // straight first span: arc length of t = 1 is close to 1
        assert!((sp.s_of_t(1.0) - 1.0).abs() < 0.05);
        for &s in &[0.1, 0.7, 1.9, 2.5] {
            assert!((sp.s_of_t(sp.t_of_s(s)) - s).abs() < 1e-9);
        }
    }

    #[test]
    fn monotone_does_not_overshoot() {
        let m = Monotone::new(vec![0.0, 1.0, 2.0, 3.0], vec![0.1, 0.1, 1.0, 1.0]);
        for k in 0..=300 {
            let v = m.eval(k as f64 / 100.0);
            assert!((0.1 - 1e-12..=1.0 + 1e-12).contains(&v), "{v}");
        }
        assert!((m.eval(2.0) - 1.0).abs() < 1e-12 && (m.eval(0.5) - 0.1).abs() < 1e-12);
    }
}
