//! ParaView output: a time series of VTK XML files under `DIR/vtk/`.
//!
//! - `blocks_NNNNNN.vtu`: every block as one polyhedron cell (VTK cell type 42) in its deformed
//!   position, with cell data `block_index`, `rock_mass` and `region` (−1 for a hand-made
//!   block), `fixed`, `velocity`, `displacement` (of the centroid since t = 0), `stress`
//!   (σx, σy, σz, τxy, τyz, τzx, Pa) and `volume` (m³, as the solver holds it); the names in
//!   field data (`block_names`, `rock_mass_names`).
//! - `contacts_NNNNNN.vtp`: every closed contact as a vertex at its point on block j, with point
//!   data `normal` (out of block j), `normal_force` and `shear_force` (the force vectors on
//!   block i, N), their magnitudes, `state` (1 lock, 2 slide), `mode` (0 vertex–face, 1
//!   edge–edge), `penetration`, `penalty`, `lambda`, `joint` (an index of the field data
//!   `joint_set_names`, −1 for `[joint]`), `block_i` and `block_j`.
//! - `blocks.pvd` and `contacts.pvd`: the collections, with each file's simulated time, so that
//!   ParaView's time slider reads simulated time. They are rewritten (atomically) after each
//!   output, so a run stopped at any point leaves a readable series.
//!
//! Data arrays are written in VTK's `binary` format, zlib-compressed in blocks of 32 KiB
//! (`vtkZLibDataCompressor`: a base64 header of UInt64 block counts and sizes, then the base64 of
//! the compressed blocks): a standing wall of 1 000 blocks writes 1.2 MB an output, where its
//! CSV rows take 1.8 MB a step. Polyhedra use the `faces`/`faceoffsets` stream that every VTK
//! reader since 5.8 reads. `vtkio` was not used: it writes XML polyhedra without their faces
//! stream, which is the part this needs.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine;

use super::{OutputError, Schedule, num, write_atomically};
use crate::snapshot::{ContactMode, ContactState, Snapshot};

/// Writes the VTK series of a run.
pub struct VtkWriter {
    dir: PathBuf,
    /// When outputs are due.
    schedule: Schedule,
    /// (time, file name) of each output so far.
    outputs: Vec<(f64, String, String)>,
}

impl VtkWriter {
    /// Creates `run_dir/vtk`. `interval`: simulated time between outputs (`None`: every step).
    pub fn create(run_dir: &Path, interval: Option<f64>) -> Result<Self, OutputError> {
        let dir = run_dir.join("vtk");
        crate::files::create_dir_clearly(&dir)
            .map_err(|e| OutputError::io(&dir, "cannot create the VTK directory", e))?;
        Ok(VtkWriter {
            dir,
            schedule: Schedule::new(interval),
            outputs: Vec::new(),
        })
    }

    /// Writes `s` if an output is due at its time: the first state, then the first step at or
    /// past each multiple of the interval.
    pub fn step(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        if self.due(s.time) {
            self.write(s)?;
        }
        Ok(())
    }

    /// Writes the final state unless it was the last output.
    pub fn finish(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        if self.schedule.final_due(s.time) {
            self.write(s)?;
        }
        Ok(())
    }

    /// Whether a state at `time` is written: the first state, then the first step at or past
    /// each multiple of the interval (every step without one).
    pub fn due(&self, time: f64) -> bool {
        self.schedule.due(time)
    }

    fn write(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        let k = self.outputs.len();
        let blocks = format!("blocks_{k:06}.vtu");
        let contacts = format!("contacts_{k:06}.vtp");
        self.put(&blocks, &blocks_vtu(s))?;
        self.put(&contacts, &contacts_vtp(s))?;
        self.outputs.push((s.time, blocks, contacts));
        self.schedule.wrote(s.time);
        let series = |pick: fn(&(f64, String, String)) -> &str| {
            collection(self.outputs.iter().map(|o| (o.0, pick(o))))
        };
        self.put("blocks.pvd", &series(|o| &o.1))?;
        self.put("contacts.pvd", &series(|o| &o.2))
    }

    fn put(&self, name: &str, text: &str) -> Result<(), OutputError> {
        let path = self.dir.join(name);
        write_atomically(&path, text.as_bytes())
            .map_err(|e| OutputError::io(&path, "cannot write", e))
    }
}

/// A `.pvd` collection of (time, file) pairs.
fn collection<'a>(files: impl Iterator<Item = (f64, &'a str)>) -> String {
    let mut x = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
         byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (t, file) in files {
        let _ = writeln!(
            x,
            "<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{file}\"/>",
            num(t)
        );
    }
    x.push_str("</Collection>\n</VTKFile>\n");
    x
}

/// Little-endian bytes of a data array's values.
trait Values {
    const TYPE: &'static str;
    fn put(&self, out: &mut Vec<u8>);
}

impl Values for f64 {
    const TYPE: &'static str = "Float64";
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Values for i32 {
    const TYPE: &'static str = "Int32";
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Values for u8 {
    const TYPE: &'static str = "UInt8";
    fn put(&self, out: &mut Vec<u8>) {
        out.push(*self);
    }
}

/// Uncompressed bytes per zlib block (VTK's default).
const BLOCK: usize = 1 << 15;

/// `bytes` as VTK's compressed `binary` data: the base64 of the header (number of blocks,
/// block size, size of a partial last block or 0, then each block's compressed size, all
/// UInt64), followed by the base64 of the compressed blocks.
fn encode(bytes: &[u8]) -> String {
    let blocks: Vec<Vec<u8>> = bytes
        .chunks(BLOCK)
        .map(|chunk| {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(chunk).expect("writing to memory");
            z.finish().expect("writing to memory")
        })
        .collect();
    let mut header = Vec::with_capacity(8 * (3 + blocks.len()));
    let mut put = |v: usize| header.extend_from_slice(&(v as u64).to_le_bytes());
    put(blocks.len());
    put(BLOCK);
    put(bytes.len() % BLOCK);
    for b in &blocks {
        put(b.len());
    }
    let b64 = &base64::engine::general_purpose::STANDARD;
    b64.encode(header) + &b64.encode(blocks.concat())
}

/// One `<DataArray>` of `components` values per tuple.
fn array<T: Values>(x: &mut String, name: &str, components: usize, values: &[T]) {
    let mut bytes = Vec::with_capacity(values.len() * 8);
    for v in values {
        v.put(&mut bytes);
    }
    let _ = writeln!(
        x,
        "<DataArray type=\"{}\" Name=\"{name}\" NumberOfComponents=\"{components}\" \
         format=\"binary\">{}</DataArray>",
        T::TYPE,
        encode(&bytes)
    );
}

/// A field-data array of strings (each written null-terminated, as VTK's writer does).
fn strings(x: &mut String, name: &str, values: &[String]) {
    let mut bytes = Vec::new();
    for v in values {
        bytes.extend_from_slice(v.as_bytes());
        bytes.push(0);
    }
    let _ = writeln!(
        x,
        "<Array type=\"String\" Name=\"{name}\" NumberOfTuples=\"{}\" format=\"binary\">{}</Array>",
        values.len(),
        encode(&bytes)
    );
}

fn header(kind: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\" \
         compressor=\"vtkZLibDataCompressor\">\n<{kind}>\n"
    )
}

/// The blocks of `s` as polyhedron cells.
pub fn blocks_vtu(s: &Snapshot) -> String {
    let mut points: Vec<f64> = Vec::new();
    let (mut connectivity, mut offsets): (Vec<i32>, Vec<i32>) = (Vec::new(), Vec::new());
    let (mut faces, mut face_offsets): (Vec<i32>, Vec<i32>) = (Vec::new(), Vec::new());
    for b in &s.blocks {
        let first = (points.len() / 3) as i32;
        points.extend(b.vertices.iter().flatten());
        connectivity.extend((0..b.vertices.len() as i32).map(|k| first + k));
        offsets.push(connectivity.len() as i32);
        faces.push(b.faces.len() as i32);
        for f in &b.faces {
            faces.push(f.len() as i32);
            faces.extend(f.iter().map(|&k| first + k as i32));
        }
        face_offsets.push(faces.len() as i32);
    }
    let mut x = header("UnstructuredGrid");
    x.push_str("<FieldData>\n");
    let names: Vec<String> = s.blocks.iter().map(|b| b.name.clone()).collect();
    strings(&mut x, "block_names", &names);
    if !s.rock_masses.is_empty() {
        strings(&mut x, "rock_mass_names", &s.rock_masses);
    }
    x.push_str("</FieldData>\n");
    let _ = writeln!(
        x,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        points.len() / 3,
        s.blocks.len()
    );
    x.push_str("<Points>\n");
    array(&mut x, "Points", 3, &points);
    x.push_str("</Points>\n<Cells>\n");
    array(&mut x, "connectivity", 1, &connectivity);
    array(&mut x, "offsets", 1, &offsets);
    array(&mut x, "types", 1, &vec![42u8; s.blocks.len()]);
    array(&mut x, "faces", 1, &faces);
    array(&mut x, "faceoffsets", 1, &face_offsets);
    x.push_str("</Cells>\n<CellData Scalars=\"block_index\" Vectors=\"velocity\">\n");
    let index: Vec<i32> = (0..s.blocks.len() as i32).collect();
    array(&mut x, "block_index", 1, &index);
    let of = |pick: fn((u16, u16)) -> u16| -> Vec<i32> {
        let at = |r: Option<(u16, u16)>| r.map_or(-1, |r| i32::from(pick(r)));
        s.blocks.iter().map(|b| at(b.rock_mass)).collect()
    };
    array(&mut x, "rock_mass", 1, &of(|r| r.0));
    array(&mut x, "region", 1, &of(|r| r.1));
    let fixed: Vec<u8> = s.blocks.iter().map(|b| u8::from(b.fixed)).collect();
    array(&mut x, "fixed", 1, &fixed);
    let flat = |f: fn(&crate::snapshot::BlockSnapshot) -> &[f64]| -> Vec<f64> {
        s.blocks.iter().flat_map(|b| f(b).iter().copied()).collect()
    };
    array(&mut x, "velocity", 3, &flat(|b| &b.velocity));
    array(&mut x, "displacement", 3, &flat(|b| &b.displacement));
    array(&mut x, "stress", 6, &flat(|b| &b.stress));
    let volume: Vec<f64> = s.blocks.iter().map(|b| b.volume).collect();
    array(&mut x, "volume", 1, &volume);
    x.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    x
}

/// The closed contacts of `s` as vertices with their forces.
pub fn contacts_vtp(s: &Snapshot) -> String {
    let c = &s.contacts;
    let n = c.len();
    let mut x = header("PolyData");
    if !s.joint_sets.is_empty() {
        x.push_str("<FieldData>\n");
        strings(&mut x, "joint_set_names", &s.joint_sets);
        x.push_str("</FieldData>\n");
    }
    let _ = writeln!(
        x,
        "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" \
         NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    x.push_str("<Points>\n");
    array(&mut x, "Points", 3, &flat(c, |k| k.point));
    x.push_str("</Points>\n<Verts>\n");
    let ids: Vec<i32> = (0..n as i32).collect();
    array(&mut x, "connectivity", 1, &ids);
    let ends: Vec<i32> = (1..=n as i32).collect();
    array(&mut x, "offsets", 1, &ends);
    x.push_str(
        "</Verts>\n<PointData Scalars=\"normal_force_magnitude\" Vectors=\"normal_force\">\n",
    );
    array(&mut x, "normal", 3, &flat(c, |k| k.normal));
    array(
        &mut x,
        "normal_force",
        3,
        &flat(c, |k| k.normal.map(|v| v * k.normal_force)),
    );
    array(&mut x, "shear_force", 3, &flat(c, |k| k.shear));
    let each =
        |f: fn(&crate::snapshot::ContactSnapshot) -> f64| -> Vec<f64> { c.iter().map(f).collect() };
    array(
        &mut x,
        "normal_force_magnitude",
        1,
        &each(|k| k.normal_force),
    );
    array(&mut x, "shear_force_magnitude", 1, &each(|k| k.shear_force));
    let state: Vec<i32> = c
        .iter()
        .map(|k| match k.state {
            ContactState::Open => 0,
            ContactState::Lock => 1,
            ContactState::Slide => 2,
        })
        .collect();
    array(&mut x, "state", 1, &state);
    let mode: Vec<i32> = c
        .iter()
        .map(|k| i32::from(k.mode == ContactMode::EdgeEdge))
        .collect();
    array(&mut x, "mode", 1, &mode);
    array(&mut x, "penetration", 1, &each(|k| k.penetration));
    array(&mut x, "penalty", 1, &each(|k| k.penalty));
    array(&mut x, "lambda", 1, &each(|k| k.lambda));
    let joint: Vec<i32> = c.iter().map(|k| k.joint.map_or(-1, i32::from)).collect();
    array(&mut x, "joint", 1, &joint);
    let block = |f: fn(&crate::snapshot::ContactSnapshot) -> usize| -> Vec<i32> {
        c.iter().map(|k| f(k) as i32).collect()
    };
    array(&mut x, "block_i", 1, &block(|k| k.block_i));
    array(&mut x, "block_j", 1, &block(|k| k.block_j));
    x.push_str("</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n");
    x
}

/// The three components of a vector of every contact, in order.
fn flat(
    c: &[crate::snapshot::ContactSnapshot],
    f: impl Fn(&crate::snapshot::ContactSnapshot) -> [f64; 3],
) -> Vec<f64> {
    c.iter().flat_map(f).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{BlockSnapshot, StepStats};

    fn snap(time: f64) -> Snapshot {
        Snapshot {
            scene_name: "t".into(),
            time,
            step: 0,
            blocks: vec![
                BlockSnapshot::test_cube("a", [0.0; 3], 1.0),
                BlockSnapshot::test_cube("b", [0.0, 0.0, 1.0], 1.0),
            ],
            contacts: vec![],
            stats: StepStats::default(),
            equilibrium: None,
            rock_masses: vec![],
            joint_sets: vec![],
        }
    }

    /// The values of array `name`, decoded as a VTK reader does.
    fn decode(text: &str, name: &str) -> Vec<u8> {
        use std::io::Read;
        let at = text
            .find(&format!("Name=\"{name}\""))
            .expect("array present");
        let start = at + text[at..].find('>').unwrap() + 1;
        let data = &text[start..start + text[start..].find('<').unwrap()];
        let b64 = &base64::engine::general_purpose::STANDARD;
        let word = |raw: &[u8], k: usize| {
            u64::from_le_bytes(raw[8 * k..8 * k + 8].try_into().unwrap()) as usize
        };
        let blocks = word(&b64.decode(&data[..32]).unwrap(), 0);
        let header_chars = (8 * (3 + blocks)).div_ceil(3) * 4;
        let header = b64.decode(&data[..header_chars]).unwrap();
        let packed = b64.decode(&data[header_chars..]).unwrap();
        let (mut out, mut at) = (Vec::new(), 0);
        for k in 0..blocks {
            let size = word(&header, 3 + k);
            let mut z = flate2::read::ZlibDecoder::new(&packed[at..at + size]);
            z.read_to_end(&mut out).unwrap();
            at += size;
        }
        let full = word(&header, 1) * blocks;
        let last = word(&header, 2);
        let expected = if last == 0 {
            full
        } else {
            full - word(&header, 1) + last
        };
        assert_eq!(out.len(), expected, "the header's sizes hold the data");
        out
    }

    fn ints(bytes: &[u8]) -> Vec<i32> {
        bytes
            .chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    #[test]
    fn two_cubes_are_two_polyhedra_with_their_faces_on_global_points() {
        let text = blocks_vtu(&snap(0.0));
        assert!(text.contains("NumberOfPoints=\"16\" NumberOfCells=\"2\""));
        assert_eq!(decode(&text, "types"), vec![42, 42]);
        assert_eq!(ints(&decode(&text, "offsets")), vec![8, 16]);
        let faces = ints(&decode(&text, "faces"));
        // Per cell: 6 faces of 4 points, each preceded by its count, after the face count.
        assert_eq!(faces.len(), 2 * (1 + 6 * 5));
        assert_eq!(&faces[..6], &[6, 4, 0, 2, 3, 1]);
        assert_eq!(&faces[31..37], &[6, 4, 8, 10, 11, 9]);
        assert_eq!(ints(&decode(&text, "faceoffsets")), vec![31, 62]);
        assert_eq!(decode(&text, "block_names"), b"a\0b\0");
    }

    #[test]
    fn outputs_follow_the_interval_and_the_collection_lists_them() {
        let dir = std::env::temp_dir().join(format!("dda3d-vtk-{}", std::process::id()));
        let mut w = VtkWriter::create(&dir, Some(0.1)).unwrap();
        for t in [0.0, 0.04, 0.0999999999999, 0.13, 0.2, 0.25] {
            w.step(&snap(t)).unwrap();
        }
        w.finish(&snap(0.25)).unwrap();
        let times: Vec<f64> = w.outputs.iter().map(|o| o.0).collect();
        assert_eq!(times, vec![0.0, 0.0999999999999, 0.2, 0.25]);
        let pvd = std::fs::read_to_string(dir.join("vtk/blocks.pvd")).unwrap();
        assert!(pvd.contains(
            "timestep=\"0.0999999999999\" group=\"\" part=\"0\" file=\"blocks_000001.vtu\""
        ));
        assert!(dir.join("vtk/contacts_000003.vtp").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
