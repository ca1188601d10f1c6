//! The study's plots: each outcome against each varied parameter. A stub with the interface the
//! real module (written alongside) keeps: it writes nothing.

use std::path::{Path, PathBuf};

/// One column of the study table for plotting: a varied parameter or an outcome.
pub struct PlotColumn {
    pub name: String,
    /// None: failed case or not a number.
    pub values: Vec<Option<f64>>,
    /// Some: values are indexes into these labels (a grid of strings).
    pub categories: Option<Vec<String>>,
    pub log_scale: bool,
    pub unit: String,
}

/// Writes DIR/plots/<outcome>_vs_<parameter>.png for every pair, and DIR/plots/overview.png
/// (all pairs in one grid); returns the files written.
pub fn write_plots(
    dir: &Path,
    parameters: &[PlotColumn],
    outcomes: &[PlotColumn],
) -> Result<Vec<PathBuf>, String> {
    let _ = (dir, parameters, outcomes);
    Ok(vec![])
}
