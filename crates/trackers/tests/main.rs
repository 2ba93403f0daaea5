//! The integration tests of this package, in one test binary (one binary per package keeps a
//! cold build short: each test binary links the whole dependency tree).

mod head;
mod library_surface;
mod smoothing;
