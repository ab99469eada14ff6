//! Legacy ASCII VTK (file version 5.1) pieces shared by the DEM's `dump custom/vtk` / `mesh/vtk`
//! (src/deck/vtk.rs) and the MPM snapshots (src/mpm/vtk.rs).
//!
//! Numbers as VTK's own writer prints them: `float` with `%g`, `double` with `%.11g`, `int` with
//! `%d`; nine values per line, each followed by a space, and a line break after every array.

use std::io::Write;
use std::path::Path;

use crate::deck::format;
use crate::deck::output::create;
use crate::physics::Vec3;

/// The three header lines: version, title, ASCII.
pub fn header(title: &str) -> String {
    format!("# vtk DataFile Version 5.1\n{title}\nASCII\n")
}

/// VTK's array layout: values each followed by a space, nine per line, then a line break.
pub fn array(s: &mut String, values: impl Iterator<Item = String>) {
    for (k, v) in values.enumerate() {
        s.push_str(&v);
        s.push(' ');
        if (k + 1) % 9 == 0 {
            s.push('\n');
        }
    }
    s.push('\n');
}

/// A value of a `float` array (rounded to single precision, `%g`).
pub fn float(x: f64) -> String {
    format::g(x as f32 as f64, 6)
}

/// A value of a `double` array (`%.11g`).
pub fn double(x: f64) -> String {
    format::g(x, 11)
}

/// Points, then cells of `per_cell` consecutive points (`keyword` VERTICES, LINES or POLYGONS).
pub fn points_and_cells(s: &mut String, points: &[Vec3], keyword: &str, per_cell: usize) {
    s.push_str(&format!("POINTS {} float\n", points.len()));
    array(s, points.iter().flat_map(|p| p.iter().map(|x| float(*x)).collect::<Vec<_>>()));
    let cells = points.len() / per_cell;
    s.push_str(&format!("{keyword} {} {}\nOFFSETS vtktypeint64\n", cells + 1, points.len()));
    array(s, (0..=cells).map(|c| (c * per_cell).to_string()));
    s.push_str("CONNECTIVITY vtktypeint64\n");
    array(s, (0..points.len()).map(|k| k.to_string()));
}

/// Writes `text` to `path`, creating missing parent directories.
pub fn write_file(path: &Path, text: &str) -> Result<(), String> {
    let mut out = create(path)?;
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}
