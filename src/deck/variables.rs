//! Variables (`index`, `string`, `universe`, `equal`, `loop`), `${…}` / `$(…)` substitution, the
//! values formulas and thermo columns read (`v_`, `c_`, `f_`, atom values, keywords), and the
//! flow-control commands (`if`, `next`, `jump`, `label`, `include`, `print`).

use super::*;

struct Resolver<'a> {
    deck: &'a Deck,
    depth: usize,
}

impl expr::Resolve for Resolver<'_> {
    fn resolve(&self, name: &str) -> R<f64> {
        self.deck.value_of(name, self.depth)
    }
}

impl Deck {
    pub(super) fn substitute(&self, line: &str) -> R<String> {
        let mut out = String::with_capacity(line.len());
        let b: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < b.len() {
            if b[i] == '$' && i + 1 < b.len() && b[i + 1] == '(' {
                // `$(expression)`: evaluated immediately (LAMMPS), printed with enough digits to
                // give back the same double.
                let mut depth = 0usize;
                let mut end = None;
                for (k, &c) in b.iter().enumerate().skip(i + 1) {
                    match c {
                        '(' => depth += 1,
                        ')' => {
                            depth -= 1;
                            if depth == 0 {
                                end = Some(k);
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                let end = end.ok_or("missing ')' after '$('")?;
                let expr: String = b[i + 2..end].iter().collect();
                out.push_str(&format::g(self.eval_formula(&expr, 0)?, 17));
                i = end + 1;
            } else if b[i] == '$' && i + 1 < b.len() {
                let (name, next) = if b[i + 1] == '{' {
                    let end = b[i + 2..].iter().position(|&c| c == '}').ok_or("missing '}' after '${'")?;
                    (b[i + 2..i + 2 + end].iter().collect::<String>(), i + 3 + end)
                } else {
                    (b[i + 1].to_string(), i + 2)
                };
                let v = match self.vars.get(&name) {
                    Some(Var::Index(s)) => s.clone(),
                    Some(Var::List { values, at }) => values[*at].clone(),
                    Some(Var::Equal(f)) => format::g(self.eval_formula(f, 0)?, 15),
                    Some(Var::Loop { value, .. }) => value.to_string(),
                    Some(Var::Atom(_)) => {
                        return Err(format!(
                            "variable {name} is atom-style (one value per particle): it cannot be substituted"
                        ))
                    }
                    None => return Err(format!("substitution for undefined variable {name}")),
                };
                out.push_str(&v);
                i = next;
            } else {
                out.push(b[i]);
                i += 1;
            }
        }
        Ok(out)
    }

    pub(super) fn eval_formula(&self, f: &str, depth: usize) -> R<f64> {
        if depth > 50 {
            return Err("variable definitions refer to each other in a loop".into());
        }
        expr::eval(f, &Resolver { deck: self, depth: depth + 1 })
    }

    /// Value of a name inside a formula or a thermo column.
    pub(super) fn value_of(&self, name: &str, depth: usize) -> R<f64> {
        let w = &self.world;
        if let Some(v) = name.strip_prefix("v_") {
            return match self.vars.get(v) {
                Some(Var::Equal(f)) => self.eval_formula(f, depth),
                Some(Var::Index(s)) => num(s).map_err(|_| format!("variable {v} is not numeric")),
                Some(Var::List { values, at }) => {
                    num(&values[*at]).map_err(|_| format!("variable {v} is not numeric"))
                }
                Some(Var::Loop { value, .. }) => Ok(*value as f64),
                Some(Var::Atom(_)) => Err(format!(
                    "variable {v} is atom-style (one value per particle): use it in an atom-style variable or fix adapt"
                )),
                None => Err(format!("unknown variable {v}")),
            };
        }
        if let Some(c) = name.strip_prefix("c_") {
            let (id, idx) = split_index(c)?;
            return match (self.computes.get(id), idx) {
                (Some(ComputeKind::ERotate), None) => Ok(w.rotational_energy()),
                (Some(ComputeKind::Ke), None) => Ok(w.kinetic_energy()),
                (Some(ComputeKind::Coord), None) => {
                    let n = w.p.len().max(1) as f64;
                    Ok(2.0 * w.pair_contacts() as f64 / n)
                }
                (Some(ComputeKind::Stress), k) => {
                    let (sc, sk) = w.stress_parts();
                    let tr = |s: &[[f64; 3]; 3]| (s[0][0] + s[1][1] + s[2][2]) / 3.0;
                    match k.unwrap_or(10) {
                        k @ 1..=9 => Ok(sc[(k - 1) / 3][(k - 1) % 3] + sk[(k - 1) / 3][(k - 1) % 3]),
                        10 => Ok(tr(&sc) + tr(&sk)),
                        11 => Ok(tr(&sc)),
                        12 => Ok(tr(&sk)),
                        k => Err(format!("compute {id} (stress/mcdem): index {k} out of range 1..12")),
                    }
                }
                (Some(ComputeKind::PropertyAtom(_)), _) => {
                    Err(format!("compute {id} is per-atom (property/atom): use it in an atom-style variable"))
                }
                (Some(_), Some(k)) => Err(format!("compute {id} is a scalar: no index [{k}]")),
                (None, _) => Err(format!("unknown compute {id}")),
            };
        }
        if let Some(f) = name.strip_prefix("f_") {
            let (id, idx) = split_index(f)?;
            let kind = self.fixes.iter().find(|(n, _)| n == id).map(|(_, k)| k.clone());
            return match (kind, idx) {
                (Some(FixKind::MeshSurface(m)), Some(k @ 1..=3)) => {
                    if !w.meshes[m].stress {
                        return Err(format!(
                            "fix {id} is mesh/surface without stress: use mesh/surface/stress"
                        ));
                    }
                    Ok(w.meshes[m].force[k - 1])
                }
                (Some(FixKind::AveTime(a)), Some(k)) => self.aves[a]
                    .as_ref()
                    .and_then(|a| a.last.get(k - 1).copied())
                    .ok_or_else(|| format!("fix {id} has no value {k}")),
                (Some(FixKind::CheckTimestep(c)), Some(k @ 1..=3)) => {
                    Ok(self.checks[c].as_ref().map_or(0.0, |c| c.values[k - 1]))
                }
                (Some(_), _) => Err(unsupported(&format!("fix reference f_{f}"))),
                (None, _) => Err(format!("unknown fix {id}")),
            };
        }
        if let (base, Some(k)) = split_index(name)? {
            let i =
                w.p.id.iter().position(|&x| x == k as i64).ok_or_else(|| format!("no atom with id {k}"))?;
            let p = &w.p;
            return Ok(match base {
                "x" => p.x[i].x,
                "y" => p.x[i].y,
                "z" => p.x[i].z,
                "vx" => p.v[i].x,
                "vy" => p.v[i].y,
                "vz" => p.v[i].z,
                "fx" => p.f[i].x,
                "fy" => p.f[i].y,
                "fz" => p.f[i].z,
                "omegax" => p.omega[i].x,
                "omegay" => p.omega[i].y,
                "omegaz" => p.omega[i].z,
                "radius" => p.radius[i],
                "mass" => p.mass[i],
                _ => return Err(unsupported(&format!("atom value {name}"))),
            });
        }
        let b = w.output_box();
        let len = |a: usize| b.map(|(lo, hi)| hi[a] - lo[a]).unwrap_or(0.0);
        Ok(match name {
            "step" => w.step as f64,
            "atoms" => w.p.len() as f64,
            "dt" => w.dt,
            "time" => w.step as f64 * w.dt,
            "ke" => w.kinetic_energy(),
            "pe" => 0.0,
            "etotal" => w.kinetic_energy(),
            "vol" => len(0) * len(1) * len(2),
            "lx" => len(0),
            "ly" => len(1),
            "lz" => len(2),
            _ => return Err(unsupported(&format!("keyword {name}"))),
        })
    }

    pub(super) fn if_command(&mut self, a: &[&str]) -> R<()> {
        let mut k = 1;
        let mut cond = a.get(k).ok_or("if: expected a condition")?.to_string();
        k += 1;
        if a.get(k) != Some(&"then") {
            return Err("if: expected 'then' after the condition".into());
        }
        k += 1;
        loop {
            let start = k;
            while k < a.len() && a[k] != "elif" && a[k] != "else" {
                k += 1;
            }
            let commands: Vec<String> = a[start..k].iter().map(|c| c.to_string()).collect();
            if self.eval_formula(&cond, 0)? != 0.0 {
                for c in commands {
                    self.command(&c)?;
                }
                return Ok(());
            }
            match a.get(k) {
                None => return Ok(()),
                Some(&"elif") => {
                    cond = a.get(k + 1).ok_or("if: expected a condition after 'elif'")?.to_string();
                    k += 2;
                }
                Some(_) => {
                    // else: everything after it runs.
                    for c in &a[k + 1..] {
                        self.command(c)?;
                    }
                    return Ok(());
                }
            }
        }
    }

    pub(super) fn variable(&mut self, a: &[&str]) -> R<()> {
        if a.len() < 4 {
            return Err("variable: expected 'variable NAME style args'".into());
        }
        let name = a[1].to_string();
        match a[2] {
            "string" => {
                if a.len() > 4 {
                    return Err(format!("variable {name} string: one value expected, got {}", a.len() - 3));
                }
                self.vars.insert(name, Var::Index(a[3].into()));
            }
            "index" | "universe" => {
                // LAMMPS: an index variable that exists (e.g. from -var) is not redefined. With one
                // partition (this engine) a universe variable is an index variable: `next` steps
                // through its values.
                self.vars.entry(name).or_insert_with(|| {
                    if a.len() == 4 {
                        Var::Index(a[3].into())
                    } else {
                        Var::List { values: a[3..].iter().map(|v| v.to_string()).collect(), at: 0 }
                    }
                });
            }
            "equal" => {
                let f = a[3..].join(" ");
                self.vars.insert(name, Var::Equal(f));
            }
            "atom" => {
                let f = a[3..].join(" ");
                self.vars.insert(name, Var::Atom(f));
            }
            "loop" => {
                let (first, last) = match a.len() {
                    4 => (1, int(a[3])?),
                    5 if a[4] == "pad" => (1, int(a[3])?),
                    5 | 6 => (int(a[3])?, int(a[4])?),
                    _ => return Err("variable loop: expected N or N1 N2".into()),
                };
                if a.get(5).is_some_and(|w| *w != "pad") {
                    return Err(unsupported(&format!("variable loop keyword {}", a[5])));
                }
                if first > last {
                    return Err(format!("variable {name}: loop from {first} to {last} is empty"));
                }
                // LAMMPS: an existing loop variable is not redefined (the loop is running).
                self.vars.entry(name).or_insert(Var::Loop { value: first, last });
            }
            other => return Err(unsupported(&format!("variable style {other}"))),
        }
        Ok(())
    }

    /// `next V…`: each variable moves to its next value; one exhausted is deleted and the `jump`
    /// that closes its loop is skipped (LAMMPS).
    pub(super) fn next(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 2)?;
        for v in &a[1..] {
            match self.vars.get_mut(*v) {
                Some(Var::Loop { value, last }) if *value < *last => *value += 1,
                Some(Var::List { values, at }) if *at + 1 < values.len() => *at += 1,
                Some(Var::Loop { .. }) | Some(Var::Index(_)) | Some(Var::List { .. }) => {
                    self.vars.remove(*v);
                    self.skip_jump = true;
                }
                Some(Var::Equal(_)) | Some(Var::Atom(_)) => {
                    return Err(format!("next: variable {v} is not a loop"))
                }
                None => return Err(format!("next: unknown variable {v}")),
            }
        }
        Ok(())
    }

    /// `jump SELF [LABEL]`: the file loop ([`Deck::execute`]) continues after the label.
    pub(super) fn jump(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 2)?;
        if a[1] != "SELF" {
            return Err(unsupported("jump to another file (use jump SELF LABEL)"));
        }
        if std::mem::take(&mut self.skip_jump) {
            return Ok(());
        }
        self.pending_jump = Some(a.get(2).map_or(String::new(), |l| l.to_string()));
        Ok(())
    }

    /// `include FILE`: its lines run here, as if they were in the deck.
    pub(super) fn include(&mut self, a: &[&str]) -> R<()> {
        commands::need(a, 2)?;
        let path = self.input_path(a[1]);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("include: cannot read {}: {e}", path.display()))?;
        self.execute(&text, &path)
    }
}
