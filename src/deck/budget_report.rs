//! The run summary's account of the multi-contact accuracy budget (`mcAccuracy`).

use super::Deck;

impl Deck {
    /// The Loop-time line's budget clause: the largest estimated error relative to EPS, the
    /// fraction of particle-steps recomputed, and the shadow check's measured error next to the
    /// bound when `mcAccuracyCheck` ran. Adds the counters to the run summary.
    pub(super) fn budget_summary(&mut self, nsteps: u64, np: usize) -> String {
        let st = self.world.take_budget_stats();
        let eps = self.world.mc_accuracy;
        let all = (nsteps as f64 * np as f64).max(1.0);
        let mut text = format!(
            ", multi-contact accuracy {eps:e}: recomputed in {:.2} % of the particle-steps with two or more contacts ({:.2} % of all), largest estimated error {:.3} of the budget",
            100.0 * st.recomputed as f64 / (st.multi as f64).max(1.0),
            100.0 * st.recomputed as f64 / all,
            st.worst_bound
        );
        let exact: u64 = st.why.iter().sum();
        if exact > 0 {
            let parts: Vec<String> = crate::engine::BUDGET_WHY
                .iter()
                .zip(st.why)
                .filter(|(_, c)| *c > 0)
                .map(|(name, c)| format!("{name} {:.1} %", 100.0 * c as f64 / exact as f64))
                .collect();
            text += &format!(" (exact evaluations by reason: {})", parts.join(", "));
        }
        if st.checks > 0 {
            text += &format!(
                ", accuracy check ({} checks, every {} steps): measured error {:.3e}, bound {:.3e} (of the particle's scale)",
                st.checks, self.world.mc_accuracy_check, st.worst_measured, st.worst_checked_bound
            );
        }
        let s = &mut self.summary.mc_budget;
        s.multi += st.multi;
        s.recomputed += st.recomputed;
        s.checks += st.checks;
        s.worst_bound = s.worst_bound.max(st.worst_bound);
        s.worst_measured = s.worst_measured.max(st.worst_measured);
        s.worst_checked_bound = s.worst_checked_bound.max(st.worst_checked_bound);
        for (t, c) in s.why.iter_mut().zip(st.why) {
            *t += c;
        }
        text
    }
}
