//! The campaign's files: writing the five outputs and reading `campaign.toml`
//! back to regenerate them.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{Campaign, CampaignSettings, SimError};
use crate::domain::Arm;
use crate::error::InputError;
use crate::io::arm::ArmFile;
use crate::io::{
    AngleUnit, LengthUnit, arm_to_toml, parse_arm, write_lengths, write_points, write_poses,
};

/// The `format` key of `campaign.toml` (2: arms are TOML tables, no longer
/// arm-file text in a string).
pub(crate) const CAMPAIGN_FORMAT: &str = "aacmm-campaign-2";

/// The poses file of a campaign (encoder readings, degrees).
pub const POSES_FILE: &str = "poses.csv";
/// The reference-length file of a campaign (mm).
pub const LENGTHS_FILE: &str = "lengths.csv";
/// The true socket centres of a campaign (mm).
pub const SOCKETS_FILE: &str = "sockets.csv";
/// The true arm of a campaign (mm, degrees).
pub const TRUE_ARM_FILE: &str = "true_arm.toml";
/// The settings, seed and nominal arm of a campaign.
pub const CAMPAIGN_FILE: &str = "campaign.toml";

/// What `campaign.toml` holds.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CampaignFile {
    /// Always [`CAMPAIGN_FORMAT`].
    format: String,
    /// The library that wrote it (informational).
    generator: String,
    /// Joints of the nominal (and true) arm.
    joints: usize,
    settings: CampaignSettings,
    /// The nominal arm, an arm file as a table.
    #[serde(with = "arm_table")]
    nominal: Arm,
}

/// Just the format, to tell an old or foreign file from a broken one.
#[derive(Deserialize)]
struct Format {
    format: Option<String>,
}

/// The text of `campaign.toml` for a campaign on `nominal`: a comment, the
/// format, the settings (seed first) and the nominal arm as a table
/// (`[nominal]`, `[[nominal.joint]]`, `[nominal.probe]`).
pub(crate) fn campaign_to_toml(
    nominal: &Arm,
    settings: &CampaignSettings,
) -> Result<String, SimError> {
    let file = CampaignFile {
        format: CAMPAIGN_FORMAT.to_string(),
        generator: format!("aacmm-core {}", env!("CARGO_PKG_VERSION")),
        joints: nominal.params.joint_count(),
        settings: settings.clone(),
        nominal: nominal.clone(),
    };
    let body = toml::to_string(&file)
        .map_err(|e| SimError::setting("settings", format!("cannot be written as TOML: {e}")))?;
    Ok(format!(
        "# A simulated calibration campaign (aacmm simulate): every setting, the seed and the\n\
         # nominal arm. aacmm_core::simulate::read_campaign + simulate regenerate the identical\n\
         # files with the same build on the same platform.\n{body}"
    ))
}

/// Parses the text of `campaign.toml`; `file` names it in messages. Returns
/// the nominal arm and the settings, validated.
pub fn parse_campaign(text: &str, file: &str) -> Result<(Arm, CampaignSettings), SimError> {
    let located = |e: toml::de::Error| {
        let line = e.span().map_or(0, |s| {
            1 + text[..s.start.min(text.len())].matches('\n').count()
        });
        let message = e.message().to_string();
        if line > 0 {
            InputError::line_error(file, line, message)
        } else {
            InputError::file_error(file, message)
        }
    };
    let format = toml::from_str::<Format>(text).map_err(located)?.format;
    if format.as_deref() != Some(CAMPAIGN_FORMAT) {
        let found = format.map_or("none".to_string(), |f| format!("\"{f}\""));
        let message = format!("expected \"{CAMPAIGN_FORMAT}\", found {found}");
        return Err(InputError::field(file, 0, "format", message).into());
    }
    let parsed: CampaignFile = toml::from_str(text).map_err(located)?;
    let joints = parsed.nominal.params.joint_count();
    if parsed.joints != joints {
        return Err(InputError::field(
            file,
            0,
            "joints",
            format!("{} joints, but the nominal arm has {joints}", parsed.joints),
        )
        .into());
    }
    parsed.settings.validate(joints)?;
    Ok((parsed.nominal, parsed.settings))
}

/// Reads `campaign.toml` (see [`parse_campaign`]).
///
/// ```no_run
/// use aacmm_core::simulate::{read_campaign, simulate};
/// let (nominal, settings) = read_campaign(std::path::Path::new("out/campaign.toml"))?;
/// let again = simulate(&nominal, &settings)?;
/// # Ok::<(), aacmm_core::simulate::SimError>(())
/// ```
pub fn read_campaign(path: &Path) -> Result<(Arm, CampaignSettings), SimError> {
    let (file, text) = crate::io::text::read_settings(path)?;
    parse_campaign(&text, &file)
}

/// Writes the campaign into `dir` (created if missing): `poses.csv` (encoder
/// readings, degrees), `lengths.csv` (mm; when there are no reference
/// lengths it is not written, and a stale one from an earlier campaign is
/// removed), `sockets.csv` (true centres, mm), `true_arm.toml` (mm, degrees)
/// and `campaign.toml`. Returns the paths written. Deterministic bytes.
///
/// ```no_run
/// use aacmm_core::{domain::Arm, params::DhParams, simulate::*};
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let settings = CampaignSettings::new(1, ErrorModel::Paper, 10, 10);
/// let campaign = simulate(&nominal, &settings)?;
/// write_campaign(std::path::Path::new("out"), &campaign, &settings)?;
/// # Ok::<(), aacmm_core::simulate::SimError>(())
/// ```
pub fn write_campaign(
    dir: &Path,
    campaign: &Campaign,
    settings: &CampaignSettings,
) -> Result<Vec<PathBuf>, SimError> {
    let io = |path: &Path, e: std::io::Error| {
        SimError::from(InputError::io(path.display().to_string(), e))
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    // The small files' text first, so that a refusal in any of them (a
    // label that does not read back) comes before anything is written; the
    // poses, most of the bytes, are then streamed into their file rather
    // than held whole (10⁶ touches: 118 MB).
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    let lengths_path = dir.join(LENGTHS_FILE);
    if !campaign.lengths.is_empty() {
        let mut lengths = Vec::new();
        write_lengths(&mut lengths, &campaign.lengths).map_err(|e| io(&lengths_path, e))?;
        files.push((lengths_path.clone(), lengths));
    }

    let mut sockets = Vec::new();
    let (labels, xyz): (Vec<&str>, Vec<[f64; 3]>) = campaign
        .sockets
        .iter()
        .map(|(l, p)| (l.as_str(), *p))
        .unzip();
    write_points(&mut sockets, &labels, &xyz).map_err(|e| io(&dir.join(SOCKETS_FILE), e))?;
    files.push((dir.join(SOCKETS_FILE), sockets));

    let true_arm = arm_to_toml(&campaign.true_arm, LengthUnit::Mm, AngleUnit::Deg);
    files.push((dir.join(TRUE_ARM_FILE), true_arm.into_bytes()));

    let toml = campaign_to_toml(&campaign.nominal, settings)?;
    files.push((dir.join(CAMPAIGN_FILE), toml.into_bytes()));

    let poses = dir.join(POSES_FILE);
    crate::io::write_atomic_with(&poses, |w| write_poses(w, &campaign.poses, AngleUnit::Deg))
        .map_err(|e| io(&poses, e))?;
    if campaign.lengths.is_empty() && lengths_path.exists() {
        std::fs::remove_file(&lengths_path).map_err(|e| io(&lengths_path, e))?;
    }
    for (path, bytes) in &files {
        crate::io::write_atomic(path, bytes).map_err(|e| io(path, e))?;
    }
    let written = files.into_iter().map(|(p, _)| p);
    Ok(std::iter::once(poses).chain(written).collect())
}

/// Serde adapter: an [`Arm`] as an arm-file table, in mm and degrees when
/// that reads back bit-exactly, else in mm and radians. Read through
/// [`toml::Table`] and arm-file text, so that it works where serde buffers the
/// value (the internally tagged `model = "file"`) and is checked like an arm
/// file; messages name the field, and the table's line is the caller's.
pub(crate) mod arm_table {
    use serde::de::Error as _;

    use super::*;

    pub(crate) fn serialize<S: serde::Serializer>(arm: &Arm, s: S) -> Result<S::Ok, S::Error> {
        ArmFile::exact(arm).serialize(s)
    }

    pub(crate) fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Arm, D::Error> {
        let table = toml::Table::deserialize(d)?;
        let text = toml::to_string(&table).map_err(D::Error::custom)?;
        match parse_arm(&text, "arm") {
            Ok((arm, _)) => Ok(arm),
            Err(e) => Err(D::Error::custom(match e.field_name() {
                Some(field) => format!("field `{field}`: {}", e.message()),
                None => e.message(),
            })),
        }
    }
}
