//! Atomic file replacement: write to a temporary file in the destination's
//! directory, `fsync` it, rename it over the destination, `fsync` the
//! directory. A crash or error at any point leaves either the old file or
//! the new one, never half a file.

use super::{FormatError, ProbeFile};
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why a `.probes` file was not written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// The contents fail validation (the file would be refused by readers).
    #[error("invalid probe file contents: {0}")]
    Invalid(#[from] FormatError),
    /// The filesystem refused (the destination is left untouched).
    #[error("cannot write {path}: {source}")]
    Io {
        /// The destination file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
}

/// Validates, serializes and atomically writes `file` to `path`.
pub fn write_probe_file(path: impl AsRef<Path>, file: &ProbeFile) -> Result<(), WriteError> {
    let bytes = file.to_bytes()?;
    write_atomic(path, &bytes)
}

/// Atomically replaces `path` with `bytes` (temporary file in the same
/// directory, fsync, rename, fsync of the directory where supported).
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic_with(path.as_ref(), |f| f.write_all(bytes))
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Creates [`write_atomic`]'s temporary file for `path`: a fresh name
/// (unique per process and call) in `path`'s directory, opened new for
/// writing. Returns the directory, the temporary's path and the file.
fn create_temporary(path: &Path) -> Result<(PathBuf, PathBuf, File), WriteError> {
    let io_err = |source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    let name = path
        .file_name()
        .ok_or_else(|| io_err(io::Error::new(io::ErrorKind::InvalidInput, "no file name")))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = dir.join(format!(
        ".{}.{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(io_err)?;
    Ok((dir, tmp, file))
}

/// Checks, before long work, that [`write_atomic`] could write `path`: its
/// directory exists and takes a new file (one is created and removed), and
/// `path` is not a directory. Nothing at `path` is touched. A bake checks
/// its outputs first so that a mistyped folder costs nothing, not the bake.
pub fn check_writable(path: impl AsRef<Path>) -> Result<(), WriteError> {
    let path = path.as_ref();
    let io_err = |source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    if path.is_dir() {
        return Err(io_err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "is a directory",
        )));
    }
    let (_, tmp, file) = create_temporary(path)?;
    drop(file);
    fs::remove_file(&tmp).map_err(io_err)
}

/// [`write_atomic`] with the contents produced by `fill` (tests inject
/// failures here).
pub(crate) fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut File) -> io::Result<()>,
) -> Result<(), WriteError> {
    let io_err = |source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (dir, tmp, mut file) = create_temporary(path)?;
    let result = (|| {
        fill(&mut file)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)?;
        // Persist the rename itself. Opening a directory fails on some
        // platforms (Windows); the rename is still atomic there.
        if let Ok(d) = File::open(&dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(io_err(e));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Parts;
    use glam::Vec3;

    fn small(v: f32) -> ProbeFile {
        ProbeFile::cloud(vec![Vec3::ZERO, Vec3::ONE], 2, &[Vec3::splat(v); 8]).unwrap()
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn check_writable_refuses_a_missing_folder_and_a_folder_and_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let ok = dir.path().join("out.probes");
        check_writable(&ok).unwrap();
        assert!(!ok.exists(), "the check must not create the file");
        assert!(leftovers(dir.path()).is_empty());
        fs::write(&ok, b"old").unwrap();
        check_writable(&ok).unwrap();
        assert_eq!(fs::read(&ok).unwrap(), b"old");
        let missing = dir.path().join("no such folder").join("out.probes");
        assert!(matches!(
            check_writable(&missing),
            Err(WriteError::Io { .. })
        ));
        assert!(matches!(
            check_writable(dir.path()),
            Err(WriteError::Io { .. })
        ));
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bake.probes");
        write_probe_file(&path, &small(1.0)).unwrap();
        write_probe_file(&path, &small(2.0)).unwrap();
        assert_eq!(ProbeFile::load(&path).unwrap(), small(2.0));
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn a_write_failing_halfway_leaves_the_old_file_intact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bake.probes");
        write_probe_file(&path, &small(1.0)).unwrap();
        let old = fs::read(&path).unwrap();
        let new = small(2.0).to_bytes().unwrap();
        // Simulates a bake interrupted mid-write (disk full, killed writer).
        let err = write_atomic_with(&path, |f| {
            f.write_all(&new[..new.len() / 2])?;
            Err(io::Error::new(io::ErrorKind::StorageFull, "disk full"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("bake.probes"), "{err}");
        assert_eq!(fs::read(&path).unwrap(), old);
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn invalid_contents_are_refused_before_touching_the_disk() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bake.probes");
        write_probe_file(&path, &small(1.0)).unwrap();
        let old = fs::read(&path).unwrap();
        let mut bad = small(2.0);
        bad.probe_set_mut().positions[1].y = f32::INFINITY;
        assert!(matches!(
            write_probe_file(&path, &bad),
            Err(WriteError::Invalid(FormatError::NonFinite { .. }))
        ));
        assert_eq!(fs::read(&path).unwrap(), old);
    }

    #[test]
    fn a_failing_rename_keeps_the_destination_and_cleans_up() {
        let dir = tempfile::tempdir().unwrap();
        // The destination is a non-empty directory: rename onto it fails.
        let path = dir.path().join("occupied");
        fs::create_dir(&path).unwrap();
        fs::write(path.join("keep"), b"x").unwrap();
        assert!(matches!(
            write_probe_file(&path, &small(1.0)),
            Err(WriteError::Io { .. })
        ));
        assert_eq!(fs::read(path.join("keep")).unwrap(), b"x");
        assert!(leftovers(dir.path()).is_empty());
        // A missing directory is an error naming the path, not a panic.
        let missing = dir.path().join("no/such/dir/x.probes");
        let err = write_probe_file(&missing, &small(1.0)).unwrap_err();
        assert!(err.to_string().contains("x.probes"));
    }
}
