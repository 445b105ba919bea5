//! The smallest sphere enclosing a set of points, exactly: Welzl's
//! algorithm in Gärtner's move-to-front form. The points are taken in the
//! order given (no shuffle: the same points give the same bytes; the
//! expected-linear bound of a random order matters not for the handful of
//! centres an acceptance test encloses). Exact duplicates are dropped
//! first; a support set that spans less than its count asks (three points
//! on a line, four on a plane, within rounding) is replaced by the smallest
//! sphere of its subsets that holds all of it.

use nalgebra::{Matrix3, Vector3};

/// A ball: centre and radius, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ball {
    /// Centre, mm.
    pub centre: [f64; 3],
    /// Radius, mm (negative for the empty ball).
    pub radius: f64,
}

impl Ball {
    const EMPTY: Ball = Ball {
        centre: [0.0; 3],
        radius: -1.0,
    };

    /// Whether `p` lies in the ball, to rounding (1e-12 relative).
    pub(crate) fn contains(&self, p: &[f64; 3]) -> bool {
        let d = crate::geometry::distance(&self.centre, p);
        self.radius >= 0.0 && d <= self.radius * (1.0 + 1e-12) + 1e-12
    }
}

/// The smallest ball enclosing `points` (the empty ball for none).
pub(crate) fn enclosing_ball(points: &[[f64; 3]]) -> Ball {
    let mut list: Vec<[f64; 3]> = Vec::with_capacity(points.len());
    for p in points {
        if !list.contains(p) {
            list.push(*p);
        }
    }
    let end = list.len();
    let mut support = Vec::with_capacity(4);
    move_to_front(&mut list, end, &mut support)
}

/// Welzl's recursion over the first `end` points of `list`, with `support`
/// on the boundary; a point outside moves to the front.
fn move_to_front(list: &mut Vec<[f64; 3]>, end: usize, support: &mut Vec<[f64; 3]>) -> Ball {
    let mut ball = ball_on(support);
    if support.len() == 4 {
        return ball;
    }
    for i in 0..end {
        let p = list[i];
        if !ball.contains(&p) {
            support.push(p);
            ball = move_to_front(list, i, support);
            support.pop();
            list.remove(i);
            list.insert(0, p);
        }
    }
    ball
}

/// The smallest ball with every point of `s` (0 to 4) on its boundary —
/// or, where `s` spans too little for that, the smallest of its subsets'
/// balls holding all of `s`.
fn ball_on(s: &[[f64; 3]]) -> Ball {
    match s.len() {
        0 => Ball::EMPTY,
        1 => Ball {
            centre: s[0],
            radius: 0.0,
        },
        2 => Ball {
            centre: std::array::from_fn(|k| (s[0][k] + s[1][k]) / 2.0),
            radius: crate::geometry::distance(&s[0], &s[1]) / 2.0,
        },
        _ => circumscribed(s).unwrap_or_else(|| smallest_of_subsets(s)),
    }
}

/// The ball through 3 or 4 points with its centre in their affine hull:
/// `c = p0 + Σ λ_k (p_k − p0)` with `|c − p_k| = |c − p0|`, i.e.
/// `A λ = b`, `A_jk = 2 (p_j − p0)·(p_k − p0)`, `b_j = |p_j − p0|²`.
/// `None` when the points span too little.
fn circumscribed(s: &[[f64; 3]]) -> Option<Ball> {
    let p0 = Vector3::from(s[0]);
    let d: Vec<Vector3<f64>> = s[1..].iter().map(|p| Vector3::from(*p) - p0).collect();
    let m = d.len();
    let mut a = Matrix3::<f64>::identity();
    let mut b = Vector3::<f64>::zeros();
    let scale = d.iter().map(|v| v.norm_squared()).fold(0.0, f64::max);
    for j in 0..m {
        for k in 0..m {
            a[(j, k)] = 2.0 * d[j].dot(&d[k]);
        }
        b[j] = d[j].norm_squared();
    }
    // The Gram determinant against the scale: points on a line (3) or a
    // plane (4) within rounding.
    let det = a.determinant();
    if det.is_nan() || det.abs() <= 1e-10 * (2.0 * scale).powi(m as i32) {
        return None;
    }
    let lambda = a.lu().solve(&b)?;
    let c = p0 + (0..m).map(|k| d[k] * lambda[k]).sum::<Vector3<f64>>();
    let ball = Ball {
        centre: [c[0], c[1], c[2]],
        radius: (c - p0).norm(),
    };
    ball.radius.is_finite().then_some(ball)
}

/// The smallest ball on a proper subset of `s` that holds every point of
/// `s` (a degenerate support set's).
fn smallest_of_subsets(s: &[[f64; 3]]) -> Ball {
    let n = s.len();
    let mut best = Ball {
        centre: [0.0; 3],
        radius: f64::INFINITY,
    };
    for mask in 1u32..(1 << n) - 1 {
        let sub: Vec<[f64; 3]> = (0..n)
            .filter(|k| mask >> k & 1 == 1)
            .map(|k| s[k])
            .collect();
        let ball = match sub.len() {
            1 | 2 => ball_on(&sub),
            _ => match circumscribed(&sub) {
                Some(b) => b,
                None => continue,
            },
        };
        if ball.radius < best.radius && s.iter().all(|p| ball.contains(p)) {
            best = ball;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_tetrahedron_and_degenerate_sets() {
        let t = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
        let b = enclosing_ball(&t);
        assert!(b.centre.iter().all(|v| v.abs() < 1e-12));
        assert!((b.radius - 3f64.sqrt()).abs() < 1e-12);
        // Duplicates, a point inside, collinear points.
        let mut more = t.to_vec();
        more.extend([[0.1, 0.0, 0.0], t[2], t[0]]);
        assert_eq!(enclosing_ball(&more).radius, b.radius);
        let line = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
        ];
        let b = enclosing_ball(&line);
        assert_eq!((b.centre, b.radius), ([1.5, 0.0, 0.0], 1.5));
        // Four on a circle: the circle's ball.
        let c = [
            [1.0, 0.0, 5.0],
            [0.0, 1.0, 5.0],
            [-1.0, 0.0, 5.0],
            [0.0, -1.0, 5.0],
        ];
        let b = enclosing_ball(&c);
        assert!((b.radius - 1.0).abs() < 1e-12 && (b.centre[2] - 5.0).abs() < 1e-12);
        assert_eq!(enclosing_ball(&[[2.0, 3.0, 4.0]; 3]).radius, 0.0);
        assert!(enclosing_ball(&[]).radius < 0.0);
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn acceptance_enclosing_enclosing_ball() {
        use crate::acceptance::enclosing_ball;
        let b = enclosing_ball(&[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.5, 0.0]]);
        assert_eq!((b.centre, b.radius), ([1.0, 0.0, 0.0], 1.0));
    }
}
