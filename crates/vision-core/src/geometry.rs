//! Ellipses and axis-aligned boxes in image coordinates (x to the right, y down, pixels).

use serde::{Deserialize, Serialize};

/// An ellipse (cx, cy, a, b, angle): semi-axis `a` along (cos θ, sin θ), `b` along (−sin θ, cos θ),
/// θ = `angle` in radians. It is the unit circle under the affine map A = R(θ)·diag(a, b),
/// t = (cx, cy).
///
/// Serialised with the field `angle`; `theta` is accepted when reading.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Ellipse {
    /// Centre x (px).
    pub cx: f64,
    /// Centre y (px).
    pub cy: f64,
    /// Semi-axis along (cos θ, sin θ) (px).
    pub a: f64,
    /// Semi-axis along (−sin θ, cos θ) (px).
    pub b: f64,
    /// Orientation θ of the `a` axis from the x axis, radians.
    #[serde(alias = "theta")]
    pub angle: f64,
}

impl Ellipse {
    /// The mean absolute difference across the contour: at `points` points evenly spaced in
    /// the ellipse's parameter, the value `offset` pixels outside the contour along its normal
    /// against the value `offset` pixels inside, read by `sample` (`None` where there is nothing
    /// to read, as outside an image). Returns the mean over the points read and their number
    /// (0 and 0 when none is). Birchfield 1998's perimeter gradient, without its normalisation.
    ///
    /// # Examples
    /// ```
    /// use vision_core::Ellipse;
    /// // A disc of value 1 on 0: a contrast of 1 everywhere on its contour.
    /// let e = Ellipse::new(0.0, 0.0, 10.0, 6.0, 0.3);
    /// let inside = |x: f64, y: f64| {
    ///     let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    ///     let (u, v) = ((c * x + s * y) / 10.0, (-s * x + c * y) / 6.0);
    ///     Some(if u * u + v * v <= 1.0 { 1.0 } else { 0.0 })
    /// };
    /// let (mean, n) = e.contrast_across(32, 1.0, inside);
    /// assert_eq!(n, 32);
    /// assert!((mean - 1.0).abs() < 1e-12);
    /// ```
    pub fn contrast_across(
        &self,
        points: usize,
        offset: f64,
        sample: impl Fn(f64, f64) -> Option<f64>,
    ) -> (f64, usize) {
        let (c, s) = (self.angle.cos(), self.angle.sin());
        let (mut sum, mut n) = (0.0, 0);
        for k in 0..points {
            let t = std::f64::consts::TAU * k as f64 / points as f64;
            let (u, v) = (self.a * t.cos(), self.b * t.sin());
            let (px, py) = (self.cx + c * u - s * v, self.cy + s * u + c * v);
            // The normal of the ellipse at t, in image coordinates.
            let (nu, nv) = (self.b * t.cos(), self.a * t.sin());
            let norm = (nu * nu + nv * nv).sqrt().max(1e-12);
            let (nx, ny) = ((c * nu - s * nv) / norm, (s * nu + c * nv) / norm);
            if let (Some(inner), Some(outer)) = (
                sample(px - offset * nx, py - offset * ny),
                sample(px + offset * nx, py + offset * ny),
            ) {
                sum += (inner - outer).abs();
                n += 1;
            }
        }
        (if n > 0 { sum / n as f64 } else { 0.0 }, n)
    }

    /// An ellipse from its five parameters.
    pub fn new(cx: f64, cy: f64, a: f64, b: f64, angle: f64) -> Self {
        Self {
            cx,
            cy,
            a,
            b,
            angle,
        }
    }

    /// Whether all five numbers are finite.
    pub fn is_finite(&self) -> bool {
        self.cx.is_finite()
            && self.cy.is_finite()
            && self.a.is_finite()
            && self.b.is_finite()
            && self.angle.is_finite()
    }

    /// Half-widths of the axis-aligned bounding box of the rotated ellipse:
    /// `sqrt(a²cos²θ + b²sin²θ)` and `sqrt(a²sin²θ + b²cos²θ)`.
    pub fn half_extents(&self) -> (f64, f64) {
        let (sn, cs) = self.angle.sin_cos();
        let hw = ((self.a * cs).powi(2) + (self.b * sn).powi(2)).sqrt();
        let hh = ((self.a * sn).powi(2) + (self.b * cs).powi(2)).sqrt();
        (hw, hh)
    }

    /// The axis-aligned bounding box of the rotated ellipse (the tracker's box, docs/MODELS.md).
    pub fn bounding_box(&self) -> BoundingBox {
        let (hw, hh) = self.half_extents();
        BoundingBox::new(self.cx - hw, self.cy - hh, 2.0 * hw, 2.0 * hh)
    }

    /// Area π·a·b (px²).
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * self.a * self.b
    }

    /// The point at parameter `t` (radians): centre + a·cos t·(cos θ, sin θ) + b·sin t·(−sin θ, cos θ).
    pub fn point(&self, t: f64) -> (f64, f64) {
        let (s, c) = self.angle.sin_cos();
        let (u, v) = (self.a * t.cos(), self.b * t.sin());
        (self.cx + u * c - v * s, self.cy + u * s + v * c)
    }

    /// Reference coordinates (u, v) of an image point: r = A⁻¹ (p − t).
    pub fn to_reference(&self, x: f64, y: f64) -> (f64, f64) {
        let (sn, cs) = self.angle.sin_cos();
        let dx = x - self.cx;
        let dy = y - self.cy;
        ((cs * dx + sn * dy) / self.a, (-sn * dx + cs * dy) / self.b)
    }

    /// Approximate signed distance (px) from an image point to the outline, negative inside.
    ///
    /// First-order: (ρ − 1)/|∇ρ| with ρ the normalised radius; exact on circles and accurate
    /// to well below 0.1 px within a pixel of the outline for head-sized ellipses.
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        let (u, v) = self.to_reference(x, y);
        let rho = u.hypot(v);
        if rho < 1e-9 {
            return -self.a.min(self.b);
        }
        let g = ((u / self.a).powi(2) + (v / self.b).powi(2)).sqrt() / rho;
        (rho - 1.0) / g
    }
}

/// An axis-aligned box: top-left corner `(x, y)`, width `w` and height `h`, in pixels (the OTB
/// ground-truth form).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct BoundingBox {
    /// Left edge x (px).
    pub x: f64,
    /// Top edge y (px).
    pub y: f64,
    /// Width (px).
    pub w: f64,
    /// Height (px).
    pub h: f64,
}

impl BoundingBox {
    /// A box from its top-left corner and size.
    pub fn new(x: f64, y: f64, w: f64, h: f64) -> Self {
        Self { x, y, w, h }
    }

    /// A box from its smallest and largest corners `(x_min, y_min)`, `(x_max, y_max)`.
    pub fn from_corners(x_min: f64, y_min: f64, x_max: f64, y_max: f64) -> Self {
        Self::new(x_min, y_min, x_max - x_min, y_max - y_min)
    }

    /// The smallest corner `(x, y)`.
    pub fn min_corner(&self) -> (f64, f64) {
        (self.x, self.y)
    }

    /// The largest corner `(x + w, y + h)`.
    pub fn max_corner(&self) -> (f64, f64) {
        (self.x + self.w, self.y + self.h)
    }

    /// `[x, y, w, h]`, the order of OTB ground-truth files.
    pub fn to_array(&self) -> [f64; 4] {
        [self.x, self.y, self.w, self.h]
    }

    /// `x,y,w,h` written compactly for messages ([`fmt_num`]): `1e300`, never 301 digits.
    pub fn shown(&self) -> String {
        [self.x, self.y, self.w, self.h].map(fmt_num).join(",")
    }

    /// Checks that the box can start a tracker in a `width`×`height` frame: finite, of positive
    /// width and height, with its centre inside the frame (it may stick out of the frame partly,
    /// as real targets near the border do). The one check of the command line and the Python
    /// package, so that both say the same, in one short line.
    ///
    /// # Errors
    /// [`Error::StartBox`](crate::Error::StartBox) naming the box ([`BoundingBox::shown`]) and
    /// the frame size.
    ///
    /// # Examples
    /// ```
    /// use vision_core::BoundingBox;
    /// let e = BoundingBox::new(100.0, 100.0, 1e300, 1e300).check_start(640, 480).unwrap_err();
    /// assert!(e.to_string().len() < 120, "{e}");
    /// assert!(BoundingBox::new(10.0, 10.0, 20.0, 20.0).check_start(640, 480).is_ok());
    /// ```
    pub fn check_start(&self, width: usize, height: usize) -> crate::Result<()> {
        let shown = self.shown();
        let reason = if !self.is_finite() {
            format!("box {shown} is not finite")
        } else if self.w <= 0.0 || self.h <= 0.0 {
            format!("box {shown} has zero or negative size")
        } else {
            let (cx, cy) = self.centre();
            if cx >= 0.0 && cy >= 0.0 && cx < width as f64 && cy < height as f64 {
                return Ok(());
            }
            format!("box {shown} lies outside the {width}×{height} frame (its centre is outside)")
        };
        Err(crate::Error::StartBox { reason })
    }

    /// The centre `(x + w/2, y + h/2)`.
    pub fn centre(&self) -> (f64, f64) {
        (self.x + 0.5 * self.w, self.y + 0.5 * self.h)
    }

    /// The area `w·h` (zero for a degenerate box).
    pub fn area(&self) -> f64 {
        self.w.max(0.0) * self.h.max(0.0)
    }

    /// Whether all four numbers are finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.w.is_finite() && self.h.is_finite()
    }

    /// Intersection over union with `other`, in [0, 1]; 0 when the union is empty.
    pub fn iou(&self, other: &BoundingBox) -> f64 {
        let ix = (self.x + self.w).min(other.x + other.w) - self.x.max(other.x);
        let iy = (self.y + self.h).min(other.y + other.h) - self.y.max(other.y);
        let inter = ix.max(0.0) * iy.max(0.0);
        let union = self.area() + other.area() - inter;
        if union > 0.0 { inter / union } else { 0.0 }
    }

    /// Euclidean distance between the two centres, in pixels.
    pub fn centre_distance(&self, other: &BoundingBox) -> f64 {
        let (ax, ay) = self.centre();
        let (bx, by) = other.centre();
        (ax - bx).hypot(ay - by)
    }

    /// The ellipse inscribed in the box: centre at the box centre, semi-axes `a = w/2`
    /// (horizontal) and `b = h/2`, angle 0.
    pub fn inscribed_ellipse(&self) -> Ellipse {
        let (cx, cy) = self.centre();
        Ellipse::new(cx, cy, 0.5 * self.w, 0.5 * self.h, 0.0)
    }
}

/// A number for a message: as typed for ordinary values (`12.5`), in scientific notation when
/// very large or very small (`1e300`, not 301 digits), so that an error stays one short line.
pub fn fmt_num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn iou_of_boxes_worked_by_hand() {
        let a = BoundingBox::new(0.0, 0.0, 4.0, 4.0);
        // Identical boxes: 1. Disjoint or only touching: 0.
        assert_eq!(a.iou(&a), 1.0);
        assert_eq!(a.iou(&BoundingBox::new(10.0, 0.0, 4.0, 4.0)), 0.0);
        assert_eq!(a.iou(&BoundingBox::new(4.0, 0.0, 4.0, 4.0)), 0.0);
        // Shifted by 2 in x: intersection 2×4 = 8, union 16 + 16 − 8 = 24.
        let b = BoundingBox::new(2.0, 0.0, 4.0, 4.0);
        assert_relative_eq!(a.iou(&b), 8.0 / 24.0, epsilon = 1e-15);
        assert_relative_eq!(b.iou(&a), a.iou(&b), epsilon = 1e-15);
        // A 2×2 box inside: 4 / 16.
        let c = BoundingBox::new(1.0, 1.0, 2.0, 2.0);
        assert_relative_eq!(a.iou(&c), 0.25, epsilon = 1e-15);
        // Shifted diagonally by (1, 1): 3·3 = 9 over 16 + 16 − 9 = 23.
        let d = BoundingBox::new(1.0, 1.0, 4.0, 4.0);
        assert_relative_eq!(a.iou(&d), 9.0 / 23.0, epsilon = 1e-15);
        // Degenerate boxes have no area and an empty union gives 0, not NaN.
        let z = BoundingBox::default();
        assert_eq!(z.iou(&z), 0.0);
        assert_eq!(a.iou(&z), 0.0);
    }

    #[test]
    fn box_corners_centres_and_distances() {
        let b = BoundingBox::from_corners(1.0, 2.0, 5.0, 10.0);
        assert_eq!(b, BoundingBox::new(1.0, 2.0, 4.0, 8.0));
        assert_eq!(b.min_corner(), (1.0, 2.0));
        assert_eq!(b.max_corner(), (5.0, 10.0));
        assert_eq!(b.centre(), (3.0, 6.0));
        assert_eq!(b.area(), 32.0);
        assert_eq!(b.to_array(), [1.0, 2.0, 4.0, 8.0]);
        let other = BoundingBox::new(4.0, 6.0, 4.0, 8.0);
        assert_relative_eq!(b.centre_distance(&other), 5.0, epsilon = 1e-15);
        assert_eq!(BoundingBox::new(0.0, 0.0, -1.0, 3.0).area(), 0.0);
        assert!(!BoundingBox::new(f64::NAN, 0.0, 1.0, 1.0).is_finite());
        let e = b.inscribed_ellipse();
        assert_eq!(e, Ellipse::new(3.0, 6.0, 2.0, 4.0, 0.0));
        assert_eq!(e.bounding_box(), b);
    }

    #[test]
    fn ellipse_box_and_contour_points() {
        let e = Ellipse::new(50.0, 40.0, 25.0, 32.0, 0.4);
        // A quarter turn swaps the half-extents.
        let q = Ellipse::new(0.0, 0.0, 30.0, 20.0, std::f64::consts::FRAC_PI_2);
        let (hw, hh) = q.half_extents();
        assert_relative_eq!(hw, 20.0, epsilon = 1e-12);
        assert_relative_eq!(hh, 30.0, epsilon = 1e-12);
        for k in 0..16 {
            let (x, y) = e.point(k as f64 * 0.39);
            assert_relative_eq!(e.signed_distance(x, y), 0.0, epsilon = 1e-9);
            let bb = e.bounding_box();
            assert!(x >= bb.x - 1e-9 && x <= bb.x + bb.w + 1e-9);
            assert!(y >= bb.y - 1e-9 && y <= bb.y + bb.h + 1e-9);
        }
        assert_relative_eq!(e.area(), std::f64::consts::PI * 800.0, epsilon = 1e-9);
        assert!(e.is_finite() && !Ellipse::new(0.0, 0.0, 1.0, 1.0, f64::NAN).is_finite());
    }

    #[test]
    fn ellipses_are_written_with_angle_and_read_with_theta_too() {
        let e = Ellipse::new(1.0, 2.0, 3.0, 4.0, 0.5);
        let text = serde_json::to_string(&e).unwrap();
        assert_eq!(text, r#"{"cx":1.0,"cy":2.0,"a":3.0,"b":4.0,"angle":0.5}"#);
        let old: Ellipse =
            serde_json::from_str(r#"{"cx":1.0,"cy":2.0,"a":3.0,"b":4.0,"theta":0.5}"#).unwrap();
        assert_eq!(old, e);
        let b = BoundingBox::new(1.0, 2.0, 3.0, 4.0);
        assert_eq!(
            serde_json::to_string(&b).unwrap(),
            r#"{"x":1.0,"y":2.0,"w":3.0,"h":4.0}"#
        );
    }
}
