//! The output guard, command by command: every subcommand of `track` (enumerated from the CLI's own
//! definition, so that a new one is covered without a new test) is run with its output on a file
//! of the user's, on its input folder, inside its input folder and on a symbolic link. Each is
//! refused with exit 4, and nothing is changed or left behind.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::CommandFactory;
use common::{DISC_INIT, disc_frames, s, stderr, track};
use track_app::cli::Cli;

/// What a subcommand writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Writes {
    /// An output folder (`--out DIR`).
    Folder,
    /// One output file (`--out FILE`).
    File,
    /// Nothing but standard output (it has no `--out`).
    Nothing,
}

/// A minimal valid invocation of a subcommand: what it writes, and its arguments given its input
/// (a folder of [`Fixture`]) and its output.
struct Case {
    writes: Writes,
    /// The input the cases put outputs onto and into (a folder, or a file), if it reads any.
    input: fn(&Fixture) -> Option<PathBuf>,
    args: fn(&Fixture, &str) -> Vec<String>,
}

/// The inputs every invocation may read: an OTB folder of disc frames (also the `eval otb` output
/// folder `eval paired` reads, as far as the guard is concerned), and a plain folder of frames.
struct Fixture {
    /// An OTB folder: img/0001.png… and groundtruth_rect.txt.
    otb: PathBuf,
    /// A plain folder of frames.
    frames: PathBuf,
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|a| (*a).to_owned()).collect()
}

/// The table of minimal invocations, keyed by the subcommand's path (`eval otb`). A subcommand
/// missing here fails the test.
fn case(name: &str) -> Option<Case> {
    let c = |writes, input: fn(&Fixture) -> Option<PathBuf>, args| Case {
        writes,
        input,
        args,
    };
    let otb = |f: &Fixture| Some(f.otb.clone());
    let frames = |f: &Fixture| Some(f.frames.clone());
    let none = |_: &Fixture| None;
    Some(match name {
        "demo" => c(Writes::Folder, none, |_, out| {
            strings(&["demo", "--particles", "20", "--out", out, "--quiet"])
        }),
        "run" => c(Writes::Folder, frames, |f, out| {
            strings(&[
                "run",
                s(&f.frames),
                "--init",
                DISC_INIT,
                "--tracker",
                "m1",
                "--particles",
                "20",
                "--gif",
                "--out",
                out,
                "--quiet",
            ])
        }),
        "eval table1" => c(Writes::Folder, none, |_, out| {
            strings(&[
                "eval",
                "table1",
                "--trials",
                "1",
                "--frames",
                "5",
                "--tracker",
                "m1",
                "--out",
                out,
                "--quiet",
            ])
        }),
        "eval switching" => c(Writes::Folder, none, |_, out| {
            strings(&[
                "eval",
                "switching",
                "--frames",
                "5",
                "--tracker",
                "w-hmm",
                "--out",
                out,
            ])
        }),
        "eval otb" => c(Writes::Folder, otb, |f, out| {
            strings(&[
                "eval",
                "otb",
                s(&f.otb),
                "--tracker",
                "m1",
                "--particles",
                "20",
                "--out",
                out,
                "--quiet",
            ])
        }),
        "eval paired" => c(Writes::File, otb, |f, out| {
            strings(&[
                "eval",
                "paired",
                "--base",
                s(&f.otb),
                "--variant",
                s(&f.otb),
                "--out",
                out,
            ])
        }),
        "motion" => c(Writes::Nothing, frames, |f, _| {
            let a = f.frames.join("0001.png");
            let b = f.frames.join("0002.png");
            strings(&["motion", s(&a), s(&b)])
        }),
        "learn-clutter" => c(
            Writes::File,
            |f| Some(f.frames.join("0001.png")),
            |f, out| {
                let a = f.frames.join("0001.png");
                strings(&["learn-clutter", s(&a), "--lines", "100", "--out", out])
            },
        ),
        "learn-switching" => c(Writes::File, otb, |f, out| {
            strings(&[
                "learn-switching",
                s(&f.otb),
                "--tracker",
                "w-hmm",
                "--iterations",
                "1",
                "--particles",
                "20",
                "--out",
                out,
                "--quiet",
            ])
        }),
        "config" => c(Writes::Nothing, frames, |_, _| strings(&["config", "m1"])),
        _ => return None,
    })
}

/// Every leaf subcommand of `command`, as its path of names (`eval otb`).
fn leaves(command: &clap::Command, prefix: &str, out: &mut Vec<(String, clap::Command)>) {
    for sub in command.get_subcommands() {
        if sub.get_name() == "help" {
            continue;
        }
        let name = if prefix.is_empty() {
            sub.get_name().to_owned()
        } else {
            format!("{prefix} {}", sub.get_name())
        };
        if sub.has_subcommands() {
            leaves(sub, &name, out);
        } else {
            out.push((name, sub.clone()));
        }
    }
}

/// Every file and folder below `dir` with its contents (folders as empty), to compare before
/// and after.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut map = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            let meta = std::fs::symlink_metadata(&p).unwrap();
            if meta.is_dir() {
                stack.push(p.clone());
                map.insert(p, Vec::new());
            } else if meta.file_type().is_symlink() {
                map.insert(
                    p.clone(),
                    std::fs::read_link(&p)
                        .unwrap()
                        .into_os_string()
                        .into_encoded_bytes(),
                );
            } else {
                map.insert(p.clone(), std::fs::read(&p).unwrap());
            }
        }
    }
    map
}

/// Runs `args`, expecting the guard's refusal: exit 4, one error line, and no change at all
/// below `root`.
fn refused(what: &str, args: &[String], root: &Path) {
    let before = snapshot(root);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = track(&refs);
    assert_eq!(o.status.code(), Some(4), "{what}: {args:?}: {}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.starts_with("error: ") && !e.contains("panicked"),
        "{what}: {e}"
    );
    let after = snapshot(root);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>(),
        "{what}: files were added or removed: {args:?}"
    );
    assert!(before == after, "{what}: a file changed: {args:?}");
}

fn fixture(root: &Path) -> Fixture {
    let otb = root.join("otb");
    disc_frames(&otb, "img", 3);
    std::fs::write(
        otb.join("groundtruth_rect.txt"),
        "18,24,24,24\n20,24,24,24\n22,24,24,24\n",
    )
    .unwrap();
    let frames = disc_frames(root, "frames", 3);
    Fixture { otb, frames }
}

#[test]
fn every_subcommand_refuses_user_files_inputs_and_links() {
    let mut subcommands = Vec::new();
    leaves(&Cli::command(), "", &mut subcommands);
    assert!(subcommands.len() >= 10, "{subcommands:?}");
    for (name, command) in subcommands {
        let Some(case) = case(&name) else {
            panic!(
                "`track {name}` has no entry in this test's table of minimal invocations: add \
                 one, so that the output guard is checked for it"
            );
        };
        let has_out = command.get_arguments().any(|a| a.get_id() == "out");
        if case.writes == Writes::Nothing {
            assert!(
                !has_out,
                "`track {name}` has --out now: say in the table what it writes"
            );
            continue;
        }
        assert!(has_out, "`track {name}` has no --out");
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let f = fixture(root);
        // 1. A file of the user's.
        let notes = root.join("notes.md");
        std::fs::write(&notes, "my notes").unwrap();
        refused(
            &format!("{name}, a user file"),
            &(case.args)(&f, s(&notes)),
            root,
        );
        if let Some(input) = (case.input)(&f) {
            // 2. The input itself.
            refused(
                &format!("{name}, the input"),
                &(case.args)(&f, s(&input)),
                root,
            );
            // 3. Inside the input.
            let inside = match case.writes {
                Writes::Folder => input.join("inside"),
                _ => input.join("inside").join("report.md"),
            };
            refused(
                &format!("{name}, inside the input"),
                &(case.args)(&f, s(&inside)),
                root,
            );
        }
        // 4. A symbolic link: to a folder of the user's, or to a file of the user's.
        #[cfg(unix)]
        {
            let target = match case.writes {
                Writes::Folder => {
                    let d = root.join("elsewhere");
                    std::fs::create_dir_all(&d).unwrap();
                    d
                }
                _ => notes.clone(),
            };
            let link = root.join("link");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(&target, &link).unwrap();
            refused(&format!("{name}, a link"), &(case.args)(&f, s(&link)), root);
        }
    }
}
