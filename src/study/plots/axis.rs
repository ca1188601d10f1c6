//! One plot axis from one study column: its range with margins, its ticks and their labels.
//! Pure functions, so the awkward inputs (no value, one value, all equal, a log column with a
//! zero) are settled here and tested without drawing anything.

/// How a column's values become positions on the axis.
#[derive(Clone, Debug, PartialEq)]
pub enum Scale {
    /// Positions are the values; `integral`: every value is a whole number (a count), so the
    /// ticks fall on whole numbers.
    Linear { integral: bool },
    /// Positions are log10 of the values.
    Log10,
    /// Positions are indexes into these labels (cut to the room they have).
    Categories(Vec<String>),
}

/// An axis: the plotted range `lo..hi` in positions, the labelled ticks and the unlabelled
/// minor ticks (positions too).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub ticks: Vec<f64>,
    pub minor: Vec<f64>,
    pub scale: Scale,
}

/// The margin left on each side of the data, as a fraction of its span, so that no point sits
/// on the frame.
const MARGIN: f64 = 0.05;

/// About how many characters of a tick label fit in the room of one of `max_ticks` ticks; a
/// category label is cut to the room its share of the ticks leaves, so that neighbouring labels
/// do not run together, and never beyond [`MAX_CATEGORY_CHARS`].
const CHARS_PER_TICK: usize = 12;
const MAX_CATEGORY_CHARS: usize = 24;

impl Axis {
    /// The axis for a column's `values`. `log`: draw it in log scale, which needs every value
    /// positive; with a zero or a negative value the axis falls back to linear rather than
    /// hide those cases. `categories`: the values are indexes into these labels.
    /// `max_ticks`: about how many labelled ticks fit.
    pub fn new(
        values: &[Option<f64>],
        log: bool,
        categories: Option<&[String]>,
        max_ticks: usize,
    ) -> Axis {
        let max_ticks = max_ticks.max(2);
        if let Some(labels) = categories {
            return categorical(labels, max_ticks);
        }
        let finite: Vec<f64> = values
            .iter()
            .flatten()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if log && !finite.is_empty() && finite.iter().all(|&v| v > 0.0) {
            let logs: Vec<f64> = finite.iter().map(|v| v.log10()).collect();
            let (lo, hi) = linear_range(&logs, false);
            let (ticks, minor) = log_ticks(lo, hi, max_ticks);
            return Axis {
                lo,
                hi,
                ticks,
                minor,
                scale: Scale::Log10,
            };
        }
        let integral = !finite.is_empty() && finite.iter().all(|v| v.fract() == 0.0);
        let (lo, hi) = linear_range(&finite, integral);
        let step = tick_step(lo, hi, max_ticks, integral);
        Axis {
            lo,
            hi,
            ticks: multiples(lo, hi, step),
            minor: Vec::new(),
            scale: Scale::Linear { integral },
        }
    }

    /// Where a value sits on the axis; None where it cannot be drawn (not finite, not positive
    /// on a log axis, not a category index).
    pub fn position(&self, value: f64) -> Option<f64> {
        if !value.is_finite() {
            return None;
        }
        match &self.scale {
            Scale::Linear { .. } => Some(value),
            Scale::Log10 => (value > 0.0).then(|| value.log10()),
            Scale::Categories(labels) => {
                let index_ok = value.fract() == 0.0 && value >= 0.0 && value < labels.len() as f64;
                index_ok.then_some(value)
            }
        }
    }

    /// The label of the tick at `position`.
    pub fn label(&self, position: f64) -> String {
        match &self.scale {
            Scale::Linear { .. } => {
                let step = match self.ticks.as_slice() {
                    [a, b, ..] => b - a,
                    _ => self.hi - self.lo,
                };
                linear_label(position, step, self.lo.abs().max(self.hi.abs()))
            }
            Scale::Log10 => short(10f64.powf(position)),
            Scale::Categories(labels) => {
                let index = position.round();
                if index < 0.0 {
                    return String::new();
                }
                labels.get(index as usize).cloned().unwrap_or_default()
            }
        }
    }
}

/// Categories sit at 0, 1, …, n − 1, half a slot from each side; with more labels than fit,
/// every k-th is labelled.
fn categorical(labels: &[String], max_ticks: usize) -> Axis {
    let n = labels.len();
    let every = n.div_ceil(max_ticks).max(1);
    let ticks: Vec<f64> = (0..n).step_by(every).map(|i| i as f64).collect();
    let room = (CHARS_PER_TICK * max_ticks / ticks.len().max(1)).clamp(6, MAX_CATEGORY_CHARS);
    Axis {
        lo: -0.5,
        hi: n.max(1) as f64 - 0.5,
        ticks,
        minor: Vec::new(),
        scale: Scale::Categories(labels.iter().map(|l| cut(l, room)).collect()),
    }
}

/// The range `lo..hi` that holds `values` with a margin. No value: 0..1. All values equal (or
/// equal to within rounding): a range around the value, at least ±1 for whole numbers so that
/// their ticks stay whole, ±10 % otherwise (±1 around zero).
pub fn linear_range(values: &[f64], integral: bool) -> (f64, f64) {
    let Some(&first) = values.first() else {
        return (0.0, 1.0);
    };
    let (min, max) = values
        .iter()
        .fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    // Halves throughout, so that values near ±f64::MAX give a finite span.
    let half_span = max / 2.0 - min / 2.0;
    if half_span <= max.abs().max(min.abs()) * 0.5e-12 {
        let mut half = max.abs() * 0.1;
        if integral {
            half = half.max(1.0);
        }
        if half == 0.0 {
            half = 1.0;
        }
        return (max - half, max + half);
    }
    let margin = MARGIN * 2.0 * half_span;
    ((min - margin).max(f64::MIN), (max + margin).min(f64::MAX))
}

/// The step between ticks over `lo..hi`: 1, 2 or 5 times a power of ten, the smallest that
/// gives at most `max_ticks` ticks; at least 1 for whole numbers.
pub fn tick_step(lo: f64, hi: f64, max_ticks: usize, integral: bool) -> f64 {
    let count = |step: f64| ((hi / step).floor() - (lo / step).ceil() + 1.0).max(0.0) as usize;
    // A step of span / max_ticks gives at most max_ticks + 1 ticks, so the answer is that or
    // one of the next smaller nice steps.
    let n = max_ticks.max(1) as f64;
    let raw = hi / n - lo / n;
    let decade = raw.log10().floor() as i32;
    let steps: Vec<f64> = (decade - 1..=decade + 1)
        .flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e)))
        .collect();
    let smallest = |limit: usize| {
        let fitting = steps.iter().copied().filter(|&s| count(s) <= limit);
        fitting.reduce(f64::min).unwrap_or(raw)
    };
    let mut step = smallest(max_ticks);
    // One or two ticks say little about a scale: one tick over the budget is the better deal.
    if count(step) < 3 {
        step = smallest(max_ticks + 1);
    }
    if integral { step.max(1.0) } else { step }
}

/// The multiples of `step` in `lo..=hi`, each computed as k·step (no running sum, so no drift).
pub fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    if step.is_nan() || step <= 0.0 || !lo.is_finite() || !hi.is_finite() {
        return Vec::new();
    }
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    // A step that is tiny beside the range (a caller's mistake) would ask for millions of ticks.
    if last.saturating_sub(first) > 1000 {
        return Vec::new();
    }
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Ticks of a log axis over the positions `lo..hi` (log10 of the values): powers of ten when
/// the axis spans enough decades, else 1, 2 and 5 times them, else plain steps in value
/// space; minor ticks at 2…9 times the powers of ten.
pub fn log_ticks(lo: f64, hi: f64, max_ticks: usize) -> (Vec<f64>, Vec<f64>) {
    let first = lo.floor() as i64;
    let last = hi.ceil() as i64;
    let within = |p: &f64| *p >= lo && *p <= hi;
    let minor: Vec<f64> = (first..=last)
        .flat_map(|e| (2..=9).map(move |m| e as f64 + (m as f64).log10()))
        .filter(within)
        .collect();
    let powers: Vec<f64> = (first..=last).map(|e| e as f64).filter(within).collect();
    if powers.len() >= 2 {
        let every = powers.len().div_ceil(max_ticks).max(1);
        return (powers.into_iter().step_by(every).collect(), minor);
    }
    let one_two_five: Vec<f64> = (first..=last)
        .flat_map(|e| [1.0f64, 2.0, 5.0].map(|m| e as f64 + m.log10()))
        .filter(within)
        .collect();
    if one_two_five.len() >= 3 && one_two_five.len() <= max_ticks {
        return (one_two_five, minor);
    }
    // Less than a decade: ticks at round values, placed at their logarithms.
    let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
    let step = tick_step(a, b, max_ticks, false);
    let ticks = multiples(a, b, step)
        .into_iter()
        .filter(|v| *v > 0.0)
        .map(f64::log10)
        .collect();
    (ticks, Vec::new())
}

/// The magnitudes written in fixed notation; others in scientific, where fixed would be long.
const FIXED: std::ops::Range<f64> = 1e-3..1e5;

/// A tick label with the decimals that `step` needs; scientific notation for large or small
/// magnitudes (`scale`: the largest magnitude on the axis), where fixed notation would be long.
pub fn linear_label(value: f64, step: f64, scale: f64) -> String {
    if value == 0.0 {
        return "0".into();
    }
    if !FIXED.contains(&scale) {
        let digits = (value.abs().log10().floor() - step.log10().floor()).max(0.0) as usize;
        return format!("{value:.digits$e}");
    }
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let text = format!("{value:.decimals$}");
    // −0.0 printed with decimals, from k·step rounding, reads as a negative zero.
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0".into()
    } else {
        text
    }
}

/// A value in at most six significant digits, without trailing zeros.
pub fn short(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    // Rounding through the decimal text gives the double nearest the short decimal, which
    // `{}` then prints as exactly that decimal.
    let rounded: f64 = format!("{value:.5e}").parse().unwrap_or(value);
    if !FIXED.contains(&rounded.abs()) {
        format!("{rounded:e}")
    } else {
        format!("{rounded}")
    }
}

/// `text` cut to `max` characters, the cut marked with an ellipsis.
pub fn cut(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let kept: String = text.chars().take(max.saturating_sub(1)).collect();
    format!("{kept}…")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn some(values: &[f64]) -> Vec<Option<f64>> {
        values.iter().map(|&v| Some(v)).collect()
    }

    #[test]
    fn ranges_have_margins_and_never_collapse() {
        let (lo, hi) = linear_range(&[-f64::MAX, f64::MAX], false);
        assert_eq!((lo, hi), (f64::MIN, f64::MAX));
        let step = tick_step(lo, hi, 6, false);
        assert!(
            step.is_finite() && !multiples(lo, hi, step).is_empty(),
            "{step}"
        );
        assert_eq!(linear_range(&[], false), (0.0, 1.0));
        assert_eq!(linear_range(&[0.0, 10.0], false), (-0.5, 10.5));
        assert_eq!(linear_range(&[2.0], false), (1.8, 2.2));
        assert_eq!(linear_range(&[2.0, 2.0], true), (1.0, 3.0));
        assert_eq!(linear_range(&[0.0, 0.0], false), (-1.0, 1.0));
        assert_eq!(linear_range(&[-5.0], false), (-5.5, -4.5));
        let (lo, hi) = linear_range(&[1e-9], false);
        assert!(lo < 1e-9 && hi > 1e-9 && hi - lo < 1e-9, "{lo} {hi}");
    }

    #[test]
    fn steps_are_one_two_five_and_whole_for_counts() {
        assert_eq!(tick_step(0.0, 10.0, 6, false), 2.0);
        assert_eq!(tick_step(0.0, 10.0, 11, false), 1.0);
        assert_eq!(tick_step(0.0, 10.0, 10, false), 2.0);
        // 2, 4, 6, 8 fit in 4 ticks where span / 4 = 2.1 would ask for a step of 5.
        assert_eq!(tick_step(1.5, 9.9, 4, false), 2.0);
        assert_eq!(tick_step(0.05, 0.95, 4, false), 0.2);
        assert_eq!(tick_step(0.0, 0.4, 8, true), 1.0);
        // 6, 8, …, 14 is one tick over 4, but 5 would leave the single tick 10.
        assert_eq!(tick_step(5.6, 14.4, 4, false), 2.0);
        assert_eq!(multiples(-0.2, 4.2, 1.0), vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(multiples(0.05, 0.95, 0.5), vec![0.5]);
        assert_eq!(multiples(0.0, 1.0, f64::NAN), Vec::<f64>::new());
    }

    #[test]
    fn a_count_axis_ticks_whole_numbers() {
        let axis = Axis::new(&some(&[0.0, 1.0, 4.0, 2.0]), false, None, 6);
        assert_eq!(axis.scale, Scale::Linear { integral: true });
        assert_eq!((axis.lo, axis.hi), (-0.2, 4.2));
        assert_eq!(axis.ticks, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        let labels: Vec<String> = axis.ticks.iter().map(|&t| axis.label(t)).collect();
        assert_eq!(labels, ["0", "1", "2", "3", "4"]);
    }

    #[test]
    fn awkward_values_give_a_usable_axis() {
        for values in [
            vec![],
            vec![None, None],
            some(&[f64::NAN, f64::INFINITY]),
            some(&[3.0]),
            some(&[7.5, 7.5, 7.5]),
        ] {
            let axis = Axis::new(&values, false, None, 6);
            assert!(axis.lo < axis.hi, "{values:?}: {axis:?}");
            assert!(!axis.ticks.is_empty(), "{values:?}: {axis:?}");
            assert!(axis.ticks.iter().all(|t| *t >= axis.lo && *t <= axis.hi));
        }
        let axis = Axis::new(&some(&[1.0, f64::NAN]), false, None, 6);
        assert_eq!(axis.position(f64::NAN), None);
        assert_eq!(axis.position(1.0), Some(1.0));
    }

    #[test]
    fn a_log_axis_over_decades_ticks_powers_of_ten() {
        let axis = Axis::new(&some(&[0.01, 1.0, 50.0]), true, None, 8);
        assert_eq!(axis.scale, Scale::Log10);
        assert_eq!(axis.ticks, vec![-2.0, -1.0, 0.0, 1.0]);
        let labels: Vec<String> = axis.ticks.iter().map(|&t| axis.label(t)).collect();
        assert_eq!(labels, ["0.01", "0.1", "1", "10"]);
        assert!(axis.minor.contains(&2f64.log10()));
        assert_eq!(axis.position(100.0), Some(2.0));
        assert_eq!(axis.position(0.0), None);
    }

    #[test]
    fn a_log_axis_within_a_decade_ticks_round_values() {
        let axis = Axis::new(&some(&[2.0, 9.0]), true, None, 6);
        let labels: Vec<String> = axis.ticks.iter().map(|&t| axis.label(t)).collect();
        assert_eq!(labels, ["2", "4", "6", "8"]);
        let axis = Axis::new(&some(&[1.5, 60.0]), true, None, 6);
        let labels: Vec<String> = axis.ticks.iter().map(|&t| axis.label(t)).collect();
        assert_eq!(labels, ["2", "5", "10", "20", "50"]);
    }

    #[test]
    fn a_log_column_with_a_zero_falls_back_to_linear() {
        let axis = Axis::new(&some(&[0.0, 10.0]), true, None, 6);
        assert_eq!(axis.scale, Scale::Linear { integral: true });
        assert_eq!(axis.position(0.0), Some(0.0));
    }

    #[test]
    fn categories_sit_at_their_indexes() {
        let labels = vec![
            "alm".to_string(),
            "penalty-with-a-much-longer-name".to_string(),
        ];
        let axis = Axis::new(&some(&[0.0, 1.0, 1.0]), false, Some(&labels), 6);
        assert_eq!((axis.lo, axis.hi), (-0.5, 1.5));
        assert_eq!(axis.ticks, vec![0.0, 1.0]);
        assert_eq!(axis.label(0.0), "alm");
        assert_eq!(axis.label(1.0), "penalty-with-a-much-lon…");
        let narrow = Axis::new(&[], false, Some(&labels), 2);
        assert_eq!(narrow.label(1.0), "penalty-wit…");
        assert_eq!(axis.position(1.0), Some(1.0));
        assert_eq!(axis.position(2.0), None);
        assert_eq!(axis.position(0.5), None);
        let many: Vec<String> = (0..20).map(|i| format!("c{i}")).collect();
        let axis = Axis::new(&[], false, Some(&many), 6);
        assert_eq!(axis.ticks, vec![0.0, 4.0, 8.0, 12.0, 16.0]);
        let none = Axis::new(&[], false, Some(&[]), 6);
        assert!(none.lo < none.hi && none.ticks.is_empty());
    }

    #[test]
    fn labels_are_short() {
        assert_eq!(linear_label(0.30000000000000004, 0.1, 1.0), "0.3");
        assert_eq!(linear_label(-0.0, 0.1, 1.0), "0");
        assert_eq!(linear_label(12.0, 2.0, 20.0), "12");
        assert_eq!(linear_label(1.2e7, 2e6, 2e7), "1.2e7");
        assert_eq!(linear_label(2e-4, 1e-4, 5e-4), "2e-4");
        assert_eq!(short(0.1 + 0.2), "0.3");
        assert_eq!(short(2e6), "2e6");
        assert_eq!(cut("abcdef", 4), "abc…");
        assert_eq!(cut("abc", 4), "abc");
    }
}
