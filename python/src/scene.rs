//! `dda3d.Scene`: a scene file read and validated, from a file, a dict or TOML text, with the
//! study's `key = value` overrides applied to its text before it is read.

use std::path::{Path, PathBuf};

use dda3d::scene::{self, Scene};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Kind, error};

/// A scene, read and checked as `dda3d run` reads it. Build one with `Scene.from_file`,
/// `Scene.from_dict` or `Scene.from_text`; a bad scene raises `SceneError` with the command's
/// one-line message.
#[pyclass(name = "Scene", module = "dda3d._native", frozen)]
pub struct PyScene {
    pub scene: Scene,
    /// The scene file's text (overrides applied).
    pub text: String,
    /// Where the scene came from, as messages name it: the path, `<dict>` or `<text>`.
    pub origin: String,
}

/// `{key: value}` as `(key, TOML value)` pairs, in the dict's order (through JSON, whose
/// numbers, strings, booleans and lists are TOML's).
fn override_pairs(
    py: Python<'_>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<(String, toml::Value)>> {
    let Some(d) = overrides else {
        return Ok(Vec::new());
    };
    let mut pairs = Vec::new();
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        let value = to_toml(py, &v).map_err(|m| error(Kind::Scene, format!("{key}: {m}")))?;
        pairs.push((key, value));
    }
    Ok(pairs)
}

/// A Python value (numbers, strings, booleans, lists and dicts of them) as a TOML value.
pub fn to_toml(py: Python<'_>, value: &Bound<'_, PyAny>) -> Result<toml::Value, String> {
    // allow_nan=False: json.dumps writes NaN and Infinity, which are not JSON, as bare words,
    // and serde_json's complaint about them ("expected value at line 1 column 7") names nothing.
    let kwargs = pyo3::types::PyDict::new(py);
    kwargs
        .set_item("allow_nan", false)
        .map_err(|e| e.to_string())?;
    let json: String = py
        .import("json")
        .and_then(|j| j.call_method("dumps", (value,), Some(&kwargs)))
        .and_then(|s| s.extract())
        .map_err(|e| match e.get_type(py).name() {
            Ok(n) if n == "ValueError" => {
                "a number is NaN or infinite: a scene takes finite numbers".to_string()
            }
            _ => e.to_string(),
        })?;
    let json: serde_json::Value = serde_json::from_str(&json).map_err(|e| e.to_string())?;
    toml::Value::try_from(json).map_err(|e| format!("not a TOML value: {e}"))
}

/// The scene text with `overrides` applied (the study key syntax).
fn apply(text: String, origin: &str, overrides: &[(String, toml::Value)]) -> PyResult<String> {
    if overrides.is_empty() {
        return Ok(text);
    }
    dda3d::study::override_scene_text(&text, overrides)
        .map_err(|m| error(Kind::Scene, format!("{origin}: {m}")))
}

impl PyScene {
    /// Reads `text` as a scene file named `origin` in messages (`default_name`: its name when
    /// the text sets none).
    fn parse(text: String, origin: &str, default_name: &str) -> PyResult<PyScene> {
        let scene = scene::parse(&text, origin, default_name)
            .map_err(|e| error(Kind::Scene, e.to_string()))?;
        Ok(PyScene {
            scene,
            text,
            origin: origin.to_string(),
        })
    }
}

#[pymethods]
impl PyScene {
    /// Reads the scene file at `path`; `overrides` (`{"joint.friction_angle": 30}`, the study
    /// key syntax) change its text before it is read.
    #[staticmethod]
    #[pyo3(signature = (path, overrides = None))]
    pub fn from_file(
        py: Python<'_>,
        path: PathBuf,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyScene> {
        let pairs = override_pairs(py, overrides)?;
        // Read once, as `dda3d run` reads it (its messages: missing, too large, not UTF-8),
        // then parsed from that text, changed by the overrides if any.
        let (text, origin, stem) = py
            .detach(|| scene::read_text(&path))
            .map_err(|e| error(Kind::Scene, e.to_string()))?;
        let text = if pairs.is_empty() {
            text
        } else {
            apply(text, &origin, &pairs)?
        };
        py.detach(|| Self::parse(text, &origin, &stem))
    }

    /// A scene from a dict in the scene file's structure (`{"solver": {"duration": 1.0},
    /// "blocks": [...]}`), written out as TOML text; `name` is its name unless the dict sets
    /// one.
    #[staticmethod]
    #[pyo3(signature = (d, name = None, overrides = None))]
    fn from_dict(
        py: Python<'_>,
        d: &Bound<'_, PyDict>,
        name: Option<String>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyScene> {
        let origin = "<dict>";
        let value =
            to_toml(py, d.as_any()).map_err(|m| error(Kind::Scene, format!("{origin}: {m}")))?;
        let text = toml::to_string(&value)
            .map_err(|e| error(Kind::Scene, format!("{origin}: not a scene: {e}")))?;
        let pairs = override_pairs(py, overrides)?;
        let name = name.unwrap_or_else(|| "scene".into());
        Self::parse(apply(text, origin, &pairs)?, origin, &name)
    }

    /// A scene from the text of a scene file; `origin` names it in messages.
    #[staticmethod]
    #[pyo3(signature = (text, origin = "<text>".to_string(), overrides = None))]
    fn from_text(
        py: Python<'_>,
        text: String,
        origin: String,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyScene> {
        let pairs = override_pairs(py, overrides)?;
        let name = default_name(Path::new(&origin));
        Self::parse(apply(text, &origin, &pairs)?, &origin, &name)
    }

    /// The scene's name (its `name`, else the file's stem).
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The blocks' names, in the order of the arrays of `Simulation.blocks()`.
    #[getter]
    fn block_names(&self) -> Vec<String> {
        self.scene
            .model
            .blocks
            .iter()
            .map(|b| b.name.clone())
            .collect()
    }

    /// Simulated time of a run, s (`[solver] duration`).
    #[getter]
    fn duration(&self) -> f64 {
        self.scene.params.duration
    }

    /// The contact method: "alm" (DDA-3a) or "penalty" (DDA-3p).
    #[getter]
    fn method(&self) -> &'static str {
        self.scene.params.method.as_str()
    }

    /// The scene file's text, overrides applied: what a study ships to a worker.
    #[getter]
    fn text(&self) -> String {
        self.text.clone()
    }

    /// Where the scene came from: its path, `<dict>` or `<text>`.
    #[getter]
    fn origin(&self) -> String {
        self.origin.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, {} blocks, from {})",
            self.scene.name,
            self.scene.model.blocks.len(),
            self.origin
        )
    }
}

/// A scene's name when it sets none: the file's stem, as `dda3d run` takes it.
fn default_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty() && !s.starts_with('<'))
        .unwrap_or_else(|| "scene".into())
}
