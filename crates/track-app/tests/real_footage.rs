//! `head` on real footage: the development set's FaceOcc1 (OTB), read from `../shared/data/real`
//! beside the checkout (or the folder `TRACK_REAL_DATA` names). A clone without that data skips
//! these tests and says so on standard error; CI has it.
//!
//! FaceOcc1 is a face that a book covers, more or less, through most of the sequence; the
//! heaviest covering is around frames 501–600, where every seed's overlap with the truth dips.
//! The tracker must find the face again after the occlusion; these tests check
//! that it holds it through it, that its P(lost) rises while the book covers the face and falls
//! once it is gone, over three seeds.

use crate::common;

use std::path::PathBuf;

use common::{s, track};

/// The development set, or `None` (with a notice) when this checkout has none beside it.
fn real_data() -> Option<PathBuf> {
    let dir = std::env::var_os("TRACK_REAL_DATA").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real"),
        PathBuf::from,
    );
    if dir.join("FaceOcc1/groundtruth_rect.txt").is_file() {
        Some(dir)
    } else {
        eprintln!(
            "SKIPPED: no development set at {} (set TRACK_REAL_DATA to its folder)",
            dir.display()
        );
        None
    }
}

/// The boxes of a box file (one `x,y,w,h` per line; commas, tabs or spaces).
fn boxes(text: &str) -> Vec<[f64; 4]> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(|c: char| c == ',' || c.is_whitespace())
                .filter(|t| !t.is_empty())
                .map(|t| t.parse().unwrap())
                .collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

fn iou(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let w = (a[0] + a[2]).min(b[0] + b[2]) - a[0].max(b[0]);
    let h = (a[1] + a[3]).min(b[1] + b[3]) - a[1].max(b[1]);
    let inter = w.max(0.0) * h.max(0.0);
    let union = a[2] * a[3] + b[2] * b[3] - inter;
    if union > 0.0 { inter / union } else { 0.0 }
}

/// Mean of `values` over frames `first..=last` (numbered from 1).
fn mean(values: &[f64], first: usize, last: usize) -> f64 {
    values[first - 1..last].iter().sum::<f64>() / (last + 1 - first) as f64
}

#[test]
fn head_holds_faceocc1_through_the_book_and_its_p_lost_says_when_it_is_covered() {
    let Some(data) = real_data() else {
        return;
    };
    let sequence = data.join("FaceOcc1");
    let truth = boxes(&std::fs::read_to_string(sequence.join("groundtruth_rect.txt")).unwrap());
    let dir = tempfile::tempdir().unwrap();
    for seed in ["1", "2", "3"] {
        let out = dir.path().join(seed);
        let run = track(&[
            "run",
            s(&sequence),
            "--tracker",
            "head",
            "--seed",
            seed,
            "--out",
            s(&out),
            "--quiet",
        ]);
        assert!(run.status.success(), "{}", common::stderr(&run));
        let tracked = boxes(&std::fs::read_to_string(out.join("boxes.txt")).unwrap());
        assert_eq!(tracked.len(), truth.len());
        let overlap: Vec<f64> = tracked.iter().zip(&truth).map(|(t, g)| iou(t, g)).collect();
        let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let column = header.iter().position(|h| *h == "alpha_p_lost").unwrap();
        let p_lost: Vec<f64> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(column).unwrap().parse().unwrap_or(0.0))
            .collect();
        let n = truth.len();
        let (covered, after) = (mean(&overlap, 501, 600), mean(&overlap, 601, n));
        let peak =
            |first: usize, last: usize| p_lost[first - 1..last].iter().cloned().fold(0.0, f64::max);
        println!(
            "seed {seed}: IoU {:.3} before the book, {covered:.3} while covered, {after:.3} \
             after; P(lost) peaks at {:.3} while covered, {:.3} after",
            mean(&overlap, 2, 500),
            peak(501, 600),
            peak(601, n)
        );
        // Held after the book: the overlap comes back to the level before it, well above
        // what it was while the face was covered.
        assert!(
            after >= 0.6 && after >= covered + 0.05,
            "seed {seed}: IoU {covered:.3} while covered, {after:.3} after"
        );
        assert!(
            mean(&overlap, 2, 500) >= 0.6,
            "seed {seed}: lost before the book"
        );
        // P(lost) rises while the face is covered, by more than an order of magnitude above
        // its peak on the uncovered frames before and after the book, and falls back once the
        // face is visible again. (The bar is relative: while covered, P(lost) peaks at 0.16–0.46
        // over seeds 1–3, against about 0.002 on the uncovered frames.)
        let uncovered = peak(2, 500).max(peak(601, n));
        assert!(
            peak(501, 600) > 10.0 * uncovered && peak(601, n) < 0.1,
            "seed {seed}: P(lost) peaks at {:.3} while covered, {:.3} before and {:.3} after",
            peak(501, 600),
            peak(2, 500),
            peak(601, n)
        );
    }
}
