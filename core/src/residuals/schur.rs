//! The Schur complement of the normal equations: the geometry's equations
//! with every auxiliary column (a frame of reference positions) fitted and
//! eliminated, `N_gg − N_ga N_aa⁻¹ N_ag` — what the identifiability of the
//! geometry is judged on, by the calibration's fixed set and by
//! `identify` alike.

use super::{Layout, Normal};

/// Why the auxiliary columns could not be eliminated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum Elimination {
    /// The layout and the normal equations disagree (a bug, not input).
    #[error("internal: parameter vector of the wrong length")]
    Shape,
    /// The data do not determine the auxiliary blocks named (their normal
    /// equations are singular).
    #[error("the auxiliary blocks ({0}): the data do not determine them")]
    Undetermined(String),
}

impl Normal {
    /// The geometry's normal equations with every auxiliary column fitted
    /// and eliminated (the module's Schur complement), owned: the analysis
    /// consumes it. The corrections beyond geometry are left out (they are
    /// judged after the geometry). Without auxiliary columns, a copy.
    ///
    /// # Errors
    ///
    /// [`Elimination::Undetermined`] when the auxiliary columns' own
    /// equations are singular; [`Elimination::Shape`] when `layout` is not
    /// these equations'.
    pub(crate) fn geometry_only(&self, layout: &Layout) -> Result<Normal, Elimination> {
        let corrections = layout.corrections().map_or(0..0, |(_, c)| c);
        let keep: Vec<usize> = (0..layout.len())
            .filter(|c| !corrections.contains(c))
            .collect();
        let restricted;
        let full = if corrections.is_empty() {
            self
        } else {
            restricted = self.restrict(&keep).ok_or(Elimination::Shape)?;
            &restricted
        };
        let (g, all) = (layout.geometry_columns(), keep.len());
        if g == all {
            return Ok(full.clone());
        }
        let nm = nalgebra::DMatrix::from_row_slice(all, all, &full.jtj);
        // Equilibrated (unit diagonal): a frame's rotation columns are the
        // reach times its translation's, and the elimination's precision is
        // the condition of what it factors.
        let scale = nalgebra::DVector::from_fn(all - g, |i, _| {
            let v = nm[(g + i, g + i)];
            if v > 0.0 && v.is_finite() {
                1.0 / v.sqrt()
            } else {
                1.0
            }
        });
        let d = nalgebra::DMatrix::from_diagonal(&scale);
        let naa = &d * nm.view((g, g), (all - g, all - g)) * &d;
        let nga = nm.view((0, g), (g, all - g)) * &d;
        let Some(ch) = naa.cholesky() else {
            let blocks: Vec<&str> = layout.blocks().map(|b| b.name()).collect();
            return Err(Elimination::Undetermined(blocks.join(", ")));
        };
        let reduced = nm.view((0, 0), (g, g)) - &nga * ch.solve(&nga.transpose());
        let geometry: Vec<usize> = (0..g).collect();
        let mut out = full.restrict(&geometry).ok_or(Elimination::Shape)?;
        out.jtj = reduced.transpose().as_slice().to_vec();
        Ok(out)
    }
}
