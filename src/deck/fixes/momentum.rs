//! `fix ID group momentum N linear xflag yflag zflag`: every N steps, the group's centre-of-mass
//! velocity is taken out of the flagged components of its particles' velocities (LAMMPS
//! `fix momentum`, in LIGGGHTS 3.8 `src/fix_momentum.cpp`). The ParScale tutorials use it to keep
//! a periodic bed from drifting sideways (`linear 1 1 0`).
//!
//! Left out: `angular` (zeroing the angular momentum needs the group's inertia tensor; no tutorial
//! deck uses it) stops with an error. LIGGGHTS 3.8 has no `rescale` keyword (it stops with
//! "Illegal fix momentum command"), and neither has mcdem.

use super::*;

/// One `fix momentum`.
#[derive(Debug, Clone)]
pub(in crate::deck) struct Momentum {
    pub(in crate::deck) fix: String,
    every: u64,
    /// The group's mask bit.
    bit: u32,
    /// Which velocity components lose the centre-of-mass velocity.
    flags: [bool; 3],
    /// The group's total mass, taken when a run is set up (LAMMPS `FixMomentum::init`).
    mass: f64,
}

impl Deck {
    pub(in crate::deck) fn momentum(&mut self, a: &[&str]) -> R<FixKind> {
        let label = format!("fix {} momentum", a[1]);
        let n = a.get(4).ok_or_else(|| format!("{label}: expected 'momentum N linear xflag yflag zflag'"))?;
        let every = int(n)
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("{label}: N must be an integer > 0, got '{n}'"))?;
        let mut flags = None;
        let mut k = 5;
        while k < a.len() {
            match a[k] {
                "linear" => {
                    if a.len() < k + 4 {
                        return Err(format!("{label}: linear needs three flags (0 or 1)"));
                    }
                    let mut f = [false; 3];
                    for (c, v) in f.iter_mut().enumerate() {
                        *v = match a[k + 1 + c] {
                            "0" => false,
                            "1" => true,
                            other => {
                                return Err(format!("{label}: linear flag must be 0 or 1, got '{other}'"))
                            }
                        };
                    }
                    flags = Some(f);
                    k += 4;
                }
                "angular" => return Err(unsupported(&format!("{label} keyword angular"))),
                "rescale" => {
                    return Err(unsupported(&format!("{label} keyword rescale (LIGGGHTS 3.8 has none)")))
                }
                other => return Err(unsupported(&format!("{label} keyword {other}"))),
            }
        }
        let flags = flags.ok_or_else(|| format!("{label}: expected 'linear xflag yflag zflag'"))?;
        let bit = self.groups.bit(a[2], &label)?;
        // As LAMMPS: a group without particles is an error when the fix is defined.
        if !self.world.p.mask.iter().any(|m| m & bit != 0) {
            return Err(format!("{label}: group {} has no atoms", a[2]));
        }
        self.momenta.push(Momentum { fix: a[1].to_string(), every: every as u64, bit, flags, mass: 0.0 });
        Ok(FixKind::Momentum)
    }

    /// At the set-up of a run: each fix's group mass.
    pub(in crate::deck) fn momentum_setup(&mut self) {
        let p = &self.world.p;
        for m in &mut self.momenta {
            m.mass = (0..p.len()).filter(|&i| p.mask[i] & m.bit != 0).map(|i| p.mass[i]).sum();
        }
    }

    /// End of a step: the fixes due now subtract their group's centre-of-mass velocity
    /// v_cm = Σ mᵢ vᵢ / M (M from the set-up) from the flagged components of each member.
    pub(in crate::deck) fn apply_momenta(&mut self) {
        let step = self.world.step;
        let p = &mut self.world.p;
        for m in &self.momenta {
            if step % m.every != 0 || m.mass <= 0.0 {
                continue;
            }
            let mut pm = Vec3::zeros();
            for i in (0..p.len()).filter(|&i| p.mask[i] & m.bit != 0) {
                pm += p.mass[i] * p.v[i];
            }
            let vcm = pm / m.mass;
            for i in (0..p.len()).filter(|&i| p.mask[i] & m.bit != 0) {
                for c in (0..3).filter(|&c| m.flags[c]) {
                    p.v[i][c] -= vcm[c];
                }
            }
        }
    }
}
