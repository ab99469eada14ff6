//! The simulation box: bounds, periodic axes and the Lees–Edwards shear of the image above it.

use crate::physics::Vec3;

/// Simulation box: bounds and which axes are periodic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    pub lo: Vec3,
    pub hi: Vec3,
    pub periodic: [bool; 3],
    /// Lees–Edwards shear (x sheared along y): x offset of the image above the box (accumulated
    /// strain × L_y, kept in [0, L_x)) and its x velocity jump γ̇ L_y. Both zero without shear.
    pub le_offset: f64,
    pub le_vjump: f64,
}

impl Domain {
    /// Box with no Lees–Edwards shear.
    pub fn new(lo: Vec3, hi: Vec3, periodic: [bool; 3]) -> Self {
        Domain { lo, hi, periodic, le_offset: 0.0, le_vjump: 0.0 }
    }

    /// Shortest periodic image of a separation vector.
    #[inline]
    pub fn minimum_image(&self, d: &mut Vec3) {
        self.minimum_image_k(d);
    }

    /// Shortest image of d = x_i − x_j; returns k, the number of box heights the image of j was
    /// moved up along y. With Lees–Edwards that image also sits k·offset further in x and moves
    /// k·γ̇L_y faster in x, so the caller adds k·le_vjump to v_j.x.
    #[inline]
    pub fn minimum_image_k(&self, d: &mut Vec3) -> f64 {
        let mut k = 0.0;
        if self.periodic[1] {
            let l = self.hi.y - self.lo.y;
            if d.y.abs() > 0.5 * l {
                k = (d.y / l).round();
                d.y -= k * l;
                d.x -= k * self.le_offset;
            }
        }
        for a in [0, 2] {
            if self.periodic[a] {
                let l = self.hi[a] - self.lo[a];
                if d[a].abs() > 0.5 * l {
                    d[a] -= l * (d[a] / l).round();
                }
            }
        }
        k
    }

    /// Advances the Lees–Edwards offset by the velocity jump over dt, kept in [0, L_x).
    pub fn advance_shear(&mut self, dt: f64) {
        if self.le_vjump != 0.0 {
            let lx = self.hi.x - self.lo.x;
            self.le_offset = (self.le_offset + self.le_vjump * dt).rem_euclid(lx);
        }
    }

    /// Streaming velocity u_x = γ̇ (y − y_mid) of the Lees–Edwards shear (zero without shear).
    #[inline]
    pub fn streaming_vx(&self, y: f64) -> f64 {
        let ly = self.hi.y - self.lo.y;
        self.le_vjump / ly * (y - 0.5 * (self.lo.y + self.hi.y))
    }

    pub fn volume(&self) -> f64 {
        let l = self.hi - self.lo;
        l.x * l.y * l.z
    }
}
