//! VTK snapshots for ParaView: the writer of format-neutral poly data ([`PolyData`], [`write_poly`]) and the
//! `.pvd` collection that animates them ([`PvdCollection`]). What the engines write is theirs: the bodies and the
//! contact force network of a 2D system ([`crate::plane::vtk`]: NSCD and planar MD), the spheres of an MD
//! system ([`crate::md::vtk`]).
//!
//! # Files
//!
//! [`write_poly`] picks the format from the extension:
//!
//! - `.vtp`: VTK XML PolyData, ASCII inline (`<DataArray format="ascii">`);
//! - `.vtk`: legacy VTK, `# vtk DataFile Version 3.0`, `ASCII`, `DATASET POLYDATA`.
//!
//! Any other extension is an error. [`PvdCollection`] writes a ParaView `.pvd`
//! collection (`<VTKFile type="Collection">`) of `.vtp` snapshots, one time step
//! per snapshot, part 0 the bodies and part 1 the contacts (NSCD) or part 0 the
//! spheres (MD): open the `.pvd` in ParaView and it plays the run.
//!
//! **Why XML for the animation.** ParaView reads a `.pvd` with
//! `vtkXMLCollectionReader`, which picks the reader of each listed file from its
//! extension among the XML formats only (`vtp`, `vtu`, `vti`, `vtr`, `vts`,
//! `vtm` and their parallel forms); a legacy `.vtk` listed in a `.pvd` is not read.
//! So the engines' snapshots are `.vtp` files. The legacy `.vtk`
//! form holds exactly the same data and is there for single snapshots and for
//! tools that read only legacy VTK.
//!
//! Floats are written with `{:e}`, the shortest text that reads back to the same
//! `f64` (a non-finite value would be written `NaN` or `inf`, which VTK readers
//! refuse; the stepper never leaves one in the state: it rolls back); integers
//! as `Int32` (`int`), coordinates and floats as `Float64` (`double`).

//!

use super::io_error;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// File format of a snapshot, chosen by [`Format::from_path`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Legacy VTK, ASCII (`.vtk`).
    Legacy,
    /// VTK XML PolyData, ASCII inline (`.vtp`), the format a `.pvd` can list.
    Xml,
}

impl Format {
    /// `.vtk` (legacy) or `.vtp` (XML), case-insensitive; any other extension is
    /// an [`Error::Io`](crate::Error::Io) of kind `InvalidInput` naming the path.
    pub fn from_path(path: &Path) -> Result<Format> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("vtk") => Ok(Format::Legacy),
            Some("vtp") => Ok(Format::Xml),
            _ => Err(io_error(
                path,
                "write",
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "unknown VTK extension, expected .vtk (legacy) or .vtp (XML PolyData)",
                ),
            )),
        }
    }
}

/// One file of a time step of a [`PvdCollection`]: a block of the data set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PvdPart {
    /// Name of the block (`bodies`, `contacts`, `spheres`).
    pub name: String,
    /// The snapshot (`.vtp`).
    pub file: PathBuf,
}

/// One time step of a [`PvdCollection`]: its parts, listed as parts 0, 1, ….
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "EntryForm")]
pub struct PvdEntry {
    /// Simulated time (s).
    pub time: f64,
    /// The blocks written at that time, in part order.
    pub parts: Vec<PvdPart>,
}

/// What a [`PvdEntry`] reads from: its own form, or that of checkpoints written
/// before the entries had a list of parts (a bodies and a contacts file).
#[derive(Deserialize)]
#[serde(untagged)]
enum EntryForm {
    Parts { time: f64, parts: Vec<PvdPart> },
    BodiesContacts { time: f64, bodies: PathBuf, contacts: PathBuf },
}

impl From<EntryForm> for PvdEntry {
    fn from(e: EntryForm) -> Self {
        match e {
            EntryForm::Parts { time, parts } => PvdEntry { time, parts },
            EntryForm::BodiesContacts { time, bodies, contacts } => {
                PvdEntry { time, parts: bodies_and_contacts(bodies, contacts) }
            }
        }
    }
}

fn bodies_and_contacts(bodies: PathBuf, contacts: PathBuf) -> Vec<PvdPart> {
    vec![PvdPart { name: "bodies".into(), file: bodies }, PvdPart { name: "contacts".into(), file: contacts }]
}

/// A ParaView `.pvd` collection of snapshots: each time step lists its files as
/// parts 0, 1, … — for an NSCD run its bodies file and its contacts file, for an
/// MD run its spheres file — so ParaView shows a multi-block data set that it
/// animates over the time steps.
///
/// ```no_run
/// # fn main() -> ballast::Result<()> {
/// use ballast::io::vtk::PvdCollection;
/// use ballast::scene::{Scene, SceneFile};
/// let scene = Scene::load("examples/block_on_floor.toml")?;
/// let mut sys = scene.build()?;
/// let dir = std::path::Path::new("out");
/// std::fs::create_dir_all(dir)?;
/// let mut pvd = PvdCollection::new();
/// for k in 1..=scene.steps() {
///     sys.step()?;
///     if k % 10 == 0 {
///         // out/bodies_000000010.vtp, out/contacts_000000010.vtp
///         ballast::plane::vtk::write_snapshot(&mut pvd, dir, &sys)?;
///         pvd.write(&dir.join("run.pvd"))?; // rewritten each time: valid even if the run stops
///     }
/// }
/// # Ok(()) }
/// ```
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PvdCollection {
    entries: Vec<PvdEntry>,
}

impl PvdCollection {
    /// An empty collection.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the snapshot at `time` (s) made of the files `bodies` and `contacts`
    /// (they should be `.vtp`: ParaView does not read legacy files from a `.pvd`).
    /// Entries at a time not smaller than `time` are dropped first (a run resumed
    /// from an earlier checkpoint rewrites them), so times are strictly
    /// increasing.
    pub fn push(&mut self, time: f64, bodies: impl Into<PathBuf>, contacts: impl Into<PathBuf>) {
        self.push_parts(time, bodies_and_contacts(bodies.into(), contacts.into()));
    }

    /// Adds the snapshot at `time` (s) made of `parts` (parts 0, 1, … in this
    /// order), dropping the entries at a time not smaller than `time` first, as
    /// [`PvdCollection::push`] does.
    pub fn push_parts(&mut self, time: f64, parts: Vec<PvdPart>) {
        self.entries.retain(|e| e.time < time);
        self.entries.push(PvdEntry { time, parts });
    }

    /// The time steps, in increasing time.
    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    /// Number of time steps.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there is no time step.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The `.pvd` text, with the file names relative to the directory `base` when
    /// they are inside it (ParaView resolves relative names from the `.pvd`'s
    /// directory), else absolute when they exist, else as given.
    pub fn to_xml(&self, base: &Path) -> String {
        let mut s = String::from("<?xml version=\"1.0\"?>\n");
        s.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n");
        for e in &self.entries {
            for (part, p) in e.parts.iter().enumerate() {
                let file = relative_to(&p.file, base);
                let _ = writeln!(
                    s,
                    "    <DataSet timestep=\"{:e}\" group=\"\" part=\"{part}\" name=\"{}\" file=\"{}\"/>",
                    e.time,
                    xml_escape(&p.name),
                    xml_escape(&file.to_string_lossy())
                );
            }
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        s
    }

    /// Writes the collection to `path` (by convention `*.pvd`), file names
    /// relative to its directory; returns `path`. The file is written to a
    /// temporary name and renamed, so a reader never sees it half written.
    pub fn write(&self, path: &Path) -> Result<PathBuf> {
        let base = path.parent().unwrap_or(Path::new(""));
        super::write_atomic(path, &self.to_xml(base))?;
        Ok(path.to_path_buf())
    }
}

/// `file` as the `.pvd` in directory `base` should name it: relative to `base`
/// when it is inside it (as written, or once both paths are canonical), as given
/// when it is a relative name of an existing file of `base`, else absolute when
/// it exists, else as given.
fn relative_to(file: &Path, base: &Path) -> PathBuf {
    let base = if base == Path::new(".") { Path::new("") } else { base };
    if let Ok(r) = file.strip_prefix(base) {
        return r.to_path_buf();
    }
    if file.is_relative() && base.join(file).exists() {
        return file.to_path_buf();
    }
    match (file.canonicalize(), base.canonicalize()) {
        (Ok(f), Ok(b)) => f.strip_prefix(&b).map(Path::to_path_buf).unwrap_or(f),
        (Ok(f), Err(_)) => f,
        _ => file.to_path_buf(),
    }
}

fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Writes `data` to `path` under the title `title`, in the format of the extension ([`Format::from_path`]:
/// `.vtk` legacy, `.vtp` XML).
///
/// # Errors
/// An unknown extension or a failed write, naming the path.
pub fn write_poly(path: &Path, data: &PolyData, title: &str) -> Result<()> {
    let format = Format::from_path(path)?;
    write_file(path, &render(data, format, title))
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| io_error(path, "write", e))
}

// ---------------------------------------------------------------------------
// Format-neutral poly data, then its two serializations.

/// The kind of the cells of a [`PolyData`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellKind {
    /// Polygons (`POLYGONS` / `<Polys>`).
    Polys,
    /// Lines (`LINES` / `<Lines>`).
    Lines,
    /// Vertices (`VERTICES` / `<Verts>`).
    Verts,
}

/// How a cell array is declared in a legacy file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Scalars,
    Vectors,
    Field,
}

#[derive(Debug, Clone)]
enum Values {
    Int(Vec<i64>),
    Float(Vec<f64>),
}

/// A named data array of a [`PolyData`]: one tuple per cell or per point.
#[derive(Debug, Clone)]
pub struct Array {
    name: &'static str,
    role: Role,
    components: usize,
    values: Values,
}

impl Array {
    /// An integer scalar.
    pub fn int(name: &'static str, v: Vec<i64>) -> Self {
        Self { name, role: Role::Scalars, components: 1, values: Values::Int(v) }
    }

    /// A float scalar.
    pub fn float(name: &'static str, v: Vec<f64>) -> Self {
        Self { name, role: Role::Scalars, components: 1, values: Values::Float(v) }
    }

    /// A vector of 3 components (the active vectors in a legacy file).
    pub fn vectors(name: &'static str, v: Vec<[f64; 3]>) -> Self {
        Self { name, role: Role::Vectors, components: 3, values: Values::Float(v.concat()) }
    }

    /// A field of 3 components (a `FIELD` block in a legacy file).
    pub fn field3(name: &'static str, v: Vec<[f64; 3]>) -> Self {
        Self { name, role: Role::Field, components: 3, values: Values::Float(v.concat()) }
    }

    /// Writes tuple `i` as space-separated values.
    fn write_tuple(&self, s: &mut String, i: usize) {
        let k = self.components;
        for c in 0..k {
            if c > 0 {
                s.push(' ');
            }
            let _ = match &self.values {
                Values::Int(v) => write!(s, "{}", v[i * k + c]),
                Values::Float(v) => write!(s, "{:e}", v[i * k + c]),
            };
        }
        s.push('\n');
    }
}

/// Format-neutral poly data: points, cells of one kind, and their data arrays; what an engine maps its state
/// onto (its `vtk.rs`) and [`write_poly`] serialises.
#[derive(Debug, Clone)]
pub struct PolyData {
    /// Point coordinates (m).
    pub points: Vec<[f64; 3]>,
    /// The kind of every cell.
    pub kind: CellKind,
    /// Point indices of every cell, one after the other.
    pub connectivity: Vec<usize>,
    /// End of each cell in `connectivity` (the XML `offsets`).
    pub offsets: Vec<usize>,
    /// Arrays of one tuple per cell.
    pub cell_data: Vec<Array>,
    /// Arrays of one tuple per point (none for the 2D engines' files).
    pub point_data: Vec<Array>,
}

impl PolyData {
    fn cells(&self) -> usize {
        self.offsets.len()
    }

    fn cell(&self, i: usize) -> &[usize] {
        let start = if i == 0 { 0 } else { self.offsets[i - 1] };
        &self.connectivity[start..self.offsets[i]]
    }
}

fn render(d: &PolyData, format: Format, title: &str) -> String {
    match format {
        Format::Legacy => legacy(d, title),
        Format::Xml => xml(d, title),
    }
}

fn legacy(d: &PolyData, title: &str) -> String {
    let mut s = String::new();
    // The title line is at most 256 characters, without a newline.
    let title: String = title.chars().filter(|c| *c != '\n' && *c != '\r').take(255).collect();
    let _ =
        write!(s, "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET POLYDATA\nPOINTS {} double\n", d.points.len());
    for p in &d.points {
        let _ = writeln!(s, "{:e} {:e} {:e}", p[0], p[1], p[2]);
    }
    let n = d.cells();
    if n == 0 {
        return s;
    }
    let keyword = match d.kind {
        CellKind::Polys => "POLYGONS",
        CellKind::Lines => "LINES",
        CellKind::Verts => "VERTICES",
    };
    let _ = writeln!(s, "{keyword} {n} {}", n + d.connectivity.len());
    for i in 0..n {
        let cell = d.cell(i);
        let _ = write!(s, "{}", cell.len());
        for p in cell {
            let _ = write!(s, " {p}");
        }
        s.push('\n');
    }
    if !d.cell_data.is_empty() {
        let _ = writeln!(s, "CELL_DATA {n}");
        legacy_arrays(&mut s, &d.cell_data, n);
    }
    if !d.point_data.is_empty() {
        let _ = writeln!(s, "POINT_DATA {}", d.points.len());
        legacy_arrays(&mut s, &d.point_data, d.points.len());
    }
    s
}

/// The `SCALARS`, `VECTORS` and `FIELD` blocks of `arrays` of `n` tuples each.
fn legacy_arrays(s: &mut String, arrays: &[Array], n: usize) {
    let type_name = |a: &Array| match a.values {
        Values::Int(_) => "int",
        Values::Float(_) => "double",
    };
    for a in arrays.iter().filter(|a| a.role != Role::Field) {
        if a.role == Role::Scalars {
            let _ = write!(s, "SCALARS {} {} 1\nLOOKUP_TABLE default\n", a.name, type_name(a));
        } else {
            let _ = writeln!(s, "VECTORS {} {}", a.name, type_name(a));
        }
        (0..n).for_each(|i| a.write_tuple(s, i));
    }
    let fields: Vec<&Array> = arrays.iter().filter(|a| a.role == Role::Field).collect();
    if !fields.is_empty() {
        let _ = writeln!(s, "FIELD FieldData {}", fields.len());
        for a in fields {
            let _ = writeln!(s, "{} {} {n} {}", a.name, a.components, type_name(a));
            (0..n).for_each(|i| a.write_tuple(s, i));
        }
    }
}

fn xml(d: &PolyData, title: &str) -> String {
    let n = d.cells();
    let (verts, lines, polys) = match d.kind {
        CellKind::Verts => (n, 0, 0),
        CellKind::Lines => (0, n, 0),
        CellKind::Polys => (0, 0, n),
    };
    let mut s = String::from("<?xml version=\"1.0\"?>\n");
    let _ = writeln!(s, "<!-- {} -->", title.replace("--", "- -"));
    s.push_str("<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <PolyData>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{verts}\" NumberOfLines=\"{lines}\" \
         NumberOfStrips=\"0\" NumberOfPolys=\"{polys}\">",
        d.points.len()
    );
    s.push_str("      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in &d.points {
        let _ = writeln!(s, "{:e} {:e} {:e}", p[0], p[1], p[2]);
    }
    s.push_str("        </DataArray>\n      </Points>\n");
    if !d.point_data.is_empty() {
        xml_arrays(&mut s, "PointData", &d.point_data, d.points.len());
    }
    if !d.cell_data.is_empty() {
        xml_arrays(&mut s, "CellData", &d.cell_data, n);
    }
    let section = match d.kind {
        CellKind::Polys => "Polys",
        CellKind::Lines => "Lines",
        CellKind::Verts => "Verts",
    };
    let _ = writeln!(s, "      <{section}>");
    s.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for i in 0..n {
        let cell: Vec<String> = d.cell(i).iter().map(usize::to_string).collect();
        let _ = writeln!(s, "{}", cell.join(" "));
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for o in &d.offsets {
        let _ = writeln!(s, "{o}");
    }
    let _ = write!(s, "        </DataArray>\n      </{section}>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
    s
}

/// `<PointData>` or `<CellData>` (`element`) of `arrays` of `n` tuples each; the
/// first scalar and the first vector array are the active ones.
fn xml_arrays(s: &mut String, element: &str, arrays: &[Array], n: usize) {
    let active = |role: Role| arrays.iter().find(|a| a.role == role).map(|a| a.name);
    let _ = write!(s, "      <{element}");
    if let Some(name) = active(Role::Scalars) {
        let _ = write!(s, " Scalars=\"{name}\"");
    }
    if let Some(name) = active(Role::Vectors) {
        let _ = write!(s, " Vectors=\"{name}\"");
    }
    s.push_str(">\n");
    for a in arrays {
        let ty = match a.values {
            Values::Int(_) => "Int32",
            Values::Float(_) => "Float64",
        };
        let _ = writeln!(
            s,
            "        <DataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">",
            a.name, a.components
        );
        (0..n).for_each(|i| a.write_tuple(s, i));
        s.push_str("        </DataArray>\n");
    }
    let _ = writeln!(s, "      </{element}>");
}
