//! `pair_style gran` (and the model part of `fix wall/gran`), and the materials and contact
//! closure built from the `fix property/global` values when a run starts.

use super::*;
use crate::engine::DEFAULT_CHECK_EVERY;
use crate::physics::mc_settings::{self, McSetting};

/// The normal contact law a `model` keyword names: parsed once, so every later decision is a
/// `match` the compiler checks rather than a string compared in several places.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NormalModel {
    /// `model hertz`: LIGGGHTS' Hertz law (Hertz–Mindlin with damping).
    Hertz,
    /// `model hooke`: LIGGGHTS' linear spring-dashpot fitted to Hertz at `characteristicVelocity`.
    Hooke,
    /// `model mc_advanced`: the advanced multi-contact law (Ghods et al. 2022, Eqs. 2–3).
    McAdvanced,
    /// `model hooke/hysteresis`: LIGGGHTS' hysteretic hooke spring with adhesion.
    HookeHysteresis,
}

impl std::str::FromStr for NormalModel {
    type Err = String;
    fn from_str(s: &str) -> R<Self> {
        match s {
            "hertz" => Ok(NormalModel::Hertz),
            "hooke" => Ok(NormalModel::Hooke),
            "mc_advanced" => Ok(NormalModel::McAdvanced),
            "hooke/hysteresis" => Ok(NormalModel::HookeHysteresis),
            other => Err(unsupported(&format!(
                "granular model '{other}' (hertz, hooke, hooke/hysteresis or mc_advanced)"
            ))),
        }
    }
}

/// `tangential history|no_history`.
fn tangential_model(s: &str) -> R<Tangential> {
    match s {
        "history" => Ok(Tangential::History),
        "no_history" => Ok(Tangential::NoHistory),
        other => Err(unsupported(&format!("tangential model '{other}' (history or no_history)"))),
    }
}

#[derive(Debug, Clone, PartialEq)]
pub(super) struct GranModel {
    /// `None` until a `model` keyword is read (it is required).
    pub(super) model: Option<NormalModel>,
    pub(super) tangential: Tangential,
    pub(super) surface_mc: bool,
    pub(super) mpr_test: MprTest,
    /// `pairRadii stock`: pairs with LIGGGHTS's radius convention (see docs/dem.md).
    pub(super) stock_pair_radii: bool,
    /// `geometryTolerance TOL` (mc_advanced): see `World::mc_geometry_tolerance`.
    pub(super) geometry_tolerance: Option<f64>,
    /// `updateEvery K` (mc_advanced): see `World::mc_every`.
    pub(super) update_every: Option<u64>,
    /// `mcAccuracy EPS` (mc_advanced): see `World::mc_accuracy`.
    pub(super) mc_accuracy: Option<f64>,
    /// `mcAccuracyCheck yes|no` (mc_advanced with mcAccuracy): see `World::mc_accuracy_check`.
    pub(super) mc_accuracy_check: Option<bool>,
    /// `tangential_damping on|off` (on by default, as in LIGGGHTS); off only with model hooke.
    pub(super) tangential_damping: bool,
    /// `limitForce on|off` (model hooke; off by default).
    pub(super) limit_force: bool,
    /// `ktToKnUser on|off` (model hooke; off by default).
    pub(super) kt_to_kn: bool,
    /// `cohesion sjkr` (`cohesion off`, the default: false).
    pub(super) cohesion: bool,
    /// `tangential_reduce on|off` (cohesion sjkr; off by default): the Coulomb limit sees the cohesion.
    pub(super) tangential_reduce: bool,
    /// `rolling_friction cdt|epsd|epsd2` (`rolling_friction off`, the default: None).
    pub(super) rolling: Option<RollStyle>,
}

/// A rolling model of `pair_style gran` / `fix wall/gran`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RollStyle {
    Cdt,
    Epsd,
    Epsd2,
}

impl RollStyle {
    fn name(self) -> &'static str {
        match self {
            RollStyle::Cdt => "cdt",
            RollStyle::Epsd => "epsd",
            RollStyle::Epsd2 => "epsd2",
        }
    }
}

/// An `on|off` value of a model option.
fn on_off(key: &str, x: &str) -> R<bool> {
    match x {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("{key} must be 'on' or 'off', got '{x}'")),
    }
}

impl GranModel {
    /// The multi-contact settings as the shared table holds them (`physics::mc_settings`), the
    /// defaults where the line gives none.
    pub(super) fn mc_values(&self) -> [f64; 4] {
        [
            f64::from(u8::from(self.mpr_test == MprTest::Signed)),
            f64::from(u8::from(self.stock_pair_radii)),
            self.geometry_tolerance.unwrap_or(McSetting::GeometryTolerance.default_value()),
            self.update_every.map_or(McSetting::UpdateEvery.default_value(), |k| k as f64),
        ]
    }

    /// One model setting `key value` of a `pair_style gran` or `fix wall/gran` line; false if `key`
    /// is not a model setting (the caller decides what else it may be).
    pub(super) fn setting(&mut self, key: &str, v: Option<&str>) -> R<bool> {
        // The multi-contact settings: one table for this reader and the plugin.
        if let (Some(s), Some(x)) = (McSetting::from_name(key), v) {
            let v = s.parse(x)?;
            match s {
                McSetting::MprTest => self.mpr_test = mc_settings::mpr_test(v),
                McSetting::PairRadii => self.stock_pair_radii = v != 0.0,
                McSetting::GeometryTolerance => self.geometry_tolerance = Some(v),
                McSetting::UpdateEvery => self.update_every = Some(v as u64),
            }
            return Ok(true);
        }
        match (key, v) {
            ("mcAccuracy", Some(x)) => self.mc_accuracy = Some(mc_accuracy(x)?),
            ("mcAccuracyCheck", Some("yes")) => self.mc_accuracy_check = Some(true),
            ("mcAccuracyCheck", Some("no")) => self.mc_accuracy_check = Some(false),
            ("mcAccuracyCheck", Some(x)) => {
                return Err(format!("mcAccuracyCheck must be 'yes' or 'no', got '{x}'"))
            }
            ("tangential_damping", Some(x)) => self.tangential_damping = on_off(key, x)?,
            ("limitForce", Some(x)) => self.limit_force = on_off(key, x)?,
            ("ktToKnUser", Some(x)) => self.kt_to_kn = on_off(key, x)?,
            ("tangential_reduce", Some(x)) => self.tangential_reduce = on_off(key, x)?,
            // LIGGGHTS' default; `viscous on` (hooke's Stokes-number restitution) is not modelled.
            ("viscous", Some("off")) => {}
            ("viscous", Some("on")) => {
                return Err(unsupported("viscous on (the Stokes-number restitution of model hooke)"))
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// The combination is one the engines run, and every setting belongs to the chosen model.
    pub(super) fn check(&self) -> R<()> {
        let advanced = match self.model {
            None => {
                return Err(
                    "pair_style gran: 'model hertz', 'model hooke', 'model hooke/hysteresis' or 'model mc_advanced' is required".into(),
                )
            }
            Some(m) => m == NormalModel::McAdvanced,
        };
        if self.stock_pair_radii && !advanced {
            return Err("pairRadii is a setting of model mc_advanced".into());
        }
        if self.geometry_tolerance.is_some() && !advanced {
            return Err("geometryTolerance is a setting of model mc_advanced".into());
        }
        if self.update_every.is_some() && !advanced {
            return Err("updateEvery is a setting of model mc_advanced".into());
        }
        if self.mc_accuracy.is_some() && !advanced {
            return Err(format!(
                "mcAccuracy is a setting of model mc_advanced: model {} has no multi-contact correction to budget",
                self.name()
            ));
        }
        if self.mc_accuracy_check.is_some() && !advanced {
            return Err("mcAccuracyCheck is a setting of model mc_advanced".into());
        }
        if self.mc_accuracy.is_some() {
            for (given, key) in [
                (self.geometry_tolerance.is_some(), "geometryTolerance"),
                (self.update_every.is_some(), "updateEvery"),
            ] {
                if given {
                    return Err(format!(
                        "mcAccuracy and {key} cannot be combined: the accuracy budget decides per particle and step when Eq. 2 is recomputed; drop {key}"
                    ));
                }
            }
        }
        if self.mc_accuracy_check == Some(true) && self.mc_accuracy.is_none_or(|e| e == 0.0) {
            return Err(
                "mcAccuracyCheck yes needs mcAccuracy EPS > 0 (EPS = 0 is exact: nothing to check)".into()
            );
        }
        if self.tangential_reduce && !self.cohesion {
            return Err("tangential_reduce is a setting of cohesion sjkr".into());
        }
        if let Some(r) = self.rolling.filter(|_| advanced || self.surface_mc) {
            return Err(unsupported(&format!("rolling_friction {} with a multi-contact model", r.name())));
        }
        if self.cohesion && (advanced || self.surface_mc) {
            return Err(unsupported("cohesion sjkr with a multi-contact model"));
        }
        let hysteresis = self.model == Some(NormalModel::HookeHysteresis);
        if hysteresis {
            // LIGGGHTS 3.8 registers these settings for hooke/hysteresis but its force never reads them.
            for (on, what) in [(self.limit_force, "limitForce on"), (self.kt_to_kn, "ktToKnUser on")] {
                if on {
                    return Err(format!(
                        "{what} has no effect in LIGGGHTS 3.8's model hooke/hysteresis (it is read by model hooke only): drop it"
                    ));
                }
            }
            if self.surface_mc {
                return Err(
                    "model hooke/hysteresis has no multi-contact form: drop 'surface multicontact'".into()
                );
            }
        }
        let hooke = self.model == Some(NormalModel::Hooke) || hysteresis;
        if !hooke {
            for (on, what) in [
                (!self.tangential_damping, "tangential_damping off"),
                (self.limit_force, "limitForce on"),
                (self.kt_to_kn, "ktToKnUser on"),
            ] {
                if on {
                    return Err(unsupported(&format!(
                        "{what} with model {} (model hooke only)",
                        self.name()
                    )));
                }
            }
        }
        if hooke && self.surface_mc {
            return Err(
                "model hooke has no multi-contact form: drop 'surface multicontact' (it goes with model hertz)".into(),
            );
        }
        if advanced && self.surface_mc {
            return Err("mc_advanced is itself a multi-contact model: drop 'surface multicontact'".into());
        }
        Ok(())
    }

    /// The model is `mc_advanced` (after [`GranModel::check`], a model is set).
    pub(super) fn is_mc_advanced(&self) -> bool {
        self.model == Some(NormalModel::McAdvanced)
    }

    /// The model is `hooke` or `hooke/hysteresis` (which starts from hooke's stiffness and damping).
    pub(super) fn is_hooke(&self) -> bool {
        matches!(self.model, Some(NormalModel::Hooke | NormalModel::HookeHysteresis))
    }

    /// The model is `hooke/hysteresis`.
    pub(super) fn is_hysteresis(&self) -> bool {
        self.model == Some(NormalModel::HookeHysteresis)
    }

    /// The `model hooke` options compared between a wall and the pair style: (tangential_damping,
    /// limitForce, ktToKnUser).
    pub(super) fn hooke_options(&self) -> (bool, bool, bool) {
        (self.tangential_damping, self.limit_force, self.kt_to_kn)
    }

    /// The model's deck name, for messages.
    pub(super) fn name(&self) -> &'static str {
        match self.model {
            Some(NormalModel::Hertz) => "hertz",
            Some(NormalModel::Hooke) => "hooke",
            Some(NormalModel::McAdvanced) => "mc_advanced",
            Some(NormalModel::HookeHysteresis) => "hooke/hysteresis",
            None => "(none)",
        }
    }
}

/// `mcAccuracy` value: a finite number ≥ 0 (the accuracy budget EPS; 0 is exact).
pub(super) fn mc_accuracy(x: &str) -> R<f64> {
    match x.parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err(format!(
            "mcAccuracy must be a finite number >= 0 (the relative error budget of the multi-contact corrections; 0 = exact), got '{x}'"
        )),
    }
}

/// Largest `updateEvery` (both engines; the plugin keeps it in an `int`).
pub use crate::physics::mc_settings::MAX_UPDATE_EVERY;

impl Deck {
    pub(super) fn gran_model(a: &[&str], start: usize) -> R<(GranModel, usize)> {
        let mut m = GranModel {
            model: None,
            tangential: Tangential::History,
            surface_mc: false,
            mpr_test: MprTest::Abs,
            stock_pair_radii: false,
            geometry_tolerance: None,
            update_every: None,
            mc_accuracy: None,
            mc_accuracy_check: None,
            tangential_damping: true,
            limit_force: false,
            kt_to_kn: false,
            cohesion: false,
            tangential_reduce: false,
            rolling: None,
        };
        let mut k = start;
        while k < a.len() {
            let v = a.get(k + 1).copied();
            match (a[k], v) {
                ("model", Some(x)) => m.model = Some(x.parse()?),
                ("tangential", Some(x)) => m.tangential = tangential_model(x)?,
                ("rolling_friction", Some("off")) => m.rolling = None,
                ("rolling_friction", Some("cdt")) => m.rolling = Some(RollStyle::Cdt),
                ("rolling_friction", Some("epsd")) => m.rolling = Some(RollStyle::Epsd),
                ("rolling_friction", Some("epsd2")) => m.rolling = Some(RollStyle::Epsd2),
                ("rolling_friction", Some("epsd3")) => {
                    return Err(unsupported(
                        "rolling_friction epsd3 (its user-set rolling stiffness coefficientRollingStiffness is not modelled; cdt, epsd, epsd2 or off)",
                    ))
                }
                ("rolling_friction", Some(other)) => {
                    return Err(unsupported(&format!("rolling model '{other}' (cdt, epsd, epsd2 or off)")))
                }
                ("cohesion", Some("off")) => m.cohesion = false,
                ("cohesion", Some("sjkr")) => m.cohesion = true,
                ("cohesion", Some(other)) => {
                    return Err(unsupported(&format!("cohesion model '{other}' (sjkr or off)")))
                }
                ("surface", Some("default")) => m.surface_mc = false,
                ("surface", Some("multicontact")) => m.surface_mc = true,
                (key, v) => {
                    if !m.setting(key, v)? {
                        break;
                    }
                }
            }
            k += 2;
        }
        m.check()?;
        Ok((m, k))
    }

    pub(super) fn pair_style(&mut self, a: &[&str]) -> R<()> {
        if a.get(1) != Some(&"gran") {
            return Err(unsupported(&format!("pair_style {}", a.get(1).unwrap_or(&""))));
        }
        let (m, k) = Self::gran_model(a, 2)?;
        if k != a.len() {
            return Err(unsupported(&format!("pair_style gran keyword {}", a[k])));
        }
        // The command-line options, when given, take precedence over the deck's settings; they
        // approximate the multi-contact pass of mc_advanced and of nothing else.
        let (cli_tol, cli_every) = (self.cli_geometry_tolerance, self.cli_mc_every);
        if !m.is_mc_advanced() && (cli_tol > 0.0 || cli_every > 1) {
            return Err(format!(
                "--mc-geometry-tolerance and --mc-update-every apply to model mc_advanced only; this pair style is model {}",
                m.name()
            ));
        }
        let (cli_eps, cli_check) = (self.cli_mc_accuracy, self.cli_mc_accuracy_check);
        if !m.is_mc_advanced() && (cli_eps.is_some() || cli_check.is_some()) {
            return Err(format!(
                "--mc-accuracy and --mc-accuracy-check apply to model mc_advanced only; this pair style is model {} (no multi-contact correction)",
                m.name()
            ));
        }
        // A pair style defined again starts from the defaults, as in LIGGGHTS.
        self.world.mc_geometry_tolerance =
            if cli_tol > 0.0 { cli_tol } else { m.geometry_tolerance.unwrap_or(0.0) };
        self.world.mc_every = if cli_every > 0 { cli_every } else { m.update_every.unwrap_or(1) };
        let eps = cli_eps.or(m.mc_accuracy).unwrap_or(0.0);
        if eps > 0.0 && (self.world.mc_geometry_tolerance > 0.0 || self.world.mc_every > 1) {
            return Err(
                "mcAccuracy (or --mc-accuracy) cannot be combined with geometryTolerance or updateEvery (or their command-line options): the accuracy budget decides per particle and step when Eq. 2 is recomputed".into(),
            );
        }
        let deck_check = if m.mc_accuracy_check == Some(true) { DEFAULT_CHECK_EVERY } else { 0 };
        let check = cli_check.unwrap_or(deck_check);
        if check > 0 && eps == 0.0 {
            return Err("mcAccuracyCheck (or --mc-accuracy-check) needs mcAccuracy EPS > 0 (EPS = 0 is exact: nothing to check)".into());
        }
        self.world.mc_accuracy = eps;
        self.world.mc_accuracy_check = check;
        self.pair = Some(m);
        Ok(())
    }

    /// `fix property/global characteristicVelocity scalar V`, which `model hooke` needs.
    fn characteristic_velocity(&self) -> R<f64> {
        const NAME: &str = "characteristicVelocity";
        let (style, v) = self.props.get(NAME).ok_or_else(|| {
            format!("fix property/global {NAME} is missing (model hooke needs 'fix ID all property/global {NAME} scalar V')")
        })?;
        match (style.as_str(), v.as_slice()) {
            ("scalar", &[x]) if x.is_finite() && x > 0.0 => Ok(x),
            ("scalar", _) => Err(format!("property {NAME} must be one number > 0")),
            _ => Err(format!("property {NAME} must be scalar")),
        }
    }

    pub(super) fn prepare(&mut self) -> R<()> {
        let pair = self.pair.clone().ok_or("run before pair_style gran")?;
        let nt = self.ntypes;
        if nt == 0 {
            return Err("run before the box and atom types exist".into());
        }
        let per_type = |s: &Self, name: &str| -> R<Vec<f64>> {
            let (style, v) =
                s.props.get(name).ok_or_else(|| format!("fix property/global {name} is missing"))?;
            if style != "peratomtype" {
                return Err(format!("property {name} must be peratomtype"));
            }
            if v.len() != nt {
                return Err(format!("property {name}: {} values for {nt} atom types", v.len()));
            }
            Ok(v.clone())
        };
        let per_pair = |s: &Self, name: &str| -> R<Vec<f64>> {
            let (style, v) =
                s.props.get(name).ok_or_else(|| format!("fix property/global {name} is missing"))?;
            if style != "peratomtypepair" {
                return Err(format!("property {name} must be peratomtypepair"));
            }
            if v.first().map(|n| *n as usize) != Some(nt) || v.len() != 1 + nt * nt {
                return Err(format!("property {name}: expected {nt} followed by {} values", nt * nt));
            }
            Ok(v[1..].to_vec())
        };
        let e = per_type(self, "youngsModulus")?;
        let nu = per_type(self, "poissonsRatio")?;
        let rest = per_pair(self, "coefficientRestitution")?;
        let fric = per_pair(self, "coefficientFriction")?;
        let (closure, gammas, mprs): (Closure, Vec<f64>, Option<Vec<f64>>) = if pair.is_mc_advanced() {
            (
                Closure::MultiContact,
                per_type(self, "geometricPrefactor")?,
                Some(per_type(self, "maxPenetrationRatio")?),
            )
        } else if pair.surface_mc {
            let g = self.mc_gamma.ok_or("surface multicontact needs fix multicontact/halfspace")?;
            (Closure::MultiContact, vec![g; nt], None)
        } else {
            if self.mc_gamma.is_some() {
                return Err("fix multicontact/halfspace needs 'surface multicontact' in pair_style".into());
            }
            (Closure::Hertz, vec![0.0; nt], None)
        };
        let mut mats = Vec::with_capacity(nt);
        for t in 0..nt {
            let cap = mprs.as_ref().map(|m| (m[t], pair.mpr_test));
            mats.push(
                Material::new(e[t], nu[t], gammas[t], cap)
                    .map_err(|e| format!("atom type {}: {e}", t + 1))?,
            );
        }
        self.world.set_materials(mats, &rest, &fric, pair.tangential)?;
        if pair.is_hooke() {
            self.world.use_hooke(self.characteristic_velocity()?, &rest, pair.hooke_options())?;
        }
        // The walls run the pair law without what they leave out (see `fix wall/gran`): plain
        // hooke beside hooke/hysteresis pairs, cohesion only where their own line asks for it.
        let mut walls = self.world.coeffs.clone();
        if pair.is_hysteresis() {
            let need = |name: &str| {
                if self.props.contains_key(name) {
                    per_pair(self, name)
                } else {
                    Err(format!(
                        "fix property/global {name} is missing (model hooke/hysteresis needs 'fix ID all property/global {name} peratomtypepair N ...')"
                    ))
                }
            };
            let (k2, kc, phi) = (
                need("coefficientMaxElasticStiffness")?,
                need("coefficientAdhesionStiffness")?,
                need("coefficientPlasticityDepth")?,
            );
            self.world.use_hysteresis(&k2, &kc, &phi)?;
        }
        let wall_model = self.wall_model.clone();
        if pair.cohesion || wall_model.as_ref().is_some_and(|w| w.cohesion) {
            const NAME: &str = "cohesionEnergyDensity";
            if !self.props.contains_key(NAME) {
                return Err(format!(
                    "fix property/global {NAME} is missing (cohesion sjkr needs 'fix ID all property/global {NAME} peratomtypepair N ...')"
                ));
            }
            let ced = per_pair(self, NAME)?;
            if pair.cohesion {
                World::add_cohesion(&mut self.world.coeffs, nt, &ced, pair.tangential_reduce)?;
            }
            if let Some(w) = wall_model.as_ref().filter(|w| w.cohesion) {
                World::add_cohesion(&mut walls, nt, &ced, w.tangential_reduce)?;
            }
        }
        let wall_rolling = wall_model.as_ref().and_then(|w| w.rolling);
        if let Some(first) = pair.rolling.or(wall_rolling) {
            let need = |name: &str, style: RollStyle| {
                if self.props.contains_key(name) {
                    per_pair(self, name)
                } else {
                    Err(format!(
                        "fix property/global {name} is missing (rolling_friction {} needs 'fix ID all property/global {name} peratomtypepair N ...')",
                        style.name()
                    ))
                }
            };
            let mu_r = need("coefficientRollingFriction", first)?;
            // `epsd` alone has a dashpot.
            let epsd = [pair.rolling, wall_rolling].contains(&Some(RollStyle::Epsd));
            let damping =
                if epsd { Some(need("coefficientRollingViscousDamping", RollStyle::Epsd)?) } else { None };
            for (style, table) in [(pair.rolling, &mut self.world.coeffs), (wall_rolling, &mut walls)] {
                match style {
                    None => {}
                    Some(RollStyle::Cdt) => World::add_rolling_friction(table, nt, &mu_r)?,
                    Some(RollStyle::Epsd) => World::add_rolling_spring(table, nt, &mu_r, damping.as_deref())?,
                    Some(RollStyle::Epsd2) => World::add_rolling_spring(table, nt, &mu_r, None)?,
                }
            }
        }
        self.world.wall_coeffs = (walls != self.world.coeffs).then_some(walls);
        self.world.closure = Some(closure);
        self.world.liggghts_radii = pair.surface_mc || pair.stock_pair_radii;
        self.world.mc_range =
            self.world.mc_range.max(if closure == Closure::MultiContact { 1.25 } else { 1.0 });
        Ok(())
    }
}
