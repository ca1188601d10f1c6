use super::*;

fn law() -> LawParams {
    LawParams {
        close_penetration: 1e-6,
        open_tension: 100.0,
        slip_tolerance: 1e-6,
        loaded_force: f64::INFINITY,
        tan_phi: 35f64.to_radians().tan(),
        held: false,
        close_sliding: true,
    }
}

fn seen(state: ContactState) -> Observation {
    Observation {
        state,
        penetration: 0.0,
        normal_force: 1e4,
        shear: Vec3::zeros(),
        shear_stiffness: 1e8,
        cohesion: 0.0,
        slip: Vec3::zeros(),
        tau: Vec3::x(),
        lambda: 1e4,
        slid_before: true,
        restarted: false,
        carried: None,
    }
}

/// Held joints (the equilibrium stage): a locked contact does not slide under any shear,
/// but still opens in tension.
#[test]
fn held_joints_do_not_slide_but_open() {
    let p = LawParams {
        held: true,
        ..law()
    };
    let mut o = seen(ContactState::Lock);
    for n in [0.0, 1e2, 1e6] {
        o.normal_force = n;
        o.shear = Vec3::new(1.0, 0.0, 0.0);
        assert_eq!(classify(&o, &p), Transition::Keep, "N = {n}");
        assert!(matches!(classify(&o, &law()), Transition::Slide { .. }));
    }
    o.normal_force = -1e3;
    assert_eq!(classify(&o, &p), Transition::Open);
}

#[test]
fn an_open_contact_closes_only_beyond_the_threshold() {
    let p = law();
    let mut o = seen(ContactState::Open);
    for (dn, want) in [
        (-1e-3, Transition::Keep),
        (0.0, Transition::Keep),
        (0.5e-6, Transition::Keep),
        (2e-6, Transition::Close),
    ] {
        o.penetration = dn;
        assert_eq!(classify(&o, &p), want, "d_n = {dn}");
    }
}

#[test]
fn a_closed_contact_opens_only_under_tension_beyond_the_threshold() {
    let p = law();
    for state in [ContactState::Lock, ContactState::Slide] {
        let mut o = seen(state);
        o.slip = Vec3::new(1e-3, 0.0, 0.0);
        o.normal_force = -50.0;
        assert_ne!(
            classify(&o, &p),
            Transition::Open,
            "{state:?}: slight tension"
        );
        o.normal_force = -150.0;
        assert_eq!(classify(&o, &p), Transition::Open, "{state:?}");
    }
}

/// Mohr–Coulomb over a family of normal forces and friction angles: the contact slides
/// exactly when p_τ·|shear| > N tan φ.
#[test]
fn a_locked_contact_slides_beyond_its_friction_strength() {
    for phi in [10.0f64, 30.0, 45.0] {
        let p = LawParams {
            tan_phi: phi.to_radians().tan(),
            ..law()
        };
        for n in [1e2, 1e4, 1e6] {
            let limit = n * p.tan_phi / 1e8; // extension at the strength, m
            let mut o = seen(ContactState::Lock);
            o.normal_force = n;
            o.shear = Vec3::new(0.0, -0.99 * limit.max(2e-6), 0.0);
            if 0.99 * limit > p.slip_tolerance {
                assert_eq!(classify(&o, &p), Transition::Keep, "φ {phi}, N {n}");
            }
            o.shear = Vec3::new(0.0, -1.01 * limit.max(2e-6), 0.0);
            assert_eq!(
                classify(&o, &p),
                Transition::Slide { tau: -Vec3::y() },
                "φ {phi}, N {n}"
            );
        }
    }
}

/// A contact carrying load slides by Mohr–Coulomb alone, however short its spring; one
/// carrying less than `loaded_force` (or no weight to scale it: infinite) keeps the slip
/// tolerance's hysteresis. Over a family of normal forces and friction angles.
#[test]
fn a_loaded_contact_slides_below_the_slip_tolerance() {
    for phi in [0.0f64, 10.0, 30.0] {
        for n in [1.0, 10.0, 50.0] {
            let p = LawParams {
                tan_phi: phi.to_radians().tan(),
                loaded_force: 0.5 * n,
                ..law()
            };
            let mut o = seen(ContactState::Lock);
            o.normal_force = n;
            // 10 % beyond the strength (1 µN without friction), well below f0·w0 = 1 µm.
            let extension = (1.1 * n * p.tan_phi).max(1e-6) / o.shear_stiffness;
            assert!(extension < p.slip_tolerance, "φ {phi}, N {n}");
            o.shear = Vec3::new(0.0, extension, 0.0);
            let slide = Transition::Slide { tau: Vec3::y() };
            assert_eq!(classify(&o, &p), slide, "loaded: φ {phi}, N {n}");
            let unloaded = LawParams {
                loaded_force: 2.0 * n,
                ..p
            };
            assert_eq!(classify(&o, &unloaded), Transition::Keep, "φ {phi}, N {n}");
            assert_eq!(classify(&o, &law_at(p.tan_phi)), Transition::Keep);
            // Within its strength it stays locked, loaded or not.
            if phi > 0.0 {
                o.shear = Vec3::new(0.0, 0.9 * n * p.tan_phi / o.shear_stiffness, 0.0);
                assert_eq!(classify(&o, &p), Transition::Keep, "φ {phi}, N {n}");
            }
        }
    }
}

fn law_at(tan_phi: f64) -> LawParams {
    LawParams { tan_phi, ..law() }
}

#[test]
fn cohesion_adds_to_the_strength_of_an_intact_joint() {
    let p = law();
    let mut o = seen(ContactState::Lock);
    let friction = o.normal_force * p.tan_phi;
    o.shear = Vec3::x() * (1.1 * friction / o.shear_stiffness);
    assert!(matches!(classify(&o, &p), Transition::Slide { .. }));
    o.cohesion = 0.2 * friction;
    assert_eq!(
        classify(&o, &p),
        Transition::Keep,
        "10 % reserve from cohesion"
    );
}

/// Hysteresis: a contact carrying no normal force does not flip to sliding for a shear
/// displacement below f0·w0.
#[test]
fn tiny_shear_of_an_unloaded_contact_is_not_slip() {
    let p = law();
    let mut o = seen(ContactState::Lock);
    o.normal_force = 0.0;
    o.shear = Vec3::x() * 0.5e-6;
    assert_eq!(classify(&o, &p), Transition::Keep);
    o.shear = Vec3::x() * 2e-6;
    assert!(matches!(classify(&o, &p), Transition::Slide { .. }));
}

/// The slip tolerance's hysteresis bounds a length, not a force: a contact carrying no load
/// whose spring pulls with `loaded_force` or more slides however short the spring. Held to
/// f0·w0 alone, the vertical crack behind a 0.2 m wedge (1.6 kg) hung it by four unloaded
/// corners pulling up to 3.7 N each, p_τ·f0·w0 = 16 N apiece: a wedge with F = 0.58 stood.
/// Over a family of spring stiffnesses and loaded forces, with no normal force and a little
/// tension (within the opening threshold).
#[test]
fn an_unloaded_contact_holds_no_more_shear_than_the_noise_force() {
    for stiffness in [1e6, 1e8, 1e10] {
        for loaded in [0.1, 10.0, 1e3] {
            let p = LawParams {
                loaded_force: loaded,
                ..law()
            };
            for n in [0.0, -0.5 * p.open_tension] {
                let mut o = seen(ContactState::Lock);
                o.normal_force = n;
                o.shear_stiffness = stiffness;
                let at = |force: f64| Vec3::y() * (force / stiffness);
                o.shear = at(1.01 * loaded);
                let expect = Transition::Slide { tau: Vec3::y() };
                assert_eq!(
                    classify(&o, &p),
                    expect,
                    "p_τ {stiffness}, {loaded} N, N {n}"
                );
                o.shear = at(0.99 * loaded);
                let want = if o.shear.norm() > p.slip_tolerance {
                    expect
                } else {
                    Transition::Keep
                };
                assert_eq!(classify(&o, &p), want, "p_τ {stiffness}, {loaded} N, N {n}");
            }
        }
    }
}

#[test]
fn a_sliding_contact_sticks_when_its_slip_reverses_or_stops() {
    let p = law();
    let mut o = seen(ContactState::Slide);
    o.slip = Vec3::new(-2e-6, 0.0, 0.0);
    assert_eq!(classify(&o, &p), Transition::Stick, "reversed");
    o.slip = Vec3::new(0.0, 0.5e-6, 0.0);
    assert_eq!(classify(&o, &p), Transition::Stop, "stopped");
    // Once stopped in this attempt and sliding again, it does not stop a second time.
    o.restarted = true;
    assert_eq!(classify(&o, &p), Transition::Keep, "restarted");
    o.slip = Vec3::new(-2e-6, 0.0, 0.0);
    assert_eq!(classify(&o, &p), Transition::Stick, "restarted, reversed");
    o.restarted = false;
    o.slip = Vec3::new(0.0, 0.5e-6, 0.0);
    // One that began to slide in this step, held still in this pass, slides on.
    o.slid_before = false;
    assert_eq!(
        classify(&o, &p),
        Transition::Keep,
        "held still by its neighbours"
    );
    o.slid_before = true;
    // A slip far beyond the spring's elastic range N tan φ / p_τ = 70 µm: friction follows
    // the slip (the trial force is 7 kN along τ plus 141 kN along the slip).
    o.slip = Vec3::new(1e-3, 1e-3, 0.0);
    let want = Vec3::new(1.0, 1.0, 0.0).normalize();
    assert!((turn(&o, &p) - want).norm() < 0.05, "follows the slip");
}

fn turn(o: &Observation, p: &LawParams) -> Vec3 {
    match classify(o, p) {
        Transition::Turn { tau } => {
            assert!((tau.norm() - 1.0).abs() < 1e-12);
            tau
        }
        t => panic!("{t:?}"),
    }
}

/// A small block's onset (its spring's elastic range N tan φ / p_τ far below the slip
/// tolerance): friction turns by a slip below the tolerance, by the trial force; a contact
/// that was already sliding, an unloaded one, or one whose range is not that fine, keeps
/// the tolerance.
#[test]
fn a_fine_contact_turns_by_any_slip_at_its_onset() {
    // A 10 cm block's corner on a 40 m slope: N = 3 N, p_τ = 8·10⁷ N/m, f0·w0 = 4 µm.
    let p = LawParams {
        slip_tolerance: 4e-6,
        loaded_force: 0.1,
        tan_phi: 0.18,
        ..law()
    };
    let mut o = seen(ContactState::Slide);
    o.normal_force = 3.0;
    o.lambda = 3.0;
    o.shear_stiffness = 8e7;
    o.slid_before = false;
    // A micrometre of slip 5° off τ: far beyond the range (6.8 nm), τ follows the slip.
    let off = 5f64.to_radians();
    o.slip = Vec3::new(off.cos(), off.sin(), 0.0) * 1e-6;
    assert!(fine_onset(&o, &p));
    let tau = turn(&o, &p);
    assert!(tau.y.atan2(tau.x) > 0.99 * off, "{tau}");
    o.slid_before = true;
    // Already sliding when the step began: a slip below the tolerance is a stop.
    assert_eq!(classify(&o, &p), Transition::Stop, "already sliding");
    o.slid_before = false;
    let unloaded = LawParams {
        loaded_force: 10.0,
        ..p
    };
    assert_eq!(classify(&o, &unloaded), Transition::Keep, "unloaded");
    // 1.4 kN: its range, 3.2 µm, is not below 1 % of the tolerance.
    o.normal_force = 1.4e3;
    assert!(!fine_onset(&o, &p));
    assert_eq!(classify(&o, &p), Transition::Keep, "a wide range");
    assert!(
        fine_range(1.4e3, 8e7, &p, 1.0),
        "within the tolerance itself"
    );
    assert!(!fine_range(1.0e4, 8e7, &p, 1.0));
}

/// A sliding contact that slips less than the tolerance stops, unless its blocks' velocities
/// carry it forward (beyond a tenth of the tolerance) and it slips at least that far (it
/// speeds up); without the carried motion (static steps, the stage) the tolerance
/// alone decides.
#[test]
fn a_slow_contact_that_speeds_up_does_not_stop() {
    let p = law();
    let mut o = seen(ContactState::Slide);
    o.slip = Vec3::x() * 5e-7;
    assert_eq!(classify(&o, &p), Transition::Stop, "no carried motion");
    o.carried = Some(Vec3::x() * 0.5 * CARRIED_SHARE * p.slip_tolerance);
    assert_eq!(classify(&o, &p), Transition::Stop, "carried too little");
    o.carried = Some(Vec3::x() * 4e-7);
    assert!(speeds_up(&o, &p));
    assert_eq!(classify(&o, &p), Transition::Keep, "speeding up");
    o.carried = Some(Vec3::x() * 6e-7);
    assert_eq!(classify(&o, &p), Transition::Stop, "slowing down");
    // Across τ, the carried motion does not count.
    o.carried = Some(Vec3::new(4e-7, 9e-7, 0.0));
    assert_eq!(classify(&o, &p), Transition::Keep);
}

/// Cundall's incremental friction: τ turns to the trial force N tan φ·τ + p_τ·slip. A slip
/// of 3 µm across τ at N tan φ = 7 kN and p_τ = 10⁸ N/m turns it by atan(300/7003) = 2.45°,
/// where taking the slip's direction turned it by 90°; the same slip with the contact in
/// tension (no friction to hold) is followed whole.
#[test]
fn micro_slip_across_the_sliding_direction_turns_it_a_little() {
    let p = law();
    let mut o = seen(ContactState::Slide);
    o.slip = Vec3::new(0.0, 3e-6, 0.0);
    let tau = turn(&o, &p);
    let held = o.normal_force * p.tan_phi;
    let want = (300.0 / held).atan();
    assert!((tau.y.atan2(tau.x) - want).abs() < 1e-12, "{tau}");
    assert!(want.to_degrees() > 2.4 && want.to_degrees() < 2.5);
    o.normal_force = -50.0;
    assert!((turn(&o, &p) - Vec3::y()).norm() < 1e-15);
    // A forward slip keeps τ whatever its size.
    o.normal_force = 1e4;
    o.slip = Vec3::new(5e-6, 0.0, 0.0);
    assert!((turn(&o, &p) - Vec3::x()).norm() < 1e-15);
}

/// An open contact that closes while its blocks move past each other closes sliding along
/// that motion, whatever the motion's direction; one that closes at rest closes locked; and
/// held joints (the equilibrium stage) and Shi's rule (DDA-3p where no block slides) close
/// locked.
#[test]
fn a_contact_closing_in_motion_closes_sliding() {
    let p = law();
    let mut o = seen(ContactState::Open);
    o.penetration = 2e-6;
    for slip in [
        Vec3::new(1e-3, 0.0, 0.0),
        Vec3::new(0.0, -3e-6, 0.0),
        Vec3::new(2e-6, 2e-6, 0.0),
    ] {
        o.slip = slip;
        assert_eq!(
            classify(&o, &p),
            Transition::CloseSliding {
                tau: slip.normalize()
            },
            "slip {slip}"
        );
        let held = LawParams { held: true, ..p };
        assert_eq!(classify(&o, &held), Transition::Close, "held, slip {slip}");
        let shi = LawParams {
            close_sliding: false,
            ..p
        };
        assert_eq!(
            classify(&o, &shi),
            Transition::Close,
            "Shi's rule, slip {slip}"
        );
    }
    o.slip = Vec3::new(0.5e-6, 0.0, 0.0);
    assert_eq!(classify(&o, &p), Transition::Close, "below the tolerance");
    o.penetration = 0.5e-6;
    o.slip = Vec3::new(1e-3, 0.0, 0.0);
    assert_eq!(classify(&o, &p), Transition::Keep, "not yet closed");
}

#[test]
fn settling_closes_and_locks_unless_a_gap_is_left() {
    let c = 1e-6;
    assert_eq!(settle(ContactState::Slide, -2e-6, c, false), Settled::Open);
    assert_eq!(settle(ContactState::Lock, -2e-6, c, false), Settled::Open);
    assert_eq!(
        settle(ContactState::Slide, -0.5e-6, c, false),
        Settled::Lock { fresh_spring: true }
    );
    assert_eq!(
        settle(ContactState::Open, 1e-4, c, false),
        Settled::Lock { fresh_spring: true }
    );
    assert_eq!(
        settle(ContactState::Lock, 1e-4, c, false),
        Settled::Lock {
            fresh_spring: false
        }
    );
}

/// A frictionless contact settles closed and sliding wherever it would lock, and open
/// across a gap as any other.
#[test]
fn a_frictionless_contact_settles_sliding() {
    let c = 1e-6;
    for state in [ContactState::Open, ContactState::Lock, ContactState::Slide] {
        assert_eq!(settle(state, -2e-6, c, true), Settled::Open);
        assert_eq!(settle(state, -0.5e-6, c, true), Settled::Slide);
        assert_eq!(settle(state, 1e-4, c, true), Settled::Slide);
    }
}
