//! Several tool points on one arm ([`crate::io::tools`]): each named tool
//! has its own offset block (`tool.NAME`, three columns `x, y, z`, mm, in
//! the last joint's frame), and a row that names it is evaluated with the
//! arm's probe replaced by that offset. The kernel's probe columns `B`
//! then hold the derivative with respect to the tool's offset
//! (`∂p/∂B = R_last`, whatever `B` is), so a tool row's `B` columns go to
//! its block, and the arm's own `B` sees only the default tool's rows. Rows
//! of the default tool keep the kernel's probe and today's code path.
//!
//! A row's orientation (a 6-D target's, `super::Mount`) belongs to the
//! body the markers are on, not to a point of it: the orientation term
//! reads it whatever tool the row names.

use std::sync::Arc;

use super::blocks::{Unit, Vector};
use super::{At, BlockId, Layout, TermError};
use crate::dataset::PositionData;
use crate::domain::block_name;
use crate::kernel::ArmKernel;
use crate::params::{DhParams, ParamId, ParamKind};

/// The rows of one tool of a positions term.
#[derive(Clone, Debug)]
pub(crate) struct ToolGroup {
    /// The rows as their own data, or `None`: every row of the term's
    /// data (no row names a tool).
    pub(crate) subset: Option<Arc<PositionData>>,
    /// Per row of `subset`, its row in the term's data.
    pub(crate) rows: Vec<usize>,
    /// The tool's offset block, or `None`: the default tool (the arm's
    /// probe columns).
    pub(crate) block: Option<BlockId>,
}

impl ToolGroup {
    /// Row `i` of the group's data as a row of the term's.
    pub(crate) fn row(&self, i: usize) -> usize {
        if self.subset.is_some() {
            self.rows[i]
        } else {
            i
        }
    }

    /// The group's data (`all`: the term's).
    pub(crate) fn data<'a>(&'a self, all: &'a PositionData) -> &'a PositionData {
        self.subset.as_deref().unwrap_or(all)
    }
}

/// The groups of `data`'s rows by tool, the default tool's first: one group
/// of every row when no row names a tool (today's path, the same sums).
///
/// # Errors
///
/// A tool without its block in `layout` (`term` names the caller).
pub(crate) fn groups(
    data: &PositionData,
    layout: &Layout,
    term: &str,
) -> Result<Vec<ToolGroup>, TermError> {
    let rows = data.rows();
    if !rows.has_tools() {
        return Ok(vec![ToolGroup {
            subset: None,
            rows: Vec::new(),
            block: None,
        }]);
    }
    let mut out = Vec::new();
    for (k, name) in rows.tools().iter().enumerate() {
        let of: Vec<usize> = (0..rows.len()).filter(|&i| rows.tool(i) == k).collect();
        if of.is_empty() {
            continue;
        }
        let block = match k {
            0 => None,
            _ => Some(layout.block_named(&block_name(name)).ok_or_else(|| {
                TermError::invalid(
                    term,
                    format!(
                        "tool {} has no block among the columns (a bug, not input)",
                        crate::error::quoted(name)
                    ),
                )
            })?),
        };
        out.push(ToolGroup {
            subset: Some(Arc::new(data.subset(&of))),
            rows: of,
            block,
        });
    }
    Ok(out)
}

/// The arm's probe columns `Bx, By, Bz` among the geometry's.
pub(crate) fn probe_columns(params: &DhParams) -> [usize; 3] {
    let n = params.joint_count();
    std::array::from_fn(|index| {
        ParamId {
            kind: ParamKind::Probe,
            index,
        }
        .column(n)
    })
}

/// `geo` (free index, arm column) for a group of tool `block`: the probe
/// columns' derivatives go to the tool's free columns instead (their free
/// index, the probe column that holds their derivative).
pub(crate) fn tool_columns(
    geo: &[(usize, usize)],
    free: &[usize],
    layout: &Layout,
    block: Option<BlockId>,
) -> Vec<(usize, usize)> {
    let Some(id) = block else {
        return geo.to_vec();
    };
    let b = probe_columns(layout.geometry());
    let mut out: Vec<(usize, usize)> = geo
        .iter()
        .copied()
        .filter(|(_, c)| !b.contains(c))
        .collect();
    let cols = layout.columns(id);
    for (a, &c) in free.iter().enumerate() {
        if cols.contains(&c) {
            out.push((a, b[c - cols.start]));
        }
    }
    out
}

/// Calls `f` with the point `at` as a group of tool `block` sees it: the
/// arm's probe replaced by the tool's offset (its kernel built for it).
///
/// # Errors
///
/// The kernel's, and `f`'s.
pub(crate) fn with_tool<R>(
    at: &At<'_>,
    block: Option<BlockId>,
    f: impl FnOnce(&At<'_>) -> Result<R, TermError>,
) -> Result<R, TermError> {
    let Some(id) = block else {
        return f(at);
    };
    let x = at.block(id);
    with_probe_at(at, [x[0], x[1], x[2]], f)
}

/// Calls `f` with the point `at` seen through a probe at `offset` (mm, the
/// last joint's frame): the arm's probe replaced, its kernel built for it.
///
/// # Errors
///
/// The kernel's, and `f`'s.
pub(crate) fn with_probe_at<R>(
    at: &At<'_>,
    offset: [f64; 3],
    f: impl FnOnce(&At<'_>) -> Result<R, TermError>,
) -> Result<R, TermError> {
    let mut arm = at.arm.clone();
    arm.probe = offset;
    let kernel = ArmKernel::new(&arm)?;
    f(&At {
        x: at.x,
        arm: &arm,
        kernel: &kernel,
        layout: at.layout,
        threads: at.threads,
    })
}

/// Adds one offset block per tool `data`'s rows name (beyond the default),
/// starting at its nominal offset.
///
/// # Errors
///
/// A tool whose offset is not known (the data were not given the arm's
/// tools: [`crate::dataset::DataSet::with_tools`]); a block of the name
/// already there.
pub(crate) fn add_tool_blocks(layout: &mut Layout, data: &PositionData) -> Result<(), TermError> {
    let rows = data.rows();
    for (k, name) in rows.tools().iter().enumerate().skip(1) {
        if !(0..rows.len()).any(|i| rows.tool(i) == k) {
            continue;
        }
        add_offset_block(layout, "positions", name, rows.tool_offset(k))?;
    }
    Ok(())
}

/// Adds tool `name`'s offset block (`tool.NAME`, three length columns)
/// starting at `start`, its nominal offset.
///
/// # Errors
///
/// No offset known (`term` names the caller); a block of the name already
/// there.
fn add_offset_block(
    layout: &mut Layout,
    term: &str,
    name: &str,
    start: Option<[f64; 3]>,
) -> Result<(), TermError> {
    let start = start.ok_or_else(|| {
        TermError::invalid(
            term,
            format!(
                "tool {}: no offset known (the arm lists no such [[tool]])",
                crate::error::quoted(name)
            ),
        )
    })?;
    let block = block_name(name);
    layout.add(Box::new(Vector {
        names: ["x", "y", "z"].map(|c| format!("{block}.{c}")).to_vec(),
        name: block,
        unit: Unit::Length,
        start: start.to_vec(),
        tolerances: vec![None; 3],
    }))?;
    Ok(())
}

/// The position of every row of `data` at `params`, each row's tool at
/// its nominal offset (the default tool at the probe): what a closed-form
/// registration of the frames starts from.
///
/// # Errors
///
/// The kernel's.
pub(crate) fn nominal_positions(
    params: &DhParams,
    data: &PositionData,
) -> Result<Vec<[f64; 3]>, crate::kernel::KernelError> {
    positions_at(params, data, &[])
}

/// The position of every row of `data` at `params`, each row's tool at
/// the offset `fitted` gives by block name (`tool.NAME`, `[x, y, z, ..]`
/// mm — a calibration's, among its frames:
/// [`crate::Calibration::frames_with_mount`]), else at its nominal offset,
/// the default tool at the probe. (A tool whose offset is not known at all
/// is evaluated at the probe: every fit refuses such data first.)
///
/// # Errors
///
/// The kernel's.
pub(crate) fn positions_at(
    params: &DhParams,
    data: &PositionData,
    fitted: &[(String, [f64; 6])],
) -> Result<Vec<[f64; 3]>, crate::kernel::KernelError> {
    let kernel = ArmKernel::new(params)?;
    let mut p = vec![[0.0; 3]; data.len()];
    kernel.positions(data.poses(), 0..data.len(), &mut p)?;
    let rows = data.rows();
    for k in 1..rows.tools().len() {
        let block = block_name(&rows.tools()[k]);
        let given = (fitted.iter().find(|(n, _)| *n == block)).map(|(_, v)| [v[0], v[1], v[2]]);
        let Some(offset) = given.or(rows.tool_offset(k)) else {
            continue;
        };
        let of: Vec<usize> = (0..rows.len()).filter(|&i| rows.tool(i) == k).collect();
        if of.is_empty() {
            continue;
        }
        let mut arm = params.clone();
        arm.probe = offset;
        // Every row through the tool's kernel, its rows kept: the data's
        // prepared poses as they are (corrected ones stay corrected).
        let mut q = vec![[0.0; 3]; data.len()];
        ArmKernel::new(&arm)?.positions(data.poses(), 0..data.len(), &mut q)?;
        for i in of {
            p[i] = q[i];
        }
    }
    Ok(p)
}

/// A tool's arm for a term's touches: the probe at the tool's offset (its
/// block's value when the layout fits one, else its nominal offset), and
/// its kernel — built once per evaluation, not per chunk.
pub(crate) struct ToolView {
    arm: DhParams,
    kernel: ArmKernel,
    /// The tool's offset block, when the layout fits one.
    pub(crate) block: Option<BlockId>,
}

/// How a term's touches are seen: per run of points of one tool (in point
/// order), the tool; per tool, its view (`None`: the default tool, `at`
/// itself).
pub(crate) struct TouchViews {
    pub(crate) runs: Vec<(usize, std::ops::Range<usize>)>,
    views: Vec<Option<ToolView>>,
}

impl TouchViews {
    /// The views of `data`'s touches at `at`: one run of every point, the
    /// default tool's, when no touch names a tool (today's path).
    ///
    /// # Errors
    ///
    /// A tool whose offset is not known (the data were not given the arm's
    /// tools, [`crate::dataset::DataSet::with_tools`]); the kernel's.
    pub(crate) fn of(data: &crate::dataset::DataSet, at: &At<'_>) -> Result<TouchViews, TermError> {
        let Some(tools) = data.touch_tools() else {
            return Ok(TouchViews {
                runs: vec![(0, 0..data.points().len())],
                views: vec![None],
            });
        };
        let mut views = Vec::with_capacity(tools.names().len());
        for (k, name) in tools.names().iter().enumerate() {
            if k == 0 || !tools.used().contains(&k) {
                views.push(None);
                continue;
            }
            let block = at.layout.block_named(&block_name(name));
            let offset = match block {
                Some(id) => {
                    let x = at.block(id);
                    [x[0], x[1], x[2]]
                }
                None => tools.offset(k).ok_or_else(|| {
                    TermError::invalid(
                        "touches",
                        format!(
                            "tool {}: no offset known (the arm lists no such [[tool]])",
                            crate::error::quoted(name)
                        ),
                    )
                })?,
            };
            let mut arm = at.arm.clone();
            arm.probe = offset;
            let kernel = ArmKernel::new(&arm)?;
            views.push(Some(ToolView { arm, kernel, block }));
        }
        Ok(TouchViews {
            runs: tools.runs(),
            views,
        })
    }

    /// `at` as tool `k` sees it.
    pub(crate) fn at<'a>(&'a self, at: &At<'a>, k: usize) -> At<'a> {
        match &self.views[k] {
            Some(v) => At {
                x: at.x,
                arm: &v.arm,
                kernel: &v.kernel,
                layout: at.layout,
                threads: at.threads,
            },
            None => At {
                x: at.x,
                arm: at.arm,
                kernel: at.kernel,
                layout: at.layout,
                threads: at.threads,
            },
        }
    }

    /// The kernel of tool `k`.
    pub(crate) fn kernel<'a>(&'a self, at: &At<'a>, k: usize) -> &'a ArmKernel {
        self.views[k].as_ref().map_or(at.kernel, |v| &v.kernel)
    }

    /// Tool `k`'s offset block (`None`: the default tool, or a tool the
    /// layout fits no block of).
    pub(crate) fn block(&self, k: usize) -> Option<BlockId> {
        self.views[k].as_ref().and_then(|v| v.block)
    }
}

/// Adds one offset block per tool `data`'s touches name (beyond the
/// default), starting at its nominal offset, or shares the block of that
/// name already there (the same tool's positions).
///
/// # Errors
///
/// A tool whose offset is not known ([`crate::dataset::DataSet::with_tools`]
/// not called with the arm's tools).
pub(crate) fn add_touch_tool_blocks(
    layout: &mut Layout,
    data: &crate::dataset::DataSet,
) -> Result<(), TermError> {
    let Some(tools) = data.touch_tools() else {
        return Ok(());
    };
    for k in tools.used() {
        let name = &tools.names()[k];
        // The same tool's positions added its block already: shared.
        if layout.block_named(&block_name(name)).is_none() {
            add_offset_block(layout, "touches", name, tools.offset(k))?;
        }
    }
    Ok(())
}

/// Where `params` puts every touch of `data` (touch order, mm), each
/// touch's tool at the offset `fitted` gives by block name (`tool.NAME`,
/// as [`positions_at`]'s), else at its nominal offset, the default tool
/// at the probe: what the figures of a calibration with several probes
/// are computed from.
///
/// # Errors
///
/// The kernel's.
pub(crate) fn touch_positions_at(
    params: &DhParams,
    data: &crate::dataset::DataSet,
    fitted: &[(String, [f64; 6])],
) -> Result<Vec<[f64; 3]>, crate::kernel::KernelError> {
    let kernel = ArmKernel::new(params)?;
    let mut p = vec![[0.0; 3]; data.len()];
    let Some(tools) = data.touch_tools() else {
        kernel.positions(data.poses(), 0..data.len(), &mut p)?;
        return Ok(p);
    };
    let points = data.points();
    for (k, run) in tools.runs() {
        let touches = points[run.start].touches.start..points[run.end - 1].touches.end;
        let out = &mut p[touches.clone()];
        if k == 0 {
            kernel.positions(data.poses(), touches, out)?;
            continue;
        }
        let block = block_name(&tools.names()[k]);
        let given = (fitted.iter().find(|(n, _)| *n == block)).map(|(_, v)| [v[0], v[1], v[2]]);
        let mut arm = params.clone();
        // `with_tools` gave every tool its offset before any fit.
        arm.probe = given.or(tools.offset(k)).unwrap_or(params.probe);
        ArmKernel::new(&arm)?.positions(data.poses(), touches, out)?;
    }
    Ok(p)
}
