//! The frame loop of `track run`: frames are read on their own thread, so that a signal is
//! noticed within [`POLL`] even while the input blocks (a pipe, ffmpeg), and each frame is
//! tracked and its overlay handed to [`Kept`].

use indicatif::ProgressBar;
use vision_core::{BoundingBox, Ellipse};

use super::Kept;
use crate::signals::StopSignals;

use crate::record::FrameRecord;
use crate::sequence::{Frame, FrameSource, Source};
use crate::session::{Session, SessionOutput};
use crate::{AppError, Result};

type Incoming = Result<Option<Frame>>;

/// How long the run waits for the next frame before checking for a signal again.
const POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// What the loop reads besides the frames.
pub(super) struct Frames<'a> {
    /// The first frame tracked; earlier frames are read and skipped.
    pub start: usize,
    /// The contour the tracker starts from.
    pub init: &'a Ellipse,
    /// The ground truth, one box (or none) per frame.
    pub truth: Option<&'a [Option<BoundingBox>]>,
    pub signals: &'a StopSignals,
    pub bar: &'a ProgressBar,
}

/// What the loop leaves.
pub(super) struct Tracked {
    /// The session's records, overlays and time.
    pub output: SessionOutput,
    /// The smoothed records (`--smooth`, when the run was not stopped).
    pub smoothed: Option<Vec<FrameRecord>>,
    /// Frames read from the input, skipped ones included.
    pub frames_read: usize,
    /// Wall-clock seconds of the whole run until the end of tracking (set by the caller).
    pub wall_seconds: f64,
    /// Why the run stopped before the end of the input: a signal or an error of the input or
    /// the tracker.
    pub stop: Option<AppError>,
}

impl Frames<'_> {
    /// Tracks every frame of `source` from `start` on, until the end of the input, a signal or
    /// an error.
    ///
    /// # Errors
    /// [`AppError::Write`] when an overlay cannot be written; a stop for any other reason is
    /// returned in [`Tracked::stop`] so that the outputs can still be written.
    pub fn track(
        &self,
        args: &super::Args,
        mut source: Source,
        mut session: Session,
        kept: &mut Kept,
    ) -> Result<Tracked> {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Incoming>(1);
        let decoder = source.stopper();
        let reader = std::thread::spawn(move || {
            loop {
                let next = source.next_frame();
                let done = !matches!(next, Ok(Some(_)));
                if tx.send(next).is_err() || done {
                    break;
                }
            }
        });
        let mut frames_read = 0;
        let mut stop: Option<AppError> = None;
        loop {
            if let Some(e) = self.interruption(args) {
                stop = Some(e);
                break;
            }
            let frame = match rx.recv_timeout(POLL) {
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) | Ok(Ok(None)) => break,
                Ok(Err(e)) => {
                    stop = Some(e);
                    break;
                }
                Ok(Ok(Some(frame))) => frame,
            };
            frames_read += 1;
            self.bar.inc(1);
            if frame.index < self.start {
                continue;
            }
            let gt = self
                .truth
                .and_then(|t| t.get(frame.index).copied().flatten());
            if let Err(e) = session.push(&frame, self.init, gt) {
                stop = Some(e);
                break;
            }
            if let Some(img) = session.take_overlay() {
                kept.overlay(args, frame.index, frame.index - self.start, img)?;
            }
        }
        self.bar.finish_and_clear();
        drop(rx);
        if stop.is_none() {
            // The reader has ended (end of input or error already received); it never blocks
            // here.
            let _ = reader.join();
        } else if let Some(ffmpeg) = &decoder {
            // A video's decoder is stopped and reaped now, not left to run to the end of the
            // file; its reader then sees the end of its input and ends too.
            ffmpeg.stop();
            let _ = reader.join();
        }
        // A signal that arrived while the last frames were read still marks the run as
        // interrupted.
        if stop.is_none() {
            stop = self.interruption(args);
        }
        // A smoother needs the whole run: an interrupted one is written as filtered only.
        let smoothed = if args.smooth && stop.is_none() {
            Some(session.smoothed(&trackers::SmootherSettings::default())?.0)
        } else {
            None
        };
        Ok(Tracked {
            smoothed,
            output: session.finish(),
            frames_read,
            wall_seconds: 0.0,
            stop,
        })
    }

    /// The error of a signal received so far, if any.
    fn interruption(&self, args: &super::Args) -> Option<AppError> {
        self.signals
            .received()
            .map(|(name, number)| AppError::Interrupted {
                signal: name,
                number,
                frames: 0,
                out: args.out.clone(),
            })
    }
}
