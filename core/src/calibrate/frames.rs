//! What a calibration says of its auxiliary columns beyond geometry: the
//! fitted frames' registrations, the tool points' offsets and the tool
//! mount, as values and as the records a calibrated arm file carries.

use super::{AuxiliaryEstimate, Calibration, validate};

impl Calibration {
    /// Each fitted frame's registration `[rx, ry, rz, tx, ty, tz]` (rad, mm)
    /// by name: the auxiliary columns `NAME.rx … NAME.tz` of the frames of
    /// reference positions.
    pub fn frames(&self) -> Vec<validate::FrameValues> {
        self.frame_columns()
            .into_iter()
            .map(|(name, cols)| {
                let x = std::array::from_fn(|k| {
                    let v = cols[k].calibrated;
                    if k < 3 { v.to_radians() } else { v }
                });
                (name.to_string(), x)
            })
            .collect()
    }

    /// [`Calibration::frames`], then the fitted tool mount of orientations
    /// when there is one, under its block's name
    /// ([`validate::FrameValues`]): what the figures of orientations need.
    pub fn frames_with_mount(&self) -> Vec<validate::FrameValues> {
        let mut frames = self.frames();
        if let Some(m) = self.mount() {
            let r = m.map(f64::to_radians);
            frames.push((
                crate::residuals::MOUNT_BLOCK.to_string(),
                [r[0], r[1], r[2], 0.0, 0.0, 0.0],
            ));
        }
        for (name, x) in self.tool_offsets() {
            frames.push((
                crate::domain::block_name(&name),
                [x[0], x[1], x[2], 0.0, 0.0, 0.0],
            ));
        }
        frames
    }

    /// Each fitted tool point's offset (`[[tool]]`, [`crate::io::tools`]):
    /// its name and `[x, y, z]` (mm, the last joint's frame), with their
    /// σ when determined, in the order of the columns.
    pub fn tool_estimates(&self) -> Vec<(String, [f64; 3], Option<[f64; 3]>)> {
        let aux = &self.auxiliary;
        let prefix = crate::domain::TOOL_BLOCK_PREFIX;
        (0..aux.len())
            .filter_map(|i| {
                let name = aux[i].name.strip_prefix(prefix)?.strip_suffix(".x")?;
                let cols = aux.get(i..i + 3)?;
                let named = (cols.iter().zip(["x", "y", "z"]))
                    .all(|(c, axis)| c.name == format!("{prefix}{name}.{axis}"));
                let sigma = [cols[0].sigma, cols[1].sigma, cols[2].sigma];
                let sigma = match sigma {
                    [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                    _ => None,
                };
                let x = std::array::from_fn(|k| cols[k].calibrated);
                named.then(|| (name.to_string(), x, sigma))
            })
            .collect()
    }

    /// [`Calibration::tool_estimates`] without the σ.
    pub fn tool_offsets(&self) -> Vec<(String, [f64; 3])> {
        (self.tool_estimates().into_iter())
            .map(|(n, x, _)| (n, x))
            .collect()
    }

    /// The fitted tool mount of orientations (`crate::residuals::Mount`),
    /// its rotation vector in degrees; `None` when none was fitted.
    pub fn mount(&self) -> Option<[f64; 3]> {
        let cols = self.mount_columns()?;
        Some(std::array::from_fn(|k| cols[k].calibrated))
    }

    /// The fitted tool mount as a calibrated arm file carries it
    /// ([`crate::io::frames::MountRecord`]); `None` when none was fitted.
    pub fn mount_record(&self) -> Option<crate::io::frames::MountRecord> {
        let cols = self.mount_columns()?;
        let sigma = [cols[0].sigma, cols[1].sigma, cols[2].sigma];
        Some(crate::io::frames::MountRecord {
            rotation_deg: std::array::from_fn(|k| cols[k].calibrated),
            small_rotation_sigma_deg: sigma[0]
                .zip(sigma[1])
                .zip(sigma[2])
                .map(|((a, b), c)| [a, b, c]),
        })
    }

    /// The mount's three columns `mount.rx … mount.rz`, if fitted.
    fn mount_columns(&self) -> Option<&[AuxiliaryEstimate]> {
        let name = |k: &str| format!("{}.{k}", crate::residuals::MOUNT_BLOCK);
        let i = (self.auxiliary.iter()).position(|c| c.name == name("rx"))?;
        let cols = self.auxiliary.get(i..i + 3)?;
        (cols[1].name == name("ry") && cols[2].name == name("rz")).then_some(cols)
    }

    /// Each fitted frame as a calibrated arm file carries it
    /// ([`crate::io::frames`]): values and σ in deg and mm.
    pub fn frame_records(&self) -> Vec<crate::io::frames::FrameRecord> {
        self.frame_columns()
            .into_iter()
            .map(|(name, cols)| {
                let three = |from: usize| std::array::from_fn(|k| cols[from + k].calibrated);
                let sigmas = |from: usize| -> Option<[f64; 3]> {
                    Some([
                        cols[from].sigma?,
                        cols[from + 1].sigma?,
                        cols[from + 2].sigma?,
                    ])
                };
                crate::io::frames::FrameRecord {
                    name: name.to_string(),
                    rotation_deg: three(0),
                    translation_mm: three(3),
                    small_rotation_sigma_deg: sigmas(0),
                    translation_sigma_mm: sigmas(3),
                }
            })
            .collect()
    }

    /// The frames among the auxiliary columns: each name and its six
    /// columns `NAME.rx … NAME.tz` (user units: deg, mm).
    pub(super) fn frame_columns(&self) -> Vec<(&str, &[AuxiliaryEstimate])> {
        const AXES: [&str; 6] = ["rx", "ry", "rz", "tx", "ty", "tz"];
        let aux = &self.auxiliary;
        (0..aux.len())
            .filter_map(|i| {
                let name = aux[i].name.strip_suffix(".rx")?;
                let cols = aux.get(i..i + 6)?;
                let named = (cols.iter().zip(AXES))
                    .all(|(c, axis)| c.name.strip_prefix(name) == Some(&format!(".{axis}")));
                named.then_some((name, cols))
            })
            .collect()
    }
}
