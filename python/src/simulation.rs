//! `dda3d.Simulation`: a run of a scene stepped from Python, its state read as NumPy arrays,
//! and (with `out`) the files of `dda3d run` written as it goes, through the command's own
//! code ([`RunSession`]).

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use dda3d::cli::RunSession;
use dda3d::render::Offscreen;
use dda3d::snapshot::Snapshot;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::failure;
use crate::render;
use crate::scene::PyScene;

/// How long the solver runs between two looks at Python's signal handlers, so that Ctrl-C
/// stops a long `run()` within this much wall time (the run stays usable where it stopped).
const SIGNAL_CHECK: Duration = Duration::from_millis(200);

/// A run of a scene, stepped from Python. With `out`, it writes blocks.csv, contacts.csv and
/// summary.json into that directory exactly as `dda3d run SCENE --out DIR` does (the same bytes
/// for the CSV files); summary.json is final once the run ends or `close()` is called.
#[pyclass(name = "Simulation", module = "dda3d._native")]
pub struct PySimulation {
    /// In a mutex only so the class is `Sync`; methods reach it through `&mut self`
    /// (`Mutex::get_mut`, no locking).
    session: Mutex<RunSession>,
    out: Option<PathBuf>,
    pub(crate) duration: f64,
    /// The off-screen target of the last `render` (kept: opening a GPU device takes time).
    pub(crate) target: Option<Mutex<Offscreen>>,
}

impl PySimulation {
    pub(crate) fn session(&mut self) -> &mut RunSession {
        self.session.get_mut().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn snapshot(&mut self) -> Snapshot {
        self.session().snapshot()
    }
}

/// `n` rows of 3 as an (n, 3) array.
fn rows3<'py>(
    py: Python<'py>,
    rows: impl Iterator<Item = [f64; 3]>,
) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f64> = rows.flatten().collect();
    let n = flat.len() / 3;
    Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any())
}

#[pymethods]
impl PySimulation {
    /// A run of `scene` (a `Scene`, or the path of a scene file), writing the outputs of
    /// `dda3d run` into `out` when given. Nothing is simulated until `step()` or `run()`.
    #[new]
    #[pyo3(signature = (scene, out = None))]
    fn new(py: Python<'_>, scene: &Bound<'_, PyAny>, out: Option<PathBuf>) -> PyResult<Self> {
        let scene = match scene.cast::<PyScene>() {
            Ok(s) => s.clone().unbind(),
            Err(_) => {
                let path: PathBuf = scene.extract()?;
                Py::new(py, PyScene::from_file(py, path, None)?)?
            }
        };
        let scene = scene.get();
        let duration = scene.scene.params.duration;
        let origin = PathBuf::from(&scene.origin);
        let session =
            RunSession::new(scene.scene.clone(), &origin, out.as_deref()).map_err(failure)?;
        Ok(PySimulation {
            session: Mutex::new(session),
            out,
            duration,
            target: None,
        })
    }

    /// One step (the first also runs the scene's initial equilibrium stage and writes the state
    /// the run starts from). Returns False, taking no step, once the run is over. Raises
    /// `SolverError` when the run diverges, `OutputError` when a file cannot be written.
    fn step(&mut self, py: Python<'_>) -> PyResult<bool> {
        let session = self.session();
        py.detach(|| session.step()).map_err(failure)
    }

    /// Steps until the simulated time reaches `until` (default: the scene's duration) or the
    /// run ends. Steps are those of `dda3d run` (never shortened to land on `until`), so the
    /// time reached may pass `until` by part of a step. Returns the time reached. Ctrl-C stops
    /// it after a step (KeyboardInterrupt); the simulation can go on from there.
    #[pyo3(signature = (until = None))]
    fn run(&mut self, py: Python<'_>, until: Option<f64>) -> PyResult<f64> {
        let until = until.unwrap_or(self.duration);
        loop {
            let session = self.session();
            let deadline = Instant::now() + SIGNAL_CHECK;
            let there = py
                .detach(|| session.advance(until, Some(deadline)))
                .map_err(failure)?;
            if there {
                return Ok(self.session().solver().time);
            }
            py.check_signals()?;
        }
    }

    /// Ends the run: rows committed and summary.json final (status "interrupted" when it
    /// stopped short of its duration). Also done when the run ends, on `with` exit, and when
    /// the simulation is garbage-collected.
    fn close(&mut self, py: Python<'_>) -> PyResult<()> {
        let session = self.session();
        py.detach(|| session.close()).map_err(failure)
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(
        &mut self,
        py: Python<'_>,
        _args: &Bound<'_, pyo3::types::PyTuple>,
    ) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    /// Simulated time, s.
    #[getter]
    fn time(&mut self) -> f64 {
        self.session().solver().time
    }

    /// Completed steps (summary.json's `steps`).
    #[getter]
    fn steps(&mut self) -> u64 {
        self.session().solver().totals.steps
    }

    /// The run is over: it reached its duration, diverged, or was closed.
    #[getter]
    fn finished(&mut self) -> bool {
        self.session().finished()
    }

    /// The scene's duration, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.duration
    }

    /// The output directory, or None.
    #[getter]
    fn out(&self) -> Option<PathBuf> {
        self.out.clone()
    }

    /// The blocks now, N of them, in the scene's order: `names` (list of str), `fixed` (N,)
    /// bool, `centroids`, `velocities`, `displacements` (N, 3) float64 (m, m/s, m since t = 0),
    /// `volumes` (N,) float64 (m³), `vertices` (list of N (k_i, 3) float64 arrays, m) and
    /// `faces` (list of N lists of faces, each a list of vertex indices, counter-clockwise seen
    /// from outside).
    fn blocks<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.snapshot();
        let d = PyDict::new(py);
        let b = &s.blocks;
        d.set_item(
            "names",
            b.iter().map(|b| b.name.clone()).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "fixed",
            PyArray1::from_vec(py, b.iter().map(|b| b.fixed).collect()),
        )?;
        d.set_item("centroids", rows3(py, b.iter().map(|b| b.centroid))?)?;
        d.set_item("velocities", rows3(py, b.iter().map(|b| b.velocity))?)?;
        d.set_item(
            "displacements",
            rows3(py, b.iter().map(|b| b.displacement))?,
        )?;
        d.set_item(
            "volumes",
            PyArray1::from_vec(py, b.iter().map(|b| b.volume).collect()),
        )?;
        let vertices = PyList::empty(py);
        for block in b {
            vertices.append(rows3(py, block.vertices.iter().copied())?)?;
        }
        d.set_item("vertices", vertices)?;
        d.set_item(
            "faces",
            b.iter().map(|b| b.faces.clone()).collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// The closed contacts now, M of them: `block_i`, `block_j` (M,) int64 (indices into
    /// `blocks()`; i owns the vertex or first edge, j the face or second edge), `points` (M, 3)
    /// (on block j, m), `normals` (M, 3) (unit, out of j toward i), `normal_force` (N,
    /// compressive positive), `shear_force` (N), `penetration` (m, overlap positive), all
    /// float64 (M,), and `state` and `mode` (lists of str: "lock"/"slide",
    /// "vertex-face"/"edge-edge"), as in contacts.csv.
    fn contacts<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.snapshot();
        let c = &s.contacts;
        let d = PyDict::new(py);
        let index = |f: fn(&dda3d::snapshot::ContactSnapshot) -> usize| {
            PyArray1::from_vec(py, c.iter().map(|x| f(x) as i64).collect())
        };
        let number = |f: fn(&dda3d::snapshot::ContactSnapshot) -> f64| {
            PyArray1::from_vec(py, c.iter().map(f).collect())
        };
        d.set_item("block_i", index(|x| x.block_i))?;
        d.set_item("block_j", index(|x| x.block_j))?;
        d.set_item("points", rows3(py, c.iter().map(|x| x.point))?)?;
        d.set_item("normals", rows3(py, c.iter().map(|x| x.normal))?)?;
        d.set_item("normal_force", number(|x| x.normal_force))?;
        d.set_item("shear_force", number(|x| x.shear_force))?;
        d.set_item("penetration", number(|x| x.penetration))?;
        let names = |f: fn(&dda3d::snapshot::ContactSnapshot) -> &'static str| {
            c.iter().map(f).collect::<Vec<_>>()
        };
        d.set_item("state", names(|x| x.state.as_str()))?;
        d.set_item("mode", names(|x| x.mode.as_str()))?;
        Ok(d)
    }

    /// The state now drawn off-screen as `dda3d render` draws a frame: a (height, width, 4)
    /// uint8 RGBA array, top row first. `camera`: "az,el[,dist]" as `render --camera`, or a
    /// dict with any of `azimuth`, `elevation` (degrees), `distance` (m), `target` ([x, y, z],
    /// m), `fov` (degrees). Raises `GpuUnavailable` when there is no GPU adapter.
    #[pyo3(signature = (width = 1280, height = 720, camera = None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        width: u32,
        height: u32,
        camera: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rgba = render::rgba(self, py, (width, height), camera)?;
        let (h, w) = (height as usize, width as usize);
        Ok(PyArray1::from_vec(py, rgba).reshape([h, w, 4])?.into_any())
    }

    /// `render()` written to a PNG file at `path` (RGB, as `dda3d render` writes frames).
    #[pyo3(signature = (path, width = 1280, height = 720, camera = None))]
    fn render_png(
        &mut self,
        py: Python<'_>,
        path: PathBuf,
        width: u32,
        height: u32,
        camera: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let rgba = render::rgba(self, py, (width, height), camera)?;
        py.detach(|| render::png(&path, &rgba, (width, height)))
    }

    fn __repr__(&mut self) -> String {
        let s = self.session().solver();
        format!(
            "Simulation({:?}, t = {} s of {} s, {} steps)",
            s.model.name, s.time, s.params.duration, s.totals.steps
        )
    }
}
