//! Orbit camera: automatic framing of a bounding box, view/projection matrices for wgpu
//! (right-handed world, z up, depth 0..1), world → pixel projection, and the mouse helpers the
//! interactive viewer uses (orbit, pan, zoom, picking ray).
//!
//! Positions on the GPU are f32 and measured from [`Camera::origin`] (an f64 world point, the
//! centre of the framed box), so a scene placed at large survey coordinates keeps millimetre
//! precision after the f64 → f32 conversion.

use glam::{DVec3, Mat4, Vec2, Vec3, Vec4};

/// Default view direction: looking from +x, −y, above, which shows a slope dipping toward +x
/// and the blocks resting on it.
pub const DEFAULT_AZIMUTH_DEG: f32 = -60.0;
pub const DEFAULT_ELEVATION_DEG: f32 = 25.0;
/// Narrow enough that parallel edges stay nearly parallel, as in report figures.
pub const DEFAULT_FOV_Y_DEG: f32 = 30.0;
/// Fraction of the half-width/half-height the framed box may fill (the rest is margin, which
/// also leaves room for the caption and legends).
const FRAME_FILL: f32 = 0.82;
/// Elevation is kept off the poles so the z-up `look_at` stays well defined.
const MAX_ELEVATION: f32 = 89.0 * std::f32::consts::PI / 180.0;

/// A ray in world coordinates (f64, like the physics).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    /// Unit direction.
    pub dir: DVec3,
}

/// Orbit camera around a target point.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// World point the f32 render coordinates are measured from.
    pub origin: DVec3,
    /// Orbit centre, relative to `origin`.
    pub target: Vec3,
    /// Angle of the eye around the z axis from +x toward +y, radians.
    pub azimuth: f32,
    /// Angle of the eye above the horizontal plane, radians.
    pub elevation: f32,
    /// Eye–target distance, same unit as the scene (m).
    pub distance: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Width / height of the image.
    pub aspect: f32,
    /// Radius of the framed scene, used to place the near and far planes.
    pub scene_radius: f32,
    /// Half extent of the framed box (centred on `origin`), kept so a changed view direction
    /// can be re-fitted.
    pub frame_half: Vec3,
}

impl Camera {
    /// Frames the box `[bbox_min, bbox_max]` from the default direction.
    pub fn frame(bbox_min: [f64; 3], bbox_max: [f64; 3], aspect: f32) -> Camera {
        Camera::frame_from(
            bbox_min,
            bbox_max,
            aspect,
            DEFAULT_AZIMUTH_DEG,
            DEFAULT_ELEVATION_DEG,
        )
    }

    /// Frames the box from the given direction (degrees): the target is the box centre and the
    /// distance is the smallest one at which all eight corners lie inside the image with a margin.
    pub fn frame_from(
        bbox_min: [f64; 3],
        bbox_max: [f64; 3],
        aspect: f32,
        azimuth_deg: f32,
        elevation_deg: f32,
    ) -> Camera {
        let (lo, hi) = sanitize_box(bbox_min, bbox_max);
        let origin = (lo + hi) * 0.5;
        let half = ((hi - lo) * 0.5).as_vec3();
        let mut cam = Camera {
            origin,
            target: Vec3::ZERO,
            azimuth: azimuth_deg.to_radians(),
            elevation: 0.0,
            distance: 1.0,
            fov_y: DEFAULT_FOV_Y_DEG.to_radians(),
            aspect: sanitize_aspect(aspect),
            scene_radius: half.length().max(1e-3),
            frame_half: half,
        };
        cam.set_elevation(elevation_deg.to_radians());
        cam.distance = cam.fit_distance(half);
        cam
    }

    /// Distance at which the box of half-extent `half` around the target fits the view.
    ///
    /// For a corner p (relative to the target) with camera-basis coordinates (x, y) and offset
    /// `p·back` toward the eye, it is inside the image when |x| ≤ tx·(d − p·back) and
    /// |y| ≤ ty·(d − p·back); the largest such lower bound on d over the corners is the answer.
    /// Every corner then also lies in front of the eye.
    fn fit_distance(&self, half: Vec3) -> f32 {
        let (right, up, back) = self.basis();
        let ty = (self.fov_y * 0.5).tan() * FRAME_FILL;
        let tx = ty * self.aspect;
        let mut d: f32 = 0.0;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { -half.x } else { half.x },
                if i & 2 == 0 { -half.y } else { half.y },
                if i & 4 == 0 { -half.z } else { half.z },
            );
            let along = corner.dot(back);
            d = d
                .max(along + corner.dot(right).abs() / tx)
                .max(along + corner.dot(up).abs() / ty);
        }
        d.max(self.scene_radius * 0.1).max(1e-3)
    }

    /// Applies user overrides (degrees, scene units, world coordinates). Unset distance is
    /// re-fitted to the box the camera was framed on when the direction changes.
    pub fn apply_override(&mut self, o: &CameraOverride) {
        let refit = o.azimuth_deg.is_some() || o.elevation_deg.is_some();
        if let Some(az) = o.azimuth_deg.filter(|v| v.is_finite()) {
            self.azimuth = az.to_radians();
        }
        if let Some(el) = o.elevation_deg.filter(|v| v.is_finite()) {
            self.set_elevation(el.to_radians());
        }
        if let Some(fov) = o
            .fov_y_deg
            .filter(|v| v.is_finite() && *v > 1.0 && *v < 170.0)
        {
            self.fov_y = fov.to_radians();
        }
        if refit {
            self.distance = self.fit_distance(self.frame_half);
        }
        if let Some(t) = o.target.filter(|t| t.iter().all(|v| v.is_finite())) {
            self.target = (DVec3::from_array(t) - self.origin).as_vec3();
        }
        if let Some(d) = o.distance.filter(|v| v.is_finite() && *v > 0.0) {
            self.distance = d;
        }
    }

    fn set_elevation(&mut self, el: f32) {
        self.elevation = if el.is_finite() {
            el.clamp(-MAX_ELEVATION, MAX_ELEVATION)
        } else {
            0.0
        };
    }

    /// Unit vectors (right, up, back) of the view; `back` points from the target to the eye.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let (sa, ca) = self.azimuth.sin_cos();
        let (se, ce) = self.elevation.sin_cos();
        let back = Vec3::new(ce * ca, ce * sa, se);
        let right = Vec3::Z.cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        (right, up, back)
    }

    /// Eye position relative to `origin`.
    pub fn eye(&self) -> Vec3 {
        self.target + self.basis().2 * self.distance
    }

    /// Eye position in world coordinates.
    pub fn eye_world(&self) -> DVec3 {
        self.origin + self.eye().as_dvec3()
    }

    /// Near and far planes: the framed sphere (and the grid around it) with room to spare.
    pub fn near_far(&self) -> (f32, f32) {
        let r = self.scene_radius * 2.5;
        let near = (self.distance - r).max(self.distance * 0.005).max(1e-4);
        let far = (self.distance + r).max(near * 2.0);
        (near, far)
    }

    /// World (relative to `origin`) → view space.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Z)
    }

    /// View → clip space, depth 0..1 as wgpu expects.
    pub fn projection(&self) -> Mat4 {
        let (near, far) = self.near_far();
        glam::camera::rh::proj::directx::perspective(self.fov_y, self.aspect, near, far)
    }

    pub fn view_proj(&self) -> Mat4 {
        self.projection() * self.view()
    }

    /// A world point converted to the f32 render coordinates.
    pub fn to_local(&self, world: [f64; 3]) -> Vec3 {
        (DVec3::from_array(world) - self.origin).as_vec3()
    }

    /// Pixel position (x right, y down, origin at the top-left corner of the image) of a world
    /// point, or `None` when the point is behind the eye.
    pub fn project(&self, world: [f64; 3], width: u32, height: u32) -> Option<Vec2> {
        self.project_local(self.to_local(world), width, height)
    }

    /// As [`Camera::project`] for a point already relative to `origin`.
    pub fn project_local(&self, local: Vec3, width: u32, height: u32) -> Option<Vec2> {
        let clip = self.view_proj() * local.extend(1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(Vec2::new(
            (ndc.x + 1.0) * 0.5 * width as f32,
            (1.0 - ndc.y) * 0.5 * height as f32,
        ))
    }

    /// Rotates the view by a mouse drag of (dx, dy) pixels: right drag turns the scene to the
    /// right, down drag raises the eye.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        const RAD_PER_PIXEL: f32 = 0.3 * std::f32::consts::PI / 180.0;
        if !(dx.is_finite() && dy.is_finite()) {
            return;
        }
        self.azimuth = (self.azimuth - dx * RAD_PER_PIXEL).rem_euclid(std::f32::consts::TAU);
        self.set_elevation(self.elevation + dy * RAD_PER_PIXEL);
    }

    /// Moves the target so that the point under the cursor follows a drag of (dx, dy) pixels in
    /// an image `viewport_height` pixels tall.
    pub fn pan(&mut self, dx: f32, dy: f32, viewport_height: f32) {
        if !(dx.is_finite() && dy.is_finite()) || viewport_height <= 0.0 {
            return;
        }
        let (right, up, _) = self.basis();
        let metres_per_pixel = 2.0 * self.distance * (self.fov_y * 0.5).tan() / viewport_height;
        self.target += (-right * dx + up * dy) * metres_per_pixel;
    }

    /// Zooms by mouse-wheel steps (positive = closer), 10 % per step.
    pub fn zoom(&mut self, wheel_steps: f32) {
        if !wheel_steps.is_finite() {
            return;
        }
        let min = self.scene_radius * 1e-3;
        let max = self.scene_radius * 1e3;
        self.distance = (self.distance * 0.9f32.powf(wheel_steps)).clamp(min, max);
    }

    /// The ray from the eye through pixel (x, y) (same convention as [`Camera::project`]).
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        let inv = self.view_proj().inverse();
        let ndc = Vec2::new(
            2.0 * x / width.max(1) as f32 - 1.0,
            1.0 - 2.0 * y / height.max(1) as f32,
        );
        let unproject = |z: f32| {
            let p = inv * Vec4::new(ndc.x, ndc.y, z, 1.0);
            p.truncate() / p.w
        };
        let near = unproject(0.0);
        let far = unproject(1.0);
        let dir = (far - near)
            .as_dvec3()
            .normalize_or(-self.basis().2.as_dvec3());
        Ray {
            origin: self.origin + near.as_dvec3(),
            dir,
        }
    }
}

/// Optional user settings that replace the automatic framing (the CLI's `--camera az,el,dist`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraOverride {
    pub azimuth_deg: Option<f32>,
    pub elevation_deg: Option<f32>,
    /// Eye–target distance, m.
    pub distance: Option<f32>,
    /// Orbit centre in world coordinates.
    pub target: Option<[f64; 3]>,
    pub fov_y_deg: Option<f32>,
}

impl CameraOverride {
    /// Parses `az,el` or `az,el,dist` (degrees, degrees, metres), as given to `--camera`. The
    /// messages do not name the flag: the command line puts `--camera: ` before them.
    pub fn parse(text: &str) -> Result<CameraOverride, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(format!(
                "expects az,el or az,el,dist (degrees, degrees, metres), got {text:?}"
            ));
        }
        let num = |s: &str, what: &str| -> Result<f32, String> {
            s.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{what} {s:?} is not a number"))
        };
        let mut o = CameraOverride {
            azimuth_deg: Some(num(parts[0], "azimuth")?),
            elevation_deg: Some(num(parts[1], "elevation")?),
            ..Default::default()
        };
        if let Some(d) = parts.get(2) {
            let d = num(d, "distance")?;
            if d <= 0.0 {
                return Err(format!("distance must be positive, got {d}"));
            }
            o.distance = Some(d);
        }
        Ok(o)
    }
}

/// Orders the corners, replaces non-finite input by a unit box and pads flat boxes so framing
/// never divides by zero.
fn sanitize_box(a: [f64; 3], b: [f64; 3]) -> (DVec3, DVec3) {
    let a = DVec3::from_array(a);
    let b = DVec3::from_array(b);
    if !(a.is_finite() && b.is_finite()) {
        return (DVec3::splat(-0.5), DVec3::splat(0.5));
    }
    let (mut lo, mut hi) = (a.min(b), a.max(b));
    let pad = ((hi - lo).max_element() * 0.01).max(0.05);
    for k in 0..3 {
        if hi[k] - lo[k] < 1e-9 {
            lo[k] -= pad;
            hi[k] += pad;
        }
    }
    (lo, hi)
}

fn sanitize_aspect(aspect: f32) -> f32 {
    if aspect.is_finite() && aspect > 1e-3 {
        aspect
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners(lo: [f64; 3], hi: [f64; 3]) -> Vec<[f64; 3]> {
        (0..8)
            .map(|i| {
                [
                    if i & 1 == 0 { lo[0] } else { hi[0] },
                    if i & 2 == 0 { lo[1] } else { hi[1] },
                    if i & 4 == 0 { lo[2] } else { hi[2] },
                ]
            })
            .collect()
    }

    fn assert_inside(cam: &Camera, lo: [f64; 3], hi: [f64; 3], w: u32, h: u32) {
        for c in corners(lo, hi) {
            let p = cam.project(c, w, h).expect("corner behind the eye");
            assert!(
                p.x >= 0.0 && p.x <= w as f32 && p.y >= 0.0 && p.y <= h as f32,
                "corner {c:?} projects to {p:?} outside {w}x{h}"
            );
        }
    }

    #[test]
    fn framing_keeps_every_corner_inside() {
        let boxes = [
            ([0.0, -1.0, 0.0], [10.0, 5.0, 5.7735]),
            ([-0.1, -0.1, -0.1], [0.1, 0.1, 0.1]),
            ([1e5, 2e5, 300.0], [1e5 + 50.0, 2e5 + 2.0, 301.0]),
            ([0.0, 0.0, 0.0], [100.0, 1.0, 0.0]), // flat in z
        ];
        for (lo, hi) in boxes {
            for (w, h) in [(1280, 720), (720, 1280), (500, 500)] {
                for (az, el) in [(-60.0, 25.0), (0.0, 0.0), (90.0, 80.0), (200.0, -30.0)] {
                    let cam = Camera::frame_from(lo, hi, w as f32 / h as f32, az, el);
                    assert_inside(&cam, lo, hi, w, h);
                }
            }
        }
    }

    #[test]
    fn framing_is_tight() {
        // The box should fill a good part of the image, not a speck in the middle.
        let (lo, hi) = ([0.0, -1.0, 0.0], [10.0, 5.0, 5.7735]);
        let cam = Camera::frame(lo, hi, 16.0 / 9.0);
        let pts: Vec<Vec2> = corners(lo, hi)
            .into_iter()
            .map(|c| cam.project(c, 1280, 720).unwrap())
            .collect();
        let w = pts.iter().map(|p| p.x).fold(f32::MIN, f32::max)
            - pts.iter().map(|p| p.x).fold(f32::MAX, f32::min);
        let h = pts.iter().map(|p| p.y).fold(f32::MIN, f32::max)
            - pts.iter().map(|p| p.y).fold(f32::MAX, f32::min);
        assert!(w > 0.6 * 1280.0 || h > 0.6 * 720.0, "extent {w} x {h}");
    }

    #[test]
    fn target_projects_to_centre_and_large_coordinates_keep_precision() {
        let lo = [4.0e5, 3.0e6, 100.0];
        let hi = [4.0e5 + 2.0, 3.0e6 + 2.0, 102.0];
        let cam = Camera::frame(lo, hi, 1.5);
        let c = cam
            .project([4.0e5 + 1.0, 3.0e6 + 1.0, 101.0], 300, 200)
            .unwrap();
        assert!(
            (c.x - 150.0).abs() < 1e-3 && (c.y - 100.0).abs() < 1e-3,
            "{c:?}"
        );
        // 1 mm sideways must move the projection (it would not in absolute f32).
        let d = cam
            .project([4.0e5 + 1.001, 3.0e6 + 1.0, 101.0], 3000, 2000)
            .unwrap();
        let c2 = cam
            .project([4.0e5 + 1.0, 3.0e6 + 1.0, 101.0], 3000, 2000)
            .unwrap();
        assert!((d - c2).length() > 0.1);
    }

    #[test]
    fn up_is_up_and_behind_is_none() {
        let cam = Camera::frame([-1.0; 3], [1.0; 3], 1.0);
        let top = cam.project([0.0, 0.0, 1.0], 100, 100).unwrap();
        let bottom = cam.project([0.0, 0.0, -1.0], 100, 100).unwrap();
        assert!(top.y < bottom.y, "z up must be up in the image");
        let behind = cam.eye_world() + (cam.eye_world() - cam.origin);
        assert!(cam.project(behind.to_array(), 100, 100).is_none());
    }

    #[test]
    fn orbit_pan_zoom() {
        let mut cam = Camera::frame([-1.0; 3], [1.0; 3], 1.0);
        let (az0, el0, d0) = (cam.azimuth, cam.elevation, cam.distance);
        cam.orbit(100.0, 0.0);
        assert!((cam.azimuth - az0).abs() > 0.1 && cam.elevation == el0);
        cam.orbit(0.0, 1e6);
        assert!(cam.elevation <= MAX_ELEVATION + 1e-6);
        assert!(
            cam.view().is_finite(),
            "view must stay defined at the pole clamp"
        );
        cam.orbit(f32::NAN, 1.0);
        assert!(cam.azimuth.is_finite());

        cam.zoom(1.0);
        assert!(cam.distance < d0);
        cam.zoom(-2.0);
        assert!(cam.distance > d0 * 0.99);

        // Dragging by p pixels moves the target point on screen by p pixels the same way.
        let mut cam = Camera::frame([-1.0; 3], [1.0; 3], 1.0);
        let before = cam.project_local(cam.target, 400, 400).unwrap();
        let world_pt = cam.origin + cam.target.as_dvec3();
        cam.pan(40.0, -20.0, 400.0);
        let after = cam.project(world_pt.to_array(), 400, 400).unwrap();
        let moved = after - before;
        assert!(
            (moved.x - 40.0).abs() < 0.5 && (moved.y + 20.0).abs() < 0.5,
            "{moved:?}"
        );
    }

    #[test]
    fn picking_ray_hits_the_projected_point() {
        let cam = Camera::frame([0.0, -1.0, 0.0], [10.0, 5.0, 5.77], 16.0 / 9.0);
        let p = [3.0, 1.0, 2.0];
        let px = cam.project(p, 1280, 720).unwrap();
        let ray = cam.ray(px.x, px.y, 1280, 720);
        let to_p = DVec3::from_array(p) - ray.origin;
        let off_axis = (to_p - ray.dir * to_p.dot(ray.dir)).length();
        assert!(off_axis < 1e-3, "ray misses by {off_axis}");
        assert!(to_p.dot(ray.dir) > 0.0);
    }

    #[test]
    fn overrides_and_parsing() {
        let o = CameraOverride::parse("30, 45,20").unwrap();
        assert_eq!(o.azimuth_deg, Some(30.0));
        assert_eq!(o.elevation_deg, Some(45.0));
        assert_eq!(o.distance, Some(20.0));
        assert!(CameraOverride::parse("30").is_err());
        assert!(CameraOverride::parse("a,b").is_err());
        assert!(CameraOverride::parse("1,2,-3").is_err());

        let (lo, hi) = ([0.0, 0.0, 0.0], [4.0, 4.0, 4.0]);
        let mut cam = Camera::frame(lo, hi, 1.0);
        cam.apply_override(&CameraOverride::parse("90,10").unwrap());
        assert!((cam.azimuth - 90f32.to_radians()).abs() < 1e-6);
        assert_inside(&cam, lo, hi, 400, 400);
        cam.apply_override(&CameraOverride {
            distance: Some(33.0),
            target: Some([1.0, 1.0, 1.0]),
            ..Default::default()
        });
        assert_eq!(cam.distance, 33.0);
        let t = cam.project([1.0, 1.0, 1.0], 400, 400).unwrap();
        assert!((t - Vec2::splat(200.0)).length() < 1e-2);
    }

    #[test]
    fn degenerate_input_does_not_panic() {
        let cam = Camera::frame([f64::NAN; 3], [1.0; 3], f32::NAN);
        assert!(cam.view_proj().is_finite());
        let cam = Camera::frame([2.0; 3], [2.0; 3], 0.0);
        assert!(cam.view_proj().is_finite());
        assert!(cam.project([2.0; 3], 10, 10).is_some());
    }
}
