//! The `[[tool]]` tables of an arm file, and the tool names a data file's
//! `tool` column may use ([`ToolNames`]). The tools themselves
//! ([`crate::domain::Tool`]): several tool points on one arm — markers on
//! one rigid body, SMRs, styli.
//!
//! An arm file lists them after its `[probe]`:
//!
//! ```toml
//! [[tool]]
//! name = "smr2"
//! offset_mm = [40.0, 0.0, 95.0]   # in the last joint's frame, like [probe]
//!
//! [[tool]]
//! name = "long"
//! offset_mm = [0.0, 0.0, 180.0]
//! ball_diameter_mm = 3.0          # optional: a probe's ball (sphere files)
//! ```
//!
//! `offset_mm` is the point's nominal centre in the last joint's frame
//! (the frame `[probe]`'s `x, y, z` are in), in mm whatever `length_unit`
//! says (the name carries the unit, like `ball_diameter_mm`). The `[probe]`
//! stays the default tool, named [`DEFAULT_TOOL`] in messages; a row of
//! data without a `tool` cell is the default tool's. A calibration fits
//! each tool's offset that some row names (its own three columns,
//! `tool.NAME.x/y/z`) and writes it back to the calibrated arm's
//! `[[tool]]`; an arm without `[[tool]]` reads and writes as before.

use crate::domain::{DEFAULT_TOOL, ToolNames};
use crate::error::{InputError, quoted};

/// Why the name `name` of a `[[tool]]` is refused (`None`: accepted),
/// `seen` the names before it.
pub(crate) fn name_refused(name: &str, seen: &[&str]) -> Option<String> {
    if name.trim().is_empty() {
        Some("[[tool]]: an empty name (name each tool point)".to_string())
    } else if name.trim() != name {
        Some(format!(
            "[[tool]] {}: a name with surrounding whitespace (it would not match a `tool` cell, \
             which is trimmed)",
            quoted(name)
        ))
    } else if name == DEFAULT_TOOL {
        Some(format!(
            "[[tool]] {}: the default tool's name (the [probe]): name the tool otherwise",
            quoted(name)
        ))
    } else if seen.contains(&name) {
        Some(format!(
            "[[tool]] {}: a second tool of this name (each tool's name is unique)",
            quoted(name)
        ))
    } else {
        None
    }
}

/// What a data file's reader adds to [`ToolNames`]: a `tool` cell resolved
/// in the file's words.
impl ToolNames {
    /// The index of the tool of cell `cell` (empty: the default tool), or
    /// an error at `file:line` naming the field `tool` and the known tools.
    ///
    /// # Errors
    ///
    /// A name the arm does not know.
    pub fn of_cell(&self, cell: &str, file: &str, line: usize) -> Result<u32, InputError> {
        if cell.is_empty() {
            return Ok(0);
        }
        self.index_of(cell).ok_or_else(|| {
            let known: Vec<String> = self.names().iter().map(|n| quoted(n)).collect();
            InputError::field(
                file,
                line,
                "tool",
                format!(
                    "{}: a tool the arm does not know (its tools: {}; list a tool point in the \
                     arm file as a [[tool]] with its name and offset_mm)",
                    quoted(cell),
                    known.join(", ")
                ),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::{Arm, Tool, block_name};
    use crate::io::{AngleUnit, LengthUnit, arm_to_toml, parse_arm};
    use crate::params::DhParams;

    fn arm_text(tools: &str) -> String {
        let arm = Arm::without_limits("n", DhParams::paper_nominal());
        arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg) + tools
    }

    #[test]
    fn tools_round_trip_in_mm_whatever_the_length_unit() {
        let text = arm_text(
            "\n[[tool]]\nname = \"smr2\"\noffset_mm = [40, 0.5, 95]\n\n[[tool]]\nname = \"m3\"\noffset_mm = [-1e-3, 0, 0]\nball_diameter_mm = 3\n",
        );
        let (arm, _) = parse_arm(&text, "a.toml").unwrap();
        assert_eq!(arm.tools.len(), 2);
        assert_eq!(arm.tools[0].name, "smr2");
        assert_eq!(arm.tools[0].offset, [40.0, 0.5, 95.0]);
        assert_eq!(arm.tools[1].offset, [-1e-3, 0.0, 0.0]);
        assert_eq!(
            (arm.tools[0].ball_diameter_mm, arm.tools[1].ball_diameter_mm),
            (None, Some(3.0))
        );
        assert_eq!(block_name(&arm.tools[0].name), "tool.smr2");
        for lu in [LengthUnit::Mm, LengthUnit::M] {
            let back = parse_arm(&arm_to_toml(&arm, lu, AngleUnit::Rad), "b.toml")
                .unwrap()
                .0;
            assert_eq!(back.tools, arm.tools);
        }
        // No tools: no `[[tool]]` written.
        let plain = Arm::without_limits("n", DhParams::paper_nominal());
        assert!(!arm_to_toml(&plain, LengthUnit::Mm, AngleUnit::Deg).contains("tool"));
    }

    #[test]
    fn bad_tools_are_refused_by_line_and_field() {
        let base = arm_text("");
        let line = base.lines().count() + 3;
        let refused = |tools: &str| {
            parse_arm(&(base.clone() + tools), "a.toml")
                .unwrap_err()
                .to_string()
        };
        let two = "\n[[tool]]\nname = \"m\"\noffset_mm = [1, 2, 3]\n";
        let e = refused(&two.repeat(2));
        assert!(
            e.starts_with(&format!(
                "a.toml:{}: field `name`: [[tool]] `m`: a second",
                line + 4
            )),
            "{e}"
        );
        let e = refused("\n[[tool]]\nname = \"m\"\noffset_mm = [1, nan, 3]\n");
        assert!(
            e.starts_with(&format!(
                "a.toml:{}: field `offset_mm`: [[tool]] `m`: ",
                line + 1
            )),
            "{e}"
        );
        assert!(e.contains("not a finite number"), "{e}");
        let e = refused("\n[[tool]]\nname = \"\"\noffset_mm = [1, 2, 3]\n");
        assert!(
            e.starts_with(&format!("a.toml:{line}: field `name`: ")),
            "{e}"
        );
        assert!(e.contains("empty"), "{e}");
        let e = refused("\n[[tool]]\nname = \"probe\"\noffset_mm = [1, 2, 3]\n");
        assert!(e.contains("default tool"), "{e}");
        let e = refused("\n[[tool]]\nname = \"m\"\noffset_mm = [1, 2]\n");
        assert!(
            e.contains("field `offset_mm`") && e.contains("found 2 values"),
            "{e}"
        );
        let e =
            refused("\n[[tool]]\nname = \"m\"\noffset_mm = [1, 2, 3]\nball_diameter_mm = 0.003\n");
        assert!(
            e.starts_with(&format!(
                "a.toml:{}: field `ball_diameter_mm`: [[tool]] `m`: a ball of 0.003 mm",
                line + 2
            )) && e.contains("metres"),
            "{e}"
        );
        let e = refused("\n[[tool]]\nname = \"m\"\noffset = [1, 2, 3]\n");
        assert!(e.contains("offset"), "{e}");
    }

    #[test]
    fn tool_names_are_looked_up_and_unknown_ones_named_with_the_known() {
        let tools = ToolNames::of(&[Tool {
            name: "smr2".into(),
            offset: [1.0, 2.0, 3.0],
            ball_diameter_mm: Some(3.0),
        }]);
        assert_eq!(tools.ball_diameter("smr2"), Some(3.0));
        assert_eq!(tools.ball_diameter("probe"), None);
        assert_eq!(tools.of_cell("", "p.csv", 3).unwrap(), 0);
        assert_eq!(tools.of_cell("probe", "p.csv", 3).unwrap(), 0);
        assert_eq!(tools.of_cell("smr2", "p.csv", 3).unwrap(), 1);
        let e = tools.of_cell("smr3", "p.csv", 7).unwrap_err().to_string();
        assert!(e.starts_with("p.csv:7: field `tool`: `smr3`"), "{e}");
        assert!(e.contains("`probe`, `smr2`"), "{e}");
    }

    #[test]
    fn tool_names_are_refused_when_empty_default_or_repeated() {
        assert!(name_refused("", &[]).unwrap().contains("empty"));
        assert!(name_refused("probe", &[]).unwrap().contains("default"));
        assert!(name_refused("a", &["a"]).unwrap().contains("second"));
        assert!(name_refused(" a", &[]).unwrap().contains("whitespace"));
        assert_eq!(name_refused("b", &["a"]), None);
    }
}
