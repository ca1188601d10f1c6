//! The paper's §3.1 validation: Table 1 (block resting on a 30° slope, static mode) and Table 2
//! (block sliding down it, dynamic mode), for DDA-3a (ALM) and DDA-3p (penalty). The closed
//! forms are the paper's, written out here; `dda3d::compare`'s (what `run --compare` writes to
//! compare.json) must agree with them.

use std::path::Path;

use dda3d::compare::slope::{self, Motion};
use dda3d::compare::tables;
use dda3d::params::Method;
use dda3d::scene;
use dda3d::snapshot::ContactState;
use dda3d::solver::Solver;

const THETA: f64 = 30.0;

fn downslope() -> [f64; 3] {
    let t = THETA.to_radians();
    [t.cos(), 0.0, -t.sin()]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn solver(file: &str, method: Method) -> Solver {
    let mut s = scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(file),
    )
    .expect("scene loads");
    s.params.method = method;
    Solver::new(s.model, s.params)
}

struct Table1 {
    /// (along-slope position of the contact point, normal force, penetration, penalty, λ)
    contacts: Vec<(f64, f64, f64, f64, f64)>,
    drift: f64,
    /// The library's table of the same state.
    table: tables::StandingTable,
}

/// The library's closed form of a slope scene agrees with the paper's geometry.
fn closed_form(s: &Solver, motion: Motion) -> slope::SlopeCase {
    let case = slope::of_solver(s).expect("a slope with a closed form");
    assert_eq!(case.motion, motion);
    assert!((case.theta_deg - THETA).abs() < 1e-9);
    let d = downslope();
    assert!((0..3).all(|k| (case.downslope[k] - d[k]).abs() < 1e-12));
    assert!((case.weight - 2750.0 * 8.0 * 9.8).abs() < 1e-6);
    case
}

fn run_table1(method: Method) -> Table1 {
    let mut s = solver("slope_stable.toml", method);
    let case = closed_form(&s, Motion::Stands);
    while !s.finished() {
        s.step().expect("no divergence");
    }
    assert!((s.time - 2.0).abs() < 1e-12);
    let snap = s.snapshot();
    let block = snap.blocks.iter().find(|b| b.name == "block").unwrap();
    let contacts = snap
        .contacts
        .iter()
        .map(|c| {
            assert_eq!(
                c.state,
                ContactState::Lock,
                "φ = 35° > 30°: every contact holds"
            );
            (
                dot(c.point, downslope()),
                c.normal_force,
                c.penetration,
                c.penalty,
                c.lambda,
            )
        })
        .collect();
    let d = block.displacement;
    Table1 {
        contacts,
        drift: dot(d, d).sqrt(),
        table: tables::standing(&case, &snap),
    }
}

#[test]
fn table1_stable_block_contact_forces() {
    // (P25) with mg = 2750 · 8 · 9.8 = 215 600 N and tan α = H/L = 0.5.
    let mg = 2750.0 * 8.0 * 9.8;
    let alpha = 0.5f64.atan();
    let th = THETA.to_radians();
    let n_up = (th + alpha).cos() / (4.0 * alpha.cos()) * mg;
    let n_down = (th - alpha).cos() / (4.0 * alpha.cos()) * mg;
    assert!((n_up - 33203.8).abs() < 0.05 && (n_down - 60153.8).abs() < 0.05);

    let mut worst = std::collections::HashMap::new();
    println!("\nTable 1 at t = 2.00 s (static mode)");
    println!(
        "{:8} {:10} {:>12} {:>12} {:>10} {:>12} {:>12}",
        "method", "contact", "theory N", "N", "error %", "d_n m", "p_n N/m"
    );
    for method in [Method::Alm, Method::Penalty] {
        let t = run_table1(method);
        assert_eq!(
            t.contacts.len(),
            4,
            "{method:?}: the four base corners, no duplicates"
        );
        let mid = t.contacts.iter().map(|c| c.0).sum::<f64>() / 4.0;
        let mut err_max: f64 = 0.0;
        for &(pos, n, dn, pn, lambda) in &t.contacts {
            let (label, theory) = if pos < mid {
                ("N1=N2", n_up)
            } else {
                ("N3=N4", n_down)
            };
            let err = (n - theory).abs() / theory;
            err_max = err_max.max(err);
            println!(
                "{:8} {:10} {:>12.1} {:>12.1} {:>10.4} {:>12.3e} {:>12.2e}  λ = {:.1}",
                format!("{method:?}"),
                label,
                theory,
                n,
                100.0 * err,
                dn,
                pn,
                lambda
            );
            match method {
                Method::Alm => {
                    assert!(
                        err <= 0.0004,
                        "ALM {label}: error {:.5} % > 0.04 %",
                        100.0 * err
                    );
                    assert!(dn <= 1.3e-5, "ALM {label}: penetration {dn:e} m > 1.3e-5 m");
                }
                Method::Penalty => {
                    // DDA-3p: the force is carried by the penetration alone, N = p_n d_n, so the
                    // penetration is N / p_n = 1.66e-4 and 3.01e-4 m (paper: 1.648e-4, 3.0008e-4).
                    assert!((n - pn * dn).abs() < 1e-6 * n);
                    assert!(
                        (dn - theory / 2.0e8).abs() < 0.01 * theory / 2.0e8,
                        "{label}: {dn:e}"
                    );
                }
            }
        }
        assert!(t.drift < 1e-3, "{method:?}: the block crept {} m", t.drift);
        // compare.json's Table 1: the same forces against the same (P25).
        assert_eq!(t.table.contacts.len(), 4);
        for row in &t.table.contacts {
            let theory = if row.along_slope < 0.0 { n_up } else { n_down };
            assert!(
                (row.theory.unwrap() - theory).abs() < 1e-6 * theory,
                "{row:?}"
            );
        }
        assert!(t.table.normal_error_percent < 1e-6 && t.table.drift == t.drift);
        worst.insert(format!("{method:?}"), err_max);
    }
    println!(
        "largest force error: ALM {:.2e} %, penalty {:.2e} %",
        100.0 * worst["Alm"],
        100.0 * worst["Penalty"]
    );
    assert!(
        worst["Penalty"] > worst["Alm"],
        "the penalty method is the less accurate one"
    );
}

#[test]
fn table2_sliding_block_displacement() {
    let th = THETA.to_radians();
    let phi = 15f64.to_radians();
    let acc = 0.5 * (th.sin() - th.cos() * phi.tan()) * 9.8;
    let case = closed_form(&solver("slope_sliding.toml", Method::Alm), Motion::Slides);
    assert!((0.5 * case.acceleration - acc).abs() < 1e-12);
    // The paper's DDA-3a relative errors (%), the bar every row must meet.
    let paper_3a = [0.34, 0.20, 0.13, 0.09, 0.07, 0.06, 0.05, 0.08, 0.07, 0.02];
    let paper_3p = [17.26, 6.95, 5.29, 4.20, 3.58, 3.08, 2.59, 2.28, 2.01, 1.77];
    let mut results = Vec::new();
    for method in [Method::Alm, Method::Penalty] {
        let mut s = solver("slope_sliding.toml", method);
        let x0 = s.snapshot().blocks[1].centroid;
        let mut rows = Vec::new();
        for k in 1..=10 {
            let t = 0.2 * k as f64;
            while s.time < t - 1e-12 {
                s.step_until(t).expect("no divergence");
            }
            assert!((s.time - t).abs() < 1e-12);
            let c = s.snapshot().blocks[1].centroid;
            let disp = dot([c[0] - x0[0], c[1] - x0[1], c[2] - x0[2]], downslope());
            rows.push(disp);
        }
        results.push(rows);
    }
    println!("\nTable 2: centroid travel along the slope (m) and relative error (%)");
    println!(
        "{:>5} {:>9} {:>9} {:>9} {:>8} {:>8} {:>10} {:>10}",
        "t s", "theory", "ALM", "penalty", "err ALM", "err pen", "paper 3a", "paper 3p"
    );
    for k in 0..10 {
        let t = 0.2 * (k + 1) as f64;
        let theory = acc * t * t;
        let (a, p) = (results[0][k], results[1][k]);
        let (ea, ep) = (
            100.0 * (a - theory).abs() / theory,
            100.0 * (p - theory).abs() / theory,
        );
        println!(
            "{t:>5.1} {theory:>9.4} {a:>9.4} {p:>9.4} {ea:>8.3} {ep:>8.3} {:>10.2} {:>10.2}",
            paper_3a[k], paper_3p[k]
        );
        assert!(
            ea <= paper_3a[k],
            "t = {t}: ALM error {ea:.3} % above the paper's {} %",
            paper_3a[k]
        );
        assert!(ea < ep, "t = {t}: ALM must beat the penalty baseline");
    }
}
