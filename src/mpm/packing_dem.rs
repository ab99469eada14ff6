//! DEM preparation of a compaction packing (Nezamabadi et al. 2019, Section 6.2: "The initial
//! configuration is prepared by means of DEM simulations").
//!
//! The discs (spheres) placed loose by random sequential addition are compressed by the box's top
//! wall (the high side of the last axis) with frictionless linear-spring contacts and viscous
//! damping, until the packing carries a small pressure at rest: it is then jammed, at the packing
//! fraction that frictionless discs of this size distribution reach. Each disc enters the DEM with
//! its radius padded by half the clearance `pad` against other discs and by the whole of it
//! against the walls (the clearances of the random placement), so that once the overlaps of the
//! padded discs (about `pressure` × d) are below half the pad the true discs neither touch one
//! another nor come within half a pad of a wall:
//! the MPM bodies start apart, as its scenes require, and the top wall is placed where the DEM
//! left it.
//!
//! Units inside: lengths over the largest padded diameter L, contact stiffness k = 1, density 1
//! (mass (r/L)^D), so that a wall pressure p (force per unit of wall length or area, in k / L^{D−2})
//! means overlaps of about p L at the wall. Only geometry leaves this module.

/// What the compression left: the discs' new centres [m], the top wall's position [m], and the
/// numbers a user needs to judge the preparation.
#[derive(Clone, Debug)]
pub struct Compressed {
    pub centres: Vec<Vec<f64>>,
    /// Final position of the top wall (high side of the last axis) [m].
    pub top: f64,
    /// Largest overlap of two padded discs or of a padded disc and a wall at the end [m]; below
    /// half the pad, so the true clearances are at least pad − 2 × this (discs) and pad − this
    /// (walls).
    pub max_overlap: f64,
    /// DEM steps taken.
    pub steps: usize,
}

/// Time step in units of 1/ω of the lightest disc on one contact (velocity Verlet is stable below
/// 2; a disc with several contacts is stiffer, up to about 2D times, hence the margin).
const DT: f64 = 0.1;
/// Damping ratio of the contact dashpots (normal relative velocity, discs and walls): a collision
/// keeps little of its energy, so a packing pushed by the wall settles without a drag on the
/// discs' absolute speed, which would resist the wall's sweep of the loose packing.
const CONTACT_DAMPING: f64 = 0.7;
/// A weak drag on the absolute velocity, in units of ω of the lightest disc: it only stops the
/// rattlers, which no contact damps.
const DRAG: f64 = 0.02;
/// Top wall displacement per step while compressing, in units of L. The wall's speed makes
/// dynamic overlaps of about its speed over ω, 10 WALL_STEP / DT = 2e-4 L here, well below the
/// overlaps of the pressures a preparation asks (1e-3 L by default), so the wall is held only
/// once the packing itself carries that pressure.
const WALL_STEP: f64 = 2e-5;
/// Below this packing fraction of the padded discs the packing cannot jam (frictionless discs
/// jam near 0.84, monodisperse 0.82), and the wall moves ten times faster.
const FAST_PHI: f64 = 0.6;
/// At rest: every disc's speed below this (units L ω), i.e. moving by under 1e-9 L per step.
const REST_SPEED: f64 = 1e-8;
/// The packing is jammed once at rest with the top wall's pressure this close to the one asked.
const PRESSURE_TOLERANCE: f64 = 0.02;
/// Steps allowed in all, a bound that a jammable packing stays far below.
const MAX_STEPS: usize = 5_000_000;

/// Compresses `discs` (centre [m], radius [m]) in the box [lo, hi] by its top wall until the
/// padded packing carries `pressure` (units above) at rest. Errors name what cannot be met.
pub fn compress<const D: usize>(
    discs: &[(Vec<f64>, f64)],
    lo: &[f64],
    hi: &[f64],
    pad: f64,
    pressure: f64,
) -> Result<Compressed, String> {
    if !(pressure.is_finite() && pressure > 0.0 && pressure < 0.05) {
        return Err(format!(
            "packing: compress.pressure must lie in (0, 0.05) (overlaps of that fraction of the largest diameter), got {pressure}"
        ));
    }
    if !(pad.is_finite() && pad > 0.0) {
        return Err(
            "packing: compress needs a positive gap (the clearance the DEM's overlaps must stay below)"
                .into(),
        );
    }
    let n = discs.len();
    let l = discs.iter().map(|d| 2.0 * d.1 + pad).fold(0.0, f64::max);
    let r: Vec<f64> = discs.iter().map(|d| (d.1 + 0.5 * pad) / l).collect();
    let wall_pad = 0.5 * pad / l;
    let m: Vec<f64> = r.iter().map(|ri| ri.powi(D as i32)).collect();
    let omega = 1.0 / m.iter().cloned().fold(f64::INFINITY, f64::min).sqrt();
    let dt = DT / omega;
    let gamma = DRAG * omega;
    let lo_s: [f64; D] = std::array::from_fn(|d| lo[d] / l);
    let mut hi_s: [f64; D] = std::array::from_fn(|d| hi[d] / l);
    let mut x: Vec<[f64; D]> = discs.iter().map(|d| std::array::from_fn(|k| d.0[k] / l)).collect();
    let mut v = vec![[0.0; D]; n];
    let mut f = vec![[0.0; D]; n];
    let top_area: f64 = (0..D - 1).map(|d| hi_s[d] - lo_s[d]).product();
    let top = D - 1;
    let r_max = r.iter().cloned().fold(0.0, f64::max);
    let mut cells = Cells::<D>::new(lo_s, 2.0 * r_max);

    let rest = REST_SPEED * omega;
    // Volume of the padded discs (2-D area, 3-D volume): the unit ball's measure times r^D, the
    // discs' masses at density 1.
    let unit_ball = if D == 2 { std::f64::consts::PI } else { 4.0 / 3.0 * std::f64::consts::PI };
    let solid: f64 = unit_ball * m.iter().sum::<f64>();
    let mut p_top = 0.0;
    let mut steps = 0;
    let mut max_overlap;
    loop {
        if steps >= MAX_STEPS {
            return Err(format!(
                "packing: the DEM compression did not come to rest at pressure {pressure} in {MAX_STEPS} steps (top wall at {:.6e} m)",
                hi_s[top] * l
            ));
        }
        steps += 1;
        // Velocity Verlet; the damping is explicit in the first half-kick and implicit in the
        // second, which keeps the scheme stable for any γ dt.
        for i in 0..n {
            for d in 0..D {
                v[i][d] += 0.5 * dt * (f[i][d] / m[i] - gamma * v[i][d]);
                x[i][d] += dt * v[i][d];
            }
        }
        // The wall is servo-controlled to the pressure: it moves in at WALL_STEP while the
        // packing carries none, and by a step proportional to the pressure's shortfall (or excess)
        // near it, so that it comes to rest where the packing carries exactly that pressure.
        let phi = solid / (hi_s[top] - lo_s[top]) / top_area;
        let fast = if phi < FAST_PHI { 10.0 } else { 1.0 };
        let wall_move = fast * WALL_STEP * ((pressure - p_top) / pressure).clamp(-1.0, 1.0);
        hi_s[top] -= wall_move;
        if hi_s[top] - lo_s[top] < 2.0 * r_max {
            return Err("packing: the DEM compression closed the box to one diameter without jamming".into());
        }
        let top_force;
        (max_overlap, top_force) = forces(&x, &v, &r, &m, wall_pad, &lo_s, &hi_s, &mut cells, &mut f);
        let mut vmax: f64 = 0.0;
        for i in 0..n {
            for d in 0..D {
                v[i][d] = (v[i][d] + 0.5 * dt * f[i][d] / m[i]) / (1.0 + 0.5 * dt * gamma);
            }
            vmax = vmax.max(v[i].iter().map(|c| c * c).sum::<f64>().sqrt());
        }
        p_top = top_force / top_area;
        if vmax < rest && (p_top - pressure).abs() <= PRESSURE_TOLERANCE * pressure {
            break; // at rest under the pressure: jammed
        }
    }
    if max_overlap * l >= 0.5 * pad {
        return Err(format!(
            "packing: the DEM's largest overlap {:.3e} m is not below half the clearance gap {pad:.3e} m: lower compress.pressure or raise gap",
            max_overlap * l
        ));
    }
    Ok(Compressed {
        centres: x.iter().map(|c| c.iter().map(|v| v * l).collect()).collect(),
        top: hi_s[top] * l,
        max_overlap: max_overlap * l,
        steps,
    })
}

/// Contact forces of the padded discs into `f` (linear springs, k = 1, and dashpots of damping
/// ratio CONTACT_DAMPING on the normal relative velocity, never pulling), through the cell list.
/// The walls count as at rest: the top wall moves by at most WALL_STEP per step, a speed far
/// below the discs' while the packing rearranges. Returns the largest overlap and the force on the
/// top wall.
#[allow(clippy::too_many_arguments)]
fn forces<const D: usize>(
    x: &[[f64; D]],
    v: &[[f64; D]],
    r: &[f64],
    m: &[f64],
    wall_pad: f64,
    lo: &[f64; D],
    hi: &[f64; D],
    cells: &mut Cells<D>,
    f: &mut [[f64; D]],
) -> (f64, f64) {
    f.iter_mut().for_each(|fi| *fi = [0.0; D]);
    let mut worst: f64 = 0.0;
    let mut top_force = 0.0;
    for i in 0..x.len() {
        let c = 2.0 * CONTACT_DAMPING * m[i].sqrt();
        for d in 0..D {
            let below = r[i] + wall_pad - (x[i][d] - lo[d]);
            if below > 0.0 {
                f[i][d] += (below - c * v[i][d]).max(0.0);
                worst = worst.max(below);
            }
            let above = r[i] + wall_pad - (hi[d] - x[i][d]);
            if above > 0.0 {
                let push = (above + c * v[i][d]).max(0.0);
                f[i][d] -= push;
                worst = worst.max(above);
                if d == D - 1 {
                    top_force += push;
                }
            }
        }
    }
    cells.fill(x);
    cells.for_each_pair(x, |i, j, dx, dist| {
        let overlap = r[i] + r[j] - dist;
        if overlap > 0.0 {
            worst = worst.max(overlap);
            let c = 2.0 * CONTACT_DAMPING * (m[i] * m[j] / (m[i] + m[j])).sqrt();
            let closing: f64 = (0..D).map(|d| (v[i][d] - v[j][d]) * dx[d] / dist).sum();
            let push = (overlap + c * closing).max(0.0);
            for d in 0..D {
                let fd = push * dx[d] / dist;
                f[i][d] -= fd;
                f[j][d] += fd;
            }
        }
    });
    (worst, top_force)
}

/// A uniform cell list of side at least one padded diameter: each pair within contact range lies
/// in the same or neighbouring cells.
struct Cells<const D: usize> {
    lo: [f64; D],
    side: f64,
    dims: [usize; D],
    head: Vec<usize>,
    next: Vec<usize>,
}

const NONE: usize = usize::MAX;

impl<const D: usize> Cells<D> {
    fn new(lo: [f64; D], side: f64) -> Self {
        Self { lo, side, dims: [1; D], head: Vec::new(), next: Vec::new() }
    }

    fn cell_of(&self, p: &[f64; D]) -> [usize; D] {
        std::array::from_fn(|d| {
            (((p[d] - self.lo[d]) / self.side).floor().max(0.0) as usize).min(self.dims[d] - 1)
        })
    }

    fn index(&self, c: &[usize; D]) -> usize {
        let mut k = 0;
        for d in (0..D).rev() {
            k = k * self.dims[d] + c[d];
        }
        k
    }

    fn fill(&mut self, x: &[[f64; D]]) {
        for d in 0..D {
            let top = x.iter().map(|p| p[d]).fold(self.lo[d], f64::max);
            self.dims[d] = ((top - self.lo[d]) / self.side).floor() as usize + 1;
        }
        self.head.clear();
        self.head.resize(self.dims.iter().product(), NONE);
        self.next.clear();
        self.next.resize(x.len(), NONE);
        for (i, p) in x.iter().enumerate() {
            let k = self.index(&self.cell_of(p));
            self.next[i] = self.head[k];
            self.head[k] = i;
        }
    }

    /// Calls `visit(i, j, x_j − x_i, |x_j − x_i|)` once for every pair closer than one cell side.
    fn for_each_pair(&self, x: &[[f64; D]], mut visit: impl FnMut(usize, usize, [f64; D], f64)) {
        for i in 0..x.len() {
            let c = self.cell_of(&x[i]);
            // The 3^D neighbour cells, each pair seen once (j > i).
            for k in 0..3usize.pow(D as u32) {
                let mut nb = [0usize; D];
                let mut ok = true;
                let mut kk = k;
                for d in 0..D {
                    let off = (kk % 3) as isize - 1;
                    kk /= 3;
                    let q = c[d] as isize + off;
                    if q < 0 || q >= self.dims[d] as isize {
                        ok = false;
                        break;
                    }
                    nb[d] = q as usize;
                }
                if !ok {
                    continue;
                }
                let mut j = self.head[self.index(&nb)];
                while j != NONE {
                    if j > i {
                        let dx: [f64; D] = std::array::from_fn(|d| x[j][d] - x[i][d]);
                        let dist = dx.iter().map(|v| v * v).sum::<f64>().sqrt();
                        if dist < self.side && dist > 0.0 {
                            visit(i, j, dx, dist);
                        }
                    }
                    j = self.next[j];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two discs stacked in a narrow box, touching the side walls at zero overlap: the servo wall
    /// stops where the column carries the pressure. Three springs in series (wall, pair, wall)
    /// carry the top force F = p W (W the box width in units of L), so the stack is shorter than
    /// its padded height 4r + 3 pad by 3 F L, to the 2 % pressure tolerance; the true discs keep
    /// their clearance pad less that pair's overlap F L.
    #[test]
    fn a_stack_of_two_discs_is_compressed_to_its_height() {
        let (r, pad, p) = (1e-3, 1e-4, 1e-3);
        let width = 2.0 * r + 2.0 * pad;
        let discs = vec![(vec![0.5 * width, 2.0e-3], r), (vec![0.5 * width, 6.0e-3], r)];
        let c = compress::<2>(&discs, &[0.0, 0.0], &[width, 10e-3], pad, p).unwrap();
        let l = 2.0 * r + pad;
        let force_l = p * width / l * l; // F L [m]
        let shortening = 4.0 * r + 3.0 * pad - c.top;
        assert!((shortening / (3.0 * force_l) - 1.0).abs() < 0.03, "{shortening} m vs {} m", 3.0 * force_l);
        let gap_between = (c.centres[1][1] - c.centres[0][1]) - 2.0 * r;
        assert!((gap_between - (pad - force_l)).abs() < 0.03 * force_l, "{gap_between}");
        assert!(c.max_overlap < 0.5 * pad);
    }

    /// A loose random packing of 40 polydisperse discs jams at a packing fraction of frictionless
    /// discs (padded): between random loose and the ordered limit, 0.75–0.90 in a small box.
    #[test]
    fn a_random_packing_jams_where_frictionless_discs_do() {
        let spec = crate::mpm::packing::PackingSpec {
            count: 40,
            diameter: [2e-3, 4e-3],
            lo: vec![0.0, 0.0],
            hi: vec![0.02, 0.04],
            gap: 5e-5,
            seed: 3,
            compress: None,
        };
        let discs = spec.discs(2).unwrap();
        let c = compress::<2>(&discs, &spec.lo, &spec.hi, spec.gap, 1e-3).unwrap();
        let area: f64 = discs.iter().map(|d| std::f64::consts::PI * (d.1 + 0.5 * spec.gap).powi(2)).sum();
        let phi = area / (0.02 * c.top);
        assert!((0.75..0.9).contains(&phi), "padded packing fraction {phi}");
        assert!(c.max_overlap < 0.5 * spec.gap);
    }
}
