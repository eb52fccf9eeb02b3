//! Python values as the crate's inputs and its values as Python's: numpy arrays of the dtype a
//! call needs, and dicts of a file's keys (a `[sensor]`, `[shadow]` or `[effects]`) through
//! JSON, so that the keys and their checks are the files' own.

use crate::raised;
use numpy::ndarray::Dimension;
use numpy::{Element, PyReadonlyArray};
use pyo3::prelude::*;

/// Any array-like as a numpy array of `dtype` and `D`'s dimensions, copied where its dtype
/// differs; anything else is refused, naming `what`. Strided arrays are read as they are.
/// Integer dtypes take integers (and booleans) within their range and nothing else, because
/// numpy's own cast would truncate 2.5 to 2 and wrap -1 to 4294967295: a label or a vertex
/// index changed silently. Float dtypes take any real numbers, converted as numpy converts them
/// (float64 coordinates rounded to float32).
pub fn array<'py, T: Element, D: Dimension>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<PyReadonlyArray<'py, T, D>> {
    let numpy = py.import("numpy")?;
    let not_an_array = |e: PyErr| raised(format!("{what} is not an array of {dtype}: {e}"));
    let given = numpy.call_method1("asarray", (obj,)).map_err(not_an_array)?;
    let kind: String = given.getattr("dtype")?.getattr("kind")?.extract()?;
    let wanted_kind: String = numpy.call_method1("dtype", (dtype,))?.getattr("kind")?.extract()?;
    let integers = wanted_kind != "f";
    let empty = given.getattr("size")?.extract::<usize>()? == 0;
    let acceptable = if integers { "biu" } else { "biuf" };
    // An empty list is float64 to numpy; it holds no value to change.
    if !empty && !acceptable.contains(kind.as_str()) {
        let of = if integers { "integers" } else { "real numbers" };
        let given_dtype = given.getattr("dtype")?.str()?;
        return Err(raised(format!(
            "{what} is not an array of {dtype}: it must hold {of}, and its dtype is {given_dtype}"
        )));
    }
    if integers && !empty && kind != "b" {
        let range = numpy.call_method1("iinfo", (dtype,))?;
        let (lowest, highest) = (given.call_method0("min")?, given.call_method0("max")?);
        if lowest.lt(range.getattr("min")?)? || highest.gt(range.getattr("max")?)? {
            return Err(raised(format!("{what} holds {lowest} to {highest}, outside {dtype}'s range")));
        }
    }
    let converted = numpy.call_method1("asarray", (given, dtype)).map_err(not_an_array)?;
    converted.extract::<PyReadonlyArray<'py, T, D>>().map_err(|_| {
        let shape = converted.getattr("shape").map(|s| s.to_string()).unwrap_or_default();
        raised(format!("{what} must have {} dimensions; its shape is {shape}", D::NDIM.unwrap_or(0)))
    })
}

/// A Python object (a dict of a file's keys) as the crate's type, through JSON.
pub fn from_keys<T: serde::de::DeserializeOwned>(py: Python<'_>, keys: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
    let text: String = py.import("json")?.call_method1("dumps", (keys,))?.extract()?;
    serde_json::from_str(&text).map_err(|e| raised(format!("{what}: {e}")))
}

/// The crate's value as a Python object of a file's keys (a dict for a `[sensor]`), through
/// JSON: `from_keys`'s reverse.
pub fn keys_of<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(raised)?;
    py.import("json")?.call_method1("loads", (text,))
}
