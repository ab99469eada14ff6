//! Per-particle values: `compute ID group property/atom col…` and atom-style variables
//! (`variable NAME atom EXPR`, LAMMPS/LIGGGHTS 3.8 `src/variable.cpp`, `compute_atom`).
//!
//! An atom-style formula is the equal-style grammar of [`expr`] evaluated once per particle, where
//! a bare per-atom keyword (`x`, `vx`, `radius`, `mass`, `type`, `id`, …, the names of
//! [`Col::parse`]), a property/atom compute (`c_ID`, or `c_ID[k]` for its k-th column) and another
//! atom-style variable (`v_NAME`) take that particle's value; everything else (numbers,
//! equal-style variables, thermo keywords, global computes, `x[5]` for atom 5) has one value for
//! all particles and is read as in an equal-style formula.

use super::*;

/// Columns of a `compute property/atom`.
pub(super) fn property_atom(id: &str, cols: &[&str]) -> R<Vec<Col>> {
    if cols.is_empty() {
        return Err(format!("compute {id} property/atom: expected at least one attribute"));
    }
    cols.iter()
        .map(|c| {
            Col::parse(c).ok_or_else(|| unsupported(&format!("compute {id} property/atom attribute {c}")))
        })
        .collect()
}

/// Resolves the names of an atom-style formula for particle `i`.
struct AtomResolver<'a> {
    deck: &'a Deck,
    i: usize,
    depth: usize,
}

impl expr::Resolve for AtomResolver<'_> {
    fn resolve(&self, name: &str) -> R<f64> {
        self.deck.atom_value_of(name, self.i, self.depth)
    }
}

impl Deck {
    /// The value of the atom-style formula `f` for particle `i`.
    fn eval_atom_formula(&self, f: &str, i: usize, depth: usize) -> R<f64> {
        if depth > 50 {
            return Err("variable definitions refer to each other in a loop".into());
        }
        expr::eval(f, &AtomResolver { deck: self, i, depth: depth + 1 })
    }

    /// A name inside an atom-style formula, for particle `i`.
    fn atom_value_of(&self, name: &str, i: usize, depth: usize) -> R<f64> {
        if let Some(col) = Col::parse(name) {
            return Ok(col.value(&self.world, i));
        }
        if let Some(c) = name.strip_prefix("c_") {
            let (id, idx) = split_index(c)?;
            if let Some(ComputeKind::PropertyAtom(cols)) = self.computes.get(id) {
                return match (cols.len(), idx) {
                    (1, None) => Ok(cols[0].value(&self.world, i)),
                    (n, Some(k)) if n > 1 && k <= n => Ok(cols[k - 1].value(&self.world, i)),
                    (1, Some(k)) => Err(format!(
                        "c_{id}[{k}]: compute {id} property/atom has one column, referenced as c_{id}"
                    )),
                    (n, Some(k)) => Err(format!("c_{id}[{k}]: compute {id} property/atom has {n} columns")),
                    (n, None) => Err(format!(
                        "c_{id}: compute {id} property/atom has {n} columns, referenced as c_{id}[k]"
                    )),
                };
            }
        }
        if let Some(v) = name.strip_prefix("v_") {
            if let Some(Var::Atom(f)) = self.vars.get(v) {
                return self.eval_atom_formula(f, i, depth);
            }
        }
        self.value_of(name, depth)
    }

    /// Per particle, the value of variable `name`, atom-style or equal-style (then the same for
    /// every particle), as LIGGGHTS' `fix adapt` reads it (`src/fix_adapt.cpp`, `change_settings`).
    /// `user` names the command asking, for the messages.
    pub(super) fn per_atom_values(&self, name: &str, user: &str) -> R<Vec<f64>> {
        let n = self.world.p.len();
        match self.vars.get(name) {
            Some(Var::Atom(f)) => (0..n).map(|i| self.eval_atom_formula(f, i, 0)).collect(),
            Some(Var::Equal(f)) => Ok(vec![self.eval_formula(f, 0)?; n]),
            Some(_) => Err(format!("{user}: variable {name} is neither atom-style nor equal-style")),
            None => Err(format!("{user}: variable {name} does not exist")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deck_with_two_particles() -> Deck {
        let mut d =
            Deck::new(Path::new("in.test"), &Options { log: Some("none".into()), ..Default::default() })
                .unwrap();
        d.world.p.push(1, 0, Vec3::new(0.1, 0.2, 0.3), 0.004, 2500.0);
        d.world.p.push(2, 0, Vec3::new(-1.0, 0.5, 2.0), 0.010, 1000.0);
        d.world.p.v[1] = Vec3::new(0.0, -3.0, 0.0);
        d
    }

    fn cmd(d: &mut Deck, line: &str) {
        d.command(line).unwrap();
    }

    /// Hand values: particle 1 has r = 0.002, x = 0.1, m = 4/3 π 0.002³ 2500; particle 2 has
    /// r = 0.005, vy = -3, type 1.
    #[test]
    fn atom_variables_read_property_atom_columns_per_particle() {
        let mut d = deck_with_two_particles();
        cmd(&mut d, "compute rad all property/atom radius");
        cmd(&mut d, "compute p all property/atom x vy mass");
        cmd(&mut d, "variable k equal 3");
        cmd(&mut d, "variable a atom 2*c_rad+v_k*c_p[1]");
        cmd(&mut d, "variable b atom v_a-x+c_p[2]*type+id");
        let a = d.per_atom_values("a", "test").unwrap();
        assert_eq!(a, vec![2.0 * 0.002 + 3.0 * 0.1, 2.0 * 0.005 - 3.0]);
        let b = d.per_atom_values("b", "test").unwrap();
        assert_eq!(b, vec![a[0] - 0.1 + 0.0 + 1.0, a[1] + 1.0 - 3.0 + 2.0]);
        cmd(&mut d, "variable m atom c_p[3]/(4*PI/3*radius^3)");
        let m = d.per_atom_values("m", "test").unwrap();
        assert!((m[0] - 2500.0).abs() < 1e-9 && (m[1] - 1000.0).abs() < 1e-9, "{m:?}");
        // Equal-style: one value for all.
        assert_eq!(d.per_atom_values("k", "test").unwrap(), vec![3.0, 3.0]);
        // Misuse is named.
        cmd(&mut d, "variable bad atom c_p");
        let e = d.per_atom_values("bad", "test").unwrap_err();
        assert!(e.contains("compute p property/atom has 3 columns"), "{e}");
        cmd(&mut d, "variable bad atom c_rad[2]");
        assert!(d.per_atom_values("bad", "test").unwrap_err().contains("has one column"));
        let e = d.eval_formula("v_a", 0).unwrap_err();
        assert!(e.contains("variable a is atom-style"), "{e}");
        let e = d.eval_formula("c_rad", 0).unwrap_err();
        assert!(e.contains("compute rad is per-atom"), "{e}");
        cmd(&mut d, "variable s string abc");
        assert!(d
            .per_atom_values("s", "fix g adapt")
            .unwrap_err()
            .contains("neither atom-style nor equal-style"));
        assert!(d.per_atom_values("zz", "fix g adapt").unwrap_err().contains("variable zz does not exist"));
        assert!(d.command("compute q all property/atom foo").unwrap_err().contains("attribute foo"));
    }
}
