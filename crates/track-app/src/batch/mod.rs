//! One run of `track run`, or one run of `track eval otb`, as a plain function: what a batch
//! runner (the Python package's `track_video` and its Dask helpers) calls, job by job, on any
//! machine, with no terminal, signal handler or progress bar.
//!
//! - [`video::track_video`] reads a sequence as `track run` reads it (a video file decoded by
//!   ffmpeg, an image folder, an OTB folder), tracks it with the same session loop, and writes
//!   the same `boxes.txt`, `track.csv` and `summary.json` when given a folder.
//! - [`otb`] splits `track eval otb` into its three steps: [`otb::plan`] lays out the runs (the
//!   same checks and the same run starts), [`otb::run`] tracks one run, and [`otb::score`] scores
//!   the runs and writes the tables, plots, box files and index page in `track eval otb`'s
//!   layout. The runs in between may be spread over any number of machines: each is independent
//!   and seeded, so the tables do not depend on where or in which order the runs ran.

pub mod otb;
pub mod video;
