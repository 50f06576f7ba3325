//! numpy ⇄ nalgebra conversions with argument-named errors.
//!
//! Inputs are accepted as anything numpy can turn into a float64 array (arrays of any float or
//! integer dtype, nested lists); the fast path is a C-contiguous float64 array. Every array is
//! read in its logical (row-major) order whatever its memory layout (C or Fortran order,
//! transposed views, negative strides, slices): `as_slice` alone would accept Fortran-ordered
//! data and read it transposed. numpy is row-major and nalgebra column-major, so matrices are
//! built row by row.

use nalgebra::{DMatrix, DVector};
use navfdi_core::run::MatrixSeq;
use numpy::{
    AllowTypeChange, IxDyn, PyArray, PyArrayDescrMethods, PyArrayDyn, PyArrayLikeDyn,
    PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// An n-dimensional float64 array read from Python: shape and row-major data.
pub struct Array {
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
}

fn shape_str(shape: &[usize]) -> String {
    match shape.len() {
        0 => "() (a scalar)".to_string(),
        1 => format!("({},)", shape[0]),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// Refuse dtypes that are not real numbers (complex, strings, objects, dates): numpy would
/// drop an imaginary part or parse strings silently when casting to float64.
fn check_kind(name: &str, arr: &Bound<'_, PyUntypedArray>) -> PyResult<()> {
    let dtype = arr.dtype();
    match dtype.kind() {
        b'b' | b'i' | b'u' | b'f' => Ok(()),
        b'c' => Err(PyValueError::new_err(format!(
            "{name}: complex values are not accepted (dtype {dtype}); pass the real part explicitly if that is what you mean"
        ))),
        _ => Err(PyValueError::new_err(format!(
            "{name}: expected real numbers, got an array of dtype {dtype}"
        ))),
    }
}

/// Copy an array view in logical (row-major, C) order, whatever its memory layout: C or F
/// order, transposed views, negative strides, non-contiguous slices.
fn logical(view: numpy::ndarray::ArrayViewD<'_, f64>) -> Array {
    use numpy::ndarray::{Ix1, Ix2, Ix3};
    let shape = view.shape().to_vec();
    let data = match view.as_slice() {
        // `ArrayView::as_slice` is `Some` only for standard (C) layout.
        Some(s) => s.to_vec(),
        // Iterating with a fixed number of dimensions is ~30× faster than with IxDyn.
        None => match shape.len() {
            1 => match view.into_dimensionality::<Ix1>() {
                Ok(v) => v.iter().copied().collect(),
                Err(_) => Vec::new(),
            },
            2 => match view.into_dimensionality::<Ix2>() {
                // F order (e.g. `DataFrame.to_numpy()`): its transpose is C order, so a
                // tiled transpose of the buffer gives the row-major data.
                Ok(v) => match v.t().as_slice() {
                    Some(cols) => {
                        let (r, c) = (shape[0], shape[1]);
                        navfdi_core::linalg::from_row_major(c, r, cols)
                            .as_slice()
                            .to_vec()
                    }
                    None => v.iter().copied().collect(),
                },
                Err(_) => Vec::new(),
            },
            3 => match view.into_dimensionality::<Ix3>() {
                Ok(v) => v.iter().copied().collect(),
                Err(_) => Vec::new(),
            },
            _ => view.iter().copied().collect(),
        },
    };
    Array { shape, data }
}

/// Read any array-like of real numbers as float64, in logical (row-major) order.
///
/// Accepts float64 arrays of any memory layout (fast path), real arrays of other dtypes (cast)
/// and nested sequences of numbers. Complex, string and object data are refused naming `name`.
pub fn read(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Array> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        let ro = a
            .try_readonly()
            .map_err(|e| PyValueError::new_err(format!("{name}: cannot read the array: {e}")))?;
        return Ok(logical(ro.as_array()));
    }
    let py = obj.py();
    let arr: Bound<'_, PyAny> = if let Ok(u) = obj.cast::<PyUntypedArray>() {
        check_kind(name, u)?;
        obj.clone()
    } else {
        let np = py.import("numpy")?;
        let a = np.call_method1("asarray", (obj,)).map_err(|e| {
            if e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py) {
                return e;
            }
            PyValueError::new_err(format!(
                "{name}: expected an array of numbers, got an object of type {} ({e})",
                type_name(obj)
            ))
        })?;
        let u = a.cast::<PyUntypedArray>().map_err(|_| {
            PyValueError::new_err(format!(
                "{name}: expected an array of numbers, got an object of type {}",
                type_name(obj)
            ))
        })?;
        check_kind(name, u)?;
        a
    };
    let f: PyArrayLikeDyn<'_, f64, AllowTypeChange> = arr.extract().map_err(|_| {
        PyValueError::new_err(format!(
            "{name}: expected an array of numbers, got an object of type {}",
            type_name(obj)
        ))
    })?;
    Ok(logical(f.as_array()))
}

/// The fast path of [`vector`] and [`matrix`]: a float64 array in C order with `ndim`
/// dimensions, handed to `f` as its shape and row-major data without an intermediate copy;
/// None for anything else (which [`read`] then converts).
fn c_order<T>(
    obj: &Bound<'_, PyAny>,
    ndim: usize,
    f: impl FnOnce(&[usize], &[f64]) -> T,
) -> Option<T> {
    let a = obj.cast::<PyArrayDyn<f64>>().ok()?;
    if a.ndim() != ndim {
        return None;
    }
    let ro = a.try_readonly().ok()?;
    let view = ro.as_array();
    let data = view.as_slice()?; // Some only in standard (C) layout
    Some(f(view.shape(), data))
}

/// Read a 1-D array of length `len` (any length when `None`).
pub fn vector(name: &str, obj: &Bound<'_, PyAny>, len: Option<usize>) -> PyResult<DVector<f64>> {
    if let Some(v) = c_order(obj, 1, |shape, data| {
        (len.is_none_or(|l| shape[0] == l)).then(|| DVector::from_column_slice(data))
    })
    .flatten()
    {
        return Ok(v);
    }
    let a = read(name, obj)?;
    if a.shape.len() != 1 || len.is_some_and(|l| a.shape[0] != l) {
        let expected = match len {
            Some(l) => format!("({l},)"),
            None => "(n,)".to_string(),
        };
        return Err(PyValueError::new_err(format!(
            "{name}: expected shape {expected}, got {}",
            shape_str(&a.shape)
        )));
    }
    Ok(DVector::from_vec(a.data))
}

/// Read a 2-D array.
pub fn matrix(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<DMatrix<f64>> {
    if let Some(m) = c_order(obj, 2, |shape, data| {
        navfdi_core::linalg::from_row_major(shape[0], shape[1], data)
    }) {
        return Ok(m);
    }
    let a = read(name, obj)?;
    if a.shape.len() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name}: expected a 2-D array, got shape {}",
            shape_str(&a.shape)
        )));
    }
    Ok(navfdi_core::linalg::from_row_major(
        a.shape[0], a.shape[1], &a.data,
    ))
}

/// Read either one matrix (2-D) or a stack with one matrix per epoch (3-D).
pub fn matrix_seq(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<MatrixSeq> {
    let a = read(name, obj)?;
    match a.shape.len() {
        2 => Ok(MatrixSeq::Const(navfdi_core::linalg::from_row_major(a.shape[0], a.shape[1], &a.data))),
        3 => {
            let (t, r, c) = (a.shape[0], a.shape[1], a.shape[2]);
            let step = r * c;
            Ok(MatrixSeq::PerEpoch(
                (0..t).map(|k| DMatrix::from_row_slice(r, c, &a.data[k * step..(k + 1) * step])).collect(),
            ))
        }
        _ => Err(PyValueError::new_err(format!(
            "{name}: expected one matrix (2-D) or a stack with one matrix per epoch (3-D), got shape {}",
            shape_str(&a.shape)
        ))),
    }
}

/// Move row-major data into a new numpy array of the given shape (no copy of the buffer).
pub fn to_numpy<'py, T: numpy::Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArray<T, IxDyn>>> {
    PyArray::from_vec(py, data).reshape(IxDyn(shape))
}

/// A column-major matrix as a row-major numpy array.
pub fn matrix_to_numpy<'py>(
    py: Python<'py>,
    m: &DMatrix<f64>,
) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
    to_numpy(
        py,
        m.transpose().as_slice().to_vec(),
        &[m.nrows(), m.ncols()],
    )
}

/// A vector as a 1-D numpy array.
pub fn vector_to_numpy<'py>(
    py: Python<'py>,
    v: &DVector<f64>,
) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
    to_numpy(py, v.as_slice().to_vec(), &[v.len()])
}

/// A float as Python would show it in a repr: `nan`, `inf`, `-inf`, or up to 6 significant
/// digits (`1.01203`, `9.21034`, `5e+159`), never Rust's 160-digit expansion of a huge value.
pub fn py_float(v: f64) -> String {
    if v.is_nan() {
        return "nan".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if v == 0.0 {
        return "0.0".into();
    }
    let a = v.abs();
    if (1e-4..1e6).contains(&a) {
        let digits = (5 - a.log10().floor() as i32).clamp(0, 10) as usize;
        let s = format!("{v:.digits$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s.contains('.') {
            s
        } else {
            format!("{s}.0")
        }
    } else {
        let s = format!("{v:.5e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        let e: i32 = e.parse().unwrap_or(0);
        format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
    }
}

/// `True` / `False`.
pub fn py_bool(b: bool) -> &'static str {
    if b {
        "True"
    } else {
        "False"
    }
}

/// An optional value as Python shows it: the value, or `None`.
pub fn py_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or_else(|| "None".into(), |x| x.to_string())
}

/// A list of floats as Python shows it: `[1.0, nan]`.
pub fn py_floats(v: &[f64]) -> String {
    format!(
        "[{}]",
        v.iter()
            .map(|x| py_float(*x))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// A float argument, with an error that names it: `pf: expected a number (e.g. 0.001), got
/// str '1e-3'` (the plain extraction error says only "must be real number, not str").
pub fn float_arg(name: &str, v: &Bound<'_, PyAny>) -> PyResult<f64> {
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{name}: expected a number, got bool {}",
            v.repr().map(|r| r.to_string()).unwrap_or_default()
        )));
    }
    v.extract::<f64>().map_err(|_| {
        let ty = v
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "object".into());
        let r = v.repr().map(|r| r.to_string()).unwrap_or_default();
        pyo3::exceptions::PyTypeError::new_err(format!(
            "{name}: expected a number (e.g. 0.001), got {ty} {r}"
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_print_like_python() {
        assert_eq!(py_float(1.0), "1.0");
        assert_eq!(py_float(9.210340371976182), "9.21034");
        assert_eq!(py_float(f64::NAN), "nan");
        assert_eq!(py_float(f64::INFINITY), "inf");
        assert_eq!(py_float(5e159), "5e+159");
        assert_eq!(py_float(-2.5e-7), "-2.5e-07");
        assert_eq!(py_float(123456.7), "123457.0");
    }
}
