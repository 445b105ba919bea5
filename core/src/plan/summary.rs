//! A plan in words: what was optimised, the predicted radius with the
//! chosen rows against all candidates and random ones, the curve as rows
//! are added and where more stop paying (the knee), the ranking, the
//! sockets and the joint spans — the text printed beside a calibration's
//! summary, the same for every front end.

use super::coverage::K_ISOTROPIC;
use super::pool::Pool;
use super::{Criterion, CurvePoint, Measure, Plan, Spread};
use crate::error::short;

/// More rows stop paying where doubling them lowers the RMS radius by less
/// than this fraction.
pub(crate) const KNEE: f64 = 0.10;

/// Where more rows stop paying, read off a plan's curve ([`knee`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Knee {
    /// Doubling from `rows` lowers the RMS by `gain` (< [`KNEE`]).
    At {
        /// Rows from which doubling gains less than [`KNEE`].
        rows: usize,
        /// The fraction doubling them lowers the RMS radius by.
        gain: f64,
    },
    /// Every doubling the curve shows still gains [`KNEE`] or more; the
    /// last from `rows`, by `gain`.
    Beyond {
        /// Rows of the last doubling the curve shows.
        rows: usize,
        /// The fraction it lowers the RMS radius by.
        gain: f64,
    },
    /// The curve shows no doubling of determined rows.
    Unknown,
}

/// The first determined point of `curve` from which doubling the rows
/// lowers the RMS radius by less than [`KNEE`] (the RMS at twice the rows
/// interpolated between the curve's points).
pub(crate) fn knee(curve: &[CurvePoint]) -> Knee {
    let points: Vec<(usize, f64)> = curve
        .iter()
        .filter_map(|c| c.rms_mm.map(|r| (c.rows, r)))
        .collect();
    let at = |rows: usize| -> Option<f64> {
        let i = points.iter().position(|&(k, _)| k >= rows)?;
        let (k1, r1) = points[i];
        if k1 == rows || i == 0 {
            return (k1 == rows).then_some(r1);
        }
        let (k0, r0) = points[i - 1];
        Some(r0 + (r1 - r0) * (rows - k0) as f64 / (k1 - k0) as f64)
    };
    let mut last = Knee::Unknown;
    for &(k, r) in &points {
        let Some(r2) = at(2 * k) else { break };
        let gain = 1.0 - r2 / r;
        if gain < KNEE {
            return Knee::At { rows: k, gain };
        }
        last = Knee::Beyond { rows: k, gain };
    }
    last
}

/// A calibration a plan adds to, as the summary names it.
#[derive(Clone, Debug, PartialEq)]
pub struct GivenNote {
    /// Where it is (its output directory), as the user named it.
    pub dir: String,
    /// Its `σ̂₀`.
    pub sigma0: f64,
}

/// What the summary says beyond the plan: where the candidates and the
/// workspace come from, and the calibration added to.
#[derive(Clone, Copy, Debug)]
pub struct SummaryContext<'a> {
    /// The candidates the plan chose from.
    pub pool: &'a Pool,
    /// The workspace's file, when one was given (else the candidates).
    pub workspace: Option<&'a str>,
    /// The calibration the plan adds to, if any.
    pub given: Option<&'a GivenNote>,
}

/// What the user reads: what was optimised, the predicted radius with the
/// chosen rows against all and against random ones, the curve, the ranking,
/// the sockets and the joint spans.
pub fn summary(plan: &Plan, context: SummaryContext<'_>) -> String {
    let mut t = header(plan, context);
    t += &spreads(plan);
    t += &curve(plan);
    t += &ranking(plan, context.pool, context.given.is_some());
    if !plan.sockets.is_empty() {
        let s: Vec<String> = (plan.sockets.iter())
            .map(|(label, n)| format!("{label} {n}"))
            .collect();
        let per = match plan.measure {
            Measure::Spheres => "Points per sphere",
            _ => "Touches per socket",
        };
        t += &format!("{per}: {}\n", s.join(", "));
    }
    let spans: Vec<String> = (plan.joints.iter())
        .map(|j| {
            let mm = if j.prismatic { " mm" } else { "" };
            format!("q{} {:.0}/{:.0}{mm}", j.joint, j.chosen_deg, j.pool_deg)
        })
        .collect();
    t += &format!(
        "Joint spans, chosen/candidates (deg): {}\n",
        spans.join(", ")
    );
    t
}

/// What the summary says the plan optimised.
fn criterion_text(plan: &Plan) -> String {
    match plan.criterion {
        Criterion::Robust if plan.hedge > 0.0 => format!(
            "the mean predicted variance of a probe position over the workspace, one row from \
             each of {} strata of look-alike candidates, each discounted by its leverage \
             (robust, τ = {:.2})",
            plan.strata, plan.hedge
        ),
        Criterion::Robust => format!(
            "the mean predicted variance of a probe position over the workspace, one row from \
             each of {} strata of look-alike candidates (robust)",
            plan.strata
        ),
        Criterion::Prediction => {
            "the mean predicted variance of a probe position over the workspace (I-optimal)"
                .to_string()
        }
        Criterion::Determinant => {
            "the determinant of the information (D-optimal, for comparison)".to_string()
        }
    }
}

/// The plan's first lines: the pool, what was optimised, the noise.
fn header(plan: &Plan, context: SummaryContext<'_>) -> String {
    let what = match plan.measure {
        Measure::Positions => "positions",
        Measure::Touches => "touches",
        Measure::Spheres => "sphere points",
    };
    let mut t = format!(
        "Plan: {} of {} candidate {what}, {}\n",
        plan.count, plan.candidates, context.pool.origin
    );
    if let Some(g) = context.given {
        t += &format!(
            "Adding to the calibration in {} (its covariance the start; σ̂₀ {:.2})\n",
            g.dir, g.sigma0
        );
    }
    let workspace = format!(
        "{}{}",
        context.workspace.unwrap_or("the candidates"),
        workspace_used(plan)
    );
    let frame = (plan.parameters.iter())
        .filter(|p| p.starts_with("frame "))
        .count();
    let spheres = (plan.parameters.iter())
        .filter(|p| p.starts_with("sphere."))
        .count();
    let geometry = plan.parameters.len() - frame - spheres;
    let frame = if frame > 0 {
        format!(" and the instrument frame's {frame}")
    } else if spheres > 0 {
        format!(" and the spheres' own {spheres}")
    } else {
        String::new()
    };
    let given = context.given.is_some();
    let row = match plan.measure {
        Measure::Spheres => "of a point along its sphere's normal",
        _ => "per coordinate of a row",
    };
    t += &format!(
        "Optimised: {}\n  workspace: {workspace}; parameters: {geometry} of the \
         geometry{frame}; noise σ {} mm {row}{}\n",
        criterion_text(plan),
        if given {
            format!("{:.4}", plan.sigma_mm)
        } else {
            short(plan.sigma_mm)
        },
        if given { " (the calibration's)" } else { "" }
    );
    t
}

/// The predicted radius with the chosen rows, all candidates, and random
/// subsets of the same size.
fn spreads(plan: &Plan) -> String {
    let row = |name: &str, s: Option<Spread>| match s {
        Some(s) => format!("  {name:<30} {:>9.4} {:>9.4}\n", s.rms_mm, s.max_mm),
        None => format!("  {name:<30}  not determined\n"),
    };
    let r = &plan.random;
    let mut t = format!(
        "Predicted 95 % radius of a probe position over the workspace (mm; {K_ISOTROPIC:.2} σ \
         for an isotropic error):\n  {:<30} {:>9} {:>9}\n",
        "", "RMS", "max"
    );
    if plan.given {
        t += &row("the calibration alone", plan.start);
        t += &row(&format!("with the {} chosen", plan.count), plan.planned);
        t += &row(
            &format!("with all {} candidates", plan.candidates),
            plan.all,
        );
    } else {
        t += &row(&format!("the {} chosen", plan.count), plan.planned);
        t += &row(&format!("all {} candidates", plan.candidates), plan.all);
    }
    t += &row(
        &format!("{} at random (median of {})", plan.count, r.sets),
        r.median,
    );
    if r.determined < r.sets {
        t += &format!(
            "  ({} of the {} random subsets determine every parameter)\n",
            r.determined, r.sets
        );
    }
    t
}

/// The curve, rows → RMS radius, with the chosen count and the knee marked.
fn curve(plan: &Plan) -> String {
    let to = plan.curve.last().map_or(plan.count, |c| c.rows);
    let knee = knee(&plan.curve);
    let mut t = format!("RMS radius as rows are added (the greedy continued to {to}):\n");
    for c in &plan.curve {
        let value = c
            .rms_mm
            .map_or("not determined".to_string(), |r| format!("{r:.4} mm"));
        let mut marks = Vec::new();
        if c.rows == plan.count {
            marks.push("chosen");
        }
        if matches!(knee, Knee::At { rows, .. } if rows == c.rows) {
            marks.push("more stops paying");
        }
        let marks = if marks.is_empty() {
            String::new()
        } else {
            format!("  ← {}", marks.join(", "))
        };
        t += &format!("  {:>6}  {value}{marks}\n", c.rows);
    }
    t += &match knee {
        Knee::At { rows, gain } => format!(
            "  From {rows} rows, twice as many lower the RMS radius by {:.0} % only (< {:.0} %).\n",
            100.0 * gain,
            100.0 * KNEE
        ),
        Knee::Beyond { rows, gain } => format!(
            "  Twice {rows} rows still lower the RMS radius by {:.0} %: more rows still pay.\n",
            100.0 * gain
        ),
        Knee::Unknown => String::new(),
    };
    t
}

/// The chosen rows in the order chosen: row of the pool (from 1), label,
/// line of the candidates file, and the criterion after each.
fn ranking(plan: &Plan, pool: &Pool, next: bool) -> String {
    let mut t = if next {
        format!("Measure these {} next, in this order", plan.count)
    } else {
        "Chosen, in order".to_string()
    };
    t += " (after each, the mean predicted variance over the workspace as an RMS radius, mm; \
          — until every parameter is determined):\n";
    let width = (plan.steps.iter().map(|s| s.label.len()))
        .max()
        .unwrap_or(0)
        .max(5);
    let line = |l: &str| {
        if pool.from_file {
            format!("  {l:>5}")
        } else {
            String::new()
        }
    };
    t += &format!(
        "  {:>4}  {:>5}  {:<width$}{}  criterion\n",
        "#",
        "row",
        "label",
        line("line")
    );
    for (rank, step) in plan.steps[..plan.count].iter().enumerate() {
        let criterion = (step.criterion_mm).map_or("—".to_string(), |c| format!("{c:.4}"));
        t += &format!(
            "  {:>4}  {:>5}  {:<width$}{}  {criterion}\n",
            rank + 1,
            step.row + 1,
            step.label,
            line(&pool.poses.line(step.row).to_string())
        );
    }
    t
}

/// How much of the workspace the criterion used: all of it, or an even
/// sample, with why and how to use more (the command line's flag: the
/// summary is the command's text).
fn workspace_used(plan: &Plan) -> String {
    if plan.workspace_poses >= plan.workspace_total {
        return format!(" ({} poses)", plan.workspace_poses);
    }
    format!(
        ", an even sample of {} of its {} poses (each workspace pose adds to every step's \
         work; --workspace-poses N uses up to N)",
        plan.workspace_poses, plan.workspace_total
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(points: &[(usize, Option<f64>)]) -> Vec<CurvePoint> {
        points
            .iter()
            .map(|&(rows, rms_mm)| CurvePoint { rows, rms_mm })
            .collect()
    }

    #[test]
    fn the_knee_is_the_first_doubling_that_gains_under_ten_percent() {
        let c = curve(&[
            (5, None),
            (10, Some(1.0)),
            (15, Some(0.7)),
            (20, Some(0.6)),
            (30, Some(0.57)),
            (40, Some(0.55)),
        ]);
        // 10 → 20: 40 %; 15 → 30: 18.6 %; 20 → 40: 8.3 %.
        match knee(&c) {
            Knee::At { rows, gain } => {
                assert_eq!(rows, 20);
                assert!((gain - (1.0 - 0.55 / 0.6)).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        // Interpolated: 10 → 20 between 15 and 30.
        let c = curve(&[(10, Some(1.0)), (15, Some(0.8)), (30, Some(0.5))]);
        match knee(&c) {
            Knee::Beyond { rows, gain } => {
                assert_eq!(rows, 15);
                assert!((gain - 0.375).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(knee(&curve(&[(5, None), (10, Some(1.0))])), Knee::Unknown);
    }
}
