//! Blocks that slide from rest travel as rigid-plastic Coulomb friction says, from their first
//! step (issue #12, item 4): blocks on slopes just beyond their friction limit, and blocks pushed
//! along a flat base by a point load. While a locked contact was only a soft shear spring, a new
//! contact stayed locked in the first step with a shear below its capacity, and the block gained
//! speed it kept for the rest of the run: 3 % too far in 2 s at a factor of safety of 0.9 on 30°,
//! 0.6 % too far in 1 s under a push of 1.5 μmg.

use dda3d::params::Method;

mod travel_support;
use travel_support::{displacement, on_slope, travel};

const ROCK: &str =
    "[materials.rock]\ndensity = 2750.0\nyoung_modulus = 2.0e10\npoisson_ratio = 0.25\n";

/// Keeps the largest error and its case, for the test's printed summary.
fn keep_worst(worst: &mut (f64, String), err: f64, case: String) {
    if err > worst.0 {
        *worst = (err, case);
    }
}

/// A block `a` × `a` × `h` on a fixed slope of `theta` degrees with tan φ = `fos` tan θ, long
/// enough for the fastest block's 2 s (20 m), the block near its upper end.
fn slope(theta: f64, fos: f64, a: f64, h: f64) -> String {
    slope_of_length(theta, fos, a, h, 8.0 * a + 40.0)
}

/// [`slope`] on a slope `length` m long.
fn slope_of_length(theta: f64, fos: f64, a: f64, h: f64, length: f64) -> String {
    let phi = (fos * theta.to_radians().tan()).atan().to_degrees();
    let depth = a.max(h);
    let shift = length / 2.0 - 2.0 * a;
    let c = |s: f64, along: f64| on_slope(theta, s, along);
    format!(
        "[joint]\nfriction_angle = {phi}\n{ROCK}\
         [[blocks]]\nname = \"slope\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [{length}, {}, {depth}], center = {}, rotation = [0, {theta}, 0] }}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\n\
         box = {{ size = [{a}, {a}, {h}], center = {}, rotation = [0, {theta}, 0] }}\n",
        2.0 * a,
        c(-depth / 2.0, shift),
        c(h / 2.0, 0.0)
    )
}

/// Coulomb's travel from rest on a slope of `theta` degrees at a factor of safety `fos`
/// (tan φ = `fos` tan θ) after `time` s, m: ½ g (sin θ − cos θ tan φ) t².
fn coulomb_travel(theta: f64, fos: f64, time: f64) -> f64 {
    let t = theta.to_radians();
    0.5 * 9.8 * (t.sin() - t.cos() * fos * t.tan()) * time * time
}

/// A block `a` × `a` × `h` on a flat fixed base with friction angle `phi`, pushed along x at its
/// centroid by `times` × μ m g.
fn push(phi: f64, times: f64, a: f64, h: f64) -> String {
    let mu = phi.to_radians().tan();
    let force = times * mu * 2750.0 * a * a * h * 9.8;
    format!(
        "[joint]\nfriction_angle = {phi}\n{ROCK}\
         [[blocks]]\nname = \"base\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [{}, {}, 1], center = [0, 0, -0.5] }}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\n\
         box = {{ size = [{a}, {a}, {h}], center = [0, 0, {}] }}\n\
         loads = [{{ point = [0, 0, {}], force = [{force}, 0, 0] }}]\n",
        12.0 * a + 40.0,
        3.0 * a,
        h / 2.0,
        h / 2.0
    )
}

#[test]
fn slides_near_the_friction_limit_match_theory_from_the_first_step() {
    let mut worst = (0.0f64, String::new());
    for theta in [20.0f64, 30.0, 40.0] {
        for fos in [0.5, 0.8, 0.9, 0.95] {
            for (a, h) in [(2.0, 1.0), (4.0, 1.0), (1.0, 0.5)] {
                let want = coulomb_travel(theta, fos, 2.0);
                let got = travel(&slope(theta, fos, a, h), Method::Alm, Some(2.0));
                let err = (got - want).abs() / want;
                let case = format!("θ {theta}°, F {fos}, {a} × {h} m");
                // At F = 0.95 the net acceleration is 5 % of the driving one, so an error in the
                // driving force is 20 times larger in the travel.
                let bound = if fos < 0.92 { 5e-4 } else { 1e-3 };
                assert!(
                    err < bound,
                    "{case}: travelled {got:.5} m, theory {want:.5} m"
                );
                keep_worst(&mut worst, err, case);
            }
        }
    }
    println!(
        "slides: largest error at 2 s {:.4} % ({})",
        100.0 * worst.0,
        worst.1
    );
}

#[test]
fn pushed_blocks_match_theory_from_the_first_step() {
    let mut worst = (0.0f64, String::new());
    for phi in [20.0f64, 30.0, 40.0] {
        for times in [1.2, 1.5, 3.0] {
            for (a, h) in [(2.0, 1.0), (1.0, 0.5)] {
                // The push and the base's friction turn the block about its front edge unless
                // times · μ · h/2 < a/2 (with a margin: the front edge carries the load).
                if times * phi.to_radians().tan() * h > 0.8 * a {
                    continue;
                }
                // Net force (times − 1) μ m g: s = ½ (times − 1) μ g t².
                let want = 0.5 * (times - 1.0) * phi.to_radians().tan() * 9.8;
                let got = travel(&push(phi, times, a, h), Method::Alm, Some(1.0));
                let err = (got - want).abs() / want;
                keep_worst(
                    &mut worst,
                    err,
                    format!("φ {phi}°, {times} μmg, {a} × {h} m"),
                );
            }
        }
    }
    println!(
        "pushes: largest error at 1 s {:.4} % ({})",
        100.0 * worst.0,
        worst.1
    );
    assert!(worst.0 < 5e-4, "{:.4} % at {}", 100.0 * worst.0, worst.1);
}

/// Small, light blocks slide too (2 to 20 cm blocks on a slope of about 40 m). The slip
/// tolerance f0·w0 scales with the contact group (w0 = half the slope's length), while a corner
/// spring's extension scales with the block's weight: held to f0·w0 alone, blocks up to about
/// 40 kg never slid, even without friction (their travel was 10⁻⁸ m). A contact pressed by more
/// than 1 % of the lighter block's weight now slides by Mohr–Coulomb alone. Under DDA-3a the
/// friction of a contact that has just begun to slide is then solved again until its lateral
/// stiffness k⊥ and (for a block this small) its direction τ follow the slip it makes: before,
/// 10 cm blocks started a step late (up to 17 % short at 1 s at F = 0.95 on 10°) and 2 cm
/// blocks at F ≥ 0.8 never slid.
#[test]
fn small_light_blocks_slide_as_theory_says() {
    let mut worst = [(0.0f64, String::new()), (0.0f64, String::new())];
    for (a, h) in [(0.02, 0.01), (0.1, 0.05), (0.2, 0.1)] {
        for theta in [10.0f64, 20.0, 45.0] {
            for fos in [0.0, 0.5, 0.95] {
                for (m, method) in [Method::Alm, Method::Penalty].into_iter().enumerate() {
                    let want = coulomb_travel(theta, fos, 1.0);
                    let got = travel(&slope(theta, fos, a, h), method, Some(1.0));
                    let err = (got - want).abs() / want;
                    let case = format!("{method:?}, θ {theta}°, F {fos}, {a} × {h} m");
                    let bound = match (fos == 0.0, method) {
                        (true, _) => 1e-3,
                        (false, Method::Alm) => 3e-3,
                        // The baseline's soft springs: 0.6 % at F = 0.95 on 10° (2 cm).
                        (false, Method::Penalty) => 1e-2,
                    };
                    assert!(
                        err < bound,
                        "{case}: travelled {got:.6} m, theory {want:.6} m"
                    );
                    keep_worst(&mut worst[m], err, case);
                }
            }
        }
    }
    for (err, case) in worst {
        println!(
            "small blocks: largest error at 1 s {:.3} % ({case})",
            100.0 * err
        );
    }
}

/// Blocks just past their friction limit (F = 0.99: a net acceleration 1 % of the driving one)
/// slide, under DDA-3a, as Coulomb says. Such a block gains speed so slowly that its second step
/// slips less than f0·w0 (1 m on 10°: 2·10⁻⁶ m against 5·10⁻⁶ m), which the stop rule read as a
/// stop: the contacts stuck again every step and the block stood (travel 4·10⁻⁵ m of 8.5 mm at
/// 1 s). A contact that slips at least as far as its blocks' velocities carry it is speeding up,
/// not stopping (`law::speeds_up`).
#[test]
fn blocks_just_past_their_friction_limit_slide() {
    let mut worst = (0.0f64, String::new());
    for (a, h) in [(0.1, 0.05), (1.0, 0.5)] {
        for theta in [10.0f64, 20.0, 30.0] {
            let fos = 0.99;
            let want = coulomb_travel(theta, fos, 1.0);
            let got = travel(&slope(theta, fos, a, h), Method::Alm, Some(1.0));
            let err = (got - want).abs() / want;
            let case = format!("θ {theta}°, {a} × {h} m");
            // 1 %: the net force is 1 % of the driving one, so this is 10⁻⁴ of the friction.
            assert!(
                err < 0.01,
                "{case}: travelled {got:.6} m, theory {want:.6} m"
            );
            keep_worst(&mut worst, err, case);
        }
    }
    println!(
        "F = 0.99: largest error at 1 s {:.3} % ({})",
        100.0 * worst.0,
        worst.1
    );
}

/// Small blocks of soft rock (E = 1 GPa, 10 cm) slide from their first step under DDA-3a. Their
/// corners spread under the block's weight, and the springs' extensions, which give a contact
/// its sliding direction at the onset, fanned out by 15–25°: the corners' lateral stiffness held
/// the block for three steps (5.8 % short at 1 s on a 10 m slope, F = 0.9 on 20°). Such a
/// contact now slides along its block pair's resultant shear (`ONSET_RESULTANT` in
/// `src/solver/open_close.rs`).
#[test]
fn small_blocks_of_soft_rock_slide_from_their_first_step() {
    let mut worst = (0.0f64, String::new());
    for theta in [10.0f64, 20.0, 40.0] {
        for fos in [0.5, 0.9] {
            // 10 m: a slip tolerance f0·w0 of 10⁻⁶ m, which the first steps' slips stay below.
            let text = slope_of_length(theta, fos, 0.1, 0.05, 10.0)
                .replace("young_modulus = 2.0e10", "young_modulus = 1.0e9");
            assert!(text.contains("young_modulus = 1.0e9"));
            let want = coulomb_travel(theta, fos, 1.0);
            let got = travel(&text, Method::Alm, Some(1.0));
            let err = (got - want).abs() / want;
            let case = format!("θ {theta}°, F {fos}");
            assert!(
                err < 2e-3,
                "{case}: travelled {got:.6} m, theory {want:.6} m"
            );
            keep_worst(&mut worst, err, case);
        }
    }
    println!(
        "soft 10 cm blocks: largest error at 1 s {:.3} % ({})",
        100.0 * worst.0,
        worst.1
    );
}

/// A block `a` × `a` × `h` launched at `speed` m/s along x (its base turned `turn`° about z) on
/// a flat fixed base with friction angle `phi`.
fn launched(phi: f64, speed: f64, a: f64, h: f64, turn: f64) -> String {
    let reach = speed * speed / (2.0 * phi.to_radians().tan() * 9.8);
    format!(
        "[joint]\nfriction_angle = {phi}\n{ROCK}\
         [[blocks]]\nname = \"base\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [{}, {}, 1], center = [0, 0, -0.5] }}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\n\
         box = {{ size = [{a}, {a}, {h}], center = [0, 0, {}], rotation = [0, 0, {turn}] }}\n\
         velocity = [{speed}, 0, 0]\n",
        4.0 * (reach + 2.0 * a) + 2.0,
        4.0 * a + 2.0,
        h / 2.0
    )
}

/// Blocks launched along a flat base stop after Coulomb's v² / (2 μ g), by either method. All
/// contacts of the first step start locked: under DDA-3p their springs tipped the block onto its
/// front edge, the friction of the pass after took that pass's tenfold normal force, and a 1 m
/// block at 2 m/s on φ = 30° stopped after 0.095 m of 0.353 m. DDA-3p's contacts now close
/// sliding where their block already slides, and take their force as friction in the solve
/// after (`open_close::check_one`).
#[test]
fn launched_blocks_stop_where_coulomb_says() {
    let mut worst = [(0.0f64, String::new()), (0.0f64, String::new())];
    for (a, h) in [(0.1, 0.05), (1.0, 0.5), (3.0, 1.0)] {
        for phi in [15.0f64, 30.0, 45.0] {
            for (speed, turn) in [(1.0, 0.0), (3.0, 30.0)] {
                let want = speed * speed / (2.0 * phi.to_radians().tan() * 9.8);
                let duration = 1.3 * speed / (phi.to_radians().tan() * 9.8) + 0.1;
                for (m, method) in [Method::Alm, Method::Penalty].into_iter().enumerate() {
                    let text = launched(phi, speed, a, h, turn);
                    let got = travel(&text, method, Some(duration));
                    let err = (got - want).abs() / want;
                    let case = format!("{method:?}, {a} × {h} m, φ {phi}°, {speed} m/s");
                    // DDA-3a within 0.05 % (0.2 % while the step a block stopped in ran on to
                    // its end: `step_control::stop_within`); the baseline within 6.4 % (its
                    // soft springs: the 3 m blocks up to 6.4 %, the others within 0.6 %;
                    // 80–97 % short before).
                    let bound = [1e-3, 8e-2][m];
                    assert!(
                        err < bound,
                        "{case}: stopped after {got:.5} m, theory {want:.5} m"
                    );
                    keep_worst(&mut worst[m], err, case);
                }
            }
        }
    }
    for (err, case) in worst {
        println!("launched: largest error {:.3} % ({case})", 100.0 * err);
    }
}

/// A block `a` × `a` × `h` in the middle of a fixed slope of `theta` degrees (dipping toward +x)
/// with friction angle `phi`, the slope `length` m long; `extra` ends the block's table (its
/// velocity, its loads).
fn mid_slope(theta: f64, phi: f64, (a, h): (f64, f64), length: f64, extra: &str) -> String {
    let depth = a.max(h);
    let c = |s: f64| on_slope(theta, s, 0.0);
    format!(
        "[joint]\nfriction_angle = {phi}\n{ROCK}\
         [[blocks]]\nname = \"slope\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [{length}, {}, {depth}], center = {}, rotation = [0, {theta}, 0] }}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\n\
         box = {{ size = [{a}, {a}, {h}], center = {}, rotation = [0, {theta}, 0] }}\n{extra}\n",
        2.0 * a,
        c(-depth / 2.0),
        c(h / 2.0),
    )
}

/// [`mid_slope`] with the block thrown up the slope at `speed` m/s.
fn thrown_up(theta: f64, phi: f64, speed: f64, a: f64, h: f64, length: f64) -> String {
    let t = theta.to_radians();
    let v = [-speed * t.cos(), 0.0, speed * t.sin()];
    let extra = format!("velocity = [{}, {}, {}]", v[0], v[1], v[2]);
    mid_slope(theta, phi, (a, h), length, &extra)
}

/// The travel down the dip of a slope of `theta` degrees in the displacement `d`, m.
fn down_dip(theta: f64, d: [f64; 3]) -> f64 {
    let t = theta.to_radians();
    d[0] * t.cos() - d[2] * t.sin()
}

/// Blocks thrown up a slope slow down at g (sin θ + cos θ tan φ), stop after t1, and then stay
/// (θ ≤ φ) or slide back at g (sin θ − cos θ tan φ). The stop falls within a step, whose friction
/// then outlasted the motion: the slip reversed, the contacts stuck with D ≈ 0, and the step's
/// v1 = 2D/Δt − v0 sent the block back down at about the speed it had come up with (34° with
/// φ = 26°: 4.5 cm beyond Coulomb after 1.5 s, 12.8 % of the 0.35 m it went up). The step is now
/// redone to end where the block stopped (`step_control::stop_within`). The stops are chosen
/// within steps (t1 = 0.274 and 0.537 s at Δt = 0.01 s): at 0.27 and 0.53 s, on step
/// boundaries, the old code was right to 1.3 %.
#[test]
fn blocks_thrown_up_a_slope_stop_and_come_back_as_coulomb_says() {
    let mut worst = [(0.0f64, String::new()), (0.0f64, String::new())];
    let duration = 1.5;
    for (theta, phi) in [(34.0f64, 26.0f64), (41.0, 29.0), (23.0, 14.0), (20.0, 25.0)] {
        let (t, mu) = (theta.to_radians(), phi.to_radians().tan());
        let slowing = 9.8 * (t.sin() + mu * t.cos());
        let back = (9.8 * (t.sin() - mu * t.cos())).max(0.0);
        for t1 in [0.274, 0.537] {
            let speed = slowing * t1;
            let up = 0.5 * speed * t1;
            // Down the dip from the start, after `duration`.
            let want = -up + 0.5 * back * (duration - t1) * (duration - t1);
            let length = 2.0 * (up + want.abs() + 3.0) + 4.0;
            for (a, h) in [(0.5, 0.25), (1.5, 0.5)] {
                for (m, method) in [Method::Alm, Method::Penalty].into_iter().enumerate() {
                    let text = thrown_up(theta, phi, speed, a, h, length);
                    let got = down_dip(theta, displacement(&text, method, Some(duration)));
                    let err = (got - want).abs() / up;
                    let case = format!("{method:?}, {a} × {h} m, θ {theta}°, φ {phi}°, t1 {t1} s");
                    // DDA-3a within 1 % of the way up (0.78 % at most; 12.8 % before), the
                    // baseline within 3 % (2.1 %; 12.9 % before).
                    let bound = [1e-2, 3e-2][m];
                    assert!(
                        err < bound,
                        "{case}: ended {got:.5} m down the dip, Coulomb {want:.5} m \
                         ({:.2} % of the {up:.4} m up)",
                        100.0 * err
                    );
                    keep_worst(&mut worst[m], err, case);
                }
            }
        }
    }
    for (err, case) in worst {
        println!(
            "thrown up: largest error {:.3} % of the way up ({case})",
            100.0 * err
        );
    }
}

/// Blocks pushed along a slope by a point load at their centroid, parallel to the dip: held while
/// the net force along the slope is within the friction, m g cos θ tan φ, and otherwise sliding
/// up or down at the excess over m. `q` is the net downslope force over m g cos θ, in units of
/// tan φ: ±0.5 hold, +1.6 slides down, −1.6 is pushed up the slope (the friction then acts down
/// it, with gravity).
#[test]
fn blocks_pushed_along_a_slope_hold_or_slide_as_coulomb_says() {
    let mut worst = [(0.0f64, String::new()), (0.0f64, String::new())];
    let (duration, rho) = (1.0, 2750.0);
    for (theta, phi) in [(30.0f64, 25.0f64), (45.0, 30.0), (15.0, 35.0)] {
        let (t, mu) = (theta.to_radians(), phi.to_radians().tan());
        for q in [-1.6f64, -0.5, 0.5, 1.6] {
            let net = if q.abs() > 1.0 {
                (q - q.signum()) * mu
            } else {
                0.0
            };
            let want = 0.5 * 9.8 * t.cos() * net * duration * duration;
            for (a, h) in [(1.0, 0.4), (2.0, 0.6)] {
                let m = rho * a * a * h;
                // m g sin θ − P = q tan φ · m g cos θ: the push P up the dip.
                let push = m * 9.8 * (t.sin() - q * mu * t.cos());
                let centroid = on_slope(theta, h / 2.0, 0.0);
                let load = format!(
                    "loads = [{{ point = {centroid}, force = [{}, 0, {}] }}]",
                    -push * t.cos(),
                    push * t.sin()
                );
                let length = 2.0 * (want.abs() + 2.0 * a) + 4.0;
                for (k, method) in [Method::Alm, Method::Penalty].into_iter().enumerate() {
                    let text = mid_slope(theta, phi, (a, h), length, &load);
                    let got = down_dip(theta, displacement(&text, method, Some(duration)));
                    // Held blocks within 0.1 mm; sliding ones within 0.5 % (DDA-3a) or 3 %.
                    let err = if net == 0.0 {
                        got.abs() / 1e-4
                    } else {
                        (got - want).abs() / want.abs() / [5e-3, 3e-2][k]
                    };
                    let case = format!("{method:?}, {a} × {h} m, θ {theta}°, φ {phi}°, q {q}");
                    assert!(
                        err < 1.0,
                        "{case}: moved {got:.6} m down the dip, Coulomb {want:.6} m"
                    );
                    keep_worst(&mut worst[k], err, case);
                }
            }
        }
    }
    for (err, case) in worst {
        println!("pushed: largest error {:.3} of its bound ({case})", err);
    }
}

/// Two blocks stacked on a slope, one joint friction angle for both joints: they slide together
/// at g (sin θ − cos θ tan φ), the upper one at its friction limit on the lower.
#[test]
fn stacked_blocks_slide_together_as_coulomb_says() {
    let mut worst = [(0.0f64, String::new()), (0.0f64, String::new())];
    let duration = 1.0;
    for (theta, phi) in [(30.0f64, 20.0f64), (45.0, 35.0), (25.0, 12.0)] {
        let t = theta.to_radians();
        let want = 0.5 * 9.8 * (t.sin() - t.cos() * phi.to_radians().tan()) * duration * duration;
        for (a, h, top) in [(1.0, 0.4, 0.3), (2.5, 0.6, 0.4)] {
            let upper = format!(
                "[[blocks]]\nname = \"top\"\nmaterial = \"rock\"\n\
                 box = {{ size = [{}, {}, {top}], center = {}, rotation = [0, {theta}, 0] }}",
                0.7 * a,
                0.7 * a,
                on_slope(theta, h + top / 2.0, 0.0)
            );
            let text = mid_slope(theta, phi, (a, h), 2.0 * (want + 2.0 * a) + 4.0, &upper);
            for (k, method) in [Method::Alm, Method::Penalty].into_iter().enumerate() {
                let got = down_dip(theta, displacement(&text, method, Some(duration)));
                let err = (got - want).abs() / want;
                let case = format!("{method:?}, {a} × {h} m under {top} m, θ {theta}°, φ {phi}°");
                // DDA-3a within 0.3 %; the baseline within 3 % (its soft springs).
                let bound = [3e-3, 3e-2][k];
                assert!(
                    err < bound,
                    "{case}: the lower block slid {got:.5} m, Coulomb {want:.5} m"
                );
                keep_worst(&mut worst[k], err, case);
            }
        }
    }
    for (err, case) in worst {
        println!("stacked: largest error {:.3} % ({case})", 100.0 * err);
    }
}
