//! `track eval otb --protocol ope|tre|sre` on generated OTB folders: the runs start
//! where `opencv_peers.py` starts them, the start frame is never scored, `--results` reads other
//! trackers' boxes (and round-trips `track run`'s `boxes.txt`), and the results do not depend on
//! the number of threads.

use std::path::{Path, PathBuf};

use crate::common;

use common::{disc_frames, one_error_line, paired, s, track};

/// The true box of the disc of [`common::disc_image`] on frame `k` of [`disc_frames`].
fn disc_box(k: usize) -> [f64; 4] {
    [18.0 + 2.0 * k as f64, 24.0, 24.0, 24.0]
}

/// An OTB folder `dir/name` of `n` disc frames whose ground-truth line k is `label(k)` (a box
/// line, or `0,0,0,0` / `NaN,NaN,NaN,NaN` for unlabelled frames).
fn otb_folder(dir: &Path, name: &str, n: usize, label: impl Fn(usize) -> String) -> PathBuf {
    let seq = dir.join(name);
    disc_frames(&seq, "img", n);
    let gt: String = (0..n).map(|k| label(k) + "\n").collect();
    std::fs::write(seq.join("groundtruth_rect.txt"), gt).unwrap();
    seq
}

fn true_line(k: usize) -> String {
    disc_box(k).map(|v| v.to_string()).join(",")
}

/// The rows of a protocol's otb.csv as (sequence, tracker) → every field.
fn csv_rows(out: &Path, protocol: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(out.join(protocol).join("otb.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert!(
        header.starts_with("protocol,sequence,tracker,runs"),
        "{header}"
    );
    lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

fn row<'a>(rows: &'a [Vec<String>], seq: &str, tracker: &str) -> &'a [String] {
    rows.iter()
        .find(|r| r[1] == seq && r[2] == tracker)
        .unwrap_or_else(|| panic!("no row {seq} {tracker} in {rows:?}"))
}

/// The index of the first line that is not `0,0,0,0`, and that line's numbers.
fn first_box(path: &Path) -> (usize, Vec<f64>, usize) {
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let k = lines.iter().position(|l| *l != "0,0,0,0").unwrap();
    let v = lines[k].split(',').map(|f| f.parse().unwrap()).collect();
    (k, v, lines.len())
}

#[test]
fn tre_and_sre_runs_start_where_the_peers_script_starts_them() {
    let dir = tempfile::tempdir().unwrap();
    // 23 frames: unlabelled (0,0,0,0) on 0–1, NaN rows on 9–10, the rest labelled.
    let seq = otb_folder(dir.path(), "gappy", 23, |k| match k {
        0 | 1 => "0,0,0,0".into(),
        9 | 10 => "NaN,NaN,NaN,NaN".into(),
        _ => true_line(k),
    });
    let out = dir.path().join("out");
    let o = track(&[
        "eval",
        "otb",
        s(&seq),
        "--tracker",
        "m1",
        "--particles",
        "50",
        "--protocol",
        "tre",
        "--protocol",
        "sre",
        "--protocol",
        "ope",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    // TRE: ⌊i·23/10⌋ = 0, 2, 4, 6, 9, 11, 13, 16, 18, 20 → first labelled at or after each:
    // 2, 2, 4, 6, 11, 11, 13, 16, 18, 20 → duplicates dropped: 8 runs.
    let tre_starts = [2, 4, 6, 11, 13, 16, 18, 20];
    for (run, &start) in tre_starts.iter().enumerate() {
        let path = out.join(format!("tre/m1/gappy.{run}.txt"));
        let (k, b, n) = first_box(&path);
        assert_eq!((k, n), (start, 23), "{}", path.display());
        // The tracker starts from the true box of its start frame.
        for (got, want) in b.iter().zip(disc_box(start)) {
            assert!(
                (got - want).abs() < 1.0,
                "{path:?}: {b:?} against {:?}",
                disc_box(start)
            );
        }
    }
    assert!(!out.join("tre/m1/gappy.8.txt").exists());
    assert_eq!(row(&csv_rows(&out, "tre"), "gappy", "m1")[3], "8");
    // SRE: 12 runs from frame 2, the box shifted by 10 % (2.4 px) or scaled about its centre.
    let [x, y, w, h] = disc_box(2);
    let mut expected: Vec<[f64; 4]> = [
        (-1.0, 0.0),
        (1.0, 0.0),
        (0.0, -1.0),
        (0.0, 1.0),
        (-1.0, -1.0),
        (1.0, -1.0),
        (-1.0, 1.0),
        (1.0, 1.0),
    ]
    .iter()
    .map(|(dx, dy)| [x + dx * 0.1 * w, y + dy * 0.1 * h, w, h])
    .collect();
    for sc in [0.8, 0.9, 1.1, 1.2] {
        expected.push([
            x + w / 2.0 - sc * w / 2.0,
            y + h / 2.0 - sc * h / 2.0,
            sc * w,
            sc * h,
        ]);
    }
    let mut starts = Vec::new();
    for (run, want) in expected.iter().enumerate() {
        let (k, b, _) = first_box(&out.join(format!("sre/m1/gappy.{run}.txt")));
        assert_eq!(k, 2);
        starts.push(b.clone());
        // The start frame's line is the tracker's estimate there: within a pixel of the box
        // it was given.
        for (got, want) in b.iter().zip(want) {
            assert!(
                (got - want).abs() < 1.0,
                "run {run}: {b:?} against {want:?}"
            );
        }
    }
    // The twelve starts differ from one another.
    for i in 0..starts.len() {
        for j in 0..i {
            assert_ne!(starts[i], starts[j], "runs {i} and {j}");
        }
    }
    assert_eq!(row(&csv_rows(&out, "sre"), "gappy", "m1")[3], "12");
    assert_eq!(row(&csv_rows(&out, "ope"), "gappy", "m1")[3], "1");
    assert_eq!(first_box(&out.join("ope/m1/gappy.txt")).0, 2);
    // Scored: the 23 − 4 labelled frames minus the start frame.
    assert_eq!(row(&csv_rows(&out, "ope"), "gappy", "m1")[5], "18");
    // Plots, tables and the index.
    for p in ["ope", "tre", "sre"] {
        for f in [
            "otb.md",
            "plots/success.svg",
            "plots/precision.svg",
            "plots/success_gappy.svg",
        ] {
            assert!(out.join(p).join(f).is_file(), "{p}/{f}");
        }
    }
    // SRE's table says what the truth scores in each run's start convention: below 1 (a box
    // shifted by a tenth of its width overlaps the truth at 0.82), and only under SRE.
    let sre_md = std::fs::read_to_string(out.join("sre/otb.md")).unwrap();
    let ceiling: f64 = sre_md
        .split("scores a success AUC of ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no start-convention score in {sre_md}"));
    assert!(ceiling > 0.5 && ceiling < 0.9, "{ceiling}");
    for p in ["ope", "tre"] {
        let md = std::fs::read_to_string(out.join(p).join("otb.md")).unwrap();
        assert!(!md.contains("start convention"), "{p}");
    }
    let index = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(index.contains("<h2>TRE</h2>") && index.contains("<h2>SRE</h2>"));
    assert!(index.contains(&format!("scores a success AUC of {ceiling:.3}")));
    assert!(index.matches("<svg").count() >= 3 * 4);
}

#[test]
fn very_short_sequences_have_the_runs_they_can_score() {
    let dir = tempfile::tempdir().unwrap();
    // Two frames: TRE's starts are 0 (i < 5) and 1 (nothing after it: dropped).
    let two = otb_folder(dir.path(), "two", 2, true_line);
    let out = dir.path().join("out");
    let o = track(&[
        "eval",
        "otb",
        s(&two),
        "--tracker",
        "m1",
        "--protocol",
        "tre",
        "--protocol",
        "sre",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let tre = csv_rows(&out, "tre");
    assert_eq!(row(&tre, "two", "m1")[3], "1");
    // One frame scored per run.
    assert_eq!(row(&tre, "two", "m1")[5], "1");
    assert_eq!(row(&csv_rows(&out, "sre"), "two", "m1")[5], "12");
    // Only the first frame labelled: nothing to score, said with the file and the sequence.
    let lonely = otb_folder(dir.path(), "lonely", 3, |k| {
        if k == 0 {
            true_line(0)
        } else {
            "0,0,0,0".into()
        }
    });
    let o = track(&[
        "eval",
        "otb",
        s(&lonely),
        "--tracker",
        "m1",
        "--out",
        s(&dir.path().join("o2")),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(
        e.contains("groundtruth_rect.txt") && e.contains("lonely"),
        "{e}"
    );
    assert!(e.contains("nothing to score"), "{e}");
}

/// Writes `text` as the results of `tracker` for every run of `protocol` on `seq`.
fn write_results(dir: &Path, protocol: &str, tracker: &str, seq: &str, runs: usize, text: &str) {
    let d = dir.join(protocol).join(tracker);
    std::fs::create_dir_all(&d).unwrap();
    for k in 0..runs {
        let name = if protocol == "ope" {
            format!("{seq}.txt")
        } else {
            format!("{seq}.{k}.txt")
        };
        std::fs::write(d.join(name), text).unwrap();
    }
}

#[test]
fn the_start_frame_is_never_scored() {
    let dir = tempfile::tempdir().unwrap();
    let n = 8;
    let seq = otb_folder(dir.path(), "walk", n, true_line);
    let results = dir.path().join("peers");
    let far = "80.00,60.00,5.00,5.00".to_owned();
    // Per run starting on frame `start`: "wrong_start" has a box far off on the start frame and
    // the true box after it; "right_start_only" the true box on the start frame and far off
    // after it. Frames before the start: no box.
    let text = |start: usize, right_at_start: bool| -> String {
        (0..n)
            .map(|k| {
                let line = if k < start {
                    "0,0,0,0".to_owned()
                } else if (k == start) == right_at_start {
                    true_line(k)
                } else {
                    far.clone()
                };
                line + "\n"
            })
            .collect()
    };
    // TRE on 8 frames: ⌊i·8/10⌋ = 0,0,1,2,3,4,4,5,6,7 → starts 0–6 (7 has nothing after it).
    let starts = [
        ("ope", vec![0]),
        ("sre", vec![0; 12]),
        ("tre", (0..7).collect::<Vec<_>>()),
    ];
    for (p, runs) in &starts {
        for (tracker, right) in [("wrong_start", false), ("right_start_only", true)] {
            let d = results.join(p).join(tracker);
            std::fs::create_dir_all(&d).unwrap();
            for (k, &start) in runs.iter().enumerate() {
                let name = if *p == "ope" {
                    "walk.txt".to_owned()
                } else {
                    format!("walk.{k}.txt")
                };
                std::fs::write(d.join(name), text(start, right)).unwrap();
            }
        }
    }
    let out = dir.path().join("out");
    let o = track(&[
        "eval",
        "otb",
        s(&seq),
        "--tracker",
        "m1",
        "--protocol",
        "ope",
        "--protocol",
        "sre",
        "--protocol",
        "tre",
        "--results",
        &format!("wrong_start={}", s(&results)),
        "--results",
        &format!("right_start_only={}", s(&results)),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for (p, runs) in &starts {
        let rows = csv_rows(&out, p);
        // Perfect on every scored frame: 20 of 21 thresholds (OTB's strict > at 1), P20 = 1.
        let w = row(&rows, "walk", "wrong_start");
        assert_eq!(
            (w[6].as_str(), w[7].as_str()),
            ("0.9524", "1.0000"),
            "{p}: {w:?}"
        );
        assert_eq!(w[3], runs.len().to_string(), "{p}");
        // Scored frames summed over runs: those after each start.
        let scored: usize = runs.iter().map(|s| n - 1 - s).sum();
        assert_eq!(
            w[5],
            scored.to_string(),
            "{p}: the start frame is not counted"
        );
        let r = row(&rows, "walk", "right_start_only");
        assert_eq!(
            (r[6].as_str(), r[7].as_str()),
            ("0.0000", "0.0000"),
            "{p}: {r:?}"
        );
        // No timing and no status for boxes read from files.
        assert_eq!((r[9].as_str(), r[10].as_str()), ("", ""), "{p}");
    }
}

#[test]
fn track_run_and_eval_otb_score_a_run_alike_and_results_round_trip_boxes_txt() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "walk", 10, |k| {
        if k == 4 {
            "0,0,0,0".into()
        } else {
            true_line(k)
        }
    });
    let run_out = dir.path().join("run");
    let o = track(&[
        "run",
        s(&seq),
        "--tracker",
        "m1",
        "--out",
        s(&run_out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let summary = common::summary(&run_out);
    let m = &summary["metrics"];
    // 9 labelled frames, the first of them the start: 8 scored.
    assert_eq!(m["labelled_frames"], 8);
    // track run's boxes.txt, put where --results looks for it.
    let results = dir.path().join("mine");
    std::fs::create_dir_all(results.join("ope/from_run")).unwrap();
    std::fs::copy(
        run_out.join("boxes.txt"),
        results.join("ope/from_run/walk.txt"),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = track(&[
        "eval",
        "otb",
        s(&seq),
        "--tracker",
        "m1",
        "--results",
        &format!("from_run={}", s(&results)),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let rows = csv_rows(&out, "ope");
    let own = row(&rows, "walk", "m1");
    let read = row(&rows, "walk", "from_run");
    let f = |v: &serde_json::Value| format!("{:.4}", v.as_f64().unwrap());
    // One scorer: track run's summary, eval's own run and the boxes read back agree.
    for r in [own, read] {
        assert_eq!(r[5], "8");
        assert_eq!(r[6], f(&m["success_auc"]), "{r:?}");
        assert_eq!(r[7], f(&m["precision_20"]), "{r:?}");
    }
    // With --results alone nothing is tracked: only the boxes read are scored.
    let only = dir.path().join("only");
    let o = track(&[
        "eval",
        "otb",
        s(&seq),
        "--results",
        &format!("from_run={}", s(&results)),
        "--out",
        s(&only),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let rows = csv_rows(&only, "ope");
    assert!(rows.iter().all(|r| r[2] == "from_run"), "{rows:?}");
    assert_eq!(row(&rows, "walk", "from_run")[6], read[6]);
    assert!(!only.join("ope/head").exists());
    // And eval's own box file is track run's boxes.txt, line for line.
    assert_eq!(
        std::fs::read_to_string(out.join("ope/m1/walk.txt")).unwrap(),
        std::fs::read_to_string(run_out.join("boxes.txt")).unwrap()
    );
}

#[test]
fn a_configuration_file_keeps_its_own_particles_and_seed_unless_the_command_line_gives_them() {
    // A file asking for 37 particles and seed 5: eval otb runs it as track run does, and
    // --particles / --seed, when given, apply to it as to the presets.
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "walk", 12, true_line);
    let printed = track(&["config", "m1"]);
    assert!(printed.status.success(), "{}", common::stderr(&printed));
    let mut config: serde_json::Value = serde_json::from_slice(&printed.stdout).unwrap();
    config["particles"] = 37.into();
    config["seed"] = 5.into();
    let file = dir.path().join("mine.json");
    std::fs::write(&file, config.to_string()).unwrap();
    let boxes = |args: &[&str], out: &Path, path: &Path| {
        let o = track(&[args, &["--out", s(out), "--quiet"]].concat());
        assert!(o.status.success(), "{}", common::stderr(&o));
        std::fs::read_to_string(path).unwrap()
    };
    let run_out = dir.path().join("run");
    let run = boxes(
        &["run", s(&seq), "--config", s(&file)],
        &run_out,
        &run_out.join("boxes.txt"),
    );
    let eval_out = dir.path().join("eval");
    let eval = boxes(
        &["eval", "otb", s(&seq), "--config", s(&file)],
        &eval_out,
        &eval_out.join("ope/m1/walk.txt"),
    );
    assert_eq!(
        eval, run,
        "eval otb did not run the file's own particles and seed"
    );
    let given_out = dir.path().join("given");
    let given = boxes(
        &[
            "eval",
            "otb",
            s(&seq),
            "--config",
            s(&file),
            "--particles",
            "200",
            "--seed",
            "1",
        ],
        &given_out,
        &given_out.join("ope/m1/walk.txt"),
    );
    let preset_out = dir.path().join("preset");
    let preset = boxes(
        &["eval", "otb", s(&seq), "--tracker", "m1"],
        &preset_out,
        &preset_out.join("ope/m1/walk.txt"),
    );
    assert_eq!(
        given, preset,
        "--particles and --seed did not apply to the file"
    );
    assert_ne!(given, run);
}

#[test]
fn missing_or_malformed_results_are_named_with_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "walk", 4, true_line);
    let results = dir.path().join("peers");
    let good: String = (0..4).map(|k| true_line(k) + "\n").collect();
    write_results(&results, "tre", "kcf", "walk", 1, &good);
    let eval = |extra: &[&str]| {
        let mut args = vec![
            "eval",
            "otb",
            s(&seq),
            "--tracker",
            "m1",
            "--protocol",
            "tre",
            "--out",
        ];
        let out = dir.path().join("out");
        let out = s(&out).to_owned();
        args.push(&out);
        args.push("--quiet");
        args.extend_from_slice(extra);
        track(&args)
    };
    let arg = format!("kcf={}", s(&results));
    // TRE on 4 frames: starts 0, 1, 2 (⌊i·4/10⌋ = 0,0,0,1,1,2,2,2,3,3; 3 has nothing after it):
    // run 1's file is missing.
    let o = eval(&["--results", &arg]);
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(
        e.contains("tre/kcf/walk.1.txt") && e.contains("missing"),
        "{e}"
    );
    write_results(&results, "tre", "kcf", "walk", 3, &good);
    std::fs::write(
        results.join("tre/kcf/walk.2.txt"),
        "1,2,3,4\n1,2,3\n1,2,3,4\n1,2,3,4\n",
    )
    .unwrap();
    let o = eval(&["--results", &arg]);
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(
        e.contains("tre/kcf/walk.2.txt") && e.contains("line 2"),
        "{e}"
    );
    std::fs::write(results.join("tre/kcf/walk.2.txt"), &good[..good.len() / 2]).unwrap();
    let e = one_error_line(&eval(&["--results", &arg]));
    assert!(
        e.contains("walk.2.txt") && e.contains("for a sequence of 4 frames"),
        "{e}"
    );
    write_results(&results, "tre", "kcf", "walk", 3, &good);
    assert!(eval(&["--results", &arg]).status.success());
    // A bad NAME=DIR is a setting (exit 2).
    for bad in ["kcf", "=dir", "a/b=dir", "m1=dir"] {
        let o = eval(&["--results", bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(one_error_line(&o).contains("--"), "{bad}");
    }
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    let a = otb_folder(dir.path(), "a", 9, true_line);
    let b = otb_folder(dir.path(), "b", 7, |k| {
        if k % 3 == 1 {
            "0,0,0,0".into()
        } else {
            true_line(k)
        }
    });
    let mut outputs = Vec::new();
    for threads in [1, 2, 1] {
        let out = dir.path().join(format!("out{threads}_{}", outputs.len()));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            track_app::cli::try_main_from_args([
                "track",
                "eval",
                "otb",
                s(&a),
                s(&b),
                "--tracker",
                "m1",
                "--tracker",
                "w-eval",
                "--particles",
                "60",
                "--protocol",
                "tre",
                "--protocol",
                "sre",
                "--out",
                s(&out),
                "--quiet",
            ])
        })
        .unwrap();
        outputs.push(out);
    }
    // Everything but the frames/s column (timing) is the same, byte for byte.
    let without_fps = |out: &Path, p: &str| -> Vec<String> {
        csv_rows(out, p)
            .into_iter()
            .map(|mut r| {
                r.remove(9);
                r.join(",")
            })
            .collect()
    };
    for p in ["tre", "sre"] {
        let first = without_fps(&outputs[0], p);
        assert!(first.len() >= 4, "{first:?}");
        for other in &outputs[1..] {
            assert_eq!(without_fps(other, p), first, "{p}");
        }
        for tracker in ["m1", "w-eval"] {
            for entry in std::fs::read_dir(outputs[0].join(p).join(tracker)).unwrap() {
                let name = entry.unwrap().file_name();
                let want = std::fs::read(outputs[0].join(p).join(tracker).join(&name)).unwrap();
                for other in &outputs[1..] {
                    let got = std::fs::read(other.join(p).join(tracker).join(&name)).unwrap();
                    assert_eq!(got, want, "{p}/{tracker}/{name:?}");
                }
            }
        }
    }
}

/// `--frame-step 2` on a sequence scores exactly what every protocol scores on a folder made of
/// its odd-numbered frames: the same runs, from the same boxes, with the same box files.
#[test]
fn a_frame_step_scores_the_sequence_as_a_folder_of_the_frames_it_keeps() {
    let dir = tempfile::tempdir().unwrap();
    // Frame 2 is unlabelled, so the kept frames keep a gap; frame 5 is labelled but not kept.
    let label = |k: usize| match k {
        2 | 7 => "0,0,0,0".into(),
        _ => true_line(k),
    };
    let full = otb_folder(dir.path(), "walk", 21, label);
    let kept = dir.path().join("kept").join("walk");
    std::fs::create_dir_all(kept.join("img")).unwrap();
    let mut gt = String::new();
    for (j, k) in (0..21).step_by(2).enumerate() {
        std::fs::copy(
            full.join("img").join(format!("{:04}.png", k + 1)),
            kept.join("img").join(format!("{:04}.png", j + 1)),
        )
        .unwrap();
        gt.push_str(&(label(k) + "\n"));
    }
    std::fs::write(kept.join("groundtruth_rect.txt"), gt).unwrap();
    let eval = |seq: &Path, out: &Path, extra: &[&str]| {
        let mut args = vec![
            "eval",
            "otb",
            s(seq),
            "--tracker",
            "m1",
            "--particles",
            "50",
            "--protocol",
            "ope",
            "--protocol",
            "tre",
            "--protocol",
            "sre",
            "--out",
            s(out),
            "--quiet",
        ];
        args.extend_from_slice(extra);
        let o = track(&args);
        assert!(o.status.success(), "{}", common::stderr(&o));
    };
    let stepped = dir.path().join("stepped");
    let reference = dir.path().join("reference");
    eval(&full, &stepped, &["--frame-step", "2"]);
    eval(&kept, &reference, &[]);
    for p in ["ope", "tre", "sre"] {
        // Every column but frames/s.
        let rows = |out: &Path| -> Vec<Vec<String>> {
            csv_rows(out, p)
                .into_iter()
                .map(|mut r| {
                    r.remove(9);
                    r
                })
                .collect()
        };
        assert_eq!(rows(&stepped), rows(&reference), "{p}");
        let runs: usize = row(&csv_rows(&stepped, p), "walk", "m1")[3]
            .parse()
            .unwrap();
        assert!(runs >= 1, "{p}");
        for k in 0..runs {
            let name = if p == "ope" {
                "walk.txt".to_owned()
            } else {
                format!("walk.{k}.txt")
            };
            let read = |out: &Path| std::fs::read_to_string(out.join(p).join("m1").join(&name));
            let boxes = read(&stepped).unwrap();
            assert_eq!(boxes.lines().count(), 11, "{p} {name}");
            assert_eq!(boxes, read(&reference).unwrap(), "{p} {name}");
        }
    }
    let md = std::fs::read_to_string(stepped.join("tre").join("otb.md")).unwrap();
    assert!(md.contains("--frame-step 2"), "{md}");
    // A step that keeps no labelled frame is the ground truth's error (exit 3), a step of 0 a
    // setting's (exit 2).
    let odd = otb_folder(dir.path(), "odd", 6, |k| {
        if k % 2 == 1 {
            true_line(k)
        } else {
            "0,0,0,0".into()
        }
    });
    let out = dir.path().join("odd-out");
    let with_step = |step: &str| {
        track(&[
            "eval",
            "otb",
            s(&odd),
            "--tracker",
            "m1",
            "--frame-step",
            step,
            "--out",
            s(&out),
            "--quiet",
        ])
    };
    let o = with_step("2");
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(
        e.contains("groundtruth_rect.txt") && e.contains("--frame-step 2"),
        "{e}"
    );
    let o = with_step("0");
    assert_eq!(o.status.code(), Some(2));
    assert!(
        common::stderr(&o).contains("--frame-step"),
        "{}",
        common::stderr(&o)
    );
}

#[test]
fn paired_compares_two_trackers_seed_by_seed_and_refuses_what_it_cannot_pair() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "disc", 12, true_line);
    let run = |tracker: &str, seed: &str| {
        let out = dir.path().join(format!("{tracker}-{seed}"));
        let o = track(&[
            "eval",
            "otb",
            s(&seq),
            "--tracker",
            tracker,
            "--seed",
            seed,
            "--protocol",
            "ope",
            "--protocol",
            "tre",
            "--out",
            s(&out),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        out
    };
    let base: Vec<PathBuf> = ["1", "2", "3"].iter().map(|k| run("head", k)).collect();
    let variant: Vec<PathBuf> = ["1", "2", "3"].iter().map(|k| run("m1", k)).collect();
    let report = dir.path().join("paired.md");
    let o = paired(&base, &variant, &["--out", s(&report)]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    // The protocols every folder holds, each with its one sequence; the file holds the same.
    assert!(text.contains("## OPE: the variant helps"), "{text}");
    assert!(text.contains("## TRE: the variant helps"), "{text}");
    assert!(!text.contains("## SRE"), "{text}");
    assert!(text.contains("3 pairs (seeds)"), "{text}");
    assert_eq!(
        std::fs::read_to_string(&report).unwrap().trim_end(),
        text.trim_end()
    );
    // Each column is the mean over the seeds of what `track eval otb` wrote.
    let mean_auc = |dirs: &[PathBuf], tracker: &str| {
        dirs.iter()
            .map(|d| {
                row(&csv_rows(d, "tre"), "disc", tracker)[6]
                    .parse::<f64>()
                    .unwrap()
            })
            .sum::<f64>()
            / dirs.len() as f64
    };
    let tre = &text[text.find("## TRE").unwrap()..];
    let line = tre.lines().find(|l| l.starts_with("| disc |")).unwrap();
    let cells: Vec<&str> = line.split('|').map(str::trim).collect();
    assert_eq!(
        cells[2],
        format!("{:.3}", mean_auc(&base, "head")),
        "{line}"
    );
    assert_eq!(
        cells[3],
        format!("{:.3}", mean_auc(&variant, "m1")),
        "{line}"
    );
    // What cannot be paired is refused, naming why: one seed, unequal counts, no results.
    for (b, v) in [(&base[..1], &variant[..1]), (&base[..], &variant[..2])] {
        let o = paired(b, v, &[]);
        assert_eq!(o.status.code(), Some(2));
        assert!(
            one_error_line(&o).contains("at least two"),
            "{}",
            common::stderr(&o)
        );
    }
    let o = paired(
        &base,
        &[dir.path().into(), dir.path().into(), dir.path().into()],
        &[],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(one_error_line(&o).contains("no protocol"));
    // A malformed otb.csv is bad input (exit 3), named by its path.
    let broken = dir.path().join("broken");
    std::fs::create_dir_all(broken.join("tre")).unwrap();
    std::fs::write(broken.join("tre/otb.csv"), "protocol,sequence\ntre,disc\n").unwrap();
    let o = paired(
        &base,
        &[broken.clone(), broken.clone(), broken.clone()],
        &["--protocol", "tre"],
    );
    assert_eq!(o.status.code(), Some(3));
    assert!(one_error_line(&o).contains("otb.csv"));
}
