//! Silent wrong results. Frames are read in natural order, `--init-ellipse`
//! starts the tracker from the ellipse given (or is refused), a zero-size first box is an error,
//! and `track.csv` has the same columns whatever the number of frames.

use crate::common;

use common::{DISC_INIT, disc_frames, disc_image, one_error_line, s, track};

#[test]
fn frames_named_with_unpadded_numbers_are_read_in_numeric_order() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("frames");
    std::fs::create_dir(&folder).unwrap();
    // Frame k (1-based) has its disc at x = 20 + 3k: in text order (1, 10, 11, 12, 2, …) the disc
    // would jump back and forth.
    for k in 1..=12 {
        disc_image(20.0 + 3.0 * f64::from(k))
            .save(folder.join(format!("{k}.png")))
            .unwrap();
    }
    let src = track_app::sequence::ImageFolder::open(&folder).unwrap();
    let names: Vec<String> = src
        .paths()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    let expected: Vec<String> = (1..=12).map(|k| format!("{k}.png")).collect();
    assert_eq!(names, expected);
    // End to end: the tracked centre moves right on every frame (3 px a frame; the tracker's
    // estimate of a clean disc is well within 1.5 px of it).
    let out = dir.path().join("out");
    let o = track(&[
        "run",
        s(&folder),
        "--init",
        "11,24,24,24",
        "--tracker",
        "m1",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    let cx: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    assert_eq!(cx.len(), 12);
    for (k, c) in cx.iter().enumerate() {
        let truth = 20.0 + 3.0 * (k + 1) as f64;
        assert!(
            (c - truth).abs() < 1.5,
            "frame {}: cx {c}, disc at {truth}",
            k + 1
        );
    }
}

/// The first data row of `out/track.csv`: cx, cy, a, b, angle.
fn first_ellipse(out: &std::path::Path) -> [f64; 5] {
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    let row: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .skip(1)
        .take(5)
        .map(|v| v.parse().unwrap())
        .collect();
    [row[0], row[1], row[2], row[3], row[4]]
}

#[test]
fn init_ellipse_starts_from_the_ellipse_given_or_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 1);
    let out = dir.path().join("out");
    let run = |tracker: &str, ellipse: &str| {
        track(&[
            "run",
            s(&frames),
            "--init-ellipse",
            ellipse,
            "--tracker",
            tracker,
            "--out",
            s(&out),
            "--quiet",
        ])
    };
    // A rotating tracker (Wu's affine shape space) starts from exactly this ellipse.
    let o = run("w-fixed", "40,36,20,6,0.785");
    assert!(o.status.success(), "{}", common::stderr(&o));
    let e = first_ellipse(&out);
    for (got, want) in e.iter().zip([40.0, 36.0, 20.0, 6.0, 0.785]) {
        assert!((got - want).abs() < 1e-9, "{e:?}");
    }
    // Axis-aligned trackers refuse a rotation they cannot represent, naming the option…
    for tracker in ["m1", "full", "head"] {
        let o = run(tracker, "40,36,20,6,0.785");
        assert_eq!(o.status.code(), Some(2), "{tracker}");
        let msg = one_error_line(&o);
        assert!(
            msg.contains("--init-ellipse") && msg.contains("0.785"),
            "{msg}"
        );
    }
    // …and take a quarter turn as the same ellipse with its axes swapped: 12 wide, 40 tall.
    for tracker in ["m1", "head"] {
        let o = run(tracker, "40,36,20,6,1.5707963");
        assert!(o.status.success(), "{tracker}: {}", common::stderr(&o));
        let [cx, cy, a, b, angle] = first_ellipse(&out);
        let (hw, hh) = (
            (a * angle.cos()).hypot(b * angle.sin()),
            (a * angle.sin()).hypot(b * angle.cos()),
        );
        assert!(
            (cx - 40.0).abs() < 1e-9 && (cy - 36.0).abs() < 1e-9,
            "{tracker}"
        );
        assert!(
            (hw - 6.0).abs() < 1e-6 && (hh - 20.0).abs() < 1e-6,
            "{tracker}: {hw} {hh}"
        );
    }
}

#[test]
fn a_zero_width_first_box_is_an_error_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("seq");
    disc_frames(&seq, "img", 3);
    let gt = seq.join("groundtruth_rect.txt");
    std::fs::write(&gt, "0,0,0,0\n18,24,0,24\n22,24,24,24\n").unwrap();
    let o = track(&["run", s(&seq), "--out", s(&dir.path().join("out"))]);
    assert_eq!(o.status.code(), Some(3));
    let msg = one_error_line(&o);
    assert!(
        msg.contains("groundtruth_rect.txt") && msg.contains("line 2"),
        "{msg}"
    );
    assert!(msg.contains("zero width or height"), "{msg}");
    assert!(!dir.path().join("out").exists());
    // After the first labelled box, a zero-size box still marks a frame without a target.
    std::fs::write(&gt, "18,24,24,24\n20,24,0,0\n22,24,24,24\n").unwrap();
    let o = track(&[
        "run",
        s(&seq),
        "--tracker",
        "m1",
        "--out",
        s(&dir.path().join("out")),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
}

#[test]
fn track_csv_has_the_same_columns_for_one_frame_as_for_many() {
    let dir = tempfile::tempdir().unwrap();
    let one = disc_frames(dir.path(), "one", 1);
    let three = disc_frames(dir.path(), "three", 3);
    for (tracker, columns) in [
        ("full", 22),
        ("w-eval", 22),
        ("w-occ", 19),
        ("head", 19),
        ("m1", 16),
    ] {
        let header = |frames: &std::path::Path, name: &str| {
            let out = dir.path().join(format!("{tracker}-{name}"));
            let o = track(&[
                "run",
                s(frames),
                "--init",
                DISC_INIT,
                "--tracker",
                tracker,
                "--particles",
                "50",
                "--out",
                s(&out),
                "--quiet",
            ]);
            assert!(o.status.success(), "{tracker}: {}", common::stderr(&o));
            common::csv_header(&out)
        };
        let (h1, h3) = (header(&one, "one"), header(&three, "three"));
        assert_eq!(h1, h3, "{tracker}");
        assert_eq!(h1.split(',').count(), columns, "{tracker}: {h1}");
    }
}
