//! numpy frames as the trackers see them: exactly the grey (and RGB) frame `track run` makes from
//! the same pixels.
//!
//! * `uint8` H×W: grey levels as they are, no colour (as a grey PNG in an image folder).
//! * `uint8` H×W×3, BGR (OpenCV's order, the default) or RGB: grey by
//!   [`vision_core::luma_bt601`], and the colour pixels (as a colour PNG). A C-contiguous
//!   frame's pixels are borrowed, not copied, in either order (`trackers::Frame::with_bgr`).
//! * `float32` H×W: grey levels in 0–255, borrowed when C-contiguous; every value must be finite.
//! * `float32` H×W×3: colour in 0–255; grey by the same weights in f32, and the RGB pixels rounded
//!   (an integer-valued float frame gives the trackers exactly what its `uint8` twin gives).
//!
//! Any other layout (strided, Fortran order, negative strides) is read through its strides.

use numpy::ndarray::{ArrayView2, ArrayView3, Axis, Ix2, Ix3};
use numpy::{
    PyArray2, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyMemoryError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use vision_core::{GreyImage, luma_bt601};

use crate::errors::FrameError;

/// The order of the channels of a colour `uint8` or `float32` frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChannelOrder {
    /// Blue, green, red: OpenCV's `imread` and `VideoCapture`.
    Bgr,
    /// Red, green, blue: Pillow, imageio, matplotlib.
    Rgb,
}

/// The most pixels a frame may have: the largest frame `track` reads (a Y4M frame's limit).
/// Larger frames raise `MemoryError` before anything is allocated.
pub const MAX_FRAME_PIXELS: usize = track_app::sequence::MAX_PIXELS;

/// Reserves room for `n` more values in `buffer`, or reports a `MemoryError`.
fn reserve<T>(buffer: &mut Vec<T>, n: usize) -> Result<(), FrameError> {
    buffer.try_reserve(n).map_err(|_| {
        FrameError::Memory(format!(
            "cannot allocate the frame's buffer of {n} values ({} bytes)",
            n.saturating_mul(std::mem::size_of::<T>())
        ))
    })
}

/// A numpy frame, checked for dtype and shape, borrowed read-only while the binding reads it.
pub struct FrameInput<'py> {
    data: Data<'py>,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    colour: bool,
}

enum Data<'py> {
    U8(PyReadonlyArrayDyn<'py, u8>),
    F32(PyReadonlyArrayDyn<'py, f32>),
}

/// The pixels of a [`FrameInput`], free of the GIL (ndarray views are `Send`).
pub enum FrameView<'a> {
    GreyU8(ArrayView2<'a, u8>),
    ColourU8(ArrayView3<'a, u8>),
    GreyF32(ArrayView2<'a, f32>),
    ColourF32(ArrayView3<'a, f32>),
}

/// A numpy shape as Python writes it: `(120, 160, 2)`.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(usize::to_string).collect();
    format!("({})", parts.join(", "))
}

impl<'py> FrameInput<'py> {
    /// Checks `obj` as a frame; `what` names it in errors.
    ///
    /// # Errors
    /// `TypeError` for something that is not a numpy array or has another dtype than `uint8` or
    /// `float32`; `ValueError` for another shape than H×W, H×W×1 or H×W×3, or an empty frame;
    /// `MemoryError` for a frame of more than [`MAX_FRAME_PIXELS`] pixels.
    pub fn read(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Self> {
        let Ok(array) = obj.cast::<PyUntypedArray>() else {
            return Err(PyTypeError::new_err(format!(
                "{what} must be a numpy array (H×W grey or H×W×3 colour, uint8 or float32), got {}",
                obj.get_type().name()?
            )));
        };
        let shape = array.shape().to_vec();
        let colour = match shape.as_slice() {
            [_, _] | [_, _, 1] => false,
            [_, _, 3] => true,
            [_, _, c] => {
                return Err(PyValueError::new_err(format!(
                    "{what} has shape {} with {c} channels: give H×W grey or H×W×3 colour \
                     (drop an alpha channel with {what}[..., :3])",
                    shape_text(&shape)
                )));
            }
            _ => {
                return Err(PyValueError::new_err(format!(
                    "{what} has shape {}: give H×W grey or H×W×3 colour",
                    shape_text(&shape)
                )));
            }
        };
        let (height, width) = (shape[0], shape[1]);
        if width == 0 || height == 0 {
            return Err(PyValueError::new_err(format!(
                "{what} is empty (shape {})",
                shape_text(&shape)
            )));
        }
        // Checked before anything is allocated: a broadcast view of one pixel can claim any
        // size, and the buffers (and the trackers' own) would then fail to allocate.
        let pixels = width.checked_mul(height).filter(|&p| p <= MAX_FRAME_PIXELS);
        if pixels.is_none() {
            return Err(PyMemoryError::new_err(format!(
                "{what} is {width}x{height} pixels, more than the {MAX_FRAME_PIXELS} pixels of \
                 the largest frame the trackers take (8192x8192)"
            )));
        }
        let busy =
            |e: numpy::BorrowError| PyValueError::new_err(format!("{what} cannot be read: {e}"));
        let data = if let Ok(a) = array.cast::<PyArrayDyn<u8>>() {
            Data::U8(a.try_readonly().map_err(busy)?)
        } else if let Ok(a) = array.cast::<PyArrayDyn<f32>>() {
            Data::F32(a.try_readonly().map_err(busy)?)
        } else {
            return Err(PyTypeError::new_err(format!(
                "{what} has dtype {}: give uint8 (0–255) or float32 grey levels \
                 ({what}.astype(numpy.float32))",
                array.dtype()
            )));
        };
        Ok(Self {
            data,
            width,
            height,
            colour,
        })
    }

    /// The pixels as 2-D (grey) or 3-D (colour) views.
    pub fn view(&self) -> FrameView<'_> {
        fn grey<T>(a: numpy::ndarray::ArrayViewD<'_, T>) -> ArrayView2<'_, T> {
            let a = if a.ndim() == 3 {
                a.index_axis_move(Axis(2), 0)
            } else {
                a
            };
            // The shape was checked in `read`: 2-D here.
            a.into_dimensionality::<Ix2>()
                .unwrap_or_else(|_| unreachable!("a grey frame is 2-D"))
        }
        fn colour<T>(a: numpy::ndarray::ArrayViewD<'_, T>) -> ArrayView3<'_, T> {
            a.into_dimensionality::<Ix3>()
                .unwrap_or_else(|_| unreachable!("a colour frame is 3-D"))
        }
        match (&self.data, self.colour) {
            (Data::U8(a), false) => FrameView::GreyU8(grey(a.as_array())),
            (Data::U8(a), true) => FrameView::ColourU8(colour(a.as_array())),
            (Data::F32(a), false) => FrameView::GreyF32(grey(a.as_array())),
            (Data::F32(a), true) => FrameView::ColourF32(colour(a.as_array())),
        }
    }
}

/// The binding's reusable buffers: the grey frame and the RGB pixels, when they cannot be
/// borrowed from the numpy array.
#[derive(Debug, Default)]
pub struct FrameBuffers {
    grey: Vec<f32>,
    rgb: Vec<u8>,
}

fn non_finite(row: usize, column: usize) -> FrameError {
    FrameError::Value(format!(
        "frame has a non-finite value (NaN or infinity) at row {row}, column {column}"
    ))
}

impl FrameBuffers {
    /// The frame the trackers see, from `view`: borrowed from it where the layout allows,
    /// converted into these buffers otherwise.
    pub fn frame<'s>(
        &'s mut self,
        view: &'s FrameView<'_>,
        order: ChannelOrder,
    ) -> Result<trackers::Frame<'s>, FrameError> {
        let (red, blue) = match order {
            ChannelOrder::Bgr => (2, 0),
            ChannelOrder::Rgb => (0, 2),
        };
        let frame = match view {
            FrameView::GreyU8(a) => {
                let (h, w) = a.dim();
                self.grey.clear();
                reserve(&mut self.grey, w * h)?;
                match a.as_slice() {
                    Some(pixels) => self.grey.extend(pixels.iter().map(|&v| f32::from(v))),
                    None => self.grey.extend(a.iter().map(|&v| f32::from(v))),
                }
                trackers::Frame::new(w, h, &self.grey)
            }
            FrameView::ColourU8(a) => {
                let (h, w, _) = a.dim();
                self.grey.clear();
                reserve(&mut self.grey, w * h)?;
                match (a.as_slice(), order) {
                    (Some(pixels), ChannelOrder::Rgb) => {
                        self.grey
                            .extend(pixels.chunks_exact(3).map(|p| luma_bt601(p[0], p[1], p[2])));
                        trackers::Frame::with_rgb(w, h, &self.grey, pixels)
                    }
                    (Some(pixels), ChannelOrder::Bgr) => {
                        // OpenCV's order is read in place by the trackers: no reordered copy.
                        // Components read in memory order (then passed as R, G, B): the loop
                        // vectorises as the RGB one does, a third faster than reading p[2] first.
                        self.grey.extend(pixels.chunks_exact(3).map(|p| {
                            let (b, g, r) = (p[0], p[1], p[2]);
                            luma_bt601(r, g, b)
                        }));
                        trackers::Frame::with_bgr(w, h, &self.grey, pixels)
                    }
                    (None, _) => {
                        self.rgb.clear();
                        reserve(&mut self.rgb, 3 * w * h)?;
                        for p in a.lanes(Axis(2)) {
                            let (r, g, b) = (p[red], p[1], p[blue]);
                            self.grey.push(luma_bt601(r, g, b));
                            self.rgb.extend_from_slice(&[r, g, b]);
                        }
                        trackers::Frame::with_rgb(w, h, &self.grey, &self.rgb)
                    }
                }
            }
            FrameView::GreyF32(a) => {
                let (h, w) = a.dim();
                let data = match a.as_slice() {
                    Some(data) => data,
                    None => {
                        self.grey.clear();
                        reserve(&mut self.grey, w * h)?;
                        self.grey.extend(a.iter().copied());
                        &self.grey
                    }
                };
                // Grey levels lie in 0–255, as in a float32 colour frame: a frame scaled to
                // 0–1 (or 0–65535) would otherwise be tracked with edges 255 times too weak
                // (or strong) for the trackers' thresholds. A NaN fails this test too and is
                // reported as non-finite.
                if let Some(i) = data.iter().position(|v| !(0.0..=255.0).contains(v)) {
                    let v = data[i];
                    if !v.is_finite() {
                        return Err(non_finite(i / w, i % w));
                    }
                    return Err(FrameError::Value(format!(
                        "a float32 grey frame holds levels in 0–255; row {}, column {} has {v}",
                        i / w,
                        i % w
                    )));
                }
                // One pass checks every value, the trackers' own check (`GreyImage::new`); its
                // error gives the first non-finite pixel's index.
                return match GreyImage::new(w, h, data) {
                    Ok(grey) => Ok(grey.into()),
                    Err(vision_core::Error::NonFinite { index }) => {
                        Err(non_finite(index / w, index % w))
                    }
                    Err(e) => Err(FrameError::Value(format!("frame: {e}"))),
                };
            }
            FrameView::ColourF32(a) => {
                let (h, w, _) = a.dim();
                self.grey.clear();
                self.rgb.clear();
                reserve(&mut self.grey, w * h)?;
                reserve(&mut self.rgb, 3 * w * h)?;
                for (i, p) in a.lanes(Axis(2)).into_iter().enumerate() {
                    let (r, g, b) = (p[red], p[1], p[blue]);
                    if !(r.is_finite() && g.is_finite() && b.is_finite()) {
                        return Err(non_finite(i / w, i % w));
                    }
                    if [r, g, b].iter().any(|v| !(0.0..=255.0).contains(v)) {
                        return Err(FrameError::Value(format!(
                            "a float32 colour frame holds levels in 0–255; row {}, column {} has \
                             ({r}, {g}, {b})",
                            i / w,
                            i % w
                        )));
                    }
                    self.grey.push(0.299 * r + 0.587 * g + 0.114 * b);
                    self.rgb.extend_from_slice(&[
                        r.round() as u8,
                        g.round() as u8,
                        b.round() as u8,
                    ]);
                }
                trackers::Frame::with_rgb(w, h, &self.grey, &self.rgb)
            }
        };
        frame.map_err(FrameError::Tracker)
    }
}

/// The weights of a mask given as `roi`: `bool` (True counts), `uint8` (non-zero counts, as
/// OpenCV's 0/255 masks), or `float32`/`float64` weights in [0, 1].
///
/// # Errors
/// `TypeError` for another dtype, `ValueError` for a weight outside [0, 1].
pub fn mask_weights(array: &Bound<'_, PyUntypedArray>) -> PyResult<Vec<f32>> {
    if let Ok(a) = array.cast::<PyArray2<bool>>() {
        return Ok(a
            .readonly()
            .as_array()
            .iter()
            .map(|&v| if v { 1.0 } else { 0.0 })
            .collect());
    }
    if let Ok(a) = array.cast::<PyArray2<u8>>() {
        return Ok(a
            .readonly()
            .as_array()
            .iter()
            .map(|&v| if v > 0 { 1.0 } else { 0.0 })
            .collect());
    }
    let weights: Vec<f64> = if let Ok(a) = array.cast::<PyArray2<f32>>() {
        a.readonly()
            .as_array()
            .iter()
            .map(|&v| f64::from(v))
            .collect()
    } else if let Ok(a) = array.cast::<PyArray2<f64>>() {
        a.readonly().as_array().iter().copied().collect()
    } else {
        return Err(PyTypeError::new_err(format!(
            "mask has dtype {}: give bool, uint8 (non-zero counts) or float weights in [0, 1]",
            array.dtype()
        )));
    };
    if let Some(v) = weights.iter().find(|v| !(0.0..=1.0).contains(*v)) {
        return Err(PyValueError::new_err(format!(
            "mask weights must lie in [0, 1], found {v}"
        )));
    }
    Ok(weights.into_iter().map(|v| v as f32).collect())
}
