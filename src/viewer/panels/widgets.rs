//! Small widgets and formatting shared by the panels: number, length and duration formats,
//! colours, table-driven parameter sliders and labels, and the toolbar's icon buttons.

use egui::{Color32, Pos2, Rect, Stroke, Vec2};

use crate::params::table::Param;

/// Compact number: plain for 0.01..10⁴, else scientific with 3 significant digits.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if !v.is_finite() {
        format!("{v}")
    } else if (0.01..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let s = format!("{v:.2e}");
        // "2.00e8" reads better as "2e8"; keep meaningful digits.
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        format!("{m}e{e}")
    }
}

/// A length with a unit that suits its size.
pub fn length(m: f64) -> String {
    let a = m.abs();
    if !m.is_finite() {
        format!("{m}")
    } else if a == 0.0 {
        "0 m".into()
    } else if a < 1e-3 {
        format!("{} µm", num(m * 1e6))
    } else if a < 1.0 {
        format!("{} mm", num(m * 1e3))
    } else {
        format!("{} m", num(m))
    }
}

/// A duration in s or ms.
pub fn seconds(s: f64) -> String {
    if s.abs() < 0.1 && s != 0.0 {
        format!("{} ms", num(s * 1e3))
    } else {
        format!("{} s", num(s))
    }
}

pub fn color32(srgb: u32) -> Color32 {
    Color32::from_rgb((srgb >> 16) as u8, (srgb >> 8) as u8, srgb as u8)
}

pub const ACCENT: Color32 = Color32::from_rgb(0xE0, 0x7A, 0x10);
pub const ERROR_RED: Color32 = Color32::from_rgb(0xC0, 0x2A, 0x1E);
pub const OK_GREEN: Color32 = Color32::from_rgb(0x2E, 0x8B, 0x3E);

/// A slider that leaves values outside its range alone (a scene may set any valid value;
/// merely showing it must not change it), while keeping new edits inside the range.
pub fn slider<Num: egui::emath::Numeric>(
    value: &mut Num,
    range: std::ops::RangeInclusive<Num>,
) -> egui::Slider<'_> {
    egui::Slider::new(value, range).clamping(egui::SliderClamping::Edits)
}

/// The slider of a parameter of the table: its range (E is the model's Young's modulus), its
/// scale, and its unit. A logarithmic slider spans decades, so its values read best in [`num`].
pub fn param_slider<'a, Num: egui::emath::Numeric>(
    value: &'a mut Num,
    param: &Param,
    young: f64,
) -> egui::Slider<'a> {
    let range = param.widget_range(young);
    let s = slider(
        value,
        Num::from_f64(*range.start())..=Num::from_f64(*range.end()),
    )
    .suffix(param.suffix());
    if param.logarithmic() {
        s.logarithmic(true).custom_formatter(|v, _| num(v))
    } else {
        s
    }
}

/// A parameter's label, with its description as the tooltip.
pub fn param_label(ui: &mut egui::Ui, param: &Param) {
    ui.label(param.label).on_hover_text(param.doc());
}

/// Toolbar icons, drawn with the painter (egui's default fonts lack the media symbols).
#[derive(Clone, Copy)]
pub enum Icon {
    Play,
    Pause,
    Step,
    Reset,
    Record,
    Stop,
    Camera,
}

/// A button of fixed width with an icon left of its text.
pub fn icon_button(
    ui: &mut egui::Ui,
    width: f32,
    icon: Icon,
    text: &str,
    fill: Option<Color32>,
) -> egui::Response {
    // Leading spaces keep the centred text clear of the icon.
    let mut b = egui::Button::new(format!("      {text}"));
    if let Some(f) = fill {
        b = b.fill(f);
    }
    let r = ui.add_sized([width, 24.0], b);
    let color = ui.style().interact(&r).fg_stroke.color;
    let c = Pos2::new(r.rect.left() + 15.0, r.rect.center().y);
    paint_icon(ui.painter(), icon, c, color);
    r
}

/// Draws `icon` centred at `c`, in `color` where the icon has no colour of its own.
fn paint_icon(p: &egui::Painter, icon: Icon, c: Pos2, color: Color32) {
    let s = 5.0;
    let tri = |pts: Vec<Pos2>, color: Color32| {
        p.add(egui::Shape::convex_polygon(pts, color, Stroke::NONE));
    };
    let bar = |at: Pos2, size: Vec2, color: Color32| {
        p.rect_filled(Rect::from_center_size(at, size), 0.0, color);
    };
    match icon {
        Icon::Play => tri(
            vec![
                c + Vec2::new(-0.7 * s, -s),
                c + Vec2::new(s, 0.0),
                c + Vec2::new(-0.7 * s, s),
            ],
            OK_GREEN,
        ),
        Icon::Pause => {
            for dx in [-2.5, 2.5] {
                bar(c + Vec2::new(dx, 0.0), Vec2::new(2.5, 2.0 * s), color);
            }
        }
        Icon::Step => {
            tri(
                vec![
                    c + Vec2::new(-s, -s),
                    c + Vec2::new(0.5 * s, 0.0),
                    c + Vec2::new(-s, s),
                ],
                color,
            );
            bar(c + Vec2::new(0.9 * s, 0.0), Vec2::new(2.0, 2.0 * s), color);
        }
        Icon::Reset => {
            // An open circle with an arrow head: "back to the start".
            let pts: Vec<Pos2> = (0..=20)
                .map(|k| {
                    let a = (40.0 + 300.0 * k as f32 / 20.0).to_radians();
                    c + Vec2::new(a.cos(), -a.sin()) * s
                })
                .collect();
            let tip = pts[20];
            p.add(egui::Shape::line(pts, Stroke::new(1.6, color)));
            tri(
                vec![
                    tip + Vec2::new(-3.0, -3.0),
                    tip + Vec2::new(3.0, -1.0),
                    tip + Vec2::new(0.0, 3.0),
                ],
                color,
            );
        }
        Icon::Record => {
            p.circle_filled(c, s, ERROR_RED);
        }
        Icon::Stop => bar(c, Vec2::splat(2.0 * s - 1.0), ERROR_RED),
        Icon::Camera => {
            let body = c + Vec2::new(0.0, 1.0);
            p.rect_stroke(
                Rect::from_center_size(body, Vec2::new(2.4 * s, 1.7 * s)),
                1.5,
                Stroke::new(1.4, color),
                egui::StrokeKind::Middle,
            );
            p.circle_stroke(body, 0.45 * s, Stroke::new(1.4, color));
            bar(
                c + Vec2::new(-0.4 * s, -0.95 * s),
                Vec2::new(0.8 * s, 0.4 * s),
                color,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_well() {
        assert_eq!(num(2.0e8), "2e8");
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(35.0), "35");
        assert_eq!(num(1.234e-5), "1.23e-5");
        assert_eq!(length(0.0004), "400 µm");
        assert_eq!(length(0.05), "50 mm");
        assert_eq!(length(2.5), "2.5 m");
        assert_eq!(seconds(0.01), "10 ms");
        assert_eq!(seconds(2.0), "2 s");
    }
}
