//! The engine's part of a restart: everything a continued run needs that the deck does not define
//! again — the box, the particles in their memory order (so that every sum runs in the same order
//! after the restart), the contact histories of pairs and wall contacts, the step and the time
//! step, and when the next spatial sort is due. Plain numbers, so that the deck reader can write it
//! as JSON (the layout is in docs/dem.md); Rust prints every f64 in its shortest form that reads
//! back to the same bits, so a continued run repeats the uninterrupted one bit for bit.

use serde::{Deserialize, Serialize};

use super::contacts::{Pair, PairHist, WallContact};
use super::{Domain, World};
use crate::physics::Vec3;

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EngineState {
    pub step: u64,
    pub dt: f64,
    pub box_lo: [f64; 3],
    pub box_hi: [f64; 3],
    pub periodic: [bool; 3],
    /// Lees–Edwards image offset and velocity jump (0 without shear).
    pub le_offset: f64,
    pub le_vjump: f64,
    pub reported_box: Option<([f64; 3], [f64; 3])>,
    /// Step at or after which the next neighbour build sorts the particles.
    pub next_sort: u64,
    pub particles: ParticleState,
    /// Candidate pairs `[i, j]` (indices into the particle arrays) and their tangential springs.
    pub pairs: Vec<[u32; 2]>,
    pub pair_shear: Vec<[f64; 3]>,
    /// Per pair under the multi-contact closure: `[|F·n| of the previous step, r_i + Δ, r_j + Δ]`
    /// and whether the pair may receive multi-contact terms (empty under Hertz).
    pub pair_hist: Vec<[f64; 3]>,
    pub pair_near: Vec<bool>,
    /// Per pair under a rolling model with a spring (`epsd`, `epsd2`): the rolling spring torque
    /// (empty under the other models, and in files written before it was saved).
    #[serde(default)]
    pub pair_roll: Vec<[f64; 3]>,
    /// Particle–wall contacts: `[particle, wall fix, mesh, triangle]` and their state.
    pub wall_contacts: Vec<WallContactState>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ParticleState {
    pub id: Vec<i64>,
    /// 0-based atom type.
    pub typ: Vec<usize>,
    pub x: Vec<[f64; 3]>,
    pub v: Vec<[f64; 3]>,
    pub omega: Vec<[f64; 3]>,
    pub f: Vec<[f64; 3]>,
    pub torque: Vec<[f64; 3]>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub density: Vec<f64>,
    pub image: Vec<[i32; 3]>,
    /// Group bits ([`super::particles::Particles::mask`]); absent in files written before groups
    /// were saved, read then as `all` only.
    #[serde(default)]
    pub mask: Vec<u32>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WallContactState {
    pub key: [u32; 4],
    pub point: [f64; 3],
    pub velocity: [f64; 3],
    pub shear: [f64; 3],
    pub fn_prev: f64,
    pub rel_prev: [f64; 3],
    pub dr: f64,
    /// The rolling spring torque of `epsd`/`epsd2` (zero otherwise; absent in older files).
    #[serde(default)]
    pub roll: [f64; 3],
}

fn a3(v: &Vec3) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn v3(a: &[f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

fn vecs(v: &[Vec3]) -> Vec<[f64; 3]> {
    v.iter().map(a3).collect()
}

fn unvecs(v: &[[f64; 3]]) -> Vec<Vec3> {
    v.iter().map(v3).collect()
}

impl World {
    /// The state a restart keeps (see the module documentation). Needs the box.
    pub fn restart_state(&self) -> Result<EngineState, String> {
        let d = self.domain.ok_or("write_restart before the simulation box exists")?;
        if !self.contacts.pair_dmax.is_empty() {
            // The restart format has no field for it; a restart without it would resume every
            // contact on its loading branch.
            return Err(
                "write_restart: the contact history of model hooke/hysteresis (largest overlap per pair) is not written by mcdem restarts".into(),
            );
        }
        let p = &self.p;
        let c = &self.contacts;
        Ok(EngineState {
            step: self.step,
            dt: self.dt,
            box_lo: a3(&d.lo),
            box_hi: a3(&d.hi),
            periodic: d.periodic,
            le_offset: d.le_offset,
            le_vjump: d.le_vjump,
            reported_box: self.reported_box.map(|(lo, hi)| (a3(&lo), a3(&hi))),
            next_sort: self.lists.next_sort,
            particles: ParticleState {
                id: p.id.clone(),
                typ: p.typ.clone(),
                x: vecs(&p.x),
                v: vecs(&p.v),
                omega: vecs(&p.omega),
                f: vecs(&p.f),
                torque: vecs(&p.torque),
                radius: p.radius.clone(),
                mass: p.mass.clone(),
                density: p.density.clone(),
                image: p.image.clone(),
                mask: p.mask.clone(),
            },
            pairs: c.pairs.iter().map(|q| [q.i, q.j]).collect(),
            pair_shear: c.pairs.iter().map(|q| a3(&q.shear)).collect(),
            pair_hist: c.pair_hist.iter().map(|h| [h.fn_prev, h.ri_prev, h.rj_prev]).collect(),
            pair_near: c.pair_hist.iter().map(|h| h.near).collect(),
            pair_roll: vecs(&c.pair_roll),
            wall_contacts: c
                .wc
                .iter()
                .map(|w| WallContactState {
                    key: [w.p, w.wall, w.mesh, w.tri],
                    point: a3(&w.point),
                    velocity: a3(&w.velocity),
                    shear: a3(&w.shear),
                    fn_prev: w.fn_prev,
                    rel_prev: a3(&w.rel_prev),
                    dr: w.dr,
                    roll: a3(&w.roll),
                })
                .collect(),
        })
    }

    /// Puts a restart's state into a world that has no box and no particles yet.
    pub fn restore_state(&mut self, s: &EngineState) -> Result<(), String> {
        if self.domain.is_some() || !self.p.is_empty() {
            return Err("read_restart after the simulation box exists".into());
        }
        let q = &s.particles;
        let n = q.id.len();
        let lens = [
            q.typ.len(),
            q.x.len(),
            q.v.len(),
            q.omega.len(),
            q.f.len(),
            q.torque.len(),
            q.radius.len(),
            q.mass.len(),
            q.density.len(),
            q.image.len(),
            if q.mask.is_empty() { n } else { q.mask.len() },
        ];
        if lens.iter().any(|&l| l != n) {
            return Err(format!("the particle arrays differ in length ({n} ids, others {lens:?})"));
        }
        if s.pairs.len() != s.pair_shear.len()
            || (!s.pair_hist.is_empty() && s.pair_hist.len() != s.pairs.len())
            || s.pair_near.len() != s.pair_hist.len()
            || (!s.pair_roll.is_empty() && s.pair_roll.len() != s.pairs.len())
        {
            return Err("the pair arrays differ in length".into());
        }
        if s.pairs.iter().any(|&[i, j]| i as usize >= n || j as usize >= n)
            || s.wall_contacts.iter().any(|w| w.key[0] as usize >= n)
        {
            return Err("a contact names a particle index beyond the particles".into());
        }
        let mut d = Domain::new(v3(&s.box_lo), v3(&s.box_hi), s.periodic);
        d.le_offset = s.le_offset;
        d.le_vjump = s.le_vjump;
        self.domain = Some(d);
        self.reported_box = s.reported_box.map(|(lo, hi)| (v3(&lo), v3(&hi)));
        self.step = s.step;
        self.dt = s.dt;
        self.lists.next_sort = s.next_sort;
        let p = &mut self.p;
        p.id = q.id.clone();
        p.typ = q.typ.clone();
        p.x = unvecs(&q.x);
        p.v = unvecs(&q.v);
        p.omega = unvecs(&q.omega);
        p.f = unvecs(&q.f);
        p.torque = unvecs(&q.torque);
        p.radius = q.radius.clone();
        p.mass = q.mass.clone();
        p.density = q.density.clone();
        p.image = q.image.clone();
        p.mask = if q.mask.is_empty() { vec![super::particles::GROUP_ALL; n] } else { q.mask.clone() };
        let c = &mut self.contacts;
        c.pairs =
            s.pairs.iter().zip(&s.pair_shear).map(|(&[i, j], sh)| Pair { i, j, shear: v3(sh) }).collect();
        c.pair_hist = s
            .pair_hist
            .iter()
            .zip(&s.pair_near)
            .map(|(h, &near)| PairHist { fn_prev: h[0], ri_prev: h[1], rj_prev: h[2], near })
            .collect();
        c.pair_roll = unvecs(&s.pair_roll);
        c.wc = s
            .wall_contacts
            .iter()
            .map(|w| WallContact {
                p: w.key[0],
                wall: w.key[1],
                mesh: w.key[2],
                tri: w.key[3],
                point: v3(&w.point),
                velocity: v3(&w.velocity),
                shear: v3(&w.shear),
                fn_prev: w.fn_prev,
                rel_prev: v3(&w.rel_prev),
                dr: w.dr,
                roll: v3(&w.roll),
            })
            .collect();
        Ok(())
    }
}
