//! The region tracker behind the `head` preset: the recommended tracker for real footage.
//!
//! A particle filter over an axis-aligned ellipse (centre, log-scale, log-aspect). Each
//! hypothesis is weighted by three terms, as Odobez's object likelihood p_o (Eq. 18, "shape or
//! colour") allows:
//! - **colour contrast**: each pixel's log-ratio ln(p_target / p_background) of its HSV bin
//!   (Pérez et al. 2002's bins; grey levels for grey footage), summed inside the ellipse as the
//!   pixel-wise posteriors of Bibby & Reid 2008 (a hypothesis grows while the pixels it takes in
//!   look more like the target than the background, and no further), less the mean of the
//!   positive log-ratios in the ring out to [`RegionSettings::contrast_ring`] times the ellipse
//!   (target-like pixels just outside say the hypothesis is too small or off-centre). The
//!   background model is the ring around the estimate, learnt from locked frames and half
//!   anchored to the first frame's;
//! - **template**: the normalised cross-correlation (Odobez Eq. 23) of the grey patch under the
//!   hypothesis with the target's template (first frame's, half anchored, half learnt);
//! - **contour**: the contrast across the ellipse along its normals (Birchfield 1998's
//!   perimeter gradient), in units of the window's mean gradient.
//!
//! The filter tracks the region the colours support, found once at the first frame by scaling
//! the annotation (`calibration`), and reports every estimate mapped back to the annotation's
//! convention. Every frame is read in a window around the target at the scale that maps the target to a
//! fixed working size ([`RegionSettings::working_size`]), so the cost does not depend on the
//! target's or the frame's size in pixels. The product is tempered so that the effective sample
//! size never falls below a set fraction of N. A two-state chain on the estimate's colour
//! similarity (`status`) says whether the target is still held. Every frame a share of the
//! particles is drawn around the centre of best colour contrast found by a dense search of the
//! window; while P(lost) is high that share grows and the window is the whole frame.

mod settings;
pub(crate) mod status;
mod tracker;

pub use settings::RegionSettings;
pub use tracker::RegionTracker;
