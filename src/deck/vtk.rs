//! `dump ID all custom/vtk N FILE columns…` and `dump ID all mesh/vtk N FILE keywords…`: legacy
//! ASCII VTK files as LIGGGHTS 3.8 (Debian build, VTK library writer) writes them, so ParaView
//! and other VTK readers open both engines' files the same way.
//!
//! What LIGGGHTS writes, and so what is written here:
//! - `custom/vtk`: `DATASET POLYDATA`, the positions as `POINTS n float`, one vertex cell per
//!   particle (`VERTICES` with `OFFSETS`/`CONNECTIVITY`, file version 5.1), and the listed columns
//!   as `POINT_DATA` arrays of a `FIELD`. A column is listed once however often the deck repeats
//!   it (`id type type x …`); x y z are the points, not an array; three components given together
//!   form one vector array named by the part before the `x` (`vx vy vz` → `v`, `ix iy iz` → `i`,
//!   `omegax …` → `omega`); arrays come in LIGGGHTS's fixed attribute order, not the deck's. Next to
//!   each frame LIGGGHTS writes the box as `…boundingBox_STEP.vtk` (`RECTILINEAR_GRID`): so here.
//! - `mesh/vtk`: the walls at their current position, `POLYDATA` with three points per triangle and
//!   one polygon per triangle, and the requested per-face data as `CELL_DATA`: `stress` →
//!   `normal_stress_average` and `shear_stress_average` (|f·n|/A and |f − (f·n)n|/A of the force f
//!   the particles exert on the face in that step), `stresscomponents` → `stress` (f/A), `id` →
//!   `meshid` (the face's index in the STL), `vel` → `v` (the face's velocity).
//!
//! Numbers and array layout as VTK's writer prints them (the helpers of [`crate::vtk_legacy`],
//! shared with the MPM snapshots).

use std::path::PathBuf;

use super::output::Col;
use crate::engine::World;
use crate::physics::Vec3;
use crate::vtk_legacy::{array, double, header, points_and_cells, write_file};

/// Position of a column in LIGGGHTS's attribute order (`DumpParticle`'s enum): arrays are written
/// in this order whatever the order of the deck.
fn rank(c: &Col) -> usize {
    match *c {
        Col::X(a) => a,
        Col::Id => 10,
        Col::Type => 12,
        Col::Mass => 14,
        Col::XU(a) => 20 + a,
        Col::Image(a) => 30 + a,
        Col::V(a) => 40 + a,
        Col::F(a) => 50 + a,
        Col::Radius => 60,
        Col::Diameter => 61,
        Col::Omega(a) => 70 + a,
        Col::Torque(a) => 80 + a,
        Col::Density => 90,
    }
}

/// One array of the point data: a scalar column or three components written as a vector.
#[derive(Debug, Clone)]
struct Field {
    name: String,
    cols: Vec<Col>,
    int: bool,
}

/// The particles as points.
#[derive(Debug)]
pub struct ParticleVtk {
    fields: Vec<Field>,
}

/// Which per-face data a `mesh/vtk` dump writes.
#[derive(Debug, Default)]
pub struct MeshVtk {
    /// Indices into the world's meshes (all meshes when the dump names none).
    meshes: Vec<usize>,
    stress: bool,
    components: bool,
    id: bool,
    vel: bool,
}

#[derive(Debug)]
pub enum What {
    Particles(ParticleVtk),
    Mesh(MeshVtk),
    /// `dump mesh/stl`: the meshes (indices) as ASCII STL.
    Stl(Vec<usize>),
}

/// A VTK dump: one legacy `.vtk` file per frame.
#[derive(Debug)]
pub struct VtkDump {
    pub name: String,
    pub every: u64,
    pub last: Option<u64>,
    file: String,
    what: What,
}

/// Checks the file name: `*` (one file per frame; a legacy VTK file holds one dataset) and the
/// `.vtk` extension (LIGGGHTS picks the XML writers for `.vtp`/`.vtu`, not written here).
fn check_file(style: &str, file: &str) -> Result<(), String> {
    if file.ends_with(".vtp") || file.ends_with(".vtu") {
        return Err(format!(
            "unsupported dump {style} to {file}: XML VTK (.vtp/.vtu) is not written by mcdem; use a .vtk name"
        ));
    }
    if !file.ends_with(".vtk") {
        return Err(format!("dump {style}: {file}: expected a name ending in .vtk"));
    }
    if !file.contains('*') {
        return Err(format!("dump {style}: {file}: expected a '*' in the name (one file per frame)"));
    }
    Ok(())
}

impl VtkDump {
    /// `custom/vtk` columns: those of `dump custom` (see [`Col`]), x y z as the points.
    pub fn particles(name: &str, every: u64, file: &str, columns: &[&str]) -> Result<Self, String> {
        check_file("custom/vtk", file)?;
        let mut cols: Vec<Col> = Vec::new();
        for c in columns {
            let col = Col::parse(c).ok_or_else(|| format!("unsupported dump custom/vtk column {c}"))?;
            if !cols.contains(&col) {
                cols.push(col);
            }
        }
        cols.sort_by_key(rank);
        let mut fields = Vec::new();
        let mut k = 0;
        while k < cols.len() {
            let c = cols[k];
            // Three components of one quantity listed together: one vector array (the columns are
            // sorted and unique, so the first and third component two apart means all three).
            let first = matches!(
                c,
                Col::X(0)
                    | Col::XU(0)
                    | Col::Image(0)
                    | Col::V(0)
                    | Col::F(0)
                    | Col::Omega(0)
                    | Col::Torque(0)
            );
            let vector = first && k + 2 < cols.len() && rank(&cols[k + 2]) == rank(&c) + 2;
            let n = if vector { 3 } else { 1 };
            if !matches!(c, Col::X(_)) {
                let word = columns.iter().find(|w| Col::parse(w) == Some(c)).expect("parsed above");
                // The name LIGGGHTS gives a vector: the first component's name cut at its first 'x'
                // ("vx" → "v"); for xu that would be empty, so "xu" is kept (an unnamed array is
                // unreadable).
                let name = match (vector, word.find('x')) {
                    (true, Some(at)) if at > 0 => word[..at].to_string(),
                    _ => word.to_string(),
                };
                fields.push(Field {
                    name,
                    cols: cols[k..k + n].to_vec(),
                    int: matches!(c, Col::Id | Col::Type | Col::Image(_)),
                });
            }
            k += n;
        }
        Ok(VtkDump {
            name: name.into(),
            every,
            last: None,
            file: file.into(),
            what: What::Particles(ParticleVtk { fields }),
        })
    }

    /// `mesh/vtk` keywords `stress stresscomponents id vel` and mesh fix IDs (`mesh_of` maps a
    /// fix ID to its mesh; `all` is every mesh, used when none is named).
    pub fn mesh(
        name: &str,
        every: u64,
        file: &str,
        words: &[&str],
        mesh_of: impl Fn(&str) -> Result<usize, String>,
        all: usize,
    ) -> Result<Self, String> {
        check_file("mesh/vtk", file)?;
        let mut m = MeshVtk::default();
        for w in words {
            match *w {
                "stress" => m.stress = true,
                "stresscomponents" => m.components = true,
                "id" => m.id = true,
                "vel" => m.vel = true,
                "output" | "face" => {
                    return Err(
                        "unsupported dump mesh/vtk keyword 'output' (face data only, the default)".into()
                    )
                }
                "wear" | "temp" | "owner" | "area" | "aedges" | "acorners" | "index" | "nneighs"
                | "distaa" => {
                    return Err(format!(
                        "unsupported dump mesh/vtk keyword {w} (written: stress stresscomponents id vel)"
                    ))
                }
                fix => m.meshes.push(mesh_of(fix).map_err(|e| format!("dump mesh/vtk: {e}"))?),
            }
        }
        if !(m.stress || m.components || m.id || m.vel) {
            return Err("dump mesh/vtk: no dump quantity selected (stress stresscomponents id vel)".into());
        }
        if m.meshes.is_empty() {
            m.meshes = (0..all).collect();
        }
        Ok(VtkDump { name: name.into(), every, last: None, file: file.into(), what: What::Mesh(m) })
    }

    /// `dump ID group mesh/stl N FILE [local|all] [mesh fix IDs]`: one ASCII STL file per frame of
    /// the meshes as they stand (moved); every mesh when none is named, as LIGGGHTS.
    pub fn stl(
        name: &str,
        every: u64,
        file: &str,
        words: &[&str],
        mesh_of: impl Fn(&str) -> Result<usize, String>,
        all: usize,
    ) -> Result<Self, String> {
        if !file.contains('*') {
            return Err(format!("dump mesh/stl: {file}: expected a '*' in the name (one file per frame)"));
        }
        let mut meshes = Vec::new();
        for w in words {
            match *w {
                // One process: the local triangles are all of them.
                "local" | "all" => {}
                "binary" | "ghost" => {
                    return Err(format!("unsupported dump mesh/stl keyword {w} (ASCII, local or all)"))
                }
                fix => meshes.push(mesh_of(fix).map_err(|e| format!("dump mesh/stl: {e}"))?),
            }
        }
        if meshes.is_empty() {
            meshes = (0..all).collect();
        }
        Ok(VtkDump { name: name.into(), every, last: None, file: file.into(), what: What::Stl(meshes) })
    }

    /// Writes the frame of the current step; `moving[m]`: mesh m is under a `fix move/mesh`.
    pub fn write(&mut self, w: &World, moving: &[bool]) -> Result<(), String> {
        self.last = Some(w.step);
        let step = w.step.to_string();
        let path = PathBuf::from(self.file.replace('*', &step));
        let text = match &self.what {
            What::Particles(p) => {
                let (lo, hi) = w.output_box().ok_or("dump before the box exists")?;
                // LIGGGHTS puts the box next to the particles: prefix + "boundingBox_" + step + suffix.
                let (pre, post) = self.file.split_once('*').expect("checked at parse");
                let bb = PathBuf::from(format!("{pre}boundingBox_{step}{post}"));
                write_file(&bb, &bounding_box(&lo, &hi))?;
                particles(p, w)
            }
            What::Mesh(m) => mesh(m, w, moving),
            What::Stl(m) => stl(m, w),
        };
        write_file(&path, &text)
    }
}

/// The title line LIGGGHTS's files carry.
const TITLE: &str = "Generated by LIGGGHTS";

fn particles(p: &ParticleVtk, w: &World) -> String {
    let n = w.p.len();
    // Id order, as the text dumps, so frames of one run line up whatever the engine's sorting.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_unstable_by_key(|&i| w.p.id[i]);
    let mut s = String::with_capacity(200 * (n + 4));
    s.push_str(&header(TITLE));
    s.push_str("DATASET POLYDATA\n");
    let pts: Vec<Vec3> = order.iter().map(|&i| w.p.x[i]).collect();
    points_and_cells(&mut s, &pts, "VERTICES", 1);
    s.push_str(&format!("POINT_DATA {n}\nFIELD FieldData {}\n", p.fields.len()));
    for f in &p.fields {
        let ty = if f.int { "int" } else { "double" };
        s.push_str(&format!("{} {} {n} {ty}\n", f.name, f.cols.len()));
        let values = order.iter().flat_map(|&i| {
            f.cols.iter().map(move |c| {
                let v = c.value(w, i);
                if f.int {
                    (v as i64).to_string()
                } else {
                    double(v)
                }
            })
        });
        array(&mut s, values);
    }
    s
}

fn bounding_box(lo: &Vec3, hi: &Vec3) -> String {
    let mut s = header(TITLE);
    s.push_str("DATASET RECTILINEAR_GRID\nDIMENSIONS 2 2 2\n");
    for (a, axis) in ["X", "Y", "Z"].iter().enumerate() {
        s.push_str(&format!("{axis}_COORDINATES 2 double\n"));
        array(&mut s, [double(lo[a]), double(hi[a])].into_iter());
    }
    s
}

/// All dumped meshes in one dataset, appended in order. As in LIGGGHTS, a mesh without face
/// forces (plain `mesh/surface`) or without velocity (no `fix move/mesh`) writes zeros in an array
/// another mesh of the file has, and an array no mesh has is left out.
/// ASCII STL as LIGGGHTS writes it (`%g` numbers, unit normals from the vertex order); the
/// closing line only when a triangle was written.
fn stl(meshes: &[usize], w: &World) -> String {
    let g = |v: &Vec3| {
        format!("{} {} {}", super::format::g(v.x, 6), super::format::g(v.y, 6), super::format::g(v.z, 6))
    };
    let mut s = String::from("solid LIGGGHTS_STL_EXPORT\n");
    let mut any = false;
    for &k in meshes {
        for tri in &w.meshes[k].tris {
            let n = (tri.v[1] - tri.v[0]).cross(&(tri.v[2] - tri.v[0]));
            s.push_str(&format!("  facet normal {}\n    outer loop\n", g(&(n / n.norm()))));
            for v in &tri.v {
                s.push_str(&format!("      vertex {}\n", g(v)));
            }
            s.push_str("    endloop\n  endfacet\n");
            any = true;
        }
    }
    if any {
        s.push_str("endsolid LIGGGHTS_STL_EXPORT\n");
    }
    s
}

fn mesh(m: &MeshVtk, w: &World, moving: &[bool]) -> String {
    let with_stress = m.meshes.iter().any(|&k| w.meshes[k].stress);
    let with_vel = m.meshes.iter().any(|&k| moving[k]);
    let mut pts = Vec::new();
    // Per face: force on it, area, unit normal, index in its mesh, velocity.
    let mut faces: Vec<(Vec3, f64, Vec3, usize, Vec3)> = Vec::new();
    for &k in &m.meshes {
        let me = &w.meshes[k];
        let forces = if me.stress { w.mesh_face_forces(k) } else { vec![Vec3::zeros(); me.tris.len()] };
        for (t, tri) in me.tris.iter().enumerate() {
            // The face's velocity at its centre (the mean of its node velocities).
            let centre = (tri.v[0] + tri.v[1] + tri.v[2]) / 3.0;
            let v = if moving[k] { me.velocity_at(t, &centre) } else { Vec3::zeros() };
            pts.extend_from_slice(&tri.v);
            let n = (tri.v[1] - tri.v[0]).cross(&(tri.v[2] - tri.v[0]));
            let area = 0.5 * n.norm();
            faces.push((forces[t], area, n / n.norm(), t, v));
        }
    }
    let mut s = header(TITLE);
    s.push_str("DATASET POLYDATA\n");
    points_and_cells(&mut s, &pts, "POLYGONS", 3);
    let nf = faces.len();
    let mut arrays: Vec<(&str, usize, &str, Vec<String>)> = Vec::new();
    if m.stress && with_stress {
        let sn = faces.iter().map(|(f, a, n, _, _)| double(f.dot(n).abs() / a)).collect();
        let st = faces.iter().map(|(f, a, n, _, _)| double((f - n * f.dot(n)).norm() / a)).collect();
        arrays.push(("normal_stress_average", 1, "double", sn));
        arrays.push(("shear_stress_average", 1, "double", st));
    }
    if m.components && with_stress {
        let v =
            faces.iter().flat_map(|(f, a, ..)| f.iter().map(|x| double(x / a)).collect::<Vec<_>>()).collect();
        arrays.push(("stress", 3, "double", v));
    }
    if m.id {
        arrays.push(("meshid", 1, "int", faces.iter().map(|x| x.3.to_string()).collect()));
    }
    if m.vel && with_vel {
        let v = faces.iter().flat_map(|x| x.4.iter().map(|c| double(*c)).collect::<Vec<_>>()).collect();
        arrays.push(("v", 3, "double", v));
    }
    s.push_str(&format!("CELL_DATA {nf}\nFIELD FieldData {}\n", arrays.len()));
    for (name, comps, ty, values) in arrays {
        s.push_str(&format!("{name} {comps} {nf} {ty}\n"));
        array(&mut s, values.into_iter());
    }
    s
}
