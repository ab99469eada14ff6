//! Cell-list neighbour search: candidate pairs (i < j, sorted by i then j) whose centres are closer
//! than `factor (r_i + r_j) + skin`. Rebuilt only when some particle moved more than skin/2 since
//! the last build (LIGGGHTS `neigh_modify delay 0 check yes`), so a pair missing from the list
//! cannot touch before the next build.

use super::Domain;
use crate::physics::Vec3;

/// Reusable cell list: all buffers persist between builds, so a rebuild allocates nothing once the
/// capacities have settled.
#[derive(Debug, Default)]
pub struct CellList {
    ncell: [usize; 3],
    head: Vec<u32>,
    next: Vec<u32>,
    cell_of: Vec<u32>,
    stencil: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl CellList {
    /// Builds the sorted candidate list into `out` (cleared first). `factor` ≥ 1 widens the
    /// contact range for multi-contact radius growth.
    pub fn build(
        &mut self,
        domain: &Domain,
        x: &[Vec3],
        radius: &[f64],
        skin: f64,
        factor: f64,
        out: &mut Vec<(u32, u32)>,
    ) {
        out.clear();
        let n = x.len();
        if n < 2 {
            return;
        }
        let rmax = radius.iter().copied().fold(0.0_f64, f64::max);
        let reach = 2.0 * rmax * factor + skin;
        let len = domain.hi - domain.lo;
        for a in 0..3 {
            self.ncell[a] = ((len[a] / reach).floor().clamp(1.0, 1e6)) as usize;
        }
        // Keep the cell array small next to the particle array (tiny particles in a huge box):
        // coarser cells stay correct, they only hold more candidates.
        while self.ncell.iter().product::<usize>() > 27.max(8 * n) {
            let a = (0..3).max_by_key(|&a| self.ncell[a]).unwrap_or(0);
            self.ncell[a] = (self.ncell[a] / 2).max(1);
        }
        let [nx, ny, nz] = self.ncell;
        let le = domain.le_vjump != 0.0 || domain.le_offset != 0.0;
        let ncells = nx * ny * nz;
        self.head.clear();
        self.head.resize(ncells, NONE);
        self.next.clear();
        self.next.resize(n, NONE);
        self.cell_of.clear();
        self.cell_of.resize(n, 0);
        let cell_index = |p: &Vec3, a: usize| -> usize {
            let nc = self.ncell[a];
            let mut s = (p[a] - domain.lo[a]) / len[a];
            if domain.periodic[a] {
                s -= s.floor();
            }
            ((s * nc as f64).floor().max(0.0) as usize).min(nc - 1)
        };
        // Insert in reverse so each cell's chain runs in increasing particle index.
        for i in (0..n).rev() {
            let c = (cell_index(&x[i], 2) * ny + cell_index(&x[i], 1)) * nx + cell_index(&x[i], 0);
            self.cell_of[i] = c as u32;
            self.next[i] = self.head[c];
            self.head[c] = i as u32;
        }
        for i in 0..n {
            let c = self.cell_of[i] as usize;
            let (cx, cy, cz) = (c % nx, (c / nx) % ny, c / (nx * ny));
            self.stencil.clear();
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let wrap = |cc: usize, d: i64, nc: usize, a: usize| -> Option<usize> {
                            let v = cc as i64 + d;
                            if v < 0 || v >= nc as i64 {
                                domain.periodic[a].then(|| v.rem_euclid(nc as i64) as usize)
                            } else {
                                Some(v as usize)
                            }
                        };
                        let (Some(ox), Some(oy), Some(oz)) =
                            (wrap(cx, dx, nx, 0), wrap(cy, dy, ny, 1), wrap(cz, dz, nz, 2))
                        else {
                            continue;
                        };
                        // Across the y boundary of a Lees–Edwards box the neighbouring row is
                        // shifted in x by the offset: take the whole row (simple and correct).
                        let yw = cy as i64 + dy;
                        let sheared = le && (yw < 0 || yw >= ny as i64);
                        let xs = if sheared { 0..nx } else { ox..ox + 1 };
                        for ox in xs {
                            let o = ((oz * ny + oy) * nx + ox) as u32;
                            // Fewer than three cells along a periodic axis: the stencil wraps
                            // onto itself; visit each cell once.
                            if !self.stencil.contains(&o) {
                                self.stencil.push(o);
                            }
                        }
                    }
                }
            }
            let start = out.len();
            for &o in &self.stencil {
                let mut j = self.head[o as usize];
                while j != NONE {
                    let ju = j as usize;
                    if ju > i {
                        let mut d = x[i] - x[ju];
                        domain.minimum_image(&mut d);
                        let cut = factor * (radius[i] + radius[ju]) + skin;
                        if d.norm_squared() < cut * cut {
                            out.push((i as u32, j));
                        }
                    }
                    j = self.next[ju];
                }
            }
            out[start..].sort_unstable();
        }
    }
}
