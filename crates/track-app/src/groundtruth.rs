//! Target boxes and ellipses, and the OTB ground-truth file `groundtruth_rect.txt`.
//!
//! The OTB layout (docs/MODELS.md, "Evaluation protocol") has one line per frame, `x,y,w,h` of the
//! target's axis-aligned box (top-left corner, width, height, in pixels), separated by commas, tabs
//! or spaces. Some sequences label only every k-th frame and write `0,0,0,0` (or `NaN,NaN,NaN,NaN`)
//! elsewhere; those frames are unlabelled ([`None`]) and left out of every metric.

use std::path::Path;

use vision_core::{BoundingBox, Ellipse};

use crate::{AppError, Result};

/// The command line's checks of a box against a frame, and its compact form for messages.
pub trait BoxInFrame {
    /// Checks that the box can start a tracker in a `width`×`height` frame: finite, of positive
    /// width and height, and with its centre inside the frame (a box may stick out of the frame
    /// partly, as real targets near the border do, but not lie outside it). `what` names the box in
    /// the error (for example `--init`).
    ///
    /// # Errors
    /// [`AppError::InvalidSetting`] naming `what`, the box and the frame size.
    fn validate_in_frame(&self, width: usize, height: usize, what: &str) -> Result<()>;

    /// The check of [`BoxInFrame::validate_in_frame`], returning what is wrong as text, so that
    /// the caller can say whose box it is (an option, or a line of a ground-truth file).
    ///
    /// # Errors
    /// The reason, with the box written compactly ([`fmt_num`]) and the frame size.
    fn check_in_frame(&self, width: usize, height: usize) -> std::result::Result<(), String>;

    /// `x,y,w,h` written compactly for messages ([`fmt_num`]).
    fn shown(&self) -> String;
}

impl BoxInFrame for BoundingBox {
    fn validate_in_frame(&self, width: usize, height: usize, what: &str) -> Result<()> {
        self.check_in_frame(width, height)
            .map_err(|reason| AppError::setting(what, reason))
    }

    fn check_in_frame(&self, width: usize, height: usize) -> std::result::Result<(), String> {
        // The one check, shared with the Python package (vision-core).
        self.check_start(width, height).map_err(|e| e.to_string())
    }

    fn shown(&self) -> String {
        BoundingBox::shown(self)
    }
}

/// A number for a message (vision-core's, shared with the Python package).
pub use vision_core::fmt_num;

/// Parses `N` comma-separated finite numbers from a command-line value.
fn parse_numbers<const N: usize>(text: &str, name: &str, form: &str) -> Result<[f64; N]> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if fields.len() != N {
        return Err(AppError::setting(
            name,
            format!("{text:?} should be {N} comma-separated numbers {form}"),
        ));
    }
    let mut out = [0.0; N];
    for (slot, f) in out.iter_mut().zip(&fields) {
        *slot = f
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| AppError::setting(name, format!("{f:?} is not a finite number")))?;
    }
    Ok(out)
}

/// Parses a box given on the command line as `x,y,w,h` (for `--init`). The size is checked
/// against the frame later, by [`BoxInFrame::validate_in_frame`].
///
/// # Errors
/// [`AppError::InvalidSetting`] naming `name` (the option): wrong count or a non-finite number.
pub fn parse_box_arg(text: &str, name: &str) -> Result<BoundingBox> {
    let [x, y, w, h] = parse_numbers(text, name, "x,y,w,h")?;
    Ok(BoundingBox::new(x, y, w, h))
}

/// Parses an ellipse given on the command line as `cx,cy,a,b,angle` (for `--init-ellipse`); the
/// angle is taken as given (the caller decides its unit). Semi-axes must be positive.
///
/// # Errors
/// [`AppError::InvalidSetting`] naming `name`: wrong count, a non-finite number, or a semi-axis
/// that is not positive.
pub fn parse_ellipse_arg(text: &str, name: &str) -> Result<Ellipse> {
    let [cx, cy, a, b, angle] = parse_numbers(text, name, "cx,cy,a,b,angle")?;
    if a <= 0.0 || b <= 0.0 {
        return Err(AppError::setting(
            name,
            format!("semi-axes must be positive, got a = {a}, b = {b}"),
        ));
    }
    Ok(Ellipse::new(cx, cy, a, b, angle))
}

/// One parsed ground-truth line.
#[derive(Debug, Clone, Copy, PartialEq)]
enum GtLine {
    /// A box of positive size.
    Box(BoundingBox),
    /// `0,0,0,0`: the OTB mark of an unlabelled frame.
    Unlabelled,
    /// Any other box of zero width or height: no target on this frame.
    ZeroSize(BoundingBox),
}

/// Parses one ground-truth line (1-based `line_no` for messages).
fn parse_line(text: &str, line_no: usize) -> std::result::Result<GtLine, String> {
    let fields: Vec<&str> = text
        .split([',', '\t', ' ', ';'])
        .map(str::trim)
        .filter(|f| !f.is_empty())
        .collect();
    if fields.len() != 4 {
        return Err(format!(
            "line {line_no}: expected 4 numbers x,y,w,h, found {} in {:?}",
            fields.len(),
            text.trim()
        ));
    }
    let mut v = [0.0_f64; 4];
    for (slot, field) in v.iter_mut().zip(&fields) {
        *slot = field
            .parse()
            .map_err(|_| format!("line {line_no}: {field:?} is not a number"))?;
    }
    // `NaN,NaN,NaN,NaN`: the other common mark of a frame without a label (UAV123, LaSOT).
    if v.iter().all(|x| x.is_nan()) {
        return Ok(GtLine::Unlabelled);
    }
    for (parsed, field) in v.iter().zip(&fields) {
        if !parsed.is_finite() {
            return Err(format!("line {line_no}: {field:?} is not a finite number"));
        }
    }
    let [x, y, w, h] = v;
    if w < 0.0 || h < 0.0 {
        return Err(format!(
            "line {line_no}: negative width or height in {:?}",
            text.trim()
        ));
    }
    if v == [0.0; 4] {
        return Ok(GtLine::Unlabelled);
    }
    if w == 0.0 || h == 0.0 {
        return Ok(GtLine::ZeroSize(BoundingBox::new(x, y, w, h)));
    }
    Ok(GtLine::Box(BoundingBox::new(x, y, w, h)))
}

/// Parses the text of a ground-truth file: one entry per line, `None` for unlabelled frames.
/// Trailing blank lines are ignored; a blank line before the last box is an error (line i belongs
/// to frame i, so a gap would shift every later label).
///
/// `0,0,0,0` (or a row of `NaN`) marks an unlabelled frame. A box of zero width or height *after* the first labelled
/// box carries no target and is taken as unlabelled too, rather than breaking the evaluation of a
/// whole sequence; *before* it, such a box stands where the tracker would start, so it is an
/// error (taking it as unlabelled would silently start the tracker on a later frame).
///
/// # Errors
/// [`AppError::BadInput`] naming `path` and the 1-based line number: wrong field count, a field
/// that is not a finite number, a negative size, a zero-size box before the first labelled one.
pub fn parse_groundtruth(text: &str, path: &Path) -> Result<Vec<Option<BoundingBox>>> {
    let lines: Vec<&str> = text.lines().collect();
    let last = lines.iter().rposition(|l| !l.trim().is_empty());
    let Some(last) = last else {
        return Err(AppError::input(path, "the ground-truth file has no boxes"));
    };
    let mut labelled = false;
    let mut out = Vec::with_capacity(last + 1);
    for (i, l) in lines[..=last].iter().enumerate() {
        if l.trim().is_empty() {
            return Err(AppError::input(path, format!("line {}: empty line", i + 1)));
        }
        let entry = match parse_line(l, i + 1).map_err(|reason| AppError::input(path, reason))? {
            GtLine::Box(b) => {
                labelled = true;
                Some(b)
            }
            GtLine::Unlabelled => None,
            GtLine::ZeroSize(b) if !labelled => {
                return Err(AppError::input(
                    path,
                    format!(
                        "line {}: the first box {} has zero width or height, so it cannot start \
                         the tracker (only 0,0,0,0 marks an unlabelled frame)",
                        i + 1,
                        b.shown()
                    ),
                ));
            }
            GtLine::ZeroSize(_) => None,
        };
        out.push(entry);
    }
    Ok(out)
}

/// Reads and parses a ground-truth file (see [`parse_groundtruth`]).
///
/// # Errors
/// [`AppError::BadInput`] when the file cannot be read or a line is malformed.
pub fn load_groundtruth(path: &Path) -> Result<Vec<Option<BoundingBox>>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| AppError::input(path, format!("cannot read ground truth: {e}")))?;
    parse_groundtruth(&text, path)
}

/// Checks that the ground truth covers exactly `frames` frames and has at least one labelled box.
///
/// # Errors
/// [`AppError::BadInput`] naming `path` and both counts.
pub fn check_groundtruth_len(
    truth: &[Option<BoundingBox>],
    frames: usize,
    path: &Path,
) -> Result<()> {
    if truth.len() != frames {
        return Err(AppError::input(
            path,
            format!("{} ground-truth lines for {frames} frames", truth.len()),
        ));
    }
    if truth.iter().all(Option::is_none) {
        return Err(AppError::input(
            path,
            "no labelled box (every line is 0,0,0,0)",
        ));
    }
    Ok(())
}

/// The first labelled frame and its box, if any.
pub fn first_labelled(truth: &[Option<BoundingBox>]) -> Option<(usize, BoundingBox)> {
    truth
        .iter()
        .enumerate()
        .find_map(|(i, b)| b.map(|b| (i, b)))
}

/// The first labelled frame and its box, checked against the `width`×`height` frames of the
/// sequence `sequence`: the box the tracker starts from.
///
/// # Errors
/// [`AppError::BadInput`] (exit 3: the ground truth is input data) naming the file, the line,
/// the sequence and what is wrong: no labelled box, or a first box that is not finite, has no
/// area or lies outside the frame.
pub fn first_box_in_frame(
    truth: &[Option<BoundingBox>],
    path: &Path,
    sequence: &str,
    width: usize,
    height: usize,
) -> Result<(usize, BoundingBox)> {
    let (k, b) = first_labelled(truth)
        .ok_or_else(|| AppError::input(path, "no labelled box (every line is 0,0,0,0)"))?;
    b.check_in_frame(width, height).map_err(|reason| {
        AppError::input(
            path,
            format!(
                "line {}: the first labelled box cannot start the tracker on sequence {sequence}: \
                 {reason}",
                k + 1
            ),
        )
    })?;
    Ok((k, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn p() -> &'static Path {
        Path::new("gt.txt")
    }

    #[test]
    fn parses_all_separators_and_unlabelled_frames() {
        let text =
            "128,46,104,127\n0,0,0,0\n1\t2\t3\t4\n5 6  7 8\n9, 10, 11, 12\nNaN,NaN,NaN,NaN\n\n\n";
        let gt = parse_groundtruth(text, p()).unwrap();
        assert_eq!(gt.len(), 6);
        assert_eq!(gt[5], None, "a row of NaN is unlabelled");
        assert_eq!(gt[0], Some(BoundingBox::new(128.0, 46.0, 104.0, 127.0)));
        assert_eq!(gt[1], None);
        assert_eq!(gt[2], Some(BoundingBox::new(1.0, 2.0, 3.0, 4.0)));
        assert_eq!(gt[3], Some(BoundingBox::new(5.0, 6.0, 7.0, 8.0)));
        assert_eq!(gt[4], Some(BoundingBox::new(9.0, 10.0, 11.0, 12.0)));
        assert_eq!(
            first_labelled(&gt),
            Some((0, BoundingBox::new(128.0, 46.0, 104.0, 127.0)))
        );
    }

    #[test]
    fn malformed_lines_name_the_line() {
        let cases = [
            ("1,2,3,4\n1,2,3\n", "line 2", "expected 4 numbers"),
            ("1,2,3,4,5\n", "line 1", "found 5"),
            ("1,2,3,4\n1,2,NaN,4\n", "line 2", "not a finite number"),
            ("1,2,x,4\n", "line 1", "not a number"),
            ("1,2,-3,4\n", "line 1", "negative"),
            ("1,2,3,4\n\n1,2,3,4\n", "line 2", "empty line"),
        ];
        for (text, line, what) in cases {
            let err = parse_groundtruth(text, p()).unwrap_err();
            let msg = err.to_string();
            assert!(msg.starts_with("gt.txt: "), "{msg}");
            assert!(
                msg.contains(line) && msg.contains(what),
                "{text:?} gave {msg}"
            );
            assert_eq!(err.exit_code(), 3);
        }
        assert!(parse_groundtruth("\n \n", p()).is_err());
    }

    #[test]
    fn length_check_and_all_unlabelled() {
        let gt = vec![Some(BoundingBox::new(0.0, 0.0, 1.0, 1.0)), None];
        assert!(check_groundtruth_len(&gt, 2, p()).is_ok());
        let msg = check_groundtruth_len(&gt, 3, p()).unwrap_err().to_string();
        assert!(msg.contains("2 ground-truth lines for 3 frames"), "{msg}");
        assert!(check_groundtruth_len(&[None, None], 2, p()).is_err());
    }

    #[test]
    fn iou_and_centre_by_hand() {
        let a = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let b = BoundingBox::new(5.0, 0.0, 10.0, 10.0);
        // Intersection 5×10 = 50, union 100 + 100 − 50 = 150.
        assert_relative_eq!(a.iou(&b), 50.0 / 150.0, epsilon = 1e-15);
        assert_relative_eq!(a.iou(&a), 1.0);
        assert_eq!(a.iou(&BoundingBox::new(20.0, 20.0, 1.0, 1.0)), 0.0);
        assert_eq!(a.centre(), (5.0, 5.0));
        assert_relative_eq!(
            a.centre_distance(&BoundingBox::new(3.0, 4.0, 10.0, 10.0)),
            5.0
        );
        // Degenerate boxes have no union: defined as 0, never NaN.
        let z = BoundingBox::new(1.0, 1.0, 0.0, 0.0);
        assert_eq!(z.iou(&z), 0.0);
    }

    #[test]
    fn ellipse_box_round_trip_and_rotation() {
        let b = BoundingBox::new(128.0, 46.0, 104.0, 127.0);
        let e = b.inscribed_ellipse();
        assert_eq!(e, Ellipse::new(180.0, 109.5, 52.0, 63.5, 0.0));
        let back = e.bounding_box();
        assert_relative_eq!(back.x, b.x, epsilon = 1e-12);
        assert_relative_eq!(back.w, b.w, epsilon = 1e-12);
        // Rotating by 90° swaps the extents.
        let r = Ellipse::new(0.0, 0.0, 10.0, 4.0, std::f64::consts::FRAC_PI_2).bounding_box();
        assert_relative_eq!(r.w, 8.0, epsilon = 1e-12);
        assert_relative_eq!(r.h, 20.0, epsilon = 1e-12);
        // At 45° both half-extents are sqrt((100 + 16)/2).
        let d = Ellipse::new(0.0, 0.0, 10.0, 4.0, std::f64::consts::FRAC_PI_4).bounding_box();
        assert_relative_eq!(d.w, 2.0 * 58.0_f64.sqrt(), epsilon = 1e-12);
        // The parametric point at t = 0 is the end of the a axis.
        let (x, y) = Ellipse::new(1.0, 2.0, 10.0, 4.0, std::f64::consts::FRAC_PI_2).point(0.0);
        assert_relative_eq!(x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(y, 12.0, epsilon = 1e-12);
    }

    #[test]
    fn command_line_boxes_and_ellipses() {
        assert_eq!(
            parse_box_arg("1, 2,3.5,4", "--init").unwrap(),
            BoundingBox::new(1.0, 2.0, 3.5, 4.0)
        );
        let e = parse_ellipse_arg("10,20,5,3,0.5", "--init-ellipse").unwrap();
        assert_eq!(e, Ellipse::new(10.0, 20.0, 5.0, 3.0, 0.5));
        for (text, what) in [
            ("1,2,3", "4 comma-separated"),
            ("1,2,x,4", "\"x\""),
            ("1,2,inf,4", "finite"),
        ] {
            let err = parse_box_arg(text, "--init").unwrap_err();
            assert!(
                err.to_string().contains("--init") && err.to_string().contains(what),
                "{err}"
            );
            assert_eq!(err.exit_code(), 2);
        }
        assert!(parse_ellipse_arg("1,2,0,3,0", "--init-ellipse").is_err());
        assert!(parse_ellipse_arg("1,2,3,4", "--init-ellipse").is_err());
    }

    #[test]
    fn validation_against_the_frame() {
        let ok = BoundingBox::new(10.0, 10.0, 20.0, 20.0);
        assert!(ok.validate_in_frame(320, 240, "--init").is_ok());
        // Partly outside is accepted (targets at the border).
        assert!(
            BoundingBox::new(-5.0, -5.0, 20.0, 20.0)
                .validate_in_frame(320, 240, "--init")
                .is_ok()
        );
        for (b, what) in [
            (
                BoundingBox::new(10.0, 10.0, 0.0, 20.0),
                "zero or negative size",
            ),
            (
                BoundingBox::new(10.0, 10.0, 20.0, -1.0),
                "zero or negative size",
            ),
            (
                BoundingBox::new(400.0, 10.0, 20.0, 20.0),
                "outside the 320×240 frame",
            ),
            (BoundingBox::new(10.0, -50.0, 20.0, 20.0), "outside"),
            (BoundingBox::new(f64::NAN, 1.0, 2.0, 2.0), "not finite"),
        ] {
            let err = b.validate_in_frame(320, 240, "--init").unwrap_err();
            let msg = err.to_string();
            assert!(msg.contains("--init") && msg.contains(what), "{msg}");
            assert_eq!(err.exit_code(), 2);
        }
    }
}
