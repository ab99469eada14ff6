//! The settings of `model mc_advanced` on a `pair_style gran` / `fix wall/gran` line, read by both
//! engines from this one table: `mcdem run`'s deck reader calls [`McSetting::parse`] directly, the
//! LIGGGHTS plugin through the C ABI (`mcdem_setting_*` in `src/ffi/setup.rs`), so that a name, a limit
//! or an error message exists once. Values travel as one `f64` per setting (a choice as 0 or 1, a
//! step count as a whole number) because that is what crosses the C boundary without a struct per
//! setting; the typed accessors below turn them back.

use std::ffi::CStr;
use std::fmt;

use super::ghods2022::MprTest;

/// Largest `updateEvery` (both engines; the plugin keeps it in an `int`).
pub const MAX_UPDATE_EVERY: u64 = 1_000_000_000;

/// One setting of `model mc_advanced`. The discriminants are the `MCDEM_SETTING_*` indices of
/// `native/mcdem.h`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum McSetting {
    /// `mprTest abs|signed`: which side of the Eq. 3 test trips the cap (docs/spec.md §1).
    MprTest = 0,
    /// `pairRadii modified|stock`: the pair radius convention (docs/dem.md).
    PairRadii = 1,
    /// `geometryTolerance TOL`: the influence cache's tolerance, a fraction of the radius.
    GeometryTolerance = 2,
    /// `updateEvery K`: the Eq. 2 corrections recomputed every K steps.
    UpdateEvery = 3,
}

/// Every setting, in index order.
pub const MC_SETTINGS: [McSetting; 4] =
    [McSetting::MprTest, McSetting::PairRadii, McSetting::GeometryTolerance, McSetting::UpdateEvery];

impl McSetting {
    /// The keyword on the deck line, NUL-terminated for the C ABI.
    pub fn c_name(self) -> &'static CStr {
        match self {
            McSetting::MprTest => c"mprTest",
            McSetting::PairRadii => c"pairRadii",
            McSetting::GeometryTolerance => c"geometryTolerance",
            McSetting::UpdateEvery => c"updateEvery",
        }
    }

    /// The keyword on the deck line.
    pub fn name(self) -> &'static str {
        self.c_name().to_str().expect("the keywords are ASCII")
    }

    pub fn from_name(name: &str) -> Option<McSetting> {
        MC_SETTINGS.into_iter().find(|s| s.name() == name)
    }

    pub fn from_index(k: i32) -> Option<McSetting> {
        usize::try_from(k).ok().and_then(|k| MC_SETTINGS.get(k).copied())
    }

    /// The value when the deck line does not give the setting.
    pub fn default_value(self) -> f64 {
        match self {
            McSetting::MprTest | McSetting::PairRadii | McSetting::GeometryTolerance => 0.0,
            McSetting::UpdateEvery => 1.0,
        }
    }

    /// Settings of the pair style's multi-contact pass that a wall may only repeat: walls take
    /// part in the pair style's Eq. 2 pass, so a different value there would be a contradiction
    /// rather than a setting. The pair-radius convention is the wall's own.
    pub fn shared_with_walls(self) -> bool {
        !matches!(self, McSetting::PairRadii)
    }

    /// The two words of a choice setting (value 0, value 1).
    fn choices(self) -> Option<(&'static str, &'static str)> {
        match self {
            McSetting::MprTest => Some((MprTest::Abs.as_str(), MprTest::Signed.as_str())),
            McSetting::PairRadii => Some(("modified", "stock")),
            _ => None,
        }
    }

    /// Reads the word after the keyword, strictly: a typo is an error naming the keyword, the word
    /// and what is expected, never a default.
    pub fn parse(self, word: &str) -> Result<f64, String> {
        let name = self.name();
        match self {
            McSetting::MprTest | McSetting::PairRadii => {
                let (off, on) = self.choices().expect("a choice setting");
                match word {
                    w if w == off => Ok(0.0),
                    w if w == on => Ok(1.0),
                    _ => Err(format!("{name} must be '{off}' or '{on}', got '{word}'")),
                }
            }
            McSetting::GeometryTolerance => match word.parse::<f64>() {
                Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
                _ => Err(format!(
                    "{name} must be a finite number >= 0 (a fraction of the particle radius), got '{word}'"
                )),
            },
            McSetting::UpdateEvery => match word.parse::<u64>() {
                Ok(k) if (1..=MAX_UPDATE_EVERY).contains(&k) => Ok(k as f64),
                _ => Err(format!(
                    "{name} must be a whole number of steps from 1 to {MAX_UPDATE_EVERY}, got '{word}'"
                )),
            },
        }
    }

    /// The value as the deck would write it.
    pub fn display(self, value: f64) -> impl fmt::Display {
        struct Shown(McSetting, f64);
        impl fmt::Display for Shown {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match (self.0.choices(), self.0) {
                    (Some((off, on)), _) => f.write_str(if self.1 != 0.0 { on } else { off }),
                    (None, McSetting::UpdateEvery) => write!(f, "{}", self.1 as u64),
                    (None, _) => write!(f, "{}", self.1),
                }
            }
        }
        Shown(self, value)
    }
}

/// Keywords of `model mc_advanced` that only `mcdem run` implements: the accuracy budget, whose
/// per-particle references live in the Rust engine's multi-contact pass, which the plugin does not
/// run (it calls the radius changes through the C ABI). The deck reader parses them
/// (`deck::pair`); the plugin names them as unsupported with [`ENGINE_ONLY_WHY`] rather than
/// LIGGGHTS's generic unknown-keyword error or, worse, running without them.
pub const ENGINE_ONLY: [&CStr; 2] = [c"mcAccuracy", c"mcAccuracyCheck"];

/// Why the plugin refuses an [`ENGINE_ONLY`] keyword, and what to use there instead.
pub const ENGINE_ONLY_WHY: &CStr =
    c"the accuracy budget runs in `mcdem run` only; use geometryTolerance/updateEvery here";

/// The `mprTest` choice of a value from [`McSetting::parse`].
pub fn mpr_test(value: f64) -> MprTest {
    if value != 0.0 {
        MprTest::Signed
    } else {
        MprTest::Abs
    }
}

/// A wall's settings against the pair style's: the first shared setting that the wall line gives
/// with another value, as the message both engines print.
pub fn check_wall(wall: &[f64; 4], given: &[bool; 4], pair: &[f64; 4]) -> Result<(), String> {
    for s in MC_SETTINGS.into_iter().filter(|s| s.shared_with_walls()) {
        let k = s as usize;
        if given[k] && wall[k] != pair[k] {
            let name = s.name();
            return Err(format!(
                "fix wall/gran with model mc_advanced: {name} {} differs from the pair style's {name} {} \
                 (the pair style computes the radius changes of every contact, walls included: set it \
                 there, or repeat its value here)",
                s.display(wall[k]),
                s.display(pair[k])
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_indices_are_the_table_order() {
        for (k, s) in MC_SETTINGS.into_iter().enumerate() {
            assert_eq!(McSetting::from_name(s.name()), Some(s));
            assert_eq!(McSetting::from_index(k as i32), Some(s));
            assert_eq!(s as usize, k);
        }
        assert_eq!(McSetting::from_index(4), None);
        assert_eq!(McSetting::from_index(-1), None);
        assert_eq!(McSetting::from_name("updateevery"), None);
    }

    #[test]
    fn parse_is_strict_and_names_the_problem() {
        assert_eq!(McSetting::MprTest.parse("signed"), Ok(1.0));
        assert_eq!(McSetting::PairRadii.parse("modified"), Ok(0.0));
        assert_eq!(McSetting::GeometryTolerance.parse("1e-3"), Ok(1e-3));
        assert_eq!(McSetting::UpdateEvery.parse("10"), Ok(10.0));
        for (s, bad) in [
            (McSetting::MprTest, "sometimes"),
            (McSetting::PairRadii, "Stock"),
            (McSetting::GeometryTolerance, "-1e-3"),
            (McSetting::GeometryTolerance, "NaN"),
            (McSetting::GeometryTolerance, "inf"),
            (McSetting::UpdateEvery, "0"),
            (McSetting::UpdateEvery, "2.5"),
            (McSetting::UpdateEvery, "1000000001"),
        ] {
            let e = s.parse(bad).unwrap_err();
            assert!(e.starts_with(s.name()) && e.ends_with(&format!("got '{bad}'")), "{e}");
        }
    }

    #[test]
    fn walls_may_repeat_but_not_contradict_the_pair_style() {
        let pair = [0.0, 0.0, 0.0, 10.0];
        let mut wall = pair;
        wall[3] = 5.0;
        let none = [false; 4];
        assert!(check_wall(&wall, &none, &pair).is_ok(), "not given: the pair style's value holds");
        let e = check_wall(&wall, &[false, false, false, true], &pair).unwrap_err();
        assert!(e.contains("updateEvery 5 differs from the pair style's updateEvery 10"), "{e}");
        // The pair radius convention is each line's own.
        let radii = [0.0, 1.0, 0.0, 10.0];
        assert!(check_wall(&radii, &[false, true, false, false], &pair).is_ok());
        let tol = [0.0, 0.0, 1e-3, 10.0];
        let e = check_wall(&tol, &[false, false, true, false], &pair).unwrap_err();
        assert!(
            e.contains("geometryTolerance 0.001 differs from the pair style's geometryTolerance 0"),
            "{e}"
        );
    }
}
