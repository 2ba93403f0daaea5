#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod convert;
mod error;
mod geometry;
mod image;
mod order;
mod status;

pub use convert::{ToGreyBuffer, grey_from_unit_range};
pub use error::{Error, Result};
pub use geometry::{BoundingBox, Ellipse, fmt_num};
pub use image::{GreyBuffer, GreyImage, luma_bt601};
pub use order::sort_natural;
pub use status::{FAILURE_IOU, FAILURE_RUN, TrackStatus, first_failure};
