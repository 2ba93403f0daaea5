//! Frame sources: a folder of images, an OTB folder, a `.y4m` file, or Y4M on standard input.
//!
//! Every source yields frames one at a time as a grey `f32` image in 0–255 grey levels (what the
//! libraries consume) together with the 8-bit original (RGB or luma) for rendering overlays. Image
//! files get their grey levels from vision-core's [`vision_core::ToGreyBuffer`] (BT.601 luma for
//! colour, the weighting of a Y4M luma plane), the one conversion the libraries offer too.
//!
//! Bad input fails with one line that names the file and the problem. So that a run can fail
//! *before* it writes any output when, say, the 300th image is corrupt, every source has
//! [`FrameSource::validate_all`], a pre-scan:
//! - image folders decode every image once and discard it (about 1 ms per 320×240 PNG, memory
//!   bounded by one frame), then decode again while tracking. Keeping all decoded frames instead
//!   would cost about 0.5 MB per 320×240 frame (grey `f32` plus RGB), 1 GB for 2,000 frames;
//! - a Y4M file is read through once without conversion (header, every `FRAME` line, exact plane
//!   sizes), then reopened;
//! - Y4M on standard input cannot be read twice and is not kept: it is a *stream*
//!   ([`FrameSource::is_stream`]), read one frame at a time in constant memory, and each frame is
//!   checked as it arrives. Its frame size is known from the header ([`Y4mSource::header`]).
//!
//! Sizes are checked before anything is allocated: a Y4M header may not claim frames wider or
//! taller than [`MAX_SIDE`] pixels or larger than [`MAX_PIXELS`] (a 4.6 kB file whose header says
//! `W4000000 H4000000` would otherwise ask for 24 TB).
//!
//! Each kind of input has its own file: `folder.rs` (image folders and the decoding of one
//! image), `y4m.rs` (the Y4M reader, from a file, memory or a stream) and [`video`] (ffmpeg
//! decoding a video file into a Y4M stream). This file holds what they share and
//! [`open_sequence`], which picks one from the command-line argument.

mod folder;
pub mod video;
mod y4m;

use std::path::{Path, PathBuf};

use image::{GrayImage, RgbImage};
use vision_core::GreyBuffer;

use crate::{AppError, Result};

pub use folder::{IMAGE_EXTENSIONS, ImageFolder, decode_image, sort_natural};
pub use y4m::{MAX_PIXELS, MAX_SIDE, Y4mColour, Y4mHeader, Y4mSource};

/// The 8-bit original of a frame, kept for drawing overlays.
#[derive(Debug, Clone, PartialEq)]
pub enum Original {
    /// A colour frame.
    Rgb(RgbImage),
    /// A grey frame.
    Luma(GrayImage),
}

impl Original {
    /// The frame as RGB (grey frames are replicated into three channels).
    pub fn to_rgb(&self) -> RgbImage {
        match self {
            Original::Rgb(img) => img.clone(),
            Original::Luma(img) => image::DynamicImage::ImageLuma8(img.clone()).to_rgb8(),
        }
    }

    /// `(width, height)` in pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        match self {
            Original::Rgb(img) => img.dimensions(),
            Original::Luma(img) => img.dimensions(),
        }
    }
}

/// One frame of a sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// 0-based position in the sequence.
    pub index: usize,
    /// Where the frame came from, for messages: the image file, or `file.y4m#frame`.
    pub name: String,
    /// The grey image the trackers read.
    pub grey: GreyBuffer,
    /// The 8-bit original for rendering.
    pub original: Original,
}

/// A sequence of frames read one at a time.
pub trait FrameSource {
    /// The number of frames, when known before reading them.
    fn len(&self) -> Option<usize>;

    /// Whether the source is known to hold no frame.
    fn is_empty(&self) -> bool {
        self.len() == Some(0)
    }

    /// The next frame, or `None` at the end.
    ///
    /// # Errors
    /// [`AppError::BadInput`] naming the file: unreadable, corrupt or truncated data, or a frame
    /// whose size differs from the first one.
    fn next_frame(&mut self) -> Result<Option<Frame>>;

    /// Reads every frame once without keeping it and checks it as [`FrameSource::next_frame`]
    /// would, so that a run can fail before it writes any output; returns the frame count and the
    /// frame size. Does not move this source's reading position.
    ///
    /// # Errors
    /// The first error [`FrameSource::next_frame`] would meet, or an empty sequence;
    /// [`AppError::BadInput`] for a stream ([`FrameSource::is_stream`]), which cannot be read
    /// twice.
    fn validate_all(&self) -> Result<SequenceInfo> {
        self.validate_all_with(&mut |_| Ok(()))
    }

    /// [`FrameSource::validate_all`], calling `on_frame` with the number of frames checked so
    /// far after each frame: to show progress, or to stop the pre-scan (a signal) by returning
    /// an error, which the pre-scan returns at once.
    ///
    /// # Errors
    /// As [`FrameSource::validate_all`], or the error of `on_frame`.
    fn validate_all_with(
        &self,
        on_frame: &mut dyn FnMut(usize) -> Result<()>,
    ) -> Result<SequenceInfo>;

    /// Whether the source is a stream (Y4M on standard input) that can be read only once: it has
    /// no [`FrameSource::validate_all`], and each frame is checked as it is read.
    fn is_stream(&self) -> bool {
        false
    }
}

/// What a pre-scan learnt about a sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SequenceInfo {
    /// Number of frames.
    pub frames: usize,
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
}

/// Reads every remaining frame of `source` into memory (convenient for short sequences and
/// tests; see the module documentation for the memory cost).
///
/// # Errors
/// The first error of [`FrameSource::next_frame`].
pub fn read_all(source: &mut dyn FrameSource) -> Result<Vec<Frame>> {
    read_every(source, 1).map(|(frames, _)| frames)
}

/// Reads every remaining frame of `source` and keeps every `step`-th from the first (`step` ≥ 1;
/// 0 is read as 1), with the number of frames read: only the frames kept are held in memory.
///
/// # Errors
/// The first error of [`FrameSource::next_frame`].
pub fn read_every(source: &mut dyn FrameSource, step: usize) -> Result<(Vec<Frame>, usize)> {
    let step = step.max(1);
    let mut frames = Vec::with_capacity(source.len().unwrap_or(0).div_ceil(step));
    let mut read = 0;
    while let Some(f) = source.next_frame()? {
        if read % step == 0 {
            frames.push(f);
        }
        read += 1;
    }
    Ok((frames, read))
}

/// What kind of input a sequence argument named.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SequenceKind {
    /// A folder of images.
    ImageFolder,
    /// An OTB folder: `img/` plus `groundtruth_rect.txt`.
    Otb,
    /// A `.y4m` file.
    Y4mFile,
    /// Y4M on standard input (`-`).
    Y4mStdin,
    /// Any other file, a video (`.mp4`, `.mov`, `.avi`, `.mkv`, …) decoded by ffmpeg and read as a
    /// Y4M stream ([`video`]).
    Video,
}

/// Any frame source the command line can open.
#[derive(Debug)]
pub enum Source {
    /// Images in a folder.
    Images(ImageFolder),
    /// A Y4M stream.
    Y4m(Y4mSource),
    /// A video file decoded by ffmpeg into a Y4M stream.
    Video {
        /// The stream of decoded frames.
        frames: Y4mSource,
        /// Stops ffmpeg early.
        ffmpeg: video::FfmpegHandle,
        /// The number of frames ffprobe expects ([`video::probe_frame_count`]), for progress.
        expected: Option<usize>,
    },
}

impl FrameSource for Source {
    fn len(&self) -> Option<usize> {
        match self {
            Source::Images(s) => s.len(),
            Source::Y4m(s) | Source::Video { frames: s, .. } => s.len(),
        }
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        match self {
            Source::Images(s) => s.next_frame(),
            Source::Y4m(s) | Source::Video { frames: s, .. } => s.next_frame(),
        }
    }

    fn validate_all_with(
        &self,
        on_frame: &mut dyn FnMut(usize) -> Result<()>,
    ) -> Result<SequenceInfo> {
        match self {
            Source::Images(s) => s.validate_all_with(on_frame),
            Source::Y4m(s) | Source::Video { frames: s, .. } => s.validate_all_with(on_frame),
        }
    }

    fn is_stream(&self) -> bool {
        match self {
            Source::Images(s) => s.is_stream(),
            Source::Y4m(s) | Source::Video { frames: s, .. } => s.is_stream(),
        }
    }
}

impl Source {
    /// The frame size `(width, height)` when it is known without reading a frame (a Y4M header).
    pub fn frame_size(&self) -> Option<(usize, usize)> {
        match self {
            Source::Images(_) => None,
            Source::Y4m(s) | Source::Video { frames: s, .. } => {
                Some((s.header().width, s.header().height))
            }
        }
    }

    /// The frame rate in frames per second, when the input states it (a Y4M header, a video).
    pub fn frame_rate(&self) -> Option<f64> {
        match self {
            Source::Images(_) => None,
            Source::Y4m(s) | Source::Video { frames: s, .. } => s
                .header()
                .frame_rate
                .map(|(n, d)| f64::from(n) / f64::from(d)),
        }
    }

    /// The number of frames a stream is expected to hold, for a progress bar: ffprobe's count
    /// for a video file, else [`FrameSource::len`]. Not a promise: the frames read decide.
    pub fn expected_frames(&self) -> Option<usize> {
        match self {
            Source::Video { expected, .. } => *expected,
            other => other.len(),
        }
    }

    /// Stops the decoder of a video (ffmpeg) so that a reader blocked on it returns; nothing for
    /// other sources.
    pub fn stopper(&self) -> Option<video::FfmpegHandle> {
        match self {
            Source::Video { ffmpeg, .. } => Some(ffmpeg.clone()),
            _ => None,
        }
    }
}

/// An opened sequence: its frames, and the ground-truth file when it is an OTB folder.
#[derive(Debug)]
pub struct Sequence {
    /// What the argument named.
    pub kind: SequenceKind,
    /// The frames.
    pub source: Source,
    /// `groundtruth_rect.txt` of an OTB folder.
    pub groundtruth: Option<PathBuf>,
    /// A short name for reports: the folder or file name, or `stdin`.
    pub name: String,
}

/// Opens the sequence named by a `track run` argument: `-` (Y4M on standard input), a `.y4m`
/// file, any other file as a video decoded by ffmpeg ([`video`]), an OTB folder (`img/` and `groundtruth_rect.txt`; a folder with only `img/` is read as
/// that image folder without ground truth), or a folder of images.
///
/// # Errors
/// [`AppError::BadInput`] naming the path: missing, not a folder or `.y4m` file, empty folder,
/// bad Y4M header.
pub fn open_sequence(spec: &str) -> Result<Sequence> {
    if spec == "-" {
        return Ok(Sequence {
            kind: SequenceKind::Y4mStdin,
            source: Source::Y4m(Y4mSource::stdin()?),
            groundtruth: None,
            name: "stdin".to_string(),
        });
    }
    let path = Path::new(spec);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| spec.to_string());
    if !path.exists() {
        return Err(AppError::input(path, "no such file or folder"));
    }
    if path.is_file() {
        if video::is_video_path(path) {
            let expected = video::probe_frame_count(path);
            let (reader, ffmpeg) = video::FfmpegReader::spawn(path)?;
            return Ok(Sequence {
                kind: SequenceKind::Video,
                source: Source::Video {
                    frames: Y4mSource::from_reader(reader, path)?,
                    ffmpeg,
                    expected,
                },
                groundtruth: None,
                name,
            });
        }
        return Ok(Sequence {
            kind: SequenceKind::Y4mFile,
            source: Source::Y4m(Y4mSource::open(path)?),
            groundtruth: None,
            name,
        });
    }
    let img = path.join("img");
    if img.is_dir() {
        let gt = path.join("groundtruth_rect.txt");
        if gt.exists() && !gt.is_file() {
            return Err(AppError::input(
                &gt,
                "not a file: an OTB folder's ground truth must be a text file of x,y,w,h lines \
                 (this is a folder or a special file)",
            ));
        }
        let has_gt = gt.is_file();
        return Ok(Sequence {
            kind: if has_gt {
                SequenceKind::Otb
            } else {
                SequenceKind::ImageFolder
            },
            source: Source::Images(ImageFolder::open(&img)?),
            groundtruth: has_gt.then_some(gt),
            name,
        });
    }
    Ok(Sequence {
        kind: SequenceKind::ImageFolder,
        source: Source::Images(ImageFolder::open(path)?),
        groundtruth: None,
        name,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes an RGB PNG whose pixel (x, y) is `f(x, y)`.
    pub(super) fn write_png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
        let img = RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
        img.save(path).unwrap();
    }

    #[test]
    fn otb_folder_is_recognised() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("img")).unwrap();
        write_png(&dir.path().join("img/0001.png"), 4, 4, |_, _| [9, 9, 9]);
        let seq = open_sequence(dir.path().to_str().unwrap()).unwrap();
        assert_eq!(seq.kind, SequenceKind::ImageFolder);
        std::fs::write(dir.path().join("groundtruth_rect.txt"), "0,0,2,2\n").unwrap();
        let seq = open_sequence(dir.path().to_str().unwrap()).unwrap();
        assert_eq!(seq.kind, SequenceKind::Otb);
        assert_eq!(
            seq.groundtruth,
            Some(dir.path().join("groundtruth_rect.txt"))
        );
        assert_eq!(seq.source.len(), Some(1));
        let not_seq = dir.path().join("groundtruth_rect.txt");
        assert!(open_sequence(not_seq.to_str().unwrap()).is_err());
    }

    #[test]
    fn sources_can_move_to_another_thread() {
        fn is_send<T: Send>() {}
        is_send::<Source>();
        is_send::<Sequence>();
    }
}
