//! FIRE relaxation (Bitzek et al., Phys. Rev. Lett. 97 (2006) 170201) with Hertz or lagged
//! nonlocal contacts: the start from a packing that is not in equilibrium, and the fallback of a
//! load step Newton cannot converge.

use super::{Contact, Geo, Nonlocal, Other, FORCE_FLOOR};
use crate::nonlocal::kernel::Kernel;
use crate::physics::Vec3;
use crate::team::{SplitMut, Team};

/// FIRE stall test (see [`Nonlocal::relax`]): the time step has collapsed below this fraction of the
/// initial one ...
const FIRE_STALL_DT: f64 = 1e-4;
/// ... and the residual has not reached a new low (by 1 %) for this many steps.
const FIRE_STALL_STEPS: usize = 2000;

/// Fewest candidates (pairs and particle-wall contacts) for which FIRE's force evaluation uses
/// the team of threads: a step of the 514-particle compression has a few thousand, so each of two
/// members gets tens of microseconds of work, well above the cost of handing it out.
const FIRE_MIN_LEN: usize = 1024;

/// The buffers of [`Nonlocal::fire_forces`] that grow with the packing, kept across the steps of
/// one relaxation instead of allocated every step, and the relaxation's team of threads.
#[derive(Default)]
struct FireScratch {
    /// The threads of the force evaluation (as many as the rayon pool the solver runs in has),
    /// started by the first evaluation that is large enough.
    team: Option<Team>,
    /// A team of this thread alone, for evaluations too small to share.
    solo: Option<Team>,
    /// Per member of the team: the kernel values of one particle's contact pairs.
    vals: Vec<Vec<f64>>,
    /// Per candidate: its geometry, if its gap may close.
    geo: Vec<Option<Geo>>,
    /// Loaded contacts per particle, compressed rows: (contact, direction from the particle).
    adj_start: Vec<usize>,
    adj: Vec<(usize, Vec3)>,
    fill: Vec<usize>,
    /// Per row entry, then per contact and side: the approach from the particle's other loads.
    app: Vec<f64>,
    app_i: Vec<f64>,
    app_j: Vec<f64>,
    /// Per particle: the lowest possible approach (see `fire_forces`).
    floor: Vec<f64>,
    /// Net force per particle.
    f: Vec<Vec3>,
}

impl Nonlocal {
    /// Contact forces for the FIRE relaxation at centres `x`: every candidate pair and every wall
    /// of every particle whose geometric overlap exceeds −`margin`, P = K max(δ, 0)^{3/2} with
    /// δ = γ − Σ G P_lagged (the nonlocal approach from the forces of the previous FIRE step, `lag`,
    /// indexed like the candidates: pairs first, then particle × wall; all zero for Hertz).
    /// Leaves the net forces (with body forces) in `s.f`, returns the mean contact force, and
    /// writes the new forces and Hertz overlaps into `p_out`, `d_out`.
    ///
    /// The per-contact and per-particle work (geometry, kernel sums, overlaps) runs on the rayon
    /// pool; every value is computed as in a serial pass and the forces are summed serially in
    /// contact order, so the result does not depend on the number of threads, bit for bit.
    #[allow(clippy::too_many_arguments)]
    fn fire_forces(
        &self,
        s: &mut FireScratch,
        x: &[Vec3],
        candidates: &[(usize, usize)],
        lag: &[f64],
        margin: f64,
        p_out: &mut [f64],
        d_out: &mut [f64],
    ) -> f64 {
        let n = x.len();
        let nw = self.walls.len();
        let np = candidates.len();
        let other_of = |k: usize| -> (usize, Other) {
            if k < np {
                (candidates[k].0, Other::Particle(candidates[k].1))
            } else {
                ((k - np) / nw, Other::Wall((k - np) % nw))
            }
        };
        let total = np + n * nw;
        let threads = rayon::current_num_threads();
        if total >= FIRE_MIN_LEN && threads > 1 && s.team.as_ref().is_none_or(|t| t.size() != threads) {
            s.team = Some(Team::new(threads));
        }
        // Every pass below on the team's members, each on its own range (of candidates, or of
        // particles), or on this thread alone: the same values either way.
        let team = match s.team.as_ref().filter(|_| total >= FIRE_MIN_LEN && threads > 1) {
            Some(t) => t,
            None => s.solo.get_or_insert_with(|| Team::new(1)),
        };
        let size = team.size();
        s.vals.resize_with(size, Vec::new);
        s.geo.clear();
        s.geo.resize(total, None);
        {
            let geo = SplitMut::new(&mut s.geo);
            team.for_shares(total, |_, r| {
                // SAFETY: the members' shares are disjoint ranges of candidates.
                let out = unsafe { geo.range(r.clone()) };
                for (k, g) in r.zip(out) {
                    let (i, o) = other_of(k);
                    let v = self.geometry(x, i, o);
                    *g = (v.gamma > -margin).then_some(v);
                }
            });
        }
        let geo = &s.geo;
        // Per particle, in compressed rows: the loaded contacts of the previous step (index,
        // direction from the particle), in contact order.
        let nonlocal = !self.kernel.is_zero();
        s.adj_start.clear();
        s.adj.clear();
        if nonlocal {
            s.adj_start.resize(n + 1, 0);
            for k in 0..total {
                if let (Some(_), true) = (&geo[k], lag[k] > 0.0) {
                    let (i, o) = other_of(k);
                    s.adj_start[i + 1] += 1;
                    if let Other::Particle(j) = o {
                        s.adj_start[j + 1] += 1;
                    }
                }
            }
            for i in 0..n {
                s.adj_start[i + 1] += s.adj_start[i];
            }
            s.adj.resize(s.adj_start[n], (0, Vec3::zeros()));
            s.fill.clear();
            s.fill.extend_from_slice(&s.adj_start[..n]);
            for k in 0..total {
                if let (Some(g), true) = (&geo[k], lag[k] > 0.0) {
                    let (i, o) = other_of(k);
                    s.adj[s.fill[i]] = (k, g.e);
                    s.fill[i] += 1;
                    if let Other::Particle(j) = o {
                        s.adj[s.fill[j]] = (k, -g.e);
                        s.fill[j] += 1;
                    }
                }
            }
        }
        let (adj, start) = (&s.adj, &s.adj_start);
        let list = |p: usize| &adj[start[p]..start[p + 1]];
        let approach = |p: usize, c: usize, dir: &Vec3| -> f64 {
            list(p)
                .iter()
                .filter(|(k, _)| *k != c)
                .map(|(k, e)| self.bound[p].value(dir.dot(e)) * lag[*k])
                .sum()
        };
        // The approach at the loaded contacts themselves, with every pair's kernel value computed
        // once (G depends on the pair's direction cosine only): the same values, summed in the same
        // order, as `approach`, at half the kernel evaluations. One value per row entry, then
        // indexed by contact: the side of its first particle, then of the second.
        s.app.clear();
        s.app_i.clear();
        s.app_j.clear();
        if nonlocal {
            s.app.resize(adj.len(), 0.0);
            // Each member the rows of its own range of particles, i.e. its own entries.
            let (app, vals) = (SplitMut::new(&mut s.app), SplitMut::new(&mut s.vals));
            team.for_shares(n, |m, ps| {
                // SAFETY: the members' shares are disjoint ranges of particles, hence of row
                // entries, and each member m takes its own value buffer.
                let (out, vals) =
                    unsafe { (app.range(start[ps.start]..start[ps.end]), &mut vals.range(m..m + 1)[0]) };
                let mut at = 0;
                for p in ps {
                    let row = list(p);
                    let z = row.len();
                    vals.clear();
                    vals.resize(z * z, 0.0);
                    for a in 0..z {
                        for c in a + 1..z {
                            let v = self.bound[p].value(row[a].1.dot(&row[c].1));
                            vals[a * z + c] = v;
                            vals[c * z + a] = v;
                        }
                    }
                    for a in 0..z {
                        out[at + a] =
                            (0..z).filter(|&c| c != a).map(|c| vals[a * z + c] * lag[row[c].0]).sum();
                    }
                    at += z;
                }
            });
            s.app_i.resize(total, 0.0);
            s.app_j.resize(total, 0.0);
            for p in 0..n {
                for (&(k, _), &a) in list(p).iter().zip(&s.app[start[p]..start[p + 1]]) {
                    if other_of(k).0 == p {
                        s.app_i[k] = a;
                    } else {
                        s.app_j[k] = a;
                    }
                }
            }
        }
        // Per particle: lower bound of the approach at any point, lower_bound · Σ lag (≤ 0).
        s.floor.clear();
        if nonlocal {
            s.floor
                .extend((0..n).map(|p| {
                    self.bound[p].lower_bound() * list(p).iter().map(|&(k, _)| lag[k]).sum::<f64>()
                }));
        }
        // Each contact's overlap and force (d_out, p_out), then the sums in contact order.
        let (app_i, app_j, floor) = (&s.app_i, &s.app_j, &s.floor);
        let (ds, ps) = (SplitMut::new(&mut d_out[..total]), SplitMut::new(&mut p_out[..total]));
        team.for_shares(total, |_, r| {
            // SAFETY: the members' shares are disjoint ranges of contacts.
            let (ds, ps) = unsafe { (ds.range(r.clone()), ps.range(r.clone())) };
            for (k, (d_out, p_out)) in r.zip(ds.iter_mut().zip(ps.iter_mut())) {
                *p_out = 0.0;
                *d_out = f64::NEG_INFINITY;
                let Some(g) = &geo[k] else { continue };
                let (i, o) = other_of(k);
                let mut delta = g.gamma;
                if nonlocal {
                    let loaded = lag[k] > 0.0;
                    if !loaded {
                        // The approach is at least lower_bound · Σ lag at each particle: when even
                        // the largest possible bulge leaves the gap open, the contact stays
                        // unloaded (its overlap is not used).
                        let mut most = g.gamma - floor[i];
                        if let Other::Particle(j) = o {
                            most -= floor[j];
                        }
                        if most < 0.0 {
                            *d_out = most;
                            continue;
                        }
                    }
                    delta -= if loaded { app_i[k] } else { approach(i, k, &g.e) };
                    if let Other::Particle(j) = o {
                        delta -= if loaded { app_j[k] } else { approach(j, k, &(-g.e)) };
                    }
                }
                *d_out = delta;
                if delta > 0.0 {
                    let c = Contact { i, other: o, delta, k: self.stiffness(i, o) };
                    *p_out = Self::force_of(&c, delta).0;
                }
            }
        });
        s.f.clear();
        s.f.extend(self.body.iter().map(|b| b * self.body_factor));
        let (mut sum, mut cnt) = (0.0, 0usize);
        for k in 0..total {
            // Overlap positive: a force was computed (d_out is −∞ or negative otherwise).
            if d_out[k] <= 0.0 {
                continue;
            }
            let (p, Some(g)) = (p_out[k], &geo[k]) else { continue };
            let (i, o) = other_of(k);
            s.f[i] -= g.e * p;
            if let Other::Particle(j) = o {
                s.f[j] += g.e * p;
            }
            sum += p;
            cnt += 1;
        }
        if cnt > 0 {
            sum / cnt as f64
        } else {
            0.0
        }
    }

    /// Pre-relaxation of a packing that is not in equilibrium (e.g. a DEM snapshot in motion):
    /// FIRE energy minimisation (Bitzek et al., Phys. Rev. Lett. 97 (2006) 170201) with plain Hertz
    /// contacts, unit masses, at the current walls and body forces. See [`Self::relax`].
    pub fn relax_hertz(&mut self, max_steps: usize, ftol: f64) -> (usize, f64) {
        self.relax(max_steps, ftol, false)
    }

    /// FIRE relaxation (Bitzek et al., Phys. Rev. Lett. 97 (2006) 170201, unit masses) at the current
    /// walls and body forces. Newton cannot do this job: far from equilibrium the packing has to
    /// rearrange, which is a minimisation, not a root-finding problem. With `nonlocal` the contact
    /// law is the nonlocal relation with the approach lagged by one FIRE step (the fixed-point
    /// iteration that standard multi-contact performs in the DEM, docs/spec.md §4 (b)); without it, plain
    /// Hertz. Stops when max |net force| ≤ `ftol` × mean contact force, after `max_steps`, or on a
    /// stall (dt below [`FIRE_STALL_DT`] × the initial dt and no new low of the residual for
    /// [`FIRE_STALL_STEPS`] steps: the lagged iteration oscillates; recorded for the caller).
    /// Returns (steps, final relative residual). The active set is replaced by the loaded contacts
    /// of the relaxed state (with their lagged Hertz overlaps), a warm start for Newton.
    pub fn relax(&mut self, max_steps: usize, ftol: f64, nonlocal: bool) -> (usize, f64) {
        let n = self.x.len();
        let nw = self.walls.len();
        let mut x = self.x.clone();
        let mut v = vec![Vec3::zeros(); n];
        let (dt0, dt_max): (f64, f64) = (0.05, 0.5);
        let (mut dt, mut alpha, mut since_neg) = (dt0, 0.1, 0usize);
        let mut candidates: Vec<(usize, usize)> = Vec::new();
        let mut x_list = x.clone();
        let rmax = self.r.iter().cloned().fold(0.0, f64::max);
        let rmin = self.r.iter().cloned().fold(f64::INFINITY, f64::min);
        let skin = 0.3 * rmax;
        // Contacts whose geometric gap is below this may be closed by the nonlocal bulge.
        let margin = if nonlocal && !self.kernel.is_zero() { 0.2 * rmin } else { 0.0 };
        let rebuild = |x: &[Vec3], c: &mut Vec<(usize, usize)>| {
            c.clear();
            for i in 0..n {
                for j in i + 1..n {
                    if (x[j] - x[i]).norm() < self.r[i] + self.r[j] + skin {
                        c.push((i, j));
                    }
                }
            }
        };
        // The lagged forces start from the current active set.
        let saved_kernel = self.kernel;
        if !nonlocal {
            self.kernel = Kernel::new(crate::nonlocal::KernelKind::None, 0.0).unwrap_or(saved_kernel);
        }
        let start: std::collections::HashMap<(usize, Other), f64> =
            self.contacts.iter().map(|c| ((c.i, c.other), Self::force_of(c, c.delta).0)).collect();
        rebuild(&x, &mut candidates);
        let index_of = |c: &[(usize, usize)], map: &std::collections::HashMap<(usize, Other), f64>| {
            let mut lag = vec![0.0; c.len() + n * nw];
            for (k, &(i, j)) in c.iter().enumerate() {
                lag[k] = map.get(&(i, Other::Particle(j))).copied().unwrap_or(0.0);
            }
            for i in 0..n {
                for w in 0..nw {
                    lag[c.len() + i * nw + w] = map.get(&(i, Other::Wall(w))).copied().unwrap_or(0.0);
                }
            }
            lag
        };
        let mut lag = index_of(&candidates, &start);
        let mut p = vec![0.0; lag.len()];
        let mut d = vec![0.0; lag.len()];
        let mut rel;
        let mut step = 0;
        let mut scratch = FireScratch::default();
        let trace = std::env::var_os("MCDEM_NONLOCAL_TRACE").is_some();
        let (mut best, mut best_step, mut min_dt, mut longest) = (f64::INFINITY, 0usize, dt0, 0usize);
        self.last_fire_stalled = false;
        loop {
            if x.iter().zip(&x_list).any(|(a, b)| (a - b).norm() > 0.5 * skin) {
                let np = candidates.len();
                let map: std::collections::HashMap<(usize, Other), f64> = (0..lag.len())
                    .filter(|&k| lag[k] > 0.0)
                    .map(|k| {
                        if k < np {
                            ((candidates[k].0, Other::Particle(candidates[k].1)), lag[k])
                        } else {
                            (((k - np) / nw, Other::Wall((k - np) % nw)), lag[k])
                        }
                    })
                    .collect();
                rebuild(&x, &mut candidates);
                x_list = x.clone();
                lag = index_of(&candidates, &map);
                p = vec![0.0; lag.len()];
                d = vec![0.0; lag.len()];
            }
            let pmean = self.fire_forces(&mut scratch, &x, &candidates, &lag, margin, &mut p, &mut d);
            let f = &scratch.f;
            std::mem::swap(&mut lag, &mut p);
            let fmax = f.iter().map(|f| f.norm()).fold(0.0, f64::max);
            rel = fmax / pmean.max(FORCE_FLOOR);
            // Below the force floor the packing is unjammed: relax on until every overlap has
            // opened (all forces exactly zero, an exact equilibrium) rather than leave Newton a
            // degenerate problem (P ∝ δ^{3/2} with dP/dδ → 0).
            let unjammed = pmean < FORCE_FLOOR && fmax > 0.0;
            if trace && step % 2000 == 0 {
                eprintln!(
                    "  fire {step}: force {rel:.3e} (mean P {pmean:.3e}) dt {dt:.3e} candidates {}",
                    candidates.len()
                );
            }
            if rel < 0.99 * best {
                (best, best_step) = (rel, step);
            }
            min_dt = min_dt.min(dt);
            longest = longest.max(step - best_step);
            // Stall: the lagged nonlocal iteration oscillates (its fixed-point map is not a
            // contraction at this load), FIRE keeps reversing, dt collapses and the residual stays
            // put; more steps change nothing.
            let stalled = dt < FIRE_STALL_DT * dt0 && step - best_step >= FIRE_STALL_STEPS;
            if (rel <= ftol && !unjammed) || step >= max_steps || stalled {
                if trace {
                    eprintln!(
                        "  fire done at {step}: force {rel:.3e} (tolerance {ftol:.0e}) min dt {min_dt:.3e} longest without progress {longest}{}",
                        if stalled { " STALLED" } else { "" }
                    );
                }
                self.last_fire_stalled = stalled;
                self.last_fire_worst =
                    (0..n).max_by(|&a, &b| f[a].norm().total_cmp(&f[b].norm())).unwrap_or(0);
                break;
            }
            step += 1;
            let power: f64 = f.iter().zip(&v).map(|(f, v)| f.dot(v)).sum();
            let fnorm = f.iter().map(|f| f.norm_squared()).sum::<f64>().sqrt();
            let vnorm = v.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
            if power > 0.0 {
                for (vi, fi) in v.iter_mut().zip(f) {
                    *vi = *vi * (1.0 - alpha) + fi * (alpha * vnorm / fnorm.max(1e-300));
                }
                since_neg += 1;
                if since_neg > 5 {
                    dt = (dt * 1.1).min(dt_max);
                    alpha *= 0.99;
                }
            } else {
                since_neg = 0;
                dt *= 0.5;
                alpha = 0.1;
                v.iter_mut().for_each(|v| *v = Vec3::zeros());
            }
            // Semi-implicit Euler with unit masses; a move cap keeps contacts in the list valid.
            for i in 0..n {
                v[i] += f[i] * dt;
                let mut dx = v[i] * dt;
                let m = dx.norm();
                if m > 0.1 * skin {
                    dx *= 0.1 * skin / m;
                }
                x[i] += dx;
            }
        }
        self.kernel = saved_kernel;
        // Warm start for Newton: the loaded contacts with their (lagged) Hertz overlaps.
        let np = candidates.len();
        self.contacts = (0..lag.len())
            .filter(|&k| lag[k] > 0.0)
            .map(|k| {
                let (i, o) = if k < np {
                    (candidates[k].0, Other::Particle(candidates[k].1))
                } else {
                    ((k - np) / nw, Other::Wall((k - np) % nw))
                };
                Contact { i, other: o, delta: d[k], k: self.stiffness(i, o) }
            })
            .collect();
        if !nonlocal {
            // Hertz relaxation: Newton re-derives the overlaps with the nonlocal terms.
            self.contacts.clear();
        }
        self.x = x;
        (step, rel)
    }
}
