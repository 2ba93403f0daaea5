//! Video files (`.mp4`, `.mov`, `.avi`, `.mkv`, …) decoded by `ffmpeg`.
//!
//! `track run clip.mp4` runs
//! `ffmpeg -nostdin -hide_banner -v error -i file:clip.mp4 -map 0:v:0 -f yuv4mpegpipe
//! -pix_fmt yuv420p -strict -1 pipe:1` and reads its standard output with the streaming Y4M reader
//! ([`crate::sequence::Y4mSource::from_reader`]), one frame at a time in constant memory; frame
//! size and rate come from the Y4M header ffmpeg writes, that is from the file. No video library
//! is linked: ffmpeg reads every format, and a missing ffmpeg is one clear error
//! ([`FFMPEG`] not on `PATH`).
//!
//! The number of frames, for the progress bar only, is asked of `ffprobe` first
//! ([`probe_frame_count`]): the stream's `nb_frames` when the container states it, else its
//! duration times its average frame rate. A missing ffprobe or an answer without either just
//! leaves the count unknown.
//!
//! The child process never outlives its reader: it is killed and reaped when the reader is dropped
//! (an early error, the end of a run) and when [`FfmpegHandle::stop`] is called (a run stopped by
//! a signal); at the end of its output it is waited for, and a failure (a nonzero exit status)
//! becomes a read error carrying the end of ffmpeg's standard error.

use std::io::Read;
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

use crate::{AppError, Result};

/// The program run to decode video files, looked up on `PATH`.
pub const FFMPEG: &str = "ffmpeg";

/// The program asked for a video's frame count, looked up on `PATH`.
pub const FFPROBE: &str = "ffprobe";

/// The number of frames of the first video stream of `path` as ffprobe states it (see
/// [`frame_count_from_probe`]); `None` when ffprobe is missing, fails or does not know.
pub fn probe_frame_count(path: &Path) -> Option<usize> {
    let mut input = std::ffi::OsString::from("file:");
    input.push(path.as_os_str());
    let out = Command::new(FFPROBE)
        .args([
            "-v",
            "error",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=nb_frames,duration,avg_frame_rate:format=duration",
            "-of",
            "flat",
        ])
        .arg(&input)
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    frame_count_from_probe(&String::from_utf8_lossy(&out.stdout))
}

/// The frame count in ffprobe's `-of flat` answer: `streams.stream.0.nb_frames` when it is a
/// positive number, else the stream's duration (or the container's) times the stream's
/// `avg_frame_rate` (`num/den`), rounded; `None` when neither is known ("N/A").
pub fn frame_count_from_probe(text: &str) -> Option<usize> {
    let value = |key: &str| -> Option<&str> {
        text.lines().find_map(|l| {
            let (k, v) = l.split_once('=')?;
            (k.trim() == key).then(|| v.trim().trim_matches('"'))
        })
    };
    if let Some(n) = value("streams.stream.0.nb_frames").and_then(|v| v.parse::<usize>().ok())
        && n > 0
    {
        return Some(n);
    }
    let seconds = value("streams.stream.0.duration")
        .and_then(|v| v.parse::<f64>().ok())
        .or_else(|| value("format.duration").and_then(|v| v.parse::<f64>().ok()))?;
    let (num, den) = value("streams.stream.0.avg_frame_rate")?.split_once('/')?;
    let rate = num.parse::<f64>().ok()? / den.parse::<f64>().ok()?;
    let n = (seconds * rate).round();
    (1.0..1e12).contains(&n).then_some(n as usize)
}

/// How much of ffmpeg's standard error is kept for messages, bytes (its last lines).
const STDERR_TAIL: usize = 2048;

/// The ffmpeg child process, shared by its reader and by whoever may need to stop it.
#[derive(Debug)]
struct ChildSlot(Mutex<Option<Child>>);

impl ChildSlot {
    /// Kills the child if it still runs and reaps it; idempotent.
    fn kill_and_reap(&self) {
        let mut slot = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(mut child) = slot.take() {
            // Killing a child that has already exited fails harmlessly; waiting reaps it either
            // way, so no zombie is left.
            let _ = child.kill();
            let _ = child.wait();
        }
    }

    /// Waits for the child to exit (its output has ended) and reaps it. `None` when it was
    /// already reaped (stopped by [`ChildSlot::kill_and_reap`]).
    fn wait(&self) -> Option<std::io::Result<std::process::ExitStatus>> {
        let mut slot = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        let mut child = slot.take()?;
        Some(child.wait())
    }
}

/// A handle that stops the ffmpeg child of a video source from another thread.
#[derive(Debug, Clone)]
pub struct FfmpegHandle(Arc<ChildSlot>);

impl FfmpegHandle {
    /// The process id of ffmpeg while it has not been reaped.
    pub fn pid(&self) -> Option<u32> {
        let slot = (self.0).0.lock().unwrap_or_else(PoisonError::into_inner);
        slot.as_ref().map(Child::id)
    }

    /// Kills ffmpeg (if it still runs) and reaps it. The reader then sees the end of its input.
    pub fn stop(&self) {
        self.0.kill_and_reap();
    }
}

/// ffmpeg's standard output as a byte stream: Y4M frames.
pub struct FfmpegReader {
    child: Arc<ChildSlot>,
    stdout: ChildStdout,
    stderr: Option<JoinHandle<Vec<u8>>>,
    /// Set once the end of the output was reached and the exit status checked.
    done: bool,
}

impl std::fmt::Debug for FfmpegReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FfmpegReader")
            .field("done", &self.done)
            .finish_non_exhaustive()
    }
}

impl FfmpegReader {
    /// Starts ffmpeg decoding `path` to Y4M (4:2:0) on a pipe.
    ///
    /// # Errors
    /// [`AppError::BadInput`] naming the file: ffmpeg is not on `PATH` (the message names the
    /// program and how to get it), or it cannot be started.
    pub fn spawn(path: &Path) -> Result<(Self, FfmpegHandle)> {
        // `file:` keeps a name such as `pipe:x` or `-x` from being read as a protocol or option.
        let mut input = std::ffi::OsString::from("file:");
        input.push(path.as_os_str());
        let mut child = Command::new(FFMPEG)
            .args(["-nostdin", "-hide_banner", "-v", "error", "-i"])
            .arg(&input)
            .args([
                "-map",
                "0:v:0",
                "-f",
                "yuv4mpegpipe",
                "-pix_fmt",
                "yuv420p",
                "-strict",
                "-1",
                "pipe:1",
            ])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::NotFound {
                    AppError::input(
                        path,
                        format!(
                            "reading this video needs the program `{FFMPEG}`, which is not on \
                             PATH: install it (Debian/Ubuntu: apt-get install ffmpeg), or convert \
                             the video to a .y4m file or a folder of images"
                        ),
                    )
                } else {
                    AppError::input(path, format!("cannot start `{FFMPEG}` to decode it: {e}"))
                }
            })?;
        let (Some(stdout), Some(stderr)) = (child.stdout.take(), child.stderr.take()) else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(AppError::input(
                path,
                format!("cannot read the output of `{FFMPEG}`"),
            ));
        };
        let stderr = std::thread::spawn(move || tail_of(stderr));
        let child = Arc::new(ChildSlot(Mutex::new(Some(child))));
        Ok((
            Self {
                child: Arc::clone(&child),
                stdout,
                stderr: Some(stderr),
                done: false,
            },
            FfmpegHandle(child),
        ))
    }

    /// At the end of the output: waits for ffmpeg and turns a failure into an error that carries
    /// the end of its standard error.
    fn finish(&mut self) -> std::io::Result<()> {
        self.done = true;
        let status = self.child.wait();
        let stderr = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        match status {
            // Stopped on purpose ([`FfmpegHandle::stop`]): the input simply ends.
            None => Ok(()),
            Some(Err(e)) => Err(std::io::Error::other(format!(
                "cannot wait for `{FFMPEG}`: {e}"
            ))),
            Some(Ok(status)) if status.success() => Ok(()),
            Some(Ok(status)) => {
                let text = String::from_utf8_lossy(&stderr);
                let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
                Err(std::io::Error::other(format!(
                    "`{FFMPEG}` could not decode it ({status}){}",
                    if text.is_empty() {
                        String::new()
                    } else {
                        format!(": {text}")
                    }
                )))
            }
        }
    }
}

/// Reads `r` to its end, keeping the last [`STDERR_TAIL`] bytes.
fn tail_of(mut r: impl Read) -> Vec<u8> {
    let mut kept = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        match r.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                kept.extend_from_slice(&buf[..n]);
                if kept.len() > 2 * STDERR_TAIL {
                    kept.drain(..kept.len() - STDERR_TAIL);
                }
            }
        }
    }
    if kept.len() > STDERR_TAIL {
        kept.drain(..kept.len() - STDERR_TAIL);
    }
    kept
}

impl Read for FfmpegReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.done {
            return Ok(0);
        }
        let n = self.stdout.read(buf)?;
        if n == 0 && !buf.is_empty() {
            self.finish()?;
        }
        Ok(n)
    }
}

impl Drop for FfmpegReader {
    fn drop(&mut self) {
        self.child.kill_and_reap();
    }
}

/// Whether `path` names a file to decode with ffmpeg: any regular file that is not `.y4m`.
pub fn is_video_path(path: &Path) -> bool {
    path.is_file()
        && !path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("y4m"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_count_from_nb_frames_or_duration_times_rate() {
        let mp4 = "streams.stream.0.avg_frame_rate=\"25/1\"\nstreams.stream.0.duration=\"22.920000\"\n\
                   streams.stream.0.nb_frames=\"573\"\nformat.duration=\"22.920000\"\n";
        assert_eq!(frame_count_from_probe(mp4), Some(573));
        // Matroska states no frame count: 9.6 s at 30000/1001 frames/s is 288 frames.
        let mkv = "streams.stream.0.avg_frame_rate=\"30000/1001\"\nstreams.stream.0.duration=\"N/A\"\n\
                   streams.stream.0.nb_frames=\"N/A\"\nformat.duration=\"9.609000\"\n";
        assert_eq!(frame_count_from_probe(mkv), Some(288));
        let unknown = "streams.stream.0.avg_frame_rate=\"0/0\"\nstreams.stream.0.duration=\"N/A\"\n\
                   streams.stream.0.nb_frames=\"N/A\"\nformat.duration=\"N/A\"\n";
        assert_eq!(frame_count_from_probe(unknown), None);
        assert_eq!(frame_count_from_probe(""), None);
    }
}
