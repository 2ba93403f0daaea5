//! Folders of images (PNG, JPEG, GIF, BMP, WebP, TIFF), and the decoding of one image file
//! that every command shares.

use std::path::{Path, PathBuf};

use vision_core::ToGreyBuffer;

use super::{Frame, FrameSource, Original, SequenceInfo};
use crate::{AppError, Result};

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

/// Sorts frame files in natural order of their names (`2.png` before `10.png`): the order
/// every reader of a folder shares, from vision-core.
pub use vision_core::sort_natural;

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
            // macOS writes its metadata of `0001.jpg` as `._0001.jpg` on foreign disks: not a
            // frame.
            if entry.file_name().to_string_lossy().starts_with("._") {
                continue;
            }
            if !path.is_file() {
                // A name of a frame that is no readable file (a symbolic link to nothing, a
                // folder) is an error, not a gap: skipping it would shift every later frame.
                if is_image_path(&path) {
                    let what = match std::fs::symlink_metadata(&path) {
                        Ok(m) if m.file_type().is_symlink() && !path.exists() => {
                            "a symbolic link to nothing"
                        }
                        Ok(m) if m.is_dir() => "a folder",
                        _ => "not a regular file",
                    };
                    return Err(AppError::input(
                        &path,
                        format!(
                            "named as a frame but {what}; every frame must be a readable image \
                             (remove or fix it)"
                        ),
                    ));
                }
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
        let (original, _) = Self::decode_checked(&path, &mut self.first)?;
        let grey = match &original {
            Original::Rgb(img) => img.to_grey_buffer(),
            Original::Luma(img) => img.to_grey_buffer(),
        };
        let index = self.next;
        self.next += 1;
        Ok(Some(Frame {
            index,
            name: path.display().to_string(),
            grey,
            original,
        }))
    }

    fn validate_all_with(
        &self,
        on_frame: &mut dyn FnMut(usize) -> Result<()>,
    ) -> Result<SequenceInfo> {
        let mut first = None;
        let mut size = (0, 0);
        for (k, path) in self.paths.iter().enumerate() {
            size = Self::decode_checked(path, &mut first)?.1;
            on_frame(k + 1)?;
        }
        Ok(SequenceInfo {
            frames: self.paths.len(),
            width: size.0 as usize,
            height: size.1 as usize,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sequence::tests::write_png;
    use crate::sequence::{open_sequence, read_all, read_every};
    use image::GrayImage;

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
        assert_eq!(frames[0].grey.width(), 4);
        // Pixel (x = 3, y = 2): R = 32, so grey = 0.299·32 (f32 arithmetic, exact to 1e-4).
        assert!((frames[0].grey.get_pixel(3, 2)[0] - 0.299 * 32.0).abs() < 1e-4);
        assert!((frames[1].grey.as_raw()[0] - 0.587 * 255.0).abs() < 1e-3);
        assert_eq!(frames[1].index, 1);
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn read_every_keeps_every_kth_frame_from_the_first_and_counts_them_all() {
        let dir = tempfile::tempdir().unwrap();
        for k in 1..=5u8 {
            write_png(&dir.path().join(format!("{k:04}.png")), 2, 2, |_, _| {
                [10 * k, 0, 0]
            });
        }
        for (step, names) in [
            (1, &["0001", "0002", "0003", "0004", "0005"][..]),
            (2, &["0001", "0003", "0005"][..]),
            (3, &["0001", "0004"][..]),
            (9, &["0001"][..]),
        ] {
            let mut src = ImageFolder::open(dir.path()).unwrap();
            let (frames, read) = read_every(&mut src, step).unwrap();
            assert_eq!(read, 5, "step {step}");
            let kept: Vec<&str> = frames
                .iter()
                .map(|f| {
                    std::path::Path::new(&f.name)
                        .file_stem()
                        .unwrap()
                        .to_str()
                        .unwrap()
                })
                .collect();
            assert_eq!(kept, names, "step {step}");
        }
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
        assert_eq!(f.grey.as_raw(), &vec![7.0, 200.0, 7.0, 200.0]);
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
}
