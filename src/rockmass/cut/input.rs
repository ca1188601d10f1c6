//! Checking the input of a cut, and turning a region into the first block.

use super::split::{self, Block, Face};
use super::{CutError, CutOptions, NORMAL_TOLERANCE, Plane, Polyhedron, REGION_TOLERANCE};
use crate::physics::geometry::bounding_box;

pub(super) fn check_options(opts: &CutOptions) -> Result<(), CutError> {
    if !(opts.min_volume.is_finite() && opts.min_volume >= 0.0) {
        return Err(CutError::InvalidOptions {
            reason: "min_volume must be a finite number ≥ 0",
        });
    }
    // An infinite max_aspect switches the aspect rule off (the thin floor stays).
    if opts.max_aspect.is_nan() || opts.max_aspect <= 0.0 {
        return Err(CutError::InvalidOptions {
            reason: "max_aspect must be a positive number",
        });
    }
    Ok(())
}

pub(super) fn check_planes(sets: &[Vec<Plane>]) -> Result<(), CutError> {
    for (set, planes) in sets.iter().enumerate() {
        for (plane, p) in planes.iter().enumerate() {
            let unit = (p.normal.norm() - 1.0).abs() <= NORMAL_TOLERANCE;
            if !(p.offset.is_finite() && p.normal.iter().all(|c| c.is_finite()) && unit) {
                return Err(CutError::InvalidPlane { set, plane });
            }
        }
    }
    Ok(())
}

/// The block of region `index` and its volume, after checking that the region is a closed,
/// convex polyhedron with outward faces. Vertices that no face uses are left out. `eps` is the
/// call's snap tolerance (it only sets the scale of the degenerate-face test here).
pub(super) fn region_block(
    index: usize,
    region: &Polyhedron,
    eps: f64,
) -> Result<(Block, f64), CutError> {
    let bad = |reason| CutError::InvalidRegion {
        region: index,
        reason,
    };
    let verts = &region.vertices;
    if verts.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
        return Err(bad("a vertex is not finite"));
    }
    if region.faces.len() < 4 {
        return Err(bad("fewer than 4 faces"));
    }
    if region
        .faces
        .iter()
        .any(|f| f.len() < 3 || f.iter().any(|&i| i >= verts.len()))
    {
        return Err(bad(
            "a face has fewer than 3 vertices or a vertex index out of range",
        ));
    }
    if !closed(&region.faces) {
        return Err(bad(
            "not closed: an edge is not shared by exactly two faces in opposite directions",
        ));
    }
    let (lo, hi) = bounding_box(region.faces.iter().flatten().map(|&i| &verts[i]));
    let tol = REGION_TOLERANCE * (hi - lo).norm();
    let mut faces = Vec::with_capacity(region.faces.len());
    for ring in &region.faces {
        let normal = split::newell(verts, ring);
        if normal.norm() <= eps * eps {
            return Err(bad("a face has no area"));
        }
        let normal = normal.normalize();
        let offset = ring.iter().map(|&i| normal.dot(&verts[i])).sum::<f64>() / ring.len() as f64;
        // Every vertex on the inner side of every face plane: convex, planar faces, outward.
        if region
            .faces
            .iter()
            .flatten()
            .any(|&i| normal.dot(&verts[i]) - offset > tol)
        {
            return Err(bad(
                "not convex, or a face is not planar, or faces are listed clockwise seen from \
                 outside",
            ));
        }
        faces.push(Face {
            ring: ring.clone(),
            tag: None,
            normal,
            offset,
        });
    }
    let block = Block::compact(index, verts, faces);
    let (volume, _) =
        split::volume_centroid(&block.verts, block.faces.iter().map(|f| f.ring.as_slice()));
    if volume.is_nan() || volume <= 0.0 {
        return Err(bad("no volume"));
    }
    Ok((block, volume))
}

/// Every directed edge is used once and its reverse once: a closed, consistently oriented
/// surface.
fn closed(faces: &[Vec<usize>]) -> bool {
    let mut edges: Vec<(usize, usize)> = faces
        .iter()
        .flat_map(|ring| {
            ring.iter()
                .zip(ring.iter().cycle().skip(1))
                .map(|(&a, &b)| (a, b))
        })
        .collect();
    edges.sort_unstable();
    let unique = edges.windows(2).all(|w| w[0] != w[1]);
    unique
        && edges
            .iter()
            .all(|&(a, b)| a != b && edges.binary_search(&(b, a)).is_ok())
}
