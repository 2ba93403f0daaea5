//! The Rust side of the overhead benchmark (`bench/bench_overhead.py`): the same frames tracked
//! without the binding, timed in Rust. Not public API.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use trackers::Preset;
use vision_core::BoundingBox;

use crate::errors::tracker_error;

/// The Rust side of `bench/bench_overhead.py`: tracks RGB frames the way `track run` feeds a
/// decoded colour image to a tracker (grey by [`vision_core::luma_bt601`], the frame with its RGB
/// pixels, `init` then `update`), timing each update's conversion and update in Rust, without the
/// GIL. Returns, for each update, its wall time and its thread CPU time in milliseconds (the CPU
/// time of the calling thread, which a loaded machine disturbs less), and the boxes of every frame.
/// Not public API.
#[pyfunction]
#[pyo3(signature = (preset, frames, bbox, particles=200, seed=1))]
#[allow(clippy::type_complexity)]
pub(crate) fn _rust_update_times(
    py: Python<'_>,
    preset: &str,
    frames: Vec<numpy::PyReadonlyArray3<'_, u8>>,
    bbox: (f64, f64, f64, f64),
    particles: usize,
    seed: u64,
) -> PyResult<(Vec<f64>, Vec<f64>, Vec<(f64, f64, f64, f64)>)> {
    let mut size = None;
    let mut pixels = Vec::with_capacity(frames.len());
    for f in &frames {
        let (h, w, c) = f.as_array().dim();
        if c != 3 || size.is_some_and(|s| s != (w, h)) {
            return Err(PyValueError::new_err(
                "frames must be RGB uint8 H×W×3 of one size",
            ));
        }
        size = Some((w, h));
        pixels.push(f.as_array().iter().copied().collect::<Vec<u8>>());
    }
    let Some((w, h)) = size else {
        return Ok((Vec::new(), Vec::new(), Vec::new()));
    };
    let config = Preset::from_name(preset)
        .map_err(tracker_error)?
        .config(particles, seed);
    let start = BoundingBox::new(bbox.0, bbox.1, bbox.2, bbox.3).inscribed_ellipse();
    py.detach(move || {
        let mut tracker = trackers::build(config)?;
        let (mut wall, mut cpu, mut boxes) = (Vec::new(), Vec::new(), Vec::new());
        // One grey buffer, reused, as the binding reuses its own.
        let mut grey: Vec<f32> = Vec::with_capacity(w * h);
        for (k, rgb) in pixels.iter().enumerate() {
            let t0 = std::time::Instant::now();
            let c0 = cpu_time::ThreadTime::now();
            grey.clear();
            grey.extend(
                rgb.chunks_exact(3)
                    .map(|p| vision_core::luma_bt601(p[0], p[1], p[2])),
            );
            let frame = trackers::Frame::with_rgb(w, h, &grey, rgb)?;
            let e = if k == 0 {
                tracker.init(frame, start)?
            } else {
                tracker.update(frame)?
            };
            if k > 0 {
                cpu.push(c0.elapsed().as_secs_f64() * 1e3);
                wall.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            boxes.push((e.bbox.x, e.bbox.y, e.bbox.w, e.bbox.h));
        }
        Ok((wall, cpu, boxes))
    })
    .map_err(tracker_error)
}
