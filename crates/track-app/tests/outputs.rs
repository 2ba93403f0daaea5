//! Outputs people can read: what the overlays, the GIF and the report of `track run`
//! show, on the disc frames of [`common::disc_frames`].

use crate::common;

use std::path::Path;

use common::{DISC_INIT, disc_frames, s, stderr, summary, track};
use track_app::render::{INIT, draw_label};

/// `track run` on `frames` with m1, 40 particles, seed 3, and `extra` options, into `out`.
fn run(frames: &Path, out: &Path, tracker: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        s(frames),
        "--init",
        DISC_INIT,
        "--tracker",
        tracker,
        "--particles",
        "40",
        "--seed",
        "3",
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    let o = track(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

/// The label box at the top left of a frame under 480 rows: 2 px margin, 12 rows high.
const LABEL_ROWS: u32 = 16;

#[test]
fn overlays_carry_the_frame_number_and_frame_1_is_the_initialisation() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "seq", 4);
    let out = dir.path().join("out");
    run(&frames, &out, "m1", &["--overlay", "--quiet"]);
    let input = rgb(&frames.join("0001.png"));
    let first = rgb(&out.join("overlay/0001.png"));
    // Frame 1: the initial contour (the circle inscribed in --init: centre (30, 36), radius 12)
    // in white, and nothing else but its halo and the label: no particles.
    assert_eq!(first.get_pixel(42, 36).0, INIT);
    assert_eq!(first.get_pixel(30, 24).0, INIT);
    for (x, y, p) in first.enumerate_pixels() {
        if p == input.get_pixel(x, y) || y < LABEL_ROWS {
            continue;
        }
        let r = (f64::from(x) - 30.0).hypot(f64::from(y) - 36.0);
        assert!(
            (r - 12.0).abs() <= 4.0,
            "pixel ({x}, {y}) at radius {r:.1} painted"
        );
    }
    // The label: "frame N" in white on a dark box; m1 has no status, so no status word.
    for k in 1..=4 {
        let name = format!("{k:04}.png");
        let (overlay, mut expected) = (
            rgb(&out.join("overlay").join(&name)),
            rgb(&frames.join(&name)),
        );
        let text = if k == 1 {
            "frame 1  init".to_owned()
        } else {
            format!("frame {k}")
        };
        let swatch = overlay.get_pixel(5, 5).0;
        draw_label(&mut expected, &text, swatch);
        for y in 0..LABEL_ROWS {
            for x in 0..60 {
                assert_eq!(
                    overlay.get_pixel(x, y),
                    expected.get_pixel(x, y),
                    "frame {k}: ({x}, {y})"
                );
            }
        }
    }
}

#[test]
fn overlays_can_be_jpeg() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "seq", 3);
    let out = dir.path().join("out");
    run(
        &frames,
        &out,
        "m1",
        &["--overlay", "--overlay-format", "jpeg", "--quiet"],
    );
    for k in 1..=3 {
        let jpg = out.join(format!("overlay/{k:04}.jpg"));
        let bytes = std::fs::read(&jpg).unwrap();
        assert!(bytes.starts_with(&[0xFF, 0xD8, 0xFF]), "{}", jpg.display());
        assert!(!out.join(format!("overlay/{k:04}.png")).exists());
    }
    assert!(
        summary(&out)["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|o| o == "overlay/0003.jpg")
    );
    let o = track(&[
        "run",
        s(&frames),
        "--init",
        DISC_INIT,
        "--overlay-format",
        "gif",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// The number of frames of an animated GIF.
fn gif_frames(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    let decoder = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(bytes)).unwrap();
    image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .unwrap()
        .len()
}

#[test]
fn a_gif_that_drops_frames_says_so_and_its_stride_and_length_can_be_chosen() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "seq", 12);
    // At most 5 frames: every 3rd of the 12 (0, 3, 6, 9), and a notice.
    let out = dir.path().join("out");
    let o = run(&frames, &out, "m1", &["--gif", "--gif-frames", "5"]);
    let e = stderr(&o);
    assert!(
        e.contains("note: track.gif holds 4 of the 12 frames tracked (one every 3)"),
        "{e}"
    );
    assert_eq!(gif_frames(&out.join("track.gif")), 4);
    let gif = &summary(&out)["gif"];
    assert_eq!(
        (
            gif["frames"].as_u64(),
            gif["tracked"].as_u64(),
            gif["stride"].as_u64()
        ),
        (Some(4), Some(12), Some(3))
    );
    // A stride of 2, at most 3 frames: frames 1, 3 and 5, and the GIF says where it stops.
    let out2 = dir.path().join("out2");
    let o = run(
        &frames,
        &out2,
        "m1",
        &["--gif", "--gif-stride", "2", "--gif-frames", "3"],
    );
    assert!(
        stderr(&o).contains("up to frame 5 of the run"),
        "{}",
        stderr(&o)
    );
    assert_eq!(gif_frames(&out2.join("track.gif")), 3);
    // Every frame: no notice.
    let out3 = dir.path().join("out3");
    let o = run(&frames, &out3, "m1", &["--gif"]);
    assert!(!stderr(&o).contains("note:"), "{}", stderr(&o));
    assert_eq!(gif_frames(&out3.join("track.gif")), 12);
    for bad in [["--gif-stride", "0"], ["--gif-frames", "0"]] {
        let mut args = vec!["run", s(&frames), "--init", DISC_INIT, "--gif"];
        args.extend(bad);
        let o = track(&args);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(bad[0]), "{}", stderr(&o));
    }
    let help = common::stdout(&track(&["run", "--help"]));
    assert!(
        help.contains("--gif-stride") && help.contains("--gif-frames"),
        "{help}"
    );
}

#[test]
fn the_report_gives_the_command_line_both_rates_and_statuses_that_add_up() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "seq", 4);
    // head's lock chain: its γ̂ is P(lost), not an occlusion, and it has no partial state.
    let out = dir.path().join("head");
    run(&frames, &out, "head", &["--report", "--plots", "--quiet"]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains(&format!(
            "track run {} --init {DISC_INIT} --tracker head",
            s(&frames)
        )),
        "no command line"
    );
    assert!(html.contains("no decoding, no drawing") && html.contains("wall-clock rate"));
    assert!(!html.contains("occlusion γ̂") && !html.contains("P(partial)"));
    assert!(!out.join("plots/gamma.svg").exists());
    assert!(html.contains("<h3>Legend</h3>"));
    let counts = |html: &str| -> Vec<usize> {
        let row = html
            .split("<th>frames locked / partial / lost</th><td class=\"v\">")
            .nth(1)
            .unwrap();
        row.split("</td>")
            .next()
            .unwrap()
            .split(|c: char| !c.is_ascii_digit())
            .filter(|w| !w.is_empty())
            .map(|w| w.parse().unwrap())
            .collect()
    };
    let row = html
        .split("<th>frames locked / lost</th><td class=\"v\">")
        .nth(1)
        .expect("head's status row has no partial column");
    let lost: Vec<usize> = row
        .split("</td>")
        .next()
        .unwrap()
        .split(|c: char| !c.is_ascii_digit())
        .filter(|w| !w.is_empty())
        .map(|w| w.parse().unwrap())
        .collect();
    // Locked and lost add up to the 3 frames after the initialisation, which has no status.
    assert_eq!(lost[..2].iter().sum::<usize>(), 3, "{lost:?}");
    // w-eval has no status at the initialisation: the report says so, and the counts of the
    // other frames add up to 3.
    let out = dir.path().join("w-eval");
    run(&frames, &out, "w-eval", &["--report", "--quiet"]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("frame 1, the initialisation, has no status"));
    let c = counts(&html);
    assert_eq!(c[..3].iter().sum::<usize>(), 3, "{c:?}");
    assert!(html.contains("occlusion γ̂") || html.contains("tracker status α̂"));
}
