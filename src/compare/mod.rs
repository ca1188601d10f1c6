//! Two runs of the same scene, A and B, side by side: the paper's whole argument is DDA-3a
//! against DDA-3p on one model (its Tables 1 and 2). `dda3d run SCENE --compare penalty`
//! drives it headless; the pieces here are plain functions of settings and snapshots, so the
//! viewer and `render` can use them too.
//!
//! - [`spec`]: what B changes of A (`--compare alm|penalty`, `--compare-set key=value,...`),
//!   checked as the scene file is;
//! - [`labels`]: the settings that tell A and B apart, as `name=value` labels, and the
//!   captions of A's and B's pictures;
//! - [`sample`]: what a comparison keeps of a run at one time, and that state between two
//!   steps (each run keeps its own steps);
//! - [`difference`]: A and B at one time (largest block displacement difference, contact
//!   force difference, penetration, kinetic energy);
//! - [`slope`]: scenes with a closed form (one free block on one fixed slope), recognised from
//!   their geometry;
//! - [`tables`]: the paper's Table 1 (standing block) and Table 2 (sliding block);
//! - [`report`]: the file `compare.json`.
//!
//! Data flow: the compare module reads the solver (a model's masses, for the closed forms),
//! snapshots and parameters; it writes no file and knows no front end.

pub mod difference;
pub mod labels;
pub mod report;
pub mod sample;
pub mod slope;
pub mod spec;
pub mod tables;

pub use difference::{Comparison, compare, compare_snapshots};
pub use labels::{Difference, caption, differences, labels, method_name};
pub use report::{Recorder, Report, RunReport};
pub use sample::Sample;
pub use slope::{Motion, SlopeCase};
pub use spec::{CompareSpec, SpecError};
