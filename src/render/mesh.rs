//! CPU geometry for the renderer: flat-shaded block meshes, edge outlines, ground grid, axes
//! and arrows. Everything here is plain f32 data relative to the camera origin, so it is tested
//! without a GPU and shared by the off-screen and interactive paths.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

/// A linear-light RGBA colour (what the shaders blend in; the sRGB target encodes it).
pub type Rgba = [f32; 4];

/// A vertex of a lit triangle. Positions are relative to the camera origin.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SolidVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub color: Rgba,
}

/// A line segment drawn as a screen-space quad `width_px` pixels wide (hardware lines are one
/// pixel on most backends, too thin for figures).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct LineInstance {
    pub a: [f32; 3],
    pub width_px: f32,
    pub b: [f32; 3],
    pub _pad: f32,
    pub color: Rgba,
}

impl LineInstance {
    pub fn new(a: Vec3, b: Vec3, width_px: f32, color: Rgba) -> LineInstance {
        LineInstance {
            a: a.to_array(),
            width_px,
            b: b.to_array(),
            _pad: 0.0,
            color,
        }
    }
}

/// sRGB 0xRRGGBB → sRGB-encoded RGBA floats (opaque). Pass the result through
/// [`srgb_to_linear`] for the GPU; kept separate so colour tables stay readable as hex.
pub const fn hex(rgb: u32) -> Rgba {
    [
        ((rgb >> 16) & 0xff) as f32 / 255.0,
        ((rgb >> 8) & 0xff) as f32 / 255.0,
        (rgb & 0xff) as f32 / 255.0,
        1.0,
    ]
}

/// sRGB-encoded channel values → linear light.
pub fn srgb_to_linear(c: Rgba) -> Rgba {
    let f = |v: f32| {
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    [f(c[0]), f(c[1]), f(c[2]), c[3]]
}

/// Linear light → sRGB-encoded channel values (for the 2-D overlay, which takes sRGB colours).
pub fn linear_to_srgb(c: Rgba) -> Rgba {
    let f = |v: f32| {
        let v = v.clamp(0.0, 1.0);
        if v <= 0.003_130_8 {
            v * 12.92
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        }
    };
    [f(c[0]), f(c[1]), f(c[2]), c[3]]
}

/// Block colours, sRGB. Light, muted hues that stay apart from the arrow colours (blue, red)
/// and from the dark outlines; chosen by block index so a block keeps its colour in every frame.
pub const BLOCK_PALETTE_SRGB: [u32; 8] = [
    0xE3B96B, // sand
    0x93C47D, // sage
    0xB8A3D6, // lavender
    0xD9C55B, // mustard
    0x7CC4BE, // teal
    0xD8A0B4, // rose
    0xB5C95E, // olive
    0xCFA483, // tan
];
/// Fixed blocks (the rock mass, supports): a warm stone grey.
pub const FIXED_BLOCK_SRGB: u32 = 0xBDB8AE;
/// Contact arrows: locked contacts blue, sliding contacts red.
pub const LOCK_SRGB: u32 = 0x1F5FD0;
pub const SLIDE_SRGB: u32 = 0xE0301E;
pub const OPEN_SRGB: u32 = 0x808080;
/// Contact-normal glyphs (when drawn with the force arrows) are dark so they stay visible
/// where they poke out of a short force arrow.
pub const NORMAL_GLYPH_SRGB: u32 = 0x303030;
pub const EDGE_SRGB: u32 = 0x262626;
pub const GRID_SRGB: u32 = 0xC9CDD3;
pub const GRID_MAJOR_SRGB: u32 = 0xA9AEB6;

/// Linear colour of block `index`.
pub fn block_color(index: usize, fixed: bool) -> Rgba {
    let srgb = if fixed {
        FIXED_BLOCK_SRGB
    } else {
        BLOCK_PALETTE_SRGB[index % BLOCK_PALETTE_SRGB.len()]
    };
    srgb_to_linear(hex(srgb))
}

/// Base colours of rock masses (sRGB): earth tones, one per rock mass in turn.
pub const ROCK_MASS_SRGB: [u32; 6] = [0xC8A27A, 0x8FA6B8, 0xB7B48A, 0xB98C8C, 0x9DB59A, 0xA99ABF];

/// Linear colour of block `index` of rock mass `mass`, region `region`: the rock mass's colour,
/// its hue turned a little per region and its lightness varied per block (by a hash of the
/// index, the same in every frame) so that neighbouring blocks stay apart; fixed blocks muted.
pub fn rock_mass_color(mass: u16, region: u16, index: usize, fixed: bool) -> Rgba {
    let base = hex(ROCK_MASS_SRGB[usize::from(mass) % ROCK_MASS_SRGB.len()]);
    // Regions: rotate the colour's channels toward the next one by a fifth each.
    let r = f32::from(region % 4) * 0.2;
    let tinted = [
        base[0] * (1.0 - r) + base[1] * r,
        base[1] * (1.0 - r) + base[2] * r,
        base[2] * (1.0 - r) + base[0] * r,
    ];
    // A fixed hash of the index to a lightness factor in [0.78, 1.12].
    let h = (index as u32).wrapping_mul(2_654_435_761) >> 24;
    let k = 0.78 + 0.34 * (h as f32 / 255.0);
    let c = srgb_to_linear([
        (tinted[0] * k).min(1.0),
        (tinted[1] * k).min(1.0),
        (tinted[2] * k).min(1.0),
        1.0,
    ]);
    if fixed { desaturate(c, 0.7) } else { c }
}

/// Perceptually uniform colour map (viridis, sampled at 9 points, linear interpolation in sRGB),
/// `t` in [0, 1] (clamped; NaN maps to 0). Returns a linear colour.
pub fn colormap(t: f32) -> Rgba {
    const VIRIDIS: [u32; 9] = [
        0x440154, 0x472D7B, 0x3B528B, 0x2C728E, 0x21918C, 0x28AE80, 0x5EC962, 0xADDC30, 0xFDE725,
    ];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (hex(VIRIDIS[i]), hex(VIRIDIS[i + 1]));
    srgb_to_linear([
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
        1.0,
    ])
}

/// Mixes a colour toward grey (for muted variants).
pub fn desaturate(c: Rgba, amount: f32) -> Rgba {
    let g = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let m = |v: f32| v + (g - v) * amount;
    [m(c[0]), m(c[1]), m(c[2]), c[3]]
}

/// Errors from malformed geometry. The message names the offending block and face.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryError(pub String);

/// Appends one polyhedral block: each face fan-triangulated with its own (Newell) normal, and
/// every distinct edge once as an outline segment. `origin` is subtracted in f64 before the
/// conversion to f32.
#[allow(clippy::too_many_arguments)]
pub fn push_block(
    solids: &mut Vec<SolidVertex>,
    lines: &mut Vec<LineInstance>,
    name: &str,
    vertices: &[[f64; 3]],
    faces: &[Vec<u32>],
    origin: DVec3,
    color: Rgba,
    edge: Option<(f32, Rgba)>,
) -> Result<(), GeometryError> {
    let mut local = Vec::with_capacity(vertices.len());
    for (k, v) in vertices.iter().enumerate() {
        let p = DVec3::from_array(*v);
        if !p.is_finite() {
            return Err(GeometryError(format!(
                "block {name:?}: vertex {k} is not finite ({v:?})"
            )));
        }
        local.push((p - origin).as_vec3());
    }
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        if face.len() < 3 {
            return Err(GeometryError(format!(
                "block {name:?}: face {f} has {} vertices (needs 3 or more)",
                face.len()
            )));
        }
        if let Some(&bad) = face.iter().find(|&&i| i as usize >= local.len()) {
            return Err(GeometryError(format!(
                "block {name:?}: face {f} refers to vertex {bad}, but the block has {}",
                local.len()
            )));
        }
        let pts: Vec<Vec3> = face.iter().map(|&i| local[i as usize]).collect();
        let normal = newell_normal(&pts);
        for k in 1..pts.len() - 1 {
            for p in [pts[0], pts[k], pts[k + 1]] {
                solids.push(SolidVertex {
                    position: p.to_array(),
                    normal: normal.to_array(),
                    color,
                });
            }
        }
        for k in 0..face.len() {
            let (a, b) = (face[k], face[(k + 1) % face.len()]);
            edges.push((a.min(b), a.max(b)));
        }
    }
    if let Some((width, ecolor)) = edge {
        edges.sort_unstable();
        edges.dedup();
        for (a, b) in edges {
            if a != b {
                lines.push(LineInstance::new(
                    local[a as usize],
                    local[b as usize],
                    width,
                    ecolor,
                ));
            }
        }
    }
    Ok(())
}

/// Unit normal of a polygon by Newell's method (robust for slightly non-planar and
/// non-convex faces); +z for degenerate ones so shading stays defined.
pub fn newell_normal(pts: &[Vec3]) -> Vec3 {
    let mut n = Vec3::ZERO;
    for (k, p) in pts.iter().enumerate() {
        let q = pts[(k + 1) % pts.len()];
        n.x += (p.y - q.y) * (p.z + q.z);
        n.y += (p.z - q.z) * (p.x + q.x);
        n.z += (p.x - q.x) * (p.y + q.y);
    }
    n.normalize_or(Vec3::Z)
}

/// The 1–2–5 number at or above `x` (`x > 0`), for grid spacings and arrow scales people read.
pub fn nice_ceil(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    for m in [1.0, 2.0, 2.5, 5.0, 10.0] {
        if m * p >= x * (1.0 - 1e-12) {
            return m * p;
        }
    }
    10.0 * p
}

/// Ground grid on the plane z = `lo.z` covering the box's footprint with a margin; every fifth
/// line is darker. Returns the spacing used. Coordinates are relative to the camera origin;
/// `world_origin` keeps the lines on round world coordinates.
pub fn push_grid(
    lines: &mut Vec<LineInstance>,
    lo: Vec3,
    hi: Vec3,
    world_origin: DVec3,
    width_px: f32,
) -> f32 {
    let ext = (hi - lo).truncate().max_element().max(1e-3);
    let step = nice_ceil(ext as f64 / 10.0);
    let margin = ext * 0.15;
    // Snap to multiples of the step in world coordinates.
    let snap = |local: f32, axis: usize, up: bool| -> f64 {
        let w = world_origin[axis] + local as f64;
        let n = w / step;
        (if up { n.ceil() } else { n.floor() }) as i64 as f64
    };
    let (ix0, ix1) = (snap(lo.x - margin, 0, false), snap(hi.x + margin, 0, true));
    let (iy0, iy1) = (snap(lo.y - margin, 1, false), snap(hi.y + margin, 1, true));
    let to_local = |i: f64, axis: usize| -> f32 { (i * step - world_origin[axis]) as f32 };
    let (x0, x1) = (to_local(ix0, 0), to_local(ix1, 0));
    let (y0, y1) = (to_local(iy0, 1), to_local(iy1, 1));
    let z = lo.z;
    let minor = srgb_to_linear(hex(GRID_SRGB));
    let major = srgb_to_linear(hex(GRID_MAJOR_SRGB));
    // Bounded: at most ~16 lines per axis by construction of `step`.
    let mut i = ix0;
    while i <= ix1 {
        let x = to_local(i, 0);
        let m = (i as i64).rem_euclid(5) == 0;
        let (w, c) = if m {
            (width_px * 1.5, major)
        } else {
            (width_px, minor)
        };
        lines.push(LineInstance::new(
            Vec3::new(x, y0, z),
            Vec3::new(x, y1, z),
            w,
            c,
        ));
        i += 1.0;
    }
    let mut j = iy0;
    while j <= iy1 {
        let y = to_local(j, 1);
        let m = (j as i64).rem_euclid(5) == 0;
        let (w, c) = if m {
            (width_px * 1.5, major)
        } else {
            (width_px, minor)
        };
        lines.push(LineInstance::new(
            Vec3::new(x0, y, z),
            Vec3::new(x1, y, z),
            w,
            c,
        ));
        j += 1.0;
    }
    step as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_cube() -> (Vec<[f64; 3]>, Vec<Vec<u32>>) {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        // CCW seen from outside.
        let f = vec![
            vec![0, 3, 2, 1],
            vec![4, 5, 6, 7],
            vec![0, 1, 5, 4],
            vec![1, 2, 6, 5],
            vec![2, 3, 7, 6],
            vec![3, 0, 4, 7],
        ];
        (v, f)
    }

    #[test]
    fn cube_mesh_has_outward_normals_and_twelve_edges() {
        let (v, f) = unit_cube();
        let (mut s, mut l) = (Vec::new(), Vec::new());
        let origin = DVec3::splat(0.5);
        push_block(
            &mut s,
            &mut l,
            "cube",
            &v,
            &f,
            origin,
            [1.0; 4],
            Some((1.0, [0.0; 4])),
        )
        .unwrap();
        assert_eq!(s.len(), 6 * 2 * 3);
        assert_eq!(l.len(), 12);
        for t in s.chunks(3) {
            let c =
                (Vec3::from(t[0].position) + Vec3::from(t[1].position) + Vec3::from(t[2].position))
                    / 3.0;
            // Centroid of the cube is at the local origin, so outward means along c.
            assert!(Vec3::from(t[0].normal).dot(c) > 0.0);
            // Winding agrees with the normal.
            let (a, b, cc) = (
                Vec3::from(t[0].position),
                Vec3::from(t[1].position),
                Vec3::from(t[2].position),
            );
            assert!((b - a).cross(cc - a).dot(Vec3::from(t[0].normal)) > 0.0);
        }
    }

    #[test]
    fn bad_faces_are_errors_not_panics() {
        let (v, mut f) = unit_cube();
        f[2] = vec![0, 1, 99];
        let (mut s, mut l) = (Vec::new(), Vec::new());
        let e = push_block(&mut s, &mut l, "b", &v, &f, DVec3::ZERO, [1.0; 4], None);
        assert!(e.unwrap_err().0.contains("vertex 99"));
        let (v, mut f) = unit_cube();
        f[0] = vec![0, 1];
        assert!(push_block(&mut s, &mut l, "b", &v, &f, DVec3::ZERO, [1.0; 4], None).is_err());
        let (mut v, f) = unit_cube();
        v[3][1] = f64::NAN;
        assert!(push_block(&mut s, &mut l, "b", &v, &f, DVec3::ZERO, [1.0; 4], None).is_err());
    }

    #[test]
    fn nice_numbers() {
        assert_eq!(nice_ceil(0.7), 1.0);
        assert_eq!(nice_ceil(1.0), 1.0);
        assert_eq!(nice_ceil(1.3), 2.0);
        assert_eq!(nice_ceil(2.2), 2.5);
        assert_eq!(nice_ceil(3.0), 5.0);
        assert_eq!(nice_ceil(30800.0), 50000.0);
        assert_eq!(nice_ceil(0.0), 1.0);
    }

    #[test]
    fn grid_on_round_coordinates() {
        let mut l = Vec::new();
        let origin = DVec3::new(5.0, 2.0, 0.0);
        let lo = Vec3::new(-5.0, -3.0, 0.0);
        let hi = Vec3::new(5.0, 3.0, 5.0);
        let step = push_grid(&mut l, lo, hi, origin, 1.0);
        assert_eq!(step, 1.0);
        assert!(l.len() > 10 && l.len() < 60);
        for s in &l {
            assert_eq!(s.a[2], 0.0);
            // World x of x-lines is a whole multiple of the step.
            if s.a[0] == s.b[0] {
                let wx = s.a[0] as f64 + origin.x;
                assert!((wx - wx.round()).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn colours() {
        assert_eq!(block_color(0, false), block_color(8, false));
        assert_ne!(block_color(0, false), block_color(1, false));
        let lo = colormap(0.0);
        let hi = colormap(1.0);
        assert!(hi[1] > lo[1]);
        assert_eq!(colormap(f32::NAN), lo);
        let c = [0.2, 0.4, 0.6, 1.0];
        let back = srgb_to_linear(linear_to_srgb(c));
        for k in 0..3 {
            assert!((back[k] - c[k]).abs() < 1e-5);
        }
    }
}
