//! `dda3d study`: many runs of one scene with parameters varied, and their outcomes.

pub mod plots;
