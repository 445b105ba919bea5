//! Where a data set's touches were read: each touch's row of the poses
//! file and the line of each row, kept in runs. A file's rows follow on
//! from line to line except after a comment or a blank line, and a
//! logger's or the simulator's file holds each point's rows together, so
//! at a million touches a few runs replace 8 MB of a row and a line per
//! touch (part of holding a large calibration within 1.8 times its file).
//! A file whose points interleave keeps a row per touch, as before.

/// Per touch (data-set order) its row of the poses file, 0-based, and the
/// line of that row, 1-based.
#[derive(Clone, Debug, PartialEq, Default)]
pub(super) struct Origins {
    rows: Rows,
    /// Per run of rows on consecutive lines, its first row and that row's
    /// line, ascending in both.
    lines: Vec<(u32, u32)>,
}

/// The touches' rows.
#[derive(Clone, Debug, PartialEq)]
enum Rows {
    /// Each touch's row.
    Each(Vec<u32>),
    /// Per run of touches on consecutive rows, its first touch and that
    /// touch's row (ascending in touch), and the touches in all.
    Runs(Vec<(u32, u32)>, u32),
}

impl Default for Rows {
    fn default() -> Rows {
        Rows::Each(Vec::new())
    }
}

/// What does not fit in 32 bits: the data set names it in its refusal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TooMany {
    Touches,
    Lines,
}

impl Origins {
    /// The touches read from `rows` (per touch, its row) of a file whose
    /// row `r` is on line `line_of(r)`, for every row below `file_rows`.
    pub(super) fn new(
        rows: &[usize],
        file_rows: usize,
        line_of: impl Fn(usize) -> usize,
    ) -> Result<Origins, TooMany> {
        let narrow = |v: usize, what| u32::try_from(v).map_err(|_| what);
        let mut lines: Vec<(u32, u32)> = Vec::new();
        let mut last = None;
        for row in 0..file_rows {
            let line = narrow(line_of(row), TooMany::Lines)?;
            if last.is_none_or(|l: u32| l.checked_add(1) != Some(line)) {
                lines.push((narrow(row, TooMany::Touches)?, line));
            }
            last = Some(line);
        }
        Ok(Origins {
            rows: Rows::of(rows.iter().copied(), rows.len())?,
            lines,
        })
    }

    /// The touches of `touches` (indices into these), in that order.
    pub(super) fn subset(&self, touches: &[usize]) -> Origins {
        let rows = touches.iter().map(|&i| self.row(i));
        Origins {
            // Fewer touches than these, on rows that fit already.
            rows: Rows::of(rows, touches.len()).unwrap_or_default(),
            lines: self.lines.clone(),
        }
    }

    /// The touches.
    pub(super) fn len(&self) -> usize {
        match &self.rows {
            Rows::Each(rows) => rows.len(),
            Rows::Runs(_, touches) => *touches as usize,
        }
    }

    /// Touch `i`'s row.
    pub(super) fn row(&self, i: usize) -> usize {
        match &self.rows {
            Rows::Each(rows) => rows[i] as usize,
            Rows::Runs(runs, touches) => {
                assert!(i < *touches as usize, "touch {i} of {touches}");
                let (first, row) = runs[last_at_most(runs, i)];
                row as usize + (i - first as usize)
            }
        }
    }

    /// Touch `i`'s line; 0 (unknown) past the touches.
    pub(super) fn line(&self, i: usize) -> usize {
        if i >= self.len() || self.lines.is_empty() {
            return 0;
        }
        let row = self.row(i);
        let (first, line) = self.lines[last_at_most(&self.lines, row)];
        line as usize + (row - first as usize)
    }

    /// Every touch's row, in touch order.
    pub(super) fn rows(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.len()).map(|i| self.row(i))
    }
}

impl Rows {
    /// `count` touches' rows from `rows`: in runs when that is smaller (a
    /// run holds two numbers, a touch one).
    fn of(rows: impl Iterator<Item = usize> + Clone, count: usize) -> Result<Rows, TooMany> {
        let count = u32::try_from(count).map_err(|_| TooMany::Touches)?;
        let mut runs: Vec<(u32, u32)> = Vec::new();
        let mut last: Option<usize> = None;
        for (i, row) in rows.clone().enumerate() {
            if last.is_none_or(|l| l + 1 != row) {
                if runs.len() >= count as usize / 2 {
                    let each = rows.map(|r| u32::try_from(r).map_err(|_| TooMany::Touches));
                    return Ok(Rows::Each(each.collect::<Result<_, _>>()?));
                }
                let row = u32::try_from(row).map_err(|_| TooMany::Touches)?;
                // i < count, which fits.
                runs.push((i as u32, row));
            }
            last = Some(row);
        }
        // The last row of a run: its first plus the run's touches, all
        // fewer than `count` past it; checked, as a row past 2³² − 1 is.
        let end = runs.last().map_or(0, |&(first, row)| {
            u64::from(row) + u64::from(count) - u64::from(first) - 1
        });
        if end > u64::from(u32::MAX) {
            return Err(TooMany::Touches);
        }
        Ok(Rows::Runs(runs, count))
    }
}

/// The index of the last run whose first element is at most `at` (runs
/// ascending, the first starting at 0 or below `at`).
fn last_at_most(runs: &[(u32, u32)], at: usize) -> usize {
    runs.partition_point(|&(first, _)| first as usize <= at)
        .saturating_sub(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows and lines come back as given, in runs or not: a file in touch
    /// order with a comment part way (two runs of lines), its points
    /// interleaved (a row a touch), and a subset of each.
    #[test]
    fn rows_and_lines_are_those_given() {
        // Rows 0..6 on lines 2, 3, 4, then (a comment) 6, 7, 8.
        let line_of = |r: usize| if r < 3 { r + 2 } else { r + 3 };
        for rows in [
            vec![0, 1, 2, 3, 4, 5],
            vec![0, 3, 1, 4, 2, 5],
            vec![3, 4, 5, 0, 1],
        ] {
            let o = Origins::new(&rows, 6, line_of).unwrap();
            assert_eq!(o.len(), rows.len());
            assert_eq!(o.rows().collect::<Vec<_>>(), rows);
            for (i, &r) in rows.iter().enumerate() {
                assert_eq!((o.row(i), o.line(i)), (r, line_of(r)), "{rows:?} {i}");
            }
            assert_eq!(o.line(rows.len()), 0);
            let some = o.subset(&[4, 0, 1]);
            let want: Vec<usize> = [4, 0, 1].iter().map(|&i| rows[i]).collect();
            assert_eq!(some.rows().collect::<Vec<_>>(), want);
            assert_eq!(some.line(0), line_of(rows[4]));
        }
        let runs = |o: &Origins| match &o.rows {
            Rows::Runs(runs, _) => Some(runs.len()),
            Rows::Each(_) => None,
        };
        let in_order = Origins::new(&[0, 1, 2, 3, 4, 5], 6, line_of).unwrap();
        assert_eq!((runs(&in_order), in_order.lines.len()), (Some(1), 2));
        let interleaved = Origins::new(&[0, 3, 1, 4, 2, 5], 6, line_of).unwrap();
        assert_eq!(runs(&interleaved), None);
        assert_eq!(Origins::default().len(), 0);
        assert_eq!(Origins::default().line(0), 0);
    }

    /// A line or a row past 2³² − 1 is refused, naming which.
    #[test]
    fn what_does_not_fit_is_named() {
        let far = |_| u32::MAX as usize + 1;
        assert_eq!(Origins::new(&[0], 1, far), Err(TooMany::Lines));
        let row = u32::MAX as usize + 1;
        assert_eq!(Origins::new(&[row], 0, |r| r), Err(TooMany::Touches));
        // A run that starts in range and ends past it.
        let rows = [u32::MAX as usize - 1, u32::MAX as usize, row];
        assert_eq!(Origins::new(&rows, 0, |r| r), Err(TooMany::Touches));
    }
}
