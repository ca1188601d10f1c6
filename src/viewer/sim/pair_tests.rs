//! The lock-step protocol of a comparison: every pair of frames the window is given has one t,
//! and a change sent to one side reaches that side only.

use super::*;
use crate::compare::CompareSpec;
use crate::viewer::sim::test_support::{rockfall, rockfall_checkpoint};

/// The rockfall, A as the scene says (ALM), B with the penalty method.
fn spawn(speed: Speed, play: bool) -> SimPair {
    let s = rockfall();
    let spec = CompareSpec::parse(Some("penalty"), None).unwrap().unwrap();
    let b = spec.derive(&s.params).unwrap();
    SimPair::spawn(s.model, (s.params, b), None, speed, play, || {}).unwrap()
}

const WAIT: Duration = Duration::from_secs(60);

#[test]
fn every_shown_pair_has_one_time_through_the_impact() {
    // Paced (0.3 s of simulated time in about 0.6 s) so that the window's view of the pair
    // moves in many small steps whatever the machine's load: at full speed the rockfall's first
    // 0.3 s can pass between two publications.
    let mut pair = spawn(Speed::RealTime(0.5), true);
    let mut times = Vec::new();
    let (a, b) = pair
        .wait_for(WAIT, |a, b| {
            assert_eq!(
                a.snapshot.time.to_bits(),
                b.snapshot.time.to_bits(),
                "A at {} and B at {}",
                a.snapshot.time,
                b.snapshot.time
            );
            if times.last() != Some(&a.snapshot.time) {
                times.push(a.snapshot.time);
            }
            a.snapshot.time >= 0.3
        })
        .expect("both reach 0.3 s");
    assert!(
        times.len() >= 10,
        "the pair moved on in small steps: {times:?}"
    );
    // Each run keeps its own steps: the two methods do not step alike through the impact.
    assert_eq!(a.params.method, crate::params::Method::Alm);
    assert_eq!(b.params.method, crate::params::Method::Penalty);
    let d = crate::compare::compare_snapshots(&a.snapshot, &b.snapshot);
    assert!(d.max_displacement_difference.is_finite());
}

#[test]
fn pause_holds_both_on_one_time_and_step_moves_both() {
    let mut pair = spawn(Speed::Max, true);
    pair.wait_for(WAIT, |a, _| a.snapshot.time >= 0.05).unwrap();
    pair.command(Command::Pause);
    let (a, b) = pair
        .wait_for(WAIT, |a, b| {
            a.state == RunState::Paused && b.state == RunState::Paused
        })
        .expect("both pause");
    assert_eq!(a.snapshot.time.to_bits(), b.snapshot.time.to_bits());
    assert!(!pair.playing());
    let t = a.snapshot.time;
    pair.command(Command::Step);
    let (a2, b2) = pair
        .wait_for(WAIT, |a, b| {
            a.snapshot.time > t && a.state == RunState::Paused && b.state == RunState::Paused
        })
        .expect("a step on");
    assert_eq!(a2.snapshot.time.to_bits(), b2.snapshot.time.to_bits());
    assert!((a2.snapshot.time - t - a2.params.max_time_step).abs() < 1e-12);
    pair.command(Command::Reset);
    let (a, b) = pair
        .wait_for(WAIT, |a, b| {
            a.snapshot.step == 0 && b.snapshot.step == 0 && a.generation > 0
        })
        .expect("both back at t = 0");
    assert_eq!(a.snapshot.time, 0.0);
    assert_eq!(b.generation, a.generation);
}

#[test]
fn a_parameter_change_sent_to_b_alone_reaches_b_and_not_a() {
    let mut pair = spawn(Speed::Max, false);
    let before = pair.tick();
    let mut p = before.1.params.clone();
    p.contact.alpha = 7.5;
    p.joint.friction_angle = 20.0;
    let id = pair
        .side(Side::B)
        .send(Command::SetParams(Box::new(p.clone())));
    // B's next frame carries the change; A's frames never do.
    let fb = pair
        .b
        .wait_for(WAIT, |f| f.applied >= id)
        .expect("B takes it");
    assert_eq!(fb.params, p);
    let fa = pair.a.latest().unwrap();
    assert_eq!(fa.params, before.0.params, "A keeps its parameters");
    // And so do the frames the window is shown after the next step.
    pair.command(Command::Step);
    let (a, b) = pair
        .wait_for(WAIT, |a, b| {
            a.snapshot.step >= 1 && b.snapshot.step >= 1 && a.state == RunState::Paused
        })
        .expect("steps");
    assert_eq!(b.params.contact.alpha, 7.5);
    assert_eq!(b.params.joint.friction_angle, 20.0);
    assert_eq!(a.params.contact.alpha, before.0.params.contact.alpha);
    assert_eq!(
        a.params.joint.friction_angle,
        before.0.params.joint.friction_angle
    );
    assert_eq!(a.snapshot.time.to_bits(), b.snapshot.time.to_bits());
}

/// `view --resume CHECKPOINT --compare METHOD`: both runs start from the checkpoint, at its
/// time, move on in lock-step from there, and Reset takes both back to it.
#[test]
fn a_comparison_from_a_checkpoint_starts_and_resets_there() {
    let (s, solver, origin) = rockfall_checkpoint(20);
    let t0 = solver.time;
    let spec = CompareSpec::parse(Some("penalty"), None).unwrap().unwrap();
    let b = spec.derive(&solver.params).unwrap();
    let params = (solver.params.clone(), b);
    let mut pair = SimPair::spawn(s.model, params, Some(origin), Speed::Max, true, || {}).unwrap();
    let (a, b) = pair.tick();
    assert_eq!((a.snapshot.time, b.snapshot.time), (t0, t0));
    let (a, b) = pair
        .wait_for(WAIT, |a, _| a.snapshot.time >= t0 + 0.05)
        .expect("both move on from the checkpoint");
    assert_eq!(a.snapshot.time.to_bits(), b.snapshot.time.to_bits());
    assert!(a.snapshot.step > 20 && b.snapshot.step > 20);
    pair.command(Command::Reset);
    let (a, b) = pair
        .wait_for(WAIT, |a, b| {
            a.generation > 0 && b.generation > 0 && a.snapshot.step == 20 && b.snapshot.step == 20
        })
        .expect("both back at the checkpoint");
    assert_eq!((a.snapshot.time, b.snapshot.time), (t0, t0));
}
