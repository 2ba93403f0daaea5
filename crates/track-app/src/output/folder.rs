//! Output folders that `track` owns: a lock, and a manifest of the files it wrote.
//!
//! The rule: **`track` never deletes or overwrites a file it did not write itself.** It knows what
//! it wrote from the manifest `OUT/.track-outputs`, one path (relative to the folder) per line,
//! appended *before* each file (or its temporary sibling) is created, so that even a run killed
//! with SIGKILL leaves nothing of its own unrecorded.
//!
//! Opening a folder ([`OutputFolder::open`]):
//! 1. refuses a folder that is a symbolic link, or that is or contains one of the command's
//!    inputs (exit 4), and creates it when absent;
//! 2. takes an exclusive lock on `OUT/.track-lock`, so that a second command writing into the same
//!    folder is refused at once instead of mixing its outputs with the first's;
//! 3. removes the files the manifest lists, with the temporary siblings an interrupted write left
//!    beside them — only regular files, and never through a symbolic link — then empties the
//!    manifest;
//! 4. registers the folder, so that every [`AtomicFile`](super::AtomicFile) written below it is
//!    recorded in the manifest first, and refused when its path is taken by a file the manifest
//!    does not list or leads through a symbolic link.
//!
//! The lock file and the manifest stay in the folder (removing a lock file races with the next
//! command that takes it); they are the only files `track` keeps there besides its outputs. A
//! command that writes nothing there (refused, or failed before its first output) removes again
//! the lock file, the manifest and the folders it created, so that a refusal changes nothing.

use std::collections::HashSet;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use crate::{AppError, Result};

/// The manifest's file name inside an output folder.
pub const MANIFEST_NAME: &str = ".track-outputs";
/// The lock file's name inside an output folder.
pub const LOCK_NAME: &str = ".track-lock";
/// The suffix of the temporary file an output is written to before its rename; its prefix is
/// `.<output file name>.`.
pub const TEMP_SUFFIX: &str = ".track-tmp";

/// An output folder owned by one command for its lifetime (see the module documentation).
#[derive(Debug)]
pub struct OutputFolder {
    state: Arc<FolderState>,
    /// Held for the folder's lifetime: the exclusive lock.
    _lock: File,
    /// What opening the folder created (the folder, its lock file, its manifest), removed again
    /// when the command ends without writing anything there (refused, or failed before its
    /// first output), so that a refusal leaves the user's folder as it was.
    created: Vec<PathBuf>,
}

/// What the registry knows of an open folder.
#[derive(Debug)]
struct FolderState {
    /// The folder as given, made absolute (not canonical: paths joined onto the argument compare
    /// with it as they are).
    root: PathBuf,
    /// The manifest, open for appending, and the relative paths recorded in it by this command.
    manifest: Mutex<(File, HashSet<PathBuf>)>,
}

/// The open output folders of this process.
static OPEN: Mutex<Vec<Arc<FolderState>>> = Mutex::new(Vec::new());

pub(super) fn write_error(path: &Path, message: impl Into<String>) -> AppError {
    AppError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(message.into()),
    }
}

fn io_error(path: &Path) -> impl Fn(std::io::Error) -> AppError + '_ {
    move |source| AppError::Write {
        path: path.to_path_buf(),
        source,
    }
}

impl OutputFolder {
    /// Opens `dir` as the output folder of a command that reads `inputs` (see the module
    /// documentation for what it checks, locks and removes).
    ///
    /// Commands open their folder through the output guard
    /// ([`OutputGuard::folder`](super::OutputGuard::folder)), which checks it against every
    /// input first.
    ///
    /// # Errors
    /// [`AppError::Write`] (exit 4) naming the folder: a symbolic link, a file, a folder that is
    /// or contains an input, one in use by another `track` command, or one that cannot be
    /// written; or naming a recorded output that cannot be removed.
    pub(super) fn open(dir: &Path, inputs: &[&Path]) -> Result<Self> {
        if std::fs::symlink_metadata(dir).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(write_error(
                dir,
                "the output folder is a symbolic link; give the folder it points to, so that \
                 what track writes and removes is plain to see",
            ));
        }
        // The folders that do not exist yet, outermost first, removed again if nothing is
        // written.
        let absolute = std::path::absolute(dir).map_err(io_error(dir))?;
        let mut missing: Vec<PathBuf> = absolute
            .ancestors()
            .take_while(|a| std::fs::symlink_metadata(a).is_err())
            .map(Path::to_path_buf)
            .collect();
        missing.reverse();
        let mut cleanup = Cleanup(missing);
        super::probe_dir(dir)?;
        let canonical = dir.canonicalize().map_err(io_error(dir))?;
        for input in inputs {
            let Ok(input_canonical) = input.canonicalize() else {
                continue;
            };
            if input_canonical.starts_with(&canonical) {
                return Err(write_error(
                    dir,
                    format!(
                        "the output folder contains the input {}; track would write over what \
                         it reads: choose another --out",
                        input.display()
                    ),
                ));
            }
        }
        let lock_path = dir.join(LOCK_NAME);
        let manifest_path = dir.join(MANIFEST_NAME);
        for path in [&lock_path, &manifest_path] {
            if std::fs::symlink_metadata(path).is_err() {
                cleanup.0.push(path.clone());
            }
        }
        let lock = take_lock(dir)?;
        remove_recorded(dir, &manifest_path)?;
        let manifest = OpenOptions::new()
            .create(true)
            .truncate(true)
            .write(true)
            .open(&manifest_path)
            .map_err(io_error(&manifest_path))?;
        let root = std::path::absolute(dir).map_err(io_error(dir))?;
        let state = Arc::new(FolderState {
            root,
            manifest: Mutex::new((manifest, HashSet::new())),
        });
        OPEN.lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(Arc::clone(&state));
        Ok(Self {
            state,
            _lock: lock,
            created: cleanup.defuse(),
        })
    }

    /// The folder (absolute).
    pub fn path(&self) -> &Path {
        &self.state.root
    }

    /// Checks, before any work, that the output `relative` can be written: no folder on its way
    /// is a symbolic link and no file the manifest does not list takes its name. With
    /// `matching`, `relative` is a folder and every file in it for which `matching` is true is
    /// checked (e.g. the overlays `overlay/NNNN.png` a run would write).
    ///
    /// # Errors
    /// [`AppError::Write`] naming the path.
    pub fn check_free(
        &self,
        relative: &Path,
        matching: Option<&dyn Fn(&Path) -> bool>,
    ) -> Result<()> {
        let path = self.state.root.join(relative);
        match matching {
            None => {
                check_no_link_below(&self.state.root, &path)?;
                check_not_foreign(&path)
            }
            Some(matches) => {
                // The folder itself is written into, so it may not be a link either.
                check_no_link_in(&self.state.root, &path)?;
                let Ok(entries) = std::fs::read_dir(&path) else {
                    return Ok(());
                };
                for entry in entries.flatten() {
                    let p = entry.path();
                    if matches(&p) {
                        check_not_foreign(&p)?;
                    }
                }
                Ok(())
            }
        }
    }
}

impl Drop for OutputFolder {
    fn drop(&mut self) {
        OPEN.lock()
            .unwrap_or_else(PoisonError::into_inner)
            .retain(|s| !Arc::ptr_eq(s, &self.state));
        let wrote_nothing = self
            .state
            .manifest
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .1
            .is_empty();
        if wrote_nothing {
            remove_created(&self.created);
        }
    }
}

/// Removes what opening a folder created, newest first: files, then the folder if it is empty.
/// The lock is still held while its file is removed, so no other command holds it.
fn remove_created(created: &[PathBuf]) {
    for path in created.iter().rev() {
        match std::fs::symlink_metadata(path) {
            Ok(m) if m.is_dir() => {
                // Only when empty: remove_dir refuses a folder with anything in it.
                let _ = std::fs::remove_dir(path);
            }
            Ok(m) if m.file_type().is_file() => {
                let _ = std::fs::remove_file(path);
            }
            _ => {}
        }
    }
}

/// What an [`OutputFolder::open`] that fails part-way has created, removed on drop.
struct Cleanup(Vec<PathBuf>);

impl Cleanup {
    /// Keeps what was created: the folder opened.
    fn defuse(mut self) -> Vec<PathBuf> {
        std::mem::take(&mut self.0)
    }
}

impl Drop for Cleanup {
    fn drop(&mut self) {
        remove_created(&self.0);
    }
}

/// Takes the folder's lock, or says which command holds it.
fn take_lock(dir: &Path) -> Result<File> {
    let path = dir.join(LOCK_NAME);
    if std::fs::symlink_metadata(&path).is_ok_and(|m| !m.file_type().is_file()) {
        return Err(write_error(&path, "the lock file is not a regular file"));
    }
    let file = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(io_error(&path))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(write_error(
            dir,
            format!(
                "the folder is in use by another track command (it holds {}); wait for it to \
                 finish or choose another --out",
                path.display()
            ),
        )),
        Err(std::fs::TryLockError::Error(e)) => Err(io_error(&path)(e)),
    }
}

/// The relative path of a manifest line, when it is a plain path below the folder.
fn recorded_path(line: &str) -> Option<PathBuf> {
    let p = Path::new(line);
    let plain = !line.is_empty() && p.components().all(|c| matches!(c, Component::Normal(_)));
    plain.then(|| p.to_path_buf())
}

/// Removes the files the manifest of `dir` lists, and their temporary siblings.
fn remove_recorded(dir: &Path, manifest_path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(manifest_path) {
        Ok(m) if m.file_type().is_file() => {}
        Ok(_) => {
            return Err(write_error(
                manifest_path,
                "the manifest of track's outputs is not a regular file",
            ));
        }
        Err(_) => return Ok(()),
    }
    let text = std::fs::read(manifest_path).map_err(io_error(manifest_path))?;
    for line in String::from_utf8_lossy(&text).lines() {
        let Some(relative) = recorded_path(line) else {
            continue;
        };
        let path = dir.join(&relative);
        // Never through a symbolic link: the folder it leads to is not ours.
        if check_no_link_below(dir, &path).is_err() {
            continue;
        }
        remove_regular(&path)?;
        remove_temporaries(&path)?;
    }
    Ok(())
}

/// Removes `path` if it is a regular file.
fn remove_regular(path: &Path) -> Result<()> {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file()) {
        std::fs::remove_file(path).map_err(io_error(path))?;
    }
    Ok(())
}

/// The prefix of the temporary files of the output `path`.
pub(super) fn temp_prefix(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    format!(".{name}.")
}

/// Removes the temporary files an interrupted write of `path` left beside it.
fn remove_temporaries(path: &Path) -> Result<()> {
    let prefix = temp_prefix(path);
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with(&prefix) && name.ends_with(TEMP_SUFFIX) {
            remove_regular(&entry.path())?;
        }
    }
    Ok(())
}

/// Refuses `path` when a folder between `root` and it is a symbolic link.
fn check_no_link_below(root: &Path, path: &Path) -> Result<()> {
    match path.parent() {
        Some(dir) => check_no_link_in(root, dir),
        None => Ok(()),
    }
}

/// Refuses the folder `dir` when it, or a folder between `root` and it, is a symbolic link.
fn check_no_link_in(root: &Path, dir: &Path) -> Result<()> {
    let Ok(relative) = dir.strip_prefix(root) else {
        return Ok(());
    };
    let mut at = root.to_path_buf();
    for part in relative.components() {
        at.push(part);
        if std::fs::symlink_metadata(&at).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(write_error(
                &at,
                "it is a symbolic link; track writes only into folders of its own output \
                 folder, never through a link (remove the link or choose another --out)",
            ));
        }
    }
    Ok(())
}

/// Refuses `path` when something takes its name (any file, since the manifest's files were
/// removed when the folder was opened).
fn check_not_foreign(path: &Path) -> Result<()> {
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        let what = if meta.file_type().is_file() {
            "a file"
        } else {
            super::file_kind(&meta.file_type())
        };
        return Err(write_error(
            path,
            format!(
                "it exists ({what}) and was not written by track (the folder's {MANIFEST_NAME} \
                 does not list it), so track will not replace it: move it away or choose another \
                 --out"
            ),
        ));
    }
    Ok(())
}

/// Whether the manifest of the folder holding the file `path` lists it (a file `track` wrote).
pub(super) fn is_listed(path: &Path) -> bool {
    let (Some(dir), Some(name)) = (path.parent(), path.file_name()) else {
        return false;
    };
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let manifest = dir.join(MANIFEST_NAME);
    if !std::fs::symlink_metadata(&manifest).is_ok_and(|m| m.file_type().is_file()) {
        return false;
    }
    std::fs::read(&manifest).is_ok_and(|text| {
        String::from_utf8_lossy(&text)
            .lines()
            .any(|l| recorded_path(l).is_some_and(|p| p.as_os_str() == name))
    })
}

/// Records the single output file `path` in the manifest of its folder (created when absent),
/// unless it is listed already, before the file is written: the next command may then replace
/// it, and a command that opens the folder as its output folder removes it.
///
/// # Errors
/// [`AppError::Write`] naming the manifest.
pub(super) fn record_single(path: &Path) -> Result<()> {
    if is_listed(path) {
        return Ok(());
    }
    let Some(name) = path.file_name() else {
        return Err(write_error(path, "an output file needs a file name"));
    };
    let line = name.to_string_lossy();
    if line.contains('\n') {
        return Err(write_error(
            path,
            "an output name may not hold a line break",
        ));
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    super::create_dir(dir)?;
    let manifest_path = dir.join(MANIFEST_NAME);
    if std::fs::symlink_metadata(&manifest_path).is_ok_and(|m| !m.file_type().is_file()) {
        return Err(write_error(
            &manifest_path,
            "the manifest of track's outputs is not a regular file",
        ));
    }
    OpenOptions::new()
        .create(true)
        .append(true)
        .open(&manifest_path)
        .and_then(|mut f| f.write_all(format!("{line}\n").as_bytes()))
        .map_err(io_error(&manifest_path))
}

/// Called before the output `path` (or its temporary sibling) is created: when `path` lies in an
/// open output folder, checks it and records it in that folder's manifest.
///
/// # Errors
/// [`AppError::Write`]: a symbolic link on the way, a file of another origin in its place, or
/// the manifest cannot be written.
pub(super) fn record(path: &Path) -> Result<()> {
    let Ok(absolute) = std::path::absolute(path) else {
        return Ok(());
    };
    let folder = OPEN
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .iter()
        .filter(|s| absolute.starts_with(&s.root))
        .max_by_key(|s| s.root.components().count())
        .cloned();
    let Some(folder) = folder else {
        return Ok(());
    };
    let Ok(relative) = absolute.strip_prefix(&folder.root) else {
        return Ok(());
    };
    let relative = relative.to_path_buf();
    check_no_link_below(&folder.root, &absolute)?;
    let mut guard = folder
        .manifest
        .lock()
        .unwrap_or_else(PoisonError::into_inner);
    let (manifest, written) = &mut *guard;
    if written.contains(&relative) {
        return Ok(());
    }
    check_not_foreign(&absolute)?;
    let line = relative.to_string_lossy();
    if line.contains('\n') {
        return Err(write_error(
            path,
            "an output name may not hold a line break",
        ));
    }
    manifest
        .write_all(format!("{line}\n").as_bytes())
        .and_then(|()| manifest.flush())
        .map_err(io_error(&folder.root.join(MANIFEST_NAME)))?;
    written.insert(relative);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::write_atomic;

    #[test]
    fn a_second_run_removes_only_what_the_first_wrote() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        {
            let _f = OutputFolder::open(&out, &[]).unwrap();
            write_atomic(&out.join("track.csv"), b"a").unwrap();
            write_atomic(&out.join("overlay/0001.png"), b"b").unwrap();
        }
        std::fs::write(out.join("notes.txt"), b"mine").unwrap();
        std::fs::write(out.join("overlay/0002.png"), b"mine too").unwrap();
        {
            let _f = OutputFolder::open(&out, &[]).unwrap();
            assert!(!out.join("track.csv").exists());
            assert!(!out.join("overlay/0001.png").exists());
            assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
            assert_eq!(
                std::fs::read(out.join("overlay/0002.png")).unwrap(),
                b"mine too"
            );
            // A file of the user's in an output's place is refused, not replaced.
            let err = write_atomic(&out.join("overlay/0002.png"), b"x").unwrap_err();
            assert_eq!(err.exit_code(), 4);
            assert!(err.to_string().contains("not written by track"), "{err}");
            assert_eq!(
                std::fs::read(out.join("overlay/0002.png")).unwrap(),
                b"mine too"
            );
            // The same output written twice by one command is fine.
            write_atomic(&out.join("summary.json"), b"1").unwrap();
            write_atomic(&out.join("summary.json"), b"2").unwrap();
        }
    }

    #[test]
    fn a_folder_in_use_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let first = OutputFolder::open(dir.path(), &[]).unwrap();
        let err = OutputFolder::open(dir.path(), &[]).unwrap_err();
        assert_eq!(err.exit_code(), 4);
        assert!(err.to_string().contains("in use by another track"), "{err}");
        drop(first);
        OutputFolder::open(dir.path(), &[]).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn links_are_never_followed() {
        let dir = tempfile::tempdir().unwrap();
        let photos = dir.path().join("photos");
        std::fs::create_dir(&photos).unwrap();
        std::fs::write(photos.join("0001.png"), b"holiday").unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&photos, out.join("overlay")).unwrap();
        // A manifest that lists the file behind the link (as an older layout could).
        std::fs::write(
            out.join(MANIFEST_NAME),
            b"overlay/0001.png\n../photos/0001.png\n",
        )
        .unwrap();
        let f = OutputFolder::open(&out, &[]).unwrap();
        assert_eq!(std::fs::read(photos.join("0001.png")).unwrap(), b"holiday");
        let err = write_atomic(&out.join("overlay/0003.png"), b"x").unwrap_err();
        assert!(err.to_string().contains("symbolic link"), "{err}");
        assert!(!photos.join("0003.png").exists());
        drop(f);
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&out, &link).unwrap();
        let err = OutputFolder::open(&link, &[]).unwrap_err();
        assert!(err.to_string().contains("symbolic link"), "{err}");
    }

    #[test]
    fn a_folder_holding_the_input_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("overlay");
        std::fs::create_dir(&input).unwrap();
        let err = OutputFolder::open(dir.path(), &[&input]).unwrap_err();
        assert_eq!(err.exit_code(), 4);
        assert!(err.to_string().contains("contains the input"), "{err}");
    }

    #[test]
    fn temporaries_of_a_killed_write_are_removed_next_time() {
        let dir = tempfile::tempdir().unwrap();
        {
            let _f = OutputFolder::open(dir.path(), &[]).unwrap();
            // What a SIGKILL during the write leaves: the entry and a temporary, no file.
            let file = crate::output::AtomicFile::create(&dir.path().join("a.png")).unwrap();
            std::mem::forget(file);
        }
        let names = |d: &Path| -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert!(names(dir.path()).iter().any(|n| n.ends_with(TEMP_SUFFIX)));
        let _f = OutputFolder::open(dir.path(), &[]).unwrap();
        assert_eq!(names(dir.path()), [LOCK_NAME, MANIFEST_NAME]);
    }
}
