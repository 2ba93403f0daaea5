//! The region tracker behind the `head` preset: the recommended tracker for real footage.
//!
//! A particle filter over an axis-aligned ellipse (centre, log-scale, log-aspect). Each
//! hypothesis is weighted by two terms, as Odobez's object likelihood p_o (Eq. 18, "shape or
//! colour") allows:
//! - **colour**: the sum over the ellipse of each pixel's log-ratio ln(p_target / p_background)
//!   of its HSV bin (Pérez et al. 2002's bins; the background model is the ring around the
//!   estimate, relearnt every locked frame), so that leaving out target pixels and taking in
//!   background pixels both cost — the term fixes the scale as well as the position;
//! - **contour**: the contrast across the ellipse along its normals (Birchfield 1998's
//!   perimeter gradient), in units of the window's mean gradient.
//!
//! Every frame is read in a window around the target at the scale that maps the target to a
//! fixed working size ([`RegionSettings::working_size`]), so the cost does not depend on the
//! target's or the frame's size in pixels. The product is tempered so that the effective sample
//! size never falls below a set fraction of N. A two-state chain on the estimate's colour
//! similarity ([`status`]) says whether the target is still held; while P(lost) is high a share
//! of the particles is drawn anywhere in the frame and the window is the whole frame.

pub mod colour;
pub mod settings;
pub mod status;
pub mod tracker;
pub mod window;

pub use settings::RegionSettings;
pub use tracker::RegionTracker;
