//! LIGGGHTS-format writers: thermo lines, `dump custom` frames, `fix ave/time` files.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::format::{self, Piece};
use crate::engine::World;

/// Opens an output file, creating missing parent directories (LIGGGHTS would stop instead; a
/// fresh working directory without `post/` is the common case when running a shipped example).
pub fn create(path: &Path) -> Result<BufWriter<File>, String> {
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)
                .map_err(|e| format!("cannot create directory {}: {e}", dir.display()))?;
        }
    }
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| format!("cannot open output file {}: {e}", path.display()))
}

/// A per-atom column of `dump custom`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Col {
    Id,
    Type,
    X(usize),
    XU(usize),
    Image(usize),
    V(usize),
    F(usize),
    Omega(usize),
    Torque(usize),
    Radius,
    Diameter,
    Mass,
    Density,
}

impl Col {
    pub fn parse(s: &str) -> Option<Col> {
        let axis = |c: char| match c {
            'x' => Some(0),
            'y' => Some(1),
            'z' => Some(2),
            _ => None,
        };
        Some(match s {
            "id" => Col::Id,
            "type" => Col::Type,
            "x" | "y" | "z" => Col::X(axis(s.chars().next()?)?),
            "xu" | "yu" | "zu" => Col::XU(axis(s.chars().next()?)?),
            "ix" | "iy" | "iz" => Col::Image(axis(s.chars().nth(1)?)?),
            "vx" | "vy" | "vz" => Col::V(axis(s.chars().nth(1)?)?),
            "fx" | "fy" | "fz" => Col::F(axis(s.chars().nth(1)?)?),
            "omegax" | "omegay" | "omegaz" => Col::Omega(axis(s.chars().nth(5)?)?),
            "tqx" | "tqy" | "tqz" => Col::Torque(axis(s.chars().nth(2)?)?),
            "radius" => Col::Radius,
            "diameter" => Col::Diameter,
            "mass" => Col::Mass,
            "density" => Col::Density,
            _ => return None,
        })
    }

    fn is_int(&self) -> bool {
        matches!(self, Col::Id | Col::Type | Col::Image(_))
    }

    pub(super) fn value(&self, w: &World, i: usize) -> f64 {
        let p = &w.p;
        match *self {
            Col::Id => p.id[i] as f64,
            Col::Type => (p.typ[i] + 1) as f64,
            Col::X(a) => p.x[i][a],
            Col::XU(a) => {
                let d = w.domain.map(|d| d.hi[a] - d.lo[a]).unwrap_or(0.0);
                p.x[i][a] + p.image[i][a] as f64 * d
            }
            Col::Image(a) => p.image[i][a] as f64,
            Col::V(a) => p.v[i][a],
            Col::F(a) => p.f[i][a],
            Col::Omega(a) => p.omega[i][a],
            Col::Torque(a) => p.torque[i][a],
            Col::Radius => p.radius[i],
            Col::Diameter => 2.0 * p.radius[i],
            Col::Mass => p.mass[i],
            Col::Density => p.density[i],
        }
    }
}

/// `dump ID group custom N file columns…`.
#[derive(Debug)]
pub struct Dump {
    pub name: String,
    pub every: u64,
    pub file: PathBuf,
    pub names: Vec<String>,
    pub cols: Vec<Col>,
    pub format: Option<Vec<Piece>>,
    pub last: Option<u64>,
    out: Option<BufWriter<File>>,
}

impl Dump {
    pub fn new(name: &str, every: u64, file: PathBuf, names: Vec<String>, cols: Vec<Col>) -> Self {
        Dump { name: name.into(), every, file, names, cols, format: None, last: None, out: None }
    }

    /// Writes one frame (`ITEM: TIMESTEP` …), LAMMPS text layout: every value followed by a space.
    pub fn write(&mut self, w: &World) -> Result<(), String> {
        self.last = Some(w.step);
        let per_frame = self.file.to_string_lossy().contains('*');
        let mut fresh;
        let out = if per_frame {
            let name = self.file.to_string_lossy().replace('*', &w.step.to_string());
            fresh = create(Path::new(&name))?;
            &mut fresh
        } else {
            if self.out.is_none() {
                self.out = Some(create(&self.file)?);
            }
            self.out.as_mut().expect("opened above")
        };
        let d = w.domain.ok_or("dump before the box exists")?;
        let bc = |a: usize| if d.periodic[a] { "pp" } else { "ff" };
        let mut s = String::with_capacity(64 * (w.p.len() + 8));
        s.push_str(&format!(
            "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS {} {} {}\n",
            w.step,
            w.p.len(),
            bc(0),
            bc(1),
            bc(2)
        ));
        let (lo, hi) = w.output_box().unwrap_or((d.lo, d.hi));
        for a in 0..3 {
            s.push_str(&format!("{} {}\n", format::g(lo[a], 6), format::g(hi[a], 6)));
        }
        s.push_str(&format!("ITEM: ATOMS {} \n", self.names.join(" ")));
        // Rows in id order (LIGGGHTS `dump_modify sort id`), whatever the engine's spatial
        // sorting did to the particle order, so frames of one run line up row by row.
        let mut order: Vec<usize> = (0..w.p.len()).collect();
        if !w.p.id.is_sorted() {
            order.sort_unstable_by_key(|&i| w.p.id[i]);
        }
        for i in order {
            match &self.format {
                Some(pieces) => {
                    let mut k = 0;
                    for pc in pieces {
                        match pc {
                            Piece::Lit(t) => s.push_str(t),
                            Piece::Conv(spec) => {
                                let v = self.cols.get(k).map(|c| c.value(w, i)).unwrap_or(0.0);
                                s.push_str(&format::number(spec, v));
                                k += 1;
                            }
                        }
                    }
                }
                None => {
                    for c in &self.cols {
                        let v = c.value(w, i);
                        if c.is_int() {
                            s.push_str(&format!("{} ", v as i64));
                        } else {
                            s.push_str(&format::g(v, 6));
                            s.push(' ');
                        }
                    }
                }
            }
            s.push('\n');
        }
        out.write_all(s.as_bytes()).map_err(|e| format!("cannot write dump {}: {e}", self.file.display()))?;
        out.flush().map_err(|e| format!("cannot write dump {}: {e}", self.file.display()))
    }
}

/// `fix ID group ave/time Nevery Nrepeat Nfreq values… [file F]`.
#[derive(Debug)]
pub struct AveTime {
    pub name: String,
    pub nevery: u64,
    pub nrepeat: u64,
    pub nfreq: u64,
    pub values: Vec<String>,
    pub sum: Vec<f64>,
    pub irepeat: u64,
    pub nvalid: u64,
    pub last: Vec<f64>,
    pub out: Option<BufWriter<File>>,
}

impl AveTime {
    /// LAMMPS `nextvalid`: the first step of the next averaging window.
    pub fn next_valid(&self, step: u64) -> u64 {
        let mut nvalid = (step / self.nfreq) * self.nfreq + self.nfreq;
        if nvalid - self.nfreq == step && self.nrepeat == 1 {
            // No averaging window to fill: a step that is already a multiple of Nfreq is written
            // at once, at the setup of the run (LAMMPS writes step 0 of `ave/time 1 1 1`).
            return step;
        }
        let back = (self.nrepeat - 1) * self.nevery;
        nvalid = nvalid.saturating_sub(back);
        if nvalid < step {
            nvalid += self.nfreq;
        }
        nvalid
    }

    /// End of step: sample when due, write the average every Nfreq steps.
    pub fn sample(&mut self, step: u64, vals: &[f64]) -> Result<(), String> {
        if step != self.nvalid {
            return Ok(());
        }
        if self.irepeat == 0 {
            self.sum.iter_mut().for_each(|s| *s = 0.0);
        }
        for (s, v) in self.sum.iter_mut().zip(vals) {
            *s += v;
        }
        self.irepeat += 1;
        if self.irepeat < self.nrepeat {
            self.nvalid += self.nevery;
            return Ok(());
        }
        self.irepeat = 0;
        self.nvalid = step + self.nfreq - (self.nrepeat - 1) * self.nevery;
        let n = self.nrepeat as f64;
        self.last = self.sum.iter().map(|s| s / n).collect();
        if let Some(out) = self.out.as_mut() {
            let mut line = step.to_string();
            for v in &self.last {
                line.push(' ');
                line.push_str(&format::g(*v, 6));
            }
            line.push('\n');
            out.write_all(line.as_bytes()).and_then(|_| out.flush()).map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}
