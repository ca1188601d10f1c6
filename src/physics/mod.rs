//! The mathematics of one block and of the global system, with no notion of contacts or time
//! stepping: what the solver's stages are built from.
//!
//! - [`geometry`]: convex hulls, polyhedron integrals (volume, centroid, second moments), the
//!   separating-axis overlap test, and the shapes a scene can name;
//! - [`hull`]: the convex hull itself, O(n log n): quickhull on exact predicates, coplanar
//!   triangles merged into faces;
//! - [`mechanics`]: Shi's 12-DOF first-order displacement function and the block submatrices
//!   (mass, elasticity, loads, fixed-point springs) of reference §1–3, and the finite-rotation
//!   update (1.3);
//! - [`integrator`]: the time step's inertia terms: Shi's step (3.2) and its dissipative
//!   Newmark relatives (rock-mass reference §4);
//! - [`linear`]: the block-sparse global matrix and its sparse Cholesky factorization.

pub mod geometry;
mod hull;
pub mod integrator;
pub mod linear;
pub mod mechanics;
