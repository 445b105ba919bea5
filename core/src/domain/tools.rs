//! Several tool points on one arm: markers on one rigid body, SMRs,
//! styli. Their `[[tool]]` tables are described in [`crate::io::tools`].

use crate::error::quoted;
use crate::setting::Setting;

/// The name of the default tool, the arm file's `[probe]`.
pub const DEFAULT_TOOL: &str = "probe";

/// The prefix of a tool's parameter block: `tool.NAME`.
pub(crate) const TOOL_BLOCK_PREFIX: &str = "tool.";

/// One named tool point of an arm.
#[derive(Clone, Debug, PartialEq)]
pub struct Tool {
    /// Its name (not empty, not [`DEFAULT_TOOL`], unique on the arm).
    pub name: String,
    /// Its centre in the last joint's frame, mm.
    pub offset: [f64; 3],
    /// The diameter of its ball when it is a probe's (a stylus touching
    /// spheres), mm: what a sphere-surface row of this tool is offset by.
    pub ball_diameter_mm: Option<f64>,
}

/// The name of tool `name`'s parameter block.
pub(crate) fn block_name(name: &str) -> String {
    format!("{TOOL_BLOCK_PREFIX}{name}")
}

/// `arm` as its tool `name` sees it: the probe at the tool's offset, the
/// ball the tool's ([`DEFAULT_TOOL`]: `arm` itself) — what the commands'
/// `--tool NAME` computes with.
///
/// ```
/// use aacmm_core::domain::{Arm, Tool, arm_with_tool};
/// let mut arm = Arm::without_limits("a", aacmm_core::DhParams::paper_nominal());
/// arm.tools.push(Tool { name: "long".into(), offset: [0.0, 0.0, 200.0], ball_diameter_mm: Some(3.0) });
/// let long = arm_with_tool(&arm, "long").unwrap();
/// assert_eq!((long.params.probe, long.ball_diameter_mm), ([0.0, 0.0, 200.0], Some(3.0)));
/// assert_eq!(arm_with_tool(&arm, "probe").unwrap(), arm);
/// let e = arm_with_tool(&arm, "short").unwrap_err();
/// assert_eq!(e.field(), "tool");
/// assert!(e.reason.contains("`probe`, `long`"), "{e}");
/// ```
///
/// # Errors
///
/// An [`OptionError`](crate::error::OptionError) on `tool` naming the
/// arm's tools when it has none of that name.
pub fn arm_with_tool(
    arm: &super::Arm,
    name: &str,
) -> Result<super::Arm, crate::error::OptionError> {
    if name == DEFAULT_TOOL {
        return Ok(arm.clone());
    }
    let Some(tool) = arm.tools.iter().find(|t| t.name == name) else {
        let known: Vec<String> = std::iter::once(quoted(DEFAULT_TOOL))
            .chain(arm.tools.iter().map(|t| quoted(&t.name)))
            .collect();
        return Err(crate::error::OptionError::new(
            Setting::Tool,
            name,
            format!(
                "the arm has no such tool (its tools: {}; list one in the arm file as a [[tool]] \
                 with its name and offset_mm)",
                known.join(", ")
            ),
        ));
    };
    let mut out = arm.clone();
    out.params.probe = tool.offset;
    out.ball_diameter_mm = tool.ball_diameter_mm;
    Ok(out)
}
