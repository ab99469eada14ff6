//! `run N [upto]`: set-up, the step loop with its end-of-step outputs, and the closing summary.

use super::*;

impl Deck {
    pub(super) fn end_of_step_outputs(&mut self, last: bool) -> R<Option<String>> {
        let step = self.world.step;
        self.check_timesteps();
        self.sample_ave_times()?;
        self.write_dumps()?;
        let thermo_due = last || (self.thermo_every > 0 && step % self.thermo_every == 0);
        if thermo_due {
            return Ok(Some(self.thermo_line()?));
        }
        Ok(None)
    }

    pub(super) fn sample_ave_times(&mut self) -> R<()> {
        let step = self.world.step;
        for k in 0..self.aves.len() {
            let Some(at) = self.aves[k].as_ref() else { continue };
            if at.nvalid != step {
                continue;
            }
            // Reused buffer: sampling happens every step in typical decks.
            let mut vals = std::mem::take(&mut self.scratch);
            vals.clear();
            for v in &at.values {
                vals.push(self.value_of(v, 0)?);
            }
            if let Some(at) = self.aves[k].as_mut() {
                at.sample(step, &vals)?;
            }
            self.scratch = vals;
        }
        Ok(())
    }

    /// `boundary m`/`s`: widens the box on shrink-wrapped axes so that every particle, with its
    /// radius and the neighbour skin as margin, stays inside. The engine checks for lost particles
    /// at list rebuilds, which come before a particle moves a skin; so a box kept a skin beyond
    /// every particle after each step never loses one. It only grows, so it never falls below the
    /// created box (LIGGGHTS' `m` minimum).
    ///
    /// The outputs report LIGGGHTS' box instead (LAMMPS `Domain::reset_box`): on a shrink-wrapped
    /// axis the extent of the particle centres widened by 1e-4 of the created length, and for `m`
    /// never inside the created box. Forces do not depend on either.
    fn shrink_wrap(&mut self) {
        if !self.shrink.iter().any(|&s| s) {
            return;
        }
        let skin = self.world.skin;
        let p = &self.world.p;
        let Some(d) = self.world.domain.as_mut() else { return };
        let (lo0, hi0) = *self.box0.get_or_insert((d.lo, d.hi));
        let (mut lo, mut hi) = (d.lo, d.hi);
        for a in (0..3).filter(|&a| self.shrink[a]) {
            // Four independent running minima and maxima per quantity, merged at the end: the
            // same values (min and max do not depend on the order), without one long chain of
            // dependent compares through every particle at every step.
            const L: usize = 4;
            let (mut cmin, mut cmax) = ([f64::INFINITY; L], [f64::NEG_INFINITY; L]);
            let (mut dlo, mut dhi) = ([d.lo[a]; L], [d.hi[a]; L]);
            let mut take = |l: usize, x: &Vec3, r: f64| {
                let (xa, m) = (x[a], r + skin);
                dlo[l] = dlo[l].min(xa - m);
                dhi[l] = dhi[l].max(xa + m);
                cmin[l] = cmin[l].min(xa);
                cmax[l] = cmax[l].max(xa);
            };
            let (xs, rs) = (p.x.chunks_exact(L), p.radius.chunks_exact(L));
            let (xt, rt) = (xs.remainder(), rs.remainder());
            for (x, r) in xs.zip(rs) {
                for l in 0..L {
                    take(l, &x[l], r[l]);
                }
            }
            for (l, (x, r)) in xt.iter().zip(rt).enumerate() {
                take(l, x, *r);
            }
            let lo_of = |v: [f64; L]| v.into_iter().fold(f64::INFINITY, f64::min);
            let hi_of = |v: [f64; L]| v.into_iter().fold(f64::NEG_INFINITY, f64::max);
            (d.lo[a], d.hi[a]) = (lo_of(dlo), hi_of(dhi));
            let (cmin, cmax) = (lo_of(cmin), hi_of(cmax));
            let small = 1e-4 * (hi0[a] - lo0[a]);
            (lo[a], hi[a]) = match (p.len(), self.shrink_min[a]) {
                (0, _) => (lo0[a], hi0[a]),
                (_, true) => ((cmin - small).min(lo0[a]), (cmax + small).max(hi0[a])),
                (_, false) => (cmin - small, cmax + small),
            };
        }
        self.world.reported_box = Some((lo, hi));
    }

    /// The box, the model and the engine set up for the particles there are now (at the start of
    /// a run, and after an insertion inside one).
    fn set_up_world(&mut self) -> R<()> {
        self.shrink_wrap();
        self.prepare()?;
        for wmsg in self.world.setup()? {
            self.warn(&wmsg);
        }
        Ok(())
    }

    /// An engine stop as the deck's error (kept in `instability` for callers that tell them apart).
    fn engine_stop(&mut self, r: Result<(), StepError>) -> R<()> {
        r.map_err(|e| {
            let mut m = e.to_string();
            let policy = &self.lost_policy;
            if policy != "error" && m.contains("lost particle") {
                m += &format!(" (thermo_modify lost {policy} asks to delete it; mcdem does not delete particles, so the run stops)");
            }
            self.instability = Some(e);
            m
        })
    }

    pub(super) fn run(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 2 {
            return Err("run: missing N".into());
        }
        let n = int(a[1])?;
        let upto = match a.get(2) {
            None => false,
            Some(&"upto") if a.len() == 3 => true,
            Some(other) => return Err(unsupported(&format!("run keyword {other}"))),
        };
        if n < 0 {
            return Err("run: N must be >= 0".into());
        }
        let nsteps = if upto {
            (n as u64).checked_sub(self.world.step).ok_or("run upto: target step already passed")?
        } else {
            n as u64
        };
        self.insert_pending()?;
        // LIGGGHTS applies `fix adapt` in the set-up of every run, before the set-up forces.
        self.adapt(true)?;
        self.set_up_world()?;
        self.momentum_setup();
        // As in LIGGGHTS, the setup of a run is an end of step for the averaging fixes.
        self.sample_ave_times()?;
        self.say("Setting up run ...");
        let header = self.thermo_header();
        self.say(&header);
        let history =
            self.pair.as_ref().and_then(|p| match (p.is_mc_advanced() || p.surface_mc, p.tangential) {
                (true, _) => None,
                (false, Tangential::History) => Some(3),
                (false, Tangential::NoHistory) => Some(0),
            });
        for c in self.pair_locals.values_mut() {
            c.set_history(history)?;
        }
        for d in &self.local_dumps {
            d.check(&self.pair_locals)?;
        }
        self.write_dumps()?;
        let first = self.thermo_line()?;
        self.say(&first);
        let bar = if self.progress && !self.quiet && std::io::stdout().is_terminal() && nsteps >= 1000 {
            let pb = indicatif::ProgressBar::new(nsteps);
            pb.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps {per_sec} eta {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            Some(pb)
        } else {
            None
        };
        let t0 = Instant::now();
        let end = self.world.step + nsteps;
        let builds0 = self.world.builds;
        let updates0 = self.world.mc_influence_updates();
        let passes0 = self.world.mc_updates;
        let threaded0 = self.world.threaded_passes();
        let kernel0 = (self.world.mc_kernel_contacts, self.world.mc_kernel_fallbacks);
        // The budget's counters from here on (the set-up pass is not a step of the run).
        self.world.take_budget_stats();
        while self.world.step < end {
            // An `insert_every N` insertion: the new particles enter as at the start of a run
            // (box, lists and forces set up again), without a new thermo header.
            if self.step_inserts() && self.insert_due()? {
                self.set_up_world()?;
            }
            // The step in two halves: `fix adapt` changes radii between the neighbour check and
            // the forces (LAMMPS `pre_force`).
            let r = self.world.step_to_pre_force();
            self.engine_stop(r)?;
            if self.adapt(false)? {
                let r = self.world.radii_changed();
                self.engine_stop(r)?;
            }
            let r = self.world.step_from_pre_force();
            self.engine_stop(r)?;
            self.apply_momenta();
            self.stream_release();
            self.shrink_wrap();
            let last = self.world.step == end;
            if let Some(line) = self.end_of_step_outputs(last)? {
                match &bar {
                    Some(pb) => pb.println(&line),
                    None if self.quiet => {}
                    None => println!("{line}"),
                }
                self.logln(&line);
            }
            if let Some(pb) = &bar {
                if self.world.step % 100 == 0 {
                    pb.set_position(nsteps - (end - self.world.step));
                }
            }
        }
        if let Some(pb) = bar {
            pb.finish_and_clear();
        }
        let secs = t0.elapsed().as_secs_f64();
        let np = self.world.p.len();
        self.summary.steps += nsteps;
        self.summary.particle_steps += (nsteps as f64) * np as f64;
        self.summary.loop_seconds += secs;
        self.summary.neighbor_builds += self.world.builds - builds0;
        let rate = if secs > 0.0 { nsteps as f64 * np as f64 / secs } else { 0.0 };
        // What the multi-contact approximations did: how often a particle's Eq. 2 geometry was
        // recomputed, and in how many steps the full pass ran.
        let mut approx = String::new();
        if self.world.mc_geometry_tolerance > 0.0 {
            let updates = self.world.mc_influence_updates() - updates0;
            approx += &format!(
                ", multi-contact geometry tolerance {:e}: recomputed in {:.2} % of particle-steps",
                self.world.mc_geometry_tolerance,
                100.0 * updates as f64 / (nsteps as f64 * np as f64).max(1.0)
            );
        }
        if self.world.mc_every > 1 {
            approx += &format!(
                ", multi-contact update every {} steps: full pass in {} of {nsteps} steps",
                self.world.mc_every,
                self.world.mc_updates - passes0
            );
        }
        if self.world.mc_accuracy > 0.0 {
            approx += &self.budget_summary(nsteps, np);
        }
        // One process, a thread pool inside it: say how many threads the force passes could use
        // and how often they did (the engine times steps with and without its threads and keeps
        // the faster; results are the same bits either way). Under `--threads-mode serial` the
        // pool is never used, so the line says one thread whatever the pool size.
        let pool = rayon::current_num_threads();
        let threads = if pool == 1 || self.world.pair_threads == crate::engine::PairThreads::Serial {
            "1 thread".to_string()
        } else {
            let (a, b) = self.world.threaded_passes();
            let passes = (a + b) - (threaded0.0 + threaded0.1);
            // (The run's set-up pass counts too: at most 100 %.)
            let pct = (100.0 * passes as f64 / (nsteps as f64).max(1.0)).min(100.0);
            format!("{pool} threads, threaded in {pct:.0} % of steps")
        };
        self.say(&format!(
            "Loop time of {secs:.6} on 1 procs for {nsteps} steps with {np} atoms ({rate:.4e} particle-steps/s, {threads}, {} neighbour builds{approx})\n",
            self.world.builds - builds0
        ));
        // Whether the Eq. 3 cap acted: contacts the multi-contact kernel evaluated, and how many of
        // them it switched back to Hertz because a penetration ratio exceeded MPR.
        let contacts = self.world.mc_kernel_contacts - kernel0.0;
        if contacts > 0 {
            let capped = self.world.mc_kernel_fallbacks - kernel0.1;
            self.say(&format!(
                "Multi-contact kernel: {contacts} contact evaluations, {capped} capped to Hertz by the maximum penetration ratio\n"
            ));
        }
        Ok(())
    }
}
