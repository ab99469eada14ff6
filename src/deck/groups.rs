//! `group ID region REG`: static groups, and what a fix, compute or dump may do with one.
//!
//! Membership is a bit per group in each particle's mask (LAMMPS `atom->mask`): `group` sets it
//! for the particles in the region, an insertion fix sets its group's bit on the particles it adds
//! (LIGGGHTS adds inserted atoms to the inserting fix's group), and restart files keep it.
//! `fix nve/sphere` and `fix momentum` act on the members of any group. Everything else
//! (forces, outputs, other fixes) treats every particle alike, so for those a group other than
//! `all` is accepted only while it holds every particle: then the deck means the same as with
//! `all`. A group that would make one of them act on a proper subset stops the deck with an error
//! naming it, never a run where the fix silently acts on all particles.

use super::*;

/// One group: its name, its mask bit, whether it holds every particle, and who acts on it as if
/// on every particle (for messages).
#[derive(Debug, Clone)]
struct Group {
    name: String,
    bit: u32,
    holds_all: bool,
    used_by: Option<String>,
}

/// LAMMPS allows 32 groups, `all` included: one bit each of the mask.
const MAX_GROUPS: usize = 32;

#[derive(Debug, Clone, Default)]
pub(super) struct Groups {
    list: Vec<Group>,
}

impl Groups {
    /// Particles are added; those of an insertion fix of group `into` join it. Every other group
    /// no longer holds every particle, which is an error if something acts on it.
    pub(super) fn particles_added(&mut self, into: Option<&str>) -> R<()> {
        for g in &mut self.list {
            if Some(g.name.as_str()) == into {
                continue;
            }
            if let Some(user) = &g.used_by {
                return Err(unsupported(&format!(
                    "{user} acts on group {}, which would no longer hold every particle once these are added (fixes, computes and dumps of a subset)",
                    g.name
                )));
            }
            g.holds_all = false;
        }
        Ok(())
    }

    /// Checks that `user` (e.g. "fix integr nve/sphere") may act on `group`, and records it.
    pub(super) fn act_on(&mut self, group: &str, user: &str) -> R<()> {
        if group == "all" {
            return Ok(());
        }
        let g = self
            .list
            .iter_mut()
            .find(|g| g.name == group)
            .ok_or_else(|| format!("{user}: no group {group}"))?;
        if !g.holds_all {
            return Err(unsupported(&format!(
                "{user} on group {group}, which does not hold every particle (fixes, computes and dumps of a subset)"
            )));
        }
        g.used_by.get_or_insert_with(|| user.to_string());
        Ok(())
    }

    /// The mask bit of `group` (`all`: [`GROUP_ALL`]), for a fix that acts on its members only.
    pub(super) fn bit(&self, group: &str, user: &str) -> R<u32> {
        if group == "all" {
            return Ok(GROUP_ALL);
        }
        self.list
            .iter()
            .find(|g| g.name == group)
            .map(|g| g.bit)
            .ok_or_else(|| format!("{user}: no group {group}"))
    }

    /// The group names in bit order (bit 1 first), for a restart file.
    pub(super) fn names(&self) -> Vec<String> {
        self.list.iter().map(|g| g.name.clone()).collect()
    }

    /// The groups of a restart file (names in bit order) over the particles' masks read with it.
    pub(super) fn restore(&mut self, names: &[String], mask: &[u32]) -> R<()> {
        if names.len() + 1 > MAX_GROUPS {
            return Err(format!("{} groups, more than the {MAX_GROUPS} LAMMPS allows", names.len() + 1));
        }
        self.list = names
            .iter()
            .enumerate()
            .map(|(k, n)| {
                let bit = 1u32 << (k + 1);
                Group { name: n.clone(), bit, holds_all: mask.iter().all(|m| m & bit != 0), used_by: None }
            })
            .collect();
        Ok(())
    }

    /// An insertion fix names `group` for its particles: it must exist.
    pub(super) fn check_exists(&self, group: &str, user: &str) -> R<()> {
        if group == "all" || self.list.iter().any(|g| g.name == group) {
            Ok(())
        } else {
            Err(format!("{user}: no group {group}"))
        }
    }
}

impl Deck {
    /// `group ID region REG`: the particles whose centre lies in the region now (surface included).
    /// As in LAMMPS, naming a group that exists adds these particles to it.
    pub(super) fn group(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 3 {
            return Err("group: expected 'group ID region REGION'".into());
        }
        let name = a[1];
        if name == "all" {
            return Err("group: 'all' cannot be redefined".into());
        }
        if a[2] != "region" || a.len() != 4 {
            return Err(unsupported(&format!("group style {} (only 'group ID region REGION')", a[2])));
        }
        // As LAMMPS ("Group command before simulation box is defined"): a restart read later
        // brings its own groups.
        if self.world.domain.is_none() {
            return Err(format!("group {name}: before the simulation box exists"));
        }
        let region =
            self.regions.get(a[3]).ok_or_else(|| format!("group {name}: unknown region {}", a[3]))?;
        let k = match self.groups.list.iter().position(|g| g.name == name) {
            Some(k) => k,
            None => {
                if self.groups.list.len() + 1 >= MAX_GROUPS {
                    return Err(format!(
                        "group {name}: too many groups (LAMMPS allows {MAX_GROUPS}, all included)"
                    ));
                }
                let bit = 1u32 << (self.groups.list.len() + 1);
                self.groups.list.push(Group { name: name.to_string(), bit, holds_all: false, used_by: None });
                self.groups.list.len() - 1
            }
        };
        let bit = self.groups.list[k].bit;
        let p = &mut self.world.p;
        for i in 0..p.len() {
            if region.holds(&p.x[i], 0.0) {
                p.mask[i] |= bit;
            }
        }
        let (count, n) = (p.mask.iter().filter(|&&m| m & bit != 0).count(), p.len());
        // Particles an insertion fix adds later go to that fix's group, not to this one.
        let holds_all = !self.inserts_later() && count == n;
        let g = &mut self.groups.list[k];
        if g.used_by.is_some() && !holds_all {
            return Err(unsupported(&format!(
                "group {name}: {} acts on it and it no longer holds every particle",
                g.used_by.as_deref().unwrap_or("")
            )));
        }
        g.holds_all = holds_all;
        self.say(&format!("{count} atoms in group {name}"));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(names: &[(&str, bool)]) -> Groups {
        Groups {
            list: names
                .iter()
                .enumerate()
                .map(|(k, &(n, h))| Group { name: n.into(), bit: 2 << k, holds_all: h, used_by: None })
                .collect(),
        }
    }

    #[test]
    fn a_group_holding_every_particle_may_be_acted_on_until_others_are_added() {
        let mut g = with(&[("ins", true), ("other", true)]);
        // An insertion into `ins`: `ins` still holds all, `other` no longer.
        g.particles_added(Some("ins")).unwrap();
        g.act_on("ins", "fix integr nve/sphere").unwrap();
        let e = g.act_on("other", "fix integr nve/sphere").unwrap_err();
        assert!(e.contains("does not hold every particle"), "{e}");
        // Particles added outside `ins` (read_data) after a fix acts on it: refused, naming the fix.
        let e = g.particles_added(None).unwrap_err();
        assert!(e.contains("fix integr nve/sphere acts on group ins"), "{e}");
        assert!(g.act_on("nope", "fix x").unwrap_err().contains("no group nope"));
        g.act_on("all", "fix x").unwrap();
    }
}
