//! Wrong or misleading messages. Each error names the option or the file at
//! fault, says what is wrong in one short line, and has the exit code of docs/CLI.md's table
//! (2 arguments and settings, `--config` files included; 3 input data; 4 outputs).

use crate::common;

use common::{DISC_INIT, disc_frames, one_error_line, s, track};

#[test]
fn edge_threshold_nan_names_edge_threshold_not_particles_or_config() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    let out = dir.path().join("out");
    let config = dir.path().join("m1.json");
    std::fs::write(&config, track(&["config", "m1"]).stdout).unwrap();
    for extra in [vec![], vec!["--config", s(&config)]] {
        let mut args = vec![
            "run",
            s(&frames),
            "--init",
            DISC_INIT,
            "--out",
            s(&out),
            "--quiet",
            "--edge-threshold",
            "NaN",
        ];
        args.extend(extra);
        let o = track(&args);
        assert_eq!(o.status.code(), Some(2));
        // Refused by the argument parser, whose message ends with a hint line.
        let e = common::stderr(&o);
        let e = e.lines().next().unwrap_or_default();
        assert!(e.starts_with("error: "), "{e}");
        assert!(e.contains("--edge-threshold") && e.contains("NaN"), "{e}");
        assert!(!e.contains("--particles") && !e.contains("--config"), "{e}");
    }
    // A bad --particles is still blamed on --particles, even with a configuration file.
    let o = track(&[
        "run",
        s(&frames),
        "--init",
        DISC_INIT,
        "--out",
        s(&out),
        "--config",
        s(&config),
        "--particles",
        "0",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(one_error_line(&o).contains("--particles"));
}

#[test]
fn first_ground_truth_box_outside_the_frame_names_file_line_and_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("Walker");
    disc_frames(&seq, "img", 3);
    let gt = seq.join("groundtruth_rect.txt");
    std::fs::write(&gt, "0,0,0,0\n1e300,10,20,20\n30,30,20,20\n").unwrap();
    for args in [
        vec![
            "run",
            s(&seq),
            "--out",
            s(&dir.path().join("out")),
            "--quiet",
        ],
        vec![
            "eval",
            "otb",
            s(&seq),
            "--tracker",
            "m1",
            "--out",
            s(&dir.path().join("eval")),
            "--quiet",
        ],
    ] {
        let o = track(&args);
        // The ground truth is input data: exit 3, as for any other bad line in it.
        assert_eq!(o.status.code(), Some(3), "{args:?}");
        let e = one_error_line(&o);
        assert!(
            e.contains("groundtruth_rect.txt") && e.contains("line 2"),
            "{e}"
        );
        assert!(e.contains("Walker") && e.contains("outside"), "{e}");
        // 1e300 is written as such, not as 301 digits.
        assert!(
            e.contains("1e300") && e.len() < 300,
            "{} bytes: {e}",
            e.len()
        );
    }
}

#[test]
fn configuration_files_that_do_not_parse_or_hold_bad_values_are_both_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    let out = dir.path().join("out");
    let good: serde_json::Value = serde_json::from_slice(&track(&["config", "m1"]).stdout).unwrap();
    let mut zero = good.clone();
    zero["particles"] = 0.into();
    // A translation noise that passed validation and failed at frame 1 ("estimated
    // contour is not finite") is refused up front, by its dotted path and range.
    let mut wild = good.clone();
    wild["dynamics"]["sigma_translation"] = 1e308.into();
    let cases = [
        (
            "broken.json",
            "{ \"particles\": ".to_owned(),
            "invalid JSON",
        ),
        ("broken.toml", "particles = [".to_owned(), "invalid TOML"),
        ("zero.json", zero.to_string(), "particles"),
        (
            "wild.json",
            wild.to_string(),
            "dynamics.sigma_translation`: 1e308 is outside (0, 1000]",
        ),
        ("missing.json", String::new(), "cannot read"),
    ];
    for (name, text, what) in cases {
        let path = dir.path().join(name);
        if name != "missing.json" {
            std::fs::write(&path, text).unwrap();
        }
        let o = track(&[
            "run",
            s(&frames),
            "--init",
            DISC_INIT,
            "--out",
            s(&out),
            "--config",
            s(&path),
        ]);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let e = one_error_line(&o);
        assert!(
            e.contains("--config") && e.contains(name) && e.contains(what),
            "{e}"
        );
    }
}

#[test]
fn roi_outside_the_image_is_exit_2_naming_roi() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    let (a, b) = (frames.join("0001.png"), frames.join("0002.png"));
    for roi in ["500,500,10,10", "-50,10,20,20", "10,100,5,5"] {
        let o = track(&["motion", s(&a), s(&b), &format!("--roi={roi}")]);
        assert_eq!(o.status.code(), Some(2), "{roi}");
        let e = one_error_line(&o);
        assert!(
            e.contains("--roi") && e.contains("outside the 96×72"),
            "{e}"
        );
    }
    // Inside the image but too small for the model: still the region's fault.
    let o = track(&["motion", s(&a), s(&b), "--roi", "94,70,2,2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(one_error_line(&o).contains("--roi"));
}

#[test]
fn y4m_header_ending_in_crlf_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (48, 36);
    let mut bytes = format!("YUV4MPEG2 W{w} H{h} F25:1 C420jpeg\r\n").into_bytes();
    for k in 0..3 {
        bytes.extend_from_slice(b"FRAME\n");
        for y in 0..h {
            for x in 0..w {
                let inside =
                    (x as f64 - 16.0 - k as f64).powi(2) + (y as f64 - 18.0).powi(2) < 64.0;
                bytes.push(if inside { 200 } else { 40 });
            }
        }
        bytes.extend(std::iter::repeat_n(128u8, 2 * (w / 2) * (h / 2)));
    }
    let video = dir.path().join("crlf.y4m");
    std::fs::write(&video, bytes).unwrap();
    let out = dir.path().join("out");
    let o = track(&[
        "run",
        s(&video),
        "--init",
        "8,10,16,16",
        "--tracker",
        "m1",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert_eq!(common::summary(&out)["frames"], 3);
    // A colour space that really is unknown is quoted, so a stray control character would show.
    std::fs::write(&video, b"YUV4MPEG2 W2 H2 C411\r\nFRAME\n\0\0\0\0\0\0\0\0").unwrap();
    let o = track(&["run", s(&video), "--init", "0,0,2,2", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(e.contains("\"C411\"") && e.contains("supported"), "{e}");
}

#[test]
fn folders_of_gif_bmp_webp_and_tiff_frames_are_read() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["gif", "bmp", "webp", "tiff", "tif", "BMP"] {
        let folder = dir.path().join(ext);
        std::fs::create_dir(&folder).unwrap();
        for k in 0..3 {
            common::disc_image(30.0 + 2.0 * f64::from(k))
                .save_with_format(
                    folder.join(format!("{:04}.{ext}", k + 1)),
                    image::ImageFormat::from_extension(ext).unwrap(),
                )
                .unwrap();
        }
        let out = dir.path().join(format!("out-{ext}"));
        let o = track(&[
            "run",
            s(&folder),
            "--init",
            DISC_INIT,
            "--tracker",
            "m1",
            "--out",
            s(&out),
            "--quiet",
        ]);
        assert!(o.status.success(), "{ext}: {}", common::stderr(&o));
        assert_eq!(common::summary(&out)["frames"], 3, "{ext}");
        assert_eq!(common::summary(&out)["width"], 96, "{ext}");
    }
    // A folder of other files says what is supported and what it found.
    let other = dir.path().join("heic");
    std::fs::create_dir(&other).unwrap();
    for name in ["a.heic", "b.heic", "notes.txt", "README"] {
        std::fs::write(other.join(name), "x").unwrap();
    }
    let o = track(&["run", s(&other), "--init", DISC_INIT]);
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    for part in [
        ".png",
        ".gif",
        ".bmp",
        ".webp",
        ".tiff",
        ".heic ×2",
        ".txt ×1",
        "no extension ×1",
    ] {
        assert!(e.contains(part), "{part}: {e}");
    }
}

/// A PNG whose header claims 60000×60000 RGB pixels (10 GB decoded), with a few bytes of data.
fn huge_png() -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
        out.extend((data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend(kind);
        out.extend(data);
        let crc = crc32(&out[start..]);
        out.extend(crc.to_be_bytes());
    }
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = 0xFFFF_FFFFu32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend(60_000u32.to_be_bytes());
    ihdr.extend(60_000u32.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    // A stored (uncompressed) zlib stream of 5 zero bytes.
    chunk(
        &mut png,
        b"IDAT",
        &[
            0x78, 0x01, 0x01, 0x05, 0x00, 0xFA, 0xFF, 0, 0, 0, 0, 0, 0, 0x05, 0x00, 0x01,
        ],
    );
    chunk(&mut png, b"IEND", &[]);
    png
}

#[test]
fn a_decoder_memory_limit_is_reported_as_too_large_by_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("big");
    std::fs::create_dir(&folder).unwrap();
    let png = folder.join("0001.png");
    std::fs::write(&png, huge_png()).unwrap();
    for args in [
        vec![
            "run",
            s(&folder),
            "--init",
            "1,1,5,5",
            "--out",
            s(&dir.path().join("o")),
        ],
        vec!["motion", s(&png), s(&png)],
        vec![
            "learn-clutter",
            s(&png),
            "--out",
            s(&dir.path().join("c.json")),
        ],
    ] {
        let o = track(&args);
        assert_eq!(o.status.code(), Some(3), "{args:?}");
        let e = one_error_line(&o);
        assert!(
            e.contains("0001.png") && e.contains("image too large"),
            "{e}"
        );
        assert!(!e.contains("corrupt"), "{e}");
    }
}

#[test]
fn an_out_that_is_a_file_is_named_as_such_by_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    let seq = dir.path().join("otb");
    disc_frames(&seq, "img", 2);
    std::fs::write(
        seq.join("groundtruth_rect.txt"),
        "18,24,24,24\n20,24,24,24\n",
    )
    .unwrap();
    let file = dir.path().join("taken");
    std::fs::write(&file, "precious").unwrap();
    let inside = file.join("sub");
    let png = frames.join("0001.png");
    for args in [
        vec![
            "run",
            s(&frames),
            "--init",
            DISC_INIT,
            "--out",
            s(&file),
            "--quiet",
        ],
        vec![
            "run",
            s(&frames),
            "--init",
            DISC_INIT,
            "--out",
            s(&inside),
            "--quiet",
        ],
        vec!["demo", "--out", s(&file), "--quiet"],
        vec![
            "eval",
            "otb",
            s(&seq),
            "--tracker",
            "m1",
            "--out",
            s(&file),
            "--quiet",
        ],
        vec!["eval", "switching", "--frames", "2", "--out", s(&file)],
        vec![
            "learn-clutter",
            s(&png),
            "--lines",
            "100",
            "--out",
            s(&inside),
        ],
    ] {
        let o = track(&args);
        assert_eq!(o.status.code(), Some(4), "{args:?}: {}", common::stderr(&o));
        let e = one_error_line(&o);
        assert!(
            e.contains("taken") && e.contains("is a file, not a folder"),
            "{e}"
        );
        assert!(!e.contains("os error"), "{e}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "precious");
}

#[test]
fn a_folder_named_groundtruth_rect_txt_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("seq");
    disc_frames(&seq, "img", 2);
    std::fs::create_dir(seq.join("groundtruth_rect.txt")).unwrap();
    for args in [
        vec!["run", s(&seq), "--out", s(&dir.path().join("o"))],
        vec![
            "eval",
            "otb",
            s(&seq),
            "--tracker",
            "m1",
            "--out",
            s(&dir.path().join("e")),
        ],
    ] {
        let o = track(&args);
        assert_eq!(o.status.code(), Some(3), "{args:?}");
        let e = one_error_line(&o);
        assert!(
            e.contains("groundtruth_rect.txt") && e.contains("not a file"),
            "{e}"
        );
        assert!(!e.contains("no ground truth"), "{e}");
    }
}

#[test]
fn config_validates_before_printing_and_names_particles() {
    for (n, shown) in [("0", "0"), ("1000000000000", "1e12")] {
        let o = track(&["config", "m1", "--particles", n]);
        assert_eq!(o.status.code(), Some(2), "--particles {n}");
        assert!(o.stdout.is_empty(), "nothing printed for --particles {n}");
        let e = one_error_line(&o);
        assert!(e.contains("--particles") && e.contains(shown), "{e}");
    }
}

#[test]
fn an_initial_box_that_cannot_work_names_init_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let tiny = dir.path().join("tiny");
    std::fs::create_dir(&tiny).unwrap();
    for k in 1..=2 {
        image::GrayImage::from_pixel(8, 8, image::Luma([100]))
            .save(tiny.join(format!("{k:04}.png")))
            .unwrap();
    }
    let out = dir.path().join("out");
    let o = track(&["run", s(&tiny), "--init", "0,0,8,8", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let e = one_error_line(&o);
    assert!(
        e.contains("--init") && e.contains("semi-axes 4 and 4"),
        "{e}"
    );
    assert!(
        !e.contains("Ellipse {") && !e.contains("cx:"),
        "no debug struct: {e}"
    );
}

#[test]
fn a_box_starting_left_of_and_above_the_frame_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 3);
    let out = dir.path().join("out");
    for (flag, value) in [
        ("--init", "-4,-6,40,44"),
        ("--init-ellipse", "-2,30,12,12,0"),
    ] {
        let o = track(&[
            "run",
            s(&frames),
            flag,
            value,
            "--tracker",
            "m1",
            "--out",
            s(&out),
            "--quiet",
        ]);
        if flag == "--init" {
            assert!(o.status.success(), "{flag} {value}: {}", common::stderr(&o));
            assert_eq!(common::summary(&out)["frames"], 3);
        } else {
            // Parsed (not mistaken for an option); the centre left of the frame is then refused
            // by name.
            assert_eq!(o.status.code(), Some(2));
            let e = one_error_line(&o);
            assert!(e.contains("--init-ellipse") || e.contains("initial"), "{e}");
        }
    }
}

#[test]
fn edge_thresholds_out_of_range_are_quoted_as_typed() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    let out = dir.path().join("out");
    for value in ["1e308", "0", "-3", "1001"] {
        let arg = format!("--edge-threshold={value}");
        let o = track(&[
            "run",
            s(&frames),
            "--init",
            DISC_INIT,
            "--out",
            s(&out),
            &arg,
        ]);
        assert_eq!(o.status.code(), Some(2), "{value}");
        let e = common::stderr(&o);
        let first = e.lines().next().unwrap_or_default();
        assert!(
            first.contains(value) && first.contains("(0, 1000]"),
            "{first}"
        );
        assert!(!first.contains("inf"), "{first}");
    }
}

#[test]
fn tracker_and_config_together_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    let config = dir.path().join("m1.toml");
    std::fs::write(&config, track(&["config", "m1", "--toml"]).stdout).unwrap();
    let out = dir.path().join("out");
    let o = track(&[
        "run",
        s(&frames),
        "--init",
        DISC_INIT,
        "--config",
        s(&config),
        "--tracker",
        "m3",
        "--out",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = common::stderr(&o);
    assert!(e.contains("--config") && e.contains("--tracker"), "{e}");
    assert!(!out.exists());
    // An unknown preset is refused by the parser with the list of presets, head included.
    let o = track(&["run", s(&frames), "--tracker", "m9", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        common::stderr(&o).contains("head"),
        "{}",
        common::stderr(&o)
    );
}

#[test]
fn learn_clutter_names_its_options() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "f", 2);
    for (flag, name) in [("--k", "--k"), ("--lines", "--lines")] {
        let o = track(&["learn-clutter", s(&frames), flag, "0"]);
        assert_eq!(o.status.code(), Some(2), "{flag}");
        let e = one_error_line(&o);
        assert!(e.contains(name), "{e}");
        assert!(!e.contains("setting k"), "{e}");
    }
}

#[test]
fn every_preset_is_listed_by_config_help() {
    let o = track(&["config", "--help"]);
    let help = common::stdout(&o);
    for preset in trackers::Preset::ALL {
        assert!(
            help.contains(preset.name()),
            "{} missing from:\n{help}",
            preset.name()
        );
    }
}
