//! CSV tables of a run (`series.csv`, `cycles.csv`, `bodies.csv`): serde row
//! types written with a [`csv::Writer`] and read back with the same types.
//!
//! A table has a header line (the row type's fields, then any extra columns such
//! as one per wall) and one line per row. Floats are written as the shortest text
//! that reads back to the same `f64`; an absent value (`None`) is an empty
//! field; names holding a comma, a quote or a line break are quoted as CSV asks.
//! Rows are read back by position ([`read`]), so a row type may end with a
//! `Vec` that takes the extra columns.
//!
//! For `--resume` a table is cut back to its length at the checkpoint
//! ([`TableWriter::resume`]): rows a killed run wrote after it disappear. The
//! writer keeps the CRC-32 of what it wrote ([`TableWriter::crc32`]), which the
//! checkpoint records, so that a table edited since is refused.

use super::io_error;
use crate::error::{Error, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fs::File;
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

/// A CSV table being written.
#[derive(Debug)]
pub struct TableWriter {
    path: PathBuf,
    out: csv::Writer<Hashed>,
    rows: u64,
}

/// A file that keeps the CRC-32 of the bytes written to it.
#[derive(Debug)]
struct Hashed {
    file: File,
    crc: crc32fast::Hasher,
}

impl Write for Hashed {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.file.write(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

fn csv_error(path: &Path, what: &str, e: csv::Error) -> Error {
    let line = e.position().map(|p| format!(" (line {})", p.line())).unwrap_or_default();
    io_error(path, &format!("{what}{line}"), std::io::Error::other(e.to_string()))
}

fn writer(file: File, crc: crc32fast::Hasher) -> csv::Writer<Hashed> {
    csv::WriterBuilder::new().has_headers(false).from_writer(Hashed { file, crc })
}

impl TableWriter {
    /// Creates (truncates) the file at `path` and writes the header.
    pub fn create<S: AsRef<str>>(path: &Path, header: &[S]) -> Result<Self> {
        let file = File::create(path).map_err(|e| io_error(path, "create", e))?;
        let mut out = writer(file, crc32fast::Hasher::new());
        out.write_record(header.iter().map(|s| s.as_ref())).map_err(|e| csv_error(path, "write", e))?;
        Ok(Self { path: path.to_path_buf(), out, rows: 0 })
    }

    /// Reopens the table at `path` to continue a run from a checkpoint: the file
    /// is cut back to `bytes` (its length when the checkpoint was written) and
    /// `rows` rows are counted as written.
    ///
    /// # Errors
    /// If the file is missing, or shorter than `bytes`, or does not hold a header
    /// and exactly `rows` complete lines in its first `bytes` bytes, or these
    /// bytes do not have the CRC-32 `crc` (the file was edited).
    pub fn resume(path: &Path, bytes: u64, rows: u64, crc: u32) -> Result<Self> {
        check_length(path, bytes, rows, crc)?;
        let file = std::fs::OpenOptions::new().write(true).open(path).map_err(|e| io_error(path, "open", e))?;
        file.set_len(bytes).map_err(|e| io_error(path, "truncate", e))?;
        let mut file = file;
        file.seek(std::io::SeekFrom::End(0)).map_err(|e| io_error(path, "seek", e))?;
        let hasher = crc32fast::Hasher::new_with_initial_len(crc, bytes);
        Ok(Self { path: path.to_path_buf(), out: writer(file, hasher), rows })
    }

    /// Appends one row.
    pub fn write<R: Serialize>(&mut self, row: &R) -> Result<()> {
        self.out.serialize(row).map_err(|e| csv_error(&self.path, "write", e))?;
        self.rows += 1;
        Ok(())
    }

    /// Flushes what is buffered and returns the length of the file (bytes), for
    /// a checkpoint.
    pub fn sync(&mut self) -> Result<u64> {
        self.out.flush().map_err(|e| io_error(&self.path, "write", e))?;
        let f = &self.out.get_ref().file;
        f.sync_data().map_err(|e| io_error(&self.path, "sync", e))?;
        Ok(f.metadata().map_err(|e| io_error(&self.path, "read", e))?.len())
    }

    /// CRC-32 of the bytes written so far, header included (after
    /// [`TableWriter::sync`]: of the whole file), for a checkpoint.
    pub fn crc32(&self) -> u32 {
        self.out.get_ref().crc.clone().finalize()
    }

    /// Number of rows written (header excluded).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// The file written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes the file.
    pub fn finish(mut self) -> Result<()> {
        self.flush()
    }

    /// Flushes the file, keeping the writer.
    pub fn flush(&mut self) -> Result<()> {
        self.out.flush().map_err(|e| io_error(&self.path, "write", e))
    }
}

/// Checks that the first `bytes` bytes of the table at `path` are its header and
/// `rows` complete lines, with the CRC-32 `crc`.
pub fn check_length(path: &Path, bytes: u64, rows: u64, crc: u32) -> Result<()> {
    let bad = |msg: String| Err(Error::Checkpoint(format!("not a valid checkpoint: '{}' {msg}", path.display())));
    let text = match std::fs::read(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return bad("is missing".into()),
        Err(e) => return Err(io_error(path, "read", e)),
    };
    if (text.len() as u64) < bytes {
        return bad(format!("is shorter ({} bytes) than at the checkpoint ({bytes} bytes)", text.len()));
    }
    let head = &text[..bytes as usize];
    let lines = head.iter().filter(|&&b| b == b'\n').count() as u64;
    if head.last() != Some(&b'\n') || lines != rows + 1 {
        return bad(format!("does not hold a header and {rows} rows in its first {bytes} bytes"));
    }
    if crc32fast::hash(head) != crc {
        return bad(format!("was edited since the checkpoint (its first {bytes} bytes have another checksum)"));
    }
    Ok(())
}

/// Reads the table at `path`: its header and its rows, each deserialised by
/// position into `R`; the error names the file and the line.
pub fn read<R: DeserializeOwned>(path: &Path) -> Result<(Vec<String>, Vec<R>)> {
    let mut reader =
        csv::ReaderBuilder::new().has_headers(true).from_path(path).map_err(|e| csv_error(path, "read", e))?;
    let header = reader.headers().map_err(|e| csv_error(path, "read", e))?.iter().map(String::from).collect();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| csv_error(path, "read", e))?;
        rows.push(record.deserialize(None).map_err(|e| csv_error(path, "read", e))?);
    }
    Ok((header, rows))
}

/// Reads the rows of the table at `path` into `R` by column name (columns `R`
/// does not name are ignored): for reading a few columns of a wider table.
pub fn read_named<R: DeserializeOwned>(path: &Path) -> Result<Vec<R>> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| csv_error(path, "read", e))?;
    reader.deserialize().map(|row| row.map_err(|e| csv_error(path, "read", e))).collect()
}

/// The named columns of the table at `path` as numbers (an empty or unreadable
/// field is NaN); the error names the file and a missing column.
pub fn read_columns(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| csv_error(path, "read", e))?;
    let header = reader.headers().map_err(|e| csv_error(path, "read", e))?.clone();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h == *n)
                .ok_or_else(|| Error::Scene(format!("{}: no column '{n}'", path.display())))
        })
        .collect::<Result<_>>()?;
    let mut out = vec![Vec::new(); names.len()];
    for rec in reader.records() {
        let rec = rec.map_err(|e| csv_error(path, "read", e))?;
        for (k, &i) in idx.iter().enumerate() {
            out[k].push(rec.get(i).and_then(|s| s.parse().ok()).unwrap_or(f64::NAN));
        }
    }
    Ok(out)
}

/// Writes `rows` to a new table at `path` with the header of `R`'s fields
/// (for summary tables of studies).
pub fn write_all<R: Serialize>(path: &Path, rows: &[R]) -> Result<()> {
    write_rows(path, rows, false)
}

/// Appends `rows` to the table at `path`, created with the header of `R`'s fields if it does not exist (a
/// record that grows over the resumes of a run: `solver_changes.csv`).
pub fn append_all<R: Serialize>(path: &Path, rows: &[R]) -> Result<()> {
    write_rows(path, rows, true)
}

/// [`write_all`], or with `append` [`append_all`].
fn write_rows<R: Serialize>(path: &Path, rows: &[R], append: bool) -> Result<()> {
    let header = !(append && path.is_file());
    let file = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(append)
        .truncate(!append)
        .open(path)
        .map_err(|e| io_error(path, "create", e))?;
    let mut w = csv::WriterBuilder::new().has_headers(header).from_writer(file);
    for r in rows {
        w.serialize(r).map_err(|e| csv_error(path, "write", e))?;
    }
    w.flush().map_err(|e| io_error(path, "write", e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    struct Row {
        time_s: f64,
        n: u32,
        fraction: Option<f64>,
        walls: Vec<f64>,
    }

    /// Rows with a trailing vector read back equal, bit for bit; a resumed table
    /// loses the rows written after the checkpoint.
    #[test]
    fn rows_read_back_and_resume_cuts() {
        let dir = std::env::temp_dir().join(format!("ballast-table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.csv");
        let rows = vec![
            Row { time_s: 0.1 + 0.2, n: 3, fraction: None, walls: vec![1.5, 2e-300] },
            Row { time_s: 1e-7, n: 0, fraction: Some(0.6), walls: vec![-0.5, 3.0] },
        ];
        let mut w = TableWriter::create(&path, &["time_s", "n", "fraction", "a, \"b\"_force_N", "c_force_N"]).unwrap();
        w.write(&rows[0]).unwrap();
        let bytes = w.sync().unwrap();
        let crc = w.crc32();
        assert_eq!(crc, crc32fast::hash(&std::fs::read(&path).unwrap()));
        w.write(&rows[1]).unwrap();
        w.finish().unwrap();
        let (header, back): (_, Vec<Row>) = read(&path).unwrap();
        assert_eq!(header[3], "a, \"b\"_force_N");
        assert_eq!(back, rows);
        assert!(TableWriter::resume(&path, bytes, 1, crc ^ 1).is_err(), "wrong checksum");
        let mut w = TableWriter::resume(&path, bytes, 1, crc).unwrap();
        assert!(TableWriter::resume(&path, bytes, 2, crc).is_err(), "wrong row count");
        w.write(&rows[1]).unwrap();
        w.sync().unwrap();
        // The checksum goes on from the resumed part: that of the whole file.
        assert_eq!(w.crc32(), crc32fast::hash(&std::fs::read(&path).unwrap()));
        w.finish().unwrap();
        assert_eq!(read::<Row>(&path).unwrap().1, rows);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
