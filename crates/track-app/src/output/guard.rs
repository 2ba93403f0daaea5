//! The output guard: the one way a command gets somewhere to write.
//!
//! Every command that writes a file builds an [`OutputGuard`] from the paths it reads, then asks it
//! for its output folder ([`OutputGuard::folder`]) or its single output file
//! ([`OutputGuard::file`]). The guard refuses, before anything is created or written (exit 4,
//! naming the path):
//!
//! 1. an output **onto** an input: the same file or folder, also through a symbolic link;
//! 2. an output **into** an input: a file or folder anywhere below an input folder, where it would
//!    be read back as data (a `track.gif` among the frames) or replace what the command reads;
//! 3. an output folder that **holds** an input;
//! 4. an output that is a symbolic link, or anything but a regular file or a folder;
//! 5. an output file that exists and was **not written by `track`**: `track` knows what it wrote
//!    from the manifest `.track-outputs` of the folder it wrote in (see [`OutputFolder`]), so a
//!    second run replaces its own earlier output and nothing else.
//!
//! A generator (an `xtask` command, or any program built on this crate) wires it in one line:
//!
//! ```no_run
//! # fn main() -> track_app::Result<()> {
//! # let (input, out) = (std::path::Path::new("clip"), std::path::Path::new("clip-zoomed"));
//! let _out = track_app::output::OutputGuard::new([input]).folder(out)?;
//! // ... write_atomic(&out.join("img/0001.jpg"), ...) as usual: every file below `out` is
//! // recorded in its manifest and checked against files of other origins.
//! # Ok(()) }
//! ```
//!
//! Keep the returned [`OutputFolder`] alive until the last file is written: it holds the folder's
//! lock and records each output. A single file is claimed and written with
//! `OutputGuard::new(inputs).file(path)?.write(bytes)`.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::folder::{MANIFEST_NAME, OutputFolder, is_listed, write_error};
use super::{check_replaceable, write_atomic};
use crate::Result;

/// The inputs of one command, against which every output is checked (see the module
/// documentation for the rules).
#[derive(Debug, Clone, Default)]
pub struct OutputGuard {
    /// Each input as given and resolved (symbolic links followed), when it exists.
    inputs: Vec<(PathBuf, PathBuf)>,
}

/// A single output file that the guard allowed: write it with [`OutputFile::write`].
#[derive(Debug)]
#[must_use = "an output file is claimed to be written"]
pub struct OutputFile {
    path: PathBuf,
}

impl OutputGuard {
    /// A guard for a command that reads `inputs` (files or folders; `-`, standard input, and
    /// paths that do not exist are ignored).
    pub fn new<P: AsRef<Path>>(inputs: impl IntoIterator<Item = P>) -> Self {
        let inputs = inputs
            .into_iter()
            .filter(|p| p.as_ref() != Path::new("-"))
            .filter_map(|p| {
                let p = p.as_ref();
                p.canonicalize().ok().map(|c| (p.to_path_buf(), c))
            })
            .collect();
        Self { inputs }
    }

    /// The inputs as given (those that exist).
    pub fn inputs(&self) -> Vec<&Path> {
        self.inputs.iter().map(|(p, _)| p.as_path()).collect()
    }

    /// Checks `target` (an output file or folder, existing or not) against the inputs: refused
    /// when it is one of them or lies in an input folder, or (a folder) when it holds one.
    ///
    /// # Errors
    /// [`crate::AppError::Write`] naming `target` and the input.
    pub fn check(&self, target: &Path, is_folder: bool) -> Result<()> {
        let resolved = resolve(target);
        for (given, input) in &self.inputs {
            let why = if resolved == *input {
                "it is an input of this command"
            } else if resolved.starts_with(input) {
                "it lies inside the input folder"
            } else if is_folder && input.starts_with(&resolved) {
                "the output folder contains the input"
            } else {
                continue;
            };
            return Err(write_error(
                target,
                format!(
                    "{why} {}; track would write over or among what it reads: choose an output \
                     outside every input",
                    given.display()
                ),
            ));
        }
        Ok(())
    }

    /// Opens `dir` as the command's output folder: checks it against the inputs ([`check`]),
    /// then [`OutputFolder`] refuses a symbolic link or a folder in use, takes the lock and
    /// removes what `track` wrote there before.
    ///
    /// [`check`]: OutputGuard::check
    ///
    /// # Errors
    /// [`crate::AppError::Write`] (exit 4) naming the folder.
    pub fn folder(&self, dir: &Path) -> Result<OutputFolder> {
        self.check(dir, true)?;
        OutputFolder::open(dir, &self.inputs())
    }

    /// Claims the single output file `path`: checked against the inputs ([`check`]), refused
    /// when it is not a regular file (a symbolic link, a folder), and refused when it exists
    /// but the manifest of its folder does not list it (a file of the user's). Nothing is
    /// created until [`OutputFile::write`].
    ///
    /// [`check`]: OutputGuard::check
    ///
    /// # Errors
    /// [`crate::AppError::Write`] (exit 4) naming the file.
    pub fn file(&self, path: &Path) -> Result<OutputFile> {
        self.check(path, false)?;
        check_replaceable(path)?;
        if std::fs::symlink_metadata(path).is_ok() && !is_listed(path) {
            return Err(write_error(
                path,
                format!(
                    "it exists and was not written by track (the {MANIFEST_NAME} beside it does \
                     not list it), so track will not replace it: move it away or choose another \
                     --out"
                ),
            ));
        }
        Ok(OutputFile {
            path: path.to_path_buf(),
        })
    }
}

impl OutputFile {
    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records the file in the manifest of its folder, then writes it atomically.
    ///
    /// # Errors
    /// [`crate::AppError::Write`] naming the file or the manifest.
    pub fn write(self, bytes: &[u8]) -> Result<()> {
        super::folder::record_single(&self.path)?;
        write_atomic(&self.path, bytes)
    }

    /// As [`OutputFile::write`], through a writer.
    ///
    /// # Errors
    /// As [`OutputFile::write`].
    pub fn write_with(
        self,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<()> {
        super::folder::record_single(&self.path)?;
        super::write_atomic_with(&self.path, fill)
    }
}

/// `path` with symbolic links resolved as far as it exists, and the rest appended (an output
/// usually does not exist yet).
fn resolve(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut rest = Vec::new();
    let mut at = absolute.as_path();
    loop {
        if let Ok(c) = at.canonicalize() {
            let mut r = c;
            for part in rest.iter().rev() {
                r.push(part);
            }
            return r;
        }
        match (at.parent(), at.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_owned());
                at = parent;
            }
            _ => return absolute,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_onto_into_or_holding_an_input_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let seq = dir.path().join("seq");
        std::fs::create_dir_all(seq.join("img")).unwrap();
        let gt = seq.join("groundtruth_rect.txt");
        std::fs::write(&gt, b"1,1,2,2\n").unwrap();
        let guard = OutputGuard::new([seq.as_path()]);
        for (target, folder) in [
            (seq.clone(), true),
            (seq.join("img"), true),
            (seq.join("img/new"), true),
            (dir.path().to_path_buf(), true),
            (gt.clone(), false),
            (seq.join("notes.md"), false),
        ] {
            let err = guard.check(&target, folder).unwrap_err();
            assert_eq!(err.exit_code(), 4, "{}", target.display());
        }
        guard.check(&dir.path().join("out"), true).unwrap();
        guard
            .check(&dir.path().join("seq-out/a.md"), false)
            .unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_link_into_an_input_is_seen_through() {
        let dir = tempfile::tempdir().unwrap();
        let seq = dir.path().join("seq");
        std::fs::create_dir(&seq).unwrap();
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&seq, &link).unwrap();
        let guard = OutputGuard::new([seq.as_path()]);
        assert!(guard.check(&link.join("out"), true).is_err());
        assert!(guard.file(&link.join("x.md")).is_err());
    }

    #[test]
    fn a_file_of_the_users_is_refused_and_an_own_output_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let notes = dir.path().join("notes.md");
        std::fs::write(&notes, b"mine").unwrap();
        let guard = OutputGuard::new::<&Path>([]);
        let err = guard.file(&notes).unwrap_err();
        assert_eq!(err.exit_code(), 4);
        assert!(err.to_string().contains("not written by track"), "{err}");
        assert_eq!(std::fs::read(&notes).unwrap(), b"mine");
        // Nothing was created by the refusal.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let report = dir.path().join("report.md");
        guard.file(&report).unwrap().write(b"1").unwrap();
        guard.file(&report).unwrap().write(b"2").unwrap();
        assert_eq!(std::fs::read(&report).unwrap(), b"2");
    }
}
