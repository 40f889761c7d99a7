//! The positions of the mobile bodies at the end of every loading cycle
//! (`[output.cycles] positions = true`): the data a settlement driver fits
//! (Karrech et al. 2007 §3: residual displacement per cycle and per coordinate).
//!
//! Two files, compact enough for 10⁴ cycles × 10³ bodies (120 MB in 2D):
//! - `cycle_bodies.csv`: one row per followed body: its index in the scene, its
//!   name and its generalised coordinates at the start of the run in full
//!   precision (`x0_m`, `y0_m`, `theta0_rad` in 2D; `x0_m`, `y0_m`, `z0_m`,
//!   `rx0_rad`, `ry0_rad`, `rz0_rad` in 3D, `r` the rotation vector);
//! - `cycle_displacements.npy`: a NumPy array (format 1.0, little-endian
//!   `float32`, C order) of shape `(cycles, bodies, dof)`: the displacement of
//!   each coordinate since the start of the run at the end of each cycle (m or
//!   rad). `float32` keeps 7 significant digits of the *displacement*, not of the
//!   position: 1e-9 m on a 1 cm displacement. Its header is rewritten with the
//!   new number of cycles after each cycle, so the file is always a valid array;
//!   read it with `numpy.load`.
//!
//! [`read`] gives the positions back as [`Configuration`]s.

use crate::engine::Configuration;
use crate::error::{Error, Result};
use crate::io::io_error;
use crate::io::layout;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Length of the `.npy` header, magic included (a multiple of 64, room for any shape).
const HEADER_LEN: usize = 128;
const MAGIC: &[u8] = b"\x93NUMPY\x01\x00";

/// One row of `cycle_bodies.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyRow {
    /// Index of the body in the scene.
    pub body: usize,
    /// Its name (may be empty).
    pub name: String,
    /// Its generalised coordinates at the start of the run (m, rad).
    pub q0: Vec<f64>,
}

/// The `.npy` header for `cycles` records of `bodies × dof` floats.
fn header(cycles: u64, bodies: usize, dof: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({cycles}, {bodies}, {dof}), }}");
    let mut h = MAGIC.to_vec();
    let len = (HEADER_LEN - MAGIC.len() - 2) as u16;
    h.extend_from_slice(&len.to_le_bytes());
    h.extend_from_slice(dict.as_bytes());
    while h.len() < HEADER_LEN - 1 {
        h.push(b' ');
    }
    h.push(b'\n');
    h
}

/// The columns of `cycle_bodies.csv` for `dof` coordinates per body (3 or 6).
fn columns(dof: usize) -> Vec<&'static str> {
    let q0: &[&str] = if dof == 3 {
        &["x0_m", "y0_m", "theta0_rad"]
    } else {
        &["x0_m", "y0_m", "z0_m", "rx0_rad", "ry0_rad", "rz0_rad"]
    };
    let mut head = vec!["body", "name"];
    head.extend_from_slice(q0);
    head
}

/// Writes the positions of a fixed set of bodies at each cycle end.
#[derive(Debug)]
pub struct PositionsWriter {
    path: PathBuf,
    file: File,
    reference: Configuration,
    cycles: u64,
    record: Vec<u8>,
    /// CRC-32 of the records written (the data after the header).
    crc: crc32fast::Hasher,
}

impl PositionsWriter {
    /// Starts the two files in `dir` for the bodies of `reference` (their
    /// coordinates at the start), named `names` (one per body).
    pub fn create(dir: &Path, reference: Configuration, names: &[String]) -> Result<Self> {
        let rows: Vec<BodyRow> = reference
            .bodies
            .iter()
            .enumerate()
            .map(|(k, &i)| BodyRow {
                body: i,
                name: names.get(k).cloned().unwrap_or_default(),
                q0: reference.body(k).to_vec(),
            })
            .collect();
        let mut w = crate::io::table::TableWriter::create(&dir.join(layout::CYCLE_BODIES), &columns(reference.dof))?;
        for r in &rows {
            w.write(r)?;
        }
        w.finish()?;
        let path = dir.join(layout::CYCLE_DISPLACEMENTS);
        let mut file = File::create(&path).map_err(|e| io_error(&path, "create", e))?;
        file.write_all(&header(0, reference.len(), reference.dof)).map_err(|e| io_error(&path, "write", e))?;
        Ok(Self { path, file, reference, cycles: 0, record: Vec::new(), crc: crc32fast::Hasher::new() })
    }

    /// Reopens the files in `dir` of a run resumed after `cycles` cycles: the
    /// displacements of later cycles are cut off.
    ///
    /// # Errors
    /// `not a valid checkpoint: …` if `cycle_bodies.csv` does not hold the
    /// bodies, `names` and coordinates of `reference`, or the displacements file is
    /// shorter than `cycles` records or their CRC-32 is not `crc` (edited).
    pub fn resume(dir: &Path, reference: Configuration, names: &[String], cycles: u64, crc: u32) -> Result<Self> {
        let invalid =
            |path: &Path, msg: &str| Error::Checkpoint(format!("not a valid checkpoint: '{}' {msg}", path.display()));
        let bodies = dir.join(layout::CYCLE_BODIES);
        let (header, rows): (Vec<String>, Vec<BodyRow>) = match crate::io::table::read(&bodies) {
            Ok(table) => table,
            Err(_) if !bodies.is_file() => return Err(invalid(&bodies, "is missing")),
            Err(e) => return Err(Error::Checkpoint(format!("not a valid checkpoint: {e}"))),
        };
        let same = header == columns(reference.dof)
            && rows.len() == reference.len()
            && rows.iter().enumerate().all(|(k, r)| {
                r.body == reference.bodies[k]
                    && names.get(k) == Some(&r.name)
                    && r.q0.len() == reference.dof
                    && r.q0.iter().zip(reference.body(k)).all(|(a, b)| a.to_bits() == b.to_bits())
            });
        if !same {
            return Err(invalid(
                &bodies,
                "does not hold the columns, followed bodies, names and start of the checkpoint",
            ));
        }
        let path = dir.join(layout::CYCLE_DISPLACEMENTS);
        let bytes = HEADER_LEN as u64 + cycles * (reference.q.len() as u64 * 4);
        let mut file =
            std::fs::OpenOptions::new().read(true).write(true).open(&path).map_err(|e| io_error(&path, "open", e))?;
        let len = file.metadata().map_err(|e| io_error(&path, "read", e))?.len();
        if len < bytes {
            return Err(invalid(&path, &format!("is shorter ({len} bytes) than {cycles} cycles need ({bytes} bytes)")));
        }
        let mut data = vec![0; (bytes - HEADER_LEN as u64) as usize];
        file.seek(SeekFrom::Start(HEADER_LEN as u64))
            .and_then(|_| file.read_exact(&mut data))
            .map_err(|e| io_error(&path, "read", e))?;
        if crc32fast::hash(&data) != crc {
            return Err(invalid(&path, "was edited since the checkpoint (its records have another checksum)"));
        }
        file.set_len(bytes).map_err(|e| io_error(&path, "truncate", e))?;
        let crc = crc32fast::Hasher::new_with_initial_len(crc, data.len() as u64);
        let mut w = Self { path, file, reference, cycles, record: Vec::new(), crc };
        w.write_header()?;
        Ok(w)
    }

    fn write_header(&mut self) -> Result<()> {
        let h = header(self.cycles, self.reference.len(), self.reference.dof);
        self.file.seek(SeekFrom::Start(0)).map_err(|e| io_error(&self.path, "seek", e))?;
        self.file.write_all(&h).map_err(|e| io_error(&self.path, "write", e))?;
        self.file.seek(SeekFrom::End(0)).map_err(|e| io_error(&self.path, "seek", e))?;
        Ok(())
    }

    /// Appends the positions `c` (the same bodies as the reference) of the cycle just ended.
    pub fn append(&mut self, c: &Configuration) -> Result<()> {
        if c.bodies != self.reference.bodies || c.dof != self.reference.dof {
            return Err(Error::Scene("cycle positions: not the bodies of the reference".into()));
        }
        self.record.clear();
        for (x, x0) in c.q.iter().zip(&self.reference.q) {
            self.record.extend_from_slice(&((x - x0) as f32).to_le_bytes());
        }
        self.file.seek(SeekFrom::End(0)).map_err(|e| io_error(&self.path, "seek", e))?;
        self.file.write_all(&self.record).map_err(|e| io_error(&self.path, "write", e))?;
        self.crc.update(&self.record);
        self.cycles += 1;
        self.write_header()
    }

    /// CRC-32 of the records written (the data after the header), for a checkpoint.
    pub fn crc32(&self) -> u32 {
        self.crc.clone().finalize()
    }

    /// Cycles written.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// The followed bodies and their coordinates at the start.
    pub fn reference(&self) -> &Configuration {
        &self.reference
    }

    /// Flushes the file to the disk (for a checkpoint).
    pub fn sync(&mut self) -> Result<()> {
        self.file.sync_data().map_err(|e| io_error(&self.path, "sync", e))
    }
}

/// The positions read back from a run's folder.
#[derive(Debug, Clone, PartialEq)]
pub struct CyclePositions {
    /// Names of the followed bodies.
    pub names: Vec<String>,
    /// Their coordinates at the start of the run.
    pub reference: Configuration,
    /// Their coordinates at the end of each cycle (reference + the stored
    /// `float32` displacement).
    pub cycles: Vec<Configuration>,
}

/// Reads `cycle_bodies.csv` and `cycle_displacements.npy` of the run in `dir`.
pub fn read(dir: &Path) -> Result<CyclePositions> {
    let (header, rows): (_, Vec<BodyRow>) = crate::io::table::read(&dir.join(layout::CYCLE_BODIES))?;
    let dof = header.len().saturating_sub(2);
    let bad = |msg: &str| Error::Scene(format!("'{}': {msg}", dir.join(layout::CYCLE_DISPLACEMENTS).display()));
    let reference = Configuration {
        dof,
        bodies: rows.iter().map(|r| r.body).collect(),
        q: rows.iter().flat_map(|r| r.q0.iter().copied()).collect(),
    };
    let path = dir.join(layout::CYCLE_DISPLACEMENTS);
    let mut bytes = Vec::new();
    File::open(&path).and_then(|mut f| f.read_to_end(&mut bytes)).map_err(|e| io_error(&path, "read", e))?;
    if bytes.len() < HEADER_LEN || &bytes[..MAGIC.len()] != MAGIC {
        return Err(bad("not a .npy file of this crate"));
    }
    let text = String::from_utf8_lossy(&bytes[MAGIC.len() + 2..HEADER_LEN]);
    let shape: Vec<u64> = text
        .split("'shape': (")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_default();
    if shape.len() != 3 || shape[1] as usize != reference.len() || shape[2] as usize != dof {
        return Err(bad("its shape does not match cycle_bodies.csv"));
    }
    let record = reference.q.len() * 4;
    let data = &bytes[HEADER_LEN..];
    if data.len() != shape[0] as usize * record {
        return Err(bad("its length does not match its shape"));
    }
    let cycles = data
        .chunks_exact(record.max(1))
        .take(shape[0] as usize)
        .map(|chunk| {
            let q = chunk
                .chunks_exact(4)
                .zip(&reference.q)
                .map(|(b, x0)| x0 + f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
                .collect();
            Configuration { dof, bodies: reference.bodies.clone(), q }
        })
        .collect();
    Ok(CyclePositions { names: rows.into_iter().map(|r| r.name).collect(), reference, cycles })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_a_padded_npy_header() {
        let h = header(12345, 724, 3);
        assert_eq!(h.len(), HEADER_LEN);
        assert_eq!(HEADER_LEN % 64, 0);
        assert_eq!(u16::from_le_bytes([h[8], h[9]]) as usize, HEADER_LEN - 10);
        assert!(String::from_utf8_lossy(&h).contains("'shape': (12345, 724, 3), }"));
        assert_eq!(*h.last().unwrap(), b'\n');
        // The largest shape still fits.
        assert_eq!(header(u64::MAX, usize::MAX, 6).len(), HEADER_LEN);
    }
}
