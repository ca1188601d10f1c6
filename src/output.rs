//! Run outputs: `blocks.csv`, `contacts.csv` and `summary.json` (the command-line contract).

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::snapshot::Snapshot;
use crate::snapshot::{EquilibriumReport, RunTotals, Timings};

/// Streams one row per block and one per active contact for every completed step.
pub struct RunWriter {
    blocks: csv::Writer<BufWriter<File>>,
    contacts: csv::Writer<BufWriter<File>>,
    dir: PathBuf,
}

/// Shortest round-trip text of a number, in exponent form when it is tiny (penetrations of
/// 1e-16 m would otherwise print as thirty zeros).
fn num(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-4 {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

fn io_err(e: csv::Error) -> io::Error {
    io::Error::other(e)
}

impl RunWriter {
    /// Creates `dir` and the two CSV files with their headers.
    pub fn create(dir: &Path) -> io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let open = |name: &str| -> io::Result<csv::Writer<BufWriter<File>>> {
            Ok(csv::Writer::from_writer(BufWriter::new(File::create(
                dir.join(name),
            )?)))
        };
        let mut blocks = open("blocks.csv")?;
        blocks
            .write_record(["time", "block", "x", "y", "z", "vx", "vy", "vz"])
            .map_err(io_err)?;
        let mut contacts = open("contacts.csv")?;
        contacts
            .write_record([
                "time",
                "block_i",
                "block_j",
                "mode",
                "state",
                "px",
                "py",
                "pz",
                "nx",
                "ny",
                "nz",
                "normal_force",
                "shear_force",
                "penetration",
                "penalty",
                "lambda",
            ])
            .map_err(io_err)?;
        Ok(RunWriter {
            blocks,
            contacts,
            dir: dir.to_path_buf(),
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Appends the rows of one completed step.
    pub fn write(&mut self, s: &Snapshot) -> io::Result<()> {
        let t = num(s.time);
        for b in &s.blocks {
            let c = b.centroid;
            let v = b.velocity;
            self.blocks
                .write_record([
                    t.as_str(),
                    &b.name,
                    &num(c[0]),
                    &num(c[1]),
                    &num(c[2]),
                    &num(v[0]),
                    &num(v[1]),
                    &num(v[2]),
                ])
                .map_err(io_err)?;
        }
        for c in &s.contacts {
            let f = num;
            self.contacts
                .write_record([
                    t.clone(),
                    s.blocks[c.block_i].name.clone(),
                    s.blocks[c.block_j].name.clone(),
                    c.mode.as_str().to_string(),
                    c.state.as_str().to_string(),
                    f(c.point[0]),
                    f(c.point[1]),
                    f(c.point[2]),
                    f(c.normal[0]),
                    f(c.normal[1]),
                    f(c.normal[2]),
                    f(c.normal_force),
                    f(c.shear_force),
                    f(c.penetration),
                    f(c.penalty),
                    f(c.lambda),
                ])
                .map_err(io_err)?;
        }
        Ok(())
    }

    pub fn flush(&mut self) -> io::Result<()> {
        self.blocks.flush()?;
        self.contacts.flush()
    }
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    pub method: String,
    pub mode: String,
    /// "completed" or "diverged".
    pub status: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub steps: u64,
    pub simulated_time: f64,
    pub wall_seconds: f64,
    /// Largest penetration of a closed contact over the run beyond its kept overlap, m.
    pub max_penetration: f64,
    /// Largest overlap kept by a contact over the run, m (see `StepStats::max_overlap`).
    pub max_overlap: f64,
    pub open_close_iterations: u64,
    pub alm_iterations: u64,
    pub time_step_cuts: u64,
    pub factorizations: u64,
    pub symbolic_analyses: u64,
    pub contacts_per_step: f64,
    pub unconverged_steps: u64,
    pub alm_cap_hits: u64,
    /// Contacts settled after cycling between states within one attempt, or at the open–close
    /// pass limit.
    pub frozen_contacts: u64,
    /// Seconds spent in each phase.
    pub timings: Timings,
    /// The initial equilibrium stage (`[solver] initial_equilibrium`): its static steps, R_max
    /// at its end, and whether R_max fell below the tolerance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<EquilibriumReport>,
}

impl Summary {
    pub fn new(scene: &str, method: &str, mode: &str, time: f64, wall: f64, t: &RunTotals) -> Self {
        Summary {
            scene: scene.to_string(),
            method: method.to_string(),
            mode: mode.to_string(),
            status: "completed".into(),
            error: None,
            steps: t.steps,
            simulated_time: time,
            wall_seconds: wall,
            max_penetration: t.max_penetration,
            max_overlap: t.max_overlap,
            open_close_iterations: t.open_close_iterations,
            alm_iterations: t.alm_iterations,
            time_step_cuts: t.time_step_cuts,
            factorizations: t.factorizations,
            symbolic_analyses: t.symbolic_analyses,
            contacts_per_step: t.contacts_per_step,
            unconverged_steps: t.unconverged_steps,
            alm_cap_hits: t.alm_cap_hits,
            frozen_contacts: t.frozen_contacts,
            timings: t.timings.clone(),
            equilibrium: None,
        }
    }

    pub fn write(&self, dir: &Path) -> io::Result<()> {
        let mut f = BufWriter::new(File::create(dir.join("summary.json"))?);
        serde_json::to_writer_pretty(&mut f, self).map_err(io::Error::other)?;
        writeln!(f)?;
        f.flush()
    }
}

/// A directory name from a scene name: lower case, runs of other characters become '-'.
pub fn slug(name: &str) -> String {
    let mut s = String::new();
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            s.push(ch.to_ascii_lowercase());
        } else if !s.ends_with('-') {
            s.push('-');
        }
    }
    let s = s.trim_matches('-').to_string();
    if s.is_empty() { "scene".into() } else { s }
}

#[cfg(test)]
mod tests {
    #[test]
    fn slugs() {
        assert_eq!(
            super::slug("Block sliding on a 30 degree slope"),
            "block-sliding-on-a-30-degree-slope"
        );
        assert_eq!(super::slug("  ?? "), "scene");
    }
}
