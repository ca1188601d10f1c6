//! dda3d — three-dimensional Discontinuous Deformation Analysis of jointed rock.
//!
//! The solver follows Shi's 3-D DDA with normal contacts enforced by the augmented Lagrangian
//! method of Zhang Hong (Chinese J. Geotech. Eng. 41(2), 2019), "DDA-3a"; the classic fixed-penalty
//! scheme ("DDA-3p") is kept as a baseline. Equation numbers (P1)…(P26) refer to that paper,
//! plain numbers such as (5.4) to `shared/docs/dda3d-reference.md`.
//!
//! Data flows one way: [`scene`] → [`solver`] → [`snapshot`] → [`render`] / [`output`].

pub mod bench;
pub mod cli;
pub mod contact;
pub mod generate;
pub mod geometry;
pub mod linear;
pub mod mechanics;
pub mod output;
pub mod params;
pub mod render;
pub mod scene;
pub mod snapshot;
pub mod solver;
pub mod ui;
