//! `reset_timestep N`: the step counter jumps to N (LIGGGHTS 3.8 `src/reset_timestep.cpp`,
//! `Update::reset_timestep`). What is scheduled by step moves with it, so that it still comes the
//! same number of steps ahead: the next insertion of each insertion fix (LIGGGHTS' `FixInsert`
//! shifts its next insertion step the same way), the release steps of streamed particles still in
//! flight, and the engine's next spatial sort.
//!
//! Left out (stop with an error naming them): a reset while `fix ave/time` or
//! `fix check/timestep/gran` is defined, or after a dump is defined — their output schedules are
//! not moved.

use super::*;

impl Deck {
    pub(in crate::deck) fn reset_timestep(&mut self, a: &[&str]) -> R<()> {
        if a.len() != 2 {
            return Err("reset_timestep: expected 'reset_timestep N' (keywords are not read)".into());
        }
        let n = int(a[1])?;
        if n < 0 {
            return Err(format!("reset_timestep: N must be >= 0, got {n}"));
        }
        let n = n as u64;
        if self.aves.iter().any(Option::is_some) || self.checks.iter().any(Option::is_some) {
            return Err(unsupported(
                "reset_timestep while fix ave/time or fix check/timestep/gran is defined (their schedules are not moved)",
            ));
        }
        if !(self.dumps.is_empty() && self.local_dumps.is_empty() && self.vtk_dumps.is_empty()) {
            return Err(unsupported("reset_timestep after a dump is defined (dump schedules are not moved)"));
        }
        let old = self.world.step;
        let shift = |s: u64| (s + n).saturating_sub(old);
        self.insertion.shift_steps(&shift);
        self.world.reset_step(n);
        Ok(())
    }
}
