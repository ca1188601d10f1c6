//! Mouse and keyboard control of the 3-D view, and picking a block under the cursor. Pure CPU
//! logic on top of [`Camera`], so it is unit-tested without a window.
//!
//! All pixel quantities are in the view's own units (egui points in the window); only ratios
//! matter, so the same code works at any display scale.

use glam::{DVec3, Vec2, Vec3, Vec4};

use crate::render::{Camera, Ray};
use crate::snapshot::{BlockSnapshot, Snapshot};

/// Pixels of wheel movement per "step" (egui reports wheel notches as 50 points).
pub const POINTS_PER_WHEEL_STEP: f32 = 50.0;
/// A press that moves less than this (points) before release is a click, not a drag.
pub const CLICK_SLOP: f32 = 4.0;

/// Which mouse button drags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DragButton {
    /// Orbit.
    Left,
    /// Pan.
    Right,
    /// Pan.
    Middle,
}

/// The camera of the interactive view, with the scene origin its f32 coordinates are measured
/// from (fixed for the run, so the renderer's vertex positions and the camera agree).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewControls {
    pub camera: Camera,
}

impl ViewControls {
    /// Frames the box `[lo, hi]` from the default direction; its centre becomes the origin.
    pub fn new(lo: DVec3, hi: DVec3, aspect: f32) -> ViewControls {
        ViewControls {
            camera: Camera::frame(lo.to_array(), hi.to_array(), aspect),
        }
    }

    /// Keeps the camera's aspect equal to the view's.
    pub fn set_viewport(&mut self, width: f32, height: f32) {
        if width > 0.0 && height > 0.0 && (width / height).is_finite() {
            self.camera.aspect = width / height;
        }
    }

    /// A drag of (dx, dy) points with `button` held, in a view `height` points tall:
    /// left orbits about the target, right or middle pans (the point under the cursor follows).
    pub fn drag(&mut self, button: DragButton, dx: f32, dy: f32, height: f32) {
        match button {
            DragButton::Left => self.camera.orbit(dx, dy),
            DragButton::Right | DragButton::Middle => self.camera.pan(dx, dy, height),
        }
    }

    /// Mouse wheel: `points` of scroll (positive = away from the user = closer).
    pub fn scroll(&mut self, points: f32) {
        self.camera.zoom(points / POINTS_PER_WHEEL_STEP);
    }

    /// Frame all (F): fits every block's current vertices, keeping the view direction and the
    /// render origin.
    pub fn frame_all(&mut self, snap: &Snapshot) {
        let Some((lo, hi)) = bounds(snap.blocks.iter()) else {
            return;
        };
        let fitted = Camera::frame_from(
            lo.to_array(),
            hi.to_array(),
            self.camera.aspect,
            self.camera.azimuth.to_degrees(),
            self.camera.elevation.to_degrees(),
        );
        let origin = self.camera.origin;
        self.camera = Camera {
            origin,
            target: (fitted.origin - origin).as_vec3(),
            ..fitted
        };
        // Near/far planes come from `scene_radius`; keep them wide enough for the old frame too
        // (the grid spans the initial box).
        self.camera.scene_radius = self
            .camera
            .scene_radius
            .max(self.camera.target.length() + fitted.scene_radius);
    }

    /// The block under the point (x, y) of a `width`×`height` view, or `None` when the ray
    /// through it hits nothing.
    pub fn pick(&self, snap: &Snapshot, x: f32, y: f32, width: f32, height: f32) -> Option<usize> {
        let ray = self.ray(x, y, width, height)?;
        pick(snap, &ray).map(|(i, _)| i)
    }

    /// The ray from the eye through (x, y) of a `width`×`height` view (as [`Camera::ray`], with
    /// fractional sizes).
    pub fn ray(&self, x: f32, y: f32, width: f32, height: f32) -> Option<Ray> {
        if !(width > 0.0 && height > 0.0 && x.is_finite() && y.is_finite()) {
            return None;
        }
        let inv = self.camera.view_proj().inverse();
        let ndc = Vec2::new(2.0 * x / width - 1.0, 1.0 - 2.0 * y / height);
        let unproject = |z: f32| {
            let p = inv * Vec4::new(ndc.x, ndc.y, z, 1.0);
            p.truncate() / p.w
        };
        let (near, far) = (unproject(0.0), unproject(1.0));
        let dir = (far - near).as_dvec3().normalize_or_zero();
        (dir != DVec3::ZERO && near.is_finite()).then(|| Ray {
            origin: self.camera.origin + near.as_dvec3(),
            dir,
        })
    }

    /// Position (x right, y down) of a world point in a `width`×`height` view, or `None` when
    /// it is behind the eye.
    pub fn project(&self, p: [f64; 3], width: f32, height: f32) -> Option<(f32, f32)> {
        let clip = self.camera.view_proj() * self.camera.to_local(p).extend(1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(((ndc.x + 1.0) * 0.5 * width, (1.0 - ndc.y) * 0.5 * height))
    }

    /// Unit vectors of the view, for tests and the overlay.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        self.camera.basis()
    }
}

/// Bounding box of the finite vertices of `blocks`.
pub fn bounds<'a>(blocks: impl Iterator<Item = &'a BlockSnapshot>) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for b in blocks {
        for v in &b.vertices {
            let p = DVec3::from_array(*v);
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// Nearest block hit by the ray: (index, distance along the ray).
pub fn pick(snap: &Snapshot, ray: &Ray) -> Option<(usize, f64)> {
    snap.blocks
        .iter()
        .enumerate()
        .filter_map(|(i, b)| ray_convex(ray, b).map(|t| (i, t)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// Entry distance of a ray into a convex block (or 0 when it starts inside), clipping the ray
/// against each face plane (outward normals by the right-hand rule, as the solver stores them).
fn ray_convex(ray: &Ray, b: &BlockSnapshot) -> Option<f64> {
    let (mut t_in, mut t_out) = (0.0f64, f64::INFINITY);
    let mut planes = 0;
    for face in &b.faces {
        let pts: Vec<DVec3> = face
            .iter()
            .filter_map(|&k| b.vertices.get(k as usize))
            .map(|v| DVec3::from_array(*v))
            .collect();
        if pts.len() < 3 {
            continue;
        }
        // Newell's normal is robust for slightly non-planar or sliver faces.
        let mut n = DVec3::ZERO;
        for (k, p) in pts.iter().enumerate() {
            let q = pts[(k + 1) % pts.len()];
            n += DVec3::new(
                (p.y - q.y) * (p.z + q.z),
                (p.z - q.z) * (p.x + q.x),
                (p.x - q.x) * (p.y + q.y),
            );
        }
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        let n = n / len;
        planes += 1;
        let c = pts.iter().sum::<DVec3>() / pts.len() as f64;
        // Inside is n·(x − c) ≤ 0.
        let denom = n.dot(ray.dir);
        let dist = n.dot(ray.origin - c);
        if denom.abs() < 1e-12 {
            if dist > 0.0 {
                return None; // parallel and outside
            }
            continue;
        }
        let t = -dist / denom;
        if denom < 0.0 {
            t_in = t_in.max(t);
        } else {
            t_out = t_out.min(t);
        }
        if t_in > t_out {
            return None;
        }
    }
    (planes >= 4 && t_in <= t_out && t_out.is_finite()).then_some(t_in)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{Snapshot, StepStats};

    fn cube(name: &str, at: [f64; 3], size: f64) -> BlockSnapshot {
        BlockSnapshot::test_cube(name, at, size)
    }

    fn snap(blocks: Vec<BlockSnapshot>) -> Snapshot {
        Snapshot {
            scene_name: "test".into(),
            time: 0.0,
            step: 0,
            blocks,
            contacts: vec![],
            stats: StepStats::default(),
            equilibrium: None,
            rock_masses: Vec::new(),
            joint_sets: Vec::new(),
        }
    }

    fn two_cubes() -> Snapshot {
        snap(vec![
            cube("a", [0.0, 0.0, 0.0], 1.0),
            cube("b", [3.0, 0.0, 0.0], 1.0),
        ])
    }

    fn controls(s: &Snapshot) -> ViewControls {
        let (lo, hi) = bounds(s.blocks.iter()).unwrap();
        ViewControls::new(lo, hi, 16.0 / 9.0)
    }

    const W: f32 = 1280.0;
    const H: f32 = 720.0;

    #[test]
    fn left_drag_orbits_right_drag_pans() {
        let s = two_cubes();
        let mut v = controls(&s);
        let before = v.camera.clone();
        v.drag(DragButton::Left, 100.0, 0.0, H);
        assert!(v.camera.azimuth != before.azimuth, "horizontal drag turns");
        assert_eq!(v.camera.target, before.target, "orbit keeps the target");
        assert_eq!(v.camera.distance, before.distance);
        v.drag(DragButton::Left, 0.0, 50.0, H);
        assert!(
            v.camera.elevation > before.elevation,
            "down drag raises the eye"
        );

        let mut v = controls(&s);
        let target = v.camera.target;
        v.drag(DragButton::Right, 40.0, 0.0, H);
        assert!(v.camera.target != target, "right drag pans");
        assert_eq!(v.camera.azimuth, before.azimuth, "pan does not turn");
        let mut m = controls(&s);
        m.drag(DragButton::Middle, 40.0, 0.0, H);
        assert_eq!(
            m.camera.target, v.camera.target,
            "middle drag pans like right"
        );
    }

    #[test]
    fn pan_keeps_the_point_under_the_cursor() {
        let s = two_cubes();
        let mut v = controls(&s);
        // A point on the plane through the orbit centre facing the eye follows the cursor
        // exactly (points nearer or farther move more or less, by perspective).
        let (right, up, _) = v.basis();
        let p =
            (v.camera.origin + (v.camera.target + right * 1.5 + up * 0.5).as_dvec3()).to_array();
        let (x0, y0) = v.project(p, W, H).unwrap();
        v.drag(DragButton::Right, 30.0, -20.0, H);
        let (x1, y1) = v.project(p, W, H).unwrap();
        assert!((x1 - x0 - 30.0).abs() < 0.01, "{x0} → {x1}");
        assert!((y1 - y0 + 20.0).abs() < 0.01, "{y0} → {y1}");
    }

    #[test]
    fn wheel_zooms_in_and_out() {
        let s = two_cubes();
        let mut v = controls(&s);
        let d0 = v.camera.distance;
        v.scroll(POINTS_PER_WHEEL_STEP);
        assert!(
            (v.camera.distance - d0 * 0.9).abs() < 1e-4 * d0,
            "one notch = 10 % closer"
        );
        v.scroll(-POINTS_PER_WHEEL_STEP);
        assert!((v.camera.distance - d0).abs() < 1e-4 * d0);
        for _ in 0..1000 {
            v.scroll(-POINTS_PER_WHEEL_STEP);
        }
        assert!(v.camera.distance.is_finite(), "zoom is clamped");
        v.scroll(f32::NAN);
        assert!(v.camera.distance.is_finite());
    }

    #[test]
    fn frame_all_brings_every_block_back_into_view() {
        let mut s = two_cubes();
        let mut v = controls(&s);
        let origin = v.camera.origin;
        // Zoom far in and pan away, and move a block far off.
        for _ in 0..30 {
            v.scroll(POINTS_PER_WHEEL_STEP);
        }
        v.drag(DragButton::Right, 500.0, 300.0, H);
        s.blocks[1] = cube("b", [10.0, 4.0, -2.0], 1.0);
        v.drag(DragButton::Left, 200.0, 30.0, H);
        let (az, el) = (v.camera.azimuth, v.camera.elevation);
        v.frame_all(&s);
        assert_eq!(v.camera.origin, origin, "render origin unchanged");
        assert!((v.camera.azimuth - az).abs() < 1e-5, "view direction kept");
        assert!((v.camera.elevation - el).abs() < 1e-5);
        for b in &s.blocks {
            for p in &b.vertices {
                let (x, y) = v.project(*p, W, H).expect("in front of the eye");
                assert!(
                    (0.0..=W).contains(&x) && (0.0..=H).contains(&y),
                    "{p:?} at {x},{y}"
                );
            }
        }
    }

    #[test]
    fn click_picks_the_block_under_the_cursor() {
        let s = two_cubes();
        let v = controls(&s);
        for (i, b) in s.blocks.iter().enumerate() {
            let (x, y) = v.project(b.centroid, W, H).unwrap();
            assert_eq!(v.pick(&s, x, y, W, H), Some(i), "block {}", b.name);
        }
        assert_eq!(
            v.pick(&s, 2.0, 2.0, W, H),
            None,
            "corner of the view is empty"
        );
    }

    #[test]
    fn pick_returns_the_nearest_of_overlapping_blocks() {
        // Two cubes in a row along the ray: the nearer one wins.
        let s = snap(vec![
            cube("far", [0.0, 0.0, 0.0], 1.0),
            cube("near", [0.0, 0.0, 5.0], 1.0),
        ]);
        let ray = Ray {
            origin: DVec3::new(0.5, 0.5, 20.0),
            dir: DVec3::new(0.0, 0.0, -1.0),
        };
        let (i, t) = pick(&s, &ray).unwrap();
        assert_eq!(s.blocks[i].name, "near");
        assert!(
            (t - 14.0).abs() < 1e-9,
            "enters the top face at z = 6: t = {t}"
        );
        let miss = Ray {
            origin: DVec3::new(2.5, 0.5, 20.0),
            dir: DVec3::new(0.0, 0.0, -1.0),
        };
        assert!(pick(&s, &miss).is_none());
    }

    #[test]
    fn viewport_changes_the_aspect_only_for_valid_sizes() {
        let s = two_cubes();
        let mut v = controls(&s);
        v.set_viewport(800.0, 400.0);
        assert_eq!(v.camera.aspect, 2.0);
        v.set_viewport(0.0, 400.0);
        assert_eq!(v.camera.aspect, 2.0);
        v.set_viewport(f32::NAN, 1.0);
        assert_eq!(v.camera.aspect, 2.0);
    }
}
