//! Occlusion between two motions found in one region: which one is behind, and the
//! pixels it loses to the one in front.
//!
//! When a surface moves over another inside the region, the pixels of the surface behind that the
//! one in front covers in the second frame fit no motion: the surface in front explains all its
//! pixels, the one behind only those that stay visible. Counted by the pixels they explain, the
//! surface in front can then win although the one behind holds more of the region's first-frame
//! pixels. Each side could claim the unexplained pixels: the motion behind fails on them because
//! their destination lies under the surface in front in the second frame; but the reverse reading
//! (the other surface is behind, seen through a hole of this one that moves with it) explains the
//! same two frames. Two frames alone cannot tell an object moving over a background from a
//! background moving behind a window.
//!
//! The order is therefore taken from the surroundings, as in figure–ground assignment: a surface
//! whose motion is that of most of the pixels around the region (its box grown by the pyramid
//! margin) while the other's is not encloses the other, and is taken to be behind it. It is then
//! credited with the region's pixels that neither motion explains, whose destination under its
//! own motion lies under the other's second-frame footprint (the second-frame positions of the
//! pixels the other explains), and beyond which, one relative displacement further on, it is
//! visible again: the band that the leading edge of the surface in front sweeps (see
//! [`hidden`]). When neither or both motions explain the surroundings, no order is assumed and
//! nothing is credited.

use crate::region::PixelBox;

/// How far from a motion boundary the pre-smoothed, interpolated images mix the two surfaces, in
/// pixels: the radius of the [1 4 6 4 1] kernel (2) and the reach of the cubic interpolation (1).
/// Neither motion explains the pixels within it on either side of an edge of the surface in
/// front, in either frame.
const REACH: f64 = 3.0;

/// What a motion does at the pixels of the context box (the region's box grown by the margin).
#[derive(Debug, Clone, Default)]
pub(crate) struct Labels {
    /// The context box, level-0 pixels (inclusive).
    pub(crate) b: Option<PixelBox>,
    /// Per pixel of the box, row-major: [`UNUSED`], [`FAILS`] or [`EXPLAINS`].
    pub(crate) label: Vec<u8>,
}

/// The pixel was not evaluated (outside the first frame's window) or its sample fell outside the
/// second frame's.
pub(crate) const UNUSED: u8 = 0;
/// The motion's displaced frame difference is beyond the comparison threshold.
pub(crate) const FAILS: u8 = 1;
/// The motion explains the pixel (DFD within the threshold).
pub(crate) const EXPLAINS: u8 = 2;

impl Labels {
    fn width(&self) -> usize {
        self.b.map_or(0, |b| b.i1 + 1 - b.i0)
    }

    fn at(&self, x: i64, y: i64) -> u8 {
        let Some(b) = self.b else { return UNUSED };
        if x < b.i0 as i64 || y < b.j0 as i64 || x > b.i1 as i64 || y > b.j1 as i64 {
            return UNUSED;
        }
        self.label[(y as usize - b.j0) * self.width() + (x as usize - b.i0)]
    }
}

/// An affine displacement d(r) = t + A (r − o) in image pixels: `a` = [a1..a6] of Odobez Eq. 13
/// (d = (a1 + a2·x + a3·y, a4 + a5·x + a6·y) with x, y relative to `o`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Motion {
    pub(crate) a: [f64; 6],
    pub(crate) o: [f64; 2],
}

impl Motion {
    /// r + d(r).
    fn forward(&self, x: f64, y: f64) -> [f64; 2] {
        let (dx, dy) = (x - self.o[0], y - self.o[1]);
        let a = &self.a;
        [
            x + a[0] + a[1] * dx + a[2] * dy,
            y + a[3] + a[4] * dx + a[5] * dy,
        ]
    }

    /// The point r with r + d(r) = q, `None` when the motion folds the plane.
    fn inverse(&self, q: [f64; 2]) -> Option<[f64; 2]> {
        let a = &self.a;
        let (m11, m12, m21, m22) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let det = m11 * m22 - m12 * m21;
        // Also rejects a NaN determinant.
        if det.is_nan() || det.abs() <= 1e-6 {
            return None;
        }
        let (bx, by) = (q[0] - self.o[0] - a[0], q[1] - self.o[1] - a[3]);
        Some([
            self.o[0] + (m22 * bx - m12 * by) / det,
            self.o[1] + (-m21 * bx + m11 * by) / det,
        ])
    }
}

/// Whether the motion labelled `x` is that of the surroundings and the one labelled `y` is not:
/// among the context box's pixels outside the region (`weight` 0) that both motions keep inside
/// the images, `x` explains at least half and `y` less than half.
pub(crate) fn surrounds(x: &Labels, y: &Labels, weight: &[f32]) -> bool {
    let (mut n, mut nx, mut ny) = (0usize, 0usize, 0usize);
    for ((&w, &lx), &ly) in weight.iter().zip(&x.label).zip(&y.label) {
        if w > 0.0 || lx == UNUSED || ly == UNUSED {
            continue;
        }
        n += 1;
        nx += usize::from(lx == EXPLAINS);
        ny += usize::from(ly == EXPLAINS);
    }
    n > 0 && 2 * nx >= n && 2 * ny < n
}

/// The weight of the region's pixels (`weight` > 0) that `x` fails on and `y` does not explain,
/// that the surface moving by `my` covers in the second frame, taken from the surface moving by
/// `mx`. A pixel r is covered when its destination under `mx` lies under `y`'s second-frame
/// footprint: the point p of the first frame that `my` carries there rounds to a pixel `y`
/// explains. It was swept by the front surface's leading edge when `x` is visible again one
/// relative displacement further on: the point r + (r − p), pushed [`REACH`] pixels further
/// (the band that smoothing and interpolation blur at the edge of the front surface's footprint
/// in the second frame), rounds to a pixel `x` explains. The covered pixels form a band as wide
/// as the relative displacement along the front surface's leading edge; a pixel that `y` fails
/// on inside its own surface (noise, a part that does not move rigidly) has more of `y` beyond
/// it, and one with no relative displacement is not covered.
pub(crate) fn hidden(x: &Labels, mx: &Motion, y: &Labels, my: &Motion, weight: &[f32]) -> f64 {
    let Some(b) = x.b else { return 0.0 };
    if y.b != x.b {
        return 0.0;
    }
    let w = x.width();
    let mut total = 0.0;
    for (k, (&lx, &ly)) in x.label.iter().zip(&y.label).enumerate() {
        let m = weight[k];
        if m <= 0.0 || lx != FAILS || ly == EXPLAINS {
            continue;
        }
        let (px, py) = ((b.i0 + k % w) as f64, (b.j0 + k / w) as f64);
        let Some(p) = my.inverse(mx.forward(px, py)) else {
            continue;
        };
        // The relative displacement, from the pixel of `y` that lands on this one's destination
        // to this one.
        let (rx, ry) = (px - p[0], py - p[1]);
        let len = rx.hypot(ry);
        if len.is_nan() || len <= 0.5 {
            continue;
        }
        let f = 1.0 + REACH / len;
        let beyond = [px + f * rx, py + f * ry];
        if y.at(p[0].round() as i64, p[1].round() as i64) == EXPLAINS
            && x.at(beyond[0].round() as i64, beyond[1].round() as i64) == EXPLAINS
        {
            total += f64::from(m);
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Labels of a 1-pixel-high strip of `n` pixels from x = 0.
    fn strip(s: &str) -> Labels {
        let label = s
            .bytes()
            .map(|c| match c {
                b'x' => EXPLAINS,
                b'.' => FAILS,
                _ => UNUSED,
            })
            .collect::<Vec<_>>();
        Labels {
            b: Some(PixelBox {
                i0: 0,
                j0: 0,
                i1: label.len() - 1,
                j1: 0,
            }),
            label,
        }
    }

    fn shift(t: f64) -> Motion {
        Motion {
            a: [t, 0.0, 0.0, 0.0, 0.0, 0.0],
            o: [0.0, 0.0],
        }
    }

    #[test]
    fn the_covered_pixels_go_to_the_surface_behind() {
        // A background at rest and a block of pixels 6–15 moving by +4 (second frame: 10–19).
        // The background pixels 16–19 are covered in the second frame, and the background's
        // pixels 6–9 are uncovered: neither motion explains 16–19, and the background fails on
        // 6–15 too. The background's destinations of 16–19 lie under the block's footprint and
        // the background is visible beyond them: they are the background's.
        let bg = strip("xxxxxx..............xxxxxxxxxxxxxxxxxxxx");
        let block = strip("......xxxxxxxxxx........................");
        let weight = vec![1.0f32; 40];
        assert_eq!(hidden(&bg, &shift(0.0), &block, &shift(4.0), &weight), 4.0);
        // Read the other way (the background in front, the block seen through a hole of it),
        // the block's destinations of 16–19 (20–23) lie under the background's footprint, with
        // the block beyond: two frames alone credit both, hence the order from the surroundings.
        assert_eq!(hidden(&block, &shift(4.0), &bg, &shift(0.0), &weight), 4.0);
        // The surroundings: pixels 0–1 and 38–39 lie outside the region.
        let mut region = vec![1.0f32; 40];
        for k in [0, 1, 38, 39] {
            region[k] = 0.0;
        }
        assert!(surrounds(&bg, &block, &region));
        assert!(!surrounds(&block, &bg, &region));
        // A region with no surroundings gives no order.
        assert!(!surrounds(&bg, &block, &weight));
    }

    #[test]
    fn the_front_surface_own_failures_are_not_covered_pixels() {
        // The block (pixels 6–21) moves by +2 and its own motion fails on its pixel 12 (a part
        // that does not move with it). The background's destination of pixel 12 lies under the
        // block's footprint, but further on is the block again: only the band 22–23 that the
        // block's leading edge sweeps is the background's.
        let bg = strip("xxxxxx..................xxxxxxxxxxxxxxxx");
        let block = strip("......xxxxxx.xxxxxxxxx..................");
        let weight = vec![1.0f32; 40];
        assert_eq!(hidden(&bg, &shift(0.0), &block, &shift(2.0), &weight), 2.0);
        // No relative displacement, no covered pixel.
        assert_eq!(hidden(&bg, &shift(0.0), &block, &shift(0.0), &weight), 0.0);
    }
}
