//! `estimate_motion` and its result `Motion`: motion-est's robust estimate of a region's
//! dominant motion between two frames, with the region read from a box or a mask.

use numpy::{PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use motion_est::{MaskView, ModelSpec, MotionEstimate, MotionEstimator, MotionModel, Region};
use vision_core::BoundingBox;

use crate::args::{order, parse_box};
use crate::errors::{FrameError, UnreliableMotion};
use crate::frames::{self, FrameBuffers, FrameInput};

/// A motion estimate between two frames (`estimate_motion`).
///
/// An unreliable estimate cannot be taken for a good one: `params`, `covariance` and `affine`
/// raise `UnreliableMotion` when `reliable` is False, and `bool(motion)` is `reliable`. The
/// `unchecked_*` properties give the numbers anyway, for diagnosis.
#[pyclass(frozen, module = "contour_track")]
pub struct Motion {
    estimate: MotionEstimate,
    /// Why no estimate could be made at all (the normal equations of a region without texture
    /// are singular), when that is the case: the parameters are then NaN.
    failure: Option<String>,
}

#[pymethods]
impl Motion {
    /// Whether the estimate can be trusted as the dominant motion of the region.
    #[getter]
    fn reliable(&self) -> bool {
        self.estimate.reliable
    }

    /// Whether the full-resolution iterations met the tolerance.
    #[getter]
    fn converged(&self) -> bool {
        self.estimate.converged
    }

    /// The model: "translation", "scale" or "affine".
    #[getter]
    fn model(&self) -> &'static str {
        self.estimate.spec.model.name()
    }

    /// The parameters; raises `UnreliableMotion` when the estimate is not reliable.
    #[getter]
    fn params(&self) -> PyResult<Vec<f64>> {
        self.check()?;
        Ok(self.estimate.params.clone())
    }

    /// The covariance of `params` (a list of rows); raises `UnreliableMotion` when unreliable.
    #[getter]
    fn covariance(&self) -> PyResult<Vec<Vec<f64>>> {
        self.check()?;
        Ok(self.rows())
    }

    /// The six affine parameters [a1..a6] whatever the model; raises `UnreliableMotion` when
    /// unreliable.
    #[getter]
    fn affine(&self) -> PyResult<[f64; 6]> {
        self.check()?;
        Ok(self.estimate.affine())
    }

    /// The parameters even when the estimate is unreliable (for diagnosis only).
    #[getter]
    fn unchecked_params(&self) -> Vec<f64> {
        self.estimate.params.clone()
    }

    /// The covariance even when the estimate is unreliable (for diagnosis only).
    #[getter]
    fn unchecked_covariance(&self) -> Vec<Vec<f64>> {
        self.rows()
    }

    /// Origin (x, y) of the model's coordinates, in pixels.
    #[getter]
    fn origin(&self) -> (f64, f64) {
        (self.estimate.origin[0], self.estimate.origin[1])
    }

    /// The weighted share of the region's pixels explained at the noise scale.
    #[getter]
    fn inlier_fraction(&self) -> f64 {
        self.estimate.inlier_fraction
    }

    /// Final robust scale of the residuals, grey levels.
    #[getter]
    fn scale(&self) -> f64 {
        self.estimate.scale
    }

    fn __bool__(&self) -> bool {
        self.estimate.reliable
    }

    fn __repr__(&self) -> String {
        let py_bool = |b: bool| if b { "True" } else { "False" };
        format!(
            "Motion(model={:?}, reliable={}, converged={}, params={:?}, inlier_fraction={:.3})",
            self.model(),
            py_bool(self.estimate.reliable),
            py_bool(self.estimate.converged),
            self.estimate.params,
            self.estimate.inlier_fraction
        )
    }
}

impl Motion {
    fn check(&self) -> PyResult<()> {
        if self.estimate.reliable {
            return Ok(());
        }
        if let Some(why) = &self.failure {
            return Err(UnreliableMotion::new_err(format!(
                "no {} motion could be estimated ({why}); read .unchecked_params to see them \
                 (NaN) anyway",
                self.model()
            )));
        }
        Err(UnreliableMotion::new_err(format!(
            "the {} motion estimate is not reliable (converged: {}, inlier fraction {:.3}): its \
             parameters do not describe the region's motion; read .unchecked_params to see them \
             anyway",
            self.model(),
            self.estimate.converged,
            self.estimate.inlier_fraction
        )))
    }

    fn rows(&self) -> Vec<Vec<f64>> {
        let n = self.estimate.params.len();
        self.estimate
            .covariance
            .chunks(n.max(1))
            .map(<[f64]>::to_vec)
            .collect()
    }
}

/// The estimate of a computation that failed: every number NaN, not converged, not reliable.
fn failed_estimate(spec: ModelSpec) -> MotionEstimate {
    let n = spec.len();
    MotionEstimate {
        spec,
        params: vec![f64::NAN; n],
        covariance: vec![f64::NAN; n * n],
        origin: [f64::NAN; 2],
        scale: f64::NAN,
        noise_sigma: f64::NAN,
        inlier_fraction: 0.0,
        iterations: Vec::new(),
        converged: false,
        reliable: false,
    }
}

/// The support region of `estimate_motion`.
enum Roi {
    Full,
    Rect(BoundingBox),
    Mask(Vec<f32>),
}

fn parse_roi(roi: Option<&Bound<'_, PyAny>>, width: usize, height: usize) -> PyResult<Roi> {
    let Some(roi) = roi.filter(|r| !r.is_none()) else {
        return Ok(Roi::Full);
    };
    if let Ok(array) = roi.cast::<PyUntypedArray>()
        && array.ndim() >= 2
    {
        let shape = array.shape().to_vec();
        // An H×W×1 mask (as OpenCV and Pillow give single-channel images) is read as H×W.
        if array.ndim() == 3 && shape[2] == 1 {
            let squeezed = roi.call_method1("squeeze", (2,))?;
            return parse_roi(Some(&squeezed), width, height);
        }
        if array.ndim() != 2 {
            return Err(PyValueError::new_err(format!(
                "mask has shape {}: give an H×W (or H×W×1) mask of the frames' size, or a box \
                 (x, y, w, h)",
                frames::shape_text(&shape)
            )));
        }
        if (shape[1], shape[0]) != (width, height) {
            return Err(PyValueError::new_err(format!(
                "mask is {}x{} but the frames are {width}x{height}",
                shape[1], shape[0]
            )));
        }
        return frames::mask_weights(array).map(Roi::Mask);
    }
    let b = parse_box(roi, "roi")?;
    if !b.is_finite() || b.w <= 0.0 || b.h <= 0.0 {
        return Err(PyValueError::new_err(format!(
            "roi {} must be finite with a positive size",
            b.shown()
        )));
    }
    Ok(Roi::Rect(b))
}

/// Estimates the dominant motion of a region from frame `f0` to frame `f1`.
///
/// The robust multiresolution estimator of motion-est (Odobez & Bouthemy): IRLS with Tukey's
/// biweight, coarse to fine, with a covariance.
///
/// Arguments:
///     f0, f1: frames of one size, as `Tracker.update` takes them (`rgb=True` for RGB colour).
///     roi: None (the whole frame), a box (x, y, w, h), or a mask of the frames' H×W (or
///         H×W×1): bool,
///         uint8 (non-zero pixels count, as OpenCV's 0/255 masks) or float weights in [0, 1].
///     model: "translation" [tx, ty], "scale" [tx, ty, k] or "affine" [a1..a6] (Odobez Eq. 13:
///         dx = a1 + a2·x + a3·y, dy = a4 + a5·x + a6·y, with x, y from `origin`).
///     offset: also estimate an intensity offset (last parameter).
///
/// Returns a `Motion`; its `params` raise `UnreliableMotion` when the estimate is not
/// reliable, including when none could be computed (a region without texture, such as constant
/// frames: the parameters are NaN). Bad frames, masks or boxes raise TypeError or ValueError;
/// frames of more than 2**26 pixels raise MemoryError before anything is allocated. A mask may
/// be H×W or H×W×1.
#[pyfunction]
#[pyo3(signature = (f0, f1, roi=None, model="affine", *, offset=false, rgb=false))]
pub(crate) fn estimate_motion(
    py: Python<'_>,
    f0: &Bound<'_, PyAny>,
    f1: &Bound<'_, PyAny>,
    roi: Option<&Bound<'_, PyAny>>,
    model: &str,
    offset: bool,
    rgb: bool,
) -> PyResult<Motion> {
    let model: MotionModel = model
        .parse()
        .map_err(|e: motion_est::Error| PyValueError::new_err(e.to_string()))?;
    let in0 = FrameInput::read(f0, "f0")?;
    let in1 = FrameInput::read(f1, "f1")?;
    if (in0.width, in0.height) != (in1.width, in1.height) {
        return Err(PyValueError::new_err(format!(
            "f0 is {}x{} but f1 is {}x{}: the frames must have one size",
            in0.width, in0.height, in1.width, in1.height
        )));
    }
    let (w, h) = (in0.width, in0.height);
    let roi = parse_roi(roi, w, h)?;
    let (v0, v1) = (in0.view(), in1.view());
    let order = order(rgb);
    let estimate = py.detach(|| {
        let (mut b0, mut b1) = (FrameBuffers::default(), FrameBuffers::default());
        let g0 = b0.frame(&v0, order)?.grey();
        let g1 = b1.frame(&v1, order)?.grey();
        let region = match &roi {
            Roi::Full => Region::Full,
            Roi::Rect(b) => Region::Rect {
                x: b.x,
                y: b.y,
                width: b.w,
                height: b.h,
            },
            Roi::Mask(weights) => {
                Region::Mask(MaskView::new(w, h, weights).map_err(FrameError::Motion)?)
            }
        };
        let estimator =
            MotionEstimator::new(motion_est::Settings::default()).map_err(FrameError::Motion)?;
        let spec = ModelSpec::new(model, offset);
        match estimator
            .estimate_images(g0, g1, &region, spec, None)
            // An unreliable estimate is kept: `Motion` makes it impossible to mistake for a
            // good one (its parameters raise `UnreliableMotion`).
            .or_else(motion_est::Error::into_unreliable)
        {
            Ok(estimate) => Ok((estimate, None)),
            // A region without texture (constant frames) has no motion to estimate: a failed
            // computation, not a bad argument, reported as an unreliable estimate.
            Err(e @ motion_est::Error::Degenerate { .. }) => {
                Ok((failed_estimate(spec), Some(e.to_string())))
            }
            Err(e) => Err(FrameError::Motion(e)),
        }
    })?;
    let (estimate, failure) = estimate;
    Ok(Motion { estimate, failure })
}
