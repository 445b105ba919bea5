//! The inputs' checks a problem makes when it is made: units, the arm's
//! shape and tools, reference positions, held-out frames.

use crate::calibrate::CalibrationError;
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::params::DhParams;
use crate::residuals::Layout;

/// Stated lengths this many times the nominal arm's distances (or their
/// inverse) are in another unit: a calibration moves the arm by per cent,
/// not by orders of magnitude — but the nominal arm of a newly assembled
/// one, its zeros anywhere, can put two sockets several times nearer or
/// farther than they are, so the bound is two orders of magnitude (metres
/// for millimetres is three).
const LENGTH_UNIT_RATIO: f64 = 100.0;

/// The reaches, mm, of arms that exist: a nominal arm outside them is in
/// another unit than its file declares (the arm reader warns from
/// `PLAUSIBLE_METRES` in metres on).
const PLAUSIBLE_REACH_MM: std::ops::RangeInclusive<f64> =
    10.0..=crate::io::arm::PLAUSIBLE_METRES * 1000.0;

/// `data` (of the arm's joint count) prepared for the arm's chain: a
/// prismatic joint's readings (mm) are used as lengths however the data
/// were made (a reader given only a joint count, arrays).
pub(super) fn of_arm_shape(arm: &Arm, data: DataSet) -> Result<DataSet, CalibrationError> {
    let Ok(shape) = arm.params.shape() else {
        return Ok(data);
    };
    let joints = (shape.joints(), data.joints());
    data.for_shape(shape).map_err(|_| CalibrationError::Joints {
        arm: joints.0,
        data: joints.1,
    })
}

/// `data` with each tool its positions name given the arm's nominal
/// offset; a tool the arm does not list is refused by file, line and field.
pub(super) fn of_arm_tools(arm: &Arm, data: DataSet) -> Result<DataSet, CalibrationError> {
    data.with_tools(&crate::domain::ToolNames::of(&arm.tools))
        .map_err(|e| match e {
            crate::error::InputError::Field {
                file,
                line,
                field,
                message,
            } => CalibrationError::Positions {
                file,
                line,
                field,
                message,
            },
            e => CalibrationError::Positions {
                file: String::new(),
                line: 0,
                field: "tool".into(),
                message: e.to_string(),
            },
        })
}

/// Refuses reference lengths whose median ratio to the nominal arm's
/// distances between the same points is beyond 100 or below 1/100
/// (lengths in metres for an arm in mm, say), naming the input at fault:
/// the poses file when the readings look like radians read as degrees
/// (the reader's warning; every joint within ±6.3° puts the sockets almost
/// on top of each other, [`CalibrationError::AngleUnits`]); the arm file
/// (`arm_file`) when its reach is no arm's — its numbers in another unit
/// than it declares ([`CalibrationError::ArmUnits`]); else the lengths
/// file ([`CalibrationError::LengthUnits`]). Every command that reads a
/// lengths file makes this check, in every front end: calibrate and
/// identify (the [`Request`]), evaluate (the command line and Python call
/// it before evaluating).
///
/// [`Request`]: super::Request
///
/// # Errors
///
/// As above; a kernel that refuses the arm.
///
/// ```
/// use aacmm_core::{calibrate::CalibrationError, domain::Arm, params::DhParams, simulate::*};
/// use aacmm_core::session::check_units;
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 4, 6);
/// settings.reference_lengths = 3;
/// let campaign = simulate(&nominal, &settings).unwrap();
/// let data = campaign.data_set().unwrap();
/// assert!(check_units(&nominal.params, &data, "arm.toml").is_ok());
/// // The arm's millimetres declared as metres: the arm is 1240 m long.
/// let mut metres = nominal.params.clone();
/// for j in &mut metres.joints {
///     (j.a, j.d) = (1000.0 * j.a, 1000.0 * j.d);
/// }
/// metres.probe = metres.probe.map(|v| 1000.0 * v);
/// let e = check_units(&metres, &data, "arm.toml").unwrap_err();
/// assert!(matches!(e, CalibrationError::ArmUnits { .. }), "{e}");
/// assert!(e.to_string().starts_with("arm.toml: "), "{e}");
/// ```
pub fn check_units(
    params: &DhParams,
    data: &DataSet,
    arm_file: &str,
) -> Result<(), CalibrationError> {
    let Some(ratio) = median_length_ratio(params, data, data.poses())? else {
        return Ok(());
    };
    let in_range = |r: f64| (1.0 / LENGTH_UNIT_RATIO..=LENGTH_UNIT_RATIO).contains(&r);
    if in_range(ratio) {
        return Ok(());
    }
    let to_deg = 1f64.to_degrees();
    let shape = (data.joints(), data.poses().prismatic_mask());
    if crate::io::poses::look_like_radians(data.readings(), data.len(), shape, to_deg) {
        // The numbers as typed, taken as radians: what `--angle-unit rad`
        // would have read (a prismatic joint's reading, mm, as it is).
        let mask = data.poses().prismatic_mask();
        let slides = |j: usize| j < 16 && mask & (1 << j) != 0;
        let typed: Vec<f64> = (data.readings().iter().enumerate())
            .map(|(i, x)| {
                if slides(i % data.joints()) {
                    *x
                } else {
                    x * to_deg
                }
            })
            .collect();
        let as_rad =
            crate::kernel::PreparedPoses::from_flat_with(data.joints(), mask, data.len(), &typed);
        let ratio_as_rad = median_length_ratio(params, data, &as_rad)?.unwrap_or(f64::NAN);
        return Err(CalibrationError::AngleUnits {
            file: data.source().poses_file().to_string(),
            ratio,
            ratio_as_rad,
            lengths_agree: in_range(ratio_as_rad),
        });
    }
    let reach = params.reach();
    if !PLAUSIBLE_REACH_MM.contains(&reach) {
        return Err(CalibrationError::ArmUnits {
            file: arm_file.to_string(),
            reach_mm: reach,
            ratio,
        });
    }
    Err(CalibrationError::LengthUnits {
        file: data.source().reference(0).file.to_string(),
        ratio,
    })
}

/// The median over the reference lengths of stated length / the nominal
/// arm's distance between the centroids of the same points, with the
/// touches at `poses`; `None` without a finite ratio (no lengths).
fn median_length_ratio(
    params: &DhParams,
    data: &DataSet,
    poses: &crate::kernel::PreparedPoses,
) -> Result<Option<f64>, CalibrationError> {
    if data.references().is_empty() {
        return Ok(None);
    }
    let kernel = crate::kernel::ArmKernel::new(params)?;
    let mut xyz = vec![[0.0; 3]; data.len()];
    kernel.positions(poses, 0..data.len(), &mut xyz)?;
    let centroids: Vec<[f64; 3]> = data
        .points()
        .iter()
        .map(|p| crate::geometry::centroid(&xyz[p.touches.clone()]))
        .collect();
    let mut ratios: Vec<f64> = data
        .references()
        .iter()
        .map(|r| r.distance / crate::geometry::distance(&centroids[r.a], &centroids[r.b]))
        .filter(|v| v.is_finite())
        .collect();
    if ratios.is_empty() {
        return Ok(None);
    }
    ratios.sort_by(f64::total_cmp);
    Ok(Some(ratios[ratios.len() / 2]))
}

/// The ratio of the spreads of an instrument's positions and the nominal
/// arm's beyond which they are in another unit (metres: 1/1000, inches:
/// 1/25.4) or of another arm.
const POSITION_SPREAD_RATIO: f64 = 5.0;

/// The share of its spread by which the nominal arm, best registered, may
/// miss a frame's positions: more is another arm, readings in another
/// joint order or unit, or a different tool (a nominal arm misses by per
/// cent of its reach, not by a fifth).
const POSITION_MISS_SHARE: f64 = 0.2;

/// Refuses reference positions the nominal arm cannot be registered to,
/// frame by frame: positions in another unit (their spread against the
/// arm's), a mirror image (swapped axes: a mirrored registration fits much
/// better than any rotation), or positions of another arm (the best
/// registration misses by a large share of their spread). When every
/// reading, read as degrees, is within ±2π — radians read as degrees, as
/// the touch readers ask ([`crate::io::poses::look_like_radians`]) — the
/// refusal names the angle unit instead, and whether the numbers read as
/// radians fit.
pub(super) fn check_positions(data: &DataSet, layout: &Layout) -> Result<(), CalibrationError> {
    let Some(positions) = data.positions() else {
        return Ok(());
    };
    let Some(refusal) = position_refusal(positions, layout.geometry())? else {
        return Ok(());
    };
    let rows = positions.rows();
    let to_deg = 1f64.to_degrees();
    let shape = (rows.joints(), rows.prismatic_mask());
    if !crate::io::poses::look_like_radians(rows.readings(), rows.len(), shape, to_deg) {
        return Err(refusal);
    }
    let as_rad =
        DataSet::from_positions(rows.revolute_scaled(to_deg), positions.file()).map_err(|e| {
            CalibrationError::Term {
                term: "positions".into(),
                message: e.to_string(),
            }
        })?;
    let fits = match as_rad.positions() {
        Some(p) => position_refusal(p, layout.geometry())?.is_none(),
        None => false,
    };
    // What reading them as degrees did, in numbers rather than the
    // refusal's guesses (another unit, another arm).
    let reg = &crate::residuals::positions::register(layout.geometry(), positions)?[0];
    Err(CalibrationError::Positions {
        file: positions.file().to_string(),
        line: rows.line(0),
        field: "q1".to_string(),
        message: format!(
            "every joint reading, read as degrees, is within ±6.28° in all {} rows: these angles \
             look like radians read as degrees, not positions in another unit — read so, the \
             nominal arm's probe spreads {:.4} mm about its centroid where the instrument saw \
             {:.4} mm; {}{}",
            rows.len(),
            reg.arm_spread_mm,
            reg.spread_mm,
            crate::calibrate::ANGLE_UNITS_REMEDY,
            if fits {
                ": read so, the nominal arm fits these positions"
            } else {
                "; read so, the nominal arm still does not fit them: check the readings' order \
                 and the positions' unit (mm) too"
            }
        ),
    })
}

/// The first frame of `positions` that the nominal arm `params` cannot be
/// registered to, as the refusal ([`check_positions`]); `None` when every
/// frame can.
fn position_refusal(
    positions: &crate::dataset::PositionData,
    params: &DhParams,
) -> Result<Option<CalibrationError>, CalibrationError> {
    let registrations = crate::residuals::positions::register(params, positions)?;
    let rows = positions.rows();
    for (f, (name, reg)) in rows.frames().iter().zip(registrations).enumerate() {
        let first = (0..rows.len()).find(|&i| rows.frame(i) == f).unwrap_or(0);
        let refuse = |field: &str, message: String| CalibrationError::Positions {
            file: positions.file().to_string(),
            line: rows.line(first),
            field: field.to_string(),
            message: format!("frame `{name}`: {message}"),
        };
        let ratio = reg.spread_mm / reg.arm_spread_mm;
        if !(1.0 / POSITION_SPREAD_RATIO..=POSITION_SPREAD_RATIO).contains(&ratio) {
            return Ok(Some(refuse(
                "x",
                format!(
                    "the positions spread {:.4} mm about their centroid, the nominal arm's \
                     {:.4} mm ({ratio:.3e} times): positions in another unit (they must be \
                     mm; metres give 1e-3) or of another arm?",
                    reg.spread_mm, reg.arm_spread_mm
                ),
            )));
        }
        if reg.mirrored_rms_mm < 0.5 * reg.rms_mm && reg.rms_mm > 0.01 * reg.spread_mm {
            return Ok(Some(refuse(
                "y",
                format!(
                    "a mirror image fits the nominal arm (RMS {:.4} mm) far better than any \
                     rotation (RMS {:.4} mm): two axes swapped, or one reversed — give x, y, z \
                     of a right-handed frame",
                    reg.mirrored_rms_mm, reg.rms_mm
                ),
            )));
        }
        if reg.rms_mm > POSITION_MISS_SHARE * reg.spread_mm {
            return Ok(Some(refuse(
                "point",
                format!(
                    "the nominal arm, best registered, misses these positions by RMS {:.4} mm \
                     over a spread of {:.4} mm: positions of another arm, joint readings in \
                     another order or unit, or another tool?",
                    reg.rms_mm, reg.spread_mm
                ),
            )));
        }
    }
    Ok(None)
}

/// The frames of `data`'s reference positions (none without them).
fn frame_names(data: &DataSet) -> &[String] {
    data.positions().map_or(&[], |p| p.rows().frames())
}

/// The frames of held-out positions that `fitted` has none of, in order.
pub(super) fn unfitted_frames<'a>(fitted: &DataSet, held: &'a DataSet) -> Vec<&'a String> {
    let have = frame_names(fitted);
    (frame_names(held).iter())
        .filter(|f| !have.contains(f))
        .collect()
}

/// Held-out positions are scored in the fitted frames of their names: a
/// frame the fit does not have would be registered on its own positions,
/// which absorbs part of the arm's error (an optimistic score), so it is
/// refused by its first line, with the fitted frames.
pub(super) fn check_held_out_frames(
    fitted: &DataSet,
    held: &DataSet,
) -> Result<(), CalibrationError> {
    let Some(p) = held.positions() else {
        return Ok(());
    };
    let Some(frame) = unfitted_frames(fitted, held).into_iter().next() else {
        return Ok(());
    };
    let rows = p.rows();
    let first = (0..rows.len())
        .find(|&i| &rows.frames()[rows.frame(i)] == frame)
        .expect("a frame has a row");
    let have = frame_names(fitted);
    let fitted = if have.is_empty() {
        "the fit has no reference positions, so no frame".to_string()
    } else {
        format!(
            "the fitted frame{} {}",
            if have.len() == 1 { " is" } else { "s are" },
            have.iter()
                .map(|f| format!("`{f}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    Err(CalibrationError::Positions {
        file: p.file().to_string(),
        line: rows.line(first),
        field: "frame".to_string(),
        message: format!(
            "held-out frame `{frame}` was not fitted ({fitted}): its positions could only be \
             registered on themselves, which hides part of the arm's error. Name the fitted \
             frame they were measured in, fit this frame too (in --positions), or let it be \
             registered on its own positions with --register-held-out (then every output says \
             so)"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{AngleUnit, parse_poses, read_lengths, write_poses};
    use crate::{calibrate::ModelOptions, session::Problem};

    /// The shipped campaign (degrees), its lengths, and the nominal arm.
    fn shipped() -> (
        crate::domain::Poses,
        Vec<crate::domain::ReferenceLength>,
        Arm,
    ) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        let (poses, _) =
            crate::io::read_poses(&root.join("paper-campaign/poses.csv"), AngleUnit::Deg, None)
                .unwrap();
        let lengths = read_lengths(&root.join("paper-campaign/lengths.csv")).unwrap();
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        (poses, lengths, arm)
    }

    /// Radians read as degrees: the library's refusal names the angle unit
    /// (every front end's setting) and finds the lengths right once the
    /// readings are taken as radians; the lengths-unit refusal stays for
    /// lengths that are wrong.
    #[test]
    fn radians_read_as_degrees_are_refused_for_the_angle_unit() {
        let (poses, lengths, arm) = shipped();
        let mut text = Vec::new();
        write_poses(&mut text, &poses, AngleUnit::Rad).unwrap();
        let text = String::from_utf8(text).unwrap();
        let (as_deg, warnings) = parse_poses(&text, "rad.csv", AngleUnit::Deg, None).unwrap();
        assert!(
            warnings[0].message.contains("look like radians"),
            "{warnings:?}"
        );
        let data = DataSet::from_poses(&as_deg, "rad.csv")
            .unwrap()
            .with_lengths(&lengths, "l.csv")
            .unwrap();
        let e = Problem::new(arm.clone(), data, ModelOptions::default()).unwrap_err();
        match &e {
            CalibrationError::AngleUnits {
                file,
                ratio,
                ratio_as_rad,
                lengths_agree,
            } => {
                assert_eq!(file, "rad.csv");
                assert!(*ratio > LENGTH_UNIT_RATIO, "{ratio}");
                // The nominal arm is within a few mm of the true one.
                assert!((ratio_as_rad - 1.0).abs() < 0.01, "{ratio_as_rad}");
                assert!(lengths_agree);
            }
            other => panic!("not the angle unit: {other}"),
        }
        let m = e.to_string();
        for want in [
            "`--angle-unit rad`",
            "angle_unit=\"rad\"",
            "AACMM_ANGLE_RAD",
        ] {
            assert!(m.contains(want), "{want}: {m}");
        }
        // Lengths in metres with readings in degrees: still the lengths.
        let metres: Vec<_> = (lengths.iter().cloned())
            .map(|mut l| {
                l.distance /= 1000.0;
                l
            })
            .collect();
        let data = DataSet::from_poses(&poses, "p.csv")
            .unwrap()
            .with_lengths(&metres, "m.csv")
            .unwrap();
        let e = Problem::new(arm, data, ModelOptions::default()).unwrap_err();
        assert!(matches!(e, CalibrationError::LengthUnits { .. }), "{e}");
    }
}
