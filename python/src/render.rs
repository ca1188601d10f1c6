//! `Simulation.render` and `render_png`: one frame drawn with the capture's look
//! ([`dda3d::render::render_rgba`]) on an off-screen target the simulation keeps.

use std::path::Path;
use std::sync::Mutex;

use dda3d::render::capture::{render_rgba, write_png};
use dda3d::render::{CameraOverride, CaptureOptions, Gpu, Offscreen, RenderError};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Kind, error};
use crate::simulation::PySimulation;

/// A render failure as its exception: no adapter is `GpuUnavailable`, bad options a
/// `ValueError`, a file an `OutputError`, the rest the base `Dda3dError`.
fn render_error(e: RenderError) -> PyErr {
    match e {
        RenderError::NoAdapter => error(Kind::GpuUnavailable, e.to_string()),
        RenderError::InvalidOptions(_) => PyValueError::new_err(e.to_string()),
        RenderError::Io { .. } | RenderError::Encode(_) => error(Kind::Output, e.to_string()),
        other => error(Kind::Base, other.to_string()),
    }
}

/// `camera` as `render --camera` takes it ("az,el[,dist]"), or a dict of its parts.
fn camera_override(camera: Option<&Bound<'_, PyAny>>) -> PyResult<CameraOverride> {
    let Some(camera) = camera else {
        return Ok(CameraOverride::default());
    };
    if let Ok(text) = camera.extract::<String>() {
        return CameraOverride::parse(&text).map_err(PyValueError::new_err);
    }
    let d = camera.cast::<PyDict>().map_err(|_| {
        PyValueError::new_err("camera: expected \"az,el[,dist]\" or a dict of azimuth, elevation, distance, target, fov")
    })?;
    let mut o = CameraOverride::default();
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        match key.as_str() {
            "azimuth" => o.azimuth_deg = Some(v.extract()?),
            "elevation" => o.elevation_deg = Some(v.extract()?),
            "distance" => o.distance = Some(v.extract()?),
            "target" => o.target = Some(v.extract()?),
            "fov" => o.fov_y_deg = Some(v.extract()?),
            other => {
                return Err(PyValueError::new_err(format!(
                    "camera: unknown key {other:?} (azimuth, elevation, distance, target, fov)"
                )));
            }
        }
    }
    Ok(o)
}

/// The simulation's state drawn at `size`: width × height × 4 bytes of RGBA.
pub fn rgba(
    sim: &mut PySimulation,
    py: Python<'_>,
    (width, height): (u32, u32),
    camera: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<u8>> {
    if width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "image size must be positive, got {width}x{height}"
        )));
    }
    let mut opts = CaptureOptions::new(".");
    opts.width = width;
    opts.height = height;
    opts.camera = camera_override(camera)?;
    let snapshot = sim.snapshot();
    let reuse = sim
        .target
        .as_mut()
        .map(|t| t.get_mut().unwrap_or_else(|p| p.into_inner()))
        .filter(|t| t.size() == (width, height));
    let mut target = match reuse {
        Some(t) => {
            py.detach(|| render_rgba(t, &snapshot, &opts))
                .map_err(render_error)?
                .0
        }
        None => {
            let mut off = py
                .detach(|| {
                    Gpu::headless().and_then(|gpu| {
                        Offscreen::with_max_samples(gpu, width, height, opts.max_msaa_samples)
                    })
                })
                .map_err(render_error)?;
            let pixels = py
                .detach(|| render_rgba(&mut off, &snapshot, &opts))
                .map_err(render_error)?
                .0;
            sim.target = Some(Mutex::new(off));
            pixels
        }
    };
    target.truncate(width as usize * height as usize * 4);
    Ok(target)
}

/// RGBA pixels written to `path` as a PNG.
pub fn png(path: &Path, rgba: &[u8], (width, height): (u32, u32)) -> PyResult<()> {
    write_png(path, rgba, width, height, false).map_err(render_error)
}
