//! dda3d — three-dimensional Discontinuous Deformation Analysis of jointed rock.
//!
//! The solver follows Shi's 3-D DDA with normal contacts enforced by the augmented Lagrangian
//! method of Zhang Hong (Chinese J. Geotech. Eng. 41(2), 2019), "DDA-3a"; the classic fixed-penalty
//! scheme ("DDA-3p") is kept as a baseline. Equation numbers (P1)…(P26) refer to that paper,
//! plain numbers such as (5.4) to `shared/docs/dda3d-reference.md`.
//!
//! Data flows one way:
//!
//! ```text
//! rockmass ─┐
//! scene ──▶ model ──▶ solver (activate → assemble → ALM / open–close → step control → commit)
//!                        │  uses physics (geometry, mechanics, linear) and contact
//!                        ▼
//!                     snapshot ──▶ output (CSV, JSON)
//!                              ├─▶ render (wgpu) ──▶ viewer (egui, winit)
//!                              └─▶ compare (two runs side by side, the paper's tables)
//! ```
//!
//! [`params`] holds every tunable; [`cli`] is the binary's front end, [`generate`] and [`bench`]
//! its scene generator and benchmark, [`study`] its parameter studies (a scene run many times
//! with keys varied: scene → solver → a table of outcomes), [`files`] the output directories
//! they all make.

pub mod bench;
pub mod cli;
pub mod compare;
pub mod contact;
pub mod files;
pub mod generate;
pub mod model;
pub mod output;
pub mod params;
pub mod physics;
pub mod render;
pub mod rockmass;
pub mod scene;
pub mod snapshot;
pub mod solver;
pub mod study;
pub mod text;
pub mod viewer;
