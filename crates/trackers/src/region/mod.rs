//! The region tracker behind the `head` preset: the recommended tracker for real footage.
//!
//! A particle filter over an axis-aligned ellipse (centre, log-scale, log-aspect). Each
//! hypothesis is weighted by three terms, as Odobez's object likelihood p_o (Eq. 18, "shape or
//! colour") allows:
//! - **colour contrast**: the mean, inside the ellipse, of each pixel's log-ratio
//!   ln(p_target / p_background) of its HSV bin (Pérez et al. 2002's bins), less the same mean in
//!   the ring out to [`RegionSettings::contrast_ring`] times the ellipse; too large a hypothesis
//!   dilutes the inside, too small a one puts target pixels in the ring, so the term fixes the
//!   scale as well as the position. The background model is the ring around the estimate, learnt
//!   from locked frames and half anchored to the first frame's;
//! - **template**: the normalised cross-correlation (Odobez Eq. 23) of the grey patch under the
//!   hypothesis with the target's template (first frame's, half anchored, half learnt);
//! - **contour**: the contrast across the ellipse along its normals (Birchfield 1998's
//!   perimeter gradient), in units of the window's mean gradient.
//!
//! Every frame is read in a window around the target at the scale that maps the target to a
//! fixed working size ([`RegionSettings::working_size`]), so the cost does not depend on the
//! target's or the frame's size in pixels. The product is tempered so that the effective sample
//! size never falls below a set fraction of N. A two-state chain on the estimate's colour
//! similarity ([`status`]) says whether the target is still held. Every frame a share of the
//! particles is drawn around the centre of best colour contrast found by a dense search of the
//! window; while P(lost) is high that share grows and the window is the whole frame.

pub mod colour;
pub mod settings;
pub mod status;
pub mod tracker;
pub mod window;

pub use settings::RegionSettings;
pub use tracker::RegionTracker;
