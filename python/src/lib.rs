//! Python bindings for whycode: `import whycode`.
//!
//! Every entry point runs its Rust work inside [`guard`], so a bug that
//! panics becomes a `whycode.WhycodeError` rather than a dead interpreter,
//! and errors keep the command line's one-line messages.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use std::panic::{catch_unwind, AssertUnwindSafe};

mod arena;
mod calibrate;
mod camera;
mod detector;
mod family;
mod pixels;
mod recording;
mod render;
mod simulate;
mod validate;

static WHYCODE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static VALUE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static OS_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static DETECTIONS: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `whycode.Detections`, the list `Detector.detect` returns.
pub(crate) fn detections_type<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyType>> {
    DETECTIONS
        .get(py)
        .map(|ty| ty.bind(py).clone())
        .ok_or_else(|| pyo3::exceptions::PyRuntimeError::new_err("whycode is not initialised"))
}

/// An error on its way to Python: bad input (ValueError) or a file that
/// could not be read or written (OSError), with its one-line message.
#[derive(Debug)]
pub(crate) enum Error {
    Value(String),
    Os(String),
    Internal(String),
}

impl Error {
    pub(crate) fn value(message: impl Into<String>) -> Error {
        Error::Value(message.into())
    }
}

/// The message every front end shows for `err`.
fn message(err: &(dyn std::error::Error + 'static)) -> String {
    whycode::error::one_line(err)
}

impl From<whycode::LoadError> for Error {
    fn from(err: whycode::LoadError) -> Error {
        if err.is_io() {
            Error::Os(message(&err))
        } else {
            Error::Value(message(&err))
        }
    }
}

impl From<whycode::WriteError> for Error {
    fn from(err: whycode::WriteError) -> Error {
        use whycode::WriteError::*;
        match err {
            // Asked to write over its own input: the arguments are wrong.
            WouldOverwriteInput { .. } | SameFileTwice { .. } => Error::Value(message(&err)),
            _ => Error::Os(message(&err)),
        }
    }
}

impl From<whycode::image_io::ImageWriteError> for Error {
    fn from(err: whycode::image_io::ImageWriteError) -> Error {
        match err {
            whycode::image_io::ImageWriteError::Write(err) => err.into(),
            other => Error::Value(message(&other)),
        }
    }
}

/// Errors that are always about the values given, never the file system.
macro_rules! value_errors {
    ($($t:ty),*) => {$(
        impl From<$t> for Error {
            fn from(err: $t) -> Error {
                Error::Value(message(&err))
            }
        }
    )*};
}
value_errors!(
    whycode::render::RenderError,
    whycode::validate::UnvalidatableSheet,
    whycode::OtherCamera,
    whycode::family::FamilyError
);

/// A library spec's error in Python's words: the keyword as it is spelled
/// here (`camera_distance: ...`); a file that could not be read is an
/// `OSError`, anything else a `ValueError`.
pub(crate) fn spec_error(err: whycode::spec::SpecError) -> Error {
    let message = whycode::error::shorten_words(&err.message_with(str::to_string));
    if err.is_io() {
        Error::Os(message)
    } else {
        Error::Value(message)
    }
}

impl From<whycode::render::job::PrintError> for Error {
    fn from(err: whycode::render::job::PrintError) -> Error {
        match err {
            whycode::render::job::PrintError::Option(err) => spec_error(err),
            whycode::render::job::PrintError::Render(
                err @ whycode::render::RenderError::SelfCheck { .. },
            ) => Error::Value(format!(
                "{err} (nothing written; check=False skips the check)"
            )),
            whycode::render::job::PrintError::Render(err) => err.into(),
        }
    }
}

impl From<Error> for PyErr {
    fn from(err: Error) -> PyErr {
        Python::attach(|py| {
            let (cell, message) = match err {
                Error::Value(m) => (&VALUE_ERROR, m),
                Error::Os(m) => (&OS_ERROR, m),
                Error::Internal(m) => (&WHYCODE_ERROR, m),
            };
            match cell.get(py) {
                Some(ty) => PyErr::from_type(ty.bind(py).clone(), message),
                None => pyo3::exceptions::PyRuntimeError::new_err(message),
            }
        })
    }
}

pub(crate) type Result<T> = std::result::Result<T, Error>;

/// Runs `f`, turning a panic into an error: a Python caller must never lose
/// its interpreter to a bug here.
pub(crate) fn guard<T>(f: impl FnOnce() -> Result<T>) -> Result<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(result) => result,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(Error::Internal(format!(
                "internal error (please report it): {what}"
            )))
        }
    }
}

/// Parses JSON text into Python objects with the standard `json` module, so
/// floats come out exactly as `json.loads` of the CLI's output would.
pub(crate) fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// A quantity argument, read as the command line reads it: text as typed
/// there ("50mm", "30deg", "97%"), and a number as that number typed
/// without a unit. One rule for every quantity in both front ends, and the
/// command line's words when it is refused (`tilt=30` is refused as
/// `--tilt 30` is; `Detector(diameter=0.05)` is metres, as `detect
/// --diameter 0.05` is).
pub(crate) fn quantity<T, E: std::fmt::Display>(
    value: &Bound<'_, PyAny>,
    what: &str,
    parse: impl Fn(&str) -> std::result::Result<T, E>,
) -> PyResult<T> {
    let text = if let Ok(text) = value.extract::<String>() {
        text
    } else if let Ok(number) = value.extract::<f64>() {
        whycode::units::format_number(number)
    } else {
        return Err(Error::value(format!(
            "{what}: expected a number or text with a unit, like '50mm' or '30deg'"
        ))
        .into());
    };
    parse(&text).map_err(|e| Error::value(format!("{what}: {e}")).into())
}

/// A length that needs a unit, as the command line's `--diameter` of
/// `marker` and `sheet` does.
pub(crate) fn length(value: &Bound<'_, PyAny>, what: &str) -> PyResult<whycode::units::Length> {
    quantity(value, what, str::parse)
}

/// A length whose bare numbers are metres, as the command line's `detect
/// --diameter` and `arena --size` take it.
pub(crate) fn metres(value: &Bound<'_, PyAny>, what: &str) -> PyResult<whycode::units::Length> {
    quantity(value, what, whycode::units::Length::parse_metres)
}

/// A class made at run time, `type(name, bases, {...})`: the exceptions
/// and `Detections`, which derive from Python's own types.
fn derived_type<'py>(
    py: Python<'py>,
    name: &str,
    bases: Vec<Bound<'py, PyAny>>,
    doc: &str,
) -> PyResult<Bound<'py, PyType>> {
    let namespace = PyDict::new(py);
    namespace.set_item("__module__", "whycode")?;
    namespace.set_item("__doc__", doc)?;
    let ty = py.import("builtins")?.getattr("type")?.call1((
        name,
        PyTuple::new(py, bases)?,
        namespace,
    ))?;
    Ok(ty.cast_into::<PyType>()?)
}

#[pymodule]
fn _whycode(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let base = derived_type(
        py,
        "WhycodeError",
        vec![py.get_type::<pyo3::exceptions::PyException>().into_any()],
        "Base of every error whycode raises.",
    )?;
    let value = derived_type(
        py,
        "WhycodeValueError",
        vec![
            base.clone().into_any(),
            py.get_type::<pyo3::exceptions::PyValueError>().into_any(),
        ],
        "Bad input: an argument, an array or a file's contents.",
    )?;
    let os = derived_type(
        py,
        "WhycodeOSError",
        vec![
            base.clone().into_any(),
            py.get_type::<pyo3::exceptions::PyOSError>().into_any(),
        ],
        "A file could not be read or written.",
    )?;
    m.add("WhycodeError", &base)?;
    m.add("WhycodeValueError", &value)?;
    m.add("WhycodeOSError", &os)?;
    let _ = WHYCODE_ERROR.set(py, base.unbind());
    let _ = VALUE_ERROR.set(py, value.unbind());
    let _ = OS_ERROR.set(py, os.unbind());

    // A plain list, so that code written for `detect()`'s list keeps
    // working, with the frame's board poses beside the markers.
    let detections = derived_type(
        py,
        "Detections",
        vec![py.get_type::<pyo3::types::PyList>().into_any()],
        "The markers of one frame (a list of Marker), with the poses of the \
         Detector's boards in `boards` (dicts as `whycode detect --board` \
         writes them; empty without boards) and in `legacy_looking` the \
         number of discs that looked like legacy WhyCon markers while \
         WhyCode ones were looked for (Detector(legacy=True) reads them).",
    )?;
    m.add("Detections", &detections)?;
    let _ = DETECTIONS.set(py, detections.unbind());

    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    family::register(m)?;
    camera::register(m)?;
    arena::register(m)?;
    calibrate::register(m)?;
    detector::register(m)?;
    render::register(m)?;
    validate::register(m)?;
    simulate::register(m)?;
    recording::register(m)?;
    Ok(())
}
