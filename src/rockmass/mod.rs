//! Rock masses: the geometry of jointed rock, independent of the run.
//!
//! - [`orientation`]: dip and dip direction, and the planes of a joint set (seeded variation);
//! - [`cut`]: a convex domain cut into convex blocks by joint planes;
//! - [`report`]: what cutting a rock mass gave (blocks, volumes, slivers);
//! - [`wedge`]: the Hoek–Bray tetrahedral wedge, the closed form the cut blocks are checked
//!   against.
//!
//! Equation tags (R…) refer to `shared/docs/rock-mass-reference.md`.

pub mod cut;
pub mod orientation;
pub mod report;
pub mod wedge;
