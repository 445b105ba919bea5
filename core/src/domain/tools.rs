//! Several tool points on one arm: markers on one rigid body, SMRs,
//! styli. Their `[[tool]]` tables are described in [`crate::io::tools`].

use std::collections::HashMap;

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

/// The tools rows may name: per name, its index
/// (`0` the default tool, `k` the arm's `k`-th `[[tool]]`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ToolNames {
    names: Vec<String>,
    /// Per name, its nominal offset (mm; `None` for the default tool,
    /// whose offset is the arm's probe).
    offsets: Vec<Option<[f64; 3]>>,
    /// Per name, its ball's diameter when stated (mm; `None` for the
    /// default tool, whose ball is the arm's `[probe]`'s).
    balls: Vec<Option<f64>>,
    index: HashMap<String, u32>,
}

impl ToolNames {
    /// The default tool and `tools`, in order.
    pub fn of(tools: &[Tool]) -> ToolNames {
        let names: Vec<String> = std::iter::once(DEFAULT_TOOL.to_string())
            .chain(tools.iter().map(|t| t.name.clone()))
            .collect();
        let index = (names.iter().enumerate())
            .map(|(k, n)| (n.clone(), k as u32))
            .collect();
        let offsets = std::iter::once(None)
            .chain(tools.iter().map(|t| Some(t.offset)))
            .collect();
        let balls = std::iter::once(None)
            .chain(tools.iter().map(|t| t.ball_diameter_mm))
            .collect();
        ToolNames {
            names,
            offsets,
            balls,
            index,
        }
    }

    /// The ball diameter of the tool named `name` (mm), `None` for the
    /// default tool, a tool without a ball, or a name not known.
    pub fn ball_diameter(&self, name: &str) -> Option<f64> {
        let k = *self.index.get(name)?;
        self.balls[k as usize]
    }

    /// The nominal offset of the tool named `name` (mm, last joint's
    /// frame), `None` for the default tool or a name not known.
    pub fn offset(&self, name: &str) -> Option<[f64; 3]> {
        let k = *self.index.get(name)?;
        self.offsets[k as usize]
    }

    /// Every name, the default tool's first.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The index of the tool named `name`, if known.
    pub(crate) fn index_of(&self, name: &str) -> Option<u32> {
        self.index.get(name).copied()
    }
}
