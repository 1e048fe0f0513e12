//! The one mapping of the core's error to Python: each kind of `gyrodrift_core::error::CoreError` is its own class
//! of `gyrodrift.errors` under `CoreError` (declared there, imported here), with the message, the offending
//! setting or input in its `key` attribute and the kind's other fields as attributes.

use gyrodrift_core::error::CoreError as CoreFailure;
use pyo3::prelude::*;

pyo3::import_exception!(gyrodrift.errors, CoreSettingError);
pyo3::import_exception!(gyrodrift.errors, CoreShapeError);
pyo3::import_exception!(gyrodrift.errors, CoreSampleError);
pyo3::import_exception!(gyrodrift.errors, CoreDivergedError);
pyo3::import_exception!(gyrodrift.errors, CoreIncompleteError);

/// The core's error as the `gyrodrift.errors` class of its kind: `key` always; `index` (Sample), `t_s`
/// (Diverged), `done` and `needed` (Incomplete).
pub(crate) fn core_err(e: CoreFailure) -> PyErr {
    let message = e.to_string();
    let err = match &e {
        CoreFailure::Setting { .. } => CoreSettingError::new_err(message),
        CoreFailure::Shape { .. } => CoreShapeError::new_err(message),
        CoreFailure::Sample { .. } => CoreSampleError::new_err(message),
        CoreFailure::Diverged { .. } => CoreDivergedError::new_err(message),
        CoreFailure::Incomplete { .. } => CoreIncompleteError::new_err(message),
    };
    Python::attach(|py| {
        let value = err.value(py);
        // Setting an attribute on a fresh exception instance cannot fail short of memory exhaustion; the
        // message alone is still a complete error then.
        let _ = value.setattr("key", e.key());
        let _ = match e {
            CoreFailure::Sample { index, .. } => value.setattr("index", index),
            CoreFailure::Diverged { t_s, .. } => value.setattr("t_s", t_s),
            CoreFailure::Incomplete { done, needed } => value
                .setattr("done", done)
                .and_then(|()| value.setattr("needed", needed)),
            CoreFailure::Setting { .. } | CoreFailure::Shape { .. } => Ok(()),
        };
    });
    err
}

/// A binding-side refusal (wrong argument type or shape) as a `gyrodrift.errors.CoreShapeError` naming `key`.
pub(crate) fn arg_err(key: &'static str, message: impl std::fmt::Display) -> PyErr {
    core_err(CoreFailure::Shape {
        key,
        message: message.to_string(),
    })
}
