//! The command table: one handler per deck keyword, and the handlers of the small set-up commands
//! (units, atom style, boundaries, neighbour settings, time step, computes, thermo settings).

use super::*;

/// A command's handler: the words of the line after substitution, the keyword first.
type Handler = fn(&mut Deck, &[&str]) -> R<()>;

/// Every command the reader knows, with its handler. A keyword not here stops the deck.
const COMMANDS: &[(&str, Handler)] = &[
    ("units", units),
    ("atom_style", atom_style),
    ("atom_modify", atom_modify),
    ("boundary", boundary),
    // Parallel-layout and bookkeeping switches with no effect on a serial engine.
    ("newton", no_effect),
    ("communicate", no_effect),
    ("processors", no_effect),
    ("echo", no_effect),
    ("soft_particles", no_effect),
    ("region", Deck::region),
    ("group", Deck::group),
    ("create_box", create_box),
    ("read_data", read_data),
    ("read_restart", Deck::read_restart),
    ("write_restart", Deck::write_restart),
    ("lattice", Deck::lattice),
    ("create_atoms", Deck::create_atoms),
    ("set", Deck::set),
    ("velocity", Deck::velocity),
    ("neighbor", neighbor),
    ("neigh_modify", neigh_modify),
    ("pair_style", Deck::pair_style),
    ("pair_coeff", pair_coeff),
    ("timestep", timestep),
    ("fix", Deck::fix),
    ("unfix", Deck::unfix),
    ("compute", compute),
    ("compute_modify", compute_modify),
    ("thermo", thermo),
    ("thermo_style", thermo_style),
    ("thermo_modify", thermo_modify),
    ("dump", Deck::dump),
    ("dump_modify", Deck::dump_modify),
    ("undump", undump),
    ("variable", Deck::variable),
    ("label", label),
    ("next", Deck::next),
    ("jump", Deck::jump),
    ("include", Deck::include),
    ("if", Deck::if_command),
    ("print", print),
    ("reset_timestep", Deck::reset_timestep),
    ("run", Deck::run),
];

/// At least `n` words (the keyword and `n - 1` arguments).
pub(super) fn need(a: &[&str], n: usize) -> R<()> {
    if a.len() < n {
        Err(format!("{}: expected at least {} arguments", a[0], n - 1))
    } else {
        Ok(())
    }
}

impl Deck {
    /// One deck line: substitution, words, then the keyword's handler.
    pub(super) fn command(&mut self, raw: &str) -> R<()> {
        let line = self.substitute(raw)?;
        if line != raw {
            self.logln(&line);
        }
        let w = lexer::words(&line)?;
        let a: Vec<&str> = w.iter().map(String::as_str).collect();
        match COMMANDS.iter().find(|(k, _)| *k == a[0]) {
            Some((_, handler)) => handler(self, &a),
            None => Err(unsupported(&format!("command {}", a[0]))),
        }
    }
}

fn no_effect(_: &mut Deck, _: &[&str]) -> R<()> {
    Ok(())
}

fn units(_: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    if a[1] != "si" {
        return Err(unsupported(&format!("units {} (only si)", a[1])));
    }
    Ok(())
}

fn atom_style(_: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    if !matches!(a[1], "sphere" | "granular") {
        return Err(unsupported(&format!("atom_style {}", a[1])));
    }
    Ok(())
}

fn atom_modify(d: &mut Deck, a: &[&str]) -> R<()> {
    // `map array|hash` only changes LIGGGHTS' memory layout; `sort Nfreq binsize`
    // sets how often particles are reordered in space (0 = never; the bin size is
    // the engine's own, half the neighbour cutoff).
    let mut k = 1;
    while k < a.len() {
        match a[k] {
            "map" => k += 2,
            "sort" => {
                let every = a.get(k + 1).ok_or("atom_modify sort: expected Nfreq binsize")?;
                let bin = a.get(k + 2).ok_or("atom_modify sort: expected Nfreq binsize")?;
                d.world.sort_every = every
                    .parse::<u64>()
                    .map_err(|_| format!("atom_modify sort: Nfreq '{every}' is not an integer >= 0"))?;
                if !bin.parse::<f64>().is_ok_and(|b| b >= 0.0) {
                    return Err(format!("atom_modify sort: binsize '{bin}' is not a number >= 0"));
                }
                k += 3;
            }
            other => return Err(unsupported(&format!("atom_modify keyword {other}"))),
        }
    }
    Ok(())
}

fn boundary(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 4)?;
    for k in 0..3 {
        d.shrink[k] = false;
        d.periodic[k] = match a[1 + k] {
            "p" => true,
            "f" => false,
            // Shrink-wrapped: the engine's box grows with the particles, never below the created
            // box; the outputs report LIGGGHTS' box (`m` with the created box as minimum, `s`
            // without), see `Deck::shrink_wrap`.
            "m" | "s" => {
                d.shrink[k] = true;
                d.shrink_min[k] = a[1 + k] == "m";
                false
            }
            other => {
                return Err(unsupported(&format!("boundary style {other} (f, p, m or s, one per axis)")))
            }
        };
    }
    Ok(())
}

fn create_box(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 3)?;
    let b = match d.regions.get(a[2]) {
        Some(regions::Region::Block(b)) => *b,
        Some(_) => return Err(format!("create_box: region {} is not a block", a[2])),
        None => return Err(format!("unknown region {}", a[2])),
    };
    d.ntypes = int(a[1])? as usize;
    d.set_box(b)
}

fn read_data(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    if a.len() > 2 {
        return Err(unsupported("read_data keywords"));
    }
    d.groups.particles_added(None)?;
    d.read_data(a[1])
}

fn neighbor(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 3)?;
    d.world.skin = num(a[1])?;
    if a[2] != "bin" {
        return Err(unsupported(&format!("neighbor style {}", a[2])));
    }
    Ok(())
}

fn neigh_modify(d: &mut Deck, a: &[&str]) -> R<()> {
    let mut k = 1;
    while k < a.len() {
        match a[k] {
            "delay" | "every" => {
                if int(a.get(k + 1).ok_or("neigh_modify: missing value")?)? > 1 && a[k] == "every" {
                    return Err(unsupported("neigh_modify every > 1 (rebuilds are displacement-triggered)"));
                }
                k += 2
            }
            "check" => {
                d.world.rebuild_every_step = match a.get(k + 1).copied() {
                    Some("yes") => false,
                    Some("no") => true,
                    other => {
                        return Err(format!(
                            "neigh_modify check {}: expected yes or no",
                            other.unwrap_or("(missing)")
                        ))
                    }
                };
                k += 2
            }
            "contact_distance_factor" => {
                // LIGGGHTS widens the neighbour search for contacts that may appear
                // through multi-contact radius growth; the engine's detection reach is
                // the same knob (never below what the contact law needs, see pair_style).
                let f = num(a.get(k + 1).ok_or("neigh_modify: missing value")?)?;
                if !(f.is_finite() && f >= 1.0) {
                    return Err(format!("neigh_modify contact_distance_factor {f}: must be >= 1"));
                }
                d.world.mc_range = f;
                k += 2
            }
            other => return Err(unsupported(&format!("neigh_modify keyword {other}"))),
        }
    }
    Ok(())
}

fn pair_coeff(_: &mut Deck, a: &[&str]) -> R<()> {
    if a.len() != 3 || a[1] != "*" || a[2] != "*" {
        return Err(unsupported(
            "pair_coeff other than '* *' (granular coefficients come from fix property/global)",
        ));
    }
    Ok(())
}

fn timestep(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    d.world.dt = num(a[1])?;
    if !(d.world.dt > 0.0 && d.world.dt.is_finite()) {
        return Err(format!("timestep must be finite and > 0, got {}", a[1]));
    }
    Ok(())
}

fn compute(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 4)?;
    d.groups.act_on(a[2], &format!("compute {} {}", a[1], a[3]))?;
    if a[3] == "pair/gran/local" {
        d.pair_locals.insert(a[1].into(), local::PairLocal::parse(&a[4..])?);
        return Ok(());
    }
    if a[3] == "property/atom" {
        let cols = atom_vars::property_atom(a[1], &a[4..])?;
        d.computes.insert(a[1].into(), ComputeKind::PropertyAtom(cols));
        return Ok(());
    }
    let kind = match a[3] {
        "erotate/sphere" => ComputeKind::ERotate,
        "ke" => ComputeKind::Ke,
        "stress/mcdem" => ComputeKind::Stress,
        "coord/mcdem" => ComputeKind::Coord,
        other => return Err(unsupported(&format!("compute style {other}"))),
    };
    if a.len() > 4 {
        return Err(unsupported(&format!("compute {} arguments", a[3])));
    }
    d.computes.insert(a[1].into(), kind);
    Ok(())
}

fn compute_modify(d: &mut Deck, _: &[&str]) -> R<()> {
    d.warn("compute_modify is output-only here: skipped");
    Ok(())
}

fn thermo(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    d.thermo_every = int(a[1])?.max(0) as u64;
    Ok(())
}

fn thermo_style(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    if a[1] != "custom" {
        return Err(unsupported(&format!("thermo_style {}", a[1])));
    }
    d.thermo_cols = a[2..].iter().map(|s| s.to_string()).collect();
    Ok(())
}

fn thermo_modify(d: &mut Deck, a: &[&str]) -> R<()> {
    let mut k = 1;
    while k < a.len() {
        match a[k] {
            "format" if a.get(k + 1) == Some(&"float") => {
                let f = a.get(k + 2).ok_or("thermo_modify format float: missing format")?;
                match format::parse(f)?.as_slice() {
                    [format::Piece::Conv(s)] => d.thermo_float = Some(s.clone()),
                    _ => {
                        return Err(format!("thermo_modify format float: one conversion expected in \"{f}\""))
                    }
                }
                k += 3;
            }
            "norm" if a.get(k + 1) == Some(&"no") => k += 2,
            // A lost particle always stops the run (deleting it is not supported); with every
            // non-periodic axis shrink-wrapped (`boundary m`/`s`) none can be lost.
            "lost" if matches!(a.get(k + 1), Some(&"error") | Some(&"ignore") | Some(&"warn")) => {
                d.lost_policy = a[k + 1].to_string();
                k += 2
            }
            // Already so: stdout is line-buffered and the log is flushed when the
            // deck ends, after an error too.
            "flush" if matches!(a.get(k + 1), Some(&"yes") | Some(&"no")) => k += 2,
            other => return Err(unsupported(&format!("thermo_modify keyword {other}"))),
        }
    }
    Ok(())
}

fn undump(d: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)?;
    d.dumps.retain(|x| x.name != a[1]);
    d.local_dumps.retain(|x| x.name != a[1]);
    d.vtk_dumps.retain(|x| x.name != a[1]);
    Ok(())
}

fn label(_: &mut Deck, a: &[&str]) -> R<()> {
    need(a, 2)
}

fn print(d: &mut Deck, a: &[&str]) -> R<()> {
    let text = a[1..].join(" ");
    d.say(&text);
    Ok(())
}
