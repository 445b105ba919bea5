//! The cost over a grid on the zero offsets' circles, and its lowest cells.

use super::*;

/// The cost on a grid of `K` angles per circle (everything else at the
/// start); returns `K` and the lowest `candidates` grid cells that are
/// local minima among their `2·circles` neighbours, lowest first.
pub(super) fn torus_grid(
    start: &DhParams,
    circles: &[usize],
    problem: &GlobalProblem<'_, '_>,
    options: &GlobalOptions,
) -> Result<(usize, Vec<DhParams>), CalibrationError> {
    let joints = start.joint_count();
    let c = circles.len() as u32;
    let mut k = 4usize;
    while (k + 1)
        .checked_pow(c)
        .is_some_and(|n| n <= options.grid_cells)
    {
        k += 1;
    }
    let cells = k.pow(c);
    let ids: Vec<ParamId> = circles
        .iter()
        .map(|&col| ParamId::from_column(joints, col).ok_or(CalibrationError::Shape))
        .collect::<Result<_, _>>()?;
    // Cell index = Σ digit_axis · k^axis; digit i is the angle −π + 2πi/k.
    let strides: Vec<usize> = (0..c).map(|axis| k.pow(axis)).collect();
    let digit = |cell: usize, stride: usize| cell / stride % k;
    let angle = |cell: usize, stride: usize| {
        let i = digit(cell, stride);
        crate::params::wrap(std::f64::consts::TAU * i as f64 / k as f64 - std::f64::consts::PI)
    };
    let place = |x: &mut DhParams, cell: usize| {
        for (id, &stride) in ids.iter().zip(&strides) {
            *x.get_mut(*id) = angle(cell, stride);
        }
    };
    // Chunks of 64 cells on the objective's threads: a cell's cost depends
    // on that cell alone, so the same costs on any count. A cancellation is
    // seen within a chunk's costs.
    const CELLS: usize = 64;
    let chunks: Vec<usize> = (0..cells.div_ceil(CELLS)).collect();
    let threads = problem.objective.threads();
    let parts = crate::parallel::parallel_map(&chunks, threads, |&chunk| {
        crate::calibrate::Cancel::check(problem.cancel.as_ref())?;
        // The start's point, its circles' columns set cell by cell (the
        // point of the arm `place` makes, without building it each time).
        let (mut x, mut xyz) = (problem.point(start), Vec::new());
        (chunk * CELLS..((chunk + 1) * CELLS).min(cells))
            .map(|cell| {
                for (&column, &stride) in circles.iter().zip(&strides) {
                    x[column] = angle(cell, stride);
                }
                // The data's cost (the prior does not steer the scan);
                // never NaN: a non-finite cost is +∞.
                Ok(problem.objective.data_cost(&x, &mut xyz)?)
            })
            .collect::<Result<Vec<f64>, CalibrationError>>()
    });
    let mut costs = Vec::with_capacity(cells);
    for part in parts {
        costs.extend(part?);
    }
    let mut minima: Vec<usize> = (0..cells)
        .filter(|&cell| {
            strides.iter().all(|&stride| {
                let d = digit(cell, stride);
                [1, k - 1].iter().all(|&step| {
                    let other = cell - d * stride + (d + step) % k * stride;
                    costs[cell] <= costs[other]
                })
            })
        })
        .collect();
    minima.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]).then(a.cmp(&b)));
    minima.truncate(options.candidates);
    Ok((
        k,
        minima
            .into_iter()
            .map(|cell| {
                let mut x = start.clone();
                place(&mut x, cell);
                x
            })
            .collect(),
    ))
}
