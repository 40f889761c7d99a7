//! VTK snapshots: the files are parsed back by the small readers below (legacy
//! ASCII and XML PolyData) and checked against the system they were written from.

use crate::fixtures;

use ballast::io::vtk::PvdCollection;
use ballast::nscd::System;
use ballast::plane::vtk::{write_bodies, write_contacts, DISC_VERTICES};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const FLOOR: usize = 0;
const BLOCK: usize = 1;
const DISC: usize = 2;
const FLYER: usize = 3;
/// Half-sizes (m) of the square bodies of [`scene`].
const HALF: [(usize, f64); 2] = [(BLOCK, 0.05), (FLYER, 0.02)];

/// The block of `examples/block_on_floor.toml` resting on its floor, a disc beside it, a square flying.
fn scene() -> Scene {
    Scene::from_toml_str(&fixtures::block_disc_and_flyer()).unwrap()
}

/// The scene's system after `steps` steps.
fn system(steps: usize) -> System {
    let mut sys = scene().build().unwrap();
    for _ in 0..steps {
        sys.step().unwrap();
    }
    sys
}

/// A fresh directory under the system temp dir, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos();
        let dir = std::env::temp_dir().join(format!("ballast-vtk-{name}-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

// ---------------------------------------------------------------------------
// Readers.

/// How a legacy file declares an array (`SCALARS`, `VECTORS` or a `FIELD` array).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Scalars,
    Vectors,
    Field,
    /// An XML `DataArray` (no such distinction).
    Xml,
}

#[derive(Debug, Clone, PartialEq)]
struct Arr {
    kind: Kind,
    components: usize,
    values: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq)]
struct Parsed {
    points: Vec<[f64; 3]>,
    /// `"POLYGONS"` or `"LINES"` (legacy), `"Polys"` or `"Lines"` (XML); `""` if no cells.
    cell_kind: String,
    cells: Vec<Vec<usize>>,
    cell_data: HashMap<String, Arr>,
}

impl Parsed {
    fn array(&self, name: &str) -> &Arr {
        self.cell_data.get(name).unwrap_or_else(|| panic!("no cell array '{name}'"))
    }

    fn scalar(&self, name: &str) -> &[f64] {
        let a = self.array(name);
        assert_eq!(a.components, 1, "{name}");
        &a.values
    }

    fn tuple(&self, name: &str, i: usize) -> &[f64] {
        let a = self.array(name);
        &a.values[i * a.components..(i + 1) * a.components]
    }

    /// Same data, array declarations aside (legacy vs XML); a legacy file
    /// without cells has no cell arrays, an XML one has them empty.
    fn same_data(&self, other: &Parsed) -> bool {
        let strip = |p: &Parsed| -> Vec<(String, usize, Vec<u64>)> {
            let mut v: Vec<_> = p
                .cell_data
                .iter()
                .filter(|(_, a)| !a.values.is_empty())
                .map(|(k, a)| (k.clone(), a.components, a.values.iter().map(|x| x.to_bits()).collect()))
                .collect();
            v.sort();
            v
        };
        self.points == other.points && self.cells == other.cells && strip(self) == strip(other)
    }
}

fn num<T: std::str::FromStr>(t: &str) -> T
where
    T::Err: std::fmt::Debug,
{
    t.parse().unwrap_or_else(|e| panic!("bad number '{t}': {e:?}"))
}

/// Legacy ASCII POLYDATA reader (the subset the writer uses).
fn parse_legacy(text: &str) -> Parsed {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("# vtk DataFile Version 3.0"));
    let title = lines.next().unwrap();
    assert!(title.len() < 256);
    assert_eq!(lines.next(), Some("ASCII"));
    let body = lines.collect::<Vec<_>>().join("\n");
    let mut t = body.split_whitespace();
    let mut next = || t.next();
    assert_eq!((next(), next()), (Some("DATASET"), Some("POLYDATA")));
    assert_eq!(next(), Some("POINTS"));
    let n: usize = num(next().unwrap());
    assert_eq!(next(), Some("double"));
    let points = (0..n).map(|_| [num(next().unwrap()), num(next().unwrap()), num(next().unwrap())]).collect();
    let mut p = Parsed { points, cell_kind: String::new(), cells: Vec::new(), cell_data: HashMap::new() };
    let mut n_cells = 0;
    while let Some(key) = next() {
        match key {
            "POLYGONS" | "LINES" => {
                p.cell_kind = key.to_string();
                n_cells = num(next().unwrap());
                let size: usize = num(next().unwrap());
                let mut read = 0;
                for _ in 0..n_cells {
                    let k: usize = num(next().unwrap());
                    p.cells.push((0..k).map(|_| num(next().unwrap())).collect());
                    read += k + 1;
                }
                assert_eq!(read, size, "{key} size");
            }
            "CELL_DATA" => assert_eq!(num::<usize>(next().unwrap()), n_cells),
            "SCALARS" => {
                let name = next().unwrap().to_string();
                assert!(matches!(next(), Some("int" | "double")));
                assert_eq!(next(), Some("1"));
                assert_eq!((next(), next()), (Some("LOOKUP_TABLE"), Some("default")));
                let values = (0..n_cells).map(|_| num(next().unwrap())).collect();
                p.cell_data.insert(name, Arr { kind: Kind::Scalars, components: 1, values });
            }
            "VECTORS" => {
                let name = next().unwrap().to_string();
                assert_eq!(next(), Some("double"));
                let values = (0..3 * n_cells).map(|_| num(next().unwrap())).collect();
                p.cell_data.insert(name, Arr { kind: Kind::Vectors, components: 3, values });
            }
            "FIELD" => {
                next();
                let k: usize = num(next().unwrap());
                for _ in 0..k {
                    let name = next().unwrap().to_string();
                    let comps: usize = num(next().unwrap());
                    assert_eq!(num::<usize>(next().unwrap()), n_cells);
                    assert!(matches!(next(), Some("int" | "double")));
                    let values = (0..comps * n_cells).map(|_| num(next().unwrap())).collect();
                    p.cell_data.insert(name, Arr { kind: Kind::Field, components: comps, values });
                }
            }
            other => panic!("unexpected legacy keyword '{other}'"),
        }
    }
    p
}

/// The value of attribute `name` in the start tag `tag` (text between `<` and `>`).
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    Some(&tag[start..start + tag[start..].find('"')?])
}

/// Every `<DataArray …>values</DataArray>` inside `section` (the text between
/// `<section…>` and `</section>`): (start tag, values).
fn data_arrays(xml: &str, section: &str) -> Vec<(String, Vec<f64>)> {
    let Some(open) = xml.find(&format!("<{section}")) else { return Vec::new() };
    let close = xml.find(&format!("</{section}>")).unwrap();
    let mut body = &xml[open..close];
    let mut out = Vec::new();
    while let Some(s) = body.find("<DataArray") {
        let tag_end = s + body[s..].find('>').unwrap();
        let end = body.find("</DataArray>").unwrap();
        let values = body[tag_end + 1..end].split_whitespace().map(num).collect();
        out.push((body[s + 1..tag_end].to_string(), values));
        body = &body[end + "</DataArray>".len()..];
    }
    out
}

/// XML PolyData reader (ASCII inline arrays).
fn parse_vtp(text: &str) -> Parsed {
    assert_well_formed(text);
    assert!(text.contains("<VTKFile type=\"PolyData\""));
    let piece = &text[text.find("<Piece").unwrap()..];
    let piece_tag = &piece[..piece.find('>').unwrap()];
    let count = |n: &str| -> usize { num(attr(piece_tag, n).unwrap()) };
    let (n_lines, n_polys) = (count("NumberOfLines"), count("NumberOfPolys"));
    assert_eq!((count("NumberOfVerts"), count("NumberOfStrips")), (0, 0));
    assert!(n_lines == 0 || n_polys == 0);
    let n_cells = n_lines + n_polys;

    let pts = data_arrays(text, "Points");
    assert_eq!(pts.len(), 1);
    assert_eq!(attr(&pts[0].0, "NumberOfComponents"), Some("3"));
    assert_eq!(pts[0].1.len(), 3 * count("NumberOfPoints"));
    let points = pts[0].1.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();

    let mut cell_data = HashMap::new();
    for (tag, values) in data_arrays(text, "CellData") {
        assert_eq!(attr(&tag, "format"), Some("ascii"));
        let components: usize = num(attr(&tag, "NumberOfComponents").unwrap());
        assert_eq!(values.len(), components * n_cells, "{tag}");
        cell_data.insert(attr(&tag, "Name").unwrap().to_string(), Arr { kind: Kind::Xml, components, values });
    }

    let cell_kind = if n_lines > 0 {
        "Lines"
    } else if n_polys > 0 {
        "Polys"
    } else {
        ""
    };
    let mut cells = Vec::new();
    if !cell_kind.is_empty() {
        let arrays = data_arrays(text, cell_kind);
        let get = |n: &str| &arrays.iter().find(|(t, _)| attr(t, "Name") == Some(n)).unwrap().1;
        let (conn, offsets) = (get("connectivity"), get("offsets"));
        assert_eq!(offsets.len(), n_cells);
        let mut start = 0;
        for &o in offsets {
            cells.push(conn[start..o as usize].iter().map(|&i| i as usize).collect());
            start = o as usize;
        }
        assert_eq!(start, conn.len());
    }
    Parsed { points, cell_kind: cell_kind.to_string(), cells, cell_data }
}

/// A minimal XML well-formedness check: balanced, properly nested tags, one
/// root element, attributes `name="value"` without `<` or `&` outside entities.
fn assert_well_formed(xml: &str) {
    let mut stack: Vec<&str> = Vec::new();
    let mut roots = 0;
    let mut rest = xml;
    if let Some(decl) = rest.strip_prefix("<?xml") {
        rest = &decl[decl.find("?>").unwrap() + 2..];
    }
    while let Some(lt) = rest.find('<') {
        let text = &rest[..lt];
        assert!(!text.contains('>') && !text.contains('&'), "stray text {text:?}");
        assert!(!stack.is_empty() || text.trim().is_empty(), "text outside the root: {text:?}");
        rest = &rest[lt..];
        if let Some(comment) = rest.strip_prefix("<!--") {
            let end = comment.find("-->").unwrap();
            rest = &comment[end + 3..];
            continue;
        }
        let gt = rest.find('>').unwrap();
        let tag = &rest[1..gt];
        rest = &rest[gt + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop(), Some(name.trim()), "closing </{name}>");
            continue;
        }
        let self_closing = tag.ends_with('/');
        let tag = tag.trim_end_matches('/');
        let name = tag.split_whitespace().next().unwrap();
        assert!(name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'), "tag name {name:?}");
        // Attributes: name="value" pairs.
        let mut attrs = tag[name.len()..].trim();
        while !attrs.is_empty() {
            let eq = attrs.find("=\"").unwrap_or_else(|| panic!("bad attributes in <{tag}>"));
            assert!(attrs[..eq].chars().all(|c| c.is_ascii_alphanumeric() || c == '_'), "<{tag}>");
            let after = &attrs[eq + 2..];
            let q = after.find('"').unwrap();
            assert!(!after[..q].contains('<'));
            attrs = after[q + 1..].trim_start();
        }
        if stack.is_empty() {
            roots += 1;
        }
        if !self_closing {
            stack.push(name);
        }
    }
    assert!(rest.trim().is_empty() && stack.is_empty(), "unclosed {stack:?}");
    assert_eq!(roots, 1, "one root element");
}

/// Writes the bodies and contacts of `sys` as `.vtk` and `.vtp` in `dir`, parses
/// them back, checks that both formats hold the same data and returns
/// (bodies, contacts) as read from the legacy files.
fn write_and_parse(dir: &Path, sys: &System) -> (Parsed, Parsed) {
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    write_bodies(&dir.join("bodies.vtk"), sys).unwrap();
    write_bodies(&dir.join("bodies.vtp"), sys).unwrap();
    write_contacts(&dir.join("contacts.vtk"), sys).unwrap();
    write_contacts(&dir.join("contacts.vtp"), sys).unwrap();
    let (bodies, contacts) = (parse_legacy(&read("bodies.vtk")), parse_legacy(&read("contacts.vtk")));
    let (bodies_x, contacts_x) = (parse_vtp(&read("bodies.vtp")), parse_vtp(&read("contacts.vtp")));
    assert!(bodies.same_data(&bodies_x), "legacy and XML bodies differ");
    assert!(contacts.same_data(&contacts_x), "legacy and XML contacts differ");
    (bodies, contacts)
}

// ---------------------------------------------------------------------------
// Tests.

#[test]
fn bodies_file_has_world_vertices_and_exact_state() {
    let dir = TempDir::new("bodies");
    let sys = system(20);
    let (b, _) = write_and_parse(&dir.0, &sys);
    let n = sys.bodies.len();
    assert_eq!(b.cell_kind, "POLYGONS");
    assert_eq!(b.cells.len(), n, "one cell per body");
    assert_eq!(b.scalar("body_id"), (0..n).map(|i| i as f64).collect::<Vec<_>>());
    assert_eq!(b.scalar("fixed"), [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(b.array("velocity").kind, Kind::Vectors);
    assert_eq!(b.array("velocity").components, 3);
    for i in 0..n {
        // {:e} round-trips: the state reads back bit for bit.
        let u = sys.bodies.u[i];
        assert_eq!(b.tuple("velocity", i), [u[0], u[1], 0.0]);
        assert_eq!(b.scalar("spin")[i], u[2]);
        assert_eq!(b.scalar("radius")[i], sys.bodies.info[i].shape.bounding_radius());
    }
    assert!(b.points.iter().all(|p| p[2] == 0.0), "planar");

    // Square bodies: corners = centre of mass + (±h, ±h) rotated by the angle,
    // counter-clockwise from (−h, −h) as in the scene.
    for (i, h) in HALF {
        let [x, y, a] = sys.bodies.q[i];
        let (s, c) = a.sin_cos();
        let cell = &b.cells[i];
        assert_eq!(cell.len(), 4);
        for (k, (dx, dy)) in [(-h, -h), (h, -h), (h, h), (-h, h)].into_iter().enumerate() {
            let expected = [x + c * dx - s * dy, y + s * dx + c * dy];
            let p = b.points[cell[k]];
            let err = (p[0] - expected[0]).abs().max((p[1] - expected[1]).abs());
            assert!(err < 1e-12, "body {i} corner {k}: {p:?} vs {expected:?}");
        }
    }
    // The flyer has turned: 0.3 rad + 20 ms at 2 rad/s.
    assert!((sys.bodies.q[FLYER][2] - 0.34).abs() < 1e-9, "flyer angle {}", sys.bodies.q[FLYER][2]);

    // The disc: DISC_VERTICES points on its circle, the first at its angle.
    let cell = &b.cells[DISC];
    assert_eq!(cell.len(), DISC_VERTICES);
    let [x, y, a] = sys.bodies.q[DISC];
    for &k in cell {
        let r = (b.points[k][0] - x).hypot(b.points[k][1] - y);
        assert!((r - 0.03).abs() < 1e-12, "disc vertex at radius {r}");
    }
    let first = b.points[cell[0]];
    assert!((first[0] - (x + 0.03 * a.cos())).abs() < 1e-12 && (first[1] - (y + 0.03 * a.sin())).abs() < 1e-12);
}

#[test]
fn contacts_file_is_the_force_network_and_the_floor_carries_the_weight() {
    let dir = TempDir::new("contacts");
    let sys = system(20);
    let (_, c) = write_and_parse(&dir.0, &sys);
    let infos: Vec<_> = sys.contact_forces().collect();
    assert_eq!(c.cell_kind, "LINES");
    assert_eq!(c.cells.len(), infos.len(), "one cell per contact");
    assert!(!infos.is_empty());
    assert_eq!(c.points.len(), sys.bodies.len(), "one point per centre of mass");
    for (k, q) in sys.bodies.q.iter().enumerate() {
        assert_eq!(c.points[k], [q[0], q[1], 0.0]);
    }
    for name in ["force", "normal", "point"] {
        assert_eq!(c.array(name).components, 3, "{name}");
    }
    assert_eq!(c.array("force").kind, Kind::Vectors);
    assert_eq!(c.array("point").kind, Kind::Field);

    let (mut on_block, mut on_disc) = (0.0, 0.0);
    for (k, info) in infos.iter().enumerate() {
        let (a, b) = (c.scalar("candidate")[k] as usize, c.scalar("antagonist")[k] as usize);
        assert_eq!((a, b), (info.candidate, info.antagonist));
        assert_eq!(c.cells[k], [a, b], "line from candidate to antagonist");
        let (r_n, r_t) = (c.scalar("normal_force")[k], c.scalar("tangential_force")[k]);
        assert_eq!((r_n, r_t, c.scalar("gap")[k]), (info.r_n, info.r_t, info.gap));
        assert_eq!(c.tuple("point", k), [info.point[0], info.point[1], 0.0]);
        // force = r_n n + r_t t, t = n rotated by +90°.
        let n = c.tuple("normal", k);
        let f = c.tuple("force", k);
        assert!((f[0] - (r_n * n[0] - r_t * n[1])).abs() <= 1e-12 * r_n.abs().max(1.0));
        assert!((f[1] - (r_n * n[1] + r_t * n[0])).abs() <= 1e-12 * r_n.abs().max(1.0));
        assert_eq!(f[2], 0.0);
        let other = match (a, b) {
            (FLOOR, o) | (o, FLOOR) => o,
            _ => panic!("only the floor carries anything, got contact {a}-{b}"),
        };
        match other {
            BLOCK => on_block += r_n,
            DISC => on_disc += r_n,
            o => panic!("body {o} touches the floor"),
        }
    }
    // Resting bodies on a horizontal floor: the normal forces of their floor
    // contacts add up to their weights (no tangential part: the normal is
    // vertical). The scene's NLGS tolerance (quad norm, 1e-6) bounds the last
    // sweep's velocity correction relative to the velocity scale of the contact
    // impulses, i.e. the relative error of the impulses, hence of Σ r_n, of a
    // converged step. Warm-started steps at rest only shrink it (measured: ~3e-9
    // on the first, cold step; round-off after 20), so `tolerance · weight` is a
    // bound the solver must meet, not a tuned margin.
    let tol = scene().nscd.unwrap().tolerance.unwrap();
    let g = 9.81;
    for (name, i, sum) in [("block", BLOCK, on_block), ("disc", DISC, on_disc)] {
        let weight = sys.bodies.info[i].mass * g;
        assert!((sum - weight).abs() <= tol * weight, "{name}: floor carries {sum} N, weight {weight} N");
    }
}

#[test]
fn empty_contact_set_is_a_valid_file() {
    let dir = TempDir::new("empty");
    let sys = system(0); // no step yet: no contacts
    let (b, c) = write_and_parse(&dir.0, &sys);
    assert_eq!(b.cells.len(), 4);
    assert!(c.cells.is_empty() && c.cell_data.is_empty());
    assert_eq!(c.points.len(), 4);
    let vtp = parse_vtp(&std::fs::read_to_string(dir.0.join("contacts.vtp")).unwrap());
    assert!(vtp.cells.is_empty());
    assert!(vtp.cell_data.values().all(|a| a.values.is_empty()));
}

#[test]
fn unknown_extension_is_refused() {
    let dir = TempDir::new("ext");
    let sys = system(0);
    let path = dir.0.join("bodies.txt");
    let err = write_bodies(&path, &sys).unwrap_err().to_string();
    assert!(err.contains("bodies.txt") && err.contains(".vtp"), "{err}");
    assert!(!path.exists());
    assert!(write_contacts(&dir.0.join("contacts"), &sys).is_err());
    // The extension is case-insensitive.
    write_bodies(&dir.0.join("BODIES.VTP"), &sys).unwrap();
}

#[test]
fn pvd_lists_the_snapshots_with_increasing_timesteps() {
    let dir = TempDir::new("pvd");
    let mut sys = scene().build().unwrap();
    let mut pvd = PvdCollection::new();
    for k in 1..=20 {
        sys.step().unwrap();
        if k % 5 == 0 {
            let (b, c) = ballast::plane::vtk::write_snapshot(&mut pvd, &dir.0, &sys).unwrap();
            assert_eq!(b, dir.0.join(format!("bodies_{k:09}.vtp")));
            assert_eq!(c, dir.0.join(format!("contacts_{k:09}.vtp")));
            pvd.write(&dir.0.join("run.pvd")).unwrap();
        }
    }
    assert_eq!(pvd.len(), 4);
    let text = std::fs::read_to_string(dir.0.join("run.pvd")).unwrap();
    assert!(!dir.0.join("run.pvd.tmp").exists());
    assert_well_formed(&text);
    assert!(text.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\""));
    assert!(text.contains("<Collection>") && text.contains("</Collection>"));

    let tags: Vec<&str> = text.split("<DataSet").skip(1).map(|s| &s[..s.find("/>").unwrap()]).collect();
    assert_eq!(tags.len(), 8, "two parts per time step");
    let mut last = f64::NEG_INFINITY;
    for (j, pair) in tags.chunks(2).enumerate() {
        let step = 5 * (j + 1);
        let t: f64 = num(attr(pair[0], "timestep").unwrap());
        assert_eq!(attr(pair[1], "timestep").map(num::<f64>), Some(t), "both parts at the same time");
        assert!(t > last, "timesteps increase");
        assert!((t - step as f64 * 1e-3).abs() < 1e-15);
        last = t;
        for (part, name, tag) in [("0", "bodies", pair[0]), ("1", "contacts", pair[1])] {
            assert_eq!(attr(tag, "part"), Some(part));
            let file = attr(tag, "file").unwrap();
            // Relative to the .pvd's directory, and there.
            assert_eq!(file, format!("{name}_{step:09}.vtp"));
            parse_vtp(&std::fs::read_to_string(dir.0.join(file)).unwrap());
        }
    }

    // Names relative to the .pvd's directory are kept; files outside it are
    // named by their absolute path.
    let mut other = PvdCollection::new();
    other.push(0.5, "bodies_000000005.vtp", dir.0.join("contacts_000000005.vtp"));
    let xml = other.to_xml(&dir.0);
    assert!(xml.contains("file=\"bodies_000000005.vtp\"") && xml.contains("file=\"contacts_000000005.vtp\""));
    let sub = dir.0.join("sub");
    std::fs::create_dir(&sub).unwrap();
    other.write(&sub.join("run.pvd")).unwrap();
    let xml = std::fs::read_to_string(sub.join("run.pvd")).unwrap();
    let abs = dir.0.canonicalize().unwrap().join("contacts_000000005.vtp");
    assert!(xml.contains(&format!("file=\"{}\"", abs.display())), "{xml}");

    // Pushing an earlier time (a resumed run) drops the later entries.
    pvd.push(0.0125, "b.vtp", "c.vtp");
    let times: Vec<f64> = pvd.entries().iter().map(|e| e.time).collect();
    assert_eq!(times.len(), 3);
    assert_eq!(times[2], 0.0125);
    assert!(times[1] < 0.0125);
    // Special characters are escaped in the XML.
    pvd.push(1.0, "a&b \"c\".vtp", "<d>.vtp");
    let xml = pvd.to_xml(Path::new(""));
    assert_well_formed(&xml);
    assert!(xml.contains("file=\"a&amp;b &quot;c&quot;.vtp\"") && xml.contains("file=\"&lt;d&gt;.vtp\""));
}
