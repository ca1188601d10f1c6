//! `dda3d._native`, the extension module of the Python package `dda3d` (built by maturin, see
//! `pyproject.toml`): scenes, simulations stepped from Python, frames rendered to arrays, and
//! the study natives the Ray and Dask runners of `dda3d.study` call. The Python side
//! (`python/dda3d/`) re-exports these and defines the exceptions raised here.
//!
//! The solver never runs with the GIL held: every step, run and render is inside
//! `Python::detach`, so other Python threads go on meanwhile.

mod errors;
mod render;
mod scene;
mod simulation;
mod study;

use pyo3::prelude::*;

/// The crate version and a hash of the sources this extension was built from (see build.rs).
const BUILD: &str = env!("DDA3D_BUILD");

/// A directory name from a name, as `dda3d run` and `dda3d study` name their default output
/// directories: lower case, runs of other characters as `-`, at most 100 characters.
#[pyfunction]
fn slug(name: &str) -> String {
    dda3d::output::slug(name)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::PyScene>()?;
    m.add_class::<simulation::PySimulation>()?;
    m.add_function(wrap_pyfunction!(slug, m)?)?;
    m.add("__build__", BUILD)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    study::register(m)?;
    Ok(())
}
