//! The registrations of an instrument's frames, as a calibrated arm file
//! carries them: one `[[frame]]` table per frame of the reference
//! positions it was fitted to.
//!
//! ```toml
//! [[frame]]
//! name = "instrument"
//! rotation_deg = [-0.0566, 0.1122, 0.0509]     # rotation vector (axis × angle)
//! translation_mm = [-0.4099, 0.0943, -0.0031]
//! small_rotation_sigma_deg = [0.0015, 0.0017, 0.0050] # about its x, y, z axes
//! translation_sigma_mm = [0.021, 0.019, 0.013]
//! ```
//!
//! A frame maps the arm's base coordinates into the instrument's,
//! `y = R p + t`, with `R` the rotation of the rotation vector. The σ (k = 1)
//! are those of the fit's step: of small rotations `δω` about the
//! instrument's x, y and z axes (`R ← exp(δω) R`) — not of the rotation
//! vector's components, which they equal only at the identity — and of
//! the translation. A frame the data did not determine has none. A file
//! written before the σ had their name (`rotation_sigma_deg`) reads the
//! same.

use serde::{Deserialize, Serialize};

use super::text::line_of;
use crate::error::{InputError, quoted};

/// A frame's registration as written in a calibrated arm file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameRecord {
    /// The frame's name (the positions file's `frame`).
    pub name: String,
    /// Rotation vector of `R`, deg.
    pub rotation_deg: [f64; 3],
    /// `t`, mm.
    pub translation_mm: [f64; 3],
    /// σ (k = 1) of small rotations about the instrument's x, y and z axes,
    /// deg, when the fit determined them (see the module).
    #[serde(
        default,
        alias = "rotation_sigma_deg",
        skip_serializing_if = "Option::is_none"
    )]
    pub small_rotation_sigma_deg: Option<[f64; 3]>,
    /// σ of the translation (k = 1), mm, when the fit determined it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translation_sigma_mm: Option<[f64; 3]>,
}

impl FrameRecord {
    /// `[rx, ry, rz, tx, ty, tz]` (rad, mm), what the library computes with.
    pub fn values(&self) -> [f64; 6] {
        let r = self.rotation_deg.map(f64::to_radians);
        let t = self.translation_mm;
        [r[0], r[1], r[2], t[0], t[1], t[2]]
    }
}

#[derive(Serialize, Deserialize)]
struct Frames {
    #[serde(default)]
    frame: Vec<FrameRecord>,
}

/// The `[[frame]]` tables of an arm file's text (none: empty); `file`
/// names it in messages.
///
/// ```
/// use aacmm_core::io::frames::{parse_frames, frames_to_toml};
/// let text = "[[frame]]\nname = \"t\"\nrotation_deg = [0.0, 0.0, 90.0]\ntranslation_mm = [1.0, 2.0, 3.0]\n";
/// let f = parse_frames(text, "c.toml").unwrap();
/// assert_eq!((f[0].name.as_str(), f[0].values()[2]), ("t", std::f64::consts::FRAC_PI_2));
/// assert_eq!(frames_to_toml(&f), text);
/// ```
///
/// # Errors
///
/// TOML that does not parse, a `[[frame]]` table with a field missing,
/// unknown or not a number, a value that is not finite, and a name given
/// twice: each naming the file.
pub fn parse_frames(text: &str, file: &str) -> Result<Vec<FrameRecord>, InputError> {
    let frames = toml::from_str::<Frames>(text)
        .map_err(|e| {
            let line = e.span().map_or(0, |s| line_of(text, s.start));
            let m = format!("a `[[frame]]` table: {}", e.message());
            InputError::field(file, line, "frame", m)
        })?
        .frame;
    for (i, f) in frames.iter().enumerate() {
        let values = f.rotation_deg.iter().chain(&f.translation_mm);
        if values.clone().any(|v| !v.is_finite()) {
            let m = format!(
                "frame {}: a value that is not a finite number",
                quoted(&f.name)
            );
            return Err(InputError::file_error(file, m));
        }
        if frames[..i].iter().any(|g| g.name == f.name) {
            let m = format!("frame {} is given twice", quoted(&f.name));
            return Err(InputError::file_error(file, m));
        }
    }
    Ok(frames)
}

/// The `[[frame]]` tables of `frames`, to append to an arm file.
pub fn frames_to_toml(frames: &[FrameRecord]) -> String {
    if frames.is_empty() {
        return String::new();
    }
    let t = Frames {
        frame: frames.to_vec(),
    };
    toml::to_string(&t).expect("strings and finite numbers always serialize to TOML")
}

/// The tool mount of a 6-D target as an arm file carries it (`[mount]`):
/// the rotation from the target's frame to the arm's last frame, fitted
/// when the positions give the tool's orientation
/// (`crate::residuals::Mount`).
///
/// ```toml
/// [mount]
/// rotation_deg = [12.5, -3.25, 90.0]            # rotation vector (axis × angle)
/// small_rotation_sigma_deg = [0.002, 0.002, 0.003] # about the last frame's x, y, z axes
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountRecord {
    /// Rotation vector of `R_m`, deg.
    pub rotation_deg: [f64; 3],
    /// σ (k = 1) of small rotations about the arm's last frame's x, y and z
    /// axes, deg, when the fit determined them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub small_rotation_sigma_deg: Option<[f64; 3]>,
}

#[derive(Serialize, Deserialize)]
struct MountTable {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mount: Option<MountRecord>,
}

/// The `[mount]` table of an arm file's text, if any; `file` names it in
/// messages.
///
/// ```
/// use aacmm_core::io::frames::{MountRecord, mount_to_toml, parse_mount};
/// let m = MountRecord { rotation_deg: [0.0, 0.0, 90.0], small_rotation_sigma_deg: None };
/// let text = mount_to_toml(&m);
/// assert_eq!(text, "[mount]\nrotation_deg = [0.0, 0.0, 90.0]\n");
/// assert_eq!(parse_mount(&text, "c.toml").unwrap(), Some(m));
/// assert_eq!(parse_mount("", "c.toml").unwrap(), None);
/// ```
///
/// # Errors
///
/// TOML that does not parse, a `[mount]` table with a field missing,
/// unknown or not a number, and a value that is not finite.
pub fn parse_mount(text: &str, file: &str) -> Result<Option<MountRecord>, InputError> {
    #[derive(Deserialize)]
    struct Only {
        #[serde(default)]
        mount: Option<MountRecord>,
    }
    // Every other table is the arm's or the frames': read elsewhere.
    let table: toml::Table = toml::from_str(text).map_err(|e| {
        let line = e.span().map_or(0, |s| line_of(text, s.start));
        InputError::field(file, line, "mount", e.message().to_string())
    })?;
    let Some(value) = table.get("mount") else {
        return Ok(None);
    };
    let mut only = toml::Table::new();
    only.insert("mount".into(), value.clone());
    let mount = (only.try_into::<Only>())
        .map_err(|e| {
            let m = format!("a `[mount]` table: {}", e.message());
            InputError::field(file, 0, "mount", m)
        })?
        .mount;
    if let Some(m) = &mount {
        let values = m
            .rotation_deg
            .iter()
            .chain(m.small_rotation_sigma_deg.iter().flatten());
        if values.clone().any(|v| !v.is_finite()) {
            let m = "mount: a value that is not a finite number".to_string();
            return Err(InputError::file_error(file, m));
        }
    }
    Ok(mount)
}

/// The `[mount]` table of `mount`, to append to an arm file.
pub fn mount_to_toml(mount: &MountRecord) -> String {
    let t = MountTable {
        mount: Some(mount.clone()),
    };
    toml::to_string(&t).expect("finite numbers always serialize to TOML")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The σ of a frame's rotation are written under the name of what they
    /// are (small rotations about its axes); a file written before, with
    /// `rotation_sigma_deg`, reads the same.
    #[test]
    fn the_rotations_sigma_is_named_and_the_old_name_still_reads() {
        let record = FrameRecord {
            name: "tracker".into(),
            rotation_deg: [1.0, 2.0, 3.0],
            translation_mm: [4.0, 5.0, 6.0],
            small_rotation_sigma_deg: Some([0.5, 0.25, 0.125]),
            translation_sigma_mm: Some([0.1, 0.2, 0.3]),
        };
        let text = frames_to_toml(std::slice::from_ref(&record));
        assert!(
            text.contains("small_rotation_sigma_deg = [0.5, 0.25, 0.125]\n"),
            "{text}"
        );
        assert_eq!(
            parse_frames(&text, "c.toml").unwrap(),
            std::slice::from_ref(&record)
        );
        let old = text.replace("small_rotation_sigma_deg", "rotation_sigma_deg");
        assert_eq!(parse_frames(&old, "c.toml").unwrap(), [record]);
    }
}
