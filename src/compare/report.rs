//! `compare.json`: what two runs of one scene did side by side. A [`Recorder`] takes the two
//! runs' states at each common time as they go, and at the end the [`Report`]: the runs and
//! the settings that tell them apart, the comparison at every time, and, for a scene with a
//! closed form ([`super::slope`]), the paper's Table 1 or Table 2 with a column per run.

use serde::Serialize;

use super::difference::{Comparison, compare};
use super::sample::Sample;
use super::slope::{Motion, SlopeCase};
use super::tables::{StandingTable, TravelRow, standing, travel};
use crate::snapshot::Snapshot;

/// One of the two runs, as it ended.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Where its files are, relative to compare.json (`A`, `B`).
    pub dir: String,
    /// The settings it does not share with the other run, `name=value`.
    pub labels: Vec<String>,
    pub method: String,
    pub mode: String,
    /// As its summary.json says: completed, diverged, interrupted or io_error.
    pub status: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Simulated time reached, s.
    pub time: f64,
    pub steps: u64,
    /// The run's largest penetration (summary.json's `max_penetration`), m.
    pub max_penetration: f64,
}

/// Each run's closed form, or why it has none.
#[derive(Clone, Debug, Serialize)]
pub struct ClosedForm {
    pub a: Option<SlopeCase>,
    pub b: Option<SlopeCase>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a_none: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub b_none: Option<String>,
}

/// A table with a column per run (a run whose block does not stand, or slide, has none).
#[derive(Clone, Debug, Serialize)]
pub struct Columns<T> {
    pub a: Option<T>,
    pub b: Option<T>,
}

/// Table 2 at one time.
#[derive(Clone, Debug, Serialize)]
pub struct TravelRows {
    pub time: f64,
    pub a: Option<TravelRow>,
    pub b: Option<TravelRow>,
}

/// compare.json.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub scene: String,
    /// Simulated time between comparisons, s.
    pub interval: f64,
    pub a: RunReport,
    pub b: RunReport,
    /// The comparison time with the largest displacement difference (the first of equals).
    pub largest_difference: Option<Comparison>,
    pub closed_form: ClosedForm,
    /// The standing block's forces at each run's last state (paper Table 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table1: Option<Columns<StandingTable>>,
    /// The sliding block's travel at every comparison time (paper Table 2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table2: Option<Vec<TravelRows>>,
    pub times: Vec<Comparison>,
}

/// Builds a [`Report`] as two runs go.
pub struct Recorder {
    names: Vec<String>,
    cases: [Result<SlopeCase, String>; 2],
    times: Vec<Comparison>,
    travel: Vec<TravelRows>,
}

impl Recorder {
    /// For runs of a scene with blocks `names` and each run's closed form (or why it has none:
    /// see [`super::slope::of_solver`]).
    pub fn new(
        names: Vec<String>,
        a: Result<SlopeCase, String>,
        b: Result<SlopeCase, String>,
    ) -> Self {
        Recorder {
            names,
            cases: [a, b],
            times: Vec::new(),
            travel: Vec::new(),
        }
    }

    fn case(&self, side: usize, motion: Motion) -> Option<&SlopeCase> {
        self.cases[side]
            .as_ref()
            .ok()
            .filter(|c| c.motion == motion)
    }

    /// The two runs at one common time.
    pub fn add(&mut self, a: &Sample, b: &Sample) {
        self.times.push(compare(a, b, &self.names));
        let row = |side: usize, s: &Sample| self.case(side, Motion::Slides).map(|c| travel(c, s));
        if self.case(0, Motion::Slides).is_some() || self.case(1, Motion::Slides).is_some() {
            let rows = TravelRows {
                time: a.time,
                a: row(0, a),
                b: row(1, b),
            };
            self.travel.push(rows);
        }
    }

    /// The comparisons so far.
    pub fn times(&self) -> &[Comparison] {
        &self.times
    }

    /// The report, with each run's last state for Table 1.
    pub fn finish(
        self,
        scene: String,
        interval: f64,
        runs: [RunReport; 2],
        last: [&Snapshot; 2],
    ) -> Report {
        let table1 = |side: usize| {
            self.case(side, Motion::Stands)
                .map(|c| standing(c, last[side]))
        };
        let table1 = Columns {
            a: table1(0),
            b: table1(1),
        };
        let has_table1 = table1.a.is_some() || table1.b.is_some();
        let largest = self.times.iter().fold(None::<&Comparison>, |m, c| match m {
            Some(m) if m.max_displacement_difference >= c.max_displacement_difference => Some(m),
            _ => Some(c),
        });
        let [a, b] = runs;
        let [case_a, case_b] = self.cases;
        Report {
            scene,
            interval,
            a,
            b,
            largest_difference: largest.cloned(),
            closed_form: ClosedForm {
                a_none: case_a.as_ref().err().cloned(),
                b_none: case_b.as_ref().err().cloned(),
                a: case_a.ok(),
                b: case_b.ok(),
            },
            table1: has_table1.then_some(table1),
            table2: (!self.travel.is_empty()).then_some(self.travel),
            times: self.times,
        }
    }
}
