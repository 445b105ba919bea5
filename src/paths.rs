//! Output paths, checked before any work is done: a command that can only
//! fail at the end — or that would overwrite its own input — says so at once.
//!
//! One rule for every command that writes (README, "Writing"): an output
//! is never overwritten silently. An output file that exists, or an output
//! directory that holds results of any aacmm command
//! ([`aacmm_core::report::earlier_results`] names them), is refused unless `--force`;
//! `--force` overwrites the command's own files and deletes nothing.
//! Devices (`/dev/stdout`) are always written.

use std::fs;
use std::path::Path;

use anyhow::{Result, bail};

/// An input of the command: the flag that gave it, and its path.
pub type Input<'a> = (&'a str, &'a Path);

/// `path`, given with `flag`, can be written as a file: it is not a
/// directory, its directory exists, it is none of the `inputs`, and
/// (unless `force`) it is not a file that exists already.
pub fn check_output_file(flag: &str, path: &Path, inputs: &[Input], force: bool) -> Result<()> {
    let shown = path.display();
    if path.as_os_str().is_empty() {
        bail!("{flag}: the output path is empty");
    }
    if path.is_dir() {
        bail!("{flag} {shown}: is a directory; give a file name");
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match fs::metadata(parent) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => bail!("{flag} {shown}: {} is not a directory", parent.display()),
        Err(_) => bail!(
            "{flag} {shown}: directory {} does not exist",
            parent.display()
        ),
    }
    not_an_input(flag, path, inputs)?;
    let existing = fs::metadata(path).is_ok_and(|m| m.is_file());
    if existing && !force {
        bail!("{flag} {shown}: already exists; give --force to overwrite it, or another name");
    }
    Ok(())
}

/// `dir`, given with `flag`, can take the files `names`: it is a directory or
/// does not exist yet in a directory that does (it will be created, as
/// `mkdir` would: a missing parent is more likely a typo than a wish), none
/// of the files is a directory, none is one of the `inputs`, and (unless
/// `force`) it holds no earlier results of any aacmm command — its own, to
/// be overwritten, or another's, to be mixed in with.
pub fn check_output_dir(
    flag: &str,
    dir: &Path,
    names: &[&str],
    inputs: &[Input],
    force: bool,
) -> Result<()> {
    let shown = dir.display();
    if dir.as_os_str().is_empty() {
        bail!("{flag}: the output directory is empty");
    }
    if dir.exists() && !dir.is_dir() {
        bail!("{flag} {shown}: exists and is not a directory");
    }
    if !dir.exists() {
        let parent = match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !parent.is_dir() {
            bail!(
                "{flag} {shown}: directory {} does not exist; only the last directory of \
                 {flag} is created (create the others first)",
                parent.display()
            );
        }
    }
    for name in names {
        let path = dir.join(name);
        if path.is_dir() {
            bail!(
                "{flag} {shown}: {} is a directory, where the file {name} is written",
                path.display()
            );
        }
        not_an_input(flag, &path, inputs)?;
    }
    let found = aacmm_core::report::earlier_results(dir);
    if !force && !found.is_empty() {
        let shown: Vec<&str> = found.iter().take(4).copied().collect();
        bail!(
            "{flag} {}: already holds earlier results ({}{}); give --force to write over \
             them, or another directory",
            dir.display(),
            shown.join(", "),
            if found.len() > shown.len() {
                ", …"
            } else {
                ""
            }
        );
    }
    Ok(())
}

/// An output must not be an input: writing it would destroy what is read.
fn not_an_input(flag: &str, out: &Path, inputs: &[Input]) -> Result<()> {
    for (input_flag, input) in inputs {
        if same_file(out, input) {
            bail!(
                "{flag}: {} is the {input_flag} input ({}); writing it would overwrite the \
                 input — choose another output",
                out.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// The same path as written, or the same existing regular file (after
/// symbolic links; on Unix, also through hard links). Devices and pipes
/// (`--data /dev/stdin --out /dev/stdout` on a terminal) lose nothing by
/// being written.
fn same_file(a: &Path, b: &Path) -> bool {
    if a == b {
        return true;
    }
    let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) else {
        // A file that does not exist cannot be an existing input.
        return false;
    };
    if !(ma.is_file() && mb.is_file()) {
        return false;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if (ma.dev(), ma.ino()) == (mb.dev(), mb.ino()) {
            return true;
        }
    }
    let _ = (ma, mb);
    matches!(
        (fs::canonicalize(a), fs::canonicalize(b)),
        (Ok(x), Ok(y)) if x == y
    )
}
