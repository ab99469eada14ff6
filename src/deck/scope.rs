//! Decks built on LIGGGHTS features outside this project's scope (heat transfer, SPH,
//! superquadrics, multisphere bodies, ParScale/CFD coupling, wear, and the LIGGGHTS 2.x granular
//! pair styles that LIGGGHTS 3.8 no longer reads) stop before their first line
//! runs, with the line that needs the feature: running their mechanical part alone would give
//! output that looks complete and is not.

/// The first line (1-based) of `text` that needs an out-of-scope feature, and which feature.
pub(super) fn out_of_scope(text: &str) -> Option<(usize, String)> {
    for (k, line) in text.lines().enumerate() {
        let w: Vec<&str> = super::strip_comment(line).split_whitespace().collect();
        if let Some(what) = feature(&w) {
            return Some((k + 1, format!("out of scope: {what}")));
        }
    }
    None
}

fn feature(w: &[&str]) -> Option<String> {
    let style = |s: &str| -> Option<&'static str> {
        if s.starts_with("heat/gran") {
            Some("heat transfer")
        } else if s.contains("multisphere") {
            Some("multisphere bodies")
        } else if s.split('/').any(|seg| seg == "sph") {
            Some("smoothed-particle hydrodynamics (SPH)")
        } else if s.contains("superquadric") {
            Some("superquadric particles")
        } else if s.starts_with("couple/cfd") || s.starts_with("cfd") {
            Some("CFD coupling")
        } else {
            None
        }
    };
    match w {
        ["atom_style", s, ..] => style(s).map(|f| format!("{f} (atom_style {s})")),
        ["fix", _, _, s, rest @ ..] => {
            if let Some(f) = style(s) {
                return Some(format!("{f} (fix {s})"));
            }
            if s.starts_with("mesh/surface") && rest.contains(&"wear") {
                return Some(format!("wear of mesh walls (fix {s} … wear)"));
            }
            None
        }
        ["pair_style", s, ..] if style(s).is_some() => style(s).map(|f| format!("{f} (pair_style {s})")),
        // LIGGGHTS 2.x styles: LIGGGHTS 3.8 itself stops on them, so there is nothing to agree with.
        ["pair_style", s, ..] if s.starts_with("gran/") => Some(format!(
            "the LIGGGHTS 2.x pair_style {s}, which LIGGGHTS 3.8 rejects too ('Invalid pair style'); write 'pair_style gran model hertz tangential history'"
        )),
        // ParScale's own input files (they sit next to the decks that drive the coupling).
        ["particle_mesh" | "particle_data" | "coupling" | "modelEqs" | "control", ..] => {
            Some(format!("a ParScale particle-model input ('{}'), not a LIGGGHTS deck", w[0]))
        }
        _ => None,
    }
}
