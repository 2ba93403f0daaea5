//! The documentation describes the software, not how it was made: no Markdown file of the
//! repository and no doc comment (`//!`, `///`) of its Rust sources names a work item by number.
//!
//! The pattern is the word `stop`, `issue` or `session` (any case, optionally plural), starting
//! at a word boundary, then one space, then a digit. Ordinary prose does not write a number
//! straight after these words: a run "stops after the current frame", a bug "is an issue", and
//! counts of them are spelled out or put before the word ("two stops"). A sentence that needs the
//! form anyway rephrases it. Code, string literals and plain `//` comments are not read: a test
//! may name a signal that stops a run, and this file builds its examples at run time.

use std::path::{Path, PathBuf};

/// Words that, followed by a space and a digit, name a work item.
const WORDS: [&str; 3] = ["stop", "issue", "session"];

/// Folders never read: build output, version control, Python environments and caches.
fn skipped(dir: &Path) -> bool {
    let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("");
    matches!(
        name,
        "target" | ".git" | "venv" | ".venv" | "node_modules" | "__pycache__" | ".pytest_cache"
    ) || dir.join("pyvenv.cfg").is_file()
}

/// Whether `line` holds one of [`WORDS`] (any case, `s` allowed after it) at a word boundary,
/// followed by exactly one space and an ASCII digit.
fn names_a_work_item(line: &str) -> bool {
    let lower = line.to_lowercase();
    let bytes = lower.as_bytes();
    WORDS.iter().any(|word| {
        lower.match_indices(word).any(|(at, _)| {
            let boundary = at == 0 || {
                let before = lower[..at].chars().next_back().unwrap_or(' ');
                !(before.is_alphanumeric() || before == '_')
            };
            let mut next = at + word.len();
            if bytes.get(next) == Some(&b's') {
                next += 1;
            }
            boundary
                && bytes.get(next) == Some(&b' ')
                && bytes.get(next + 1).is_some_and(u8::is_ascii_digit)
        })
    })
}

/// Whether a Rust source line is a doc comment.
fn is_doc_comment(line: &str) -> bool {
    let t = line.trim_start();
    t.starts_with("//!") || (t.starts_with("///") && !t.starts_with("////"))
}

/// Every Markdown and Rust file under `dir`, skipping [`skipped`] folders.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let Ok(kind) = entry.file_type() else {
            continue;
        };
        if kind.is_dir() {
            if !skipped(&path) {
                files(&path, out);
            }
        } else if kind.is_file() && path.extension().is_some_and(|e| e == "md" || e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_matcher_finds_work_item_numbers_and_nothing_else() {
    // Built at run time, so that this file's own text holds none of them.
    let hit = |word: &str, rest: &str| format!("as measured at {word}{rest}");
    for (word, rest) in [
        ("stop", " 39"),
        ("Stop", " 37 decision"),
        ("ISSUE", " 27's rule"),
        ("issues", " 15 and 24"),
        ("stops", " 33–40"),
        ("session", " 4"),
    ] {
        assert!(names_a_work_item(&hit(word, rest)), "{word}{rest}");
    }
    assert!(names_a_work_item(&format!("({} 17, item 6)", "issue")));
    for clean in [
        "a run stops after the current frame",
        "stop3 has no space",
        "stop  3 has two spaces",
        "the issue's bound is 0.25 px",
        "stopped 2 frames later",
        "session data",
    ] {
        assert!(!names_a_work_item(clean), "{clean}");
    }
    assert!(!names_a_work_item(&format!(
        "tissue {} is not a work item",
        3
    )));
}

#[test]
fn no_markdown_file_or_doc_comment_names_a_work_item() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut all = Vec::new();
    files(root, &mut all);
    all.sort();
    assert!(
        all.iter().any(|p| p.ends_with("README.md")) && all.iter().any(|p| p.ends_with("lib.rs")),
        "the walk found the repository's files"
    );
    let mut found = Vec::new();
    for path in &all {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let rust = path.extension().is_some_and(|e| e == "rs");
        for (k, line) in text.lines().enumerate() {
            if (!rust || is_doc_comment(line)) && names_a_work_item(line) {
                let shown = path.strip_prefix(root).unwrap_or(path);
                found.push(format!("{}:{}: {}", shown.display(), k + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "describe what the code does, not the work item that made it:\n{}",
        found.join("\n")
    );
}
