//! The one reader of LIGGGHTS data files (`read_data`, `atom_style sphere`): the header counts
//! and box, the `Atoms` section (`id type diameter density x y z [ix iy iz]`) and the
//! `Velocities` section (`id vx vy vz wx wy wz`). The deck's `read_data` and the nonlocal scenes
//! (and `mcdem packing --describe`) read data files through it, so both accept and refuse the
//! same files with the same messages.

use std::path::Path;

use super::lexer::strip_comment;
use super::{int, num, unsupported, R};

/// One line of the `Atoms` section.
#[derive(Debug, Clone, PartialEq)]
pub struct DataAtom {
    pub id: i64,
    /// Atom type as written (1-based).
    pub typ: usize,
    pub diameter: f64,
    pub density: f64,
    pub x: [f64; 3],
    /// Image flags, when the line has them.
    pub image: Option<[i32; 3]>,
}

/// What a data file holds.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DataFile {
    /// `N atoms`.
    pub natoms: usize,
    /// `N atom types`, when the header has it.
    pub atom_types: Option<usize>,
    /// The box bounds (xlo xhi ylo yhi zlo zhi) from the header lines before the `Atoms` section;
    /// `None` without an `Atoms` section.
    pub bounds: Option<[f64; 6]>,
    pub atoms: Vec<DataAtom>,
    /// `Velocities` lines: the index of the atom in `atoms`, velocity and angular velocity.
    pub velocities: Vec<(usize, [f64; 6])>,
    /// The file has a `Velocities` header (even an empty section).
    pub has_velocities: bool,
}

/// Reads the data file at `path`.
pub fn read(path: &Path) -> R<DataFile> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read data file {}: {e}", path.display()))?;
    parse(&text, path)
}

/// Parses the text of a data file; `path` names it in the messages. The first line is the
/// title; `#` starts a comment. Sections and header keywords other than those above stop with an
/// `unsupported` message naming them, and the atom count must match the header.
pub fn parse(text: &str, path: &Path) -> R<DataFile> {
    let mut d = DataFile::default();
    let mut b = [0.0; 6];
    let mut section = "";
    // Velocities name atoms by id: one map for the section (a search per line is quadratic).
    let mut by_id = std::collections::HashMap::new();
    for l in text.lines().skip(1) {
        let l = strip_comment(l).trim();
        if l.is_empty() {
            continue;
        }
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.as_slice() {
            [n, "atoms"] => d.natoms = int(n)? as usize,
            [n, "atom", "types"] => d.atom_types = Some(int(n)? as usize),
            [lo, hi, "xlo", "xhi"] => (b[0], b[1]) = (num(lo)?, num(hi)?),
            [lo, hi, "ylo", "yhi"] => (b[2], b[3]) = (num(lo)?, num(hi)?),
            [lo, hi, "zlo", "zhi"] => (b[4], b[5]) = (num(lo)?, num(hi)?),
            ["Atoms", ..] => {
                if d.bounds.is_some() {
                    // As the deck reader always said: the box is set at the Atoms header, once.
                    return Err("the simulation box already exists".into());
                }
                d.bounds = Some(b);
                section = "Atoms";
            }
            ["Velocities"] => {
                section = "Velocities";
                d.has_velocities = true;
                by_id = d.atoms.iter().enumerate().map(|(i, a)| (a.id, i)).collect();
            }
            [word, ..] if word.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) => {
                return Err(unsupported(&format!(
                    "data file section or header \"{l}\" in {}",
                    path.display()
                )));
            }
            _ => match section {
                "Atoms" => {
                    if t.len() < 7 {
                        return Err(format!(
                            "{}: Atoms line needs id type diameter density x y z: \"{l}\"",
                            path.display()
                        ));
                    }
                    let image = if t.len() >= 10 {
                        Some([int(t[7])? as i32, int(t[8])? as i32, int(t[9])? as i32])
                    } else {
                        None
                    };
                    d.atoms.push(DataAtom {
                        id: int(t[0])?,
                        typ: int(t[1])? as usize,
                        diameter: num(t[2])?,
                        density: num(t[3])?,
                        x: [num(t[4])?, num(t[5])?, num(t[6])?],
                        image,
                    });
                }
                "Velocities" => {
                    if t.len() < 7 {
                        return Err(format!(
                            "{}: Velocities line needs id vx vy vz wx wy wz",
                            path.display()
                        ));
                    }
                    let id = int(t[0])?;
                    let i = *by_id.get(&id).ok_or_else(|| format!("no atom with id {id}"))?;
                    let mut v = [0.0; 6];
                    for (k, x) in v.iter_mut().enumerate() {
                        *x = num(t[k + 1])?;
                    }
                    d.velocities.push((i, v));
                }
                _ => return Err(format!("{}: data line outside a section: \"{l}\"", path.display())),
            },
        }
    }
    if d.atoms.len() != d.natoms {
        return Err(format!("{}: header says {} atoms, found {}", path.display(), d.natoms, d.atoms.len()));
    }
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = "title\n\n2 atoms\n1 atom types\n0 1 xlo xhi\n0 2 ylo yhi\n0 3 zlo zhi\n\nAtoms # sphere\n\n\
                        1 1 0.1 1000 0.5 0.5 0.5\n2 1 0.2 2000 0.5 1.5 2.5 0 1 0\n\nVelocities\n\n2 1 2 3 4 5 6\n";

    #[test]
    fn reads_header_atoms_and_velocities() {
        let d = parse(FILE, Path::new("f.data")).unwrap();
        assert_eq!((d.natoms, d.atom_types, d.bounds), (2, Some(1), Some([0.0, 1.0, 0.0, 2.0, 0.0, 3.0])));
        assert_eq!(
            d.atoms[1],
            DataAtom {
                id: 2,
                typ: 1,
                diameter: 0.2,
                density: 2000.0,
                x: [0.5, 1.5, 2.5],
                image: Some([0, 1, 0])
            }
        );
        assert_eq!((d.atoms[0].image, &d.velocities), (None, &vec![(1, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0])]));
    }

    #[test]
    fn bad_files_name_the_file_and_the_fault() {
        let p = Path::new("f.data");
        let err = |text: String| parse(&text, p).unwrap_err();
        assert_eq!(err(FILE.replace("2 atoms", "3 atoms")), "f.data: header says 3 atoms, found 2");
        assert!(err(FILE.replace("1 atom types", "Masses")).starts_with("unsupported data file section"));
        assert_eq!(err(FILE.replace("2 1 2 3", "7 1 2 3")), "no atom with id 7");
        assert!(err(FILE.replace(" 1 0.1 1000", " 1 0.1")).starts_with("f.data: Atoms line needs"));
    }
}
