//! Contact arrows as the GPU draws them: one small indexed template of a unit arrow (base disc,
//! shaft, annulus under the head, cone), placed per arrow by the vertex shader
//! (`vs_arrow` in shaders/arrow.wgsl) from an [`ArrowInstance`] of 64 bytes.
//!
//! A rock mass shows hundreds of arrows in every new frame. As plain triangles they were 288
//! vertices (11 kB) each, built, uploaded and shaded anew for every state; as instances a frame
//! uploads 64 bytes an arrow and the template's 113 shared vertices are shaded once per arrow.
//! [`ArrowInstance::vertex`] is the shader's formula in Rust, so the geometry is unit-tested
//! here without a GPU.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::camera::Camera;
use super::mesh::{Rgba, SolidVertex};

/// Index into [`ARROW_LODS`] of the template the renderer draws `arrow` with, seen by
/// `camera` on a target `height` pixels high.
pub fn lod_seen(arrow: &ArrowInstance, camera: &Camera, height: u32) -> usize {
    let px_per_unit = 0.5 * height as f32 / (0.5 * camera.fov_y).tan();
    lod_for(arrow.radius_px(camera.eye(), px_per_unit))
}

/// An arrow: a cylindrical shaft from `base` along `dir`, then a cone whose apex is the tip at
/// `base + dir * length`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arrow {
    pub base: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    pub length: f32,
    pub shaft_radius: f32,
    pub head_radius: f32,
    /// Requested head length; shortened to half the arrow on short arrows.
    pub head_length: f32,
}

impl Arrow {
    /// An arrow of the given length and thickness with the usual head proportions.
    pub fn new(base: Vec3, dir: Vec3, length: f32, shaft_radius: f32) -> Arrow {
        Arrow {
            base,
            dir: dir.normalize_or(Vec3::Z),
            length,
            shaft_radius,
            head_radius: shaft_radius * 2.4,
            head_length: shaft_radius * 6.0,
        }
    }

    pub fn tip(&self) -> Vec3 {
        self.base + self.dir * self.length
    }

    /// Head length actually drawn.
    pub fn head_len(&self) -> f32 {
        self.head_length.min(self.length * 0.5)
    }

    /// Where the shaft ends and the cone begins.
    pub fn neck(&self) -> Vec3 {
        self.base + self.dir * (self.length - self.head_len())
    }
}

/// Sides of the arrow cylinder and cone: smooth enough at figure scale.
pub const ARROW_SEGMENTS: usize = 16;

/// The templates drawn, finest first: an arrow gets the coarsest whose outline stays within
/// [`MAX_SAGITTA_PX`] of the round one on screen ([`sides_for`]).
pub const ARROW_LODS: [usize; 3] = [ARROW_SEGMENTS, 8, 4];

/// Largest gap, in pixels, between an n-sided arrow's outline and a round one's.
pub const MAX_SAGITTA_PX: f32 = 0.5;

/// Index into [`ARROW_LODS`] of the template for an arrow whose head radius spans
/// `radius_px` pixels on screen: the coarsest n with sagitta r·(1 − cos(π/n)) ≤
/// [`MAX_SAGITTA_PX`]. An arrow of a few pixels on a rock mass of thousands of contacts is
/// drawn with 4 sides instead of 16: a quarter of the triangles, the same pixels.
pub fn lod_for(radius_px: f32) -> usize {
    let fits =
        |n: usize| radius_px * (1.0 - (std::f32::consts::PI / n as f32).cos()) <= MAX_SAGITTA_PX;
    (0..ARROW_LODS.len())
        .rev()
        .find(|&k| fits(ARROW_LODS[k]))
        .unwrap_or(0)
}

/// One arrow for the GPU: the per-instance vertex data of `vs_arrow`, read at its `repr(C)`
/// offsets (the padding keeps the colour 16-byte aligned).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ArrowInstance {
    pub base: [f32; 3],
    pub length: f32,
    /// Unit direction.
    pub dir: [f32; 3],
    pub shaft_radius: f32,
    /// Head radius (at least the shaft's) and head length (the one drawn, above zero).
    pub head: [f32; 2],
    pub _pad: [f32; 2],
    pub color: Rgba,
}

impl ArrowInstance {
    /// The instance of `arrow`, or `None` for a degenerate one (non-finite, zero length or
    /// radius), which is not drawn.
    pub fn new(arrow: &Arrow, color: Rgba) -> Option<ArrowInstance> {
        let ok = arrow.base.is_finite()
            && arrow.dir.is_finite()
            && arrow.length.is_finite()
            && arrow.length > 0.0
            && arrow.shaft_radius > 0.0
            && arrow.head_radius.is_finite();
        ok.then(|| ArrowInstance {
            base: arrow.base.to_array(),
            length: arrow.length,
            dir: arrow.dir.to_array(),
            shaft_radius: arrow.shaft_radius,
            head: [
                arrow.head_radius.max(arrow.shaft_radius),
                arrow.head_len().max(1e-9),
            ],
            _pad: [0.0; 2],
            color,
        })
    }

    /// Where template vertex `t` lands for this arrow, and its normal: `vs_arrow`'s formula.
    pub fn vertex(&self, t: &ArrowTemplateVertex) -> (Vec3, Vec3) {
        let d = Vec3::from(self.dir);
        let (u, v) = orthonormal_pair(d);
        let r = u * t.ring[0] + v * t.ring[1];
        let [head_radius, head_len] = self.head;
        let along = match t.part[0] as u32 {
            STATION_BASE => 0.0,
            STATION_NECK => self.length - head_len,
            _ => self.length,
        };
        let radius = match t.part[1] as u32 {
            RADIUS_AXIS => 0.0,
            RADIUS_SHAFT => self.shaft_radius,
            _ => head_radius,
        };
        let normal = match t.part[2] as u32 {
            NORMAL_BACK => -d,
            NORMAL_RADIAL => r,
            // The cone's side: radial tilted toward the tip by the half-angle.
            _ => (r * head_len + d * head_radius).normalize(),
        };
        (Vec3::from(self.base) + d * along + r * radius, normal)
    }

    /// How many pixels its head radius spans at its nearest point to `eye`, seen through a
    /// perspective that maps a unit at unit distance to `px_per_unit` pixels.
    pub fn radius_px(&self, eye: Vec3, px_per_unit: f32) -> f32 {
        let base = Vec3::from(self.base);
        let tip = base + Vec3::from(self.dir) * self.length;
        let near = base.distance(eye).min(tip.distance(eye)) - self.head[0];
        self.head[0] * px_per_unit / near.max(1e-6)
    }

    /// The arrow as plain triangles of the finest template (what the GPU draws up close), for
    /// tests and CPU consumers.
    pub fn triangles(&self) -> Vec<SolidVertex> {
        self.triangles_with(ARROW_SEGMENTS)
    }

    /// As [`ArrowInstance::triangles`], with `sides` sides.
    pub fn triangles_with(&self, sides: usize) -> Vec<SolidVertex> {
        let (vertices, indices) = arrow_template(sides);
        indices
            .iter()
            .map(|&i| {
                let (p, n) = self.vertex(&vertices[usize::from(i)]);
                SolidVertex {
                    position: p.to_array(),
                    normal: n.to_array(),
                    color: self.color,
                }
            })
            .collect()
    }
}

/// An orthonormal pair perpendicular to the unit vector `d` (Duff et al. 2017, as glam's
/// `any_orthonormal_pair`, with the sign taken as `vs_arrow` takes it).
fn orthonormal_pair(d: Vec3) -> (Vec3, Vec3) {
    let sign = if d.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + d.z);
    let b = d.x * d.y * a;
    (
        Vec3::new(1.0 + sign * d.x * d.x * a, sign * b, -sign * d.x),
        Vec3::new(b, sign + d.y * d.y * a, -d.y),
    )
}

/// `part[0]`: where along the arrow.
const STATION_BASE: u32 = 0;
const STATION_NECK: u32 = 1;
const STATION_TIP: u32 = 2;
/// `part[1]`: how far from the axis.
const RADIUS_AXIS: u32 = 0;
const RADIUS_SHAFT: u32 = 1;
const RADIUS_HEAD: u32 = 2;
/// `part[2]`: which normal.
const NORMAL_BACK: u32 = 0;
const NORMAL_RADIAL: u32 = 1;
const NORMAL_CONE: u32 = 2;

/// A vertex of the unit arrow: a direction around the axis (cos, sin in the arrow's
/// orthonormal pair) and its part as small whole numbers (station, radius, normal; see the
/// constants above), which `vs_arrow` turns into a position and a normal per arrow.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ArrowTemplateVertex {
    pub ring: [f32; 2],
    pub part: [f32; 3],
}

/// The unit arrow of `n` sides: its vertices (shared where position and normal agree) and the
/// indices of its triangles. Per side: a triangle of the base disc, two of the shaft, two of
/// the annulus under the head and one of the cone.
pub fn arrow_template(n: usize) -> (Vec<ArrowTemplateVertex>, Vec<u16>) {
    let at = |k: f32| {
        let a = k / n as f32 * std::f32::consts::TAU;
        [a.cos(), a.sin()]
    };
    let mut vertices = vec![ArrowTemplateVertex {
        ring: [1.0, 0.0],
        part: [STATION_BASE as f32, RADIUS_AXIS as f32, NORMAL_BACK as f32],
    }];
    // Rings of n vertices each, in this order (index of ring r's vertex k: 1 + r·n + k).
    let rings = [
        (STATION_BASE, RADIUS_SHAFT, NORMAL_BACK, 0.0), // 0: base disc's rim
        (STATION_BASE, RADIUS_SHAFT, NORMAL_RADIAL, 0.0), // 1: shaft at the base
        (STATION_NECK, RADIUS_SHAFT, NORMAL_RADIAL, 0.0), // 2: shaft at the neck
        (STATION_NECK, RADIUS_SHAFT, NORMAL_BACK, 0.0), // 3: annulus, inner
        (STATION_NECK, RADIUS_HEAD, NORMAL_BACK, 0.0),  // 4: annulus, outer
        (STATION_NECK, RADIUS_HEAD, NORMAL_CONE, 0.0),  // 5: cone's rim
        (STATION_TIP, RADIUS_AXIS, NORMAL_CONE, 0.5),   // 6: tip, normal between two sides
    ];
    for &(station, radius, normal, shift) in &rings {
        for k in 0..n {
            vertices.push(ArrowTemplateVertex {
                ring: at(k as f32 + shift),
                part: [station as f32, radius as f32, normal as f32],
            });
        }
    }
    let v = |ring: usize, k: usize| (1 + ring * n + k % n) as u16;
    let mut indices = Vec::with_capacity(n * 6 * 3);
    for k in 0..n {
        let k1 = k + 1;
        indices.extend([0, v(0, k1), v(0, k)]);
        indices.extend([v(1, k), v(1, k1), v(2, k1)]);
        indices.extend([v(1, k), v(2, k1), v(2, k)]);
        indices.extend([v(3, k), v(4, k1), v(4, k)]);
        indices.extend([v(3, k), v(3, k1), v(4, k1)]);
        indices.extend([v(5, k), v(5, k1), v(6, k)]);
    }
    (vertices, indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn instance(arrow: &Arrow) -> ArrowInstance {
        ArrowInstance::new(arrow, [1.0; 4]).expect("a drawable arrow")
    }

    #[test]
    fn arrow_base_tip_and_extent() {
        let base = Vec3::new(1.0, 2.0, 3.0);
        let dir = Vec3::new(-0.5, 0.0, 0.866_025_4);
        let arrow = Arrow::new(base, dir, 2.0, 0.05);
        let tip = base + dir * 2.0;
        assert!((arrow.tip() - tip).length() < 1e-6);
        let out = instance(&arrow).triangles();
        assert_eq!(out.len(), ARROW_SEGMENTS * 6 * 3);
        let coarse = instance(&arrow).triangles_with(4);
        assert_eq!(coarse.len(), 4 * 6 * 3);
        // The farthest vertex along dir is the tip; the nearest is on the base plane.
        let along: Vec<f32> = out
            .iter()
            .map(|v| (Vec3::from(v.position) - base).dot(dir))
            .collect();
        let max = along.iter().cloned().fold(f32::MIN, f32::max);
        let min = along.iter().cloned().fold(f32::MAX, f32::min);
        assert!((max - 2.0).abs() < 1e-5, "tip at {max}");
        assert!(min.abs() < 1e-5, "base at {min}");
        assert!(
            out.iter()
                .any(|v| (Vec3::from(v.position) - tip).length() < 1e-5)
        );
        // No vertex farther from the axis than the head radius, and the head's rim on it.
        let radial = |p: Vec3| {
            let r = p - base;
            (r - dir * r.dot(dir)).length()
        };
        let widest = out
            .iter()
            .map(|v| radial(Vec3::from(v.position)))
            .fold(0.0, f32::max);
        assert!((widest - arrow.head_radius).abs() < 1e-5, "{widest}");
        // The neck sits a head length below the tip.
        let neck = (arrow.neck() - base).dot(dir);
        assert!((neck - (2.0 - 0.3)).abs() < 1e-5);
    }

    #[test]
    fn the_arrow_is_closed_and_its_normals_point_out() {
        for dir in [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.4, -0.2)] {
            let arrow = Arrow::new(Vec3::new(0.5, -1.0, 2.0), dir, 1.5, 0.04);
            for sides in ARROW_LODS {
                closed_and_outward(&arrow, sides);
            }
        }
    }

    fn closed_and_outward(arrow: &Arrow, sides: usize) {
        let tris = instance(arrow).triangles_with(sides);
        let d = arrow.dir;
        // Every edge (by its end points) is shared by exactly two triangles.
        let key = |p: [f32; 3]| p.map(|x| (x * 1e4).round() as i64);
        let mut edges = std::collections::HashMap::new();
        for t in tris.chunks(3) {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                let (ka, kb) = (key(t[a].position), key(t[b].position));
                *edges.entry([ka.min(kb), ka.max(kb)].concat()).or_insert(0) += 1;
            }
        }
        assert!(
            edges.values().all(|&c| c == 2),
            "an open edge, dir {d}, {sides} sides"
        );
        // Normals are unit and point away from the axis or backwards, never inwards.
        for v in &tris {
            let n = Vec3::from(v.normal);
            assert!((n.length() - 1.0).abs() < 1e-5);
            let r = Vec3::from(v.position) - arrow.base;
            let radial = r - d * r.dot(d);
            let back = n.dot(d) < -0.999;
            assert!(back || n.dot(radial) >= -1e-6, "inward normal {n}");
        }
    }

    #[test]
    fn coarse_templates_only_where_the_outline_stays_within_half_a_pixel() {
        // 16 sides up close, 8 from 6.6 px of head radius down, 4 below 1.7 px.
        assert_eq!(lod_for(100.0), 0);
        assert_eq!(lod_for(7.0), 0);
        assert_eq!(lod_for(6.0), 1);
        assert_eq!(lod_for(2.0), 1);
        assert_eq!(lod_for(1.5), 2);
        assert_eq!(lod_for(f32::NAN), 0);
        for k in 0..=1000 {
            let r = k as f32 * 0.05;
            let n = ARROW_LODS[lod_for(r)] as f32;
            let sagitta = r * (1.0 - (std::f32::consts::PI / n).cos());
            assert!(n == 16.0 || sagitta <= MAX_SAGITTA_PX, "{r} px: {n} sides");
        }
        // An arrow 1 m away with a 1 cm head, at 1000 px per unit: 10 px, farther: fewer.
        let a = instance(&Arrow::new(Vec3::ZERO, Vec3::X, 0.5, 0.01 / 2.4));
        let near = a.radius_px(Vec3::new(0.0, 1.0, 0.0), 1000.0);
        let far = a.radius_px(Vec3::new(0.0, 10.0, 0.0), 1000.0);
        assert!((near - 10.1).abs() < 0.1, "{near}");
        assert!(far < near / 9.0);
    }

    #[test]
    fn the_pair_is_orthonormal_for_any_direction() {
        for d in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, 2.0, -3.0).normalize(),
        ] {
            let (u, v) = orthonormal_pair(d);
            for (a, b) in [(u, v), (u, d), (v, d)] {
                assert!(a.dot(b).abs() < 1e-6);
            }
            assert!((u.length() - 1.0).abs() < 1e-6 && (v.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn short_arrow_head_takes_half() {
        let arrow = Arrow::new(Vec3::ZERO, Vec3::Z, 0.1, 0.05);
        assert!((arrow.head_len() - 0.05).abs() < 1e-7);
        assert!((arrow.neck().z - 0.05).abs() < 1e-7);
        assert_eq!(instance(&arrow).head[1], 0.05);
    }

    #[test]
    fn degenerate_arrows_are_skipped() {
        for arrow in [
            Arrow::new(Vec3::ZERO, Vec3::X, 0.0, 0.1),
            Arrow::new(Vec3::ZERO, Vec3::X, f32::NAN, 0.1),
            Arrow::new(Vec3::NAN, Vec3::X, 1.0, 0.1),
            Arrow::new(Vec3::ZERO, Vec3::X, 1.0, 0.0),
        ] {
            assert_eq!(ArrowInstance::new(&arrow, [1.0; 4]), None);
        }
        // A zero direction falls back to +z rather than producing NaNs.
        let up = instance(&Arrow::new(Vec3::ZERO, Vec3::ZERO, 1.0, 0.1));
        assert!(
            up.triangles()
                .iter()
                .all(|v| Vec3::from(v.position).is_finite())
        );
    }

    #[test]
    fn the_instance_layout_is_what_the_shader_reads() {
        assert_eq!(std::mem::size_of::<ArrowInstance>(), 64);
        assert_eq!(std::mem::offset_of!(ArrowInstance, color), 48);
        assert_eq!(std::mem::size_of::<ArrowTemplateVertex>(), 20);
        for n in ARROW_LODS {
            let (v, i) = arrow_template(n);
            assert_eq!(v.len(), 1 + 7 * n);
            assert_eq!(i.len(), 6 * 3 * n);
            assert!(i.iter().all(|&k| usize::from(k) < v.len()));
        }
    }
}
