//! The wall contacts of a step: which wall elements (planes, mesh triangles) each particle is
//! within reach of, each physical contact once, with its history carried over from the last step.
//!
//! Why a contact can be found more than once: a sphere whose closest point on a mesh lies on an edge
//! or corner shared by several triangles is found by each of them at the same place
//! (`Mesh::contact`); those are merged into one record here. Why history moves between triangles:
//! a sphere rolling or sliding across the seam of two coplanar triangles keeps one contact with one
//! plane, so its tangential spring and multi-contact state go with it (LIGGGHTS does the same for
//! coplanar neighbours), instead of restarting from zero on the second triangle.

use super::contacts::{WallCandidate, WallContact};
use super::mesh::{Feature, Mesh};
use super::{WallFix, WallGeom};
use crate::physics::Vec3;

/// Per contact of the particle and mesh being collected: where on its triangle its point lies and
/// whether its record carries history from the last step. Kept between steps (no allocation).
pub(super) type GroupScratch = Vec<(Feature, bool)>;

/// What the contact search reads.
pub(super) struct Scene<'a> {
    pub walls: &'a [WallFix],
    pub meshes: &'a [Mesh],
    pub x: &'a [Vec3],
    pub radius: &'a [f64],
    /// Reach of a wall contact as a multiple of the particle radius.
    pub reach_factor: f64,
}

impl<'a> Scene<'a> {
    /// What the world's particles and walls give the search.
    pub fn of(w: &'a super::World) -> Self {
        Scene { walls: &w.walls, meshes: &w.meshes, x: &w.p.x, radius: &w.p.radius, reach_factor: w.mc_range }
    }
}

/// Fills `out` with the contacts among `cands` (in their order, which is the key order), taking
/// history from `old` (sorted by key).
pub(super) fn collect(
    s: &Scene,
    cands: &[WallCandidate],
    old: &[WallContact],
    out: &mut Vec<WallContact>,
    scratch: &mut GroupScratch,
) {
    out.clear();
    scratch.clear();
    let mut k = 0;
    let mut group = Group { prefix: (u32::MAX, u32::MAX, u32::MAX), start: 0, reordered: false };
    for c in cands {
        let (i, w) = (c.p as usize, c.wall as usize);
        let x = s.x[i];
        let reach = s.radius[i] * s.reach_factor;
        match &s.walls[w].geom {
            WallGeom::Plane(pl) => {
                let d = x[pl.axis] - pl.pos;
                if d.abs() < reach {
                    let mut point = x;
                    point[pl.axis] = pl.pos;
                    let mut fresh = WallContact::fresh(i, w, 0, 0, point, Vec3::zeros());
                    take_history(&mut fresh, old, &mut k);
                    out.push(fresh);
                }
            }
            WallGeom::Cylinder(cy) => {
                let Some(point) = cy.nearest(&x) else { continue };
                if (x - point).norm_squared() < reach * reach {
                    let mut fresh = WallContact::fresh(i, w, 0, 0, point, Vec3::zeros());
                    take_history(&mut fresh, old, &mut k);
                    out.push(fresh);
                }
            }
            WallGeom::Meshes(_) => {
                let (mi, t) = (c.mesh as usize, c.tri as usize);
                let m = &s.meshes[mi];
                if m.surely_beyond(t, &x, reach) {
                    continue;
                }
                let Some((q, feature)) = m.contact(t, &x) else { continue };
                let dist2 = (x - q).norm_squared();
                if dist2 >= reach * reach {
                    continue;
                }
                let prefix = (c.p, c.wall, c.mesh);
                if prefix != group.prefix {
                    group.finish(out);
                    group = Group { prefix, start: out.len(), reordered: false };
                    scratch.clear();
                }
                let mut fresh = WallContact::fresh(i, w, mi, t, q, m.velocity_at(t, &q));
                let had = take_history(&mut fresh, old, &mut k);
                let dist = dist2.sqrt();
                let found = &mut out[group.start..];
                match found.iter().position(|o| m.same_contact(&x, &o.point, &q, dist)) {
                    None => {
                        if !had {
                            inherit_coplanar(&mut fresh, m, old);
                        }
                        out.push(fresh);
                        scratch.push((feature, had));
                    }
                    Some(j) => {
                        // One contact found by two triangles: keep the record that carries its
                        // history (else the first), at the most exact of the two points.
                        let (kept_feature, kept_had) = scratch[j];
                        let best = kept_feature.min(feature);
                        if had && !kept_had {
                            if kept_feature < feature {
                                (fresh.point, fresh.velocity) = (found[j].point, found[j].velocity);
                            }
                            found[j] = fresh;
                            group.reordered = true;
                        } else if feature < kept_feature {
                            (found[j].point, found[j].velocity) = (q, fresh.velocity);
                        }
                        scratch[j] = (best, had || kept_had);
                    }
                }
            }
        }
    }
    group.finish(out);
}

/// The contacts of one particle with one mesh, collected together so that duplicates merge.
struct Group {
    prefix: (u32, u32, u32),
    start: usize,
    /// A merge put a later triangle's record in an earlier place: the group is re-sorted by key.
    reordered: bool,
}

impl Group {
    fn finish(&self, out: &mut [WallContact]) {
        if self.reordered {
            out[self.start..].sort_unstable_by_key(WallContact::key);
        }
    }
}

/// Copies the history of the same contact at the last step, found by key from cursor `k` on
/// (`old` is sorted by key and the keys asked for increase). Returns whether there was one.
fn take_history(c: &mut WallContact, old: &[WallContact], k: &mut usize) -> bool {
    let key = c.key();
    while *k < old.len() && old[*k].key() < key {
        *k += 1;
    }
    match old.get(*k) {
        Some(o) if o.key() == key => {
            copy_history(c, o);
            true
        }
        _ => false,
    }
}

/// A contact new to triangle `c.tri` takes over the history of the particle's contact, at the last
/// step, with a coplanar neighbour of that triangle (the lowest-numbered one if several).
fn inherit_coplanar(c: &mut WallContact, m: &Mesh, old: &[WallContact]) {
    let (lo, hi) = ((c.p, c.wall, c.mesh, 0), (c.p, c.wall, c.mesh, u32::MAX));
    let from = old.partition_point(|o| o.key() < lo);
    let to = old.partition_point(|o| o.key() <= hi);
    let nbrs = m.coplanar_neighbours(c.tri as usize);
    if let Some(o) = old[from..to].iter().find(|o| nbrs.contains(&o.tri)) {
        copy_history(c, o);
    }
}

#[inline]
fn copy_history(c: &mut WallContact, o: &WallContact) {
    c.shear = o.shear;
    c.fn_prev = o.fn_prev;
    c.rel_prev = o.rel_prev;
    c.roll = o.roll;
    // Read only between multi-contact updates (every pass sets it anew).
    c.dr = o.dr;
}
