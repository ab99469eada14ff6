//! `fix ID group adapt N atom diameter v_NAME [reset yes|no] [scale yes|no]`: particle growth or
//! shrinkage, as LIGGGHTS 3.8 `src/fix_adapt.cpp` does it for granular atoms:
//!
//! - the variable is atom-style (one diameter per particle) or equal-style (one for all);
//! - it is applied at the set-up of every run (`setup_pre_force`) and then at every step that is
//!   a multiple of N (`pre_force`: after the neighbour check, before the forces); N = 0: only at
//!   set-ups;
//! - each particle's mass is rescaled to keep its density (`Particles::set_diameter_keep_density`);
//! - `reset` and `scale` act only on pair and kspace parameters in LIGGGHTS 3.8, so for
//!   `atom diameter` they change nothing: read and checked, with no effect here either.
//!
//! The `pair`, `kspace` and `atom charge` forms stop with an error naming them.

use super::*;

impl Deck {
    pub(super) fn fix_adapt(&mut self, a: &[&str]) -> R<FixKind> {
        let id = a[1];
        let usage =
            format!("fix {id} adapt: expected 'adapt N atom diameter v_NAME [reset yes|no] [scale yes|no]'");
        if a.len() < 8 {
            return Err(usage);
        }
        let every = int(a[4]).map_err(|e| format!("fix {id} adapt: N: {e}"))?;
        if every < 0 {
            return Err(format!("fix {id} adapt: N must be >= 0, got {every}"));
        }
        match (a[5], a[6]) {
            ("atom", "diameter") => {}
            ("atom", "charge") => {
                return Err(unsupported(&format!(
                    "fix {id} adapt atom charge (granular particles carry no charge)"
                )))
            }
            ("pair", _) | ("kspace", _) => {
                return Err(unsupported(&format!("fix {id} adapt {} (only atom diameter)", a[5])))
            }
            _ => return Err(usage),
        }
        let var = a[7]
            .strip_prefix("v_")
            .filter(|v| !v.is_empty())
            .ok_or_else(|| format!("fix {id} adapt: expected v_NAME after 'atom diameter', got {}", a[7]))?;
        let mut k = 8;
        while k < a.len() {
            match a[k] {
                "reset" | "scale" => match a.get(k + 1) {
                    Some(&"yes") | Some(&"no") => k += 2,
                    other => {
                        return Err(format!(
                            "fix {id} adapt {}: expected yes or no, got {}",
                            a[k],
                            other.unwrap_or(&"(nothing)")
                        ))
                    }
                },
                "atom" | "pair" | "kspace" => {
                    return Err(unsupported(&format!(
                        "fix {id} adapt with more than one attribute (only one atom diameter)"
                    )))
                }
                other => return Err(format!("fix {id} adapt: unknown keyword {other}")),
            }
        }
        Ok(FixKind::Adapt { every: every as u64, var: var.to_string() })
    }

    /// Applies the `fix adapt`s due now: all of them at a run's set-up (`setup`), else those whose
    /// N divides the step. Returns whether any radius changed. A diameter that is not finite and
    /// positive stops the run, naming the particle.
    pub(in crate::deck) fn adapt(&mut self, setup: bool) -> R<bool> {
        let step = self.world.step;
        let due: Vec<(String, String)> = self
            .fixes
            .iter()
            .filter_map(|(id, k)| match k {
                FixKind::Adapt { every, var } if setup || (*every > 0 && step % every == 0) => {
                    Some((id.clone(), var.clone()))
                }
                _ => None,
            })
            .collect();
        for (id, var) in &due {
            let user = format!("fix {id} adapt");
            let d = self.per_atom_values(var, &user)?;
            if let Some(i) = d.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(format!(
                    "{user}: variable {var} gives diameter {} for particle {} at step {step}: it must be finite and > 0",
                    d[i], self.world.p.id[i]
                ));
            }
            for (i, di) in d.into_iter().enumerate() {
                self.world.p.set_diameter_keep_density(i, di);
            }
        }
        Ok(!due.is_empty())
    }
}
