//! Materials as data: per-type elastic constants and multi-contact parameters, per-pair
//! restitution and friction, validated once so the hot path never sees a bad value.

use std::fmt;

use super::ghods2022::{Cap, MprTest};
use super::rolling_epsd::Epsd;

/// Per-type material of a particle (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus E [Pa], > 0.
    pub youngs_modulus: f64,
    /// Poisson ratio ν [-], in [0, 0.5] (0.5, incompressible, is valid: the paper's hydrogel).
    pub poisson_ratio: f64,
    /// Geometric prefactor γ of Eq. 2 [-], ≥ 0. γ = 0 switches the multi-contact correction off.
    pub gamma: f64,
    /// Advanced-MC cap (Eq. 3); `None` is standard MC (Eq. 2 without a cap).
    pub cap: Option<Cap>,
}

/// A parameter that failed validation: names the parameter and the offending value.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialError {
    pub parameter: &'static str,
    pub value: f64,
    pub requirement: &'static str,
}

impl fmt::Display for MaterialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid {} = {}: must be {}", self.parameter, self.value, self.requirement)
    }
}

impl std::error::Error for MaterialError {}

/// Checks one parameter; `ok` is evaluated only for finite values.
pub(crate) fn check(
    parameter: &'static str,
    value: f64,
    requirement: &'static str,
    ok: impl Fn(f64) -> bool,
) -> Result<f64, MaterialError> {
    if value.is_finite() && ok(value) {
        Ok(value)
    } else {
        Err(MaterialError { parameter, value, requirement })
    }
}

pub(crate) fn check_youngs_modulus(e: f64) -> Result<f64, MaterialError> {
    check("youngs_modulus", e, "finite and > 0", |v| v > 0.0)
}

pub fn check_poisson_ratio(nu: f64) -> Result<f64, MaterialError> {
    check("poisson_ratio", nu, "finite and in [0, 0.5]", |v| (0.0..=0.5).contains(&v))
}

pub fn check_friction(mu: f64) -> Result<f64, MaterialError> {
    check("coefficientFriction", mu, "finite and >= 0", |v| v >= 0.0)
}

pub(crate) fn check_gamma(gamma: f64) -> Result<f64, MaterialError> {
    check("gamma (geometricPrefactor)", gamma, "finite and >= 0", |v| v >= 0.0)
}

pub(crate) fn check_mpr(mpr: f64) -> Result<f64, MaterialError> {
    check("mpr (maxPenetrationRatio)", mpr, "finite and >= 0", |v| v >= 0.0)
}

impl Material {
    /// Validated constructor. `mpr = None` gives standard MC.
    pub fn new(
        youngs_modulus: f64,
        poisson_ratio: f64,
        gamma: f64,
        mpr: Option<(f64, MprTest)>,
    ) -> Result<Self, MaterialError> {
        let cap = match mpr {
            Some((m, test)) => Some(Cap { mpr: check_mpr(m)?, test }),
            None => None,
        };
        Ok(Self {
            youngs_modulus: check_youngs_modulus(youngs_modulus)?,
            poisson_ratio: check_poisson_ratio(poisson_ratio)?,
            gamma: check_gamma(gamma)?,
            cap,
        })
    }

    /// Hertz-only material (no multi-contact correction).
    pub fn hertz(youngs_modulus: f64, poisson_ratio: f64) -> Result<Self, MaterialError> {
        Self::new(youngs_modulus, poisson_ratio, 0.0, None)
    }
}

impl MaterialError {
    /// The LIGGGHTS `fix property/global` that holds the parameter (what a deck must change).
    pub fn property(&self) -> &'static str {
        match self.parameter {
            "youngs_modulus" => "youngsModulus",
            "poisson_ratio" => "poissonsRatio",
            "gamma (geometricPrefactor)" => "geometricPrefactor",
            "mpr (maxPenetrationRatio)" => "maxPenetrationRatio",
            other => other,
        }
    }
}

/// The pair coefficients of every ordered pair of `materials` (row a holds a's pairs: entry
/// a·n + b), from the `peratomtypepair` tables of restitution and friction in the same order.
/// One builder for both engines: `mcdem run`'s `World::set_materials` and the plugin's material
/// table (`mcdem_material_table`).
pub fn pair_table(
    materials: &[Material],
    restitution: &[f64],
    friction: &[f64],
) -> Result<Vec<PairCoeffs>, String> {
    let nt = materials.len();
    if restitution.len() != nt * nt || friction.len() != nt * nt {
        return Err(format!("peratomtypepair tables must have {nt}×{nt} entries"));
    }
    let mut coeffs = Vec::with_capacity(nt * nt);
    for (a, ma) in materials.iter().enumerate() {
        for (b, mb) in materials.iter().enumerate() {
            coeffs.push(
                PairCoeffs::new(ma, mb, restitution[a * nt + b], friction[a * nt + b])
                    .map_err(|e| format!("types {} and {}: {e}", a + 1, b + 1))?,
            );
        }
    }
    Ok(coeffs)
}

/// The tangential sub-model of a contact (LIGGGHTS `tangential history|no_history`), chosen per
/// pair table; the forces are [`super::hertz::tangential_history`] and
/// [`super::hertz::tangential_no_history`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tangential {
    /// Elastic spring on the accumulated tangential displacement with damping and Coulomb limit.
    #[default]
    History,
    /// Viscous tangential damping only, Coulomb-limited.
    NoHistory,
}

/// Parameters of LIGGGHTS' `model hooke` for one type pair (the law is [`super::hooke::normal`]).
/// Kept here with the pair coefficients that carry it, as [`Tangential`] is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hooke {
    /// `characteristicVelocity` V [m/s], the impact speed the linear stiffness is fitted to, > 0.
    pub char_vel: f64,
    /// ln e of the pair's coefficient of restitution (LIGGGHTS' `coeffRestLog`).
    pub ln_e: f64,
    /// `tangential_damping on` (LIGGGHTS' default): γ_t = γ_n; off: γ_t = 0.
    pub tangential_damping: bool,
    /// `limitForce on`: a negative (attractive) normal force is set to zero. Default off.
    pub limit_force: bool,
    /// `ktToKnUser on`: k_t = (2/7) k_n instead of k_t = k_n. Default off.
    pub kt_to_kn: bool,
}

/// The three per-type-pair ratios of LIGGGHTS' `model hooke/hysteresis` (the law is
/// [`super::hooke_hysteresis::normal`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    /// `coefficientMaxElasticStiffness` k₂,max / k_n, > 1.
    pub max_stiffness: f64,
    /// `coefficientAdhesionStiffness` k_c / k_n, ≥ 0.
    pub adhesion_stiffness: f64,
    /// `coefficientPlasticityDepth` φ_f, ≥ 0 (δ_lim = k₂,max/(k₂,max − k_n) φ_f 2R*).
    pub plasticity_depth: f64,
}

impl Hysteresis {
    /// Validated ratios: k₂,max/k_n > 1 (LIGGGHTS divides by k₂,max − k_n), the others ≥ 0.
    pub fn new(
        max_stiffness: f64,
        adhesion_stiffness: f64,
        plasticity_depth: f64,
    ) -> Result<Self, MaterialError> {
        Ok(Self {
            max_stiffness: check("coefficientMaxElasticStiffness", max_stiffness, "finite and > 1", |v| {
                v > 1.0
            })?,
            adhesion_stiffness: check(
                "coefficientAdhesionStiffness",
                adhesion_stiffness,
                "finite and >= 0",
                |v| v >= 0.0,
            )?,
            plasticity_depth: check(
                "coefficientPlasticityDepth",
                plasticity_depth,
                "finite and >= 0",
                |v| v >= 0.0,
            )?,
        })
    }
}

/// The normal contact law of a type pair.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum NormalLaw {
    /// Hertz with viscous damping ([`super::hertz::normal`]).
    #[default]
    Hertz,
    /// LIGGGHTS' linear spring-dashpot `model hooke` ([`super::hooke::normal`]).
    Hooke(Hooke),
    /// LIGGGHTS' `model hooke/hysteresis` ([`super::hooke_hysteresis::normal`]): the hooke
    /// stiffness and damping with a hysteretic loop; it keeps the largest overlap per contact.
    HookeHysteresis(Hooke, Hysteresis),
}

impl NormalLaw {
    /// The law keeps a history value per contact (the largest overlap of `hooke/hysteresis`).
    pub fn has_history(&self) -> bool {
        matches!(self, NormalLaw::HookeHysteresis(..))
    }
}

/// The rolling model of a pair with rolling friction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RollingLaw {
    /// `cdt`: constant directional torque, no history ([`super::rolling_cdt`]).
    Cdt,
    /// `epsd` or `epsd2`: the elastic–plastic spring(–dashpot), with a per-contact spring
    /// ([`super::rolling_epsd`]).
    Spring(Epsd),
}

/// Coefficients of one type pair, precomputed once (App. C, Eqs. C.3, C.4, C.8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairCoeffs {
    /// Effective Young's modulus E* [Pa] (Eq. C.3).
    pub e_star: f64,
    /// Effective shear modulus G* [Pa] (Eq. C.8).
    pub g_star: f64,
    /// β = ln e / √(ln²e + π²) [-] (Eq. C.4 with the square root the paper's typesetting dropped).
    pub beta: f64,
    /// Coulomb friction coefficient μ [-].
    pub friction: f64,
    /// Tangential sub-model (history unless the deck asks for `no_history`).
    pub tangential: Tangential,
    /// Normal law (Hertz unless the deck asks for `model hooke`).
    pub normal: NormalLaw,
    /// `cohesion sjkr`: the pair's `cohesionEnergyDensity` k_c [J/m³] ([`super::sjkr`]); 0 without
    /// cohesion.
    pub cohesion: f64,
    /// `tangential_reduce on` (of `cohesion sjkr`): the Coulomb limit sees the cohesive force.
    pub tangential_reduce: bool,
    /// `rolling_friction cdt|epsd|epsd2`: the pair's `coefficientRollingFriction` μ_r [-]; 0
    /// without rolling friction (no rolling torque whatever `rolling_law`).
    pub rolling_friction: f64,
    /// Which rolling model μ_r belongs to (read only when μ_r > 0).
    pub rolling_law: RollingLaw,
    /// γ_t / γ_n = √(S_t / S_n) = √(4 G* / E*): a property of the pair of materials, so the
    /// tangential damping costs a product per contact instead of a square root. Derived: build
    /// with [`PairCoeffs::new`] or [`PairCoeffs::from_moduli`].
    pub damping_ratio_t_n: f64,
}

impl PairCoeffs {
    /// Builds the pair coefficients from two materials, the pair's coefficient of restitution
    /// e ∈ (0, 1] and friction μ ≥ 0. A rigid wall is a material with its own E and ν (LIGGGHTS
    /// convention: walls are atom types too).
    pub fn new(mi: &Material, mj: &Material, restitution: f64, friction: f64) -> Result<Self, MaterialError> {
        let e =
            check("coefficientRestitution", restitution, "finite and in (0, 1]", |v| v > 0.0 && v <= 1.0)?;
        let mu = check_friction(friction)?;
        let (ei, ni) = (mi.youngs_modulus, mi.poisson_ratio);
        let (ej, nj) = (mj.youngs_modulus, mj.poisson_ratio);
        let e_star = 1.0 / ((1.0 - ni * ni) / ei + (1.0 - nj * nj) / ej);
        let g_star = 1.0 / (2.0 * (2.0 - ni) * (1.0 + ni) / ei + 2.0 * (2.0 - nj) * (1.0 + nj) / ej);
        let ln_e = e.ln();
        let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI * std::f64::consts::PI).sqrt();
        Ok(Self::from_moduli(e_star, g_star, beta, mu, Tangential::History))
    }

    /// From the effective moduli directly (the C ABI passes them); fills the derived ratio.
    pub fn from_moduli(e_star: f64, g_star: f64, beta: f64, friction: f64, tangential: Tangential) -> Self {
        Self {
            e_star,
            g_star,
            beta,
            friction,
            tangential,
            normal: NormalLaw::Hertz,
            cohesion: 0.0,
            tangential_reduce: false,
            rolling_friction: 0.0,
            rolling_law: RollingLaw::Cdt,
            damping_ratio_t_n: (4.0 * g_star / e_star).sqrt(),
        }
    }

    /// The same pair under `model hooke` with characteristic velocity `char_vel` [m/s] > 0 and the
    /// pair's coefficient of restitution e ∈ (0, 1]; `options` is (tangential_damping,
    /// limitForce, ktToKnUser).
    pub fn with_hooke(
        self,
        char_vel: f64,
        restitution: f64,
        (tangential_damping, limit_force, kt_to_kn): (bool, bool, bool),
    ) -> Result<Self, MaterialError> {
        let v = check("characteristicVelocity", char_vel, "finite and > 0", |v| v > 0.0)?;
        let e =
            check("coefficientRestitution", restitution, "finite and in (0, 1]", |v| v > 0.0 && v <= 1.0)?;
        let h = Hooke { char_vel: v, ln_e: e.ln(), tangential_damping, limit_force, kt_to_kn };
        Ok(Self { normal: NormalLaw::Hooke(h), ..self })
    }

    /// The same pair under `model hooke/hysteresis`: `model hooke` (see [`PairCoeffs::with_hooke`],
    /// whose `limitForce` and `ktToKnUser` this law does not read) with the loop's ratios.
    pub fn with_hysteresis(self, hy: Hysteresis) -> Result<Self, MaterialError> {
        match self.normal {
            NormalLaw::Hooke(h) => Ok(Self { normal: NormalLaw::HookeHysteresis(h, hy), ..self }),
            _ => Err(MaterialError {
                parameter: "normal law",
                value: f64::NAN,
                requirement: "model hooke before the hysteresis is added",
            }),
        }
    }

    /// The same pair with `cohesion sjkr` of energy density `energy_density` [J/m³] ≥ 0.
    pub fn with_cohesion(self, energy_density: f64, tangential_reduce: bool) -> Result<Self, MaterialError> {
        let k = check("cohesionEnergyDensity", energy_density, "finite and >= 0", |v| v >= 0.0)?;
        Ok(Self { cohesion: k, tangential_reduce, ..self })
    }

    /// The same pair with `rolling_friction cdt` of coefficient `mu_r` ≥ 0.
    pub fn with_rolling_friction(self, mu_r: f64) -> Result<Self, MaterialError> {
        let m = check("coefficientRollingFriction", mu_r, "finite and >= 0", |v| v >= 0.0)?;
        Ok(Self { rolling_friction: m, rolling_law: RollingLaw::Cdt, ..self })
    }

    /// The same pair with `rolling_friction epsd` (`damping` = `coefficientRollingViscousDamping`
    /// η_r ≥ 0) or `epsd2` (`damping` None) of coefficient `mu_r` ≥ 0.
    pub fn with_rolling_spring(self, mu_r: f64, damping: Option<f64>) -> Result<Self, MaterialError> {
        let m = check("coefficientRollingFriction", mu_r, "finite and >= 0", |v| v >= 0.0)?;
        let model = match damping {
            Some(d) => Epsd::Epsd {
                damping: check("coefficientRollingViscousDamping", d, "finite and >= 0", |v| v >= 0.0)?,
            },
            None => Epsd::Epsd2,
        };
        Ok(Self { rolling_friction: m, rolling_law: RollingLaw::Spring(model), ..self })
    }
}
