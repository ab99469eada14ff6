//! Property tests of the contact core over random finite inputs: the kernel and the pair force
//! never give NaN or infinity (coincident and antipodal contacts, ν = 0.5, zero forces included),
//! the cap limits hold exactly, and the pair force obeys Newton's third law and torque balance.

use mcdem::physics::brodu2015::{bracket_pair_over_chord, compliance_prefactor, displacement};
use mcdem::physics::contact_set::{influence, radius_changes, radius_changes_with, ContactLoad, McParams};
use mcdem::physics::ghods2022::{Cap, MprTest};
use mcdem::physics::hertz::Tangential;
use mcdem::physics::material::{Material, PairCoeffs};
use mcdem::physics::pair::{particle_particle, particle_wall, Body, PairLanes, WallLanes, WallPoint, LANES};
use mcdem::physics::Vec3;
use proptest::prelude::*;

const R: f64 = 1e-3;

/// A direction on the unit sphere; a few fixed ones make antipodal and coincident pairs common.
fn direction() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        Just(Vec3::new(0.0, 0.0, 1.0)),
        Just(Vec3::new(0.0, 0.0, -1.0)),
        Just(Vec3::new(1.0, 0.0, 0.0)),
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
            .prop_filter("non-zero", |(x, y, z)| x * x + y * y + z * z > 1e-6)
            .prop_map(|(x, y, z)| Vec3::new(x, y, z).normalize()),
    ]
}

fn contact() -> impl Strategy<Value = ContactLoad> {
    (direction(), 0.5..1.0f64, prop_oneof![Just(0.0), 0.0..1e-2f64])
        .prop_map(|(d, depth, force)| ContactLoad { point: d * depth * R, force })
}

fn params() -> impl Strategy<Value = McParams> {
    (
        prop_oneof![Just(0.5), Just(0.0), 0.0..=0.5f64],
        0.0..3.0f64,
        prop_oneof![Just(None), (0.0..2.0f64).prop_map(Some)],
        any::<bool>(),
    )
        .prop_map(|(nu, gamma, mpr, signed)| McParams {
            radius: R,
            youngs_modulus: 23.3e3,
            poisson_ratio: nu,
            gamma,
            cap: mpr.map(|mpr| Cap { mpr, test: if signed { MprTest::Signed } else { MprTest::Abs } }),
        })
}

proptest! {
    // A fixed seed keeps CI reproducible; widen the search locally with PROPTEST_CASES.
    #![proptest_config(ProptestConfig { cases: 2000, rng_seed: proptest::test_runner::RngSeed::Fixed(0x006d_6364_656d), ..ProptestConfig::default() })]

    #[test]
    fn kernel_is_always_finite(p in params(), cs in prop::collection::vec(contact(), 0..16)) {
        let mut d = vec![f64::NAN; cs.len()];
        let mut fb = vec![true; cs.len()];
        let s = radius_changes(&p, &cs, &mut d, &mut fb).unwrap();
        prop_assert!(d.iter().all(|v| v.is_finite()));
        prop_assert_eq!(s.fallbacks, fb.iter().filter(|f| **f).count());
        // A contact switched to Hertz has no correction at all.
        for (dv, f) in d.iter().zip(&fb) {
            if *f { prop_assert_eq!(*dv, 0.0); }
        }
    }

    #[test]
    fn mpr_zero_is_hertz_and_large_mpr_is_standard(p in params(), cs in prop::collection::vec(contact(), 0..12)) {
        let n = cs.len();
        let run = |cap| {
            let mut d = vec![0.0; n];
            let mut fb = vec![false; n];
            radius_changes(&McParams { cap, ..p }, &cs, &mut d, &mut fb).unwrap();
            d
        };
        let standard = run(None);
        let zero = run(Some(Cap { mpr: 0.0, test: MprTest::Abs }));
        prop_assert!(zero.iter().all(|v| *v == 0.0), "MPR = 0 must give no correction: {:?}", zero);
        prop_assert_eq!(run(Some(Cap { mpr: 1e9, test: MprTest::Abs })), standard.clone());
        prop_assert_eq!(run(Some(Cap { mpr: 1e9, test: MprTest::Signed })), standard);
    }

    /// The geometry-tolerance path (influence matrix, then this step's forces) is the kernel to
    /// round-off when the matrix is fresh: same terms, same summation order, same cap decisions.
    #[test]
    fn influence_matrix_times_forces_is_the_kernel(p in params(), cs in prop::collection::vec(contact(), 0..14)) {
        let n = cs.len();
        let (mut d1, mut f1) = (vec![0.0; n], vec![false; n]);
        let (mut d2, mut f2) = (vec![0.0; n], vec![false; n]);
        let s1 = radius_changes(&p, &cs, &mut d1, &mut f1).unwrap();
        let mut g = vec![f64::NAN; n * n];
        influence(&p, &cs, &mut g).unwrap();
        prop_assert!(g.iter().all(|v| v.is_finite()));
        let s2 = radius_changes_with(&p, &g, &cs, &mut d2, &mut f2).unwrap();
        prop_assert_eq!(s1, s2);
        prop_assert_eq!(f1, f2);
        let threshold = p.loaded_threshold();
        for (c, (a, b)) in d1.iter().zip(&d2).enumerate() {
            let scale: f64 = cs.iter().enumerate().filter(|(k, ck)| *k != c && ck.force > threshold)
                .map(|(_, ck)| displacement(&ck.point, &cs[c].point, ck.force, p.gamma, p.youngs_modulus, p.poisson_ratio).abs())
                .sum();
            prop_assert!((a - b).abs() <= 1e-13 * scale, "contact {}: {} vs {} (scale {})", c, a, b, scale);
        }
    }

    /// The kernel against Eq. 2 written out term by term (`brodu2015::displacement`, which takes
    /// the bracket through unit vectors and three divisions, not the kernel's one-division form):
    /// Δ_c is the sum of the terms to round-off and the cap trips on the same contacts. Up to 19
    /// contacts, so the kernel's padded four-pair chunks end at every offset.
    #[test]
    fn kernel_is_the_sum_of_eq2_terms(p in params(), cs in prop::collection::vec(contact(), 0..20)) {
        let n = cs.len();
        let (mut d, mut fb) = (vec![f64::NAN; n], vec![false; n]);
        radius_changes(&p, &cs, &mut d, &mut fb).unwrap();
        let threshold = p.loaded_threshold();
        for c in 0..n {
            let terms: Vec<f64> = (0..n)
                .filter(|&k| k != c && cs[k].force > threshold)
                .map(|k| displacement(&cs[k].point, &cs[c].point, cs[k].force, p.gamma, p.youngs_modulus, p.poisson_ratio))
                .collect();
            let scale: f64 = terms.iter().map(|t| t.abs()).sum();
            let sum: f64 = terms.iter().sum();
            let trips = |dm: f64, test: MprTest| terms.iter().any(|&t| match test {
                MprTest::Abs => t.abs() > dm,
                MprTest::Signed => t > dm,
            });
            match p.cap {
                Some(cap) if p.gamma > 0.0 => {
                    let dm = cap.mpr * p.radius;
                    // Terms within round-off of δ_max may go either way.
                    if terms.iter().any(|t| (t.abs() - dm).abs() <= 1e-12 * dm.max(t.abs())) { continue; }
                    prop_assert_eq!(fb[c], trips(dm, cap.test), "contact {}: cap decision", c);
                    if fb[c] { prop_assert_eq!(d[c], 0.0); continue; }
                }
                _ => prop_assert!(!fb[c]),
            }
            prop_assert!((d[c] - sum).abs() <= 1e-12 * scale, "contact {}: kernel {} vs terms {} (scale {})", c, d[c], sum, scale);
        }
    }

    /// The kernel's summation, bit for bit: each Δ_c is +0 + t_{0→c} + t_{1→c} + … (k ≠ c) in
    /// increasing source index, every term the one-division bracket of its pair times the source
    /// weight pref·F_k, written out here pair by pair on plain f64 (the kernel evaluates four
    /// pairs per instruction and stores them in a matrix). Any change of the order in which the
    /// kernel adds its terms, or of a term's operations, changes bits here (and in the engine's
    /// pinned outputs); the rounding of the result is thereby fixed, not only its value to 1e-12.
    #[test]
    fn kernel_sums_its_terms_in_source_order_bit_for_bit(p in params(), cs in prop::collection::vec(contact(), 0..20)) {
        let n = cs.len();
        let (mut d, mut fb) = (vec![f64::NAN; n], vec![false; n]);
        radius_changes(&McParams { cap: None, ..p }, &cs, &mut d, &mut fb).unwrap();
        let (nu, threshold) = (p.poisson_ratio, p.loaded_threshold());
        let pref = compliance_prefactor(p.gamma, p.youngs_modulus, nu);
        let len = |q: &Vec3| (q.x * q.x + q.y * q.y + q.z * q.z).sqrt();
        let normal = |q: &Vec3| { let l = len(q); if l > 0.0 { Vec3::new(-q.x / l, -q.y / l, -q.z / l) } else { Vec3::zeros() } };
        let weight = |c: &ContactLoad| if len(&c.point) > 0.0 && c.force > threshold { pref * c.force } else { 0.0 };
        // t_{k→c} of Eq. 2 as the kernel forms it: the pair (a, b) = (min, max), bracket over the chord.
        let term = |k: usize, c: usize| {
            let (a, b) = (k.min(c), k.max(c));
            let (pa, pb, na, nb) = (cs[a].point, cs[b].point, normal(&cs[a].point), normal(&cs[b].point));
            let (cx, cy, cz) = (pb.x - pa.x, pb.y - pa.y, pb.z - pa.z);
            let d2 = cx * cx + cy * cy + cz * cz;
            let a_c = na.x * cx + na.y * cy + na.z * cz;
            let b_c = nb.x * cx + nb.y * cy + nb.z * cz;
            let ab = na.x * nb.x + na.y * nb.y + na.z * nb.z;
            let (g_ab, g_ba) = bracket_pair_over_chord::<f64>(a_c, b_c, ab, d2, nu);
            if k == a { g_ab * weight(&cs[a]) } else { g_ba * weight(&cs[b]) }
        };
        let active = n >= 2 && p.gamma != 0.0 && cs.iter().any(|c| c.force > threshold);
        for (c, dc) in d.iter().enumerate() {
            let want = if active { (0..n).filter(|&k| k != c).fold(0.0, |acc, k| acc + term(k, c)) } else { 0.0 };
            prop_assert_eq!(dc.to_bits(), want.to_bits(), "contact {} of {}: kernel {:e} vs in order {:e}", c, n, dc, want);
        }
    }

    #[test]
    fn kernel_does_not_depend_on_contact_order(p in params(), cs in prop::collection::vec(contact(), 2..10), rot in 1usize..9) {
        let n = cs.len();
        let mut rotated = cs.clone();
        rotated.rotate_left(rot % n);
        let (mut d1, mut f1) = (vec![0.0; n], vec![false; n]);
        let (mut d2, mut f2) = (vec![0.0; n], vec![false; n]);
        radius_changes(&p, &cs, &mut d1, &mut f1).unwrap();
        radius_changes(&p, &rotated, &mut d2, &mut f2).unwrap();
        // Round-off bound of a sum in another order: ε times the sum of the terms' magnitudes,
        // each term computed independently with Eq. 2 (`displacement`).
        let threshold = p.loaded_threshold();
        let scale: Vec<f64> = cs.iter().enumerate().map(|(c, cc)| {
            cs.iter().enumerate().filter(|(k, ck)| *k != c && ck.force > threshold)
                .map(|(_, ck)| displacement(&ck.point, &cc.point, ck.force, p.gamma, p.youngs_modulus, p.poisson_ratio).abs())
                .sum()
        }).collect();
        d1.rotate_left(rot % n);
        f1.rotate_left(rot % n);
        let mut scale = scale;
        scale.rotate_left(rot % n);
        // Each term is bitwise the same in any order, so the cap decisions are identical.
        prop_assert_eq!(f1, f2);
        for ((a, b), s) in d1.iter().zip(&d2).zip(&scale) {
            prop_assert!((a - b).abs() <= 1e-13 * s, "{} vs {} (scale {})", a, b, s);
        }
    }

    #[test]
    fn two_contacts_on_a_sphere_match_b_of_s(nu in 0.0..=0.5f64, alpha in 0.01..std::f64::consts::PI, f in 1e-6..1e-2f64) {
        // Independent closed form: δ = −γ(1+ν)F/(2πE · 2r s) · B(s), s = sin(α/2), d = 2 r s.
        let p = McParams { radius: R, youngs_modulus: 23.3e3, poisson_ratio: nu, gamma: 1.0, cap: None };
        let cs = [
            ContactLoad { point: Vec3::new(0.0, 0.0, R), force: f },
            ContactLoad { point: Vec3::new(R * alpha.sin(), 0.0, R * alpha.cos()), force: 0.0 },
        ];
        let (mut d, mut fb) = ([0.0; 2], [false; 2]);
        radius_changes(&p, &cs, &mut d, &mut fb).unwrap();
        // Written out here, not called from the code under test: prefactor −γ(1+ν)/(2πE) with
        // γ = 1, chord d = 2 r s, bracket B(s) = 2(1−ν) + 2(1−2ν)s − (7−8ν)s² (Brodu et al. 2015,
        // Eq. 2 evaluated for two points on one sphere, docs/spec.md §2).
        let s = (alpha / 2.0).sin();
        let scale = -(1.0 + nu) / (2.0 * std::f64::consts::PI * 23.3e3) * f / (2.0 * R * s);
        let expected = scale * (2.0 * (1.0 - nu) + 2.0 * (1.0 - 2.0 * nu) * s - (7.0 - 8.0 * nu) * s * s);
        // Tolerance relative to the size of the bracket's terms (B itself crosses zero near 70°–82°).
        prop_assert!((d[1] - expected).abs() <= 1e-12 * scale.abs(), "{} vs {}", d[1], expected);
        prop_assert_eq!(d[0], 0.0);
    }

    #[test]
    fn pair_force_newton_and_torque_balance(
        nu in 0.0..=0.5f64, e in 0.05..=1.0f64, mu in prop_oneof![Just(0.0), 0.0..2.0f64],
        dir in direction(), gap in 0.0..0.3f64,
        vi in prop::array::uniform3(-1.0..1.0f64), wi in prop::array::uniform3(-100.0..100.0f64),
        wj in prop::array::uniform3(-100.0..100.0f64), sh in prop::array::uniform3(-1e-4..1e-4f64),
        dri in -1e-4..1e-4f64, drj in -1e-4..1e-4f64, history in any::<bool>(),
    ) {
        let m = Material::hertz(23.3e3, nu).unwrap();
        let tangential = if history { Tangential::History } else { Tangential::NoHistory };
        let c = PairCoeffs { tangential, ..PairCoeffs::new(&m, &m, e, mu).unwrap() };
        let bj = Body { x: Vec3::new(0.1, -0.2, 0.3), v: Vec3::zeros(), omega: Vec3::from(wj), radius: 1.2 * R, mass: 7e-6 };
        let bi = Body { x: bj.x + dir * (2.2 * R - gap * R), v: Vec3::from(vi), omega: Vec3::from(wi), radius: R, mass: 4e-6 };
        let mut shear = Vec3::from(sh);
        if let Some(f) = particle_particle(&c, &bi, &bj, dri, drj, 1e-5, &mut shear).unwrap() {
            prop_assert!(f.force_i.iter().chain(f.torque_i.iter()).chain(f.torque_j.iter()).all(|v| v.is_finite()));
            // Angular momentum about the origin is conserved by the pair: τ_i + τ_j + (x_i − x_j) × F_i = 0.
            let l = f.torque_i + f.torque_j + (bi.x - bj.x).cross(&f.force_i);
            prop_assert!(l.norm() <= 1e-12 * (f.force_i.norm() * R).max(1e-300));
            // Coulomb: the tangential part never exceeds μ|F_n| (plus round-off) once truncated; the
            // history model adds its damping term below the limit, the viscous model never exceeds it.
            let ft = f.force_i - f.en * f.force_i.dot(&f.en);
            let slack = if history { f.normal.gamma_t * 2e3 } else { 1e-12 * f.force_i.norm() };
            prop_assert!(ft.norm() <= mu * f.normal.force.abs() * (1.0 + 1e-12) + slack);
            if !history && mu > 0.0 {
                prop_assert_eq!(shear, Vec3::from(sh), "no_history keeps no state");
            }
        }
    }

    #[test]
    fn vectorised_batch_is_the_pair_force_bit_for_bit(
        pairs in prop::collection::vec((
            (0.0..=0.5f64, 0.05..=1.0f64, prop_oneof![Just(0.0), 0.0..2.0f64]),
            (direction(), 0.0..1.3f64, prop::array::uniform3(-1.0..1.0f64)),
            (prop::array::uniform3(-100.0..100.0f64), prop::array::uniform3(-100.0..100.0f64)),
            (prop::array::uniform3(-1e-4..1e-4f64), -1e-4..1e-4f64, -1e-4..1e-4f64),
        ), 1..=LANES),
        dt in prop_oneof![Just(0.0), Just(1e-5)],
    ) {
        // Random overlapping pairs (some beyond a radius, frictionless, undamped among them) in
        // one batch: each lane must give exactly what `particle_particle` gives for that pair,
        // and flag exactly the pairs it refuses.
        let mut lanes = PairLanes::default();
        let mut expected = Vec::new();
        for ((nu, e, mu), (dir, gap, vi), (wi, wj), (sh, dri, drj)) in pairs {
            let m = Material::hertz(23.3e3, nu).unwrap();
            let c = PairCoeffs::new(&m, &m, e, mu).unwrap();
            let bj = Body { x: Vec3::new(0.1, -0.2, 0.3), v: Vec3::zeros(), omega: Vec3::from(wj), radius: 1.2 * R, mass: 7e-6 };
            let bi = Body { x: bj.x + dir * (2.2 * R - gap * R), v: Vec3::from(vi), omega: Vec3::from(wi), radius: R, mass: 4e-6 };
            let d = bi.x - bj.x;
            let radsum = (bi.radius + dri) + (bj.radius + drj);
            if d.norm_squared() >= radsum * radsum {
                continue;
            }
            let l = expected.len();
            for a in 0..3 {
                lanes.d[a][l] = d[a];
                lanes.vr[a][l] = bi.v[a] - bj.v[a];
                lanes.omega_i[a][l] = bi.omega[a];
                lanes.omega_j[a][l] = bj.omega[a];
                lanes.shear[a][l] = sh[a];
            }
            (lanes.radius_i[l], lanes.radius_j[l], lanes.dri[l], lanes.drj[l]) = (bi.radius, bj.radius, dri, drj);
            (lanes.mass_i[l], lanes.mass_j[l]) = (bi.mass, bj.mass);
            lanes.coeffs.set(l, &c);
            let mut shear = Vec3::from(sh);
            let r = particle_particle(&c, &bi, &bj, dri, drj, dt, &mut shear);
            expected.push((r, shear));
        }
        prop_assume!(!expected.is_empty());
        lanes.pad_from_first(expected.len());
        lanes.evaluate(dt);
        for (l, (r, shear)) in expected.iter().enumerate() {
            let lane = |a: &[[f64; LANES]; 3]| Vec3::new(a[0][l], a[1][l], a[2][l]);
            match r {
                Ok(Some(f)) => {
                    prop_assert!(lanes.ok[l]);
                    prop_assert_eq!(lane(&lanes.force), f.force_i);
                    prop_assert_eq!(lane(&lanes.torque_i), f.torque_i);
                    prop_assert_eq!(lane(&lanes.torque_j), f.torque_j);
                    prop_assert_eq!(lane(&lanes.shear), *shear);
                    prop_assert_eq!(lanes.fnorm[l], f.force_i.dot(&f.en).abs());
                }
                Ok(None) => unreachable!("only overlapping pairs are batched"),
                Err(_) => prop_assert!(!lanes.ok[l], "lane {} accepted a pair the pair force refuses", l),
            }
        }
    }

    #[test]
    fn vectorised_wall_batch_is_the_wall_force_bit_for_bit(
        contacts in prop::collection::vec((
            (0.0..=0.5f64, 0.05..=1.0f64, prop_oneof![Just(0.0), 0.0..2.0f64]),
            (direction(), 0.0..1.3f64, prop::array::uniform3(-1.0..1.0f64), prop::array::uniform3(-1.0..1.0f64)),
            prop::array::uniform3(-100.0..100.0f64),
            (prop::array::uniform3(-1e-4..1e-4f64), -1e-4..1e-4f64),
        ), 1..=LANES),
        dt in prop_oneof![Just(0.0), Just(1e-5)],
    ) {
        // Random particle–wall contacts that reach the wall (some beyond a radius, frictionless,
        // undamped, on moving walls among them) in one batch: each lane must give exactly what
        // `particle_wall` gives, and flag exactly the contacts it refuses.
        let mut lanes = WallLanes::default();
        let mut expected = Vec::new();
        for ((nu, e, mu), (dir, gap, vi, vw), wi, (sh, dri)) in contacts {
            let m = Material::hertz(23.3e3, nu).unwrap();
            let w = Material::hertz(5e7, 0.5).unwrap();
            let c = PairCoeffs::new(&m, &w, e, mu).unwrap();
            let wall = WallPoint { point: Vec3::new(0.1, -0.2, 0.3), velocity: Vec3::from(vw) };
            let b = Body { x: wall.point + dir * (R - gap * R), v: Vec3::from(vi), omega: Vec3::from(wi), radius: R, mass: 4e-6 };
            let d = b.x - wall.point;
            let ri = b.radius + dri;
            if d.norm_squared() >= ri * ri {
                continue;
            }
            let l = expected.len();
            for a in 0..3 {
                lanes.d[a][l] = d[a];
                lanes.vr[a][l] = b.v[a] - wall.velocity[a];
                lanes.omega[a][l] = b.omega[a];
                lanes.shear[a][l] = sh[a];
            }
            (lanes.radius[l], lanes.dr[l], lanes.mass[l]) = (b.radius, dri, b.mass);
            lanes.coeffs.set(l, &c);
            let mut shear = Vec3::from(sh);
            let r = particle_wall(&c, &b, &wall, dri, dt, &mut shear);
            expected.push((r, shear));
        }
        prop_assume!(!expected.is_empty());
        lanes.pad_from_first(expected.len());
        lanes.evaluate(dt);
        for (l, (r, shear)) in expected.iter().enumerate() {
            let lane = |a: &[[f64; LANES]; 3]| Vec3::new(a[0][l], a[1][l], a[2][l]);
            match r {
                Ok(Some(f)) => {
                    prop_assert!(lanes.ok[l]);
                    prop_assert_eq!(lane(&lanes.force), f.force_i);
                    prop_assert_eq!(lane(&lanes.torque), f.torque_i);
                    prop_assert_eq!(lane(&lanes.shear), *shear);
                    prop_assert_eq!(lanes.fnorm[l], f.force_i.dot(&f.en).abs());
                }
                Ok(None) => unreachable!("only contacts that reach the wall are batched"),
                Err(_) => prop_assert!(!lanes.ok[l], "lane {} accepted a contact the wall force refuses", l),
            }
        }
    }

    #[test]
    fn wall_force_is_finite_and_normal_without_friction(nu in 0.0..=0.5f64, depth in 0.0..0.9f64, dri in -1e-4..1e-4f64) {
        let m = Material::hertz(23.3e3, nu).unwrap();
        let w = Material::hertz(5e7, 0.5).unwrap();
        let c = PairCoeffs::new(&m, &w, 0.95, 0.0).unwrap();
        let b = Body { x: Vec3::new(0.0, 0.0, R * (1.0 - depth)), v: Vec3::new(0.0, 0.0, -0.01), omega: Vec3::new(1.0, 0.0, 0.0), radius: R, mass: 4e-6 };
        let wall = WallPoint { point: Vec3::zeros(), velocity: Vec3::zeros() };
        if let Ok(Some(f)) = particle_wall(&c, &b, &wall, dri, 1e-5, &mut Vec3::zeros()) {
            prop_assert!(f.force_i.iter().all(|v| v.is_finite()));
            prop_assert!(f.force_i.x == 0.0 && f.force_i.y == 0.0 && f.force_i.z > 0.0);
        }
    }
}

#[test]
fn overlap_beyond_radius_is_an_error_not_a_force() {
    let m = Material::hertz(23.3e3, 0.5).unwrap();
    let c = PairCoeffs::new(&m, &m, 0.95, 0.03).unwrap();
    let bj = Body { x: Vec3::zeros(), v: Vec3::zeros(), omega: Vec3::zeros(), radius: R, mass: 4e-6 };
    let bi = Body { x: Vec3::new(0.0, 0.0, 0.9 * R), ..bj };
    let e = particle_particle(&c, &bi, &bj, 0.0, 0.0, 1e-5, &mut Vec3::zeros()).unwrap_err();
    assert!(e.to_string().contains("reached the particle radius"), "{e}");
    let same = particle_particle(&c, &bj, &bj, 0.0, 0.0, 1e-5, &mut Vec3::zeros()).unwrap_err();
    assert!(same.to_string().contains("coincident"), "{same}");
}

#[test]
fn shrunk_radii_turn_a_geometric_overlap_into_no_contact() {
    // Stock LIGGGHTS multicontact aborts with `sidata.deltan < 0!` here; the core reports no contact.
    let m = Material::hertz(23.3e3, 0.5).unwrap();
    let c = PairCoeffs::new(&m, &m, 0.95, 0.03).unwrap();
    let bj = Body { x: Vec3::zeros(), v: Vec3::zeros(), omega: Vec3::zeros(), radius: R, mass: 4e-6 };
    let bi = Body { x: Vec3::new(0.0, 0.0, 1.99 * R), ..bj };
    let mut shear = Vec3::new(1e-6, 0.0, 0.0);
    assert!(particle_particle(&c, &bi, &bj, -0.02 * R, 0.0, 1e-5, &mut shear).unwrap().is_none());
    assert_eq!(shear, Vec3::zeros(), "history is cleared when the contact opens");
}

#[test]
fn invalid_materials_name_the_parameter() {
    let cases: [(f64, f64, f64, Option<f64>, &str); 6] = [
        (0.0, 0.3, 1.0, None, "youngs_modulus"),
        (1e4, 0.51, 1.0, None, "poisson_ratio"),
        (1e4, -0.01, 1.0, None, "poisson_ratio"),
        (1e4, 0.3, -1.0, None, "gamma"),
        (1e4, 0.3, 1.0, Some(-0.1), "mpr"),
        (f64::NAN, 0.3, 1.0, None, "youngs_modulus"),
    ];
    for (e, nu, g, mpr, name) in cases {
        let err = Material::new(e, nu, g, mpr.map(|m| (m, MprTest::Abs))).unwrap_err();
        assert!(err.to_string().contains(name), "{err} should name {name}");
    }
    assert!(Material::new(1e4, 0.5, 0.81, Some((0.11, MprTest::Abs))).is_ok(), "ν = 0.5 is valid");
    let m = Material::hertz(1e4, 0.3).unwrap();
    assert!(PairCoeffs::new(&m, &m, 0.0, 0.1).unwrap_err().to_string().contains("coefficientRestitution"));
    assert!(PairCoeffs::new(&m, &m, 1.2, 0.1).unwrap_err().to_string().contains("coefficientRestitution"));
    assert!(PairCoeffs::new(&m, &m, 0.9, -0.1).unwrap_err().to_string().contains("coefficientFriction"));
}
