//! Thermo output: the header and the line of `thermo_style custom` columns.

use super::*;

impl Deck {
    pub(super) fn thermo_header(&self) -> String {
        let mut s = String::new();
        for c in &self.thermo_cols {
            let (name, is_int) = match c.as_str() {
                "step" => ("Step".to_string(), true),
                "atoms" => ("Atoms".to_string(), true),
                "ke" => ("KinEng".to_string(), false),
                "pe" => ("PotEng".to_string(), false),
                "etotal" => ("TotEng".to_string(), false),
                "vol" => ("Volume".to_string(), false),
                "time" => ("Time".to_string(), false),
                "dt" => ("Dt".to_string(), false),
                "lx" => ("Lx".to_string(), false),
                "ly" => ("Ly".to_string(), false),
                "lz" => ("Lz".to_string(), false),
                other => (other.get(2..).unwrap_or(other).to_string(), false),
            };
            if is_int {
                s.push_str(&format!("{name:>8} "));
            } else {
                s.push_str(&format!("{name:>14} "));
            }
        }
        s
    }

    pub(super) fn thermo_line(&self) -> R<String> {
        let mut s = String::new();
        for c in &self.thermo_cols {
            let v = self.value_of(c, 0)?;
            if matches!(c.as_str(), "step" | "atoms") {
                s.push_str(&format!("{:>8} ", v as i64));
            } else {
                match &self.thermo_float {
                    Some(spec) => s.push_str(&format::number(spec, v)),
                    None => s.push_str(&format::gw(v, 14, 8)),
                }
                s.push(' ');
            }
        }
        Ok(s)
    }
}
