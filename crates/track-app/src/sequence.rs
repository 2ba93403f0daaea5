//! Frame sources: a folder of images, an OTB folder, a `.y4m` file, or Y4M on standard input.
//!
//! Every source yields frames one at a time as a grey `f32` image in 0–255 grey levels (what the
//! libraries consume) together with the 8-bit original (RGB or luma) for rendering overlays.
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

use std::fs::File;
use std::io::{BufRead, BufReader, Cursor, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use image::{GrayImage, RgbImage};

use crate::{AppError, Result};

/// A grey image: row-major, `width × height` samples in 0–255 grey-level units.
#[derive(Debug, Clone, PartialEq)]
pub struct GrayFrame {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major samples, `data[y * width + x]`.
    pub data: Vec<f32>,
}

impl GrayFrame {
    /// The sample at column `x`, row `y`, or `None` outside the image.
    pub fn get(&self, x: usize, y: usize) -> Option<f32> {
        (x < self.width && y < self.height).then(|| self.data[y * self.width + x])
    }
}

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
    pub gray: GrayFrame,
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
    fn validate_all(&self) -> Result<SequenceInfo>;

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
    let mut frames = Vec::with_capacity(source.len().unwrap_or(0));
    while let Some(f) = source.next_frame()? {
        frames.push(f);
    }
    Ok(frames)
}

/// Converts 8-bit RGB to grey with the ITU-R BT.601 luma weights, the same weighting as the luma
/// plane of a Y4M video, so both kinds of input give the trackers the same grey levels.
fn rgb_to_gray(img: &RgbImage) -> Vec<f32> {
    img.pixels()
        .map(|p| 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Image folders.

/// A folder of images (PNG, JPEG, GIF, BMP, WebP, TIFF), read in the natural order of their
/// file names.
#[derive(Debug, Clone)]
pub struct ImageFolder {
    folder: PathBuf,
    paths: Vec<PathBuf>,
    next: usize,
    /// Size and name of the first frame, fixed once it is read.
    first: Option<(u32, u32, PathBuf)>,
}

/// The file extensions read as images (lower case; any case matches).
pub const IMAGE_EXTENSIONS: [&str; 8] = ["png", "jpg", "jpeg", "gif", "bmp", "webp", "tif", "tiff"];

/// Whether `path` has one of the [`IMAGE_EXTENSIONS`] (case-insensitive).
fn is_image_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// The supported extensions as a message lists them: `.png, .jpg, …`.
fn supported_extensions() -> String {
    IMAGE_EXTENSIONS.map(|e| format!(".{e}")).join(", ")
}

/// Sorts frame files in natural order of their names: runs of digits compare by value, so
/// `2.png` comes before `10.png` (as image viewers and ffmpeg's `%d` patterns number frames),
/// and zero-padded names (`0001.png`) keep their order. Uses the `alphanumeric-sort` crate,
/// which compares names that are not UTF-8 too.
pub fn sort_natural(paths: &mut [PathBuf]) {
    alphanumeric_sort::sort_slice_by_os_str_key(paths, |p: &PathBuf| {
        p.file_name().unwrap_or(p.as_os_str())
    });
}

impl ImageFolder {
    /// Lists the image files ([`IMAGE_EXTENSIONS`], any case) in `folder`, sorted in natural
    /// order of their names ([`sort_natural`]). Other files are ignored.
    ///
    /// # Errors
    /// [`AppError::BadInput`] when the folder cannot be read or holds no image; the message lists
    /// the supported extensions and the extensions of the files it found instead.
    pub fn open(folder: &Path) -> Result<Self> {
        let entries = std::fs::read_dir(folder)
            .map_err(|e| AppError::input(folder, format!("cannot read folder: {e}")))?;
        let mut paths = Vec::new();
        let mut others: std::collections::BTreeMap<String, usize> = Default::default();
        for entry in entries {
            let entry =
                entry.map_err(|e| AppError::input(folder, format!("cannot read folder: {e}")))?;
            let path = entry.path();
            if !path.is_file() {
                continue;
            }
            if is_image_path(&path) {
                paths.push(path);
            } else {
                let ext = path
                    .extension()
                    .map(|e| format!(".{}", e.to_string_lossy().to_ascii_lowercase()))
                    .unwrap_or_else(|| "no extension".to_owned());
                *others.entry(ext).or_default() += 1;
            }
        }
        if paths.is_empty() {
            let found = if others.is_empty() {
                "it holds no file".to_owned()
            } else {
                let list: Vec<String> = others.iter().map(|(e, n)| format!("{e} ×{n}")).collect();
                format!("found only {}", list.join(", "))
            };
            return Err(AppError::input(
                folder,
                format!(
                    "empty folder: no image with a supported extension ({}); {found}",
                    supported_extensions()
                ),
            ));
        }
        sort_natural(&mut paths);
        Ok(Self {
            folder: folder.to_path_buf(),
            paths,
            next: 0,
            first: None,
        })
    }

    /// The folder.
    pub fn folder(&self) -> &Path {
        &self.folder
    }

    /// The image files, in reading order.
    pub fn paths(&self) -> &[PathBuf] {
        &self.paths
    }

    /// Decodes `path` and checks its size against the first frame, recording it if there is none.
    fn decode_checked(
        path: &Path,
        first: &mut Option<(u32, u32, PathBuf)>,
    ) -> Result<(Original, (u32, u32))> {
        let img = decode_image(path)?;
        let original = match img {
            image::DynamicImage::ImageLuma8(g) => Original::Luma(g),
            other => Original::Rgb(other.to_rgb8()),
        };
        let (w, h) = original.dimensions();
        match first {
            None => *first = Some((w, h, path.to_path_buf())),
            Some((fw, fh, fpath)) if (*fw, *fh) != (w, h) => {
                let first_name = fpath.file_name().map(|n| n.to_string_lossy().into_owned());
                return Err(AppError::input(
                    path,
                    format!(
                        "frame is {w}×{h} but the first frame ({}) is {fw}×{fh}; all frames must have the same size",
                        first_name.unwrap_or_default()
                    ),
                ));
            }
            Some(_) => {}
        }
        Ok((original, (w, h)))
    }
}

/// Whether a JPEG file has an end-of-image marker (FF D9) after its last start-of-scan marker
/// (FF DA). The JPEG decoder fills a truncated scan with grey without complaint, so a cut-off
/// file must be caught here. Inside entropy-coded data a 0xFF byte is always followed by 0x00 or
/// a restart marker, so neither marker can appear there by accident; an EOI that belongs to an
/// embedded thumbnail comes before the main image's scan and does not count.
fn jpeg_is_complete(bytes: &[u8]) -> bool {
    let find_last = |m: u8| bytes.windows(2).rposition(|w| w == [0xFF, m]);
    match (find_last(0xDA), find_last(0xD9)) {
        (Some(sos), Some(eoi)) => eoi > sos,
        _ => false,
    }
}

/// Decodes one image file, with a clear message for unreadable, corrupt and truncated files and
/// for images the decoder's memory limit refuses. Every command reads images through it.
///
/// # Errors
/// [`AppError::BadInput`] naming the file and the problem.
pub fn decode_image(path: &Path) -> Result<image::DynamicImage> {
    let bytes = std::fs::read(path)
        .map_err(|e| AppError::input(path, format!("cannot read image: {e}")))?;
    if bytes.is_empty() {
        return Err(AppError::input(path, "empty file (0 bytes), not an image"));
    }
    let format = image::guess_format(&bytes).map_err(|_| {
        AppError::input(
            path,
            "corrupt image: not a PNG, JPEG, GIF, BMP, WebP or TIFF file",
        )
    })?;
    if format == image::ImageFormat::Jpeg && !jpeg_is_complete(&bytes) {
        return Err(AppError::input(
            path,
            "truncated image: the JPEG data ends before its end-of-image marker",
        ));
    }
    image::load_from_memory_with_format(&bytes, format).map_err(|e| {
        let what = match &e {
            image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
                "truncated image".to_string()
            }
            image::ImageError::Unsupported(_) => format!("unsupported image: {e}"),
            image::ImageError::Limits(_) => {
                format!("image too large: the decoder's memory limit refuses it ({e})")
            }
            _ => {
                let text = e.to_string();
                let lower = text.to_ascii_lowercase();
                if lower.contains("eof") || lower.contains("end of") {
                    format!("truncated image ({text})")
                } else if lower.contains("limit") || lower.contains("too large") {
                    // Some decoders report their memory limit as a decoding error.
                    format!("image too large: the decoder's memory limit refuses it ({text})")
                } else {
                    format!("corrupt image ({text})")
                }
            }
        };
        AppError::input(path, what)
    })
}

impl FrameSource for ImageFolder {
    fn len(&self) -> Option<usize> {
        Some(self.paths.len())
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let Some(path) = self.paths.get(self.next).cloned() else {
            return Ok(None);
        };
        let (original, (w, h)) = Self::decode_checked(&path, &mut self.first)?;
        let data = match &original {
            Original::Rgb(img) => rgb_to_gray(img),
            Original::Luma(img) => img.as_raw().iter().map(|&v| f32::from(v)).collect(),
        };
        let index = self.next;
        self.next += 1;
        Ok(Some(Frame {
            index,
            name: path.display().to_string(),
            gray: GrayFrame {
                width: w as usize,
                height: h as usize,
                data,
            },
            original,
        }))
    }

    fn validate_all(&self) -> Result<SequenceInfo> {
        let mut first = None;
        let mut size = (0, 0);
        for path in &self.paths {
            size = Self::decode_checked(path, &mut first)?.1;
        }
        Ok(SequenceInfo {
            frames: self.paths.len(),
            width: size.0 as usize,
            height: size.1 as usize,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Y4M.

/// Largest frame width or height accepted from a Y4M header, pixels.
pub const MAX_SIDE: usize = 32_768;
/// Largest frame area accepted from a Y4M header, pixels: 2²⁶ (8192×8192, twice 8K UHD). One frame
/// of that size takes about 1.3 GB through reading, conversion, tracking and drawing.
pub const MAX_PIXELS: usize = 1 << 26;

/// Chroma layouts of Y4M that can be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Y4mColour {
    /// 4:2:0 (`C420jpeg`, `C420paldv`, `C420`, `C420mpeg2`, or no `C` tag): chroma planes of
    /// ⌈w/2⌉×⌈h/2⌉.
    C420,
    /// 4:4:4 (`C444`): full-size chroma planes.
    C444,
    /// Luma only (`Cmono`).
    Mono,
}

impl Y4mColour {
    /// Size in bytes of one frame's planes.
    fn frame_bytes(self, w: usize, h: usize) -> usize {
        match self {
            Y4mColour::C420 => w * h + 2 * w.div_ceil(2) * h.div_ceil(2),
            Y4mColour::C444 => 3 * w * h,
            Y4mColour::Mono => w * h,
        }
    }
}

/// The stream header of a Y4M video.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Y4mHeader {
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// Chroma layout.
    pub colour: Y4mColour,
    /// Frame rate as numerator and denominator, when given.
    pub frame_rate: Option<(u32, u32)>,
}

impl Y4mHeader {
    /// Parses the header line (without its newline). `name` is the file for messages.
    ///
    /// # Errors
    /// [`AppError::BadInput`]: missing `YUV4MPEG2` signature, missing or invalid size, or an
    /// unsupported colour space (named in the message).
    pub fn parse(line: &[u8], name: &Path) -> Result<Self> {
        // A header saved with Windows line endings ends in CR LF; the CR is not part of the last
        // tag (it made `C420jpeg` read as an unknown colour space).
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let text = std::str::from_utf8(line)
            .map_err(|_| AppError::input(name, "bad Y4M header: not ASCII text"))?;
        let mut tokens = text.split(' ').filter(|t| !t.is_empty());
        if tokens.next() != Some("YUV4MPEG2") {
            return Err(AppError::input(
                name,
                "bad Y4M header: the file does not start with YUV4MPEG2",
            ));
        }
        let (mut width, mut height, mut colour, mut frame_rate) =
            (None, None, Y4mColour::C420, None);
        for token in tokens {
            let (tag, value) = token.split_at(1);
            match tag {
                "W" | "H" => {
                    let v: usize = value.parse().ok().filter(|&v| v > 0).ok_or_else(|| {
                        AppError::input(name, format!("bad Y4M header: invalid size {token:?}"))
                    })?;
                    if tag == "W" {
                        width = Some(v);
                    } else {
                        height = Some(v);
                    }
                }
                "C" => {
                    colour = match value {
                        "420jpeg" | "420paldv" | "420" | "420mpeg2" => Y4mColour::C420,
                        "444" => Y4mColour::C444,
                        "mono" => Y4mColour::Mono,
                        other => {
                            return Err(AppError::input(
                                name,
                                format!(
                                    "unsupported Y4M colour space {:?} (supported: C420jpeg, C420paldv, C420, C420mpeg2, C444, Cmono; convert with ffmpeg -pix_fmt yuv420p)",
                                    format!("C{other}")
                                ),
                            ));
                        }
                    };
                }
                "F" => {
                    frame_rate = value.split_once(':').and_then(|(n, d)| {
                        Some((n.parse().ok()?, d.parse().ok()?))
                            .filter(|&(_, d): &(u32, u32)| d > 0)
                    });
                }
                // Interlacing, aspect ratio and extensions do not change how frames are read.
                _ => {}
            }
        }
        match (width, height) {
            (Some(width), Some(height)) => {
                // Checked before any buffer is sized from the header.
                let pixels = width.saturating_mul(height);
                if width > MAX_SIDE || height > MAX_SIDE || pixels > MAX_PIXELS {
                    return Err(AppError::input(
                        name,
                        format!(
                            "Y4M frame size {width}×{height} is too large (at most {MAX_SIDE} \
                             pixels a side and {MAX_PIXELS} pixels a frame)"
                        ),
                    ));
                }
                Ok(Self {
                    width,
                    height,
                    colour,
                    frame_rate,
                })
            }
            _ => Err(AppError::input(name, "bad Y4M header: missing W or H")),
        }
    }

    /// Size in bytes of one frame's planes (without the `FRAME` line).
    pub fn frame_bytes(&self) -> usize {
        self.colour.frame_bytes(self.width, self.height)
    }
}

/// Reads one line up to `\n` (at most `limit` bytes); `None` at a clean end of input.
fn read_line_limited(reader: &mut dyn BufRead, limit: usize) -> std::io::Result<Option<Vec<u8>>> {
    let mut line = Vec::new();
    let n = reader.take(limit as u64).read_until(b'\n', &mut line)?;
    if n == 0 {
        return Ok(None);
    }
    if line.last() == Some(&b'\n') {
        line.pop();
    } else {
        // No newline within the limit: report as an unterminated line.
        return Err(std::io::Error::new(
            std::io::ErrorKind::UnexpectedEof,
            "line without newline",
        ));
    }
    Ok(Some(line))
}

/// Reads the stream header from `reader`; also returns its length in bytes with the newline.
fn read_header(reader: &mut dyn BufRead, name: &Path) -> Result<(Y4mHeader, usize)> {
    match read_line_limited(reader, 1024) {
        Ok(Some(line)) => Ok((Y4mHeader::parse(&line, name)?, line.len() + 1)),
        Ok(None) => Err(AppError::input(name, "bad Y4M header: empty input")),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => Err(AppError::input(
            name,
            "bad Y4M header: no header line (is this a Y4M file?)",
        )),
        Err(e) => Err(AppError::input(name, format!("cannot read: {e}"))),
    }
}

/// Reads the planes of frame `index` into `buf`; `Ok(false)` at a clean end of the stream.
fn read_frame_raw(
    reader: &mut dyn BufRead,
    header: &Y4mHeader,
    index: usize,
    name: &Path,
    buf: &mut Vec<u8>,
) -> Result<bool> {
    let frame_no = index + 1;
    let line = match read_line_limited(reader, 1024) {
        Ok(Some(line)) => line,
        Ok(None) => return Ok(false),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            return Err(AppError::input(
                name,
                format!("truncated Y4M: frame {frame_no} header is cut off"),
            ));
        }
        Err(e) => return Err(AppError::input(name, format!("cannot read: {e}"))),
    };
    if !line.starts_with(b"FRAME") {
        return Err(AppError::input(
            name,
            format!("corrupt Y4M: frame {frame_no} does not start with FRAME"),
        ));
    }
    let need = header.frame_bytes();
    buf.clear();
    let got = reader
        .take(need as u64)
        .read_to_end(buf)
        .map_err(|e| AppError::input(name, format!("cannot read: {e}")))?;
    if got < need {
        return Err(AppError::input(
            name,
            format!("truncated Y4M: frame {frame_no} has {got} of its {need} bytes"),
        ));
    }
    Ok(true)
}

/// Converts one frame's planes to the grey frame (the luma plane as is) and an RGB original
/// (full-range BT.601 conversion, chroma upsampled by repetition).
fn convert_frame(header: &Y4mHeader, raw: &[u8]) -> (GrayFrame, Original) {
    let (w, h) = (header.width, header.height);
    let luma = &raw[..w * h];
    let gray = GrayFrame {
        width: w,
        height: h,
        data: luma.iter().map(|&v| f32::from(v)).collect(),
    };
    let (cw, sub) = match header.colour {
        Y4mColour::Mono => {
            let img = GrayImage::from_raw(w as u32, h as u32, luma.to_vec());
            return (
                gray,
                Original::Luma(img.unwrap_or_else(|| GrayImage::new(w as u32, h as u32))),
            );
        }
        Y4mColour::C420 => (w.div_ceil(2), 2),
        Y4mColour::C444 => (w, 1),
    };
    let ch = h.div_ceil(sub);
    let (u_plane, v_plane) = raw[w * h..].split_at(cw * ch);
    let mut rgb = RgbImage::new(w as u32, h as u32);
    for (i, px) in rgb.pixels_mut().enumerate() {
        let (x, y) = (i % w, i / w);
        let c = (y / sub) * cw + x / sub;
        let yv = f32::from(luma[i]);
        let u = f32::from(u_plane[c]) - 128.0;
        let v = f32::from(v_plane[c]) - 128.0;
        let to_u8 = |f: f32| f.round().clamp(0.0, 255.0) as u8;
        *px = image::Rgb([
            to_u8(yv + 1.402 * v),
            to_u8(yv - 0.344_136 * u - 0.714_136 * v),
            to_u8(yv + 1.772 * u),
        ]);
    }
    (gray, Original::Rgb(rgb))
}

/// Where a Y4M stream's bytes are: a file or bytes in memory can be read again by the pre-scan;
/// a stream (standard input) cannot.
#[derive(Debug, Clone)]
enum Y4mInput {
    File(PathBuf),
    Memory(Arc<[u8]>),
    Stream,
}

impl Y4mInput {
    fn reader(&self, name: &Path) -> Result<Box<dyn BufRead + Send>> {
        match self {
            Y4mInput::File(path) => {
                let f = File::open(path)
                    .map_err(|e| AppError::input(path, format!("cannot open: {e}")))?;
                Ok(Box::new(BufReader::with_capacity(1 << 16, f)))
            }
            Y4mInput::Memory(bytes) => Ok(Box::new(Cursor::new(Arc::clone(bytes)))),
            Y4mInput::Stream => Err(AppError::input(
                name,
                "a stream can be read only once: it cannot be pre-scanned",
            )),
        }
    }
}

/// A Y4M (YUV4MPEG2) video from a file or from memory.
pub struct Y4mSource {
    name: PathBuf,
    input: Y4mInput,
    header: Y4mHeader,
    reader: Box<dyn BufRead + Send>,
    next: usize,
    len: Option<usize>,
    buf: Vec<u8>,
}

impl std::fmt::Debug for Y4mSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Y4mSource")
            .field("name", &self.name)
            .field("header", &self.header)
            .field("next", &self.next)
            .finish_non_exhaustive()
    }
}

impl Y4mSource {
    /// Opens a `.y4m` file and reads its header.
    ///
    /// # Errors
    /// [`AppError::BadInput`]: unreadable file, bad header, unsupported colour space.
    pub fn open(path: &Path) -> Result<Self> {
        let len_bytes = std::fs::metadata(path)
            .map_err(|e| AppError::input(path, format!("cannot open: {e}")))?
            .len();
        let input = Y4mInput::File(path.to_path_buf());
        let reader = input.reader(path)?;
        Self::from_input(input, reader, path, Some(len_bytes))
    }

    /// A Y4M stream read from `reader` (for example standard input) one frame at a time, in
    /// constant memory; reads its header now. `name` is used in messages (`-` for standard
    /// input). A stream cannot be pre-scanned ([`FrameSource::is_stream`]).
    ///
    /// # Errors
    /// [`AppError::BadInput`]: read failure, bad header, unsupported colour space, frame size
    /// too large.
    pub fn from_reader(reader: impl Read + Send + 'static, name: &Path) -> Result<Self> {
        let reader = Box::new(BufReader::with_capacity(1 << 16, reader));
        Self::from_input(Y4mInput::Stream, reader, name, None)
    }

    /// A Y4M video held in memory (it can be pre-scanned, unlike [`Y4mSource::from_reader`]).
    ///
    /// # Errors
    /// As [`Y4mSource::from_reader`].
    pub fn from_bytes(bytes: Vec<u8>, name: &Path) -> Result<Self> {
        let len_bytes = bytes.len() as u64;
        let input = Y4mInput::Memory(bytes.into());
        let reader = input.reader(name)?;
        Self::from_input(input, reader, name, Some(len_bytes))
    }

    /// Y4M from standard input, streamed (see [`Y4mSource::from_reader`]).
    ///
    /// # Errors
    /// As [`Y4mSource::from_reader`].
    pub fn stdin() -> Result<Self> {
        Self::from_reader(std::io::stdin(), Path::new("-"))
    }

    fn from_input(
        input: Y4mInput,
        mut reader: Box<dyn BufRead + Send>,
        name: &Path,
        len_bytes: Option<u64>,
    ) -> Result<Self> {
        let (header, header_len) = read_header(&mut reader, name)?;
        // The frame count is known when every frame line is a bare `FRAME\n` (the usual case):
        // then the bytes after the header are a whole number of frames.
        let per_frame = (header.frame_bytes() + 6) as u64;
        let len = len_bytes
            .and_then(|b| b.checked_sub(header_len as u64))
            .filter(|rest| rest % per_frame == 0)
            .map(|rest| (rest / per_frame) as usize);
        Ok(Self {
            name: name.to_path_buf(),
            input,
            header,
            reader,
            next: 0,
            len,
            buf: Vec::new(),
        })
    }

    /// The stream header.
    pub fn header(&self) -> &Y4mHeader {
        &self.header
    }
}

impl FrameSource for Y4mSource {
    fn len(&self) -> Option<usize> {
        self.len
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let mut buf = std::mem::take(&mut self.buf);
        let more = read_frame_raw(
            &mut self.reader,
            &self.header,
            self.next,
            &self.name,
            &mut buf,
        );
        let more = match more {
            Ok(more) => more,
            Err(e) => {
                self.buf = buf;
                return Err(e);
            }
        };
        if !more {
            self.buf = buf;
            return Ok(None);
        }
        let (gray, original) = convert_frame(&self.header, &buf);
        self.buf = buf;
        let index = self.next;
        self.next += 1;
        Ok(Some(Frame {
            index,
            name: format!("{}#{}", self.name.display(), index + 1),
            gray,
            original,
        }))
    }

    fn is_stream(&self) -> bool {
        matches!(self.input, Y4mInput::Stream)
    }

    fn validate_all(&self) -> Result<SequenceInfo> {
        let mut reader = self.input.reader(&self.name)?;
        read_header(&mut reader, &self.name)?;
        let mut buf = Vec::with_capacity(self.header.frame_bytes());
        let mut frames = 0;
        while read_frame_raw(&mut reader, &self.header, frames, &self.name, &mut buf)? {
            frames += 1;
        }
        if frames == 0 {
            return Err(AppError::input(
                &self.name,
                "empty Y4M: no frame after the header",
            ));
        }
        Ok(SequenceInfo {
            frames,
            width: self.header.width,
            height: self.header.height,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Opening whatever the user named.

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
    /// Y4M stream ([`crate::video`]).
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
        ffmpeg: crate::video::FfmpegHandle,
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

    fn validate_all(&self) -> Result<SequenceInfo> {
        match self {
            Source::Images(s) => s.validate_all(),
            Source::Y4m(s) | Source::Video { frames: s, .. } => s.validate_all(),
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
                Some((s.header.width, s.header.height))
            }
        }
    }

    /// The frame rate in frames per second, when the input states it (a Y4M header, a video).
    pub fn frame_rate(&self) -> Option<f64> {
        match self {
            Source::Images(_) => None,
            Source::Y4m(s) | Source::Video { frames: s, .. } => s
                .header
                .frame_rate
                .map(|(n, d)| f64::from(n) / f64::from(d)),
        }
    }

    /// Stops the decoder of a video (ffmpeg) so that a reader blocked on it returns; nothing for
    /// other sources.
    pub fn stopper(&self) -> Option<crate::video::FfmpegHandle> {
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
/// file, any other file as a video decoded by ffmpeg ([`crate::video`]), an OTB folder (`img/` and `groundtruth_rect.txt`; a folder with only `img/` is read as
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
        if crate::video::is_video_path(path) {
            let (reader, ffmpeg) = crate::video::FfmpegReader::spawn(path)?;
            return Ok(Sequence {
                kind: SequenceKind::Video,
                source: Source::Video {
                    frames: Y4mSource::from_reader(reader, path)?,
                    ffmpeg,
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

    fn write_png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
        let img = RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
        img.save(path).unwrap();
    }

    fn y4m_bytes(header: &str, frames: &[Vec<u8>]) -> Vec<u8> {
        let mut v = format!("{header}\n").into_bytes();
        for f in frames {
            v.extend_from_slice(b"FRAME\n");
            v.extend_from_slice(f);
        }
        v
    }

    #[test]
    fn folder_frames_in_name_order_with_bt601_grey() {
        let dir = tempfile::tempdir().unwrap();
        // Written out of order; read back sorted by name.
        write_png(&dir.path().join("0002.png"), 4, 3, |_, _| [0, 255, 0]);
        write_png(&dir.path().join("0001.png"), 4, 3, |x, y| {
            [(10 * x + y) as u8, 0, 0]
        });
        std::fs::write(dir.path().join("notes.txt"), "ignored").unwrap();
        let mut src = ImageFolder::open(dir.path()).unwrap();
        assert_eq!(src.len(), Some(2));
        let info = src.validate_all().unwrap();
        assert_eq!(
            info,
            SequenceInfo {
                frames: 2,
                width: 4,
                height: 3
            }
        );
        let frames = read_all(&mut src).unwrap();
        assert_eq!(frames.len(), 2);
        assert!(frames[0].name.ends_with("0001.png"));
        assert_eq!(frames[0].gray.width, 4);
        // Pixel (x = 3, y = 2): R = 32, so grey = 0.299·32 (f32 arithmetic, exact to 1e-4).
        assert!((frames[0].gray.get(3, 2).unwrap() - 0.299 * 32.0).abs() < 1e-4);
        assert!((frames[1].gray.data[0] - 0.587 * 255.0).abs() < 1e-3);
        assert_eq!(frames[1].index, 1);
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn grey_png_stays_luma() {
        let dir = tempfile::tempdir().unwrap();
        GrayImage::from_fn(2, 2, |x, _| image::Luma([if x == 0 { 7 } else { 200 }]))
            .save(dir.path().join("a.png"))
            .unwrap();
        let f = ImageFolder::open(dir.path())
            .unwrap()
            .next_frame()
            .unwrap()
            .unwrap();
        assert!(matches!(f.original, Original::Luma(_)));
        assert_eq!(f.gray.data, vec![7.0, 200.0, 7.0, 200.0]);
        assert_eq!(f.original.to_rgb().get_pixel(1, 0).0, [200, 200, 200]);
    }

    #[test]
    fn empty_and_missing_folders() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("readme.txt"), "x").unwrap();
        let msg = ImageFolder::open(dir.path()).unwrap_err().to_string();
        assert!(msg.contains("empty folder"), "{msg}");
        let missing = dir.path().join("nope");
        let err = open_sequence(missing.to_str().unwrap()).unwrap_err();
        assert!(err.to_string().contains("no such file or folder"));
        assert_eq!(err.exit_code(), 3);
    }

    #[test]
    fn corrupt_png_is_named_and_caught_by_the_prescan() {
        let dir = tempfile::tempdir().unwrap();
        write_png(&dir.path().join("0001.png"), 8, 8, |_, _| [1, 2, 3]);
        std::fs::write(dir.path().join("0002.png"), b"this is not an image at all").unwrap();
        let src = ImageFolder::open(dir.path()).unwrap();
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(
            msg.contains("0002.png") && msg.contains("corrupt image"),
            "{msg}"
        );
        // A PNG signature followed by garbage is corrupt too.
        let mut bad = vec![0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];
        bad.extend_from_slice(&[0xde; 40]);
        std::fs::write(dir.path().join("0002.png"), bad).unwrap();
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(msg.contains("0002.png") && msg.contains("image"), "{msg}");
        std::fs::write(dir.path().join("0002.png"), b"").unwrap();
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(msg.contains("empty file"), "{msg}");
    }

    #[test]
    fn truncated_png_is_reported_as_truncated() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("0001.png");
        // Noise so the compressed data is long enough to cut in the middle of the pixel data.
        write_png(&path, 64, 64, |x, y| {
            [(x * 37 + y * 91) as u8, (x ^ y) as u8, (x * y) as u8]
        });
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let mut src = ImageFolder::open(dir.path()).unwrap();
        let err = src.next_frame().unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("0001.png") && msg.contains("truncated"),
            "{msg}"
        );
        assert_eq!(err.exit_code(), 3);
    }

    #[test]
    fn truncated_jpeg_is_reported_as_truncated() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("0001.jpg");
        write_png(&dir.path().join("x.png"), 48, 32, |x, y| {
            [(x * 5) as u8, (y * 7) as u8, 90]
        });
        image::open(dir.path().join("x.png"))
            .unwrap()
            .save(&path)
            .unwrap();
        std::fs::remove_file(dir.path().join("x.png")).unwrap();
        // The complete file decodes.
        let src = ImageFolder::open(dir.path()).unwrap();
        assert_eq!(src.validate_all().unwrap().width, 48);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 40]).unwrap();
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(
            msg.contains("0001.jpg") && msg.contains("truncated image"),
            "{msg}"
        );
    }

    #[test]
    fn mismatched_sizes_name_the_frame_and_both_sizes() {
        let dir = tempfile::tempdir().unwrap();
        write_png(&dir.path().join("0001.png"), 8, 6, |_, _| [0, 0, 0]);
        write_png(&dir.path().join("0002.png"), 8, 6, |_, _| [0, 0, 0]);
        write_png(&dir.path().join("0003.png"), 9, 6, |_, _| [0, 0, 0]);
        let src = ImageFolder::open(dir.path()).unwrap();
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(msg.contains("0003.png"), "{msg}");
        assert!(
            msg.contains("9×6") && msg.contains("8×6") && msg.contains("0001.png"),
            "{msg}"
        );
        let mut src = src;
        assert!(src.next_frame().is_ok() && src.next_frame().is_ok());
        assert!(src.next_frame().is_err());
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
    fn y4m_420_frames_and_colour() {
        // 3×3 frame: luma 9 bytes, chroma planes 2×2 each.
        let luma: Vec<u8> = (0..9).map(|v| v * 10).collect();
        let mut f1 = luma.clone();
        f1.extend_from_slice(&[128; 8]);
        let mut f2 = vec![100; 9];
        f2.extend_from_slice(&[128, 128, 128, 128, 228, 228, 228, 228]);
        let bytes = y4m_bytes(
            "YUV4MPEG2 W3 H3 F25:1 Ip A1:1 C420jpeg XYSCSS=420JPEG",
            &[f1, f2],
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("v.y4m");
        std::fs::write(&path, &bytes).unwrap();
        let mut seq = open_sequence(path.to_str().unwrap()).unwrap();
        assert_eq!(seq.kind, SequenceKind::Y4mFile);
        assert_eq!(seq.source.len(), Some(2));
        assert_eq!(seq.source.validate_all().unwrap().frames, 2);
        let frames = read_all(&mut seq.source).unwrap();
        assert_eq!(frames.len(), 2);
        assert_eq!(
            frames[0].gray.data,
            luma.iter().map(|&v| f32::from(v)).collect::<Vec<_>>()
        );
        // Neutral chroma gives grey RGB equal to luma.
        assert_eq!(frames[0].original.to_rgb().get_pixel(2, 1).0, [50, 50, 50]);
        // V = 228 (+100): R = 100 + 140.2 → 240, G = 100 − 71.4 → 29, B = 100.
        assert_eq!(
            frames[1].original.to_rgb().get_pixel(0, 0).0,
            [240, 29, 100]
        );
        let src = Y4mSource::from_bytes(bytes.clone(), Path::new("v.y4m")).unwrap();
        assert_eq!(src.header().frame_rate, Some((25, 1)));
        assert_eq!(src.validate_all().unwrap().frames, 2);
        // A stream is read once, frame by frame, and has no pre-scan.
        let mut stream = Y4mSource::from_reader(Cursor::new(bytes), Path::new("-")).unwrap();
        assert!(stream.is_stream() && !src.is_stream());
        assert_eq!(stream.len(), None);
        let msg = stream.validate_all().unwrap_err().to_string();
        assert!(msg.contains("cannot be pre-scanned"), "{msg}");
        let streamed = read_all(&mut stream).unwrap();
        assert_eq!(streamed.len(), 2);
        for (a, b) in streamed.iter().zip(&frames) {
            assert_eq!((&a.gray, &a.original), (&b.gray, &b.original));
        }
        assert_eq!(streamed[1].name, "-#2");
    }

    #[test]
    fn sources_can_move_to_another_thread() {
        fn is_send<T: Send>() {}
        is_send::<Source>();
        is_send::<Sequence>();
    }

    #[test]
    fn y4m_mono_and_444() {
        let bytes = y4m_bytes("YUV4MPEG2 W2 H1 Cmono", &[vec![3, 4]]);
        let mut src = Y4mSource::from_reader(Cursor::new(bytes), Path::new("m.y4m")).unwrap();
        let f = src.next_frame().unwrap().unwrap();
        assert!(matches!(f.original, Original::Luma(_)));
        assert_eq!(f.gray.data, vec![3.0, 4.0]);
        let bytes = y4m_bytes("YUV4MPEG2 W2 H1 C444", &[vec![3, 4, 128, 128, 128, 128]]);
        let mut src = Y4mSource::from_reader(Cursor::new(bytes), Path::new("c.y4m")).unwrap();
        assert_eq!(
            src.next_frame()
                .unwrap()
                .unwrap()
                .original
                .to_rgb()
                .get_pixel(1, 0)
                .0,
            [4, 4, 4]
        );
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn y4m_unsupported_colour_space_is_named() {
        for cs in ["C422", "C420p10", "C444alpha"] {
            let bytes = y4m_bytes(&format!("YUV4MPEG2 W2 H2 {cs}"), &[vec![0; 8]]);
            let err = Y4mSource::from_reader(Cursor::new(bytes), Path::new("v.y4m")).unwrap_err();
            let msg = err.to_string();
            assert!(
                msg.starts_with("v.y4m: unsupported Y4M colour space") && msg.contains(cs),
                "{msg}"
            );
            assert_eq!(err.exit_code(), 3);
        }
    }

    #[test]
    fn y4m_bad_headers() {
        for (bytes, what) in [
            (b"P6 3 3 255\n".to_vec(), "YUV4MPEG2"),
            (b"YUV4MPEG2 W3 C420\n".to_vec(), "missing W or H"),
            (b"YUV4MPEG2 W0 H3\n".to_vec(), "invalid size"),
            (b"YUV4MPEG2 W3 H3".to_vec(), "no header line"),
            (Vec::new(), "empty input"),
        ] {
            let msg = Y4mSource::from_reader(Cursor::new(bytes), Path::new("v.y4m"))
                .unwrap_err()
                .to_string();
            assert!(
                msg.contains("bad Y4M header") && msg.contains(what),
                "{msg}"
            );
        }
    }

    #[test]
    fn y4m_truncated_frame_and_bad_frame_marker() {
        let mut bytes = y4m_bytes("YUV4MPEG2 W4 H2 C420", &[vec![1; 12], vec![2; 12]]);
        bytes.truncate(bytes.len() - 5);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.y4m");
        std::fs::write(&path, &bytes).unwrap();
        let mut src = Y4mSource::open(&path).unwrap();
        assert_eq!(src.len(), None);
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(
            msg.contains("t.y4m") && msg.contains("truncated Y4M: frame 2 has 7 of its 12 bytes"),
            "{msg}"
        );
        assert!(src.next_frame().unwrap().is_some());
        assert!(src.next_frame().is_err());
        let bytes = b"YUV4MPEG2 W1 H1 Cmono\nFRAME\n\x05FRAMX\n\x06".to_vec();
        let src = Y4mSource::from_bytes(bytes, Path::new("v.y4m")).unwrap();
        let msg = src.validate_all().unwrap_err().to_string();
        assert!(msg.contains("frame 2 does not start with FRAME"), "{msg}");
        let src = Y4mSource::from_bytes(b"YUV4MPEG2 W1 H1\n".to_vec(), Path::new("e")).unwrap();
        assert!(
            src.validate_all()
                .unwrap_err()
                .to_string()
                .contains("no frame")
        );
    }

    #[test]
    fn y4m_sizes_that_cannot_fit_are_refused_before_reading_a_frame() {
        for (header, what) in [
            ("YUV4MPEG2 W4000000 H4000000 C420jpeg", "4000000×4000000"),
            ("YUV4MPEG2 W32769 H2 Cmono", "32769×2"),
            ("YUV4MPEG2 W16384 H16384", "16384×16384"),
            // The product overflows 64 bits.
            (
                "YUV4MPEG2 W18446744073709551615 H3",
                "18446744073709551615×3",
            ),
        ] {
            let mut bytes = format!("{header}\nFRAME\n").into_bytes();
            bytes.extend_from_slice(&[0; 4096]);
            let err = Y4mSource::from_reader(Cursor::new(bytes), Path::new("big.y4m")).unwrap_err();
            let msg = err.to_string();
            assert!(
                msg.starts_with("big.y4m: Y4M frame size") && msg.contains(what),
                "{msg}"
            );
            assert!(msg.contains("too large"), "{msg}");
            assert_eq!(err.exit_code(), 3);
        }
        // The largest accepted sizes are accepted (the header alone, no frame).
        for header in ["YUV4MPEG2 W8192 H8192", "YUV4MPEG2 W32768 H2048"] {
            let src = Y4mSource::from_bytes(format!("{header}\n").into_bytes(), Path::new("h"));
            assert!(src.is_ok(), "{header}");
        }
    }
}
