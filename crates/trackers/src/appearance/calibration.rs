//! The ellipse the colour model fits, against the box the user drew.
//!
//! An annotated box and the region that the colour contrast ([`WorkingWindow::contrast`]) holds
//! best need not coincide: a face box leaves out hair and ears that share the face's colour, a
//! loose box takes in wall. Tracking the annotation's ellipse would let the estimate settle on its
//! own onto the region the colours support, drifting in scale over the first frames while the
//! scale prior pulls it back. Instead the first frame is searched once for the scale of the
//! annotation that the colours support best; the filter tracks that region, and every reported
//! ellipse is scaled back, so the output keeps the user's convention. (Shifting the centre as
//! well was tried: it moved the reported centres off the annotators' and cost precision.)

use vision_core::Ellipse;

use super::window::WorkingWindow;

/// Scale factors of the annotation tried at the first frame.
const SCALES: [f64; 9] = [0.8, 0.85, 0.9, 0.95, 1.0, 1.06, 1.12, 1.18, 1.25];

/// The scale from the annotation's ellipse to the tracked region: the region's half-axes are
/// `scale` times the annotation's, about the same centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// Half-axes of the tracked region over the annotation's.
    pub scale: f64,
}

impl Calibration {
    /// No change: the tracked region is the annotation.
    pub const IDENTITY: Self = Self { scale: 1.0 };

    /// The scale of best contrast (ring `ring`) of the annotation `e` within the searched
    /// range, on a window whose log-ratios have been integrated. Ties keep the annotation.
    pub fn search(window: &WorkingWindow, e: &Ellipse, ring: f64) -> Self {
        let reference = window.area(e);
        let mut best = (Self::IDENTITY, window.contrast(e, ring, reference));
        for scale in SCALES {
            let candidate = Self { scale };
            let c = window.contrast(&candidate.tracked(e), ring, reference);
            if c > best.1 {
                best = (candidate, c);
            }
        }
        best.0
    }

    /// The tracked region of the annotation `e`.
    pub fn tracked(&self, e: &Ellipse) -> Ellipse {
        scaled(e, self.scale)
    }

    /// The annotation-convention ellipse of a tracked region `e` (the inverse of
    /// [`Calibration::tracked`]).
    pub fn reported(&self, e: &Ellipse) -> Ellipse {
        scaled(e, 1.0 / self.scale)
    }
}

/// `e` with its half-axes times `factor`, about the same centre.
fn scaled(e: &Ellipse, factor: f64) -> Ellipse {
    Ellipse {
        a: e.a * factor,
        b: e.b * factor,
        ..*e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reported_inverts_tracked() {
        let e = Ellipse {
            cx: 40.0,
            cy: 30.0,
            a: 12.0,
            b: 15.0,
            angle: 0.0,
        };
        let c = Calibration { scale: 1.18 };
        let back = c.reported(&c.tracked(&e));
        for (x, y) in [
            (back.cx, e.cx),
            (back.cy, e.cy),
            (back.a, e.a),
            (back.b, e.b),
        ] {
            assert!((x - y).abs() < 1e-12, "{back:?} vs {e:?}");
        }
    }
}
