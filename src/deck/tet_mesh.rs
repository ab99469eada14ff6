//! `region ID mesh/tet file F scale S move dx dy dz rotate ax ay az units box`: a volume made of
//! the tetrahedra of a legacy ASCII VTK unstructured grid (LIGGGHTS 3.8 `src/region_mesh_tet.cpp`,
//! file reader `src/input_mesh_tet.cpp`).
//!
//! The file: a header line, a title line, `ASCII`, `DATASET UNSTRUCTURED_GRID`, `POINTS n type`
//! and 3n coordinates, `CELLS n size` and n cells (`k i0 … ik-1`), `CELL_TYPES n` and n types.
//! Cells of type 10 (VTK_TETRA) are kept; others are dropped with a warning, as LIGGGHTS does.
//! Anything after the cell types (point or cell data) is not read. Vertices are moved, then scaled,
//! then rotated (angles in degrees about x, y, z, the rotation LIGGGHTS writes out term by term).

use super::*;

/// A tetrahedral mesh region: nodes of each tetrahedron (positive orientation) and the bounding
/// box of all of them.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct TetMesh {
    tets: Vec<[Vec3; 4]>,
    /// Per tetrahedron: its bounding box, a cheap rejection before the four volume tests.
    boxes: Vec<(Vec3, Vec3)>,
    lo: Vec3,
    hi: Vec3,
    volume: f64,
}

/// Signed volume of the tetrahedron (v0, v1, v2, v3): ((v3 − v1) × (v2 − v1)) · (v0 − v1) / 6,
/// evaluated in the order of LIGGGHTS 3.8 `RegTetMesh::volume_of_tet` so that the sign, which
/// decides whether a lattice site on a shared face is inside, is the same bit for bit.
fn signed_volume(v0: &Vec3, v1: &Vec3, v2: &Vec3, v3: &Vec3) -> f64 {
    let a = [v3.x - v1.x, v3.y - v1.y, v3.z - v1.z];
    let b = [v2.x - v1.x, v2.y - v1.y, v2.z - v1.z];
    let c = [v0.x - v1.x, v0.y - v1.y, v0.z - v1.z];
    let cp = [a[1] * b[2] - a[2] * b[1], -a[0] * b[2] + a[2] * b[0], a[0] * b[1] - a[1] * b[0]];
    (cp[0] * c[0] + cp[1] * c[1] + cp[2] * c[2]) / 6.0
}

impl TetMesh {
    /// Strictly inside one of the tetrahedra: the four volumes with the point in place of one node
    /// all > 0 (`RegTetMesh::is_inside_tet`). A point on a face is inside no tetrahedron that
    /// face belongs to, so lattice sites on inner faces are left out, as in LIGGGHTS.
    pub(super) fn holds(&self, x: &Vec3) -> bool {
        if (0..3).any(|k| x[k] < self.lo[k] || x[k] > self.hi[k]) {
            return false;
        }
        self.tets.iter().zip(&self.boxes).any(|(n, (lo, hi))| {
            (0..3).all(|k| x[k] >= lo[k] && x[k] <= hi[k])
                && signed_volume(&n[0], &n[1], &n[2], x) > 0.0
                && signed_volume(&n[0], &n[1], x, &n[3]) > 0.0
                && signed_volume(&n[0], x, &n[2], &n[3]) > 0.0
                && signed_volume(x, &n[1], &n[2], &n[3]) > 0.0
        })
    }

    pub(super) fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    /// The sum of the tetrahedra's volumes (LIGGGHTS `total_vol`).
    pub(super) fn volume(&self) -> f64 {
        self.volume
    }

    pub(super) fn len(&self) -> usize {
        self.tets.len()
    }
}

/// Where the vertices go: `(x + move) · scale`, then rotated.
pub(super) struct Placement {
    pub scale: f64,
    pub shift: Vec3,
    /// Degrees about x, y, z.
    pub rotate: Vec3,
}

impl Placement {
    /// LIGGGHTS 3.8 `InputMeshTet::meshtetfile_vtk`: translate, scale, then the rotation
    /// R = Rz(φz)·Ry(φy)·Rx(φx) written out (same terms, same order).
    fn place(&self, p: &Vec3) -> Vec3 {
        let v = (p + self.shift) * self.scale;
        let r = self.rotate * (std::f64::consts::PI / 180.0);
        let (cx, sx, cy, sy, cz, sz) = (r.x.cos(), r.x.sin(), r.y.cos(), r.y.sin(), r.z.cos(), r.z.sin());
        Vec3::new(
            v.x * cy * cz + v.y * (cz * sx * sy - cx * sz) + v.z * (cx * cz * sy + sx * sz),
            v.x * cy * sz + v.z * (-cz * sx + cx * sy * sz) + v.y * (cx * cz + sx * sy * sz),
            v.z * cx * cy + v.y * cy * sx - v.x * sy,
        )
    }
}

/// Reads a tetrahedral mesh; `warn` receives the note about dropped cells. Errors name the file
/// and the line.
pub(super) fn read_vtk(path: &Path, place: &Placement, warn: &mut dyn FnMut(String)) -> R<TetMesh> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read tet mesh file {name}: {e}"))?;
    let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l));
    let bad = |line: usize, what: &str| format!("{name}:{line}: {what}");
    let mut next_line = |what: &str| -> R<(usize, &str)> {
        lines
            .by_ref()
            .find(|(_, l)| !l.trim().is_empty())
            .ok_or_else(|| format!("{name}: file ends before {what}"))
    };
    let (l, head) = next_line("the header")?;
    if !head.trim_start().starts_with("# vtk DataFile") {
        return Err(bad(l, "not a legacy VTK file (expected '# vtk DataFile Version …')"));
    }
    next_line("the title")?;
    let (l, fmt) = next_line("ASCII")?;
    if fmt.trim() != "ASCII" {
        return Err(bad(l, &format!("expected ASCII, got '{}' (binary VTK is not read)", fmt.trim())));
    }
    let (l, ds) = next_line("DATASET")?;
    if ds.split_whitespace().collect::<Vec<_>>() != ["DATASET", "UNSTRUCTURED_GRID"] {
        return Err(bad(l, &format!("expected 'DATASET UNSTRUCTURED_GRID', got '{}'", ds.trim())));
    }
    // The rest is read as words with their line numbers: VTK lets values wrap freely.
    let mut words = lines.flat_map(|(k, l)| l.split_whitespace().map(move |w| (k, w)));
    let mut last_line = l;
    let mut word = |what: &str| -> R<(usize, &str)> {
        let w = words.next().ok_or_else(|| format!("{name}: file ends before {what}"))?;
        last_line = w.0;
        Ok(w)
    };
    let count = |(l, w): (usize, &str), what: &str| -> R<usize> {
        w.parse::<usize>().map_err(|_| bad(l, &format!("{what}: expected a count, got '{w}'")))
    };
    let keyword = |(l, w): (usize, &str), want: &str| -> R<()> {
        if w == want {
            Ok(())
        } else {
            Err(bad(l, &format!("expected '{want}', got '{w}'")))
        }
    };
    keyword(word("POINTS")?, "POINTS")?;
    let npoints = count(word("the number of points")?, "POINTS")?;
    word("the point data type")?;
    let mut points = Vec::with_capacity(npoints);
    for _ in 0..npoints {
        let mut c = [0.0; 3];
        for v in &mut c {
            let (l, w) = word("the last point")?;
            *v =
                w.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                    bad(l, &format!("point coordinate: expected a finite number, got '{w}'"))
                })?;
        }
        points.push(place.place(&Vec3::new(c[0], c[1], c[2])));
    }
    keyword(word("CELLS")?, "CELLS")?;
    let ncells = count(word("the number of cells")?, "CELLS")?;
    count(word("the cell list size")?, "CELLS size")?;
    let mut cells: Vec<(usize, Vec<usize>)> = Vec::with_capacity(ncells);
    for _ in 0..ncells {
        let w = word("the last cell")?;
        let k = count(w, "cell")?;
        let mut ids = Vec::with_capacity(k);
        for _ in 0..k {
            let (l, w) = word("the last cell")?;
            let i = count((l, w), "cell point index")?;
            if i >= npoints {
                return Err(bad(l, &format!("cell point index {i} beyond the {npoints} points")));
            }
            ids.push(i);
        }
        cells.push((w.0, ids));
    }
    keyword(word("CELL_TYPES")?, "CELL_TYPES")?;
    let w = word("the number of cell types")?;
    if count(w, "CELL_TYPES")? != ncells {
        return Err(bad(w.0, &format!("CELL_TYPES {} differs from CELLS {ncells}", w.1)));
    }
    let mut tets = Vec::new();
    let mut dropped = 0usize;
    for (line, ids) in &cells {
        let w = word("the last cell type")?;
        match count(w, "cell type")? {
            10 if ids.len() == 4 => {
                tets.push([points[ids[0]], points[ids[1]], points[ids[2]], points[ids[3]]])
            }
            10 => return Err(bad(*line, &format!("a tetrahedron (type 10) with {} points", ids.len()))),
            _ => dropped += 1,
        }
    }
    if tets.is_empty() {
        return Err(format!("{name}:{last_line}: no tetrahedron (cell type 10) in the mesh"));
    }
    if dropped > 0 {
        warn(format!("{name}: {dropped} cells other than tetrahedra dropped (only tetrahedra make the region, as in LIGGGHTS)"));
    }
    let mut volume = 0.0;
    for n in &mut tets {
        // Nodes in positive order (LIGGGHTS `add_tet` swaps nodes 0 and 3 of a negative one).
        if signed_volume(&n[0], &n[1], &n[2], &n[3]) < 0.0 {
            n.swap(0, 3);
        }
        volume += signed_volume(&n[0], &n[1], &n[2], &n[3]);
    }
    let corner = |n: &[Vec3], f: fn(f64, f64) -> f64| {
        n.iter().skip(1).fold(n[0], |m, p| Vec3::new(f(m.x, p.x), f(m.y, p.y), f(m.z, p.z)))
    };
    let boxes: Vec<(Vec3, Vec3)> = tets.iter().map(|n| (corner(n, f64::min), corner(n, f64::max))).collect();
    let all: Vec<Vec3> = tets.iter().flatten().copied().collect();
    let (lo, hi) = (corner(&all, f64::min), corner(&all, f64::max));
    Ok(TetMesh { tets, boxes, lo, hi, volume })
}

impl Deck {
    /// The arguments of `region ID mesh/tet …` after the style; returns the region and how many
    /// words it used.
    pub(super) fn region_mesh_tet(&mut self, a: &[&str]) -> R<(regions::Region, usize)> {
        let what = "region mesh/tet";
        let expect = |k: usize, kw: &str| -> R<()> {
            match a.get(k) {
                Some(w) if *w == kw => Ok(()),
                Some(w) => Err(format!("{what}: expected keyword '{kw}', got '{w}'")),
                None => {
                    Err(format!("{what}: expected 'file F scale S move dx dy dz rotate ax ay az units box'"))
                }
            }
        };
        let n = |k: usize, name: &str| -> R<f64> {
            let s = a.get(k).ok_or_else(|| format!("{what}: missing {name}"))?;
            num(s).map_err(|e| format!("{what}: {name}: {e}"))
        };
        expect(3, "file")?;
        let file = a.get(4).ok_or_else(|| format!("{what}: missing file name"))?;
        expect(5, "scale")?;
        let scale = n(6, "scale")?;
        if scale <= 0.0 {
            return Err(format!("{what}: scale must be > 0, got {}", a[6]));
        }
        expect(7, "move")?;
        let shift = Vec3::new(n(8, "move x")?, n(9, "move y")?, n(10, "move z")?);
        expect(11, "rotate")?;
        let rotate = Vec3::new(n(12, "rotate x")?, n(13, "rotate y")?, n(14, "rotate z")?);
        // LIGGGHTS: "Lattice scaling not implemented for region mesh/tet, please use 'units box'".
        if !a[15..].windows(2).any(|w| w == ["units", "box"]) {
            return Err(format!(
                "{what}: needs 'units box' (lattice units are not implemented for it, as in LIGGGHTS)"
            ));
        }
        let path = self.input_path(file);
        let mut notes = Vec::new();
        let mesh = read_vtk(&path, &Placement { scale, shift, rotate }, &mut |m| notes.push(m))?;
        for m in notes {
            self.warn_here(&m);
        }
        // LIGGGHTS: a region may not reach outside the box.
        if let Some(d) = self.world.domain.as_ref() {
            let (lo, hi) = mesh.bounds();
            if (0..3).any(|k| lo[k] < d.lo[k] || hi[k] > d.hi[k]) {
                return Err(format!(
                    "{what}: {}: one or more vertices outside the simulation box",
                    path.display()
                ));
            }
        }
        self.say(&format!(
            "  {} tetrahedra, volume {:e} m³ from {}",
            mesh.len(),
            mesh.volume(),
            path.display()
        ));
        Ok((regions::Region::TetMesh(Box::new(mesh)), 12))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(text: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.vtk");
        std::fs::write(&p, text).unwrap();
        (dir, p)
    }

    const ONE: Placement =
        Placement { scale: 1.0, shift: Vec3::new(0.0, 0.0, 0.0), rotate: Vec3::new(0.0, 0.0, 0.0) };

    const HEAD: &str = "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";

    #[test]
    fn unit_tetrahedron_volume_and_inside() {
        let (_d, p) = write(&format!(
            "{HEAD}POINTS 5 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n9 9 9\nCELLS 2 9\n4 0 1 2 3\n3 0 1 2\nCELL_TYPES 2\n10\n5\n"
        ));
        let mut notes = Vec::new();
        let m = read_vtk(&p, &ONE, &mut |s| notes.push(s)).unwrap();
        assert_eq!(m.len(), 1);
        assert!((m.volume() - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(notes.len(), 1, "the triangle is dropped with a note");
        assert!(m.holds(&Vec3::new(0.1, 0.1, 0.1)));
        assert!(!m.holds(&Vec3::new(0.5, 0.5, 0.5)), "beyond the slanted face");
        assert!(!m.holds(&Vec3::new(0.0, 0.2, 0.2)), "on a face: outside, as LIGGGHTS");
    }

    #[test]
    fn malformed_files_name_file_and_line() {
        let cases = [
            (format!("{HEAD}POINTS 2 double\n0 0 0\n1 x 0\n"), ":7: point coordinate"),
            (format!("{HEAD}POINTS 1 double\n0 0 0\nCELLS 1 5\n4 0 1 2 3\n"), ":8: cell point index 1 beyond"),
            (format!("{HEAD}POINT 1 double\n"), ":5: expected 'POINTS', got 'POINT'"),
            ("# vtk DataFile Version 2.0\nt\nBINARY\n".to_string(), ":3: expected ASCII"),
            (format!("{HEAD}POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n5\n"), "no tetrahedron"),
            (format!("{HEAD}POINTS 4 double\n0 0 0\n1 0 0\n"), "file ends before the last point"),
        ];
        for (text, want) in cases {
            let (_d, p) = write(&text);
            let e = read_vtk(&p, &ONE, &mut |_| {}).unwrap_err();
            assert!(e.contains("m.vtk") && e.contains(want), "{e} (wanted {want})");
        }
    }

    #[test]
    fn placement_moves_then_scales() {
        let pl = Placement { scale: 2.0, shift: Vec3::new(1.0, 0.0, 0.0), rotate: Vec3::new(0.0, 0.0, 90.0) };
        let q = pl.place(&Vec3::new(1.0, 0.0, 0.0));
        // (1 + 1)·2 = 4 on x, turned 90° about z onto y.
        assert!((q - Vec3::new(0.0, 4.0, 0.0)).norm() < 1e-12, "{q}");
    }
}
