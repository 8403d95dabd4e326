//! numpy arrays in and out, through numpy's own Python API (`asarray`,
//! `tobytes`, `frombuffer`): no numpy C API, so the stable ABI holds.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyByteArray, PyBytes, PyModule, PyTuple};

static NUMPY: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

fn numpy(py: Python<'_>) -> PyResult<&Bound<'_, PyModule>> {
    NUMPY
        .get_or_try_init(py, || Ok::<_, PyErr>(py.import("numpy")?.unbind()))
        .map(|m| m.bind(py))
}

/// A C-ordered float64 array read into Rust.
pub struct Floats {
    pub data: Vec<f64>,
    pub shape: Vec<usize>,
}

impl Floats {
    /// Rows of three (shape (3,) is one row).
    pub fn rows3(&self) -> Vec<[f64; 3]> {
        self.data
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect()
    }

    /// `(3,)` → false, `(n, 3)` → true; anything else is a ValueError naming `what`.
    pub fn triples(&self, what: &str) -> PyResult<bool> {
        match self.shape.as_slice() {
            [3] => Ok(false),
            [_, 3] => Ok(true),
            s => Err(PyValueError::new_err(format!(
                "{what} must have shape (3,) or (n, 3), got {}",
                shape_text(s)
            ))),
        }
    }
}

pub fn shape_text(s: &[usize]) -> String {
    match s {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            s.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Any array-like of numbers as float64 (numpy's conversion rules); a value
/// numpy cannot convert raises numpy's error, naming `what`.
pub fn floats(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Floats> {
    let py = obj.py();
    let np = numpy(py)?;
    // `tobytes` is C order whatever the layout (0-d arrays stay 0-d).
    let a = np.call_method1("asarray", (obj, "float64")).map_err(|e| {
        // numpy's own class (ValueError, TypeError), with the argument named.
        PyErr::from_type(
            e.get_type(py),
            format!(
                "{what} must be an array-like of real numbers: {}",
                e.value(py)
            ),
        )
    })?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let bytes = a.call_method0("tobytes")?;
    let bytes = bytes.cast::<PyBytes>()?.as_bytes();
    let data = bytes
        .chunks_exact(8)
        .map(|c| f64::from_ne_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
        .collect();
    Ok(Floats { data, shape })
}

/// A new (writable) float64 array of `shape` holding `data` in C order.
pub fn array<'py>(py: Python<'py>, data: &[f64], shape: &[usize]) -> PyResult<Bound<'py, PyAny>> {
    debug_assert_eq!(data.len(), shape.iter().product::<usize>());
    let mut bytes = Vec::with_capacity(data.len() * 8);
    for x in data {
        bytes.extend_from_slice(&x.to_ne_bytes());
    }
    let buffer = PyByteArray::new(py, &bytes);
    let a = numpy(py)?.call_method1("frombuffer", (buffer, "float64"))?;
    a.call_method1("reshape", (PyTuple::new(py, shape)?,))
}

/// Rows of three as an (n, 3) array, or (3,) for one row when `!many`.
pub fn rows_array<'py>(
    py: Python<'py>,
    rows: &[[f64; 3]],
    many: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    if many {
        array(py, &flat, &[rows.len(), 3])
    } else {
        array(py, &flat, &[3])
    }
}
