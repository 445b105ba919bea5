//! What `evaluate --positions` reports: the 3-D errors of one arm at
//! reference positions (a laser tracker's), each frame registered — as the
//! arm file states it (a calibrated arm's `[[frame]]` of the same name), or
//! else to this arm in closed form on these very positions — and which of
//! the two, said with every figure: a frame registered on the positions it
//! scores absorbs a rigid motion of the arm's error, so its figures are a
//! lower bound of what a fixed registration would show. Where rows give
//! the tool's orientation, its errors too, per frame, with the mount of the
//! 6-D target as the arm file states it (`[mount]`) or else in closed form
//! on these orientations (optimistic, and said so).

use serde::Serialize;

use crate::calibrate::CalibrationError;
use crate::calibrate::validate::{
    FrameValues, PositionErrors, orientation_errors_per_row, pose_errors, registered_frames,
    seen_by,
};
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::residuals::MOUNT_BLOCK;

/// One frame's registration and the arm's 3-D errors in it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameEvaluation {
    /// The frame's name.
    pub name: String,
    /// Registered as the arm file states it (`true`), or in closed form on
    /// the positions evaluated (`false`: optimistic).
    pub from_arm_file: bool,
    /// Its rotation vector, deg.
    pub rotation_deg: [f64; 3],
    /// Its translation, mm.
    pub translation_mm: [f64; 3],
    /// The 3-D errors `|R p + t − y|` of its rows, mm.
    pub errors: PositionErrors,
    /// The orientation errors of its rows that give the tool's
    /// orientation, deg; absent when none does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientations: Option<PositionErrors>,
}

/// The mount of the 6-D target the orientations were evaluated with.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MountEvaluation {
    /// As the arm file states it (`true`, `[mount]`), or in closed form on
    /// the orientations evaluated (`false`: optimistic).
    pub(crate) from_arm_file: bool,
    /// Its rotation vector, deg.
    pub rotation_deg: [f64; 3],
}

/// The 3-D errors of an arm at the reference positions of a file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PositionEvaluation {
    /// The positions file.
    pub positions_file: String,
    /// Over every row, mm.
    pub errors: PositionErrors,
    /// Per frame, in the file's order.
    pub frames: Vec<FrameEvaluation>,
    /// Over every row that gives the tool's orientation, deg; absent when
    /// none does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientations: Option<PositionErrors>,
    /// The 6-D target's mount the orientations were evaluated with; absent
    /// without orientations.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mount: Option<MountEvaluation>,
}

impl PositionEvaluation {
    /// The errors of `arm` (through the corrections its file states) at
    /// `data`'s reference positions, each frame registered as `stated`
    /// says (the arm file's frames), else in closed form on them.
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Term`] for data without reference positions or
    /// a correction whose conditions the data lack; the kernel's.
    pub fn new(
        arm: &Arm,
        data: &DataSet,
        stated: &[FrameValues],
    ) -> Result<PositionEvaluation, CalibrationError> {
        let seen = seen_by(&arm.params, &arm.physics, data)?;
        let Some(p) = seen.positions() else {
            return Err(CalibrationError::Term {
                term: "positions".into(),
                message: "no reference positions to evaluate".into(),
            });
        };
        let mut closed = registered_frames(&arm.params, &seen)?;
        // The frames alone (a mount of orientations after them: not here).
        closed.truncate(p.rows().frames().len());
        let frames: Vec<(FrameValues, bool)> = (closed.into_iter())
            .map(|(name, x)| match stated.iter().find(|(n, _)| *n == name) {
                Some(s) => (s.clone(), true),
                None => ((name, x), false),
            })
            .collect();
        let mut values: Vec<FrameValues> = frames.iter().map(|(f, _)| f.clone()).collect();
        let (_, d) = pose_errors(&arm.params, p, &values)?;
        let mount = mount_of(&arm.params, p, &values, stated)?;
        if let Some(m) = &mount {
            let r = m.rotation_deg.map(f64::to_radians);
            values.push((MOUNT_BLOCK.to_string(), [r[0], r[1], r[2], 0.0, 0.0, 0.0]));
        }
        let turned = orientation_errors_per_row(&arm.params, p, &values)?;
        let rows = p.rows();
        let of = |k: Option<usize>| {
            let mine = |i: &usize| k.is_none_or(|k| rows.frame(*i) == k);
            let e: Vec<f64> = (0..d.len())
                .filter(mine)
                .filter_map(|i| turned[i])
                .collect();
            (!e.is_empty()).then(|| PositionErrors::of(&e))
        };
        let per_frame = frames
            .into_iter()
            .enumerate()
            .map(|(k, ((name, x), from_arm_file))| {
                let mine: Vec<f64> = (0..d.len())
                    .filter(|&i| rows.frame(i) == k)
                    .map(|i| d[i])
                    .collect();
                FrameEvaluation {
                    name,
                    from_arm_file,
                    rotation_deg: [x[0], x[1], x[2]].map(f64::to_degrees),
                    translation_mm: [x[3], x[4], x[5]],
                    errors: PositionErrors::of(&mine),
                    orientations: of(Some(k)),
                }
            })
            .collect();
        Ok(PositionEvaluation {
            positions_file: p.file().to_string(),
            errors: PositionErrors::of(&d),
            frames: per_frame,
            orientations: of(None),
            mount,
        })
    }
}

/// The mount of the 6-D target: as `stated` gives it (the arm file's
/// `[mount]`, under [`MOUNT_BLOCK`]), else in closed form on `data`'s
/// orientations in the frames `frames`; `None` when no row gives one.
fn mount_of(
    params: &crate::params::DhParams,
    data: &crate::dataset::PositionData,
    frames: &[FrameValues],
    stated: &[FrameValues],
) -> Result<Option<MountEvaluation>, crate::kernel::KernelError> {
    if data.rows().oriented_rows() == 0 {
        return Ok(None);
    }
    if let Some((_, m)) = stated.iter().find(|(n, _)| n == MOUNT_BLOCK) {
        return Ok(Some(MountEvaluation {
            from_arm_file: true,
            rotation_deg: [m[0], m[1], m[2]].map(f64::to_degrees),
        }));
    }
    let x: Vec<[f64; 6]> = frames.iter().map(|(_, x)| *x).collect();
    Ok(
        crate::residuals::mount_start(params, data, &x)?.map(|m| MountEvaluation {
            from_arm_file: false,
            rotation_deg: m.map(f64::to_degrees),
        }),
    )
}
