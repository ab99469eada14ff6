//! Particle insertion as LIGGGHTS 3.8 documents it: `fix particletemplate/sphere` (one kind of
//! particle), `fix particledistribution/discrete` (templates with weights) and `fix insert/pack`
//! (fill a region once, at the start of the next run, with non-overlapping particles).
//!
//! Placement is random rejection sampling from the fix's seed, sequential and so the same on any
//! thread count. Larger particles are placed first (as LIGGGHTS does: they are the hardest to fit).
//! A target the region cannot hold is, as in LIGGGHTS, a warning (`Less insertions than
//! requested`, with the deck's FILE:LINE) and a short insertion: the run goes on with what fitted.

use std::collections::HashMap;
use std::f64::consts::PI;

use super::insert_common::{positive, seed};
use crate::deck::regions::Region;
use crate::deck::*;
use crate::rng::SplitMix64;

/// Templates, distributions and the insertions waiting for the next run.
#[derive(Debug, Default)]
pub(in crate::deck) struct Insertion {
    templates: HashMap<String, Template>,
    distributions: HashMap<String, Distribution>,
    pending: Vec<Pack>,
    /// `insert_every N` insertions: each with the step of its next insertion.
    periodic: Vec<(Pack, u64)>,
    /// `fix insert/stream` insertions.
    pub(super) streams: Vec<super::stream::Stream>,
    /// Insertion states read from a restart file, waiting for a `fix insert/stream` of their ID.
    pub(super) restored: Vec<super::stream::StreamState>,
    /// Particle index by ID for the streams' particles in flight, kept between steps and rebuilt
    /// only when an entry no longer points at its particle (after a sort or a new run's set-up).
    pub(super) id_index: HashMap<i64, usize>,
}

impl Insertion {
    /// The state of each `fix insert/stream`, for a restart file.
    pub(in crate::deck) fn stream_states(&self) -> Vec<super::stream::StreamState> {
        self.streams.iter().map(super::stream::Stream::state).collect()
    }

    /// A restart file's insertion states, taken up by the fixes of their IDs defined next.
    pub(in crate::deck) fn restore_streams(&mut self, states: Vec<super::stream::StreamState>) {
        self.restored = states;
    }

    /// `reset_timestep`: each `insert_every` insertion's next step moved by `shift`.
    pub(super) fn shift_steps(&mut self, shift: &dyn Fn(u64) -> u64) {
        for (_, next) in &mut self.periodic {
            *next = shift(*next);
        }
        for s in &mut self.streams {
            s.shift_steps(shift);
        }
    }

    pub(super) fn has_distribution(&self, id: &str) -> bool {
        self.distributions.contains_key(id)
    }

    /// LIGGGHTS 3.8 stops an insertion fix whose seed is also the seed of its distribution or of
    /// one of that distribution's templates (`fix_insert.cpp`: the streams would be correlated);
    /// a deck that mcdem ran and LIGGGHTS refuses would break the cross-check, so the same rule
    /// holds here.
    pub(super) fn check_distinct_seed(&self, what: &str, seed: u64, dist: &str) -> R<()> {
        let Some(d) = self.distributions.get(dist) else { return Ok(()) };
        let clash = if d.seed == seed {
            Some(format!("distribution {dist}"))
        } else {
            d.parts
                .iter()
                .find(|(id, _)| self.templates.get(id.as_str()).is_some_and(|t| t.seed == seed))
                .map(|(id, _)| format!("template {id} of distribution {dist}"))
        };
        match clash {
            Some(who) => Err(format!(
                "{what}: seed {seed} is also the seed of {who}; the insertion, its distribution and \
                 the distribution's templates need different seeds (LIGGGHTS stops here too)"
            )),
            None => Ok(()),
        }
    }
}

#[derive(Debug, Clone)]
pub(super) struct Template {
    /// 0-based atom type.
    typ: usize,
    density: f64,
    radius: Radius,
    seed: u64,
}

#[derive(Debug, Clone, Copy)]
enum Radius {
    Constant(f64),
    /// Normal (mean, standard deviation); draws ≤ 0 are drawn again (σ ≤ μ/3 keeps that rare).
    Gaussian(f64, f64),
    /// Uniform on [min, max].
    Uniform(f64, f64),
}

impl Radius {
    fn draw(&self, rng: &mut SplitMix64) -> f64 {
        match *self {
            Radius::Constant(r) => r,
            Radius::Uniform(a, b) => a + (b - a) * rng.uniform(),
            Radius::Gaussian(mu, s) => loop {
                let r = mu + s * rng.normal();
                if r > 0.0 {
                    break r;
                }
            },
        }
    }

    /// Mean of r³ (for the expected particle volume and mass).
    fn mean_cube(&self) -> f64 {
        match *self {
            Radius::Constant(r) => r * r * r,
            Radius::Uniform(a, b) if b > a => (b.powi(4) - a.powi(4)) / (4.0 * (b - a)),
            Radius::Uniform(a, _) => a * a * a,
            Radius::Gaussian(mu, s) => mu * mu * mu + 3.0 * mu * s * s,
        }
    }
}

impl Template {
    fn mean_volume(&self) -> f64 {
        4.0 / 3.0 * PI * self.radius.mean_cube()
    }
}

#[derive(Debug, Clone)]
struct Distribution {
    seed: u64,
    /// Template IDs with their number fractions (summing to 1).
    parts: Vec<(String, f64)>,
}

#[derive(Debug, Clone)]
enum Target {
    Count(usize),
    VolumeFraction(f64),
    Mass(f64),
}

#[derive(Debug, Clone)]
struct Pack {
    /// `fix ID insert/pack (line N)`, for messages at the run that inserts.
    label: String,
    /// The fix ID (`unfix` stops its insertions).
    fix: String,
    /// The mask bit of the fix's group, which its particles join.
    bit: u32,
    /// Steps between insertions (`insert_every N`); `None`: once.
    every: Option<u64>,
    /// Insertions done so far: each draws from its own random stream.
    round: u64,
    seed: u64,
    dist: String,
    region: Region,
    target: Target,
    all_in: bool,
    exact: bool,
    maxattempt: usize,
    vel: Vec3,
    omega: Vec3,
}

impl Deck {
    /// `fix ID group particletemplate/sphere SEED atom_type T density constant RHO radius STYLE …`
    /// with STYLE `constant R`, `gaussian MU SIGMA` or `uniform MIN MAX`.
    pub(in crate::deck) fn particle_template(&mut self, a: &[&str]) -> R<FixKind> {
        let what = format!("fix {} particletemplate/sphere", a[1]);
        let seed = seed(a.get(4).ok_or_else(|| format!("{what}: expected a seed"))?, &what)?;
        let (mut typ, mut density, mut radius) = (None, None, None);
        let mut k = 5;
        let arg = |k: usize| a.get(k).copied().ok_or_else(|| format!("{what}: {} needs a value", a[k - 1]));
        while k < a.len() {
            match a[k] {
                "atom_type" => {
                    let t = int(arg(k + 1)?)?;
                    if t < 1 || (self.ntypes > 0 && t as usize > self.ntypes) {
                        return Err(format!("{what}: atom_type {t} outside 1..{}", self.ntypes));
                    }
                    typ = Some(t as usize - 1);
                    k += 2;
                }
                "density" => {
                    if arg(k + 1)? != "constant" {
                        return Err(unsupported(&format!("{what}: density style {} (constant)", a[k + 1])));
                    }
                    density = Some(positive(arg(k + 2)?, &format!("{what}: density"))?);
                    k += 3;
                }
                "radius" => {
                    let k0 = k;
                    let p = |j: usize| positive(arg(k0 + j)?, &format!("{what}: radius"));
                    radius = Some(match arg(k0 + 1)? {
                        "constant" => {
                            k += 3;
                            Radius::Constant(p(2)?)
                        }
                        "gaussian" => {
                            let (mu, sigma) = (p(2)?, num(arg(k0 + 3)?)?);
                            if !(0.0..=mu / 3.0).contains(&sigma) {
                                return Err(format!(
                                    "{what}: radius gaussian standard deviation must be in [0, mean/3] (no radius <= 0 in practice), got {sigma}"
                                ));
                            }
                            k += 4;
                            Radius::Gaussian(mu, sigma)
                        }
                        "uniform" => {
                            let (lo, hi) = (p(2)?, p(3)?);
                            if hi < lo {
                                return Err(format!("{what}: radius uniform max {hi} below min {lo}"));
                            }
                            k += 4;
                            Radius::Uniform(lo, hi)
                        }
                        other => {
                            return Err(unsupported(&format!(
                                "{what}: radius style {other} (constant, gaussian or uniform)"
                            )))
                        }
                    });
                }
                "relative" if a.get(k + 1) == Some(&"no") => k += 2,
                "volume_limit" => {
                    positive(arg(k + 1)?, &format!("{what}: volume_limit"))?;
                    k += 2;
                }
                other => return Err(unsupported(&format!("{what} keyword {other}"))),
            }
        }
        let t = Template {
            typ: typ.ok_or_else(|| format!("{what}: atom_type is required"))?,
            density: density.ok_or_else(|| format!("{what}: density is required"))?,
            radius: radius.ok_or_else(|| format!("{what}: radius is required"))?,
            seed,
        };
        self.insertion.templates.insert(a[1].into(), t);
        Ok(FixKind::Property)
    }

    /// `fix ID group particledistribution/discrete[/massbased|/numberbased] SEED N T1 W1 … TN WN`.
    pub(in crate::deck) fn particle_distribution(&mut self, a: &[&str]) -> R<FixKind> {
        let what = format!("fix {} {}", a[1], a[3]);
        let massbased = a[3] != "particledistribution/discrete/numberbased";
        let seed = seed(a.get(4).ok_or_else(|| format!("{what}: expected SEED N T1 W1 …"))?, &what)?;
        let n = int(a.get(5).ok_or_else(|| format!("{what}: expected SEED N T1 W1 …"))?)?;
        if n < 1 || a.len() != 6 + 2 * n as usize {
            return Err(format!(
                "{what}: expected {n} template/weight pairs after N, got {} words",
                a.len() - 6
            ));
        }
        let mut parts = Vec::new();
        for j in 0..n as usize {
            let (id, w) = (a[6 + 2 * j], a[7 + 2 * j]);
            let t = self
                .insertion
                .templates
                .get(id)
                .ok_or_else(|| format!("{what}: {id} is not a particletemplate/sphere fix"))?;
            let w = num(w)?;
            if !(w > 0.0 && w <= 1.0) {
                return Err(format!("{what}: weight of {id} must be in (0, 1], got {w}"));
            }
            // Mass fractions become number fractions through each template's mean mass.
            let per = if massbased { w / (t.density * t.mean_volume()) } else { w };
            parts.push((id.to_string(), w, per));
        }
        let sum: f64 = parts.iter().map(|p| p.1).sum();
        // LIGGGHTS renormalises with a warning; a typo in a fraction is caught here instead.
        if (sum - 1.0).abs() > 1e-6 {
            return Err(format!("{what}: the weights sum to {sum}, not 1"));
        }
        let total: f64 = parts.iter().map(|p| p.2).sum();
        let parts = parts.into_iter().map(|(id, _, per)| (id, per / total)).collect();
        self.insertion.distributions.insert(a[1].into(), Distribution { seed, parts });
        Ok(FixKind::Property)
    }

    /// `fix ID group insert/pack seed S distributiontemplate D [general keywords] region R` and one
    /// of `particles_in_region N`, `volumefraction_region F`, `mass_in_region M`.
    pub(in crate::deck) fn insert_pack(&mut self, a: &[&str]) -> R<FixKind> {
        let what = format!("fix {} insert/pack", a[1]);
        let label = format!("{what} (line {})", self.line_no);
        let (mut region, mut target) = (None, None);
        let (mut all_in, mut maxattempt) = (false, 50usize);
        let mut every = None;
        let yes_no = |v: &str, key: &str| match v {
            "yes" => Ok(true),
            "no" => Ok(false),
            _ => Err(format!("{what}: {key} must be yes or no, got '{v}'")),
        };
        let common = self.insert_keywords(a, &what, |key, v| {
            match key {
                "region" => {
                    let r =
                        self.regions.get(v).cloned().ok_or_else(|| format!("{what}: unknown region {v}"))?;
                    // Random points in tetrahedra (LIGGGHTS' `generate_random`) are not implemented.
                    if matches!(r, Region::TetMesh(_)) {
                        return Err(unsupported(&format!("{what} into region {v} of style mesh/tet")));
                    }
                    region = Some(r)
                }
                "particles_in_region" => {
                    let n = int(v)?;
                    if n < 1 {
                        return Err(format!("{what}: particles_in_region must be >= 1, got {v}"));
                    }
                    target = Some(Target::Count(n as usize));
                }
                "volumefraction_region" => {
                    let f = num(v)?;
                    if !(f > 0.0 && f < 1.0) {
                        return Err(format!("{what}: volumefraction_region must be in (0, 1), got {v}"));
                    }
                    target = Some(Target::VolumeFraction(f));
                }
                "mass_in_region" => {
                    target = Some(Target::Mass(positive(v, &format!("{what}: mass_in_region"))?))
                }
                "insert_every" if v == "once" => every = None,
                "insert_every" => {
                    let n = int(v).map_err(|e| format!("{what}: insert_every: {e}"))?;
                    if n < 1 {
                        return Err(format!("{what}: insert_every must be once or >= 1, got {v}"));
                    }
                    every = Some(n as u64);
                }
                "overlapcheck" if v == "yes" => {}
                "overlapcheck" => return Err(unsupported(&format!("{what}: overlapcheck {v} (only yes)"))),
                "all_in" => all_in = yes_no(v, "all_in")?,
                "maxattempt" => {
                    let m = int(v)?;
                    if m < 1 {
                        return Err(format!("{what}: maxattempt must be >= 1, got {v}"));
                    }
                    maxattempt = m as usize;
                }
                // Output and parallel bookkeeping; the region volume is computed exactly.
                "verbose" | "compress_tags" | "check_dist_from_subdomain_border" => {
                    yes_no(v, key)?;
                }
                "ntry_mc" => {
                    int(v)?;
                }
                other => return Err(unsupported(&format!("{what} keyword {other}"))),
            }
            Ok(())
        })?;
        let pack = Pack {
            label,
            fix: a[1].to_string(),
            bit: self.groups.bit(a[2], &what)?,
            every,
            round: 0,
            seed: common.seed.ok_or_else(|| format!("{what}: seed is required"))?,
            dist: common.dist.ok_or_else(|| format!("{what}: distributiontemplate is required"))?,
            region: region.ok_or_else(|| format!("{what}: region is required"))?,
            target: target.ok_or_else(|| {
                format!(
                    "{what}: one of particles_in_region, volumefraction_region, mass_in_region is required"
                )
            })?,
            all_in,
            exact: common.exact,
            maxattempt,
            vel: common.vel.unwrap_or_else(Vec3::zeros),
            omega: common.omega,
        };
        self.insertion.check_distinct_seed(&what, pack.seed, &pack.dist)?;
        match pack.every {
            None => self.insertion.pending.push(pack),
            // As LIGGGHTS: first on the step after the definition, then every N steps.
            Some(_) => self.insertion.periodic.push((pack, self.world.step + 1)),
        }
        Ok(FixKind::Insert)
    }

    /// Runs the insertions waiting for this run (at its start, as LIGGGHTS inserts on the first step).
    pub(in crate::deck) fn insert_pending(&mut self) -> R<()> {
        for pack in std::mem::take(&mut self.insertion.pending) {
            let n = self.insert(&pack).map_err(|e| format!("{}: {e}", pack.label))?;
            self.say(&format!("INFO: {}: inserted {n} particles", pack.label));
        }
        self.insert_due()?;
        Ok(())
    }

    /// The `insert_every N` insertions due before the coming step; whether any particle came.
    pub(in crate::deck) fn insert_due(&mut self) -> R<bool> {
        let next = self.world.step + 1;
        let mut added = false;
        for k in 0..self.insertion.periodic.len() {
            let (pack, due) = &self.insertion.periodic[k];
            if *due > next {
                continue;
            }
            let pack = pack.clone();
            let n = self.insert(&pack).map_err(|e| format!("{} at step {next}: {e}", pack.label))?;
            self.say(&format!("INFO: {}: inserted {n} particles at step {next}", pack.label));
            added |= n > 0;
            let (p, due) = &mut self.insertion.periodic[k];
            p.round += 1;
            *due = next + p.every.unwrap_or(u64::MAX);
        }
        added |= self.stream_due()?;
        Ok(added)
    }

    /// Whether an `insert_every N` insertion is active (checked before each step).
    pub(in crate::deck) fn step_inserts(&self) -> bool {
        !self.insertion.periodic.is_empty() || !self.insertion.streams.is_empty()
    }

    /// Whether an insertion fix will still add particles (a group defined now misses them).
    pub(in crate::deck) fn inserts_later(&self) -> bool {
        !self.insertion.pending.is_empty()
            || !self.insertion.periodic.is_empty()
            || !self.insertion.streams.is_empty()
    }

    /// `unfix` of an insertion fix: its insertions not yet done are dropped.
    pub(in crate::deck) fn stop_inserting(&mut self, fix: &str) {
        self.insertion.pending.retain(|p| p.fix != fix);
        self.insertion.periodic.retain(|(p, _)| p.fix != fix);
        self.insertion.streams.retain(|s| s.fix != fix);
    }

    /// Mean particle volume and mass of a distribution (number fractions over template means).
    pub(super) fn distribution_means(&self, dist: &str) -> (f64, f64) {
        let dist = &self.insertion.distributions[dist];
        let mut m = (0.0, 0.0);
        for (id, f) in &dist.parts {
            let t = &self.insertion.templates[id];
            m.0 += f * t.mean_volume();
            m.1 += f * t.density * t.mean_volume();
        }
        m
    }

    /// The largest radius a distribution can draw (mean + 3σ for a gaussian).
    pub(super) fn distribution_max_radius(&self, dist: &str) -> f64 {
        let dist = &self.insertion.distributions[dist];
        dist.parts
            .iter()
            .map(|(id, _)| match self.insertion.templates[id].radius {
                Radius::Constant(r) => r,
                Radius::Uniform(_, b) => b,
                Radius::Gaussian(mu, s) => mu + 3.0 * s,
            })
            .fold(0.0, f64::max)
    }

    /// The particles of one insertion of `n` from distribution `dist`: the templates and, per
    /// particle, its radius and template index, largest first. `exact`: template shares by
    /// largest remainders, else each particle's template drawn on its own.
    pub(super) fn draw_batch(
        &self,
        dist: &str,
        n: usize,
        seed: u64,
        exact: bool,
    ) -> (Vec<Template>, Vec<(f64, usize)>) {
        let dist = &self.insertion.distributions[dist];
        let templates: Vec<Template> =
            dist.parts.iter().map(|(id, _)| self.insertion.templates[id].clone()).collect();
        let frac: Vec<f64> = dist.parts.iter().map(|p| p.1).collect();
        let mut pick = SplitMix64(dist.seed ^ seed.rotate_left(32));
        let mut counts = vec![0usize; templates.len()];
        if exact {
            let raw: Vec<f64> = frac.iter().map(|f| f * n as f64).collect();
            for (c, r) in counts.iter_mut().zip(&raw) {
                *c = r.floor() as usize;
            }
            let mut order: Vec<usize> = (0..raw.len()).collect();
            order.sort_by(|&x, &y| {
                (raw[y] - raw[y].floor()).total_cmp(&(raw[x] - raw[x].floor())).then(x.cmp(&y))
            });
            let short = n - counts.iter().sum::<usize>();
            for &j in order.iter().take(short) {
                counts[j] += 1;
            }
        } else {
            for _ in 0..n {
                let u = pick.uniform();
                let mut acc = 0.0;
                let j = frac.iter().position(|f| {
                    acc += f;
                    u < acc
                });
                counts[j.unwrap_or(frac.len() - 1)] += 1;
            }
        }
        let mut new: Vec<(f64, usize)> = Vec::with_capacity(n);
        for (j, t) in templates.iter().enumerate() {
            let mut rng = SplitMix64(t.seed ^ seed);
            new.extend((0..counts[j]).map(|_| (t.radius.draw(&mut rng), j)));
        }
        // Largest first; ties keep template order (a stable sort).
        new.sort_by(|x, y| y.0.total_cmp(&x.0));
        (templates, new)
    }

    /// The particles present, hashed for overlap tests against a batch about to be placed.
    pub(super) fn occupied(&self, new: &[(f64, usize)]) -> Grid {
        let p = &self.world.p;
        let rmax = new.iter().map(|x| x.0).chain(p.radius.iter().copied()).fold(0.0, f64::max);
        let mut grid = Grid::new(2.0 * rmax);
        for i in 0..p.len() {
            grid.add(p.x[i], p.radius[i]);
        }
        grid
    }

    /// Adds one inserted particle (the next free id) and returns its index.
    pub(super) fn add_inserted(&mut self, t: &Template, x: Vec3, r: f64, vel: Vec3, omega: Vec3) -> usize {
        let id = self.world.p.id.iter().copied().max().unwrap_or(0) + 1;
        self.world.p.push(id, t.typ, x, 2.0 * r, t.density);
        let i = self.world.p.len() - 1;
        self.world.p.v[i] = vel;
        self.world.p.omega[i] = omega;
        i
    }

    fn insert(&mut self, pack: &Pack) -> R<usize> {
        let dom = self.world.domain.ok_or("insertion before the simulation box exists")?;
        let (lo, hi) = pack.region.bounds();
        if (0..3).any(|k| lo[k] < dom.lo[k] || hi[k] > dom.hi[k]) {
            return Err("the region reaches outside the simulation box".into());
        }
        let (mean_vol, mean_mass) = self.distribution_means(&pack.dist);
        // What is already in the region counts towards the target.
        let p = &self.world.p;
        let inside: Vec<usize> = (0..p.len()).filter(|&i| pack.region.holds(&p.x[i], 0.0)).collect();
        let want = match pack.target {
            Target::Count(n) => n as f64 - inside.len() as f64,
            Target::VolumeFraction(f) => {
                let have: f64 = inside.iter().map(|&i| 4.0 / 3.0 * PI * p.radius[i].powi(3)).sum();
                (f * pack.region.volume() - have) / mean_vol
            }
            Target::Mass(m) => (m - inside.iter().map(|&i| p.mass[i]).sum::<f64>()) / mean_mass,
        };
        let n = want.round().max(0.0) as usize;
        // Round 0 keeps the streams of a single insertion; later rounds draw new ones.
        let seed = crate::rng::mix_seed(pack.seed, pack.round);
        let (templates, new) = self.draw_batch(&pack.dist, n, seed, pack.exact);
        let mut grid = self.occupied(&new);
        let p = &self.world.p;
        let mut rng = SplitMix64(seed);
        let mut id = p.id.iter().copied().max().unwrap_or(0);
        // As LIGGGHTS (FixInsertPack::x_v_omega): one budget of n × maxattempt random tries for the
        // whole insertion; a particle is tried until it fits or the budget is spent.
        let budget = n.saturating_mul(pack.maxattempt);
        let mut tries = 0usize;
        let mut placed = 0usize;
        for &(r, j) in &new {
            let margin = if pack.all_in { r } else { 0.0 };
            let mut at = None;
            while tries < budget {
                tries += 1;
                let x = Vec3::new(
                    lo.x + margin + (hi.x - lo.x - 2.0 * margin).max(0.0) * rng.uniform(),
                    lo.y + margin + (hi.y - lo.y - 2.0 * margin).max(0.0) * rng.uniform(),
                    lo.z + margin + (hi.z - lo.z - 2.0 * margin).max(0.0) * rng.uniform(),
                );
                if pack.region.holds(&x, margin) && !grid.overlaps(x, r) {
                    at = Some(x);
                    break;
                }
            }
            let Some(x) = at else { break };
            grid.add(x, r);
            id += 1;
            let t = &templates[j];
            self.world.p.push(id, t.typ, x, 2.0 * r, t.density);
            let i = self.world.p.len() - 1;
            self.world.p.v[i] = pack.vel;
            self.world.p.omega[i] = pack.omega;
            self.world.p.mask[i] |= pack.bit;
            placed += 1;
        }
        if placed < n {
            // LIGGGHTS warns ("Particle insertion: Less insertions than requested") and goes on.
            let r = new[placed].0;
            self.warn_here(&format!(
                "{} at step {}: Particle insertion: Less insertions than requested: placed {placed} of {n} ({} random tries, maxattempt {} per particle, found no free place for one of radius {r:e} m)",
                pack.label,
                self.world.step + 1,
                budget,
                pack.maxattempt
            ));
        }
        Ok(placed)
    }
}

/// Spheres hashed into cubic cells no smaller than the largest diameter: an overlap can only be
/// with a sphere in one of the 27 cells around a point.
pub(super) struct Grid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<(Vec3, f64)>>,
}

impl Grid {
    fn new(cell: f64) -> Self {
        Grid { cell: cell.max(f64::MIN_POSITIVE), cells: HashMap::new() }
    }

    fn key(&self, x: Vec3) -> [i64; 3] {
        [(x.x / self.cell).floor() as i64, (x.y / self.cell).floor() as i64, (x.z / self.cell).floor() as i64]
    }

    pub(super) fn add(&mut self, x: Vec3, r: f64) {
        let k = self.key(x);
        self.cells.entry(k).or_default().push((x, r));
    }

    pub(super) fn overlaps(&self, x: Vec3, r: f64) -> bool {
        let k = self.key(x);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if v.iter().any(|(y, s)| (x - y).norm() < r + s) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}
