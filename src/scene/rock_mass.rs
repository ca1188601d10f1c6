//! `[[rock_masses]]`: a domain of convex regions cut into blocks by persistent joint sets
//! ([`crate::rockmass`]), and `[[joint_sets]]`, the planes of a cut rock mass written out by
//! `dda3d cut`. Both end as [`CutSet`]s, whose planes tag the faces of the rock mass's blocks
//! ([`tag_faces`]), so that a scene and its `cut` output load to the same model.
//!
//! Blocks of a rock mass are named `mass/1`, `mass/2`, … in the cutter's order
//! ([`crate::rockmass::cut`]): by region, then by the planes of each set below the block (set
//! by set, in the file's order), then by centroid.

use nalgebra::Vector3;

/// The smallest spacing, relative to its origin's largest coordinate, that a joint set may
/// have: f64's 16 digits, less a margin (as for a block's size against its coordinates).
const ORIGIN_RESOLUTION: f64 = 1e-9;

use super::build::shape_points;
use super::format::{FixedSpec, JointSetSpec, PlanesSpec, RockMassSpec};
use crate::model::{Block, JointFace, RockMassOf};
use crate::params::JointParams;
use crate::params::table::{COHESION, FRICTION_ANGLE};
use crate::physics::geometry::{Vec3, bounding_box, convex_hull, overlap_depth};
use crate::rockmass::cut::{self, CutOptions, Plane, Polyhedron};
use crate::rockmass::orientation::{SetGeometry, planes_through};
use crate::rockmass::report::RockMassReport;
use crate::text::short;

/// The largest tilt of a joint set's planes (`orientation_deviation`), degrees: beyond it the
/// "set" is no longer a set of near-parallel planes.
pub const MAX_ORIENTATION_DEVIATION: f64 = 45.0;

/// The default `max_aspect`: a cut is not made where it would leave a piece thinner than a
/// thirtieth of its extent (a sliver), as UnBlocks-gen's example (rock-mass reference §2.3).
pub const DEFAULT_MAX_ASPECT: f64 = 30.0;

/// The default `min_volume`, as a fraction of the median block's volume (reference §2.3).
pub const DEFAULT_MIN_VOLUME_FRACTION: f64 = 1e-3;

/// A joint set ready to tag faces: its properties and planes, and the rock mass it cuts.
pub(super) struct CutSet {
    pub(super) name: String,
    pub(super) rock_mass: u16,
    pub(super) joint: JointParams,
    pub(super) planes: Vec<Plane>,
}

/// A block cut from a rock mass, before it is built.
pub(super) struct CutBlock {
    pub(super) name: String,
    pub(super) fixed: bool,
    pub(super) vertices: Vec<Vec3>,
    pub(super) rock_mass: RockMassOf,
}

/// A rock mass cut: its blocks and sets.
pub(super) struct CutMass {
    pub(super) blocks: Vec<CutBlock>,
    pub(super) sets: Vec<CutSet>,
    pub(super) report: RockMassReport,
}

/// Cuts rock mass number `index` (of the scene's rock masses). Errors are the problem alone,
/// with the key they concern when there is one (for the line).
pub(super) fn cut_mass(
    spec: &RockMassSpec,
    index: u16,
    default_joint: &JointParams,
    max_blocks: usize,
) -> Result<CutMass, String> {
    check_fixed(&spec.fixed)?;
    let regions = regions(spec)?;
    let points: Vec<Vec3> = regions
        .iter()
        .flat_map(|r| r.vertices.iter().copied())
        .collect();
    // The cut's own ε: a plane that only touches the domain within it cuts nothing.
    let snap = cut::snap_tolerance(&regions);
    let mut sets = Vec::with_capacity(spec.joint_sets.len());
    let mut names = std::collections::HashSet::new();
    for s in &spec.joint_sets {
        let set = s.get_ref();
        if !names.insert(set.name.as_str()) {
            return Err(format!("joint set name '{}' is used twice", set.name));
        }
        let joint = joint_of(
            &set.name,
            set.friction_angle,
            set.cohesion,
            default_joint,
            "joint_sets",
        )?;
        let geometry = set_geometry(set)?;
        let planes = planes_through(&geometry, &points, snap, max_blocks).map_err(|n| {
            format!(
                "joint set '{}': more than {n} planes cross the domain, more than the limit \
                     of {max_blocks} blocks could hold: increase the spacing",
                set.name
            )
        })?;
        sets.push(CutSet {
            name: set.name.clone(),
            rock_mass: index,
            joint,
            planes: planes.iter().map(Plane::from).collect(),
        });
    }
    let planes: Vec<Vec<Plane>> = sets.iter().map(|s| s.planes.clone()).collect();
    let max_aspect = spec.max_aspect.unwrap_or(DEFAULT_MAX_ASPECT);
    if !(max_aspect.is_finite() && max_aspect >= 1.0) {
        return Err(format!(
            "max_aspect must be a number ≥ 1, got {}",
            short(max_aspect)
        ));
    }
    let min_volume = match spec.min_volume {
        Some(v) if !(v.is_finite() && v >= 0.0) => {
            return Err(format!("min_volume must be ≥ 0 m³, got {}", short(v)));
        }
        other => other,
    };
    let opts = CutOptions {
        min_volume: min_volume.unwrap_or(0.0),
        max_aspect,
        aspect_length: spec
            .joint_sets
            .iter()
            .map(|s| s.get_ref().spacing)
            .fold(f64::INFINITY, f64::min),
        max_blocks,
    };
    let (mut pieces, mut report) = cut::cut(&regions, &planes, &opts).map_err(|e| e.to_string())?;
    if min_volume.is_none() {
        drop_below_median_fraction(&mut pieces, &mut report);
    }
    // A rock mass of no block would run an empty model (`run` completed with no rows).
    if pieces.is_empty() {
        return Err(format!(
            "min_volume = {} m³ drops every piece of the cut ({} of them, {} m³ in all): no block is left",
            short(opts.min_volume),
            report.dropped,
            short(report.dropped_volume)
        ));
    }
    let blocks: Vec<CutBlock> = pieces
        .into_iter()
        .enumerate()
        .map(|(k, p)| CutBlock {
            name: format!("{}/{}", spec.name, k + 1),
            fixed: is_fixed(&spec.fixed, &p.centroid, p.region),
            vertices: p.vertices,
            rock_mass: RockMassOf {
                mass: index,
                region: p.region as u16,
            },
        })
        .collect();
    let report = RockMassReport {
        name: spec.name.clone(),
        blocks: blocks.len(),
        fixed: blocks.iter().filter(|b| b.fixed).count(),
        planes: planes.iter().map(Vec::len).sum(),
        domain_volume: report.domain_volume,
        volume: report.volume,
        smallest: report.smallest,
        dropped: report.dropped,
        dropped_volume: report.dropped_volume,
        rejected_cuts: report.rejected_cuts,
    };
    Ok(CutMass {
        blocks,
        sets,
        report,
    })
}

/// Drops the pieces smaller than [`DEFAULT_MIN_VOLUME_FRACTION`] of the median piece's volume
/// (the default `min_volume`), and counts them in the report.
fn drop_below_median_fraction(pieces: &mut Vec<cut::Piece>, report: &mut cut::CutReport) {
    let mut volumes: Vec<f64> = pieces.iter().map(|p| p.volume).collect();
    if volumes.is_empty() {
        return;
    }
    volumes.sort_by(f64::total_cmp);
    let limit = DEFAULT_MIN_VOLUME_FRACTION * volumes[volumes.len() / 2];
    pieces.retain(|p| {
        let keep = p.volume >= limit;
        if !keep {
            report.dropped += 1;
            report.dropped_volume += p.volume;
        }
        keep
    });
    report.volume = pieces.iter().map(|p| p.volume).sum();
    report.smallest = pieces
        .iter()
        .map(|p| p.volume)
        .fold(f64::INFINITY, f64::min);
}

/// The regions as convex polyhedra; each must be convex (every point it is given on its hull)
/// and no two may overlap.
fn regions(spec: &RockMassSpec) -> Result<Vec<Polyhedron>, String> {
    if spec.regions.is_empty() {
        return Err("regions is empty: give the domain as one or more convex shapes".into());
    }
    let mut out: Vec<Polyhedron> = Vec::with_capacity(spec.regions.len());
    let mut hulls: Vec<(Vec<Vec3>, crate::physics::geometry::Topology)> =
        Vec::with_capacity(spec.regions.len());
    for (k, r) in spec.regions.iter().enumerate() {
        let rerr = |m: String| format!("region {}: {m}", k + 1);
        let points = shape_points(&r.get_ref().shape()).map_err(rerr)?;
        let (vertices, topo) = convex_hull(&points).map_err(|e| rerr(e.to_string()))?;
        if let Some(p) = off_hull_edges(&points, &vertices, &topo) {
            return Err(rerr(format!(
                "not convex: its point {} ({}, {}, {}) is not on an edge of the points' convex \
                 hull; give a non-convex domain as several convex regions",
                p + 1,
                short(points[p].x),
                short(points[p].y),
                short(points[p].z)
            )));
        }
        for (j, (v, t)) in hulls.iter().enumerate() {
            let depth = overlap_depth(v, t, &vertices, &topo);
            let (lo, hi) = bounding_box(&vertices);
            if depth > 1e-9 * (hi - lo).norm() {
                return Err(rerr(format!(
                    "overlaps region {} by {} m (regions may share faces, not volume)",
                    j + 1,
                    short(depth)
                )));
            }
        }
        out.push(Polyhedron {
            vertices: vertices.clone(),
            faces: topo.faces.clone(),
        });
        hulls.push((vertices, topo));
    }
    Ok(out)
}

/// The first of `points` that lies on no edge of their hull (`vertices`, `topo`), beyond the
/// hull's tolerance: a convex shape's points are its corners, or lie on its edges. A point
/// inside the hull, or inside one of its faces (the reflex corner of a prism's base), is not.
fn off_hull_edges(
    points: &[Vec3],
    vertices: &[Vec3],
    topo: &crate::physics::geometry::Topology,
) -> Option<usize> {
    let (lo, hi) = bounding_box(vertices);
    let tol = 1e-6 * (hi - lo).norm();
    let to_segment = |p: &Vec3, a: &Vec3, b: &Vec3| {
        let ab = b - a;
        let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
        (p - (a + ab * t)).norm()
    };
    points.iter().position(|p| {
        topo.edges
            .iter()
            .all(|e| to_segment(p, &vertices[e.v[0]], &vertices[e.v[1]]) > tol)
    })
}

/// `fixed`'s coordinate selectors are finite numbers (`below = nan` held no block, silently).
fn check_fixed(fixed: &FixedSpec) -> Result<(), String> {
    let limits = [
        ("below", fixed.below),
        ("above", fixed.above),
        ("x_below", fixed.x_below),
        ("x_above", fixed.x_above),
        ("y_below", fixed.y_below),
        ("y_above", fixed.y_above),
    ];
    match limits
        .iter()
        .find(|(_, v)| v.is_some_and(|v| !v.is_finite()))
    {
        Some((key, _)) => Err(format!("fixed.{key} must be a finite coordinate, m")),
        None => Ok(()),
    }
}

/// Whether a block of centroid `c` in `region` is held, by `fixed`'s selectors.
fn is_fixed(fixed: &FixedSpec, c: &Vec3, region: usize) -> bool {
    let below = |limit: Option<f64>, x: f64| limit.is_some_and(|l| x < l);
    let above = |limit: Option<f64>, x: f64| limit.is_some_and(|l| x > l);
    below(fixed.below, c.z)
        || above(fixed.above, c.z)
        || below(fixed.x_below, c.x)
        || above(fixed.x_above, c.x)
        || below(fixed.y_below, c.y)
        || above(fixed.y_above, c.y)
        || fixed.regions.iter().any(|&r| usize::from(r) == region + 1)
}

/// The joint of a set named `name` from its optional friction and cohesion (`[joint]`'s where
/// not given), checked against the ranges of `[joint]`'s keys.
fn joint_of(
    name: &str,
    friction_angle: Option<f64>,
    cohesion: Option<f64>,
    default: &JointParams,
    table: &str,
) -> Result<JointParams, String> {
    let joint = JointParams {
        friction_angle: friction_angle.unwrap_or(default.friction_angle),
        cohesion: cohesion.unwrap_or(default.cohesion),
    };
    let params = crate::params::SolverParams {
        joint: joint.clone(),
        ..Default::default()
    };
    for p in [&FRICTION_ANGLE, &COHESION] {
        p.check_finite(&params)
            .and_then(|()| p.check_range(&params))
            .map_err(|m| m.replacen(p.key, &format!("{table} '{name}': {}", p.name()), 1))?;
    }
    Ok(joint)
}

/// A set's geometry, checked: dip in [0, 90]°, dip direction in [0, 360)°, spacing > 0, the
/// deviations ≥ 0 and the tilt at most [`MAX_ORIENTATION_DEVIATION`].
fn set_geometry(set: &JointSetSpec) -> Result<SetGeometry, String> {
    let bad = |key: &str, want: &str, v: f64| {
        Err(format!(
            "joint set '{}': {key} must {want}, got {}",
            set.name,
            short(v)
        ))
    };
    let checks: [(&str, f64, bool, &str); 5] = [
        (
            "dip",
            set.dip,
            (0.0..=90.0).contains(&set.dip),
            "lie in [0, 90]°",
        ),
        (
            "dip_direction",
            set.dip_direction,
            (0.0..360.0).contains(&set.dip_direction),
            "lie in [0, 360)°",
        ),
        (
            "spacing",
            set.spacing,
            set.spacing > 0.0 && set.spacing.is_finite(),
            "be positive",
        ),
        (
            "spacing_deviation",
            set.spacing_deviation,
            set.spacing_deviation >= 0.0 && set.spacing_deviation.is_finite(),
            "be ≥ 0 m",
        ),
        (
            "orientation_deviation",
            set.orientation_deviation,
            (0.0..=MAX_ORIENTATION_DEVIATION).contains(&set.orientation_deviation),
            "lie in [0, 45]°",
        ),
    ];
    for (key, v, ok, want) in checks {
        if !ok {
            return bad(key, want, v);
        }
    }
    if set.origin.iter().any(|x| !x.is_finite()) {
        return Err(format!("joint set '{}': origin is not finite", set.name));
    }
    // The planes lie at n·o + k·spacing: an origin so far out that f64 cannot resolve the
    // spacing there gives wrong planes (at 1e17 m, two blocks from 7 planes instead of 7 from
    // 6), and farther still, a walk of 10^300 planes that never ends.
    let reach = set.origin.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if reach * ORIGIN_RESOLUTION > set.spacing {
        return Err(format!(
            "joint set '{}': an origin {} m out cannot resolve a spacing of {} m; put the origin in or near the rock mass",
            set.name,
            crate::text::short(reach),
            crate::text::short(set.spacing)
        ));
    }
    Ok(SetGeometry {
        dip: set.dip,
        dip_direction: set.dip_direction,
        spacing: set.spacing,
        origin: Vector3::from(set.origin),
        spacing_deviation: set.spacing_deviation,
        orientation_deviation: set.orientation_deviation,
        seed: set.seed,
    })
}

/// A `[[joint_sets]]` entry: its planes checked (unit normals, finite), for rock mass `index`.
pub(super) fn planes_set(
    spec: &PlanesSpec,
    index: u16,
    default_joint: &JointParams,
) -> Result<CutSet, String> {
    let joint = joint_of(
        &spec.name,
        spec.friction_angle,
        spec.cohesion,
        default_joint,
        "joint_sets",
    )?;
    let mut planes = Vec::with_capacity(spec.planes.len());
    for (k, p) in spec.planes.iter().enumerate() {
        let [x, y, z, d] = p.0;
        let normal = Vec3::new(x, y, z);
        if !(d.is_finite() && normal.iter().all(|c| c.is_finite()))
            || (normal.norm() - 1.0).abs() > 1e-9
        {
            return Err(format!(
                "joint set '{}': plane {} needs a unit normal and a finite offset",
                spec.name,
                k + 1
            ));
        }
        planes.push(Plane { normal, offset: d });
    }
    Ok(CutSet {
        name: spec.name.clone(),
        rock_mass: index,
        joint,
        planes,
    })
}

/// Tags every face of `block` that lies on a plane of `set` (number `set_index`): all its
/// vertices within the hull's tolerance (10⁻⁷ of the block's diagonal) of the plane.
pub(super) fn tag_faces(block: &mut Block, set: &CutSet, set_index: u16) {
    let tol = 1e-7 * (block.hi - block.lo).norm();
    for (f, face) in block.topo.faces.iter().enumerate() {
        if block.face_joints[f].is_some() {
            continue;
        }
        let n = block.face_normals[f];
        let hit = set.planes.iter().position(|p| {
            n.dot(&p.normal).abs() > 1.0 - 1e-6
                && face
                    .iter()
                    .all(|&v| (p.normal.dot(&block.vertices[v]) - p.offset).abs() <= tol)
        });
        if let Some(k) = hit {
            block.face_joints[f] = Some(JointFace {
                set: set_index,
                plane: k as u32,
            });
        }
    }
}
