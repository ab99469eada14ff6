//! `group ID region REG`: static groups, and what a fix, compute or dump may do with one.
//!
//! The engine integrates, forces and outputs every particle alike, so a group other than `all` is
//! accepted only while it holds every particle: then the deck means the same as with `all`. That
//! is the tutorials' use, `group nve_group region reg` over the whole box followed by an insertion
//! fix of that group (whose particles join it, as LIGGGHTS adds inserted atoms to the inserting
//! fix's group) and `fix nve/sphere` of it. A group that would act on a proper subset stops the
//! deck with an error naming it, never a run where the fix silently acts on all particles.

use super::*;

/// One group: its name, whether it holds every particle, and who acts on it (for messages).
#[derive(Debug, Clone)]
struct Group {
    name: String,
    holds_all: bool,
    used_by: Option<String>,
}

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
    /// `group ID region REG`: the particles whose centre lies in the region now.
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
        let region =
            self.regions.get(a[3]).ok_or_else(|| format!("group {name}: unknown region {}", a[3]))?;
        if self.groups.list.iter().any(|g| g.name == name) {
            return Err(unsupported(&format!("redefining group {name}")));
        }
        // Particles an insertion fix adds later go to that fix's group, not to this one.
        let p = &self.world.p;
        let holds_all = !self.inserts_later() && (0..p.len()).all(|i| region.holds(&p.x[i], 0.0));
        self.groups.list.push(Group { name: name.to_string(), holds_all, used_by: None });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(names: &[(&str, bool)]) -> Groups {
        Groups {
            list: names.iter().map(|&(n, h)| Group { name: n.into(), holds_all: h, used_by: None }).collect(),
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
