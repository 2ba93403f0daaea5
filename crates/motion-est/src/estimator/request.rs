//! What one estimate is asked for, and the two frames' pyramids it reads.

use crate::model::ModelSpec;
use crate::pyramid::Pyramid;
use crate::region::Region;

/// What to estimate: the region, the model, the origin of the model's coordinates and an optional
/// warm start. Build it with [`new`](Self::new) (cold start, origin at [`Region::centre`]) and
/// set the optional parts with [`with_origin`](Self::with_origin) and
/// [`with_initial`](Self::with_initial), or with struct update syntax.
#[derive(Debug, Clone, Copy)]
pub struct Request<'a> {
    /// The pixels whose motion is estimated.
    pub region: &'a Region<'a>,
    /// The motion model, with or without an intensity offset.
    pub spec: ModelSpec,
    /// Origin of the model's coordinates (x, y), image pixels; `None`: [`Region::centre`].
    pub origin: Option<[f64; 2]>,
    /// A warm start: parameters in level-0 pixels laid out as
    /// [`MotionEstimate::params`](crate::MotionEstimate::params) (`spec.len()` values, about the
    /// same origin); `None`: a cold start.
    pub initial: Option<&'a [f64]>,
}

impl<'a> Request<'a> {
    /// A cold start for `region` and `spec`, origin at the region's centre.
    pub fn new(region: &'a Region<'a>, spec: ModelSpec) -> Self {
        Self {
            region,
            spec,
            origin: None,
            initial: None,
        }
    }

    /// The same request with the model's origin at `origin` (image pixels).
    pub fn with_origin(self, origin: [f64; 2]) -> Self {
        Self {
            origin: Some(origin),
            ..self
        }
    }

    /// The same request warm-started from `initial` (see [`initial`](Self::initial)).
    pub fn with_initial(self, initial: &'a [f64]) -> Self {
        Self {
            initial: Some(initial),
            ..self
        }
    }
}

/// The pyramids of the first and second frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frames<'p> {
    pub(super) p0: &'p Pyramid,
    pub(super) p1: &'p Pyramid,
}
