//! `track run`: track an object through a sequence and write what the tracker believed.
//!
//! The command's arguments and its driver are here; [`settings`] turns the options into a
//! tracker configuration, `frames` runs the frame loop, `outputs` writes what it produced.

use std::path::{Path, PathBuf};

use indicatif::ProgressBar;
use trackers::TrackerConfig;
use vision_core::{BoundingBox, Ellipse};

use crate::groundtruth::{BoxInFrame, check_groundtruth_len, first_box_in_frame, load_groundtruth};
use crate::progress::stream_progress;
use crate::render::OverlayFormat;
use crate::sequence::{FrameSource, Sequence, Source, open_sequence};
use crate::session::{ColourBy, DrawOptions, Session};
use crate::signals;
use crate::{AppError, Result};
use outputs::{Kept, write_outputs};

mod frames;
mod outputs;
pub mod settings;
mod thinned;

pub use crate::progress::{progress, progress_of, progress_to, rate_in, rate_text};
pub(crate) use outputs::score;
pub use outputs::{OUTPUT_FILES, gif_delay_ms, prepare_out};
pub use settings::{
    AXIS_ANGLE_TOLERANCE, MAX_EDGE_THRESHOLD, Overrides, initial_ellipse_for, parse_box,
    parse_edge_threshold, parse_ellipse, tracker_config,
};

/// The tracker `track run` uses when neither `--tracker` nor `--config` names one.
pub const DEFAULT_TRACKER: &str = "head";
/// Default number of particles.
pub const DEFAULT_PARTICLES: usize = trackers::DEFAULT_PARTICLES;
/// Default seed.
pub const DEFAULT_SEED: u64 = trackers::DEFAULT_SEED;
/// Default largest number of frames put in the animated GIF (`--gif-frames`; longer runs use
/// every k-th overlay).
pub const GIF_MAX_FRAMES: usize = 150;
/// Display time of one GIF frame when every overlay is in it, milliseconds (12 frames/s).
pub const GIF_FRAME_MS: u32 = 1000 / 12;
/// Longest display time of one GIF frame, milliseconds: a GIF of every k-th overlay shows each
/// k times longer, up to this.
pub const GIF_MAX_DELAY_MS: u32 = 250;
/// Number of overlay frames in the report's strip.
pub const STRIP_FRAMES: usize = 8;

/// Arguments of `track run`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    track run ../shared/data/real/girl_mil --tracker m3 --out girl --overlay --report\n  \
    track run frames/ --init 120,40,60,70 --tracker w-eval --plots\n  \
    track run clip.mp4 --init 100,80,60,70 --out clip --overlay\n  \
    ffmpeg -i video.mp4 -f yuv4mpegpipe - | track run - --init 100,80,60,70 --out video\n\n\
    Outputs in --out: track.csv, boxes.txt, summary.json; overlay/NNNN.png or .jpg (--overlay), \
    track.gif (--gif), plots/*.svg (--plots), report.html (--report).\n\n\
    Overlays: the estimate is a thick contour over a dark halo, coloured by status (locked \
    green, partial orange, lost red) or clutter class (--colour-by clutter); faint thin contours \
    are the heaviest particles; a white dashed box is the ground truth; frame 1 shows the \
    initial contour in white; the frame number and status are written at the top left.")]
pub struct Args {
    /// A folder of images (PNG, JPEG, GIF, BMP, WebP, TIFF; in natural order of their names), an
    /// OTB folder (img/ + groundtruth_rect.txt), a video file (.mp4, .mov, .avi, .mkv, …: any file
    /// but .y4m, decoded by ffmpeg, which must be on PATH), a .y4m file, or - for Y4M on standard
    /// input.
    pub sequence: String,
    /// Tracker preset [default: head, recommended for real footage]. Not with --config, which
    /// names its own tracker.
    #[arg(long, value_parser = crate::commands::preset_parser(), conflicts_with = "config")]
    pub tracker: Option<String>,
    /// Number of particles [default: 200, or the configuration file's].
    #[arg(long)]
    pub particles: Option<usize>,
    /// Random seed [default: 1, or the configuration file's].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Initial box x,y,w,h on the first frame (default: the first labelled box of an OTB folder).
    /// A box may start left of or above the frame: --init -20,-20,44,56.
    #[arg(
        long,
        value_parser = parse_box,
        conflicts_with = "init_ellipse",
        allow_hyphen_values = true
    )]
    pub init: Option<BoundingBox>,
    /// Initial ellipse cx,cy,a,b,angle (angle in radians) on the first frame. Only the w-*
    /// trackers rotate; the others refuse an angle that is not a multiple of π/2.
    #[arg(long, value_parser = parse_ellipse, allow_hyphen_values = true)]
    pub init_ellipse: Option<Ellipse>,
    /// A tracker configuration (JSON or TOML, the `TrackerConfig` of the trackers crate); replaces
    /// the preset.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "track-out")]
    pub out: PathBuf,
    /// Write overlay frames into OUT/overlay/ (NNNN.png, or NNNN.jpg with --overlay-format jpeg).
    #[arg(long)]
    pub overlay: bool,
    /// File format of the overlay frames: png (lossless) or jpeg (quality 90, several times
    /// smaller; docs/RESULTS.md gives sizes).
    #[arg(long, value_enum, default_value_t)]
    pub overlay_format: OverlayFormat,
    /// Write an animated GIF of the overlays, OUT/track.gif. It holds at most --gif-frames
    /// frames: a longer run puts every k-th overlay in it (k as small as fits), and says so.
    #[arg(long)]
    pub gif: bool,
    /// Put every N-th overlay in the GIF, from the first, until it holds --gif-frames frames
    /// (then the GIF ends before the run does) [default: the smallest N that fits the whole run].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub gif_stride: Option<u32>,
    /// Most frames in the GIF (each is kept in memory until the end of the run).
    #[arg(long, value_name = "N", default_value_t = GIF_MAX_FRAMES as u32,
          value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub gif_frames: u32,
    /// Write SVG plots of β̂, λ̂, γ̂, α̂ and ESS into OUT/plots/.
    #[arg(long)]
    pub plots: bool,
    /// Write a self-contained HTML report, OUT/report.html.
    #[arg(long)]
    pub report: bool,
    /// What colours the contour in overlays.
    #[arg(long, value_enum, default_value_t)]
    pub colour_by: ColourBy,
    /// Use all cores: the cluster motions beside the appearance's detection, and the particles'
    /// weights in chunks (same results as one core).
    #[arg(long)]
    pub parallel: bool,
    /// Edge threshold of the measurement lines, grey levels per pixel [default: the preset's, 8,
    /// the value the synthetic clutter is calibrated for]. Real footage is more textured: on
    /// girl_mil 24 works better (docs/RESULTS.md). Refused (exit 2) for a tracker without
    /// measurement lines (head), which would not read it.
    #[arg(long, value_parser = parse_edge_threshold)]
    pub edge_threshold: Option<f32>,
    /// Also smooth the run once every frame is tracked (forward filtering–backward smoothing of
    /// the recorded particles: each frame's estimate given the whole sequence) and write
    /// OUT/smoothed.csv (the columns of track.csv) and OUT/smoothed_boxes.txt; the plots draw
    /// both. Memory grows with frames × particles. Every tracker is smoothed, head included (it
    /// runs on the same engine; the smoother's transition density leaves out its reacquisition
    /// jumps, as it does every tracker's); not written for a run that is interrupted.
    #[arg(long)]
    pub smooth: bool,
    /// No progress bar, no notice (such as the GIF's) and no summary.
    #[arg(long)]
    pub quiet: bool,
}

/// The progress bar of the pre-scan of `source` (every frame decoded once before tracking),
/// hidden when `quiet`; a spinner when the number of frames is not known before.
fn prescan_progress(source: &Source, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = match source.len() {
        Some(n) => progress(n as u64, false, ""),
        None => stream_progress(false),
    };
    bar.set_message("checking the frames");
    bar
}

/// Pre-scans `source` ([`FrameSource::validate_all_with`]), moving `bar` on at each frame
/// checked and calling `stop` (a signal check) there; clears the bar at the end.
///
/// # Errors
/// The pre-scan's error, or `stop`'s.
pub fn prescan(
    source: &Source,
    bar: &ProgressBar,
    stop: &dyn Fn() -> Result<()>,
) -> Result<crate::sequence::SequenceInfo> {
    let info = source.validate_all_with(&mut |checked| {
        bar.set_position(checked as u64);
        stop()
    });
    bar.finish_and_clear();
    info
}

/// Runs `track run`.
///
/// Inputs are checked before anything is written: a folder or a `.y4m` file is pre-scanned
/// whole; Y4M on standard input is a stream, read and checked one frame at a time in constant
/// memory (its header is checked first). Then `--out` is prepared ([`prepare_out`]) and the
/// frames are tracked, overlays written as they come. Ctrl-C or SIGTERM, or an error in a
/// stream, stops the run after the current frame: `track.csv`, `boxes.txt`, `summary.json` (with
/// `"interrupted"`) and the other outputs asked for are written for the frames tracked so far,
/// and the run exits with 128 + the signal number (or the error's code).
///
/// # Errors
/// See [`AppError`].
pub fn run(args: &Args) -> Result<()> {
    let started = std::time::Instant::now();
    // First of all, so that a signal during the checks ends the run cleanly, with a message.
    let signals = signals::StopSignals::install()?;
    let (input, source) = CheckedInput::open(args, &signals)?;
    let tracker = trackers::build(input.config.clone())
        .map_err(|e| AppError::setting("--tracker", e.to_string()))?;
    // Everything the run reads is checked; now the output folder, before any tracking. It stays
    // locked until the outputs are written.
    let inputs: Vec<&Path> = [
        Some(Path::new(&args.sequence)),
        input.groundtruth.as_deref(),
        args.config.as_deref(),
    ]
    .into_iter()
    .flatten()
    .filter(|p| *p != Path::new("-"))
    .collect();
    let _folder = prepare_out(&args.out, &inputs, args.overlay, args.plots)?;
    signals.stop_if_received()?;

    let draw = (args.overlay || args.gif || args.report).then(|| DrawOptions {
        colour_by: args.colour_by,
        ..DrawOptions::default()
    });
    let session = Session::new(tracker, draw);
    let mut kept = Kept::new(args, input.known_frames, input.start);
    let bar = match input.known_frames.or(input.expected_frames) {
        Some(n) => progress(n as u64, args.quiet, ""),
        None => stream_progress(args.quiet),
    };
    bar.set_message(format!("{} on {}", input.config.name, input.name));
    let frames = frames::Frames {
        start: input.start,
        init: &input.init,
        truth: input.truth.as_deref(),
        signals: &signals,
        bar: &bar,
    };
    let mut tracked = frames.track(args, source, session, &mut kept)?;
    tracked.wall_seconds = started.elapsed().as_secs_f64();
    write_outputs(args, &input, tracked, kept)
}

/// Everything `track run` reads, checked before anything is written.
struct CheckedInput {
    config: TrackerConfig,
    /// A short name of the sequence for reports.
    name: String,
    /// Frames per second, when the input states it.
    frame_rate: Option<f64>,
    /// The number of frames, unless the input is a stream.
    known_frames: Option<usize>,
    /// The number of frames a stream is expected to have (ffprobe's count for a video file),
    /// for the progress bar only.
    expected_frames: Option<usize>,
    width: usize,
    height: usize,
    /// The ground truth of an OTB folder, one box (or none) per frame.
    truth: Option<Vec<Option<BoundingBox>>>,
    /// The first frame tracked (the first labelled one when the ground truth gives the start).
    start: usize,
    /// The contour the tracker starts from.
    init: Ellipse,
    /// The ground-truth file, when the input has one.
    groundtruth: Option<PathBuf>,
}

impl CheckedInput {
    /// Checks the settings and the input; returns them with the frames to track.
    fn open(args: &Args, signals: &signals::StopSignals) -> Result<(Self, Source)> {
        let mut config = tracker_config(
            args.tracker.as_deref().unwrap_or(DEFAULT_TRACKER),
            args.config.as_deref(),
            Overrides {
                particles: args.particles,
                seed: args.seed,
                parallel: args.parallel,
                edge_threshold: args.edge_threshold,
            },
        )?;
        if args.smooth {
            config.filter.history = Some(Default::default());
        }
        let sequence = open_sequence(&args.sequence)?;
        let (known_frames, width, height) = if sequence.source.is_stream() {
            let (w, h) = sequence
                .source
                .frame_size()
                .ok_or_else(|| AppError::input(&args.sequence, "a stream without a frame size"))?;
            (None, w, h)
        } else {
            let info = prescan(
                &sequence.source,
                &prescan_progress(&sequence.source, args.quiet),
                &|| signals.stop_if_received(),
            )?;
            (Some(info.frames), info.width, info.height)
        };
        let truth = checked_truth(sequence.groundtruth.as_deref(), known_frames)?;
        let (start, init) =
            initial_contour(args, &config, &sequence, truth.as_deref(), (width, height))?;
        let input = Self {
            config,
            name: sequence.name,
            frame_rate: sequence.source.frame_rate(),
            known_frames,
            expected_frames: sequence.source.expected_frames(),
            width,
            height,
            truth,
            start,
            init,
            groundtruth: sequence.groundtruth.clone(),
        };
        Ok((input, sequence.source))
    }
}

/// The ground truth of a sequence whose frames are counted, checked against their count; `None`
/// for a stream or a sequence without one.
pub(crate) fn checked_truth(
    groundtruth: Option<&Path>,
    known_frames: Option<usize>,
) -> Result<Option<Vec<Option<BoundingBox>>>> {
    match (groundtruth, known_frames) {
        (Some(path), Some(frames)) => {
            let t = load_groundtruth(path)?;
            check_groundtruth_len(&t, frames, path)?;
            Ok(Some(t))
        }
        _ => Ok(None),
    }
}

/// The first frame and the initial contour: `--init`, `--init-ellipse`, or the first box of the
/// ground truth that lies in the frame.
fn initial_contour(
    args: &Args,
    config: &TrackerConfig,
    sequence: &Sequence,
    truth: Option<&[Option<BoundingBox>]>,
    (width, height): (usize, usize),
) -> Result<(usize, Ellipse)> {
    match (args.init, args.init_ellipse, truth) {
        (Some(b), _, _) => {
            b.validate_in_frame(width, height, "--init")?;
            Ok((0, b.inscribed_ellipse()))
        }
        (None, Some(e), _) => {
            e.bounding_box()
                .validate_in_frame(width, height, "--init-ellipse")?;
            Ok((0, initial_ellipse_for(&e, config)?))
        }
        (None, None, Some(t)) => {
            let path = sequence
                .groundtruth
                .as_deref()
                .unwrap_or(Path::new("ground truth"));
            let (k, b) = first_box_in_frame(t, path, &sequence.name, width, height)?;
            Ok((k, b.inscribed_ellipse()))
        }
        (None, None, None) => Err(AppError::setting(
            "--init",
            "this sequence has no ground truth: give --init x,y,w,h or --init-ellipse",
        )),
    }
}

/// The command line as typed, for the report: the program's file name and the arguments, each
/// quoted for a POSIX shell when it holds anything but letters, digits and `-_.,/:=+@%`.
pub fn command_line(args: impl IntoIterator<Item = std::ffi::OsString>) -> String {
    let mut words = Vec::new();
    for (i, a) in args.into_iter().enumerate() {
        let a = a.to_string_lossy().into_owned();
        let a = if i == 0 {
            Path::new(&a)
                .file_name()
                .map_or(a.clone(), |n| n.to_string_lossy().into_owned())
        } else {
            a
        };
        let plain = !a.is_empty()
            && a.chars()
                .all(|c| c.is_alphanumeric() || "-_.,/:=+@%".contains(c));
        words.push(if plain {
            a
        } else {
            format!("'{}'", a.replace('\'', "'\\''"))
        });
    }
    words.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prescan_moves_its_progress_bar_once_per_frame() {
        let dir = tempfile::tempdir().unwrap();
        for k in 1..=5 {
            image::RgbImage::new(8, 6)
                .save(dir.path().join(format!("{k}.png")))
                .unwrap();
        }
        let source = crate::sequence::open_sequence(dir.path().to_str().unwrap())
            .unwrap()
            .source;
        let bar = ProgressBar::hidden();
        bar.set_length(5);
        let seen = std::cell::RefCell::new(Vec::new());
        let info = prescan(&source, &bar, &|| {
            seen.borrow_mut().push(bar.position());
            Ok(())
        })
        .unwrap();
        assert_eq!(info.frames, 5);
        assert_eq!(*seen.borrow(), vec![1, 2, 3, 4, 5]);
        // A stop (a signal) ends the pre-scan at once.
        let stopped = prescan(&source, &ProgressBar::hidden(), &|| {
            Err(AppError::setting("signal", "stop"))
        });
        assert!(stopped.is_err());
    }

    #[test]
    fn the_command_line_is_quoted_for_a_shell() {
        let args = [
            "/opt/bin/track",
            "run",
            "my clips/a.mp4",
            "--init",
            "-20,-20,44,56",
            "--out",
            "it's",
        ]
        .map(std::ffi::OsString::from);
        assert_eq!(
            command_line(args),
            "track run 'my clips/a.mp4' --init -20,-20,44,56 --out 'it'\\''s'"
        );
    }
}
