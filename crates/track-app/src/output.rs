//! Output: atomic files, output folders and standard output.
//!
//! - Every file is written to a temporary sibling and renamed into place, so an interrupted run
//!   leaves only complete files ([`write_atomic`], [`AtomicFile`]).
//! - Every command gets its outputs from one guard ([`OutputGuard`]): never onto or into an input,
//!   never over a file `track` did not write.
//! - An output folder is owned by one command at a time, and `track` removes or replaces only
//!   the files its manifest says it wrote there ([`OutputFolder`]).
//! - A path that already exists must be a regular file: a FIFO, a symbolic link, a device node or
//!   a folder in its place is refused ([`check_replaceable`]), because the rename would silently
//!   replace it (a FIFO by a file, `/dev/full` by a file when run as root, a symlink instead of its
//!   target).
//! - Standard output ([`print_stdout`]): a closed pipe (`track config full | head -c 10`) ends the
//!   command quietly with exit 0, as Unix tools do; any other failure (`> /dev/full`) is one line
//!   and exit 4.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::{AppError, Result};

mod folder;
mod guard;
pub use folder::{LOCK_NAME, MANIFEST_NAME, OutputFolder, TEMP_SUFFIX};
pub use guard::{OutputFile, OutputGuard};

/// The name used in messages for standard output.
pub const STDOUT_NAME: &str = "standard output";

/// Checks that `path` either does not exist or is a regular file (not followed through a symbolic
/// link), so that writing it replaces nothing but an earlier output.
///
/// # Errors
/// [`AppError::Write`] naming the path and what it is.
pub fn check_replaceable(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_file() => Ok(()),
        Ok(meta) => Err(AppError::Write {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                format!(
                    "it exists and is {}, not a regular file; refusing to replace it",
                    file_kind(&meta.file_type())
                ),
            ),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(source) => Err(AppError::Write {
            path: path.to_path_buf(),
            source: file_in_place_of_folder(path).unwrap_or(source),
        }),
    }
}

/// What a non-regular file is, for messages.
pub(super) fn file_kind(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        return "a folder";
    }
    if t.is_symlink() {
        return "a symbolic link";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device node";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// The folder an output path lives in (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// When a parent folder of `path` is a file, the error that says so. Creating or opening `path`
/// would otherwise fail with the system's bare "Not a directory" or "File exists".
fn file_in_place_of_folder(path: &Path) -> Option<std::io::Error> {
    let file = path
        .ancestors()
        .skip(1)
        .find(|a| std::fs::metadata(a).is_ok_and(|m| !m.is_dir()))?;
    Some(std::io::Error::new(
        std::io::ErrorKind::AlreadyExists,
        format!(
            "{} exists and is a file, not a folder, so nothing can be written in it",
            file.display()
        ),
    ))
}

/// Creates the folder `dir` (and its parents) for outputs, with a clear message when a
/// component is a file.
///
/// # Errors
/// [`AppError::Write`] naming the folder.
pub fn create_dir(dir: &Path) -> Result<()> {
    let wrap = |source| AppError::Write {
        path: dir.to_path_buf(),
        source,
    };
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => return Ok(()),
        Ok(_) => {
            return Err(wrap(std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "it exists and is a file, not a folder; give a folder, or a name that does not \
                 exist yet",
            )));
        }
        Err(_) => {}
    }
    if let Some(e) = file_in_place_of_folder(dir) {
        return Err(wrap(e));
    }
    std::fs::create_dir_all(dir).map_err(wrap)
}

/// A file being written atomically: a temporary sibling of its destination that becomes the
/// destination only on [`AtomicFile::commit`]. Dropped without committing (an error, an
/// interrupt), it is deleted and the destination is untouched.
pub struct AtomicFile {
    path: PathBuf,
    writer: std::io::BufWriter<tempfile::NamedTempFile>,
}

impl std::fmt::Debug for AtomicFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AtomicFile")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl AtomicFile {
    /// Starts writing `path`: checks that it is absent or a regular file, creates its folder and
    /// the temporary file.
    ///
    /// # Errors
    /// [`AppError::Write`] as [`check_replaceable`], or when the folder or the temporary file
    /// cannot be created.
    pub fn create(path: &Path) -> Result<Self> {
        check_replaceable(path)?;
        folder::record(path)?;
        let wrap = |source| AppError::Write {
            path: path.to_path_buf(),
            source,
        };
        let dir = parent_dir(path);
        create_dir(dir)?;
        let tmp = tempfile::Builder::new()
            .prefix(&folder::temp_prefix(path))
            .suffix(TEMP_SUFFIX)
            .tempfile_in(dir)
            .map_err(wrap)?;
        Ok(Self {
            path: path.to_path_buf(),
            writer: std::io::BufWriter::with_capacity(1 << 16, tmp),
        })
    }

    /// The destination.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The error of a failed write to this file.
    pub fn error(&self, source: std::io::Error) -> AppError {
        AppError::Write {
            path: self.path.clone(),
            source,
        }
    }

    /// Flushes, syncs and renames the file into place (checking again that the destination is
    /// not something other than a regular file).
    ///
    /// # Errors
    /// [`AppError::Write`].
    pub fn commit(self) -> Result<()> {
        let path = self.path;
        let wrap = |source| AppError::Write {
            path: path.clone(),
            source,
        };
        let tmp = self.writer.into_inner().map_err(|e| wrap(e.into_error()))?;
        // Temporary files are created private (0600); outputs are ordinary files, readable by
        // others as the user's umask would make them.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            tmp.as_file()
                .set_permissions(std::fs::Permissions::from_mode(0o644))
                .map_err(wrap)?;
        }
        tmp.as_file().sync_all().map_err(wrap)?;
        // Checked again just before the rename: the run may have lasted minutes.
        check_replaceable(&path)?;
        tmp.persist(&path).map_err(|e| wrap(e.error))?;
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.writer.write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer.flush()
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
///
/// # Errors
/// [`AppError::Write`] when `path` exists and is not a regular file, the folder cannot be
/// created or the file cannot be written.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes to `path` atomically through `fill`, which receives a buffered writer.
///
/// # Errors
/// [`AppError::Write`] when `path` exists and is not a regular file, the folder cannot be
/// created, `fill` fails or the rename fails.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    if let Err(e) = fill(&mut file) {
        return Err(file.error(e));
    }
    file.commit()
}

/// Checks that files can be created in the folder `dir` (creating it when absent) by creating
/// and deleting a temporary file, so that an unwritable output folder is found before any work.
///
/// # Errors
/// [`AppError::Write`] naming the folder.
pub fn probe_dir(dir: &Path) -> Result<()> {
    create_dir(dir)?;
    tempfile::Builder::new()
        .prefix(".track-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .and_then(|t| t.close())
        .map_err(|source| AppError::Write {
            path: dir.to_path_buf(),
            source,
        })
}

/// Maps an error writing standard output: a closed pipe becomes [`AppError::StdoutClosed`] (the
/// command ends quietly with exit 0), anything else [`AppError::Write`] (exit 4).
pub fn stdout_error(e: std::io::Error) -> AppError {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        AppError::StdoutClosed
    } else {
        AppError::Write {
            path: PathBuf::from(STDOUT_NAME),
            source: e,
        }
    }
}

/// Prints `text` to standard output and flushes it; use instead of `print!`, which panics when
/// standard output is closed or full.
///
/// # Errors
/// [`AppError::StdoutClosed`] when the reader went away (a closed pipe), [`AppError::Write`] when
/// standard output cannot be written (for example a full disk).
pub fn print_stdout(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// [`print_stdout`] with a newline after `text`, the replacement of `println!`.
///
/// # Errors
/// As [`print_stdout`].
pub fn println_stdout(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_complete_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/out.txt");
        write_atomic(&path, b"hello").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"hello");
        let leftovers: Vec<_> = std::fs::read_dir(path.parent().unwrap()).unwrap().collect();
        assert_eq!(leftovers.len(), 1);
    }

    #[test]
    fn failing_writer_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        let err = write_atomic_with(&path, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("interrupted"))
        })
        .unwrap_err();
        assert_eq!(err.exit_code(), 4);
        assert!(!path.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_regular_file_is_replaced_but_a_folder_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        std::fs::write(&path, b"old").unwrap();
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let folder = dir.path().join("folder");
        std::fs::create_dir(&folder).unwrap();
        let err = write_atomic(&folder, b"x").unwrap_err();
        assert_eq!(err.exit_code(), 4);
        assert!(err.to_string().contains("a folder"), "{err}");
        assert!(folder.is_dir());
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_is_refused_and_its_target_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.txt");
        std::fs::write(&target, b"precious").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let err = write_atomic(&link, b"x").unwrap_err();
        assert!(err.to_string().contains("symbolic link"), "{err}");
        assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"precious");
        // No temporary file is left beside them.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn dropped_atomic_file_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.gif");
        let mut f = AtomicFile::create(&path).unwrap();
        f.write_all(&[0; 1000]).unwrap();
        drop(f);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn output_folder_that_is_a_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("out");
        std::fs::write(&file, b"").unwrap();
        let err = probe_dir(&file).unwrap_err();
        assert_eq!(err.exit_code(), 4);
        assert!(err.to_string().contains("not a folder"), "{err}");
        probe_dir(&dir.path().join("new/sub")).unwrap();
        assert_eq!(
            std::fs::read_dir(dir.path().join("new/sub"))
                .unwrap()
                .count(),
            0
        );
    }
}
