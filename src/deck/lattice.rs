//! `lattice sc|bcc|fcc SCALE` and `create_atoms TYPE region ID` / `create_atoms TYPE box`: atoms on
//! the sites of a cubic lattice (LIGGGHTS 3.8 `src/lattice.cpp`, `src/create_atoms.cpp`, both from
//! LAMMPS).
//!
//! In every unit system but `lj` the scale is the lattice constant (m in `units si`). Only the
//! default orientation and origin are read: the keywords `origin`, `orient`, `spacing`, `a1`…`a3`
//! and `basis`, and the styles `hcp`, `diamond`, `custom` and the 2-d ones stop with an error
//! naming them.

use super::*;

/// A cubic lattice: its constant (m) and the basis sites in fractions of the unit cell.
#[derive(Debug, Clone)]
pub(super) struct Lattice {
    scale: f64,
    basis: &'static [[f64; 3]],
}

const SC: &[[f64; 3]] = &[[0.0, 0.0, 0.0]];
const BCC: &[[f64; 3]] = &[[0.0, 0.0, 0.0], [0.5, 0.5, 0.5]];
const FCC: &[[f64; 3]] = &[[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]];

/// LAMMPS `create_atoms`: on a periodic axis the creation box is this fraction of the box length
/// lower, so that a site on both periodic faces is created once.
const PERIODIC_EPSILON: f64 = 1.0e-6;

impl Lattice {
    /// The sites whose positions fall in `[lo, hi)` (after `keep`), in LAMMPS' order: unit cells
    /// by z, then y, then x, the basis sites inside each cell. Cell indices span the box in lattice
    /// units with one spare cell each side (`CreateAtoms::add_lattice`); a site is
    /// `(i + basis) · scale` — with the default orientation LAMMPS' transforms reduce to this
    /// exactly.
    pub(super) fn sites(&self, lo: Vec3, hi: Vec3, mut keep: impl FnMut(&Vec3) -> bool) -> Vec<Vec3> {
        let bound = |v: f64, up: bool| {
            let c = v / self.scale;
            // `static_cast<int>` truncates toward zero: one more cell below a negative minimum.
            let t = c.trunc() as i64;
            if up {
                t + 1
            } else {
                t - 1 - i64::from(c < 0.0)
            }
        };
        let (ilo, ihi) = (bound(lo.x, false), bound(hi.x, true));
        let (jlo, jhi) = (bound(lo.y, false), bound(hi.y, true));
        let (klo, khi) = (bound(lo.z, false), bound(hi.z, true));
        let mut out = Vec::new();
        for k in klo..=khi {
            for j in jlo..=jhi {
                for i in ilo..=ihi {
                    for b in self.basis {
                        let x = Vec3::new(
                            (i as f64 + b[0]) * self.scale,
                            (j as f64 + b[1]) * self.scale,
                            (k as f64 + b[2]) * self.scale,
                        );
                        if !keep(&x) {
                            continue;
                        }
                        if (0..3).any(|d| x[d] < lo[d] || x[d] >= hi[d]) {
                            continue;
                        }
                        out.push(x);
                    }
                }
            }
        }
        out
    }
}

impl Deck {
    /// `lattice STYLE SCALE` (`lattice none …` removes it).
    pub(super) fn lattice(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 3)?;
        let basis = match a[1] {
            "none" => {
                num(a[2])?;
                self.lattice = None;
                return Ok(());
            }
            "sc" => SC,
            "bcc" => BCC,
            "fcc" => FCC,
            other => return Err(unsupported(&format!("lattice style {other} (sc, bcc, fcc or none)"))),
        };
        let scale = num(a[2])?;
        if scale <= 0.0 {
            return Err(format!("lattice {}: scale must be > 0, got {}", a[1], a[2]));
        }
        if let Some(k) = a.get(3) {
            return Err(unsupported(&format!(
                "lattice keyword {k} (only the default orientation and origin)"
            )));
        }
        self.lattice = Some(Lattice { scale, basis });
        self.say(&format!("Lattice spacing in x,y,z = {scale} {scale} {scale}"));
        Ok(())
    }

    /// `create_atoms TYPE region ID` or `create_atoms TYPE box`: one atom (diameter 1, density 1,
    /// as LIGGGHTS' defaults) on every lattice site inside the box and, for `region`, the region.
    pub(super) fn create_atoms_lattice(&mut self, a: &[&str]) -> R<()> {
        let typ = int(a[1])?;
        if typ < 1 || typ as usize > self.ntypes {
            return Err(format!("create_atoms: atom type {typ} outside 1..{}", self.ntypes));
        }
        let (region, rest) = match a[2] {
            "box" => (None, &a[3..]),
            _ => {
                let id = a.get(3).ok_or("create_atoms region: missing region ID")?;
                let r = self.regions.get(*id).ok_or_else(|| format!("create_atoms: unknown region {id}"))?;
                (Some(r.clone()), &a[4..])
            }
        };
        match rest {
            [] | ["units", "box" | "lattice"] => {}
            [k, ..] => return Err(unsupported(&format!("create_atoms keyword {k}"))),
        }
        let lattice =
            self.lattice.clone().ok_or("create_atoms: no lattice defined (use the lattice command first)")?;
        let d = self.world.domain.ok_or("create_atoms before the simulation box exists")?;
        // The box as LIGGGHTS has it (the engine's own grows a skin beyond shrink-wrapped atoms).
        let (mut lo, mut hi) = self.world.reported_box.unwrap_or((d.lo, d.hi));
        for k in (0..3).filter(|&k| self.periodic[k]) {
            let eps = (hi[k] - lo[k]) * PERIODIC_EPSILON;
            lo[k] -= eps;
            hi[k] -= 2.0 * eps;
        }
        let sites = lattice.sites(lo, hi, |x| region.as_ref().is_none_or(|r| r.holds(x, 0.0)));
        self.groups.particles_added(None)?;
        let mut id = self.world.p.id.iter().copied().max().unwrap_or(0);
        for x in &sites {
            id += 1;
            self.world.p.push(id, typ as usize - 1, *x, 1.0, 1.0);
        }
        self.say(&format!("Created {} atoms", sites.len()));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn site_counts_and_order() {
        let sc = Lattice { scale: 0.5, basis: SC };
        let s = sc.sites(Vec3::zeros(), Vec3::new(1.0, 1.0, 1.0), |_| true);
        // Half-open box: sites at 0 and 0.5 on each axis.
        assert_eq!(s.len(), 8);
        assert_eq!(s[1], Vec3::new(0.5, 0.0, 0.0), "x runs fastest");
        assert_eq!(s[2], Vec3::new(0.0, 0.5, 0.0));
        let fcc = Lattice { scale: 1.0, basis: FCC };
        assert_eq!(fcc.sites(Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 1.0, 1.0), |_| true).len(), 32);
        let bcc = Lattice { scale: 1.0, basis: BCC };
        assert_eq!(bcc.sites(Vec3::zeros(), Vec3::new(2.0, 2.0, 2.0), |_| true).len(), 16);
    }
}
