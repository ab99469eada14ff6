//! The trilinear 8-node hexahedron in total Lagrangian form: 2×2×2 Gauss quadrature, element strain
//! energy, its gradient (internal force) and Hessian (tangent stiffness) with respect to the 24
//! nodal displacements.
//!
//! Volumetric locking (ν → 1/2) is removed by the mean-dilatation F-bar method (de Souza Neto,
//! Perić, Dunca & Owen, Comm. Numer. Meth. Eng. 12 (1996) 97; Hughes, Int. J. Numer. Meth. Eng.
//! 15 (1980) 1413 for the small-strain B-bar): at every Gauss point F̄ = (J̄/J)^{1/3} F with
//! J̄ = v_e / V_e the element's current over reference volume. Written as an energy,
//! Π_e = Σ_g w_g W(F̄_g), so the tangent is the exact, symmetric Hessian. For the Neo-Hookean law
//! W(F̄) = μ/2 (J̄^{2/3} Ī₁(F) − 3) + U(J̄) (Ī₁ is unchanged by the volumetric scaling); for the
//! linear law the trace of the strain is replaced by its element mean (B-bar).
//! Without the remedy each Gauss point is its own "element mean", which gives the plain energy.

use super::material::{
    det_derivs, iso_i1_derivs, linear_deviatoric, linear_deviatoric_hessian, nh_volumetric, Lame, H9, M3,
};

/// Constitutive law of the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Law {
    /// Small-strain Hooke (geometrically linear strain measure).
    Linear,
    /// Compressible Neo-Hookean.
    NeoHookean,
}

/// Treatment of the volumetric part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Volumetric {
    /// Plain displacement element (locks as ν → 1/2).
    Full,
    /// Mean-dilatation F-bar / B-bar.
    MeanDilatation,
}

/// Natural coordinates of the nodes: bottom face counter-clockwise, then the top face.
pub const CORNERS: [[f64; 3]; 8] = [
    [-1., -1., -1.],
    [1., -1., -1.],
    [1., 1., -1.],
    [-1., 1., -1.],
    [-1., -1., 1.],
    [1., -1., 1.],
    [1., 1., 1.],
    [-1., 1., 1.],
];

/// Reference-configuration data of one element: shape-function gradients ∂N_a/∂X at the 8 Gauss
/// points and the quadrature weights (det of the reference Jacobian; the Gauss weights are 1).
#[derive(Clone, Debug)]
pub struct Geometry {
    pub dn: [[[f64; 3]; 8]; 8],
    pub w: [f64; 8],
}

/// Shape-function gradients and weights at the 2×2×2 Gauss points; an error if the element is
/// inverted or degenerate (det of the Jacobian ≤ 0 at a Gauss point).
pub fn geometry(x: &[[f64; 3]; 8]) -> Result<Geometry, String> {
    let gp = 1.0 / 3f64.sqrt();
    let mut g = Geometry { dn: [[[0.0; 3]; 8]; 8], w: [0.0; 8] };
    for (q, c) in CORNERS.iter().enumerate() {
        let xi = [c[0] * gp, c[1] * gp, c[2] * gp];
        let mut dxi = [[0.0; 3]; 8];
        for (a, na) in CORNERS.iter().enumerate() {
            let f = |d: usize| 1.0 + na[d] * xi[d];
            dxi[a] = [na[0] * f(1) * f(2) / 8.0, na[1] * f(0) * f(2) / 8.0, na[2] * f(0) * f(1) / 8.0];
        }
        // jac[i][k] = ∂X_i/∂ξ_k
        let mut jac = [[0.0; 3]; 3];
        for a in 0..8 {
            for i in 0..3 {
                for k in 0..3 {
                    jac[i][k] += x[a][i] * dxi[a][k];
                }
            }
        }
        let m = nalgebra::Matrix3::from_fn(|i, k| jac[i][k]);
        let det = m.determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(format!("element with non-positive Jacobian {det:.3e} at a Gauss point"));
        }
        let inv = m.try_inverse().ok_or("singular element Jacobian")?;
        for a in 0..8 {
            for j in 0..3 {
                // ∂N/∂X_j = Σ_k ∂N/∂ξ_k ∂ξ_k/∂X_j
                g.dn[q][a][j] = (0..3).map(|k| dxi[a][k] * inv[(k, j)]).sum();
            }
        }
        g.w[q] = det;
    }
    Ok(g)
}

/// Energy, gradient and Hessian of one element (the Hessian only when asked).
pub struct Output {
    pub energy: f64,
    pub grad: [f64; 24],
    pub hess: [[f64; 24]; 24],
}

impl Default for Output {
    fn default() -> Self {
        Output { energy: 0.0, grad: [0.0; 24], hess: [[0.0; 24]; 24] }
    }
}

/// F = I + Σ_a u_a ⊗ ∂N_a/∂X.
fn deformation_gradient(dn: &[[f64; 3]; 8], u: &[[f64; 3]; 8]) -> M3 {
    let mut f = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for a in 0..8 {
        for i in 0..3 {
            for j in 0..3 {
                f[i][j] += u[a][i] * dn[a][j];
            }
        }
    }
    f
}

/// Chain rule from F to the nodal displacements: g_(a,i) = Σ_J G_iJ ∂N_a/∂X_J.
fn push_grad(g: &M3, dn: &[[f64; 3]; 8], s: f64, out: &mut [f64; 24]) {
    for a in 0..8 {
        for i in 0..3 {
            out[3 * a + i] += s * (g[i][0] * dn[a][0] + g[i][1] * dn[a][1] + g[i][2] * dn[a][2]);
        }
    }
}

/// K_(a,i)(b,k) += Σ_JL H_(iJ)(kL) ∂N_a/∂X_J ∂N_b/∂X_L.
fn push_hess(h: &H9, dn: &[[f64; 3]; 8], out: &mut [[f64; 24]; 24]) {
    let mut t = [[0.0; 24]; 9];
    for p in 0..9 {
        for b in 0..8 {
            for k in 0..3 {
                t[p][3 * b + k] =
                    h[p][3 * k] * dn[b][0] + h[p][3 * k + 1] * dn[b][1] + h[p][3 * k + 2] * dn[b][2];
            }
        }
    }
    for a in 0..8 {
        for i in 0..3 {
            let row = &mut out[3 * a + i];
            for c in 0..24 {
                row[c] += dn[a][0] * t[3 * i][c] + dn[a][1] * t[3 * i + 1][c] + dn[a][2] * t[3 * i + 2][c];
            }
        }
    }
}

fn add_outer(out: &mut [[f64; 24]; 24], s: f64, a: &[f64; 24], b: &[f64; 24]) {
    for (r, row) in out.iter_mut().enumerate() {
        for c in 0..24 {
            row[c] += s * a[r] * b[c];
        }
    }
}

/// The element's energy Π_e, gradient ∂Π_e/∂u and (if `hessian`) ∂²Π_e/∂u². `Err` if a Gauss point
/// is inverted (J ≤ 0), which the Newton line search treats as a step too long.
#[allow(clippy::result_unit_err)] // the one failure has no payload: the caller shortens the step
pub fn evaluate(
    law: Law,
    lame: &Lame,
    vol: Volumetric,
    geo: &Geometry,
    u: &[[f64; 3]; 8],
    hessian: bool,
    out: &mut Output,
) -> Result<(), ()> {
    out.energy = 0.0;
    out.grad = [0.0; 24];
    if hessian {
        out.hess = [[0.0; 24]; 24];
    }
    let groups: &[std::ops::Range<usize>] = match vol {
        Volumetric::MeanDilatation => std::slice::from_ref(&(0..8)),
        Volumetric::Full => &[0..1, 1..2, 2..3, 3..4, 4..5, 5..6, 6..7, 7..8],
    };
    match law {
        Law::NeoHookean => {
            let mu = lame.mu;
            let mut jg = [0.0; 8];
            let mut dj = [[[0.0; 3]; 3]; 8];
            let mut d2j = [[[0.0; 9]; 9]; 8];
            let mut ib = [0.0; 8];
            let mut dib = [[[0.0; 3]; 3]; 8];
            let mut d2ib = [[[0.0; 9]; 9]; 8];
            for q in 0..8 {
                let f = deformation_gradient(&geo.dn[q], u);
                let (j, d, d2) = det_derivs(&f);
                if j.is_nan() || j <= 0.0 {
                    return Err(());
                }
                let (i, di, d2i) = iso_i1_derivs(&f, j, &d, &d2);
                (jg[q], dj[q], d2j[q], ib[q], dib[q], d2ib[q]) = (j, d, d2, i, di, d2i);
            }
            for r in groups {
                let v: f64 = r.clone().map(|q| geo.w[q]).sum();
                let jb = r.clone().map(|q| geo.w[q] * jg[q]).sum::<f64>() / v;
                let a: f64 = r.clone().map(|q| geo.w[q] * 0.5 * mu * ib[q]).sum();
                let mut gjb = [0.0; 24];
                let mut ga = [0.0; 24];
                for q in r.clone() {
                    push_grad(&dj[q], &geo.dn[q], geo.w[q] / v, &mut gjb);
                    push_grad(&dib[q], &geo.dn[q], geo.w[q] * 0.5 * mu, &mut ga);
                }
                let (uu, u1, u2) = nh_volumetric(lame, jb);
                let j23 = jb.powf(2.0 / 3.0);
                out.energy += j23 * a - 1.5 * mu * v + v * uu;
                let c1 = 2.0 / 3.0 * a / jb.cbrt() + v * u1;
                for k in 0..24 {
                    out.grad[k] += c1 * gjb[k] + j23 * ga[k];
                }
                if hessian {
                    let s = 2.0 / 3.0 / jb.cbrt();
                    add_outer(&mut out.hess, s, &ga, &gjb);
                    add_outer(&mut out.hess, s, &gjb, &ga);
                    add_outer(&mut out.hess, v * u2 - 2.0 / 9.0 * a / (jb * jb.cbrt()), &gjb, &gjb);
                    for q in r.clone() {
                        let (sj, si) = (c1 * geo.w[q] / v, j23 * geo.w[q] * 0.5 * mu);
                        let mut h = [[0.0; 9]; 9];
                        for p in 0..9 {
                            for m in 0..9 {
                                h[p][m] = sj * d2j[q][p][m] + si * d2ib[q][p][m];
                            }
                        }
                        push_hess(&h, &geo.dn[q], &mut out.hess);
                    }
                }
            }
        }
        Law::Linear => {
            let k_bulk = lame.bulk();
            let p = linear_deviatoric_hessian(lame);
            let eye = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            for r in groups {
                let v: f64 = r.clone().map(|q| geo.w[q]).sum();
                let mut th = 0.0;
                let mut gth = [0.0; 24];
                for q in r.clone() {
                    let f = deformation_gradient(&geo.dn[q], u);
                    let (w, g, t) = linear_deviatoric(lame, &f);
                    out.energy += geo.w[q] * w;
                    push_grad(&g, &geo.dn[q], geo.w[q], &mut out.grad);
                    th += geo.w[q] * t / v;
                    push_grad(&eye, &geo.dn[q], geo.w[q] / v, &mut gth);
                    if hessian {
                        let mut h = p;
                        h.iter_mut().flatten().for_each(|x| *x *= geo.w[q]);
                        push_hess(&h, &geo.dn[q], &mut out.hess);
                    }
                }
                out.energy += 0.5 * v * k_bulk * th * th;
                for k in 0..24 {
                    out.grad[k] += v * k_bulk * th * gth[k];
                }
                if hessian {
                    add_outer(&mut out.hess, v * k_bulk, &gth, &gth);
                }
            }
        }
    }
    Ok(())
}
