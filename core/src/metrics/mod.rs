//! Evaluation metrics: the paper's figures (method.md §3, §7) and the arm
//! standards' figures (standards.md), as pure functions with a typed,
//! serialisable report.
//!
//! Input is a list of measured probe centres in row order, each labelled with
//! the physical point (cone socket) it touches, plus optional reference
//! lengths between points. All lengths are mm. Rows are grouped by label in the
//! order labels first appear, so every list in the report has a deterministic
//! order; "touch k" of a point is its k-th row in input order.
//!
//! # Per point (socket) — [`point_stats`]
//!
//! With touches `x_1..x_n` (n ≥ [`MIN_TOUCHES`]), centroid `x̄ = (1/n) Σ x_i`
//! and `δ_i = |x_i − x̄|`:
//!
//! | figure | formula | source |
//! |---|---|---|
//! | `e` | `(1/n) Σ δ_i` | paper eq. 9–10 |
//! | `σ` | `sqrt((1/n) Σ (δ_i − e)²)` (population) | paper eq. 11 |
//! | `OA` | `e + 3σ` | paper eq. 12 (the calibration objective) |
//! | `δ_max` | `max δ_i` | ASME B89.4.22 single-point articulation test (SPAT) |
//! | `2s` | `2·sqrt(Σ δ_i² / (n − 1))` | SPAT (unverified whether vendors quote `δ_max` or `2s`) |
//! | half-range | `(max − min)/2` of X, Y and Z separately | FARO's SPAT routine |
//!
//! Across points, [`Summary`] gives min, mean, max and population standard
//! deviation of `e` (the paper's Fig. 6 numbers, §7), of `δ_max` and of `2s`.
//!
//! # Per pair of points — [`pair_length_error`]
//!
//! The paper's length error (eq. 19) for points `i < j` (first-appearance
//! order), over the common touch count `n = min(n_i, n_j)`:
//!
//! ```text
//! d_error = (1/n) Σ_{k=1..n} ( |x_ik − x_jk| − |x̄_i − x̄_j| )
//! ```
//!
//! where the centroids use all touches of each point; `d_error_abs` is the
//! same with absolute values inside the sum — our reading of the paper's
//! reported figures, since the printed formula is of second order in the
//! scatter (see [`pair_length_error`]). **Eq. 19 uses no
//! reference length** (method.md §8.4): it compares touch-by-touch distances
//! with the distance between centroids, so it measures repeatability again,
//! not scale. A uniformly shrunk arm scores as well as a correct one. With
//! equal touch counts it is never negative (the mean of distances is at least
//! the distance of the means); with unequal counts it can be. Summary over all
//! pairs: the paper's Fig. 7 numbers.
//!
//! # Per reference length — [`reference_error`]
//!
//! For a calibrated distance `L` between points `a` and `b` (ball bar, cone
//! plate, step gauge): `error = |x̄_a − x̄_b| − L`, as in ISO 10360-12 `E_Uni`
//! (`E = L_meas − L_cal`). Summary ([`ReferenceSummary`]): min, mean, max,
//! population std, `max |error|`, `RMS = sqrt((1/m) Σ error²)` and `2·RMS` —
//! the ASME B89.4.22 volumetric-test figures (unverified which the standard
//! quotes). This is the only figure here that measures scale.
//!
//! # Example
//!
//! ```
//! use aacmm_core::metrics::{evaluate, ReferenceDistance};
//!
//! // Socket "p" touched at the four corners of a square of side 2 around
//! // (0, 0, 0); socket "q" four times at exactly (100.01, 0, 0).
//! let labels = ["p", "p", "p", "p", "q", "q", "q", "q"];
//! let points = [
//!     [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0],
//!     [100.01, 0.0, 0.0], [100.01, 0.0, 0.0], [100.01, 0.0, 0.0], [100.01, 0.0, 0.0],
//! ];
//! let bar = ReferenceDistance { a: "p".into(), b: "q".into(), distance: 100.0 };
//! let ev = evaluate(&labels, &points, &[bar]).unwrap();
//!
//! assert_eq!(ev.points[0].label, "p");
//! assert!((ev.points[0].e - 2f64.sqrt()).abs() < 1e-12); // δ = √2 for every corner
//! assert_eq!(ev.points[1].e, 0.0);
//! assert!((ev.single_point_e.mean - 2f64.sqrt() / 2.0).abs() < 1e-12);
//! assert!((ev.reference[0].error - 0.01).abs() < 1e-9);
//! println!("{}", ev.to_table());
//! ```

mod length;
mod point;
mod table;

pub use length::{
    PairLengthError, ReferenceDistance, ReferenceError, ReferenceSummary, pair_length_error,
    reference_error,
};
pub use point::{PointStats, point_stats};

pub(crate) use crate::geometry::{centroid, distance};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Fewest touches a point needs: `2s` divides by `n − 1`, and fewer than three
/// touches say next to nothing about articulation error.
pub const MIN_TOUCHES: usize = 3;

/// Why the metrics could not be computed. Every variant names what the caller
/// needs to point the user at the offending input (label, row).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MetricsError {
    /// No measured points at all.
    #[error("no measured points")]
    Empty,
    /// `labels` and `points` differ in length.
    #[error("{labels} labels but {points} points")]
    LengthMismatch {
        /// Number of labels given.
        labels: usize,
        /// Number of points given.
        points: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("point `{label}`, row {row}: coordinate is not a finite number")]
    NonFinite {
        /// Label of the offending row.
        label: String,
        /// 0-based index into the point slice passed to the reporting function
        /// (for [`evaluate`], the input row).
        row: usize,
    },
    /// A point has fewer than [`MIN_TOUCHES`] touches.
    #[error("point `{label}` has {touches} touch(es); at least {MIN_TOUCHES} are needed")]
    TooFewTouches {
        /// The point's label.
        label: String,
        /// How many touches it has.
        touches: usize,
    },
    /// A reference length names a point that was not measured.
    #[error("reference length names point `{label}`, which was not measured")]
    UnknownLabel {
        /// The unknown label.
        label: String,
    },
    /// A reference length joins a point to itself, or its distance is not a
    /// finite positive number.
    #[error(
        "reference length `{a}`–`{b}` = {distance} mm: needs two different points \
         and a finite positive distance"
    )]
    InvalidReference {
        /// First point's label.
        a: String,
        /// Second point's label.
        b: String,
        /// The distance given, mm.
        distance: f64,
    },
}

/// Min, mean, max and population standard deviation of a list of values
/// (`std = sqrt((1/m) Σ (v − mean)²)`). The one summary used everywhere in
/// this module, including for the per-point `e`, `σ` and `δ_max`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Number of values summarised.
    pub count: usize,
    /// Smallest value.
    pub min: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Largest value.
    pub max: f64,
    /// Population standard deviation (divides by the count, not count − 1).
    pub std: f64,
}

impl Summary {
    /// Summarises `values`; `None` when there are none.
    ///
    /// ```
    /// use aacmm_core::metrics::Summary;
    /// // mean 2.5; squared deviations 2.25 + 0.25 + 0.25 + 2.25 = 5; 5/4 = 1.25
    /// let s = Summary::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
    /// assert_eq!((s.count, s.min, s.mean, s.max), (4, 1.0, 2.5, 4.0));
    /// assert!((s.std - 1.25f64.sqrt()).abs() < 1e-15);
    /// assert_eq!(Summary::of(&[]), None);
    /// ```
    pub fn of(values: &[f64]) -> Option<Summary> {
        let count = values.len();
        if count == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / count as f64;
        let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / count as f64;
        Some(Summary {
            count,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            mean,
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            std: variance.sqrt(),
        })
    }
}

/// Everything [`evaluate`] computes; lists are in first-appearance order of
/// the labels (pairs `i < j` in that order, references in input order).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// Per-point figures (paper eq. 9–12, SPAT).
    pub points: Vec<PointStats>,
    /// `e` across points: the paper's single-point repeatability (Fig. 6).
    pub single_point_e: Summary,
    /// `δ_max` across points (SPAT).
    pub single_point_delta_max: Summary,
    /// `2s` across points (SPAT, unverified which figure vendors quote).
    pub single_point_two_s: Summary,
    /// The paper's length error (eq. 19) for every pair of points.
    pub pair_length: Vec<PairLengthError>,
    /// `d_error` across pairs (Fig. 7); `None` with a single point.
    pub pair_length_summary: Option<Summary>,
    /// `d_error_abs` across pairs; `None` with a single point.
    pub pair_length_abs_summary: Option<Summary>,
    /// Error against every given reference length.
    pub reference: Vec<ReferenceError>,
    /// Summary of the reference errors; `None` when none were given.
    pub reference_summary: Option<ReferenceSummary>,
}

/// Computes every metric of the module for labelled points and optional
/// reference lengths (see the module documentation for the formulas).
///
/// `labels[r]` names the physical point measured in row `r` of `points`.
///
/// # Errors
///
/// [`MetricsError::LengthMismatch`], [`MetricsError::Empty`],
/// [`MetricsError::NonFinite`] (with the input row),
/// [`MetricsError::TooFewTouches`] (the first such point),
/// [`MetricsError::UnknownLabel`] and [`MetricsError::InvalidReference`].
///
/// ```
/// use aacmm_core::metrics::{evaluate, MetricsError};
/// // Socket "a" at x = 0, 0, 0, 4 (centroid 1, δ = 1, 1, 1, 3);
/// // socket "b" three times at (10, 0, 0).
/// let labels = ["a", "b", "a", "b", "a", "b", "a"];
/// let x = |v: f64| [v, 0.0, 0.0];
/// let points = [x(0.0), x(10.0), x(0.0), x(10.0), x(0.0), x(10.0), x(4.0)];
/// let ev = evaluate(&labels, &points, &[]).unwrap();
/// assert_eq!(ev.points[0].e, 1.5); // (1 + 1 + 1 + 3) / 4
/// assert_eq!(ev.points[0].delta_max, 3.0);
/// assert_eq!(ev.points[0].two_s, 4.0); // 2·sqrt((1 + 1 + 1 + 9) / 3)
/// // eq. 19 pairs the first three touches: distances 10, 10, 10 vs 9 between centroids.
/// assert_eq!(ev.pair_length[0].pairs, 3);
/// assert_eq!(ev.pair_length[0].d_error, 1.0);
/// assert_eq!(ev.reference_summary, None);
///
/// let err = evaluate(&["a", "a"], &[x(0.0), x(1.0)], &[]).unwrap_err();
/// assert_eq!(err, MetricsError::TooFewTouches { label: "a".into(), touches: 2 });
/// ```
pub fn evaluate<S: AsRef<str>>(
    labels: &[S],
    points: &[[f64; 3]],
    references: &[ReferenceDistance],
) -> Result<Evaluation, MetricsError> {
    check_rows(labels, points)?;
    let groups = group_by_label(labels, points);
    let stats = groups
        .iter()
        .map(|(label, touches)| point_stats(label, touches))
        .collect::<Result<Vec<_>, _>>()?;
    let pair_length = all_pairs(&groups)?;
    let reference = references
        .iter()
        .map(|r| reference_error(r, &stats))
        .collect::<Result<Vec<_>, _>>()?;
    let across_points = |figure: fn(&PointStats) -> f64| {
        let values: Vec<f64> = stats.iter().map(figure).collect();
        Summary::of(&values).expect("check_rows rejects empty input")
    };
    Ok(Evaluation {
        single_point_e: across_points(|p| p.e),
        single_point_delta_max: across_points(|p| p.delta_max),
        single_point_two_s: across_points(|p| p.two_s),
        pair_length_summary: Summary::of(
            &pair_length.iter().map(|p| p.d_error).collect::<Vec<_>>(),
        ),
        pair_length_abs_summary: Summary::of(
            &pair_length
                .iter()
                .map(|p| p.d_error_abs)
                .collect::<Vec<_>>(),
        ),
        reference_summary: ReferenceSummary::of(
            &reference.iter().map(|r| r.error).collect::<Vec<_>>(),
        ),
        points: stats,
        pair_length,
        reference,
    })
}

/// Rejects mismatched lengths, empty input and non-finite coordinates.
fn check_rows<S: AsRef<str>>(labels: &[S], points: &[[f64; 3]]) -> Result<(), MetricsError> {
    if labels.len() != points.len() {
        return Err(MetricsError::LengthMismatch {
            labels: labels.len(),
            points: points.len(),
        });
    }
    if points.is_empty() {
        return Err(MetricsError::Empty);
    }
    check_finite(labels.iter().map(AsRef::as_ref).zip(points))
}

/// The first row (0-based, in iteration order) with a non-finite coordinate.
fn check_finite<'a>(
    rows: impl Iterator<Item = (&'a str, &'a [f64; 3])>,
) -> Result<(), MetricsError> {
    for (row, (label, p)) in rows.enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(MetricsError::NonFinite {
                label: label.to_owned(),
                row,
            });
        }
    }
    Ok(())
}

/// Checks what every per-point function needs: enough, finite touches.
fn check_touches(label: &str, touches: &[[f64; 3]]) -> Result<(), MetricsError> {
    if touches.len() < MIN_TOUCHES {
        return Err(MetricsError::TooFewTouches {
            label: label.to_owned(),
            touches: touches.len(),
        });
    }
    check_finite(touches.iter().map(|p| (label, p)))
}

/// Rows grouped by label, labels in order of first appearance, touches in row
/// order.
fn group_by_label<'a, S: AsRef<str>>(
    labels: &'a [S],
    points: &[[f64; 3]],
) -> Vec<(&'a str, Vec<[f64; 3]>)> {
    let mut index: HashMap<&str, usize> = HashMap::new();
    let mut groups: Vec<(&str, Vec<[f64; 3]>)> = Vec::new();
    for (label, p) in labels.iter().map(AsRef::as_ref).zip(points) {
        let i = *index.entry(label).or_insert_with(|| {
            groups.push((label, Vec::new()));
            groups.len() - 1
        });
        groups[i].1.push(*p);
    }
    groups
}

/// Eq. 19 for every pair `i < j` of groups.
fn all_pairs(groups: &[(&str, Vec<[f64; 3]>)]) -> Result<Vec<PairLengthError>, MetricsError> {
    let mut pairs = Vec::new();
    for (i, (a, touches_a)) in groups.iter().enumerate() {
        for (b, touches_b) in &groups[i + 1..] {
            pairs.push(pair_length_error(a, touches_a, b, touches_b)?);
        }
    }
    Ok(pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn x(v: f64) -> [f64; 3] {
        [v, 0.0, 0.0]
    }

    #[test]
    fn summary_of_one_value_has_zero_spread() {
        let s = Summary::of(&[-0.5]).unwrap();
        assert_eq!(
            (s.count, s.min, s.mean, s.max, s.std),
            (1, -0.5, -0.5, -0.5, 0.0)
        );
    }

    #[test]
    fn summary_of_signed_values() {
        // [-3, 1]: mean -1, deviations ∓2, variance (4 + 4)/2 = 4, std 2
        let s = Summary::of(&[-3.0, 1.0]).unwrap();
        assert_eq!((s.min, s.mean, s.max, s.std), (-3.0, -1.0, 1.0, 2.0));
    }

    #[test]
    fn groups_keep_first_appearance_order() {
        let labels = ["b", "a", "b", "c", "a", "b"];
        let points: Vec<[f64; 3]> = (0..6).map(|r| x(r as f64)).collect();
        let groups = group_by_label(&labels, &points);
        let order: Vec<&str> = groups.iter().map(|g| g.0).collect();
        assert_eq!(order, ["b", "a", "c"]);
        assert_eq!(groups[0].1, [x(0.0), x(2.0), x(5.0)]);
        assert_eq!(groups[1].1, [x(1.0), x(4.0)]);
    }

    #[test]
    fn evaluation_order_is_deterministic() {
        let labels: Vec<String> = ["s3", "s1", "s2"]
            .iter()
            .cycle()
            .take(9)
            .map(|s| s.to_string())
            .collect();
        let points: Vec<[f64; 3]> = (0..9).map(|r| [r as f64, (r * r) as f64, 1.0]).collect();
        let first = evaluate(&labels, &points, &[]).unwrap();
        for _ in 0..5 {
            assert_eq!(evaluate(&labels, &points, &[]).unwrap(), first);
        }
        let names: Vec<&str> = first.points.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(names, ["s3", "s1", "s2"]);
        let pairs: Vec<(&str, &str)> = first
            .pair_length
            .iter()
            .map(|p| (p.a.as_str(), p.b.as_str()))
            .collect();
        assert_eq!(pairs, [("s3", "s1"), ("s3", "s2"), ("s1", "s2")]);
    }

    #[test]
    fn summaries_across_points() {
        // "p": x = 0, 0, 0, 4 → e 1.5, δ_max 3, 2s 4 (see point::tests)
        // "q": x = 10, 10, 10   → e 0,   δ_max 0, 2s 0
        let labels = ["p", "p", "p", "p", "q", "q", "q"];
        let points = [x(0.0), x(0.0), x(0.0), x(4.0), x(10.0), x(10.0), x(10.0)];
        let ev = evaluate(&labels, &points, &[]).unwrap();
        let e = ev.single_point_e;
        // e: [1.5, 0] → mean 0.75, std 0.75
        assert_eq!(
            (e.count, e.min, e.mean, e.max, e.std),
            (2, 0.0, 0.75, 1.5, 0.75)
        );
        assert_eq!(ev.single_point_delta_max.max, 3.0);
        assert_eq!(ev.single_point_two_s.mean, 2.0);
        // one pair: centroids 1 and 10 → 9; touch distances 10, 10, 10 → d_error 1
        let pair = ev.pair_length_summary.unwrap();
        assert_eq!((pair.count, pair.mean, pair.std), (1, 1.0, 0.0));
    }

    #[test]
    fn single_point_has_no_pairs_and_no_reference_summary() {
        let ev = evaluate(&["p"; 3], &[x(0.0), x(1.0), x(2.0)], &[]).unwrap();
        assert!(ev.pair_length.is_empty());
        assert_eq!(ev.pair_length_summary, None);
        assert_eq!(ev.reference_summary, None);
    }

    #[test]
    fn accepts_owned_labels() {
        let labels = vec!["p".to_string(); 3];
        assert!(evaluate(&labels, &[x(0.0); 3], &[]).is_ok());
    }

    #[test]
    fn empty_input_is_an_error() {
        let none: [&str; 0] = [];
        assert_eq!(evaluate(&none, &[], &[]), Err(MetricsError::Empty));
    }

    #[test]
    fn mismatched_lengths_are_an_error() {
        assert_eq!(
            evaluate(&["p", "p"], &[x(0.0); 3], &[]),
            Err(MetricsError::LengthMismatch {
                labels: 2,
                points: 3
            })
        );
    }

    #[test]
    fn first_point_with_too_few_touches_is_named() {
        // "q" (1 touch) appears before "r" (2 touches); "p" has enough.
        let labels = ["p", "q", "p", "r", "p", "r"];
        let err = evaluate(&labels, &[x(0.0); 6], &[]).unwrap_err();
        assert_eq!(
            err,
            MetricsError::TooFewTouches {
                label: "q".into(),
                touches: 1
            }
        );
        assert!(err.to_string().contains("`q` has 1 touch"));
    }

    #[test]
    fn non_finite_coordinate_names_the_input_row() {
        let labels = ["p", "q", "p", "q", "p", "q"];
        let mut points = [x(0.0); 6];
        points[3][1] = f64::NAN;
        assert_eq!(
            evaluate(&labels, &points, &[]),
            Err(MetricsError::NonFinite {
                label: "q".into(),
                row: 3
            })
        );
    }

    #[test]
    fn unknown_reference_label_is_an_error() {
        let bar = ReferenceDistance {
            a: "p".into(),
            b: "nowhere".into(),
            distance: 1.0,
        };
        let err = evaluate(&["p"; 3], &[x(0.0); 3], &[bar]).unwrap_err();
        assert_eq!(
            err,
            MetricsError::UnknownLabel {
                label: "nowhere".into()
            }
        );
        assert!(err.to_string().contains("`nowhere`"));
    }

    #[test]
    fn report_round_trips_through_json() {
        // serde_json's default float parser may be off by one ulp, so compare
        // with a tolerance rather than exactly.
        let labels = ["p", "q", "p", "q", "p", "q"];
        let points = [x(0.0), x(10.0), x(0.1), x(10.0), x(0.2), x(10.1)];
        let bar = ReferenceDistance {
            a: "q".into(),
            b: "p".into(),
            distance: 9.9,
        };
        let ev = evaluate(&labels, &points, &[bar]).unwrap();
        let back: Evaluation = serde_json::from_str(&serde_json::to_string(&ev).unwrap()).unwrap();
        let (ev, back) = (
            serde_json::to_value(&ev).unwrap(),
            serde_json::to_value(&back).unwrap(),
        );
        assert!(json_close(&ev, &back), "{ev}\n{back}");
    }

    fn json_close(a: &serde_json::Value, b: &serde_json::Value) -> bool {
        use serde_json::Value::{Array, Number, Object};
        match (a, b) {
            (Number(a), Number(b)) => (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() < 1e-12,
            (Array(a), Array(b)) => {
                a.len() == b.len() && a.iter().zip(b).all(|(a, b)| json_close(a, b))
            }
            (Object(a), Object(b)) => {
                a.len() == b.len()
                    && a.iter()
                        .all(|(k, v)| b.get(k).is_some_and(|w| json_close(v, w)))
            }
            _ => a == b,
        }
    }
}
