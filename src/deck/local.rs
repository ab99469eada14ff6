//! `compute ID all pair/gran/local KEYWORDS…` and `dump ID all local N FILE c_ID[k]…`: one row per
//! particle–particle contact that carries a force, with LIGGGHTS's columns per keyword, so that the
//! same post-processing reads both engines' files.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use super::format;
use super::output::create;
use crate::engine::{PairContact, World};

/// A keyword of `compute pair/gran/local` and the columns it adds. The declaration order is the
/// order LIGGGHTS 3.8 writes the columns in, whatever the order of the keywords in the deck
/// (`compute_pair_gran_local.cpp` sets one flag per keyword and writes the flagged groups in a
/// fixed order), so the keywords are sorted by it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Quantity {
    /// x_i, x_j (6).
    Pos,
    /// v_i, v_j (6).
    Vel,
    /// id_i, id_j, 1 if the contact crosses a periodic boundary (3).
    Id,
    /// Contact force on i (3).
    Force,
    /// Its component along the centre line (3).
    ForceNormal,
    /// The rest (3).
    ForceTangential,
    /// Contact torque on i (3).
    Torque,
    /// The pair's contact history as LIGGGHTS lists it: under `model hertz tangential history`
    /// the tangential spring (3), under `no_history` nothing (0).
    History,
    /// Area of the intersection circle of the two original spheres (1).
    ContactArea,
    /// Geometric overlap r_i + r_j − |x_i − x_j| with the original radii (1).
    Delta,
}

impl Quantity {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "pos" => Quantity::Pos,
            "vel" => Quantity::Vel,
            "id" => Quantity::Id,
            "force" => Quantity::Force,
            "force_normal" => Quantity::ForceNormal,
            "force_tangential" => Quantity::ForceTangential,
            "torque" => Quantity::Torque,
            "contactArea" => Quantity::ContactArea,
            "delta" => Quantity::Delta,
            "history" => Quantity::History,
            _ => return None,
        })
    }
}

/// `compute ID all pair/gran/local KEYWORDS…`.
#[derive(Debug, Clone, PartialEq)]
pub struct PairLocal {
    quantities: Vec<Quantity>,
    /// Columns of `history` for the run's contact model (set when a run starts).
    history: usize,
}

impl PairLocal {
    /// From the keywords after the style; none gives LIGGGHTS's default set (`pos vel id force
    /// torque history contactArea`). Keywords LIGGGHTS 3.8 does not have, or that need a physics
    /// mcdem does not model, are named with the reason.
    pub fn parse(keywords: &[&str]) -> Result<Self, String> {
        use Quantity::*;
        let mut quantities = if keywords.is_empty() {
            vec![Pos, Vel, Id, Force, Torque, History, ContactArea]
        } else {
            keywords
                .iter()
                .map(|k| {
                    Quantity::parse(k).ok_or_else(|| match *k {
                        "heatFlux" => "compute pair/gran/local keyword heatFlux: out of scope: heat transfer \
                                       (it reads fix heat/gran/conduction)"
                            .to_string(),
                        "contactPoint" | "ms_id" => format!(
                            "compute pair/gran/local keyword {k} is not one of LIGGGHTS 3.8 (which stops at it \
                             with 'Invalid keyword'; later LIGGGHTS versions added it)"
                        ),
                        _ => format!(
                            "unsupported compute pair/gran/local keyword {k} (pos vel id force force_normal \
                             force_tangential torque history contactArea delta)"
                        ),
                    })
                })
                .collect::<Result<Vec<_>, _>>()?
        };
        // LIGGGHTS writes each flagged group once, in its own order.
        quantities.sort_unstable();
        quantities.dedup();
        Ok(PairLocal { quantities, history: 3 })
    }

    /// Values of every touching pair, one row each.
    fn rows(&self, contacts: &[PairContact], w: &World) -> Vec<Vec<f64>> {
        let p = &w.p;
        contacts
            .iter()
            .map(|c| {
                let mut row = Vec::with_capacity(32);
                let r = c.branch.norm();
                let n = -c.branch / r; // from i towards j, as LIGGGHTS
                let fnormal = n * c.force.dot(&n);
                let (ri, rj) = (p.radius[c.i], p.radius[c.j]);
                for q in &self.quantities {
                    match q {
                        Quantity::Pos => row.extend(p.x[c.i].iter().chain(p.x[c.j].iter())),
                        Quantity::Vel => row.extend(p.v[c.i].iter().chain(p.v[c.j].iter())),
                        Quantity::Id => {
                            row.extend([p.id[c.i] as f64, p.id[c.j] as f64, f64::from(u8::from(c.periodic))])
                        }
                        Quantity::Force => row.extend(c.force.iter()),
                        Quantity::ForceNormal => row.extend(fnormal.iter()),
                        Quantity::ForceTangential => row.extend((c.force - fnormal).iter()),
                        Quantity::Torque => row.extend(c.torque.iter()),
                        Quantity::ContactArea => row.push(
                            -std::f64::consts::FRAC_PI_4
                                * ((r - ri - rj) * (r + ri - rj) * (r - ri + rj) * (r + ri + rj))
                                / (r * r),
                        ),
                        Quantity::Delta => row.push(ri + rj - r),
                        Quantity::History => row.extend(c.shear.iter().take(self.history)),
                    }
                }
                row
            })
            .collect()
    }
}

/// `dump ID all local N FILE c_ID[k]…`.
#[derive(Debug)]
pub struct LocalDump {
    pub name: String,
    pub every: u64,
    file: PathBuf,
    /// Column labels as written in the deck, and the (compute, 1-based column) they read.
    labels: Vec<String>,
    refs: Vec<(String, usize)>,
    pub last: Option<u64>,
    out: Option<BufWriter<File>>,
}

impl LocalDump {
    /// `args`: the deck words after `dump ID all local`.
    pub fn parse(name: &str, args: &[&str]) -> Result<Self, String> {
        if args.len() < 3 {
            return Err("dump local: expected N FILE c_ID[k]…".into());
        }
        let every: i64 =
            args[0].parse().map_err(|_| format!("dump local: N must be an integer, got {}", args[0]))?;
        if every <= 0 {
            return Err("dump local: N must be > 0".into());
        }
        let mut refs = Vec::new();
        for c in &args[2..] {
            let inner =
                c.strip_prefix("c_").ok_or_else(|| format!("unsupported dump local column {c} (c_ID[k])"))?;
            let (id, k) = inner
                .strip_suffix(']')
                .and_then(|s| s.split_once('['))
                .ok_or_else(|| format!("dump local column {c}: expected c_ID[k]"))?;
            let k: usize = k.parse().map_err(|_| format!("dump local column {c}: bad index"))?;
            if k == 0 {
                return Err(format!("dump local column {c}: indices start at 1"));
            }
            refs.push((id.to_string(), k));
        }
        Ok(LocalDump {
            name: name.into(),
            every: every as u64,
            file: PathBuf::from(args[1]),
            labels: args[2..].iter().map(|s| s.to_string()).collect(),
            refs,
            last: None,
            out: None,
        })
    }

    /// Checks that every referenced compute is a pair/gran/local with enough columns.
    pub fn check(&self, computes: &HashMap<String, PairLocal>) -> Result<(), String> {
        for (id, k) in &self.refs {
            let c = computes
                .get(id)
                .ok_or_else(|| format!("dump {}: no compute pair/gran/local {id}", self.name))?;
            let width: usize = c.rows_width();
            if *k > width {
                return Err(format!("dump {}: c_{id}[{k}] beyond its {width} columns", self.name));
            }
        }
        Ok(())
    }

    /// Writes one frame: `ITEM: NUMBER OF ENTRIES`, `ITEM: ENTRIES …`, one line per contact.
    pub fn write(&mut self, w: &mut World, computes: &HashMap<String, PairLocal>) -> Result<(), String> {
        self.last = Some(w.step);
        self.check(computes)?;
        let contacts = w.touching_pairs().map_err(|e| e.to_string())?;
        let w = &*w;
        let mut tables: HashMap<&str, Vec<Vec<f64>>> = HashMap::new();
        for (id, _) in &self.refs {
            if !tables.contains_key(id.as_str()) {
                tables.insert(id, computes[id].rows(&contacts, w));
            }
        }
        let n = tables.values().next().map_or(0, Vec::len);
        let d = w.domain.ok_or("dump before the box exists")?;
        let bc = |a: usize| if d.periodic[a] { "pp" } else { "ff" };
        let mut s = format!(
            "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ENTRIES\n{n}\nITEM: BOX BOUNDS {} {} {}\n",
            w.step,
            bc(0),
            bc(1),
            bc(2)
        );
        let (lo, hi) = w.output_box().unwrap_or((d.lo, d.hi));
        for a in 0..3 {
            s.push_str(&format!("{} {}\n", format::g(lo[a], 6), format::g(hi[a], 6)));
        }
        s.push_str(&format!("ITEM: ENTRIES {} \n", self.labels.join(" ")));
        // One line per contact: every referenced compute lists the same contacts in the same order.
        let columns: Vec<(&Vec<Vec<f64>>, usize)> =
            self.refs.iter().map(|(id, k)| (&tables[id.as_str()], k - 1)).collect();
        for row in 0..n {
            for (table, k) in &columns {
                s.push_str(&format::g(table[row][*k], 6));
                s.push(' ');
            }
            s.push('\n');
        }
        if self.out.is_none() {
            self.out = Some(create(&self.file)?);
        }
        let out = self.out.as_mut().expect("opened above");
        out.write_all(s.as_bytes())
            .and_then(|_| out.flush())
            .map_err(|e| format!("cannot write dump {}: {e}", self.file.display()))
    }
}

impl PairLocal {
    /// Sets the columns of `history` for the run's model: `Some(n)`, or `None` where the record
    /// is not one this reader writes (an error if the compute lists `history`).
    pub fn set_history(&mut self, columns: Option<usize>) -> Result<(), String> {
        match columns {
            Some(n) => self.history = n,
            None if self.quantities.contains(&Quantity::History) => {
                return Err("unsupported compute pair/gran/local keyword history with a multi-contact model (its contact record is the plugin's own layout; list the other keywords: the default set, with no keyword, includes history)".into())
            }
            None => {}
        }
        Ok(())
    }

    fn rows_width(&self) -> usize {
        self.quantities
            .iter()
            .map(|q| match q {
                Quantity::Pos | Quantity::Vel => 6,
                Quantity::Id
                | Quantity::Force
                | Quantity::ForceNormal
                | Quantity::ForceTangential
                | Quantity::Torque => 3,
                Quantity::ContactArea | Quantity::Delta => 1,
                Quantity::History => self.history,
            })
            .sum()
    }
}
