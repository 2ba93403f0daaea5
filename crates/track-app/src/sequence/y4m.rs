//! Y4M (YUV4MPEG2) video from a file, from bytes in memory or from a stream (standard input, or
//! ffmpeg's output for a video file).

use std::fs::File;
use std::io::{BufRead, BufReader, Cursor, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use image::{GrayImage, Luma, RgbImage};
use vision_core::{GreyBuffer, ToGreyBuffer};

use super::{Frame, FrameSource, Original, SequenceInfo};
use crate::{AppError, Result};

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
    /// 4:2:2 (`C422`): chroma planes of ⌈w/2⌉×h, what ffmpeg gives for most camera and ProRes
    /// footage without `-pix_fmt yuv420p`.
    C422,
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
            Y4mColour::C422 => w * h + 2 * w.div_ceil(2) * h,
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
                        "422" => Y4mColour::C422,
                        "444" => Y4mColour::C444,
                        "mono" => Y4mColour::Mono,
                        other => {
                            return Err(AppError::input(
                                name,
                                format!(
                                    "unsupported Y4M colour space {:?} (supported: C420jpeg, C420paldv, C420, C420mpeg2, C422, C444, Cmono; convert with ffmpeg -pix_fmt yuv420p)",
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
/// (full-range BT.601 conversion, chroma upsampled by repetition: `(sub_x, sub_y)` pixels share
/// one chroma sample).
fn convert_frame(header: &Y4mHeader, raw: &[u8]) -> (GreyBuffer, Original) {
    let (w, h) = (header.width, header.height);
    let luma = &raw[..w * h];
    // The luma plane as an 8-bit grey image, through the one conversion to grey levels.
    let grey = image::ImageBuffer::<Luma<u8>, &[u8]>::from_raw(w as u32, h as u32, luma)
        .map(|plane| plane.to_grey_buffer())
        .unwrap_or_else(|| GreyBuffer::new(w as u32, h as u32));
    let (cw, (sub_x, sub_y)) = match header.colour {
        Y4mColour::Mono => {
            let img = GrayImage::from_raw(w as u32, h as u32, luma.to_vec());
            return (
                grey,
                Original::Luma(img.unwrap_or_else(|| GrayImage::new(w as u32, h as u32))),
            );
        }
        Y4mColour::C420 => (w.div_ceil(2), (2, 2)),
        Y4mColour::C422 => (w.div_ceil(2), (2, 1)),
        Y4mColour::C444 => (w, (1, 1)),
    };
    let ch = h.div_ceil(sub_y);
    let (u_plane, v_plane) = raw[w * h..].split_at(cw * ch);
    let mut rgb = RgbImage::new(w as u32, h as u32);
    for (i, px) in rgb.pixels_mut().enumerate() {
        let (x, y) = (i % w, i / w);
        let c = (y / sub_y) * cw + x / sub_x;
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
    (grey, Original::Rgb(rgb))
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
        let (grey, original) = convert_frame(&self.header, &buf);
        self.buf = buf;
        let index = self.next;
        self.next += 1;
        Ok(Some(Frame {
            index,
            name: format!("{}#{}", self.name.display(), index + 1),
            grey,
            original,
        }))
    }

    fn is_stream(&self) -> bool {
        matches!(self.input, Y4mInput::Stream)
    }

    fn validate_all_with(
        &self,
        on_frame: &mut dyn FnMut(usize) -> Result<()>,
    ) -> Result<SequenceInfo> {
        let mut reader = self.input.reader(&self.name)?;
        read_header(&mut reader, &self.name)?;
        let mut buf = Vec::with_capacity(self.header.frame_bytes());
        let mut frames = 0;
        while read_frame_raw(&mut reader, &self.header, frames, &self.name, &mut buf)? {
            frames += 1;
            on_frame(frames)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sequence::{SequenceKind, open_sequence, read_all};

    fn y4m_bytes(header: &str, frames: &[Vec<u8>]) -> Vec<u8> {
        let mut v = format!("{header}\n").into_bytes();
        for f in frames {
            v.extend_from_slice(b"FRAME\n");
            v.extend_from_slice(f);
        }
        v
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
            frames[0].grey.as_raw(),
            &luma.iter().map(|&v| f32::from(v)).collect::<Vec<_>>()
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
            assert_eq!((&a.grey, &a.original), (&b.grey, &b.original));
        }
        assert_eq!(streamed[1].name, "-#2");
    }

    #[test]
    fn y4m_mono_and_444() {
        let bytes = y4m_bytes("YUV4MPEG2 W2 H1 Cmono", &[vec![3, 4]]);
        let mut src = Y4mSource::from_reader(Cursor::new(bytes), Path::new("m.y4m")).unwrap();
        let f = src.next_frame().unwrap().unwrap();
        assert!(matches!(f.original, Original::Luma(_)));
        assert_eq!(f.grey.as_raw(), &vec![3.0, 4.0]);
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
    fn y4m_422_shares_chroma_between_horizontal_neighbours() {
        // 3×2 frame: luma 6 bytes, chroma planes 2×2 each; neutral chroma except U at (1, 1).
        let planes = vec![
            10, 20, 30, 40, 50, 60, 128, 128, 128, 228, 128, 128, 128, 128,
        ];
        let bytes = y4m_bytes("YUV4MPEG2 W3 H2 C422", &[planes]);
        let mut src = Y4mSource::from_reader(Cursor::new(bytes), Path::new("v.y4m")).unwrap();
        let f = src.next_frame().unwrap().unwrap();
        let Original::Rgb(rgb) = &f.original else {
            panic!("4:2:2 is colour")
        };
        // Row 0 has neutral chroma: grey equals luma.
        assert_eq!(rgb.get_pixel(0, 0).0, [10, 10, 10]);
        assert_eq!(rgb.get_pixel(2, 0).0, [30, 30, 30]);
        // Row 1: pixel x = 2 reads chroma sample 1 of its own row (U = 228, blue up).
        assert_eq!(rgb.get_pixel(0, 1).0, [40, 40, 40]);
        assert_eq!(rgb.get_pixel(2, 1).0[2], 237);
        assert_eq!(f.grey.get_pixel(2, 1).0[0], 60.0);
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn y4m_unsupported_colour_space_is_named() {
        for cs in ["C411", "C420p10", "C444alpha"] {
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
