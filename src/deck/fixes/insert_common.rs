//! The keywords LIGGGHTS 3.8 gives every insertion fix through its base class `FixInsert`
//! (`fix_insert.cpp`): `seed`, `distributiontemplate`, `random_distribute`, `vel constant` and
//! `omega constant`, read here once for `fix insert/pack` and `fix insert/stream`. Each fix reads
//! the rest itself: its own keywords, and those of the base class whose accepted values or
//! messages differ between the two here (`insert_every`, `overlapcheck`, `all_in`, `maxattempt`,
//! `verbose`; `nparticles`, `mass`, `particlerate`, `massrate` only for the stream).

use crate::deck::*;

/// The common keywords of an insertion fix, as read (defaults: `random_distribute exact`, no
/// velocity, zero spin).
#[derive(Debug)]
pub(super) struct InsertKeywords {
    pub(super) seed: Option<u64>,
    pub(super) dist: Option<String>,
    /// `random_distribute exact` (true) or `uncorrelated`.
    pub(super) exact: bool,
    pub(super) vel: Option<Vec3>,
    pub(super) omega: Vec3,
}

/// A seed as LIGGGHTS asks for it (a whole number; LIGGGHTS wants a prime > 10000, which only
/// matters to its own generator).
pub(super) fn seed(s: &str, what: &str) -> R<u64> {
    s.parse::<u64>().map_err(|_| format!("{what}: seed must be a whole number >= 0, got '{s}'"))
}

/// `random_distribute exact|uncorrelated` of the insertion fixes: whether each insertion holds the
/// distribution's exact proportions.
pub(super) fn random_distribute(v: &str, what: &str) -> R<bool> {
    match v {
        "exact" => Ok(true),
        "uncorrelated" => Ok(false),
        _ => Err(format!("{what}: random_distribute must be exact or uncorrelated, got '{v}'")),
    }
}

pub(super) fn positive(s: &str, what: &str) -> R<f64> {
    let v = num(s)?;
    if !(v > 0.0 && v.is_finite()) {
        return Err(format!("{what} must be > 0, got {s}"));
    }
    Ok(v)
}

impl Deck {
    /// Reads the keyword–value pairs `a[4..]` of the insertion fix `what`: the common ones here,
    /// every other through `own(keyword, value)`, which reads the fix's own keywords and stops on
    /// the ones it does not know (with the fix's message).
    pub(super) fn insert_keywords(
        &self,
        a: &[&str],
        what: &str,
        mut own: impl FnMut(&str, &str) -> R<()>,
    ) -> R<InsertKeywords> {
        let mut c = InsertKeywords { seed: None, dist: None, exact: true, vel: None, omega: Vec3::zeros() };
        let arg = |j: usize| a.get(j).copied().ok_or_else(|| format!("{what}: {} needs a value", a[j - 1]));
        let vec3 =
            |j: usize| -> R<Vec3> { Ok(Vec3::new(num(arg(j)?)?, num(arg(j + 1)?)?, num(arg(j + 2)?)?)) };
        let mut k = 4;
        while k < a.len() {
            let v = arg(k + 1)?;
            k += 2;
            match a[k - 2] {
                "seed" => c.seed = Some(seed(v, what)?),
                "distributiontemplate" => {
                    if !self.insertion.has_distribution(v) {
                        return Err(format!("{what}: {v} is not a particledistribution/discrete fix"));
                    }
                    c.dist = Some(v.to_string());
                }
                "random_distribute" => c.exact = random_distribute(v, what)?,
                "vel" if v == "constant" => {
                    c.vel = Some(vec3(k)?);
                    k += 3;
                }
                "omega" if v == "constant" => {
                    c.omega = vec3(k)?;
                    k += 3;
                }
                key => own(key, v)?,
            }
        }
        Ok(c)
    }
}
