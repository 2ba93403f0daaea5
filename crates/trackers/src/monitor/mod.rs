//! What a tracker believes about its own track: whether the target is held ([`lock`], on the
//! appearance) and whether it is seen at all ([`visibility`], on the contour's edges).

pub(crate) mod lock;
pub(crate) mod visibility;
