//! Standard multi-contact displacement: Brodu, Dijksman & Behringer, Phys. Rev. E 91, 032201
//! (2015), as written in Ghods et al. (2022) Eq. 2.
//!
//! Sign convention (docs/spec.md §2): `n_k`, `n_c` are the **inward** unit normals of the particle at the
//! contact points (from the contact point toward the centre). With inward normals Eq. 2 is
//! Boussinesq's half-space point-load displacement projected on `n_c` (Johnson, Contact Mechanics,
//! eq. 3.22), which is also what LIGGGHTS `fix multicontact/halfspace` implements.

use super::lanes::Lane;
use super::Vec3;

/// Contacts closer than this (chord length, m) are treated as the same point and skipped: the
/// half-space kernel is singular there and the local Hertz term already accounts for the load.
pub const MIN_CHORD: f64 = 1e-10;

/// Below this value of `1 + n_k·u_kc` the third term of Eq. 2 is dropped (0/0 when the chord runs
/// straight along the load direction; on a sphere this never happens since there it equals 1 + s ≥ 1).
pub const MIN_DENOMINATOR: f64 = 1e-6;

/// The curly bracket of Eq. 2, B(n_k, n_c, u_kc; ν), for unit vectors.
#[inline]
pub fn bracket(n_k: &Vec3, n_c: &Vec3, u_kc: &Vec3, nu: f64) -> f64 {
    let nk_u = n_k.dot(u_kc);
    let nc_u = n_c.dot(u_kc);
    let nk_nc = n_k.dot(n_c);
    let denom = 1.0 + nk_u;
    let third =
        if denom > MIN_DENOMINATOR { (1.0 - 2.0 * nu) * (nk_nc + u_kc.dot(n_c)) / denom } else { 0.0 };
    nk_u * nc_u + (3.0 - 4.0 * nu) * nk_nc - third
}

/// Both directions of Eq. 2's bracket for one pair of contacts a, b from the three dot products they
/// share: returns (B_{a→b}, B_{b→a}) with `u_ab` the unit chord from a to b. Bitwise equal to
/// `bracket(n_a, n_b, u_ab)` and `bracket(n_b, n_a, −u_ab)` (negation is exact), at half the cost:
/// the kernel visits each pair once.
#[inline]
pub fn bracket_pair(n_a: &Vec3, n_b: &Vec3, u_ab: &Vec3, nu: f64) -> (f64, f64) {
    let a_u = n_a.dot(u_ab);
    let b_u = n_b.dot(u_ab);
    let ab = n_a.dot(n_b);
    let common = a_u * b_u + (3.0 - 4.0 * nu) * ab;
    let third =
        |num: f64, denom: f64| if denom > MIN_DENOMINATOR { (1.0 - 2.0 * nu) * num / denom } else { 0.0 };
    (common - third(ab + b_u, 1.0 + a_u), common - third(ab - a_u, 1.0 - b_u))
}

/// Both directions of Eq. 2's bracket divided by the chord length, (B_{a→b}/d, B_{b→a}/d), from the
/// unnormalised chord c = p_b − p_a: `a_c` = n_a·c, `b_c` = n_b·c, `ab` = n_a·n_b, `d2` = c·c.
/// The kernel's hot path: [`bracket_pair`] with u = c/d substituted and everything brought
/// over one common denominator, so a pair costs one square root and one division instead of a
/// square root and three divisions (the pair loop is bound by the divider). Equal to
/// `bracket_pair(n_a, n_b, c/d, ν) / d` up to rounding; (0, 0) for coincident points
/// (chord below [`MIN_CHORD`]). Generic over [`Lane`], so the kernel evaluates four pairs at once
/// with the same operations.
#[inline(always)]
pub fn bracket_pair_over_chord<L: Lane>(a_c: L, b_c: L, ab: L, d2: L, nu: f64) -> (L, L) {
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let d = d2.sqrt();
    // 1 + a_u = (d + a_c)/d and 1 − b_u = (d − b_c)/d: the same guards as `bracket_pair`.
    let (da, db) = (d + a_c, d - b_c);
    let (ok_a, ok_b) = (da.gt(L::splat(MIN_DENOMINATOR) * d), db.gt(L::splat(MIN_DENOMINATOR) * d));
    let (da, db) = (L::select(ok_a, da, one), L::select(ok_b, db, one));
    let coincident = d2.le(L::splat(MIN_CHORD * MIN_CHORD));
    let r = L::select(coincident, zero, one / (d2 * d * da * db));
    let inv_d3 = da * db * r;
    let inv_d = d2 * inv_d3;
    let common = a_c * b_c * inv_d3 + L::splat(3.0 - 4.0 * nu) * ab * inv_d;
    let k = L::splat(1.0 - 2.0 * nu) * d2 * r;
    let third_ab = L::select(ok_a, k * (ab * d + b_c) * db, zero);
    let third_ba = L::select(ok_b, k * (ab * d - a_c) * da, zero);
    (common - third_ab, common - third_ba)
}

/// Eq. 2 bracket for two contacts on one sphere, as a function of s = sin(α/2) where α is the
/// angle between the contacts: B(s) = 2(1−ν) + 2(1−2ν)s − (7−8ν)s² (docs/spec.md §2).
/// B(0) = 2(1−ν) (Boussinesq), B(1) = 2ν − 3 (antipodal contacts: the radius grows).
#[inline]
pub fn bracket_on_sphere(s: f64, nu: f64) -> f64 {
    2.0 * (1.0 - nu) + 2.0 * (1.0 - 2.0 * nu) * s - (7.0 - 8.0 * nu) * s * s
}

/// Prefactor of Eq. 2 without the bracket and the chord: −γ(1+ν) / (2π E). Multiply by F_k / d_kc
/// and by the bracket to get δ_{k→c}. Hoisted so the per-particle kernel computes it once.
#[inline]
pub fn compliance_prefactor(gamma: f64, youngs_modulus: f64, nu: f64) -> f64 {
    -gamma * (1.0 + nu) / (2.0 * std::f64::consts::PI * youngs_modulus)
}

/// Eq. 2: displacement of the particle surface at contact c caused by the normal force `f_k`
/// (magnitude, N) at contact k. `p_k`, `p_c` are the contact points relative to the particle centre
/// (m). Positive means the radius grows at c. Returns 0 for coincident contacts (chord below
/// [`MIN_CHORD`]) or a non-positive force.
#[inline]
pub fn displacement(p_k: &Vec3, p_c: &Vec3, f_k: f64, gamma: f64, youngs_modulus: f64, nu: f64) -> f64 {
    let chord = p_c - p_k;
    let d = chord.norm();
    let (lk, lc) = (p_k.norm(), p_c.norm());
    if d < MIN_CHORD || f_k <= 0.0 || lk <= 0.0 || lc <= 0.0 {
        return 0.0;
    }
    let u = chord / d;
    let n_k = -p_k / lk;
    let n_c = -p_c / lc;
    compliance_prefactor(gamma, youngs_modulus, nu) * f_k / d * bracket(&n_k, &n_c, &u, nu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bracket_pair_is_bitwise_two_brackets() {
        let mut rng = crate::rng::Lcg64(12345);
        let mut next = || rng.symmetric();
        for _ in 0..10_000 {
            let na = Vec3::new(next(), next(), next()).normalize();
            let nb = Vec3::new(next(), next(), next()).normalize();
            let u = Vec3::new(next(), next(), next()).normalize();
            let nu = 0.25 * (next() + 1.0);
            let (ab, ba) = bracket_pair(&na, &nb, &u, nu);
            assert_eq!(ab.to_bits(), bracket(&na, &nb, &u, nu).to_bits());
            assert_eq!(ba.to_bits(), bracket(&nb, &na, &(-u), nu).to_bits());
        }
    }

    /// The one-division form equals the bracket over the chord to round-off, guards included
    /// (chords along ±n where 1 ± n·u vanishes, and coincident points).
    #[test]
    fn bracket_over_chord_matches_bracket_pair() {
        let mut rng = crate::rng::Lcg64(987);
        let mut next = || rng.symmetric();
        let mut worst: f64 = 0.0;
        for k in 0..20_000 {
            let na = Vec3::new(next(), next(), next()).normalize();
            let nb = Vec3::new(next(), next(), next()).normalize();
            let len = 1e-3 * (1.0 + next());
            let c = match k % 4 {
                0 => -na * len, // 1 + n_a·u = 0: third term of a→b dropped
                1 => nb * len,  // 1 − n_b·u = 0: third term of b→a dropped
                _ => Vec3::new(next(), next(), next()).normalize() * len,
            };
            let nu = 0.25 * (next() + 1.0);
            let d = c.norm();
            let (ab, ba) = bracket_pair(&na, &nb, &(c / d), nu);
            let (gab, gba) =
                bracket_pair_over_chord(na.dot(&c), nb.dot(&c), na.dot(&nb), c.norm_squared(), nu);
            // Relative to the size of B's parts: |common| ≤ 4 and the third term ≤ 2/(1 ± n·u),
            // which grows near the guards, where both forms lose the same cancellation digits.
            let u = c / d;
            let rel = |g: f64, b: f64, den: f64| (g - b / d).abs() / ((4.0 + 2.0 / den.abs()) / d);
            worst = worst.max(rel(gab, ab, 1.0 + na.dot(&u))).max(rel(gba, ba, 1.0 - nb.dot(&u)));
        }
        assert!(worst < 1e-13, "worst relative difference {worst:e}");
        assert_eq!(bracket_pair_over_chord(0.0, 0.0, 1.0, 0.0, 0.3), (0.0, 0.0));
        assert_eq!(bracket_pair_over_chord(1e-22, 0.0, 1.0, 1e-40, 0.3), (0.0, 0.0));
    }
}
