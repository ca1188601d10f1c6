//! A checkpoint round trip is exact: the restored solver takes the same steps, bit for bit, as
//! the one it was taken from; and a file that is not a whole checkpoint of this version is
//! refused with its reason.

use std::path::Path;

use super::*;
use crate::scene;

fn rockfall() -> Solver {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/rock_column_rockfall.toml");
    let s = scene::load(&path).unwrap();
    Solver::new(s.model, s.params)
}

/// Everything a step leaves that the outputs or the next step read, as text that differs
/// whenever a bit does (`{:?}` prints the shortest f64 that reads back to the same bits).
fn fingerprint(s: &Solver) -> String {
    let mut records: Vec<_> = s.records.iter().collect();
    records.sort_by_key(|(k, _)| **k);
    format!(
        "{:?}\n{:?}\n{:?}\n{} {} {}\n{:?}\n{:?}",
        s.snapshot(),
        s.model.blocks,
        records,
        s.dt,
        s.w0,
        s.accelerations,
        s.linear.pattern,
        s.energy
    )
}

fn steps(s: &mut Solver, n: usize) {
    for _ in 0..n {
        s.step().unwrap();
    }
}

#[test]
fn a_restored_solver_steps_as_the_original() {
    let mut a = rockfall();
    steps(&mut a, 40);
    assert!(!a.records.is_empty(), "the rock column is in contact");
    let bytes = encode(&a);
    let mut b = decode(&bytes).unwrap();
    assert_eq!(fingerprint(&a), fingerprint(&b));
    steps(&mut a, 30);
    steps(&mut b, 30);
    assert_eq!(fingerprint(&a), fingerprint(&b));
    assert_eq!(a.totals.steps, b.totals.steps);
}

/// A restored solver's records live in a new `HashMap`, iterated in another order: the bytes
/// must not show it.
#[test]
fn the_same_state_gives_the_same_bytes() {
    let mut a = rockfall();
    steps(&mut a, 25);
    let bytes = encode(&a);
    assert_eq!(bytes, encode(&a));
    assert_eq!(bytes, encode(&decode(&bytes).unwrap()));
    assert_eq!(&bytes[..16], MAGIC);
}

#[test]
fn a_stage_under_way_is_restored() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/rock_column_rockfall.toml");
    let mut s = scene::load(&path).unwrap();
    s.params.initial_equilibrium = true;
    let mut a = Solver::new(s.model, s.params);
    steps(&mut a, 5);
    assert!(a.in_equilibrium_stage());
    let mut b = decode(&encode(&a)).unwrap();
    assert!(b.in_equilibrium_stage());
    while a.in_equilibrium_stage() {
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(a.in_equilibrium_stage(), b.in_equilibrium_stage());
    }
    steps(&mut a, 5);
    steps(&mut b, 5);
    assert_eq!(fingerprint(&a), fingerprint(&b));
    assert_eq!(
        format!("{:?}", a.equilibrium()),
        format!("{:?}", b.equilibrium())
    );
}

#[test]
fn what_is_not_a_whole_checkpoint_is_refused() {
    let mut a = rockfall();
    steps(&mut a, 5);
    let bytes = encode(&a);
    let err = |b: &[u8]| decode(b).err().expect("refused");
    assert_eq!(err(b""), CheckpointError::Foreign);
    assert_eq!(err(b"[solver]\nduration = 1\n"), CheckpointError::Foreign);
    for cut in [
        3,
        16,
        21,
        HEADER,
        HEADER + 1,
        bytes.len() / 2,
        bytes.len() - 1,
    ] {
        assert!(
            matches!(err(&bytes[..cut]), CheckpointError::Truncated { .. }),
            "cut at {cut}: {}",
            err(&bytes[..cut])
        );
    }
    let mut other = bytes.clone();
    other[16..20].copy_from_slice(&(VERSION + 1).to_le_bytes());
    assert_eq!(err(&other), CheckpointError::Version { found: VERSION + 1 });
    for at in [HEADER, HEADER + 100, bytes.len() - 1] {
        let mut flipped = bytes.clone();
        flipped[at] ^= 0x10;
        assert!(matches!(err(&flipped), CheckpointError::Corrupt(_)));
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(matches!(err(&longer), CheckpointError::Corrupt(_)));
}

/// A payload whose checksum holds but whose state does not (a writer's bug, or a forged
/// file) is refused, not stepped.
#[test]
fn a_state_that_does_not_hold_together_is_refused() {
    let a = rockfall();
    let mut saved = SavedSolver::of(&a);
    saved.break_a_record_for_tests();
    let payload = postcard::to_allocvec(&saved).unwrap();
    let mut bytes = encode(&a)[..HEADER].to_vec();
    bytes[20..28].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes[28..32].copy_from_slice(&crc32fast::hash(&payload).to_le_bytes());
    bytes.extend_from_slice(&payload);
    let e = decode(&bytes).err().expect("refused");
    assert!(
        matches!(&e, CheckpointError::Corrupt(m) if m.contains("names block")),
        "{e}"
    );
}

#[test]
fn file_names_say_the_time() {
    assert_eq!(file_name(0.5), "checkpoint_0.500000.ckpt");
    assert_eq!(file_name(12.0000004), "checkpoint_12.000000.ckpt");
}
