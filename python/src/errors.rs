//! The exceptions raised from Rust. They are defined in Python (`dda3d/_errors.py`), where a
//! class can have two bases (`SceneError(Dda3dError, ValueError)`), and looked up here by name
//! when raised. Their messages are the command line's one-line messages, without `error: `.

use dda3d::cli::exit::Failure;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception classes of `dda3d._errors`.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// The base class: a failure that is neither the input, the run nor a file.
    Base,
    Scene,
    Solver,
    Output,
    /// Raised by the study natives only.
    Study,
    GpuUnavailable,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Base => "Dda3dError",
            Kind::Scene => "SceneError",
            Kind::Solver => "SolverError",
            Kind::Output => "OutputError",
            Kind::Study => "StudyError",
            Kind::GpuUnavailable => "GpuUnavailable",
        }
    }
}

/// An exception of `kind` with `message`.
pub fn error(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| {
        let class = py
            .import("dda3d._errors")
            .and_then(|m| m.getattr(kind.class_name()))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(class) => PyErr::from_type(class, message),
            // Only if the package's Python half is missing (the extension imported alone).
            Err(_) => PyRuntimeError::new_err(message),
        }
    })
}

/// A command's failure as the exception the package documents for it: bad input is a
/// `SceneError`, a diverged run a `SolverError`, a file an `OutputError`.
pub fn failure(f: Failure) -> PyErr {
    let kind = match f {
        Failure::Input(_) => Kind::Scene,
        Failure::Diverged(_) => Kind::Solver,
        Failure::Io(_) => Kind::Output,
        Failure::Failed(_) | Failure::Interrupted(..) => Kind::Base,
    };
    error(kind, f.message())
}
