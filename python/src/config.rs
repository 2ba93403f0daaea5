//! The tracker configuration a `Tracker(...)` (or `track_video`) call describes: a preset, or a
//! configuration given as a dict or a file, with the `particles` and `seed` overrides, by
//! `track run`'s rules; a bad value of a dict is named by its key.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use trackers::{ConfigFormat, Preset, TrackerConfig};

use crate::args::{index_of, int_text};
use crate::errors::tracker_error;

/// The key path of a configuration value in messages: `filter.resample_threshold`, `terms[2]`.
fn key_path(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_owned()
    } else if key.starts_with('[') {
        format!("{path}{key}")
    } else {
        format!("{path}.{key}")
    }
}

/// A copy of a configuration dict made of JSON's own types, each value checked on the way so
/// that a bad one is named by its key: numpy integers become ints and numpy floats floats; a NaN
/// or infinity, an integer beyond 64 bits, or a value JSON cannot hold is refused.
///
/// # Errors
/// `ValueError` naming the key for a non-finite number or an integer out of range; `TypeError`
/// naming the key for a value of another type.
fn json_value<'py>(v: &Bound<'py, PyAny>, path: &str) -> PyResult<Bound<'py, PyAny>> {
    use pyo3::types::{PyBool, PyFloat, PyList, PyString, PyTuple};
    let py = v.py();
    let at = if path.is_empty() { "config" } else { path };
    if v.is_none() || v.is_instance_of::<PyBool>() || v.is_instance_of::<PyString>() {
        return Ok(v.clone());
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let out = PyDict::new(py);
        for (k, value) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!("config: {at} has a key that is not a string: {k}"))
            })?;
            out.set_item(&key, json_value(&value, &key_path(path, &key))?)?;
        }
        return Ok(out.into_any());
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let out = PyList::empty(py);
        for (k, item) in v.try_iter()?.enumerate() {
            out.append(json_value(&item?, &key_path(path, &format!("[{k}]")))?)?;
        }
        return Ok(out.into_any());
    }
    let type_name = v.get_type().name()?.to_string();
    if type_name == "bool_" {
        return Ok(PyBool::new(py, v.is_truthy()?).to_owned().into_any());
    }
    if !v.is_instance_of::<PyFloat>()
        && let Ok(i) = index_of(v, at)
    {
        if i.extract::<i64>().is_err() && i.extract::<u64>().is_err() {
            return Err(PyValueError::new_err(format!(
                "config: {at} is out of range (an integer of at most 64 bits), got {}",
                int_text(&i)
            )));
        }
        return Ok(i.into_any());
    }
    if let Ok(x) = v.extract::<f64>()
        && (v.is_instance_of::<PyFloat>() || type_name.starts_with("float"))
    {
        if !x.is_finite() {
            return Err(PyValueError::new_err(format!(
                "config: {at} = {x} is not a finite number"
            )));
        }
        return Ok(PyFloat::new(py, x).into_any());
    }
    Err(PyTypeError::new_err(format!(
        "config: {at} is a {type_name}, which a configuration cannot hold (give numbers, \
         strings, booleans, lists and dicts)"
    )))
}

/// The key at a position of `json` (text as `json.dumps(..., indent=1)` writes it, one key per
/// line): the dotted path of the keys open at line `line` (1-based).
fn key_at_line(json: &str, line: usize) -> Option<String> {
    let mut stack: Vec<String> = Vec::new();
    let mut here = None;
    for (i, text) in json.lines().enumerate().take(line) {
        let t = text.trim();
        let key = t
            .strip_prefix('"')
            .and_then(|r| r.split_once("\": "))
            .map(|(k, _)| k.to_owned());
        if i + 1 == line {
            here = key.or_else(|| stack.last().cloned().map(|_| String::new()));
            break;
        }
        if t.ends_with('{') || t.ends_with('[') {
            stack.push(key.unwrap_or_else(|| "[]".to_owned()));
        } else if t.starts_with('}') || t.starts_with(']') {
            stack.pop();
        }
    }
    let mut parts: Vec<String> = stack.into_iter().filter(|k| k != "[]").collect();
    if let Some(k) = here.filter(|k| !k.is_empty()) {
        parts.push(k);
    }
    (!parts.is_empty()).then(|| parts.join("."))
}

/// A configuration parser's message made short and pointed at the key: `at line L column C` is
/// replaced by the key found at that line of `json`.
fn config_message(message: &str, json: &str) -> String {
    let Some(pos) = message.find(" at line ") else {
        return message.to_owned();
    };
    let line = message[pos + 9..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse::<usize>().ok());
    match line.and_then(|l| key_at_line(json, l)) {
        Some(key) => format!("{key}: {}", &message[..pos]),
        None => message.to_owned(),
    }
}

/// The configuration a `Tracker(...)` call describes: `track run`'s rules (a preset at
/// [`trackers::DEFAULT_PARTICLES`] and [`trackers::DEFAULT_SEED`], or a configuration), then the
/// `particles` and `seed` overrides.
pub(crate) fn tracker_config(
    py: Python<'_>,
    preset: Option<&str>,
    particles: Option<u64>,
    seed: Option<u64>,
    config: Option<&Bound<'_, PyAny>>,
) -> PyResult<TrackerConfig> {
    let mut c = match config.filter(|c| !c.is_none()) {
        Some(config) => {
            if let Some(name) = preset {
                return Err(PyValueError::new_err(format!(
                    "give a preset ({name:?}) or a config, not both: the config names its own tracker"
                )));
            }
            let c = if config.is_instance_of::<PyDict>() {
                let clean = json_value(config, "")?;
                let kwargs = PyDict::new(py);
                kwargs.set_item("indent", 1)?;
                let json: String = py
                    .import("json")?
                    .call_method("dumps", (clean,), Some(&kwargs))?
                    .extract()?;
                TrackerConfig::parse(&json, ConfigFormat::Json).map_err(|e| {
                    PyValueError::new_err(format!(
                        "config: {}",
                        config_message(&e.to_string(), &json)
                    ))
                })?
            } else {
                let path: std::path::PathBuf = config.extract().map_err(|_| {
                    PyTypeError::new_err(format!(
                        "config must be a dict or a path (str or os.PathLike), got {}",
                        config
                            .get_type()
                            .name()
                            .map_or_else(|_| "?".into(), |n| n.to_string())
                    ))
                })?;
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    let message = format!("config {}: cannot read it: {e}", path.display());
                    match e.kind() {
                        std::io::ErrorKind::NotFound => {
                            pyo3::exceptions::PyFileNotFoundError::new_err(message)
                        }
                        _ => pyo3::exceptions::PyOSError::new_err(message),
                    }
                })?;
                TrackerConfig::parse(&text, ConfigFormat::of_path(&path))
                    .map_err(|e| PyValueError::new_err(format!("config {}: {e}", path.display())))?
            };
            c.validate()
                .map_err(|e| PyValueError::new_err(format!("config: {e}")))?;
            c
        }
        None => {
            let p = Preset::from_name(preset.unwrap_or(DEFAULT_TRACKER)).map_err(tracker_error)?;
            p.config(trackers::DEFAULT_PARTICLES, trackers::DEFAULT_SEED)
        }
    };
    if let Some(s) = seed {
        c.seed = s;
    }
    if let Some(n) = particles {
        c.particles = usize::try_from(n).unwrap_or(usize::MAX);
        c.validate()
            .map_err(|e| PyValueError::new_err(format!("particles: {e}")))?;
    }
    Ok(c)
}

/// The preset `Tracker()` uses when neither a preset nor a config is given: `track run`'s.
pub(crate) const DEFAULT_TRACKER: &str = track_app::commands::run::DEFAULT_TRACKER;

/// The presets, one `(name, description)` pair each, in the order of `track --help`.
#[pyfunction]
pub(crate) fn presets() -> Vec<(&'static str, &'static str)> {
    Preset::ALL
        .iter()
        .map(|p| (p.name(), p.description()))
        .collect()
}
