//! The shell examples of the README and CONTRIBUTING run as written. A fenced block whose info
//! string is `sh runnable` is run by `bash -e -o pipefail` in a fresh temporary folder, with this
//! build's `track` first on `PATH`; the blocks of one file run in order in the same folder.
//!
//! The documents generate their clips with `cargo xtask gen-clutter` (in a block that is not
//! marked, since it compiles xtask); this test makes the same folder with the same library calls
//! as xtask (`scene_synth::Scene::new` on the scenario's preset, then `write_sequence`), so the
//! runnable blocks find it. Python blocks marked `python runnable` run in
//! `python/tests/test_readme_examples.py`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::TRACK;

/// The documents whose runnable blocks are run.
const DOCUMENTS: [&str; 4] = [
    "README.md",
    "CONTRIBUTING.md",
    "docs/CLI.md",
    "docs/PYTHON.md",
];

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The fenced code blocks of a Markdown text: (info string, body).
fn blocks(markdown: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut open: Option<(String, String)> = None;
    for line in markdown.lines() {
        let t = line.trim_start();
        match open.take() {
            None => {
                if let Some(info) = t.strip_prefix("```") {
                    open = Some((info.trim().to_owned(), String::new()));
                }
            }
            Some((info, mut body)) => {
                if t.starts_with("```") {
                    out.push((info, body));
                } else {
                    body.push_str(line);
                    body.push('\n');
                    open = Some((info, body));
                }
            }
        }
    }
    out
}

/// Whether a block's info string marks it as a runnable shell block.
fn runnable_shell(info: &str) -> bool {
    let mut words = info.split_whitespace();
    matches!(words.next(), Some("sh" | "bash")) && words.any(|w| w == "runnable")
}

/// Makes, in `dir`, the folder of every `cargo xtask gen-clutter --scenario S [--seed N]
/// [--frames F] --out DIR` line of the document's shell blocks, as xtask would.
fn generate_clips(markdown: &str, dir: &Path) {
    for (info, body) in blocks(markdown) {
        if !info.starts_with("sh") {
            continue;
        }
        for line in body.lines() {
            let Some(args) = line.trim().strip_prefix("cargo xtask gen-clutter ") else {
                continue;
            };
            let args: Vec<&str> = args
                .split('#')
                .next()
                .unwrap_or("")
                .split_whitespace()
                .collect();
            let value = |flag: &str| {
                args.iter()
                    .position(|a| *a == flag)
                    .and_then(|i| args.get(i + 1).copied())
            };
            let scenario: scene_synth::Scenario = value("--scenario")
                .expect("--scenario")
                .parse()
                .expect("a scenario");
            let mut params = scene_synth::ScenarioParams::preset(scenario);
            if let Some(frames) = value("--frames") {
                params.frames = frames.parse().expect("--frames");
            }
            let seed = value("--seed").map_or(1, |s| s.parse().expect("--seed"));
            let scene = scene_synth::Scene::new(&params, seed).expect("the scene renders");
            let out = dir.join(value("--out").expect("--out"));
            scene_synth::write_sequence(&out, &scene).expect("the scene is written");
        }
    }
}

/// Runs the document's runnable shell blocks; returns how many ran.
fn run_document(name: &str) -> usize {
    let path = root().join(name);
    let markdown = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let runnable: Vec<String> = blocks(&markdown)
        .into_iter()
        .filter(|(info, _)| runnable_shell(info))
        .map(|(_, body)| body)
        .collect();
    if runnable.is_empty() {
        return 0;
    }
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join(".bin");
    std::fs::create_dir(&bin).unwrap();
    std::os::unix::fs::symlink(TRACK, bin.join("track")).unwrap();
    let path_var = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![bin];
    paths.extend(std::env::split_paths(&path_var));
    let path_var = std::env::join_paths(paths).unwrap();
    generate_clips(&markdown, dir.path());
    for (k, body) in runnable.iter().enumerate() {
        let out = Command::new("bash")
            .args(["-e", "-o", "pipefail", "-c", body])
            .current_dir(dir.path())
            .env("PATH", &path_var)
            .output()
            .expect("bash runs");
        assert!(
            out.status.success(),
            "{name}, runnable shell block {}:\n{body}\nexit {:?}\nstdout:\n{}\nstderr:\n{}",
            k + 1,
            out.status.code(),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    runnable.len()
}

#[test]
fn the_documents_runnable_shell_blocks_run() {
    let counts: Vec<(&str, usize)> = DOCUMENTS.iter().map(|d| (*d, run_document(d))).collect();
    let readme = counts
        .iter()
        .find(|(d, _)| *d == "README.md")
        .map_or(0, |c| c.1);
    assert!(
        readme >= 1,
        "the README has runnable shell blocks: {counts:?}"
    );
}

#[test]
fn blocks_and_markers_are_read_as_written() {
    let md = concat!(
        "text\n```sh runnable\ntrack demo\n```\n",
        "```sh\ncargo build\n```\n",
        "```python runnable\nx = 1\n```\n"
    );
    let b = blocks(md);
    assert_eq!(b.len(), 3);
    assert_eq!(b[0], ("sh runnable".to_owned(), "track demo\n".to_owned()));
    assert!(runnable_shell(&b[0].0) && !runnable_shell(&b[1].0) && !runnable_shell(&b[2].0));
}
