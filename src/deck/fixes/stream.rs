//! `fix insert/stream` as LIGGGHTS 3.8 documents it: every K steps, particles drawn from a
//! distribution are placed at random in the slab behind a planar insertion face (a `fix
//! mesh/surface` mesh) extruded by `extrude_length` against the insertion velocity. They fly
//! with the velocity's component normal to the face, force-free and without rotation, until
//! they reach the face, where they are released with the insertion velocity (and `omega`).
//!
//! With `extrude_length`, K = ⌊L / (Δt |v_n|)⌋: one slab has crossed the face by the next
//! insertion. With `insert_every K` instead, L = duration · Δt · |v_n| (duration = K unless
//! given). Each insertion inserts ⌊rate · K · Δt + u⌋ particles (u uniform on [0, 1), so the
//! mean is exact), the rate being `particlerate` or `massrate` over the distribution's mean
//! particle mass, until `nparticles` (or `mass`) are reached.
//!
//! Templates, distributions, overlap tests and random streams are those of `insert/pack`
//! (`insert.rs`).

use std::collections::HashMap;

use super::insert_common::positive;
use crate::deck::*;
use crate::rng::SplitMix64;

/// LIGGGHTS' round-off guard in the step counts.
const TINY: f64 = 1e-14;

#[derive(Debug, Clone, Copy)]
enum Rate {
    /// Particles per second.
    Count(f64),
    /// Kilograms per second.
    Mass(f64),
}

#[derive(Debug, Clone, Copy)]
enum Total {
    Count(usize),
    Mass(f64),
    Unlimited,
}

/// What a restart file keeps of a `fix insert/stream`. LIGGGHTS restores an insertion fix's
/// state when the continuing deck defines one with the same ID (`Resetting global state of Fix …
/// from restart file info`); so does mcdem: the next insertion step, the insertions and particles
/// done (the `nparticles` budget continues), and the particles still flying towards the face.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(in crate::deck) struct StreamState {
    fix: String,
    due: u64,
    round: u64,
    inserted: usize,
    /// Particles in flight: id, insertion point, insertion step, release step.
    flying: Vec<(i64, [f64; 3], u64, u64)>,
}

/// A particle still flying towards the face: where and when it was inserted, when it is
/// released.
#[derive(Debug, Clone)]
struct Flight {
    id: i64,
    x0: Vec3,
    inserted: u64,
    release: u64,
}

#[derive(Debug, Clone)]
pub(in crate::deck) struct Stream {
    label: String,
    pub(super) fix: String,
    /// The mask bit of the fix's group, which its particles join.
    bit: u32,
    seed: u64,
    dist: String,
    /// Insertions done so far: each draws from its own random stream.
    round: u64,
    total: Total,
    rate: Rate,
    every: Option<u64>,
    duration: Option<u64>,
    extrude: Option<f64>,
    overlap: bool,
    exact: bool,
    maxattempt: usize,
    vel: Vec3,
    omega: Vec3,
    /// Index of the face mesh in `World::meshes`.
    face: usize,
    /// Step of the next insertion.
    due: u64,
    inserted: usize,
    /// The flight velocity (`vel` projected on the face normal), set at each insertion.
    vn: Vec3,
    flying: Vec<Flight>,
}

/// What an insertion needs from the face, the velocity and Δt.
struct Geometry {
    every: u64,
    extrude: f64,
    /// Unit face normal along the velocity.
    normal: Vec3,
    /// Velocity component along `normal` (the flight velocity).
    vn: Vec3,
    /// A point of the face.
    p_ref: Vec3,
    /// Cumulative triangle areas (for area-weighted picks).
    cum: Vec<f64>,
}

impl Stream {
    pub(in crate::deck) fn state(&self) -> StreamState {
        StreamState {
            fix: self.fix.clone(),
            due: self.due,
            round: self.round,
            inserted: self.inserted,
            flying: self
                .flying
                .iter()
                .map(|f| (f.id, [f.x0.x, f.x0.y, f.x0.z], f.inserted, f.release))
                .collect(),
        }
    }

    /// `reset_timestep`: the next insertion and the flights' steps moved by `shift`.
    pub(super) fn shift_steps(&mut self, shift: &dyn Fn(u64) -> u64) {
        self.due = shift(self.due);
        for f in &mut self.flying {
            (f.inserted, f.release) = (shift(f.inserted), shift(f.release));
        }
    }
}

impl Deck {
    /// `fix ID group insert/stream seed S distributiontemplate D nparticles N|INF (or mass M)
    /// massrate|particlerate R vel constant VX VY VZ insertion_face MESH extrude_length L
    /// (or insert_every K [duration D]) [overlapcheck yes|no] [all_in no] [maxattempt M]
    /// [omega constant WX WY WZ] [random_distribute exact|uncorrelated]`.
    pub(in crate::deck) fn insert_stream(&mut self, a: &[&str]) -> R<FixKind> {
        let what = format!("fix {} insert/stream", a[1]);
        let label = format!("{what} (line {})", self.line_no);
        let (mut total, mut rate, mut face) = (None, None, None);
        let (mut every, mut duration, mut extrude) = (None, None, None);
        let (mut overlap, mut maxattempt) = (true, 50usize);
        let steps = |v: &str, key: &str| -> R<u64> {
            match int(v) {
                Ok(n) if n >= 1 => Ok(n as u64),
                _ => Err(format!("{what}: {key} must be a whole number >= 1, got '{v}'")),
            }
        };
        let common = self.insert_keywords(a, &what, |key, v| {
            match key {
                "nparticles" if v == "INF" => total = Some(Total::Unlimited),
                "nparticles" => total = Some(Total::Count(steps(v, "nparticles")? as usize)),
                "mass" => total = Some(Total::Mass(positive(v, &format!("{what}: mass"))?)),
                "particlerate" => rate = Some(Rate::Count(positive(v, &format!("{what}: particlerate"))?)),
                "massrate" => rate = Some(Rate::Mass(positive(v, &format!("{what}: massrate"))?)),
                "insert_every" => every = Some(steps(v, "insert_every")?),
                "duration" => duration = Some(steps(v, "duration")?),
                "extrude_length" => {
                    let l = num(v)?;
                    if !(l > 0.0 && l.is_finite()) {
                        return Err(format!("{what}: extrude_length must be > 0, got {v}"));
                    }
                    extrude = Some(l);
                }
                "insertion_face" => {
                    face = Some(self.mesh_index(v).map_err(|e| format!("{what}: insertion_face: {e}"))?)
                }
                "overlapcheck" => {
                    overlap = match v {
                        "yes" => true,
                        "no" => false,
                        _ => return Err(format!("{what}: overlapcheck must be yes or no, got '{v}'")),
                    }
                }
                "all_in" if v == "no" => {}
                // LIGGGHTS wants a mesh/surface/planar face for all_in yes.
                "all_in" => {
                    return Err(unsupported(&format!(
                        "{what}: all_in {v} (only no with a mesh/surface face)"
                    )))
                }
                "maxattempt" => maxattempt = steps(v, "maxattempt")? as usize,
                "verbose" if v == "yes" || v == "no" => {}
                other => return Err(unsupported(&format!("{what} keyword {other} {v}"))),
            }
            Ok(())
        })?;
        let vel = common.vel.ok_or_else(|| format!("{what}: vel constant VX VY VZ is required"))?;
        if vel.norm() < 1e-5 {
            return Err(format!("{what}: insertion velocity too low (|vel| < 1e-5)"));
        }
        match (every, extrude) {
            (None, None) => {
                return Err(format!("{what}: one of insert_every and extrude_length is required"))
            }
            (Some(_), Some(_)) => {
                return Err(format!("{what}: insert_every and extrude_length exclude each other"))
            }
            _ => {}
        }
        if let (Some(d), Some(e)) = (duration, every) {
            if d > e {
                return Err(format!("{what}: duration {d} > insert_every {e}"));
            }
        }
        if duration.is_some() && every.is_none() {
            return Err(format!("{what}: duration needs insert_every (not extrude_length)"));
        }
        let stream = Stream {
            label,
            fix: a[1].to_string(),
            bit: self.groups.bit(a[2], &what)?,
            seed: common.seed.ok_or_else(|| format!("{what}: seed is required"))?,
            dist: common.dist.ok_or_else(|| format!("{what}: distributiontemplate is required"))?,
            round: 0,
            total: total.ok_or_else(|| format!("{what}: nparticles or mass is required"))?,
            rate: rate.ok_or_else(|| format!("{what}: massrate or particlerate is required"))?,
            every,
            duration,
            extrude,
            overlap,
            exact: common.exact,
            maxattempt,
            vel,
            omega: common.omega,
            face: face.ok_or_else(|| format!("{what}: insertion_face is required"))?,
            // As LIGGGHTS: first on the step after the definition.
            due: self.world.step + 1,
            inserted: 0,
            vn: Vec3::zeros(),
            flying: Vec::new(),
        };
        self.insertion.check_distinct_seed(&what, stream.seed, &stream.dist)?;
        let g = self.geometry(&stream).map_err(|e| format!("{what}: {e}"))?;
        let mut stream = stream;
        if let Some(k) = self.insertion.restored.iter().position(|r| r.fix == stream.fix) {
            let r = self.insertion.restored.remove(k);
            if let Some(&(id, ..)) = r.flying.iter().find(|f| !self.world.p.id.contains(&f.0)) {
                return Err(format!(
                    "{what}: the restart's particle {id} in flight is not among the particles"
                ));
            }
            (stream.due, stream.round, stream.inserted, stream.vn) = (r.due, r.round, r.inserted, g.vn);
            stream.flying = r
                .flying
                .iter()
                .map(|&(id, x, inserted, release)| Flight {
                    id,
                    x0: Vec3::new(x[0], x[1], x[2]),
                    inserted,
                    release,
                })
                .collect();
            self.say(&format!(
                "INFO: {what}: continues from the restart file: {} particles inserted, {} in flight, next insertion at step {}",
                stream.inserted,
                stream.flying.len(),
                stream.due
            ));
        }
        self.insertion.streams.push(stream);
        Ok(FixKind::Insert)
    }

    /// Face normal, flight velocity, K and L from the face, the velocity and the current Δt.
    fn geometry(&self, s: &Stream) -> R<Geometry> {
        if self.fixes.iter().any(|(_, k)| matches!(k, FixKind::MoveMesh(m) if *m == s.face)) {
            return Err("the insertion face is under a fix move/mesh (LIGGGHTS refuses a moving face)".into());
        }
        let mesh = &self.world.meshes[s.face];
        let t0 = mesh.tris.first().ok_or("the insertion face has no triangle")?;
        let n0 = (t0.v[1] - t0.v[0]).cross(&(t0.v[2] - t0.v[0]));
        let mut normal = n0.normalize();
        let size = mesh.tris.iter().flat_map(|t| t.v).map(|x| (x - t0.v[0]).norm()).fold(0.0, f64::max);
        let planar = mesh.tris.iter().all(|t| {
            let n = (t.v[1] - t.v[0]).cross(&(t.v[2] - t.v[0])).normalize();
            n.cross(&normal).norm() < 1e-6
                && t.v.iter().all(|x| (x - t0.v[0]).dot(&normal).abs() <= 1e-9 * size)
        });
        if !planar {
            return Err("the insertion face must be planar".into());
        }
        if s.vel.dot(&normal) < 0.0 {
            normal = -normal;
        }
        let vn = normal * s.vel.dot(&normal);
        if vn.norm() < 1e-3 {
            return Err("insertion velocity projected on the face normal is < 1e-3".into());
        }
        let dt = self.world.dt;
        let rmax = self.distribution_max_radius(&s.dist);
        let (every, extrude) = match (s.every, s.extrude) {
            (_, Some(l)) => {
                if l < 3.0 * rmax {
                    return Err(format!("extrude_length {l} is below 3 particle radii ({})", 3.0 * rmax));
                }
                let k = ((l + TINY) / (dt * vn.norm())) as u64;
                if k == 0 {
                    return Err("insertion velocity too high or extrude_length too low".into());
                }
                (k, l)
            }
            (Some(k), None) => {
                let l = s.duration.unwrap_or(k) as f64 * dt * vn.norm();
                if l < 3.0 * rmax {
                    return Err(format!(
                        "insert_every or vel is too small, or the particles too large: the extruded length {l} is below 3 radii ({})",
                        3.0 * rmax
                    ));
                }
                (k, l)
            }
            (None, None) => unreachable!("checked at the fix"),
        };
        let mut cum = Vec::with_capacity(mesh.tris.len());
        let mut acc = 0.0;
        for t in &mesh.tris {
            acc += 0.5 * (t.v[1] - t.v[0]).cross(&(t.v[2] - t.v[0])).norm();
            cum.push(acc);
        }
        Ok(Geometry { every, extrude, normal, vn, p_ref: t0.v[0], cum })
    }

    /// The `insert/stream` insertions due before the coming step; whether any particle came.
    pub(super) fn stream_due(&mut self) -> R<bool> {
        let next = self.world.step + 1;
        let mut added = false;
        for k in 0..self.insertion.streams.len() {
            if self.insertion.streams[k].due > next {
                continue;
            }
            let s = self.insertion.streams[k].clone();
            let g = self.geometry(&s).map_err(|e| format!("{}: {e}", s.label))?;
            let (n, flights) = self.stream_insert(&s, &g, next)?;
            if n > 0 {
                self.say(&format!("INFO: {}: inserted {n} particles at step {next}", s.label));
            }
            added |= n > 0;
            let s = &mut self.insertion.streams[k];
            s.round += 1;
            s.inserted += n;
            s.flying.extend(flights);
            s.vn = g.vn;
            s.due = next + g.every;
        }
        Ok(added)
    }

    fn stream_insert(&mut self, s: &Stream, g: &Geometry, step: u64) -> R<(usize, Vec<Flight>)> {
        let dom = self.world.domain.ok_or("insertion before the simulation box exists")?;
        let (_, mean_mass) = self.distribution_means(&s.dist);
        let nrate = match s.rate {
            Rate::Count(r) => r,
            Rate::Mass(m) => m / mean_mass,
        };
        let per = nrate * g.every as f64 * self.world.dt;
        // Round 0 keeps the streams of a single insertion; later rounds draw new ones.
        let seed = crate::rng::mix_seed(s.seed, s.round);
        let mut rng = SplitMix64(seed);
        let mut n = (per + rng.uniform()) as usize;
        let left = match s.total {
            Total::Count(m) => m.saturating_sub(s.inserted),
            Total::Mass(m) => (((m + TINY) / mean_mass) as usize).saturating_sub(s.inserted),
            Total::Unlimited => usize::MAX,
        };
        n = n.min(left);
        if n == 0 {
            return Ok((0, Vec::new()));
        }
        let (templates, new) = self.draw_batch(&s.dist, n, seed, s.exact);
        let mut grid = self.occupied(&new);
        let mesh = &self.world.meshes[s.face];
        let tris: Vec<[Vec3; 3]> = mesh.tris.iter().map(|t| t.v).collect();
        let area = *g.cum.last().unwrap_or(&0.0);
        let inside = |x: &Vec3, r: f64| (0..3).all(|k| x[k] - r >= dom.lo[k] && x[k] + r <= dom.hi[k]);
        // One budget of tries for the whole insertion, as LIGGGHTS.
        let (mut tries, budget) = (0usize, n * s.maxattempt);
        let mut flights = Vec::with_capacity(n);
        let speed = g.vn.norm();
        for &(r, j) in &new {
            let mut at = None;
            while at.is_none() && tries < budget {
                tries += 1;
                let u = rng.uniform() * area;
                let t = &tris[g.cum.iter().position(|&c| u < c).unwrap_or(tris.len() - 1)];
                let (mut a, mut b) = (rng.uniform(), rng.uniform());
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                let on_face = t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b;
                // Behind the face by r … L + r with the overlap check, r … L − r without.
                let depth = if s.overlap {
                    rng.uniform() * g.extrude + r
                } else {
                    rng.uniform() * (g.extrude - 2.0 * r) + r
                };
                let x = on_face - g.normal * depth;
                if inside(&x, r) && !(s.overlap && grid.overlaps(x, r)) {
                    at = Some(x);
                }
            }
            let Some(x) = at else { break };
            grid.add(x, r);
            let i = self.add_inserted(&templates[j], x, r, g.vn, Vec3::zeros());
            self.world.p.mask[i] |= s.bit;
            let depth = (g.p_ref - x).dot(&g.normal);
            let release = step + ((depth + TINY) / (speed * self.world.dt)) as u64;
            flights.push(Flight { id: self.world.p.id[i], x0: x, inserted: step, release });
        }
        if flights.len() < n {
            self.warn(&format!(
                "{}: Less insertions than requested: {} of {n} at step {step} ({} random tries)",
                s.label,
                flights.len(),
                budget
            ));
        }
        Ok((flights.len(), flights))
    }

    /// After each step: particles still behind the face move on at the flight velocity, free of
    /// force and rotation; on their release step they take the insertion velocity and `omega`.
    pub(in crate::deck) fn stream_release(&mut self) {
        if self.insertion.streams.iter().all(|s| s.flying.is_empty()) {
            return;
        }
        let step = self.world.step;
        let dt = self.world.dt;
        let p = &mut self.world.p;
        // Rebuilding the ID map every step cost a third of a streaming run: it is rebuilt only
        // when a flying particle's entry is stale.
        let index = &mut self.insertion.id_index;
        let valid =
            |index: &HashMap<i64, usize>, id: i64| index.get(&id).is_some_and(|&i| p.id.get(i) == Some(&id));
        if !self.insertion.streams.iter().flat_map(|s| &s.flying).all(|f| valid(index, f.id)) {
            index.clear();
            index.extend(p.id.iter().enumerate().map(|(i, &id)| (id, i)));
        }
        let index = &*index;
        for s in &mut self.insertion.streams {
            let vn = s.vn;
            s.flying.retain(|f| {
                let Some(&i) = index.get(&f.id) else { return false };
                p.x[i] = f.x0 + vn * ((step - f.inserted) as f64 * dt);
                p.f[i] = Vec3::zeros();
                p.torque[i] = Vec3::zeros();
                if step >= f.release {
                    p.v[i] = s.vel;
                    p.omega[i] = s.omega;
                    false
                } else {
                    p.v[i] = vn;
                    p.omega[i] = Vec3::zeros();
                    true
                }
            });
        }
    }
}
