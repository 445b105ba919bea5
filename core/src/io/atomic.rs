//! Writes that either happen whole or not at all.
//!
//! A file written in place and interrupted — a full file system, a killed
//! process — is left truncated under its final name, where the next
//! command reads it as a result. Every output is written to a temporary
//! file beside its target (same directory, so the same file system), made
//! durable, then renamed over the target: a rename is atomic, so the target
//! holds the old bytes or the new ones, never a part. On failure the
//! temporary file is removed.
//!
//! A target that is not a regular file — `/dev/null`, `/dev/stdout`, a
//! pipe, a symbolic link — is written in place: renaming over it would
//! replace the device or the link with a file.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (see the module).
///
/// # Errors
///
/// The system's, from creating, writing, syncing or renaming; the target is
/// then untouched.
pub fn write_atomic(path: &Path, bytes: impl AsRef<[u8]>) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes.as_ref()))
}

/// Writes what `fill` writes to `path` atomically (see the module).
///
/// # Errors
///
/// As [`write_atomic`], and `fill`'s.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let special = std::fs::symlink_metadata(path).is_ok_and(|m| {
        let t = m.file_type();
        !t.is_file() && !t.is_dir()
    });
    if special {
        let mut w = BufWriter::new(
            std::fs::OpenOptions::new()
                .write(true)
                .truncate(true)
                .open(path)?,
        );
        fill(&mut w)?;
        return w.flush();
    }
    let temp = temporary_beside(path)?;
    let result = (|| {
        let mut w = BufWriter::new(File::create(&temp)?);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&temp, path)
    })();
    if result.is_err() {
        // Best effort: the error that matters is the write's.
        let _ = std::fs::remove_file(&temp);
    }
    result
}

/// `.<name>.aacmm-<pid>.tmp` in the target's directory.
fn temporary_beside(path: &Path) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a file name (empty, `..` or a root)",
        )
    })?;
    let mut temp = std::ffi::OsString::from(".");
    temp.push(name);
    temp.push(format!(".aacmm-{}.tmp", std::process::id()));
    Ok(path.with_file_name(temp))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("aacmm-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let d = dir("fail");
        let target = d.join("calibration.json");
        write_atomic(&target, "old\n").unwrap();
        let e = write_atomic_with(&target, |w| {
            w.write_all(b"half of the new")?;
            Err(io::Error::other("no space left on device"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "no space left on device");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "old\n");
        let left: Vec<_> = std::fs::read_dir(&d).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        write_atomic(&target, "new\n").unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new\n");
    }

    #[test]
    fn a_device_is_written_in_place_not_replaced() {
        let null = Path::new("/dev/null");
        if null.exists() {
            write_atomic(null, "discarded").unwrap();
            assert!(!std::fs::metadata(null).unwrap().file_type().is_file());
        }
    }

    #[test]
    fn a_path_without_a_file_name_is_refused() {
        for p in ["", "/", ".."] {
            let e = write_atomic(Path::new(p), "x").unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{p:?}");
        }
    }
}
