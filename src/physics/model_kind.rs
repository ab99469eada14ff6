//! The contact laws that `mcdem validate` and `mcdem bench` run side by side, as a type: a result
//! row names its law by a variant, so a misspelt law name does not compile. The text of each law
//! (`name`) is the one the recorded CSV/JSON files carry.

use std::fmt;
use std::str::FromStr;

/// A contact law compared by the validation cases and the benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// Plain Hertz (LIGGGHTS `model hertz`).
    Hertz,
    /// The standard multi-contact law, Eq. 2 with γ only (LIGGGHTS `surface multicontact`).
    StandardMc,
    /// The advanced multi-contact law, γ and MPR (Ghods et al. 2022, Eqs. 2–3).
    McAdvanced,
}

impl ModelKind {
    /// The law's name in results files and messages.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Hertz => "hertz",
            ModelKind::StandardMc => "standard_mc",
            ModelKind::McAdvanced => "mc_advanced",
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // `pad`, not `write_str`: tables align the name with `{:<30}`.
        f.pad(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        [ModelKind::Hertz, ModelKind::StandardMc, ModelKind::McAdvanced]
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown model '{s}' (expected hertz, standard_mc or mc_advanced)"))
    }
}

/// The model column of a result row: one of the laws, or a label of its own for a variant (a
/// law with its parameters, an approximation, a parameter scan, a reference solution).
#[derive(Debug, Clone, PartialEq)]
pub enum ModelLabel {
    Law(ModelKind),
    Other(String),
}

impl ModelLabel {
    /// The text written to the results files.
    pub fn as_str(&self) -> &str {
        match self {
            ModelLabel::Law(k) => k.name(),
            ModelLabel::Other(s) => s,
        }
    }
}

impl From<ModelKind> for ModelLabel {
    fn from(k: ModelKind) -> Self {
        ModelLabel::Law(k)
    }
}

/// A text that names a law becomes that law, so that a row built from text compares equal to the
/// law's variant.
impl From<&str> for ModelLabel {
    fn from(s: &str) -> Self {
        s.parse().map_or_else(|_| ModelLabel::Other(s.to_string()), ModelLabel::Law)
    }
}

impl From<String> for ModelLabel {
    fn from(s: String) -> Self {
        match s.parse() {
            Ok(k) => ModelLabel::Law(k),
            Err(_) => ModelLabel::Other(s),
        }
    }
}

impl PartialEq<ModelKind> for ModelLabel {
    fn eq(&self, k: &ModelKind) -> bool {
        *self == ModelLabel::Law(*k)
    }
}

impl fmt::Display for ModelLabel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.as_str())
    }
}

impl serde::Serialize for ModelLabel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::{ModelKind, ModelLabel};

    #[test]
    fn names_parse_back_and_labels_keep_their_text() {
        for k in [ModelKind::Hertz, ModelKind::StandardMc, ModelKind::McAdvanced] {
            assert_eq!(k.name().parse::<ModelKind>(), Ok(k));
            assert_eq!(ModelLabel::from(k.name()), k);
        }
        assert!("standard-mc".parse::<ModelKind>().unwrap_err().contains("unknown model 'standard-mc'"));
        let l = ModelLabel::from(format!("standard_mc nu={}", 0.3));
        assert_eq!(l.as_str(), "standard_mc nu=0.3");
        assert_ne!(l, ModelKind::StandardMc);
        assert_eq!(format!("[{:<7}]", ModelLabel::from(ModelKind::Hertz)), "[hertz  ]");
        assert_eq!(serde_json::to_string(&ModelLabel::from("mc_advanced")).unwrap(), "\"mc_advanced\"");
    }
}
