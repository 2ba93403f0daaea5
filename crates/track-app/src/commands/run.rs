//! `track run`: track an object through a sequence and write what the tracker believed.

use std::path::{Path, PathBuf};

use image::RgbImage;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};
use trackers::{Preset, TrackerConfig};
use vision_core::{BoundingBox, Ellipse, TrackStatus};

use crate::groundtruth::{
    BoxInFrame, check_groundtruth_len, first_box_in_frame, load_groundtruth, parse_box_arg,
    parse_ellipse_arg,
};
use crate::metrics::{SequenceMetrics, score_run};
use crate::plots::{all_figures_with, write_figures};
use crate::record::{
    CsvColumns, FrameRecord, GifSummary, Interruption, Summary, status_counts, write_summary,
    write_track_tables,
};
use crate::render::{OverlayFormat, thumbnail, write_gif};
use crate::report::{ReportInput, strip_indices, summary_rows, write_report};
use crate::sequence::{FrameSource, Sequence, Source, open_sequence};
use thinned::Thinned;

mod frames;
mod signals;
mod thinned;
use crate::session::{ColourBy, DrawOptions, Session};
use crate::{AppError, Result};

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
    /// Weight particles on all cores (same results as one core).
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
    /// both. Memory grows with frames × particles; not for the head tracker, nor for a run that
    /// is interrupted.
    #[arg(long)]
    pub smooth: bool,
    /// No progress bar, no notice (such as the GIF's) and no summary.
    #[arg(long)]
    pub quiet: bool,
}

/// Parses `--init x,y,w,h` for clap.
///
/// # Errors
/// The message of [`parse_box_arg`].
pub fn parse_box(s: &str) -> std::result::Result<BoundingBox, String> {
    parse_box_arg(s, "--init").map_err(|e| e.to_string())
}

/// Largest `--edge-threshold`: a grey-level step of 255 across one pixel, the steepest edge an
/// 8-bit frame can hold, is far below it; a larger threshold finds no edge at all.
pub const MAX_EDGE_THRESHOLD: f64 = 1000.0;

/// Parses `--edge-threshold` for clap: a number in (0, [`MAX_EDGE_THRESHOLD`]], reported as the
/// user typed it when it is out of range.
///
/// # Errors
/// A message that names the value and the range.
pub fn parse_edge_threshold(s: &str) -> std::result::Result<f32, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s} is not a number of grey levels per pixel"))?;
    if !(v.is_finite() && v > 0.0 && v <= MAX_EDGE_THRESHOLD) {
        return Err(format!(
            "{s} is out of range: give a number of grey levels per pixel in (0, {MAX_EDGE_THRESHOLD}]"
        ));
    }
    Ok(v as f32)
}

/// Parses `--init-ellipse cx,cy,a,b,angle` (angle in radians) for clap.
///
/// # Errors
/// The message of [`parse_ellipse_arg`].
pub fn parse_ellipse(s: &str) -> std::result::Result<Ellipse, String> {
    parse_ellipse_arg(s, "--init-ellipse").map_err(|e| e.to_string())
}

/// Command-line settings applied on top of a preset or a configuration file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Overrides {
    /// `--particles`.
    pub particles: Option<usize>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--parallel`.
    pub parallel: bool,
    /// `--edge-threshold`: the 1-D edge detector's threshold in grey levels per pixel, for every
    /// measurement-line term; refused for a tracker without measurement lines.
    pub edge_threshold: Option<f32>,
}

/// The tracker configuration from `--config` or the preset, with the command-line overrides
/// applied, validated.
///
/// Each error names what is at fault: the configuration file (`--config`) or the preset
/// (`--tracker`) for their own values, and the option for an override (`--particles`,
/// `--edge-threshold`), so a bad override is never blamed on the file.
///
/// # Errors
/// [`AppError::InvalidSetting`] (exit 2) for an unknown preset, a configuration file that cannot
/// be read or parsed or holds an invalid value (the file is a setting, like the options that
/// override it), or an invalid override (`--edge-threshold` for a tracker without measurement
/// lines, which would not read it).
pub fn tracker_config(preset: &str, config: Option<&Path>, o: Overrides) -> Result<TrackerConfig> {
    let mut c = match config {
        Some(path) => {
            let c = load_config(path)?;
            c.validate()
                .map_err(|e| config_error(path, e.to_string()))?;
            c
        }
        None => {
            let c = Preset::from_name(preset)
                .map_err(|e| AppError::setting("--tracker", e.to_string()))?
                .config(DEFAULT_PARTICLES, DEFAULT_SEED);
            c.validate()
                .map_err(|e| AppError::setting("--tracker", e.to_string()))?;
            c
        }
    };
    if let Some(s) = o.seed {
        c.seed = s;
    }
    c.filter.parallel |= o.parallel;
    if let Some(n) = o.particles {
        c.particles = n;
        c.validate()
            .map_err(|e| AppError::setting("--particles", e.to_string()))?;
    }
    if let Some(t) = o.edge_threshold {
        if !(t.is_finite() && t > 0.0) {
            return Err(AppError::setting(
                "--edge-threshold",
                format!("{t} is not a finite positive number of grey levels per pixel"),
            ));
        }
        // Refused, not ignored, for a tracker without measurement lines (head).
        c.set_edge_threshold(t).map_err(|e| match e {
            trackers::Error::InvalidSetting { reason, .. } => {
                AppError::setting("--edge-threshold", reason)
            }
            other => AppError::setting("--edge-threshold", other.to_string()),
        })?;
        c.validate()
            .map_err(|e| AppError::setting("--edge-threshold", e.to_string()))?;
    }
    Ok(c)
}

/// An error in the configuration file `path`: exit 2, naming `--config` and the file.
fn config_error(path: &Path, reason: impl std::fmt::Display) -> AppError {
    AppError::setting("--config", format!("{}: {reason}", path.display()))
}

fn load_config(path: &Path) -> Result<TrackerConfig> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| config_error(path, format!("cannot read the configuration: {e}")))?;
    TrackerConfig::parse(&text, trackers::ConfigFormat::of_path(path))
        .map_err(|reason| config_error(path, reason))
}

/// Largest difference, in radians, between an `--init-ellipse` angle and a multiple of π/2 that
/// an axis-aligned tracker accepts as that multiple (the library's constant).
pub use trackers::AXIS_ANGLE_TOLERANCE;

/// The ellipse `e` as the tracker of `config` can start from it, exactly: the library's
/// [`TrackerConfig::initial_ellipse`] (a rotated ellipse is refused by trackers of axis-aligned
/// ellipses), checked here so that the error names the option.
///
/// # Errors
/// [`AppError::InvalidSetting`] naming `--init-ellipse` for a rotated, non-circular ellipse and a
/// tracker that cannot rotate.
pub fn initial_ellipse_for(e: &Ellipse, config: &TrackerConfig) -> Result<Ellipse> {
    config.initial_ellipse(e).map_err(|err| match err {
        trackers::Error::InvalidSetting { reason, .. } => {
            AppError::setting("--init-ellipse", reason)
        }
        other => AppError::setting("--init-ellipse", other.to_string()),
    })
}

/// A progress bar on standard error, hidden when `quiet`: `len` frames, with the rate and the
/// time left.
pub fn progress(len: u64, quiet: bool, what: &str) -> ProgressBar {
    progress_of(len, quiet, what, "frames")
}

/// A progress bar on standard error over `len` things named `unit` (`frames`, `runs`), hidden
/// when `quiet`.
pub fn progress_of(len: u64, quiet: bool, what: &str, unit: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    progress_to(len, what, unit, ProgressDrawTarget::stderr())
}

/// [`progress_of`] drawn on `target`.
pub fn progress_to(len: u64, what: &str, unit: &str, target: ProgressDrawTarget) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), target);
    let template = format!("{{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{rate}}, eta {{eta}}");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        let unit = unit.to_owned();
        let rate = move |state: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = w.write_str(&rate_in(state.per_sec(), &unit));
        };
        bar.set_style(style.with_key("rate", rate).progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

/// A rate in frames per second with one decimal (`–` before there is one).
pub fn rate_text(per_sec: f64) -> String {
    rate_in(per_sec, "frames")
}

/// A rate in `unit` per second with one decimal (`–` before there is one).
pub fn rate_in(per_sec: f64, unit: &str) -> String {
    if per_sec.is_finite() && per_sec >= 0.0 {
        format!("{per_sec:.1} {unit}/s")
    } else {
        format!("– {unit}/s")
    }
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

/// The files `track run` writes in `--out`, besides `overlay/NNNN.png` and `plots/*.svg`.
pub const OUTPUT_FILES: [&str; 7] = [
    "track.csv",
    "boxes.txt",
    "smoothed.csv",
    "smoothed_boxes.txt",
    "summary.json",
    "track.gif",
    "report.html",
];

/// Whether `path` is named as an overlay `track run` writes (`<digits>.png` or `<digits>.jpg`).
fn is_overlay_name(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "png" || e == "jpg")
        && path
            .file_stem()
            .and_then(|s| s.to_str())
            .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
}

/// Opens `--out` before tracking ([`OutputFolder::open`](crate::output::OutputFolder)): refuses
/// a symbolic link, a folder that holds one of `inputs`, or one in use by another command;
/// removes what `track` wrote there before (its manifest says what, and nothing else is ever
/// removed); then checks that no file of another origin takes the name of an output this run
/// will write, so that the run cannot fail on it halfway.
///
/// # Errors
/// [`AppError::Write`] naming the folder or the file.
pub fn prepare_out(
    out: &Path,
    inputs: &[&Path],
    overlay: bool,
    plots: bool,
) -> Result<crate::output::OutputFolder> {
    let folder = crate::output::OutputFolder::open(out, inputs)?;
    for name in OUTPUT_FILES {
        folder.check_free(Path::new(name), None)?;
    }
    if overlay {
        folder.check_free(Path::new("overlay"), Some(&is_overlay_name))?;
    }
    if plots {
        folder.check_free(
            Path::new("plots"),
            Some(&|p: &Path| p.extension().is_some_and(|e| e == "svg")),
        )?;
    }
    Ok(folder)
}

/// What one frame read from the sequence produced: the reader runs on its own thread, one frame
/// ahead, so a signal is noticed even while standard input is waiting for data.
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
        let truth = match (&sequence.groundtruth, known_frames) {
            (Some(path), Some(frames)) => {
                let t = load_groundtruth(path)?;
                check_groundtruth_len(&t, frames, path)?;
                Some(t)
            }
            _ => None,
        };
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

/// Writes every output of a run from what the frame loop left, then reports the stop (a
/// signal or a stream error) as the run's error, or prints the summary.
fn write_outputs(
    args: &Args,
    input: &CheckedInput,
    tracked: frames::Tracked,
    kept: Kept,
) -> Result<()> {
    let frames::Tracked {
        output,
        smoothed: tracked_smoothed,
        frames_read,
        wall_seconds,
        mut stop,
    } = tracked;
    let (config, start) = (&input.config, input.start);
    let records = output.records;
    let smoothed = tracked_smoothed;
    if records.is_empty() {
        return Err(stop.unwrap_or_else(|| {
            AppError::input(
                &args.sequence,
                "no frame to track after the first labelled one",
            )
        }));
    }
    let interrupted = interruption(&mut stop, records.len(), frames_read);
    let Kept {
        gif,
        strip,
        strip_known,
        mut written,
    } = kept;

    write_tables(
        args,
        config,
        start,
        &records,
        smoothed.as_deref(),
        &mut written,
    )?;
    let (figures, gif) = write_animation_and_plots(
        args,
        input,
        &records,
        smoothed.as_deref(),
        gif,
        &mut written,
    )?;
    if let Some(notice) = gif.as_ref().and_then(|g| g.notice())
        && !args.quiet
    {
        // A notice only: standard error that cannot be written is no reason to fail the run.
        let _ = std::io::Write::write_all(
            &mut std::io::stderr(),
            format!("note: {notice}\n").as_bytes(),
        );
    }
    let metrics = match &input.truth {
        Some(t) => score(start, &records, t, output.seconds)?,
        None => None,
    };
    if args.report {
        written.push("report.html".into());
    }
    written.push("summary.json".into());
    let mut summary = run_summary(
        input,
        &records,
        output.seconds,
        metrics,
        written,
        interrupted,
    );
    summary.wall_seconds = Some(wall_seconds);
    summary.gif = gif;
    if args.report {
        write_run_report(args, input, &summary, figures, strip, strip_known.is_some())?;
    }
    write_summary(&args.out.join("summary.json"), &summary)?;
    if let Some(e) = stop {
        return Err(e);
    }
    if !args.quiet {
        print_summary(&summary, &args.out)?;
    }
    Ok(())
}

/// What stopped the run early, for the summary; an interruption by a signal is given the number
/// of frames tracked.
fn interruption(
    stop: &mut Option<AppError>,
    tracked_frames: usize,
    frames_read: usize,
) -> Option<Interruption> {
    if let Some(AppError::Interrupted { frames, .. }) = stop {
        *frames = tracked_frames;
    }
    stop.as_ref().map(|e| Interruption {
        reason: match e {
            AppError::Interrupted { signal, .. } => (*signal).to_owned(),
            other => other.to_string(),
        },
        frames_read,
    })
}

/// Writes `track.csv` and `boxes.txt`, and their smoothed versions when there are smoothed
/// records, adding them to `written`.
fn write_tables(
    args: &Args,
    config: &TrackerConfig,
    start: usize,
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    written: &mut Vec<String>,
) -> Result<()> {
    let columns = CsvColumns::of_tracker(config);
    let tables = [
        ("track.csv", "boxes.txt", Some(records)),
        ("smoothed.csv", "smoothed_boxes.txt", smoothed),
    ];
    for (csv, boxes, records) in tables {
        if let Some(records) = records {
            write_track_tables(&args.out, [csv, boxes], records, columns, start)?;
            written.extend([csv.to_owned(), boxes.to_owned()]);
        }
    }
    Ok(())
}

/// The run's `summary.json`.
fn run_summary(
    input: &CheckedInput,
    records: &[FrameRecord],
    seconds: f64,
    metrics: Option<SequenceMetrics>,
    outputs: Vec<String>,
    interrupted: Option<Interruption>,
) -> Summary {
    let config = &input.config;
    Summary {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        sequence: input.name.clone(),
        tracker: config.name.clone(),
        particles: config.particles,
        seed: config.seed,
        frames: records.len(),
        width: input.width,
        height: input.height,
        frame_rate: input.frame_rate,
        initial_box: Some(input.init.bounding_box()),
        seconds,
        fps: records.len() as f64 / seconds.max(1e-9),
        mean_millis: 1e3 * seconds / records.len().max(1) as f64,
        status_counts: status_counts(records),
        metrics,
        outputs,
        wall_seconds: None,
        gif: None,
        interrupted,
    }
}

/// Writes `report.html`: the summary's figures, the plots and the strip of overlays.
fn write_run_report(
    args: &Args,
    input: &CheckedInput,
    summary: &Summary,
    figures: Vec<crate::plots::Figure>,
    strip: Thinned<(String, RgbImage)>,
    strip_picked_in_advance: bool,
) -> Result<()> {
    let config = &input.config;
    let report = ReportInput {
        title: format!("{} — {}", input.name, config.name),
        subtitle: format!(
            "{} (tracker {}, {} particles, seed {})",
            command_line(std::env::args_os()),
            config.name,
            config.particles,
            config.seed
        ),
        metrics: tracker_rows(config, summary),
        figures,
        strip: strip_frames(strip, strip_picked_in_advance),
        notes: report_notes(config, summary),
    };
    write_report(&args.out.join("report.html"), &report)
}

/// Writes `track.gif` and `plots/*.svg` when asked for, adding them to `written`; returns the
/// figures, which the report shows too (none when neither plots nor a report are asked for),
/// and what the GIF holds.
fn write_animation_and_plots(
    args: &Args,
    input: &CheckedInput,
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    gif: Thinned<RgbImage>,
    written: &mut Vec<String>,
) -> Result<(Vec<crate::plots::Figure>, Option<GifSummary>)> {
    let mut gif_summary = None;
    if args.gif {
        let stride = gif.stride();
        let frames: Vec<RgbImage> = gif.into_items().into_iter().map(|(_, f)| f).collect();
        let delay_ms = gif_delay_ms(stride);
        write_gif(&args.out.join("track.gif"), &frames, delay_ms)?;
        written.push("track.gif".into());
        gif_summary = Some(GifSummary {
            frames: frames.len(),
            tracked: records.len(),
            stride,
            delay_ms,
        });
    }
    let figures = if args.plots || args.report {
        let options = crate::plots::PlotOptions::of_tracker(&input.config)
            .with_truth(truth_points(input.truth.as_deref()));
        all_figures_with(records, smoothed, &options)?
    } else {
        Vec::new()
    };
    if args.plots {
        for p in write_figures(&args.out.join("plots"), &figures)? {
            if let Ok(rel) = p.strip_prefix(&args.out) {
                written.push(rel.display().to_string());
            }
        }
    }
    Ok((figures, gif_summary))
}

/// The display time of a GIF frame that stands for `stride` frames: `stride` twelfths of a
/// second, at most [`GIF_MAX_DELAY_MS`].
pub fn gif_delay_ms(stride: usize) -> u32 {
    u32::try_from(stride)
        .unwrap_or(u32::MAX)
        .saturating_mul(GIF_FRAME_MS)
        .min(GIF_MAX_DELAY_MS)
}

/// The ground-truth boxes of an OTB folder as plot points (frame index = position).
fn truth_points(truth: Option<&[Option<BoundingBox>]>) -> Vec<crate::plots::TruthAt> {
    truth
        .unwrap_or_default()
        .iter()
        .map(|b| crate::plots::TruthAt {
            bbox: *b,
            ..Default::default()
        })
        .collect()
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

/// The report's metrics rows for the tracker of `config`: a tracker without a partial state
/// (the lock chain) counts its frames locked / lost.
fn tracker_rows(config: &TrackerConfig, summary: &Summary) -> Vec<(String, String)> {
    let mut rows = summary_rows(summary);
    if !config.has_partial_state()
        && let Some([l, _, o]) = summary.status_counts
    {
        for (name, value) in &mut rows {
            if name == "frames locked / partial / lost" {
                let unstated = summary.frames.saturating_sub(l + o);
                *name = "frames locked / lost".to_owned();
                *value = format!("{l} / {o}{}", crate::report::unstated_text(unstated));
            }
        }
    }
    rows
}

/// Notes under the report's metrics: what the ESS means for this tracker, what its status
/// probabilities are.
fn report_notes(config: &TrackerConfig, summary: &Summary) -> Vec<String> {
    let mut notes = crate::report::standard_notes(summary);
    notes.push(crate::report::ess_note(config.is_tempered()));
    notes
}

/// The overlays kept for the report's strip: all of them when the frames were picked in
/// advance (known length), else evenly spaced ones among those the stream kept.
fn strip_frames(
    strip: Thinned<(String, RgbImage)>,
    picked_in_advance: bool,
) -> Vec<(String, RgbImage)> {
    let kept: Vec<_> = strip.into_items().into_iter().map(|(_, f)| f).collect();
    if picked_in_advance {
        return kept;
    }
    let ks = strip_indices(kept.len(), STRIP_FRAMES);
    kept.into_iter()
        .enumerate()
        .filter(|(i, _)| ks.contains(i))
        .map(|(_, f)| f)
        .collect()
}

/// What a run keeps of its overlays while it tracks, and the outputs written so far.
struct Kept {
    /// Frames for the animated GIF.
    gif: Thinned<RgbImage>,
    /// Labelled thumbnails for the report's strip.
    strip: Thinned<(String, RgbImage)>,
    /// The strip's frames (relative to the start), when the length is known in advance.
    strip_known: Option<Vec<usize>>,
    /// Output files written, relative to `--out`.
    written: Vec<String>,
}

impl Kept {
    fn new(args: &Args, known_frames: Option<usize>, start: usize) -> Self {
        // With a known length the GIF takes every k-th overlay and the strip fixed frames; a
        // stream keeps evenly spaced frames in bounded memory ([`Thinned`]). A stride the user
        // gives is kept, and the GIF ends when it is full.
        let cap = args.gif_frames as usize;
        let gif = match args.gif_stride {
            Some(k) => Thinned::truncating(cap, k as usize),
            None => Thinned::new(
                cap,
                known_frames.map_or(1, |n| n.saturating_sub(start).div_ceil(cap)),
            ),
        };
        Self {
            gif,
            strip: Thinned::new(2 * STRIP_FRAMES, 1),
            strip_known: known_frames.map(|n| strip_indices(n - start, STRIP_FRAMES)),
            written: Vec::new(),
        }
    }

    /// Writes or keeps the overlay `img` of frame `index` (the `k`-th tracked) as the run's
    /// options ask.
    ///
    /// # Errors
    /// [`AppError::Write`] when the overlay PNG cannot be written.
    fn overlay(&mut self, args: &Args, index: usize, k: usize, img: RgbImage) -> Result<()> {
        if args.overlay {
            let format = args.overlay_format;
            let name = format!("overlay/{:04}.{}", index + 1, format.extension());
            format.write(&args.out.join(&name), &img)?;
            self.written.push(name);
        }
        if args.report {
            let label = format!("frame {}", index + 1);
            let wanted = match &self.strip_known {
                Some(ks) => ks.contains(&k),
                None => self.strip.wants(k),
            };
            if wanted {
                self.strip.push(k, (label, thumbnail(&img, 200)));
            }
        }
        if args.gif {
            self.gif.push(k, img);
        }
        Ok(())
    }
}

/// A progress spinner for a stream of unknown length, hidden when `quiet`.
fn stream_progress(quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{msg} {pos} frames, {rate}") {
        bar.set_style(style.with_key("rate", rate_key));
    }
    bar
}

/// The `{rate}` of a progress bar over frames: frames per second with one decimal.
fn rate_key(state: &ProgressState, w: &mut dyn std::fmt::Write) {
    let _ = w.write_str(&rate_text(state.per_sec()));
}

/// Scores the tracked frames against the ground truth with the one scorer of `track eval otb`
/// ([`score_run`]): the start frame is given, not tracked, so it is not scored. `None` when no
/// labelled frame follows it.
fn score(
    start: usize,
    records: &[FrameRecord],
    truth: &[Option<BoundingBox>],
    seconds: f64,
) -> Result<Option<SequenceMetrics>> {
    let predicted: Vec<Option<BoundingBox>> = std::iter::repeat_n(None, start)
        .chain(records.iter().map(|r| Some(r.bbox)))
        .collect();
    score_run(&predicted, truth, start, Some(seconds.max(1e-9)))
}

fn print_summary(s: &Summary, out: &Path) -> Result<()> {
    let mut text = format!(
        "{}: {} frames with {} ({} particles) at {:.1} frames/s tracking alone{}\n",
        s.sequence,
        s.frames,
        s.tracker,
        s.particles,
        s.fps,
        s.wall_seconds
            .map(|w| format!(", {:.1} frames/s wall clock", s.frames as f64 / w.max(1e-9)))
            .unwrap_or_default()
    );
    if let Some(m) = &s.metrics {
        text.push_str(&format!(
            "  precision@20px {:.3}, success AUC {:.3}, mean IoU {:.3}{}\n",
            m.precision_20,
            m.success_auc,
            m.mean_iou,
            m.failed_at_frame
                .map(|f| format!(", lost at frame {}", f + 1))
                .unwrap_or_default()
        ));
    }
    if let Some(c) = s.status_counts {
        let unstated = s.frames.saturating_sub(c.iter().sum());
        text.push_str(&format!(
            "  status: {} locked, {} partial, {} lost{}\n",
            c[TrackStatus::Locked.index()],
            c[TrackStatus::PartiallyOccluded.index()],
            c[TrackStatus::Lost.index()],
            crate::report::unstated_text(unstated)
        ));
    }

    text.push_str(&format!("  outputs in {}\n", out.display()));
    crate::output::print_stdout(&text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    /// A terminal that keeps what is drawn on it.
    #[derive(Debug, Clone, Default)]
    struct Screen(Arc<Mutex<String>>);

    impl indicatif::TermLike for Screen {
        fn width(&self) -> u16 {
            200
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.write_str(&format!("{s}\n"))
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().unwrap().push_str(s);
            Ok(())
        }
        fn clear_line(&self) -> std::io::Result<()> {
            Ok(())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_progress_bar_shows_total_eta_and_a_rate_with_one_decimal() {
        let screen = Screen::default();
        let bar = progress_to(
            40,
            "m1 on clip",
            "frames",
            ProgressDrawTarget::term_like(Box::new(screen.clone())),
        );
        for _ in 0..12 {
            std::thread::sleep(std::time::Duration::from_millis(2));
            bar.inc(1);
        }
        bar.abandon();
        let text = screen.0.lock().unwrap().clone();
        let last = text.lines().rev().find(|l| !l.trim().is_empty()).unwrap();
        assert!(
            last.contains("m1 on clip") && last.contains("12/40 frames"),
            "{last}"
        );
        assert!(last.contains("eta "), "{last}");
        // "NNN.N frames/s": one decimal, never indicatif's four.
        let rate = last.split(", ").find(|p| p.ends_with("frames/s")).unwrap();
        let number = rate.trim_end_matches(" frames/s");
        assert_eq!(number.split('.').nth(1).map(str::len), Some(1), "{last}");
        assert_eq!(rate_text(12.345_67), "12.3 frames/s");
        assert_eq!(rate_text(f64::NAN), "– frames/s");
    }

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

    #[test]
    fn gif_frames_show_longer_for_a_larger_stride_up_to_a_quarter_second() {
        assert_eq!(gif_delay_ms(1), 83);
        assert_eq!(gif_delay_ms(2), 166);
        assert_eq!(gif_delay_ms(4), GIF_MAX_DELAY_MS);
        assert_eq!(gif_delay_ms(usize::MAX), GIF_MAX_DELAY_MS);
    }
}
