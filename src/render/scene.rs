//! From a [`Snapshot`] to what the GPU draws: the geometry buffers plus the few numbers the
//! caption and legends print. Pure CPU work (tested without a GPU).

use glam::{DVec3, Vec3};

use super::RenderError;
use super::arrow_mesh::{Arrow, ArrowInstance};
use super::camera::{Camera, CameraOverride};
use super::mesh::{
    self, EDGE_SRGB, LOCK_SRGB, LineInstance, NORMAL_GLYPH_SRGB, OPEN_SRGB, Rgba, SLIDE_SRGB,
    SolidVertex, hex, srgb_to_linear,
};
use crate::snapshot::{BlockSnapshot, ContactSnapshot, ContactState, Snapshot};

/// What decides a block's colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coloring {
    /// A fixed palette colour per block index (the same in every frame).
    #[default]
    PerBlock,
    /// Speed of the centroid, |v| (m/s), through a colour map.
    Velocity,
    /// Magnitude of the centroid displacement since t = 0 (m), through a colour map.
    Displacement,
    /// A colour per rock mass, shaded per region and block; hand-made blocks as `PerBlock`.
    RockMass,
}

impl Coloring {
    /// Parses `block`, `velocity` or `displacement` (for a CLI flag).
    pub fn parse(s: &str) -> Result<Coloring, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "block" | "blocks" | "per-block" => Ok(Coloring::PerBlock),
            "velocity" | "speed" | "v" => Ok(Coloring::Velocity),
            "displacement" | "disp" | "u" => Ok(Coloring::Displacement),
            "rock-mass" | "rockmass" | "mass" | "region" => Ok(Coloring::RockMass),
            other => Err(format!(
                "unknown colouring {other:?} (expected block, velocity, displacement or \
                 rock-mass)"
            )),
        }
    }
}

/// Contacts drawn with arrows by default: the strongest this many. Every shipped scene but the
/// jointed slope has fewer, so their pictures show every contact.
pub const DEFAULT_ARROW_LIMIT: usize = 500;

/// Which contact arrows to draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ArrowMode {
    None,
    /// Unit-length glyphs along the contact normals.
    Normals,
    /// Arrows along the normal with length = normal force / scale.
    #[default]
    Forces,
    /// Force arrows, plus thin dark normal glyphs (visible where a force is small).
    Both,
}

/// How a frame looks. The defaults make a report figure.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneStyle {
    pub coloring: Coloring,
    /// Colour-map range for [`Coloring::Velocity`]/[`Coloring::Displacement`]; `None` = 0 to the
    /// largest value in the frame.
    pub field_range: Option<(f64, f64)>,
    pub arrows: ArrowMode,
    /// Newtons per metre of force arrow; `None` = chosen so that the largest force in the frame
    /// is about as long as a block (at most 20 % of the scene), rounded to a 1–2–2.5–5 number.
    pub force_scale: Option<f64>,
    /// Draw the arrows of at most this many contacts, the strongest (largest |N|); `None` =
    /// all. Ten thousand arrows on a rock mass hide it; the strongest show its load paths.
    pub arrow_limit: Option<usize>,
    /// Transparent background (alpha 0) instead of the light grey one.
    pub transparent: bool,
    pub grid: bool,
    pub edges: bool,
    /// Caption (scene, time, step), legends and the axis triad.
    pub overlay: bool,
}

impl Default for SceneStyle {
    fn default() -> Self {
        SceneStyle {
            coloring: Coloring::PerBlock,
            field_range: None,
            arrows: ArrowMode::Forces,
            force_scale: None,
            arrow_limit: Some(DEFAULT_ARROW_LIMIT),
            transparent: false,
            grid: true,
            edges: true,
            overlay: true,
        }
    }
}

/// The reference box of a picture: where the camera looks, how big arrows and grid cells are,
/// and the origin the f32 coordinates are measured from. Kept fixed across the frames of an
/// animation so nothing jumps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneFrame {
    pub lo: DVec3,
    pub hi: DVec3,
}

impl SceneFrame {
    /// The bounding box of all block vertices (a unit box at the origin when there are none).
    pub fn of_snapshot(snap: &Snapshot) -> SceneFrame {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for b in &snap.blocks {
            for v in &b.vertices {
                let p = DVec3::from_array(*v);
                if p.is_finite() {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
        if lo.is_finite() && hi.is_finite() {
            SceneFrame::from_box(lo.to_array(), hi.to_array())
        } else {
            SceneFrame::from_box([-0.5; 3], [0.5; 3])
        }
    }

    /// A box given by two corners (any order). Non-finite input gives a unit box.
    pub fn from_box(a: [f64; 3], b: [f64; 3]) -> SceneFrame {
        let (a, b) = (DVec3::from_array(a), DVec3::from_array(b));
        if !(a.is_finite() && b.is_finite()) {
            return SceneFrame {
                lo: DVec3::splat(-0.5),
                hi: DVec3::splat(0.5),
            };
        }
        SceneFrame {
            lo: a.min(b),
            hi: a.max(b),
        }
    }

    /// Centre of the box: the origin of the f32 render coordinates.
    pub fn origin(&self) -> DVec3 {
        (self.lo + self.hi) * 0.5
    }

    /// Length of the box diagonal (at least 1 mm), the yardstick for glyph sizes.
    pub fn size(&self) -> f64 {
        (self.hi - self.lo).length().max(1e-3)
    }

    /// The camera that frames this box for an image of the given aspect, with user overrides.
    pub fn camera(&self, aspect: f32, view: &CameraOverride) -> Camera {
        let mut cam = Camera::frame(self.lo.to_array(), self.hi.to_array(), aspect);
        cam.apply_override(view);
        cam
    }
}

/// The text the caption prints.
#[derive(Clone, Debug, PartialEq)]
pub struct Caption {
    pub scene_name: String,
    pub time: f64,
    pub step: u64,
    /// While the initial equilibrium stage runs (time stands at 0): its static steps so far and
    /// R_max after the last one. A stage of a large rock mass takes minutes, and the picture
    /// barely moves meanwhile.
    pub stage: Option<(u64, f64)>,
}

/// Colour-map legend.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldLegend {
    pub label: &'static str,
    pub unit: &'static str,
    pub min: f64,
    pub max: f64,
}

/// Everything one frame draws, in f32 coordinates relative to `origin`.
#[derive(Clone, Debug)]
pub struct RenderScene {
    pub origin: DVec3,
    /// Block faces (and nothing else) — lit, depth-tested.
    pub solids: Vec<SolidVertex>,
    /// Contact arrows — drawn depth-tested, then again faintly where hidden, so an arrow inside
    /// or behind a block still reads.
    pub arrows: Vec<ArrowInstance>,
    /// Outlines and grid.
    pub lines: Vec<LineInstance>,
    pub caption: Caption,
    /// N per metre of arrow in effect, when force arrows are drawn and there are contacts.
    pub force_scale: Option<f64>,
    pub field: Option<FieldLegend>,
    pub contacts_lock: usize,
    pub contacts_slide: usize,
    /// Contacts drawn with arrows, when [`SceneStyle::arrow_limit`] left some out.
    pub arrows_shown: Option<usize>,
    pub transparent: bool,
    pub overlay: bool,
    /// Grid spacing in metres, when a grid is drawn.
    pub grid_step: Option<f64>,
}

/// Background of opaque frames (sRGB): a light grey that prints well and separates white-ish
/// blocks from the page.
pub const BACKGROUND_SRGB: u32 = 0xF4F4F1;

impl RenderScene {
    /// Builds the frame. Errors on malformed blocks (face indices out of range, non-finite
    /// vertices); contacts with non-finite data are skipped.
    pub fn build(
        snap: &Snapshot,
        style: &SceneStyle,
        frame: &SceneFrame,
    ) -> Result<RenderScene, RenderError> {
        let origin = frame.origin();
        let field = FieldLegend::for_style(snap, style);
        let mut solids = Vec::new();
        let mut lines = Vec::new();
        push_blocks(snap, style, field.as_ref(), origin, &mut solids, &mut lines)?;
        let contacts = ContactArrows::build(snap, style, frame);
        let grid_step = style.grid.then(|| {
            let lo = (frame.lo - origin).as_vec3();
            let hi = (frame.hi - origin).as_vec3();
            mesh::push_grid(&mut lines, lo, hi, origin, 1.0) as f64
        });
        Ok(RenderScene {
            origin,
            solids,
            arrows: contacts.arrows,
            lines,
            caption: Caption {
                scene_name: snap.scene_name.clone(),
                time: snap.time,
                step: snap.step,
                stage: snap
                    .equilibrium
                    .filter(|r| r.running)
                    .map(|r| (r.steps, r.residual)),
            },
            force_scale: contacts.force_scale,
            field,
            contacts_lock: contacts.lock,
            contacts_slide: contacts.slide,
            arrows_shown: contacts.shown,
            transparent: style.transparent,
            overlay: style.overlay,
            grid_step,
        })
    }

    /// Linear background colour (alpha 0 when transparent).
    pub fn background(&self) -> Rgba {
        if self.transparent {
            [0.0; 4]
        } else {
            srgb_to_linear(hex(BACKGROUND_SRGB))
        }
    }

    /// Local (f32) position of a world point.
    pub fn to_local(&self, world: [f64; 3]) -> Vec3 {
        (DVec3::from_array(world) - self.origin).as_vec3()
    }
}

/// A block's colour-map value under `coloring` (`None` for per-block colours, or when the
/// value is not finite).
fn field_value(b: &BlockSnapshot, coloring: Coloring) -> Option<f64> {
    let v = match coloring {
        Coloring::PerBlock | Coloring::RockMass => return None,
        Coloring::Velocity => DVec3::from_array(b.velocity).length(),
        Coloring::Displacement => DVec3::from_array(b.displacement).length(),
    };
    v.is_finite().then_some(v)
}

/// Largest colour-map value among the moving blocks of a snapshot (0 when there is none).
pub(super) fn field_max(snap: &Snapshot, coloring: Coloring) -> f64 {
    snap.blocks
        .iter()
        .filter(|b| !b.fixed)
        .filter_map(|b| field_value(b, coloring))
        .fold(0.0, f64::max)
}

impl FieldLegend {
    /// The legend of `style.coloring` (`None` for per-block colours): the range given, or 0 to
    /// the largest value in the frame.
    fn for_style(snap: &Snapshot, style: &SceneStyle) -> Option<FieldLegend> {
        let (label, unit) = match style.coloring {
            Coloring::PerBlock | Coloring::RockMass => return None,
            Coloring::Velocity => ("speed |v|", "m/s"),
            Coloring::Displacement => ("displacement |u|", "m"),
        };
        let (min, max) = match style.field_range {
            Some((a, b)) if a.is_finite() && b.is_finite() && b > a => (a, b),
            _ => (0.0, field_max(snap, style.coloring)),
        };
        Some(FieldLegend {
            label,
            unit,
            min,
            max,
        })
    }

    /// The colour-map colour of `v` (the bottom of the map when the range is empty).
    fn color(&self, v: f64) -> Rgba {
        let t = if self.max > self.min {
            (v - self.min) / (self.max - self.min)
        } else {
            0.0
        };
        mesh::colormap(t as f32)
    }
}

/// Faces and (with `style.edges`) outlines of every block: moving blocks coloured by the field
/// when there is one, fixed blocks and per-block colouring from the palette.
fn push_blocks(
    snap: &Snapshot,
    style: &SceneStyle,
    field: Option<&FieldLegend>,
    origin: DVec3,
    solids: &mut Vec<SolidVertex>,
    lines: &mut Vec<LineInstance>,
) -> Result<(), RenderError> {
    let edge = style
        .edges
        .then(|| (1.4f32, srgb_to_linear(hex(EDGE_SRGB))));
    for (i, b) in snap.blocks.iter().enumerate() {
        let color = match (field, field_value(b, style.coloring), b.rock_mass) {
            (Some(f), Some(v), _) if !b.fixed => f.color(v),
            (_, _, Some((mass, region))) if style.coloring == Coloring::RockMass => {
                mesh::rock_mass_color(mass, region, i, b.fixed)
            }
            _ => mesh::block_color(i, b.fixed),
        };
        mesh::push_block(
            solids,
            lines,
            &b.name,
            &b.vertices,
            &b.faces,
            origin,
            color,
            edge,
        )
        .map_err(|e| RenderError::InvalidSnapshot(e.0))?;
    }
    Ok(())
}

/// The contact part of a frame: its arrows and what the force legend prints.
struct ContactArrows {
    arrows: Vec<ArrowInstance>,
    force_scale: Option<f64>,
    lock: usize,
    slide: usize,
    /// How many contacts have arrows, when not all of them do.
    shown: Option<usize>,
}

/// Radius and length of the glyphs, m.
#[derive(Clone, Copy)]
struct GlyphSize {
    shaft: f32,
    normal_len: f32,
}

impl ContactArrows {
    fn build(snap: &Snapshot, style: &SceneStyle, frame: &SceneFrame) -> ContactArrows {
        let size = frame.size();
        // Arrow lengths and thickness follow the blocks, within the scene's size: on a rock
        // mass of a thousand blocks an arrow a fifth of the scene long crosses fifty blocks.
        let block = typical_block_size(snap).unwrap_or(size);
        let mut usable: Vec<&ContactSnapshot> = snap
            .contacts
            .iter()
            .filter(|c| {
                DVec3::from_array(c.point).is_finite()
                    && DVec3::from_array(c.normal).is_finite()
                    && DVec3::from_array(c.normal).length() > 1e-12
                    && c.normal_force.is_finite()
            })
            .collect();
        let count = |s: ContactState| usable.iter().filter(|c| c.state == s).count();
        let (lock, slide, total) = (
            count(ContactState::Lock),
            count(ContactState::Slide),
            usable.len(),
        );
        strongest(&mut usable, style.arrow_limit);
        let draw_forces = matches!(style.arrows, ArrowMode::Forces | ArrowMode::Both);
        let draw_normals = matches!(style.arrows, ArrowMode::Normals | ArrowMode::Both);
        let force_scale = (draw_forces && !usable.is_empty()).then(|| match style.force_scale {
            Some(s) if s.is_finite() && s > 0.0 => s,
            _ => {
                let max_force = usable
                    .iter()
                    .map(|c| c.normal_force.abs())
                    .fold(0.0, f64::max);
                auto_force_scale(max_force, size, block)
            }
        });
        let glyph = GlyphSize {
            shaft: (size * 0.005).min(block * 0.06) as f32,
            normal_len: (size * 0.06).min(block * 0.5) as f32,
        };
        let mut arrows = Vec::new();
        for c in &usable {
            let base = (DVec3::from_array(c.point) - frame.origin()).as_vec3();
            if let Some(scale) = force_scale {
                push_force_arrow(&mut arrows, c, base, scale, size.min(5.0 * block), glyph);
            }
            if draw_normals {
                push_normal_glyph(&mut arrows, c, base, draw_forces, glyph);
            }
        }
        ContactArrows {
            arrows,
            force_scale,
            lock,
            slide,
            shown: (usable.len() < total).then_some(usable.len()),
        }
    }
}

/// Lock blue, slide red, open grey.
fn state_color(state: ContactState) -> Rgba {
    srgb_to_linear(hex(match state {
        ContactState::Lock => LOCK_SRGB,
        ContactState::Slide => SLIDE_SRGB,
        ContactState::Open => OPEN_SRGB,
    }))
}

/// The force on block i as an arrow from the contact point, `scale` N per metre.
fn push_force_arrow(
    arrows: &mut Vec<ArrowInstance>,
    c: &ContactSnapshot,
    base: Vec3,
    scale: f64,
    scene_size: f64,
    glyph: GlyphSize,
) {
    let n = DVec3::from_array(c.normal).normalize().as_vec3();
    // The force on block i is +N·n (n points from j toward i); a tensile (negative) force
    // points the other way.
    let dir = if c.normal_force >= 0.0 { n } else { -n };
    // Impacts can carry a hundred times the static forces that set a fixed scale; cap the
    // arrow at 40 % of the view so it does not cross the whole picture.
    let len = ((c.normal_force.abs() / scale) as f32).min(0.4 * scene_size as f32);
    let arrow = Arrow::new(base, dir, len, glyph.shaft);
    arrows.extend(ArrowInstance::new(&arrow, state_color(c.state)));
}

/// A fixed-length glyph along the contact normal: thin and dark beside force arrows, in the
/// contact's state colour on its own.
fn push_normal_glyph(
    arrows: &mut Vec<ArrowInstance>,
    c: &ContactSnapshot,
    base: Vec3,
    beside_forces: bool,
    glyph: GlyphSize,
) {
    let n = DVec3::from_array(c.normal).normalize().as_vec3();
    let (r, color) = if beside_forces {
        (glyph.shaft * 0.45, srgb_to_linear(hex(NORMAL_GLYPH_SRGB)))
    } else {
        (glyph.shaft, state_color(c.state))
    };
    arrows.extend(ArrowInstance::new(
        &Arrow::new(base, n, glyph.normal_len, r),
        color,
    ));
}

/// Median bounding-box diagonal of the blocks (None without blocks).
fn typical_block_size(snap: &Snapshot) -> Option<f64> {
    let mut sizes: Vec<f64> = snap
        .blocks
        .iter()
        .filter_map(|b| {
            let mut lo = DVec3::splat(f64::INFINITY);
            let mut hi = DVec3::splat(f64::NEG_INFINITY);
            for v in &b.vertices {
                let p = DVec3::from_array(*v);
                lo = lo.min(p);
                hi = hi.max(p);
            }
            let d = (hi - lo).length();
            (d.is_finite() && d > 0.0).then_some(d)
        })
        .collect();
    if sizes.is_empty() {
        return None;
    }
    sizes.sort_by(f64::total_cmp);
    Some(sizes[(sizes.len() - 1) / 2])
}

/// N per metre of arrow so that the largest force draws about 20 % of the scene size, rounded
/// up to a number a legend reads cleanly.
pub fn auto_force_scale(max_force: f64, scene_size: f64, block_size: f64) -> f64 {
    if !(max_force.is_finite() && max_force > 0.0) {
        return 1.0;
    }
    let longest = (0.20 * scene_size).min(block_size).max(1e-3);
    mesh::nice_ceil(max_force / longest)
}

/// Keeps the `limit` contacts with the largest |N| (ties in their order), in their order.
fn strongest(contacts: &mut Vec<&ContactSnapshot>, limit: Option<usize>) {
    let Some(limit) = limit.filter(|&l| l < contacts.len()) else {
        return;
    };
    let mut order: Vec<usize> = (0..contacts.len()).collect();
    order.sort_by(|&a, &b| {
        let f = |k: usize| contacts[k].normal_force.abs();
        f(b).total_cmp(&f(a)).then(a.cmp(&b))
    });
    order.truncate(limit);
    order.sort_unstable();
    *contacts = order.into_iter().map(|k| contacts[k]).collect();
}

#[cfg(test)]
mod tests;
