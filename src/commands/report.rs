//! Writing a report — the page and its figures — into a directory, with
//! every file checked.

use std::path::{Path, PathBuf};

use aacmm_core::report::{HTML_FILE, Report};
use anyhow::{Context, Result};

/// Writes every file of `report` into `dir` (created if missing); returns
/// the page's path.
pub fn write(flag: &str, dir: &Path, report: &Report) -> Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{flag} {}: cannot create", dir.display()))?;
    for (name, text) in report.files() {
        let path = dir.join(name);
        aacmm_core::io::write_atomic(&path, text)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(dir.join(HTML_FILE))
}
