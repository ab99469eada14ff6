//! Constitutive pieces of the finite-element reference, as functions of the deformation gradient F
//! with their first and second derivatives with respect to F (index pair (i, J) flattened to 3i + J).
//!
//! The element (`element.rs`) assembles the strain energy from these pieces so that the volumetric
//! part can be evaluated on the element's mean dilatation (locking remedy) while the rest stays at
//! the Gauss point. Both laws are written so that, evaluated at one Gauss point without the
//! remedy, they are exactly the textbook energies:
//!
//! * compressible Neo-Hookean (Bonet & Wood, *Nonlinear continuum mechanics for finite element
//!   analysis*, 2nd ed., Eq. 6.27): W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)², rewritten with the
//!   isochoric invariant Ī₁ = J^{-2/3} I₁ as W = μ/2 (J^{2/3} Ī₁ − 3) + U(J),
//!   U(J) = −μ ln J + λ/2 (ln J)²;
//! * linear elasticity (small strain ε = sym(F) − I): W = μ ε:ε + λ/2 (tr ε)², rewritten as
//!   W = μ ε_dev:ε_dev + K/2 (tr ε)² with K = λ + 2μ/3.

/// A 3×3 matrix, row-major.
pub type M3 = [[f64; 3]; 3];
/// A fourth-order tensor ∂²f/∂F_iJ ∂F_kL as a 9×9 matrix on (3i + J, 3k + L).
pub type H9 = [[f64; 9]; 9];

/// Lamé constants from Young's modulus and Poisson's ratio (small-strain identification, which
/// both laws share: the Neo-Hookean law linearises to Hooke's law with the same μ and λ).
#[derive(Clone, Copy, Debug)]
pub struct Lame {
    pub mu: f64,
    pub lambda: f64,
}

impl Lame {
    /// μ = E / (2(1 + ν)), λ = E ν / ((1 + ν)(1 − 2ν)); ν must be below 1/2.
    pub fn from_e_nu(e: f64, nu: f64) -> Self {
        Lame { mu: e / (2.0 * (1.0 + nu)), lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)) }
    }
    /// Bulk modulus K = λ + 2μ/3.
    pub fn bulk(&self) -> f64 {
        self.lambda + 2.0 * self.mu / 3.0
    }
}

/// Levi-Civita symbol.
#[inline]
fn eps(i: usize, j: usize, k: usize) -> f64 {
    if i == j || j == k || i == k {
        0.0
    } else if (i, j, k) == (0, 1, 2) || (i, j, k) == (1, 2, 0) || (i, j, k) == (2, 0, 1) {
        1.0
    } else {
        -1.0
    }
}

/// J = det F, ∂J/∂F = cof F, and ∂²J/∂F_iJ∂F_kL = ε_ikm ε_JLN F_mN (from
/// J = ε_ikm ε_JLN F_iJ F_kL F_mN / 6; polynomial, so valid for any F).
pub fn det_derivs(f: &M3) -> (f64, M3, H9) {
    let mut cof = [[0.0; 3]; 3];
    let mut h = [[0.0; 9]; 9];
    for i in 0..3 {
        for jj in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    let mut s = 0.0;
                    for m in 0..3 {
                        let a = eps(i, k, m);
                        if a == 0.0 {
                            continue;
                        }
                        for n in 0..3 {
                            s += a * eps(jj, l, n) * f[m][n];
                        }
                    }
                    h[3 * i + jj][3 * k + l] = s;
                }
            }
            // cof_iJ = ½ ε_ikm ε_JLN F_kL F_mN = ½ Σ_kL H[iJ][kL] F_kL
            let mut c = 0.0;
            for k in 0..3 {
                for l in 0..3 {
                    c += h[3 * i + jj][3 * k + l] * f[k][l];
                }
            }
            cof[i][jj] = 0.5 * c;
        }
    }
    let j = f[0][0] * cof[0][0] + f[0][1] * cof[0][1] + f[0][2] * cof[0][2];
    (j, cof, h)
}

/// Ī₁ = J^{-2/3} tr(FᵀF) and its derivatives, given J and its derivatives (J > 0).
pub fn iso_i1_derivs(f: &M3, j: f64, dj: &M3, d2j: &H9) -> (f64, M3, H9) {
    let i1: f64 = f.iter().flatten().map(|x| x * x).sum();
    let a = j.powf(-2.0 / 3.0);
    let a1 = -2.0 / 3.0 * a / j; // da/dJ
    let a2 = 10.0 / 9.0 * a / (j * j); // d²a/dJ²
    let mut g = [[0.0; 3]; 3];
    let mut h = [[0.0; 9]; 9];
    for p in 0..9 {
        let (i, jj) = (p / 3, p % 3);
        let dap = a1 * dj[i][jj];
        g[i][jj] = dap * i1 + a * 2.0 * f[i][jj];
        for q in 0..9 {
            let (k, l) = (q / 3, q % 3);
            let daq = a1 * dj[k][l];
            let d2a = a2 * dj[i][jj] * dj[k][l] + a1 * d2j[p][q];
            h[p][q] =
                d2a * i1 + dap * 2.0 * f[k][l] + daq * 2.0 * f[i][jj] + if p == q { 2.0 * a } else { 0.0 };
        }
    }
    (a * i1, g, h)
}

/// Neo-Hookean volumetric energy U(J) = −μ ln J + λ/2 (ln J)² and U′, U″ (Bonet & Wood Eq. 6.27).
pub fn nh_volumetric(l: &Lame, j: f64) -> (f64, f64, f64) {
    let lj = j.ln();
    (
        -l.mu * lj + 0.5 * l.lambda * lj * lj,
        (-l.mu + l.lambda * lj) / j,
        (l.mu + l.lambda - l.lambda * lj) / (j * j),
    )
}

/// Small-strain deviatoric energy density μ ε_dev:ε_dev, its gradient 2μ ε_dev and its (constant)
/// Hessian 2μ (𝕀_sym − I⊗I/3), all with respect to F (ε = sym(F) − I). Also returns tr ε.
pub fn linear_deviatoric(l: &Lame, f: &M3) -> (f64, M3, f64) {
    let theta = f[0][0] + f[1][1] + f[2][2] - 3.0;
    let mut e = [[0.0; 3]; 3];
    let mut w = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let eij = 0.5 * (f[i][j] + f[j][i]) - if i == j { 1.0 + theta / 3.0 } else { 0.0 };
            e[i][j] = 2.0 * l.mu * eij;
            w += l.mu * eij * eij;
        }
    }
    (w, e, theta)
}

/// The Hessian of [`linear_deviatoric`]: 2μ [(δ_ik δ_JL + δ_iL δ_Jk)/2 − δ_iJ δ_kL / 3].
pub fn linear_deviatoric_hessian(l: &Lame) -> H9 {
    let d = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
    let mut h = [[0.0; 9]; 9];
    for p in 0..9 {
        for q in 0..9 {
            let (i, j, k, m) = (p / 3, p % 3, q / 3, q % 3);
            h[p][q] = 2.0 * l.mu * (0.5 * (d(i, k) * d(j, m) + d(i, m) * d(j, k)) - d(i, j) * d(k, m) / 3.0);
        }
    }
    h
}
