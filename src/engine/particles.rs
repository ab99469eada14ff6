//! Per-particle state as a struct of arrays, and the sphere's mass and inertia.

use crate::physics::Vec3;

/// Moment of inertia prefactor of a solid sphere, I = 0.4 m r² (as LIGGGHTS `nve/sphere`).
pub(super) const INERTIA: f64 = 0.4;

/// Per-particle state, struct of arrays. Indices change only when [`World::sort_every`] asks for
/// spatial sorting (then at neighbour builds); everything keyed by index is remapped with them,
/// and ids never change.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    pub id: Vec<i64>,
    /// Atom type, 0-based.
    pub typ: Vec<usize>,
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub omega: Vec<Vec3>,
    pub f: Vec<Vec3>,
    pub torque: Vec<Vec3>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub density: Vec<f64>,
    /// Periodic image counts (LAMMPS ix iy iz).
    pub image: Vec<[i32; 3]>,
    /// Group membership, one bit per group as in LAMMPS' `atom->mask`: bit 0 is `all` (every
    /// particle has it), the deck's groups take the next bits in the order they are defined.
    pub mask: Vec<u32>,
}

/// The mask bit of group `all`.
pub const GROUP_ALL: u32 = 1;

impl Particles {
    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a sphere; mass from the density as LIGGGHTS `atom_style sphere` does.
    pub fn push(&mut self, id: i64, typ: usize, x: Vec3, diameter: f64, density: f64) {
        let r = 0.5 * diameter;
        self.id.push(id);
        self.typ.push(typ);
        self.x.push(x);
        self.v.push(Vec3::zeros());
        self.omega.push(Vec3::zeros());
        self.f.push(Vec3::zeros());
        self.torque.push(Vec3::zeros());
        self.radius.push(r);
        self.mass.push(sphere_mass(r, density));
        self.density.push(density);
        self.image.push([0; 3]);
        self.mask.push(GROUP_ALL);
    }

    /// Recomputes the mass of particle `i` after a diameter or density change.
    pub fn set_size(&mut self, i: usize, diameter: Option<f64>, density: Option<f64>) {
        if let Some(d) = diameter {
            self.radius[i] = 0.5 * d;
        }
        if let Some(rho) = density {
            self.density[i] = rho;
        }
        self.mass[i] = sphere_mass(self.radius[i], self.density[i]);
    }

    /// Sets the diameter of particle `i` and rescales its mass so that its density stays, as
    /// LIGGGHTS 3.8 `fix adapt ... atom diameter` does (`src/fix_adapt.cpp`, `change_settings`):
    /// the density is taken from the current mass and radius, ρ = m / (4/3 π r³), and the new
    /// mass is 4/3 π r'³ ρ.
    pub fn set_diameter_keep_density(&mut self, i: usize, diameter: f64) {
        let rho = self.mass[i] / sphere_mass(self.radius[i], 1.0);
        self.radius[i] = 0.5 * diameter;
        self.density[i] = rho;
        self.mass[i] = sphere_mass(self.radius[i], rho);
    }
}

impl Particles {
    /// Reorders every array: the particle at old index `old_of_new[k]` moves to index k.
    pub(super) fn permute(&mut self, old_of_new: &[u32]) {
        fn gather<T: Copy>(v: &mut Vec<T>, old_of_new: &[u32]) {
            // One fresh array per field and sort: sorts are rare (every `sort_every` steps at a
            // neighbour build), so this stays out of the step loop's cost.
            let out: Vec<T> = old_of_new.iter().map(|&o| v[o as usize]).collect();
            *v = out;
        }
        gather(&mut self.id, old_of_new);
        gather(&mut self.typ, old_of_new);
        gather(&mut self.x, old_of_new);
        gather(&mut self.v, old_of_new);
        gather(&mut self.omega, old_of_new);
        gather(&mut self.f, old_of_new);
        gather(&mut self.torque, old_of_new);
        gather(&mut self.radius, old_of_new);
        gather(&mut self.mass, old_of_new);
        gather(&mut self.density, old_of_new);
        gather(&mut self.image, old_of_new);
        gather(&mut self.mask, old_of_new);
    }
}

pub(super) fn sphere_mass(r: f64, density: f64) -> f64 {
    if r == 0.0 {
        density
    } else {
        4.0 * std::f64::consts::PI / 3.0 * r * r * r * density
    }
}
