//! Writes that either happen whole or not at all.
//!
//! A file written in place and interrupted — a full file system, a killed
//! process — is left truncated under its final name, where the next
//! command reads it as a result. Every output is written to a temporary
//! file beside its target (same directory, so the same file system), made
//! durable, then renamed over the target: a rename is atomic, so the target
//! holds the old bytes or the new ones, never a part. The directory is
//! synced after the rename, so that the new name itself survives a power
//! cut. On failure the temporary file is removed.
//!
//! The temporary file's name is unique (`tempfile` draws it and creates the
//! file exclusively), so two writers of one target — two threads of a host
//! program, two processes — each write their own temporary file and the
//! target ends as one of them, whole. Its mode is a new file's (`0666`
//! less the umask), as the target's would be if written in place.
//!
//! A target that is not a regular file — `/dev/null`, `/dev/stdout`, a
//! pipe, a symbolic link — is written in place: renaming over it would
//! replace the device or the link with a file.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

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
    let (dir, name) = split(path)?;
    // Dropped on any error before `persist`: the temporary file goes with it.
    let mut temp = temporary_in(dir, name)?;
    let mut w = BufWriter::new(temp.as_file_mut());
    fill(&mut w)?;
    w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    temp.persist(path).map_err(|e| e.error)?;
    sync_directory(dir)
}

/// The directory a target is written in (`.` for a bare file name) and the
/// target's file name.
fn split(path: &Path) -> io::Result<(&Path, &std::ffi::OsStr)> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a file name (empty, `..` or a root)",
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Ok((dir, name))
}

/// A new, uniquely named `.<name>.<random>.aacmm.tmp` in `dir`, created
/// exclusively with a new file's mode.
fn temporary_in(dir: &Path, name: &std::ffi::OsStr) -> io::Result<tempfile::NamedTempFile> {
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(".");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".aacmm.tmp");
    // tempfile's own default is 0600 (a secret); an output is not one.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    builder.tempfile_in(dir)
}

/// Makes the rename durable: the directory entry is data of the directory,
/// which `sync_all` on the file does not write. Where a directory cannot be
/// opened as a file (not Unix) there is nothing to sync.
fn sync_directory(dir: &Path) -> io::Result<()> {
    #[cfg(unix)]
    File::open(dir)?.sync_all()?;
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A fresh directory of the system's temporary one, removed when the
    /// test ends (pass or fail): one per test and process id, so that runs
    /// do not pile up there.
    struct Scratch(PathBuf);

    impl std::ops::Deref for Scratch {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn dir(name: &str) -> Scratch {
        let d = std::env::temp_dir().join(format!("aacmm-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Scratch(d)
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
        let left: Vec<_> = std::fs::read_dir(&*d).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        write_atomic(&target, "new\n").unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new\n");
    }

    /// Two threads of one process write the same target again and again:
    /// every write succeeds, the target is always one writer's text whole,
    /// and no temporary file is left (the temporary's name was the process
    /// id, so the two collided: one renamed the other's half-written file,
    /// or failed on its vanished temporary).
    #[test]
    fn two_threads_writing_one_target_both_complete_whole() {
        let d = dir("race");
        let target = d.join("calibration.json");
        // Large enough that a write is many system calls, not one.
        let texts: [String; 2] = ["a", "b"].map(|c| c.repeat(1 << 20));
        std::thread::scope(|s| {
            for text in &texts {
                let (target, texts) = (&target, &texts);
                s.spawn(move || {
                    for _ in 0..20 {
                        write_atomic(target, text).unwrap();
                        let read = std::fs::read_to_string(target).unwrap();
                        assert!(texts.contains(&read), "a torn file: {} bytes", read.len());
                    }
                });
            }
        });
        let left: Vec<_> = std::fs::read_dir(&*d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, [std::ffi::OsString::from("calibration.json")]);
    }

    #[cfg(unix)]
    #[test]
    fn the_target_has_a_new_files_mode_not_a_temporarys() {
        use std::os::unix::fs::PermissionsExt;
        let d = dir("mode");
        let target = d.join("calibrated.toml");
        write_atomic(&target, "x").unwrap();
        let plain = d.join("plain");
        File::create(&plain).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&target), mode(&plain));
    }

    #[test]
    fn a_bare_file_name_is_written_in_the_current_directory() {
        assert_eq!(split(Path::new("out.json")).unwrap().0, Path::new("."));
        assert_eq!(split(Path::new("a/out.json")).unwrap().0, Path::new("a"));
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
