//! Checkpoints: the complete state of a [`Solver`] in a file, from which a run goes on exactly as
//! if it had never stopped (`dda3d run --checkpoint-every T`, `dda3d run --resume FILE`).
//!
//! # Format (version 2)
//!
//! All integers of the header are little-endian.
//!
//! | bytes | what |
//! |---|---|
//! | 0–15 | the magic string `DDA3D-CHECKPOINT` (ASCII) |
//! | 16–19 | the format version, `u32` ([`VERSION`]) |
//! | 20–27 | the length of the payload in bytes, `u64` |
//! | 28–31 | the CRC-32 (IEEE) of the payload, `u32` |
//! | 32– | the payload: the solver state encoded with `postcard` (serde's compact binary form: varint integers, f64 as their 8 bytes, so every number comes back bit for bit) |
//!
//! The payload is [`state`]'s `SavedSolver`, in the order its fields are declared: the
//! parameters (every field of `SolverParams`, the joint sets and the `[joint]` table included),
//! the model's name and rock masses, each block (name, material, fixed, vertices, topology, mass,
//! the 12 velocities and accelerations, stress, strain, spring anchors, point loads, initial
//! centroid, joint faces, rock mass), time, completed steps, the next Δt, w0, the initial
//! bounding boxes, the contact records sorted by their key (state, λ, penalty, forces,
//! penetration, spring reference, sliding direction, normal, cohesion, kept overlap), the last
//! sparsity pattern with the count of symbolic analyses, the closed contacts of the last step,
//! the last step's statistics, the run's totals (without the wall-clock timings), the
//! equilibrium stage (if under way) and its report, whether the blocks carry accelerations, and
//! the energy watch, and each block's still time and whether it sleeps (version 2; version 1
//! had no sleeping blocks and the two sleep parameters). Sorting the records and encoding
//! nothing that depends on memory addresses, hash order or the clock makes the same state give
//! the same bytes in every process.
//!
//! What a block derives from its vertices and the factorization are recomputed on loading (see
//! [`state`]). The mirrors in [`state`] fail to compile when the type they mirror gains a
//! field; the smaller types saved through their own serde derives (`ContactKey`,
//! `ContactSnapshot`, `StepStats`, `RunTotals`, `EquilibriumReport`, `EnergyWatch`, the
//! stage's `Phase`, `Material`, `ContactParams`, `JointParams`, `JointSetParams`, `Method`,
//! `Mode`) change the payload silently, so a change to any of them raises [`VERSION`] too.
//!
//! A reader refuses a file whose magic differs (not a checkpoint), whose version differs (the
//! layout of another version is not guessed at), that is shorter than its header says
//! (truncated), or whose checksum, encoding or indices do not hold (corrupt). Any change to what
//! the payload holds raises [`VERSION`].

mod state;

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use state::SavedSolver;

use super::Solver;

/// The first bytes of every checkpoint.
pub const MAGIC: &[u8; 16] = b"DDA3D-CHECKPOINT";
/// The layout this build writes and the only one it reads.
pub const VERSION: u32 = 2;
/// The extension of checkpoint files.
pub const EXTENSION: &str = "ckpt";
/// Magic, version, payload length and checksum.
const HEADER: usize = 16 + 4 + 8 + 4;

/// Why a checkpoint could not be read. The message is one line, for after the file's name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read: {0}")]
    Read(String),
    #[error("not a dda3d checkpoint")]
    Foreign,
    #[error("checkpoint format version {found}, this dda3d reads version {VERSION} only")]
    Version { found: u32 },
    #[error("truncated: {found} bytes, the header says {expected}")]
    Truncated { found: u64, expected: u64 },
    #[error("corrupt: {0}")]
    Corrupt(String),
}

/// The checkpoint of `solver`'s state as bytes: the same state gives the same bytes.
pub fn encode(solver: &Solver) -> Vec<u8> {
    let payload = postcard::to_allocvec(&SavedSolver::of(solver))
        .expect("the solver state is plain data, which postcard always encodes");
    framed(&payload)
}

/// `payload` behind the header: magic, version, its length and its checksum.
fn framed(payload: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    bytes.extend_from_slice(payload);
    bytes
}

/// The solver a checkpoint holds, ready to take its next step.
pub fn decode(bytes: &[u8]) -> Result<Solver, CheckpointError> {
    let magic = &bytes[..bytes.len().min(MAGIC.len())];
    if magic != &MAGIC[..magic.len()] || magic.is_empty() {
        return Err(CheckpointError::Foreign);
    }
    let truncated = |expected: usize| CheckpointError::Truncated {
        found: bytes.len() as u64,
        expected: expected as u64,
    };
    if bytes.len() < MAGIC.len() + 4 {
        return Err(truncated(HEADER));
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let found = word(16);
    if found != VERSION {
        return Err(CheckpointError::Version { found });
    }
    if bytes.len() < HEADER {
        return Err(truncated(HEADER));
    }
    let length = u64::from_le_bytes(bytes[20..28].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER..];
    if (payload.len() as u64) < length {
        return Err(CheckpointError::Truncated {
            found: bytes.len() as u64,
            expected: length.saturating_add(HEADER as u64),
        });
    }
    if payload.len() as u64 > length {
        return Err(CheckpointError::Corrupt(format!(
            "{} bytes after the end of the state",
            payload.len() as u64 - length
        )));
    }
    if crc32fast::hash(payload) != word(28) {
        return Err(CheckpointError::Corrupt("checksum mismatch".into()));
    }
    let (saved, rest): (SavedSolver, _) = postcard::take_from_bytes(payload)
        .map_err(|e| CheckpointError::Corrupt(format!("cannot decode the state: {e}")))?;
    if !rest.is_empty() {
        return Err(CheckpointError::Corrupt(format!(
            "{} bytes left after the state",
            rest.len()
        )));
    }
    let solver = saved.into_solver().map_err(CheckpointError::Corrupt)?;
    match not_finite(&solver) {
        Some(what) => Err(CheckpointError::Corrupt(format!("{what} is not finite"))),
        None => Ok(solver),
    }
}

/// The first value of a restored state that is not a finite number, if any: the run's clock and
/// step, the blocks' materials, geometry and motion, and the contacts' published values. A file
/// whose checksum was made to match a state holding inf ran to its end and wrote `inf` into
/// `contacts.csv`.
fn not_finite(solver: &Solver) -> Option<String> {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if !finite(&[solver.time, solver.dt, solver.w0]) {
        return Some("the run's time or step".into());
    }
    for b in &solver.model.blocks {
        let m = &b.material;
        if !finite(&[m.density, m.young_modulus, m.poisson_ratio, b.mass]) {
            return Some(format!("block {}'s material", b.name));
        }
    }
    let snap = solver.snapshot();
    for b in &snap.blocks {
        let corners = b.vertices.iter().flatten().copied();
        let motion = [b.centroid, b.velocity, b.displacement]
            .into_iter()
            .flatten();
        if !corners.chain(motion).chain(b.stress).all(f64::is_finite) {
            return Some(format!("block {}'s state", b.name));
        }
    }
    for c in &snap.contacts {
        let values = [c.normal_force, c.shear_force, c.penetration, c.penalty];
        let vectors = [c.point, c.normal, c.shear].into_iter().flatten();
        if !vectors.chain(values).all(f64::is_finite) {
            return Some(format!("a contact of {} and {}", c.block_i, c.block_j));
        }
    }
    None
}

/// Reads the checkpoint at `path`: its header first, then no more than the payload length the
/// header gives. (Read whole, `/dev/zero` filled the memory before anything was checked.)
pub fn load(path: &Path) -> Result<Solver, CheckpointError> {
    let read = |e: std::io::Error| CheckpointError::Read(e.to_string());
    let mut file = std::fs::File::open(path).map_err(read)?;
    let mut bytes = Vec::with_capacity(HEADER);
    (&mut file)
        .take(HEADER as u64)
        .read_to_end(&mut bytes)
        .map_err(read)?;
    // The header alone tells a foreign file, another version and a truncated header (decode
    // finds the payload missing past that).
    match decode(&bytes) {
        Err(e @ (CheckpointError::Foreign | CheckpointError::Version { .. })) => return Err(e),
        Err(e) if bytes.len() < HEADER => return Err(e),
        _ => {}
    }
    let length = u64::from_le_bytes(bytes[20..28].try_into().expect("8 bytes"));
    // One byte more than the header says, to tell a longer file from a whole one.
    file.take(length.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(read)?;
    decode(&bytes)
}

/// Writes `solver`'s checkpoint to `path`, beside it first and then renamed, so that a run
/// killed while writing leaves the previous file or none, never half of one.
pub fn save(solver: &Solver, path: &Path) -> std::io::Result<()> {
    let mut partial = path.as_os_str().to_owned();
    partial.push(".partial");
    let partial = PathBuf::from(partial);
    let mut file = std::fs::File::create(&partial)?;
    file.write_all(&encode(solver))?;
    file.sync_all()?;
    drop(file);
    std::fs::rename(&partial, path)
}

/// `DIR/checkpoint_<t>.ckpt`, with t in seconds to the microsecond.
pub fn file_name(time: f64) -> String {
    format!("checkpoint_{time:.6}.{EXTENSION}")
}

/// A checkpoint round trip is exact: the restored solver takes the same steps, bit for bit, as
/// the one it was taken from; and a file that is not a whole checkpoint of this version is
/// refused with its reason.
#[cfg(test)]
mod tests {
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
            "{:?}\n{:?}\n{:?}\n{} {} {}\n{:?}\n{:?}\n{:?}",
            s.snapshot(),
            s.model.blocks,
            records,
            s.dt,
            s.w0,
            s.accelerations,
            s.linear.pattern,
            s.energy,
            s.sleep
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

    /// A column that has fallen asleep is restored asleep, with its still time, and wakes
    /// with the original when the rock dropped on it comes near.
    #[test]
    fn a_sleeping_column_is_restored_asleep() {
        // A generated column of three blocks (the lowest fixed by its springs), standing, and
        // a cube 4.6 m above it.
        let standing = crate::generate::column_wall(3, 3, false);
        let text = format!(
            "{standing}\n[[blocks]]\nname = \"rock\"\nmaterial = \"rock\"\n\
             box = {{ size = [0.8, 0.8, 0.8], center = [0, 0, 11] }}\n"
        );
        let s = scene::parse(&text, "column.toml", "column").unwrap();
        let (column, rock) = ([2, 3], 4);
        let mut a = Solver::new(s.model, s.params);
        while !a.is_asleep(column[0]) {
            a.step().unwrap();
            assert!(a.time < 0.8, "the column sleeps before the rock comes near");
        }
        let mut b = decode(&encode(&a)).unwrap();
        assert!(column.iter().all(|&i| b.is_asleep(i)) && !b.is_asleep(rock));
        assert_eq!(fingerprint(&a), fingerprint(&b));
        let mut woken = false;
        while a.time < 1.5 {
            a.step().unwrap();
            b.step().unwrap();
            woken |= !a.is_asleep(column[0]);
        }
        assert!(woken, "the rock wakes the column");
        assert_eq!(fingerprint(&a), fingerprint(&b));
        // Without the rock everything sleeps, and a restored solver goes on resting with the
        // same steps.
        let column = crate::generate::column_wall(3, 3, false);
        let s = scene::parse(&column, "column.toml", "column").unwrap();
        let mut a = Solver::new(s.model, s.params);
        while a.sleep.resting().is_none() {
            a.step().unwrap();
            assert!(a.time < 1.0, "everything sleeps by 1 s");
        }
        let mut b = decode(&encode(&a)).unwrap();
        assert_eq!(fingerprint(&a), fingerprint(&b));
        steps(&mut a, 5);
        steps(&mut b, 5);
        assert_eq!(fingerprint(&a), fingerprint(&b));
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
    /// A whole checkpoint of `saved`, its header's length and checksum made to match it (a
    /// forged file).
    fn with_checksum(saved: &SavedSolver) -> Vec<u8> {
        framed(&postcard::to_allocvec(saved).unwrap())
    }

    #[test]
    fn a_state_that_does_not_hold_together_is_refused() {
        let a = rockfall();
        let mut saved = SavedSolver::of(&a);
        saved.break_a_record_for_tests();
        let e = decode(&with_checksum(&saved)).err().expect("refused");
        assert!(
            matches!(&e, CheckpointError::Corrupt(m) if m.contains("names block")),
            "{e}"
        );
    }

    /// A state holding inf or NaN under a checksum that matches it is refused as corrupt.
    #[test]
    fn a_state_that_is_not_finite_is_refused() {
        let a = rockfall();
        for value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut saved = SavedSolver::of(&a);
            saved.poison_for_tests(value);
            let e = decode(&with_checksum(&saved)).err().expect("refused");
            assert!(
                matches!(&e, CheckpointError::Corrupt(m) if m.contains("not finite")),
                "{value}: {e}"
            );
        }
    }

    /// `load` reads the header before the payload: an endless stream is refused at once.
    #[test]
    fn an_endless_file_is_refused_from_its_header() {
        for path in ["/dev/zero", "/dev/urandom"] {
            if Path::new(path).exists() {
                assert_eq!(load(Path::new(path)).err(), Some(CheckpointError::Foreign));
            }
        }
        // A whole checkpoint loads through the same path.
        let dir = std::env::temp_dir().join(format!("dda3d-ckpt-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a.ckpt");
        save(&rockfall(), &file).unwrap();
        assert!(load(&file).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn file_names_say_the_time() {
        assert_eq!(file_name(0.5), "checkpoint_0.500000.ckpt");
        assert_eq!(file_name(12.0000004), "checkpoint_12.000000.ckpt");
    }
}
