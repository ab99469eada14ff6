//! Contact geometry, the Hertz law P(δ) and the residual of force balance and nonlocal relation
//! with its exact Jacobian (the equations in the module documentation of `solver`).

use faer::sparse::Triplet;

use super::{Contact, Eval, Geo, Nonlocal, Other, FORCE_FLOOR};
use crate::physics::material::PairCoeffs;
use crate::physics::Vec3;

impl Nonlocal {
    pub(super) fn force_unit(&self) -> f64 {
        self.e_ref * self.len * self.len
    }

    /// (4/3) E* √R* for a new contact (scaled), E* from [`PairCoeffs`] (Eq. C.3).
    pub(super) fn stiffness(&self, i: usize, other: Other) -> f64 {
        let (mj, rstar) = match other {
            Other::Particle(j) => (self.mats[j], self.r[i] * self.r[j] / (self.r[i] + self.r[j])),
            Other::Wall(_) => (self.wall_material, self.r[i]),
        };
        // Restitution 1 and friction 0 are placeholders: only E* is read.
        let e_star = PairCoeffs::new(&self.mats[i], &mj, 1.0, 0.0).map(|c| c.e_star).unwrap_or(f64::NAN);
        4.0 / 3.0 * e_star / self.e_ref * rstar.sqrt()
    }

    pub(super) fn geometry(&self, x: &[Vec3], i: usize, other: Other) -> Geo {
        match other {
            Other::Particle(j) => {
                let v = x[j] - x[i];
                let d = v.norm();
                Geo { e: v / d, d, gamma: self.r[i] + self.r[j] - d }
            }
            Other::Wall(w) => {
                let wall = &self.walls[w];
                Geo {
                    e: -wall.normal,
                    d: f64::INFINITY,
                    gamma: self.r[i] - (x[i] - wall.point).dot(&wall.normal),
                }
            }
        }
    }

    /// Hertz P(δ) = K max(δ, 0)^{3/2} and dP/dδ (Hertz, Eq. 5 static part). C¹ at δ = 0, so a
    /// contact that opens during the iterations simply stops carrying force (no artificial tension)
    /// while its relation row keeps tracking the gap, and it re-engages if the gap closes again.
    #[inline]
    pub(super) fn force_of(c: &Contact, delta: f64) -> (f64, f64) {
        if delta <= 0.0 {
            return (0.0, 0.0);
        }
        let s = delta.sqrt();
        (c.k * delta * s, 1.5 * c.k * s)
    }

    /// Per particle: (contact index, sign) with e_sc = sign · e_c.
    pub(super) fn adjacency(&self) -> Vec<Vec<(usize, f64)>> {
        let mut adj = vec![Vec::new(); self.x.len()];
        for (c, ct) in self.contacts.iter().enumerate() {
            adj[ct.i].push((c, 1.0));
            if let Other::Particle(j) = ct.other {
                adj[j].push((c, -1.0));
            }
        }
        adj
    }

    pub(super) fn other_particle(ct: &Contact, side: f64) -> Option<usize> {
        if side > 0.0 {
            match ct.other {
                Other::Particle(j) => Some(j),
                Other::Wall(_) => None,
            }
        } else {
            Some(ct.i)
        }
    }

    /// Residual (and Jacobian triplets) of the current active set at centres `x`, overlaps `delta`.
    pub(super) fn evaluate(
        &self,
        x: &[Vec3],
        delta: &[f64],
        adj: &[Vec<(usize, f64)>],
        jac: bool,
        shift: f64,
    ) -> Eval {
        let n = x.len();
        let nc = self.contacts.len();
        let row_c = |c: usize| 3 * n + c;
        let mut res = vec![0.0; 3 * n + nc];
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut push = |r: usize, c: usize, v: f64| {
            if jac && v != 0.0 {
                trip.push(Triplet::new(r, c, v));
            }
        };
        let geo: Vec<Geo> = self.contacts.iter().map(|c| self.geometry(x, c.i, c.other)).collect();
        let pf: Vec<(f64, f64)> =
            self.contacts.iter().zip(delta).map(|(c, &d)| Self::force_of(c, d)).collect();

        if self.body_factor != 0.0 {
            for (i, b) in self.body.iter().enumerate() {
                for a in 0..3 {
                    res[3 * i + a] += self.body_factor * b[a];
                }
            }
        }
        let mut k_sum = 0.0;
        for (c, ct) in self.contacts.iter().enumerate() {
            let (p, dp) = pf[c];
            let g = &geo[c];
            k_sum += dp;
            // Force on i is −P e, on j +P e.
            for a in 0..3 {
                res[3 * ct.i + a] -= p * g.e[a];
            }
            res[row_c(c)] += g.gamma - delta[c];
            for a in 0..3 {
                push(3 * ct.i + a, row_c(c), -dp * g.e[a]);
                // ∂γ/∂x_i = e_ic.
                push(row_c(c), 3 * ct.i + a, g.e[a]);
            }
            push(row_c(c), row_c(c), -1.0);
            if let Other::Particle(j) = ct.other {
                for a in 0..3 {
                    res[3 * j + a] += p * g.e[a];
                    push(3 * j + a, row_c(c), dp * g.e[a]);
                    push(row_c(c), 3 * j + a, -g.e[a]);
                }
                // ∂e/∂x_j = T/d, ∂e/∂x_i = −T/d with T = I − e eᵀ.
                if jac {
                    let t = (nalgebra::Matrix3::identity() - g.e * g.e.transpose()) * (p / g.d);
                    for a in 0..3 {
                        for b in 0..3 {
                            let v = t[(a, b)];
                            push(3 * ct.i + a, 3 * j + b, -v);
                            push(3 * ct.i + a, 3 * ct.i + b, v);
                            push(3 * j + a, 3 * j + b, v);
                            push(3 * j + a, 3 * ct.i + b, -v);
                        }
                    }
                }
            }
        }

        // Nonlocal terms: for particle s, the load at b moves the surface at a.
        if !self.kernel.is_zero() {
            // G(μ) of each pair once (μ is symmetric in the pair); the derivative only with the
            // Jacobian.
            let mut gvals: Vec<(f64, f64)> = Vec::new();
            for (s, list) in adj.iter().enumerate() {
                let z = list.len();
                gvals.clear();
                gvals.resize(z * z, (0.0, 0.0));
                for p in 0..z {
                    let ep = geo[list[p].0].e * list[p].1;
                    for q in p + 1..z {
                        let mu = ep.dot(&(geo[list[q].0].e * list[q].1));
                        let v = if jac { self.bound[s].eval(mu) } else { (self.bound[s].value(mu), 0.0) };
                        gvals[p * z + q] = v;
                        gvals[q * z + p] = v;
                    }
                }
                for (p, &(a, sa)) in list.iter().enumerate() {
                    let ea = geo[a].e * sa;
                    for (q, &(b, sb)) in list.iter().enumerate() {
                        if a == b {
                            continue;
                        }
                        let eb = geo[b].e * sb;
                        let mu = ea.dot(&eb);
                        let (gk, dgk) = gvals[p * z + q];
                        let (pb, dpb) = pf[b];
                        res[row_c(a)] -= gk * pb;
                        push(row_c(a), row_c(b), -gk * dpb);
                        if jac && dgk != 0.0 {
                            let coef = -dgk * pb;
                            // ∂μ/∂x: direction a moves with s and its partner, direction b likewise;
                            // T_a e_b = e_b − μ e_a.
                            if geo[a].d.is_finite() {
                                let v = (eb - ea * mu) * (coef / geo[a].d);
                                let oa = Self::other_particle(&self.contacts[a], sa).unwrap_or(s);
                                for q in 0..3 {
                                    push(row_c(a), 3 * s + q, -v[q]);
                                    push(row_c(a), 3 * oa + q, v[q]);
                                }
                            }
                            if geo[b].d.is_finite() {
                                let v = (ea - eb * mu) * (coef / geo[b].d);
                                let ob = Self::other_particle(&self.contacts[b], sb).unwrap_or(s);
                                for q in 0..3 {
                                    push(row_c(a), 3 * s + q, -v[q]);
                                    push(row_c(a), 3 * ob + q, v[q]);
                                }
                            }
                        }
                    }
                }
            }
        }

        // Tether of the rigid-body modes (Jacobian only).
        if jac {
            let k_ref = if nc > 0 && k_sum > 0.0 { k_sum / nc as f64 } else { 1.0 };
            let eps = (self.settings.regularisation + shift) * k_ref;
            for i in 0..3 * n {
                push(i, i, -eps);
            }
        }

        let p_mean = {
            let (sum, cnt) =
                pf.iter().filter(|p| p.0 > 0.0).fold((0.0, 0usize), |(s, k), p| (s + p.0, k + 1));
            // Forces below FORCE_FLOOR (scaled units) are round-off level: without a floor a lone
            // vanishing contact would be judged relative to itself.
            if cnt > 0 {
                (sum / cnt as f64).max(FORCE_FLOOR)
            } else {
                1.0
            }
        };
        let mut force_max = 0.0;
        let mut worst = 0;
        for i in 0..n {
            let f = (res[3 * i].powi(2) + res[3 * i + 1].powi(2) + res[3 * i + 2].powi(2)).sqrt();
            if f > force_max || f.is_nan() {
                force_max = f;
                worst = i;
            }
        }
        let relation_rel = res[3 * n..].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        Eval { res, trip, force_rel: force_max / p_mean, relation_rel, worst, p_mean }
    }

    pub(super) fn merit(r: &[f64]) -> f64 {
        r.iter().map(|v| v * v).sum::<f64>()
    }
}
