//! A reference length between two labelled points. Its file is
//! [`crate::io::lengths`].

/// One reference length between two labelled points.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceLength {
    /// Label of the first point.
    pub a: String,
    /// Label of the second point (different from `a`).
    pub b: String,
    /// Distance, mm, `> 0`.
    pub distance: f64,
    /// Standard uncertainty of the distance, mm, `>= 0`, if stated.
    pub uncertainty: Option<f64>,
    /// 1-based line in the source file, for messages; 0 for a length made
    /// in memory ([`ReferenceLength::new`]): messages then name the source
    /// alone.
    pub line: usize,
}

impl ReferenceLength {
    /// A length made in memory, from no file's line: between the points
    /// labelled `a` and `b`, `distance_mm` apart, with the standard
    /// uncertainty `uncertainty_mm` if stated. A data set checks the
    /// values when it takes them, as a file's reader does
    /// ([`crate::DataSet::with_lengths`], [`crate::DataSet::from_touches`]).
    ///
    /// ```
    /// use aacmm_core::domain::ReferenceLength;
    /// let l = ReferenceLength::new("S1", "S2", 500.0, Some(0.002));
    /// assert_eq!((l.distance, l.line), (500.0, 0));
    /// ```
    pub fn new(
        a: impl Into<String>,
        b: impl Into<String>,
        distance_mm: f64,
        uncertainty_mm: Option<f64>,
    ) -> ReferenceLength {
        ReferenceLength {
            a: a.into(),
            b: b.into(),
            distance: distance_mm,
            uncertainty: uncertainty_mm,
            line: 0,
        }
    }
}
