//! Reading the arguments of the binding's functions: integers as Python's `operator.index`
//! reads them, boxes from sequences of four numbers, the `rgb` keyword; each refusal a
//! `TypeError` or `ValueError` in one short line.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use vision_core::BoundingBox;

use crate::frames::ChannelOrder;

/// An integer argument as Python's `operator.index` reads it: an `int`, or any object with
/// `__index__` (numpy's integer scalars), but not a `bool` (numpy's `bool_` included) nor a float.
///
/// # Errors
/// `TypeError` naming `what` and the type given.
pub(crate) fn index_of<'py>(
    v: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, pyo3::types::PyInt>> {
    let type_name = v.get_type().name()?.to_string();
    let refused = || {
        PyTypeError::new_err(format!(
            "{what} must be an int (or a numpy integer), got {type_name}"
        ))
    };
    if v.is_instance_of::<pyo3::types::PyBool>() || type_name == "bool_" || type_name == "bool" {
        return Err(refused());
    }
    if let Ok(i) = v.cast::<pyo3::types::PyInt>() {
        return Ok(i.clone());
    }
    let index = v.py().import("operator")?.call_method1("index", (v,));
    match index {
        Ok(i) => i.cast_into::<pyo3::types::PyInt>().map_err(|_| refused()),
        Err(_) => Err(refused()),
    }
}

/// An integer for a message: as it is up to 20 digits, else its number of digits, so that the
/// message stays one short line.
pub(crate) fn int_text(i: &Bound<'_, pyo3::types::PyInt>) -> String {
    let text = i.to_string();
    let digits = text.trim_start_matches('-').len();
    if digits <= 20 {
        text
    } else {
        format!("an integer of {digits} digits")
    }
}

/// Extracts an optional non-negative integer keyword with a clear `ValueError`/`TypeError`;
/// numpy integer scalars are accepted as ints are.
pub(crate) fn non_negative(value: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<u64>> {
    let Some(v) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    let i = index_of(v, what)?;
    i.extract::<u64>().map(Some).map_err(|_| {
        PyValueError::new_err(format!(
            "{what} must be a non-negative integer below 2**64, got {}",
            int_text(&i)
        ))
    })
}

/// Reads the `rgb` keyword.
pub(crate) fn order(rgb: bool) -> ChannelOrder {
    if rgb {
        ChannelOrder::Rgb
    } else {
        ChannelOrder::Bgr
    }
}

/// A box (x, y, w, h) from any sequence of four real numbers.
pub(crate) fn parse_box(value: &Bound<'_, PyAny>, what: &str) -> PyResult<BoundingBox> {
    let v: Vec<f64> = value
        .extract()
        .ok()
        .filter(|v: &Vec<f64>| v.len() == 4)
        .ok_or_else(|| PyTypeError::new_err(format!("{what} must be four numbers (x, y, w, h)")))?;
    Ok(BoundingBox::new(v[0], v[1], v[2], v[3]))
}

/// The checks of a box that need no frame: finite, of positive size. The box is shown as
/// vision-core's [`BoundingBox::shown`] writes it for the command line (`1e300`, not 301 digits).
///
/// # Errors
/// `ValueError` naming `what` and the box.
pub(crate) fn check_finite_box(b: &BoundingBox, what: &str) -> PyResult<()> {
    if !b.is_finite() {
        return Err(PyValueError::new_err(format!(
            "{what} {} is not finite",
            b.shown()
        )));
    }
    if b.w <= 0.0 || b.h <= 0.0 {
        return Err(PyValueError::new_err(format!(
            "{what} {} has zero or negative size",
            b.shown()
        )));
    }
    Ok(())
}
