//! Points on spheres held out: dealt to cross-validation folds, and scored
//! by their radial error against a sphere fitted without them.
//!
//! **How they split.** Each sphere's points are dealt to the folds one by
//! one in a seeded order (the stream of its own, `SPHERE_FOLDS`), so every
//! fold holds out a few points of every sphere and its training keeps the
//! rest — not whole spheres. A sphere's centre (and fitted radius) is a
//! block of the layout every fold fits: a sphere held out whole would leave
//! its block without a row in that fold (no fit), and scoring it would need
//! its centre refitted on the held-out points themselves, which then set
//! what scores them. Dealt points are scored as a new point on a known
//! sphere is: its radial error against the centre and radius the fold
//! fitted. Each fold's training must keep at least
//! [`MIN_TRAINING_POINTS`] points of every sphere, not on one circle
//! (checked where the start arm puts them); a fold count that leaves fewer
//! is refused by the sphere's name.

use super::{SphereTerm, TERM, algebraic_sphere};
use crate::residuals::{At, HeldOutScorer, Term, TermError, TermFold};

/// The fewest points a sphere keeps in a fold's training: its centre and
/// radius are 4 unknowns.
pub(crate) const MIN_TRAINING_POINTS: usize = 4;

impl SphereTerm {
    /// The term of rows `rows` (ascending) of this one, on the same blocks
    /// (each sphere's centre and radius), with their weights.
    ///
    /// # Errors
    ///
    /// The kernel's refusal of the readings.
    pub(crate) fn restricted(&self, rows: &[usize]) -> Result<SphereTerm, TermError> {
        let spheres = self.spheres.subset(rows);
        // Per sphere of the subset, the whole term's sphere of that name.
        let mut of = vec![0; spheres.spheres().len()];
        for (k, &i) in rows.iter().enumerate() {
            of[spheres.sphere(k)] = self.spheres.sphere(i);
        }
        let all: Vec<usize> = (0..spheres.len()).collect();
        let poses = super::prepared(&spheres, &all, self.poses.shape())?;
        let pick = |v: &[f64]| -> Vec<f64> {
            if v.len() == self.spheres.len() {
                rows.iter().map(|&i| v[i]).collect()
            } else {
                Vec::new()
            }
        };
        // The subset numbers its tools anew: each keeps its ball by name.
        let balls = (spheres.tools().iter())
            .map(|t| {
                let k = self.spheres.tools().iter().position(|o| o.name == t.name);
                k.map_or(0.0, |k| self.balls[k])
            })
            .collect();
        Ok(SphereTerm {
            by_tool: super::by_tool(&spheres, self.poses.shape())?,
            centres: of.iter().map(|&s| self.centres[s]).collect(),
            balls,
            radii: of.iter().map(|&s| self.radii[s]).collect(),
            robust: rows.iter().map(|&i| self.robust[i]).collect(),
            sigmas: pick(&self.sigmas),
            weights: pick(&self.weights),
            spheres,
            poses,
            ..self.clone()
        })
    }

    /// Per sphere (this term's order), its centre and the radius of its
    /// probe-centre sphere (the sphere's own plus the ball's, mm), fitted
    /// on this term's points at `at`'s arm held fixed: of least squared
    /// radial error (unweighted), the radius stated when the diameter is.
    ///
    /// # Errors
    ///
    /// The kernel's; a sphere whose points fix no sphere.
    pub(crate) fn refitted_spheres(&self, at: &At<'_>) -> Result<Vec<([f64; 3], f64)>, TermError> {
        let q = self.positions(at)?;
        (self.spheres.spheres().iter().enumerate())
            .map(|(s, name)| {
                let known = (self.known_radius).map(|r| r + self.ball_radius_of(s));
                let points: Vec<[f64; 3]> = self.spheres.rows_of(s).iter().map(|&i| q[i]).collect();
                fit_sphere(&points, known).ok_or_else(|| {
                    TermError::invalid(TERM, format!("sphere `{name}`: no sphere fits its points"))
                })
            })
            .collect()
    }

    /// Per row, its radial error (mm) at `at`'s arm against its sphere
    /// refitted on the rows of `fit_on` (a term of the same file's rows,
    /// [`SphereTerm::restricted`]) with the arm fixed
    /// ([`SphereTerm::refitted_spheres`]). `fit_on` may be this term
    /// itself: a held-out sphere file's figures, each sphere's form as the
    /// arm sees it.
    ///
    /// # Errors
    ///
    /// The kernel's; a sphere `fit_on` has no points of, or whose points
    /// fix no sphere.
    pub(crate) fn refitted_errors(
        &self,
        fit_on: &SphereTerm,
        at: &At<'_>,
    ) -> Result<Vec<f64>, TermError> {
        let p = self.positions(at)?;
        let spheres = fit_on.refitted_spheres(at)?;
        let fitted = (self.spheres.spheres().iter())
            .map(|name| {
                (fit_on.spheres.spheres().iter())
                    .position(|n| n == name)
                    .map(|s| spheres[s])
                    .ok_or_else(|| {
                        TermError::invalid(TERM, format!("sphere `{name}`: no point to fit it on"))
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((0..p.len())
            .map(|i| {
                let (c, r) = fitted[self.spheres.sphere(i)];
                crate::geometry::distance(&p[i], &c) - r
            })
            .collect())
    }
}

/// The sphere of least squared radial error through `points`: its centre
/// and its radius (`radius` when given, else fitted), by Gauss–Newton from
/// the algebraic fit ([`algebraic_sphere`]). `None` for points that fix no
/// sphere.
pub(crate) fn fit_sphere(points: &[[f64; 3]], radius: Option<f64>) -> Option<([f64; 3], f64)> {
    let (start, r0) = algebraic_sphere(points)?;
    let n = if radius.is_some() { 3 } else { 4 };
    let mut c = nalgebra::Vector3::from(start);
    let mut r = radius.unwrap_or(r0);
    for _ in 0..100 {
        let (mut jtj, mut jtr) = (nalgebra::DMatrix::zeros(n, n), nalgebra::DVector::zeros(n));
        for p in points {
            let v = nalgebra::Vector3::from(*p) - c;
            let d = v.norm();
            let u = if d > 0.0 { v / d } else { v };
            let j = nalgebra::DVector::from_fn(n, |k, _| if k < 3 { -u[k] } else { -1.0 });
            jtj += &j * j.transpose();
            jtr += &j * (d - r);
        }
        let step = jtj.cholesky()?.solve(&(-jtr));
        c += step.rows(0, 3);
        if n == 4 {
            r += step[3];
        }
        if step.norm() <= 1e-12 * (1.0 + c.norm()) {
            break;
        }
    }
    (c.iter().all(|v| v.is_finite()) && r.is_finite() && r > 0.0).then(|| ([c[0], c[1], c[2]], r))
}

/// One fold's held-out points: scored against the fold's spheres.
#[derive(Clone, Debug)]
struct SphereScorer {
    /// The fold's training points (what a start arm's spheres are
    /// refitted on).
    training: SphereTerm,
    /// The points held out.
    held: SphereTerm,
}

impl HeldOutScorer for SphereScorer {
    fn labels(&self) -> Vec<String> {
        (0..self.held.observations())
            .map(|i| self.held.origin(i).at)
            .collect()
    }

    fn what(&self) -> String {
        format!(
            "points on spheres ({}): |radial error| against the fold's spheres (before: the \
             nominal arm, each sphere refitted on the fold's training points)",
            self.held.file
        )
    }

    fn fitted(&self, at: &At<'_>) -> Result<Vec<f64>, TermError> {
        self.held.radial_errors(at)
    }

    fn refitted(&self, at: &At<'_>) -> Result<Vec<f64>, TermError> {
        self.held.refitted_errors(&self.training, at)
    }
}

/// Per fold, the rows it holds out (ascending): each sphere's points in a
/// seeded order dealt one by one, the deal carried on from one sphere to
/// the next so that the folds are as even as the points allow.
fn deal(term: &SphereTerm, k: usize, seed: u64) -> Vec<Vec<usize>> {
    use rand::seq::SliceRandom;
    let mut rng = crate::random::rng(seed, crate::random::streams::SPHERE_FOLDS);
    let mut folds: Vec<Vec<usize>> = vec![Vec::new(); k];
    let mut next = 0;
    for s in 0..term.spheres.spheres().len() {
        let mut rows = term.spheres.rows_of(s);
        rows.shuffle(&mut rng);
        for row in rows {
            folds[next % k].push(row);
            next += 1;
        }
    }
    folds.iter_mut().for_each(|f| f.sort_unstable());
    folds
}

/// [`Term::split`] of the sphere term: see the module's documentation.
pub(super) fn split(
    term: &SphereTerm,
    at: &At<'_>,
    k: usize,
    seed: u64,
) -> Result<Vec<TermFold>, TermError> {
    for (s, name) in term.spheres.spheres().iter().enumerate() {
        let n = term.spheres.rows_of(s).len();
        if k < 2 || n.saturating_sub(n.div_ceil(k)) < MIN_TRAINING_POINTS {
            return Err(TermError::invalid(
                TERM,
                format!(
                    "sphere `{name}` has {n} points: {k} folds leave fewer than \
                     {MIN_TRAINING_POINTS} in a fold's training (its centre and size are 4 \
                     unknowns)"
                ),
            ));
        }
    }
    if k > term.spheres.len() {
        return Err(TermError::invalid(
            TERM,
            format!(
                "{k} folds for {} points: a fold would hold none out",
                term.spheres.len()
            ),
        ));
    }
    let start = term.positions(at)?;
    deal(term, k, seed)
        .into_iter()
        .enumerate()
        .map(|(f, held)| {
            let train: Vec<usize> = (0..term.spheres.len())
                .filter(|i| held.binary_search(i).is_err())
                .collect();
            let training = term.restricted(&train)?;
            let seen: Vec<[f64; 3]> = train.iter().map(|&i| start[i]).collect();
            training
                .spheres
                .check_geometry(&term.file, &seen)
                .map_err(|e| TermError::invalid(TERM, format!("fold {}'s training: {e}", f + 1)))?;
            Ok(TermFold {
                held_out: Box::new(SphereScorer {
                    held: term.restricted(&held)?,
                    training: training.clone(),
                }),
                training: Box::new(training),
            })
        })
        .collect()
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn residuals_spheres_folds_fit_sphere() {
        use super::fit_sphere;
        let p = [
            [11.0, 2.0, 3.0],
            [1.0, 12.0, 3.0],
            [1.0, 2.0, 13.0],
            [-9.0, 2.0, 3.0],
            [1.0, -8.0, 3.1],
        ];
        let (c, r) = fit_sphere(&p, None).unwrap();
        let (_, known) = fit_sphere(&p, Some(10.0)).unwrap();
        assert!((c[0] - 1.0).abs() < 0.05 && (r - 10.0).abs() < 0.05 && known == 10.0);
    }
}
