//! Readers of LIGGGHTS text outputs (`dump custom`, `dump local`, `fix ave/time ... file`, the
//! `Loop time` lines of a log and the details mcdem adds to them), shared
//! by the validation harness and the tests of both engines so that every comparison reads files the
//! same way. LIGGGHTS writes runs of spaces, a trailing space and many frames per file; malformed
//! input is an error naming the file and line, never a silently short table.

use std::path::Path;

/// One frame of a `dump custom` (`ITEM: ATOMS ...`) or `dump local` (`ITEM: ENTRIES ...`) file.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub step: u64,
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Frame {
    /// Index of a column by name.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
}

fn read(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

/// Parses the text of a dump file (see [`read_dump`]); `name` is used in error messages.
pub fn parse_dump(text: &str, name: &str) -> Result<Vec<Frame>, String> {
    let mut frames: Vec<Frame> = Vec::new();
    let mut lines = text.lines().enumerate();
    let mut expect_rows = 0usize;
    while let Some((no, line)) = lines.next() {
        let at = |what: &str| format!("{name}:{}: {what}", no + 1);
        if line.starts_with("ITEM: TIMESTEP") {
            if expect_rows > 0 {
                return Err(at(&format!("frame ended {expect_rows} rows early")));
            }
            let (n2, v) = lines.next().ok_or_else(|| at("missing timestep value"))?;
            let step = v.trim().parse().map_err(|_| format!("{name}:{}: bad timestep '{v}'", n2 + 1))?;
            frames.push(Frame { step, columns: Vec::new(), rows: Vec::new() });
        } else if line.starts_with("ITEM: NUMBER OF") {
            let (n2, v) = lines.next().ok_or_else(|| at("missing count"))?;
            expect_rows = v.trim().parse().map_err(|_| format!("{name}:{}: bad count '{v}'", n2 + 1))?;
        } else if let Some(cols) =
            line.strip_prefix("ITEM: ATOMS").or_else(|| line.strip_prefix("ITEM: ENTRIES"))
        {
            let f = frames.last_mut().ok_or_else(|| at("columns before the first TIMESTEP"))?;
            f.columns = cols.split_whitespace().map(str::to_owned).collect();
            for _ in 0..expect_rows {
                let (n2, l) = lines.next().ok_or_else(|| at("file ends inside a frame"))?;
                let row = l
                    .split_whitespace()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|_| format!("{name}:{}: not a number in '{l}'", n2 + 1))?;
                if row.len() != f.columns.len() {
                    return Err(format!(
                        "{name}:{}: expected {} values, found {}",
                        n2 + 1,
                        f.columns.len(),
                        row.len()
                    ));
                }
                f.rows.push(row);
            }
            expect_rows = 0;
        } else if line.starts_with("ITEM: BOX BOUNDS") {
            for _ in 0..3 {
                lines.next().ok_or_else(|| at("file ends inside BOX BOUNDS"))?;
            }
        } else if !line.trim().is_empty() {
            return Err(at(&format!("unexpected line '{line}'")));
        }
    }
    Ok(frames)
}

/// Reads a LIGGGHTS `dump custom` or `dump local` text file into frames.
pub fn read_dump(path: &Path) -> Result<Vec<Frame>, String> {
    parse_dump(&read(path)?, &path.display().to_string())
}

/// Parses `fix ave/time ... file` text: `#` comment lines, then one numeric row per output step
/// (first column the time step).
pub fn parse_ave_time(text: &str, name: &str) -> Result<Vec<Vec<f64>>, String> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty())
        .map(|(no, l)| {
            l.split_whitespace()
                .map(|x| x.parse::<f64>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(|_| format!("{name}:{}: not a number in '{l}'", no + 1))
        })
        .collect()
}

/// Reads a `fix ave/time ... file` output.
pub fn read_ave_time(path: &Path) -> Result<Vec<Vec<f64>>, String> {
    parse_ave_time(&read(path)?, &path.display().to_string())
}

/// The figures of the `Loop time of T on P procs for N steps with A atoms` lines of a LIGGGHTS or
/// `mcdem run` log (mcdem appends its details in parentheses, which are not read here), summed
/// over the runs of the log: the one reader of that line for the benchmarks and the harness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopTotals {
    /// Loop time T summed over the lines [s].
    pub seconds: f64,
    /// Steps N summed over the lines.
    pub steps: u64,
    /// N × A summed over the lines (particle-steps).
    pub particle_steps: f64,
    /// A of the last line.
    pub atoms: u64,
}

impl LoopTotals {
    /// Particle-steps per second of the loops together (0 when they took no measurable time).
    pub fn rate(&self) -> f64 {
        if self.seconds > 0.0 {
            self.particle_steps / self.seconds
        } else {
            0.0
        }
    }
}

/// Reads every `Loop time of` line of `text`; `None` when there is none with steps or one does
/// not have the LIGGGHTS layout (T at word 4, N at word 9, A at word 12).
pub fn loop_totals(text: &str) -> Option<LoopTotals> {
    let mut t = LoopTotals { seconds: 0.0, steps: 0, particle_steps: 0.0, atoms: 0 };
    for l in text.lines().filter(|l| l.starts_with("Loop time of")) {
        let w: Vec<&str> = l.split_whitespace().collect();
        let (secs, steps, atoms): (f64, u64, u64) =
            (w.get(3)?.parse().ok()?, w.get(8)?.parse().ok()?, w.get(11)?.parse().ok()?);
        t.seconds += secs;
        t.steps += steps;
        t.particle_steps += steps as f64 * atoms as f64;
        t.atoms = atoms;
    }
    (t.steps > 0).then_some(t)
}

/// What `mcdem run` adds in parentheses to each `Loop time` line (written by `src/deck/run.rs`):
/// the thread count, the share of threaded steps, the neighbour builds and, with
/// `--mc-update-every`, the full multi-contact passes.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopDetails {
    /// `1 thread` or `T threads`.
    pub threads: u64,
    /// `threaded in P % of steps`, printed when the force passes had more than one thread.
    pub threaded_percent: Option<f64>,
    /// `N neighbour builds`.
    pub neighbour_builds: u64,
    /// `full pass in K of N steps`, printed with `--mc-update-every` > 1.
    pub full_passes: Option<u64>,
}

/// The details of every `Loop time of` line of an mcdem log, in order; an error naming the line
/// when one lacks them (a LIGGGHTS log, or a layout this reader does not know).
pub fn loop_details(text: &str) -> Result<Vec<LoopDetails>, String> {
    let word_before = |l: &str, tag: &str| -> Option<u64> {
        let (head, _) = l.split_once(tag)?;
        head.rsplit([' ', '(']).next()?.parse().ok()
    };
    let word_after = |l: &str, tag: &str| -> Option<String> {
        let (_, rest) = l.split_once(tag)?;
        rest.split(' ').next().map(str::to_string)
    };
    text.lines()
        .filter(|l| l.starts_with("Loop time of"))
        .map(|l| {
            let bad = || format!("no mcdem details in '{l}'");
            let threads = word_before(l, " thread").ok_or_else(bad)?;
            let threaded_percent = match word_after(l, "threaded in ") {
                Some(p) => Some(p.parse::<f64>().map_err(|_| bad())?),
                None => None,
            };
            let full_passes = match word_after(l, "full pass in ") {
                Some(k) => Some(k.parse::<u64>().map_err(|_| bad())?),
                None => None,
            };
            Ok(LoopDetails {
                threads,
                threaded_percent,
                neighbour_builds: word_before(l, " neighbour builds").ok_or_else(bad)?,
                full_passes,
            })
        })
        .collect()
}

/// Normalised root-mean-square error of `model` against `reference` (paired samples):
/// RMSE / mean(|reference|), the paper's NRMSE (Sect. 3, Fig. 4).
pub fn nrmse(model: &[f64], reference: &[f64]) -> f64 {
    assert_eq!(model.len(), reference.len(), "nrmse needs paired samples");
    let n = reference.len() as f64;
    let mse = model.iter().zip(reference).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / n;
    let mean = reference.iter().map(|b| b.abs()).sum::<f64>() / n;
    mse.sqrt() / mean
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUMP: &str = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\nITEM: ATOMS id x fz \n1 0.5 -1e-3 \n2 0.25 2 \nITEM: TIMESTEP\n10\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\nITEM: ATOMS id x fz \n1 0.5 0 \n";

    #[test]
    fn reads_frames_with_trailing_spaces() {
        let f = parse_dump(DUMP, "d").unwrap();
        assert_eq!(f.len(), 2);
        assert_eq!((f[1].step, f[0].column("fz")), (10, Some(2)));
        assert_eq!(f[0].rows, vec![vec![1.0, 0.5, -1e-3], vec![2.0, 0.25, 2.0]]);
    }

    #[test]
    fn malformed_dumps_name_file_and_line() {
        let short = DUMP.replace("2 0.25 2 \n", "");
        assert!(parse_dump(&short, "d").unwrap_err().starts_with("d:"));
        let bad = DUMP.replace("0.25", "x");
        assert_eq!(parse_dump(&bad, "d").unwrap_err(), "d:11: not a number in '2 x 2 '");
        let cols = DUMP.replace("2 0.25 2 ", "2 0.25");
        assert!(parse_dump(&cols, "d").unwrap_err().contains("expected 3 values, found 2"));
    }

    #[test]
    fn ave_time_and_nrmse() {
        let rows = parse_ave_time("# c\n# TimeStep v\n1000 2.5\n2000 3.5\n", "a").unwrap();
        assert_eq!(rows, vec![vec![1000.0, 2.5], vec![2000.0, 3.5]]);
        assert!(parse_ave_time("1000 nan?\n", "a").is_err());
        // RMSE of (1, −1) is 1, mean |reference| is 2.
        assert_eq!(nrmse(&[3.0, 1.0], &[2.0, 2.0]), 0.5);
    }

    #[test]
    fn loop_time_lines_of_both_engines_are_summed() {
        // A LIGGGHTS line and an mcdem line with its details in parentheses.
        let text = "x\nLoop time of 2.5 on 1 procs for 1000 steps with 514 atoms\n\
                    Loop time of 0.5 on 1 procs for 1000 steps with 400 atoms (1e6 particle-steps/s, 2 threads, 3 neighbour builds)\n";
        let t = loop_totals(text).unwrap();
        assert_eq!((t.seconds, t.steps, t.particle_steps, t.atoms), (3.0, 2000, 914_000.0, 400));
        assert_eq!(t.rate(), 914_000.0 / 3.0);
        assert_eq!(loop_totals("nothing"), None);
        assert_eq!(loop_totals("Loop time of 1 on 1 procs for x steps with 5 atoms"), None);
    }

    #[test]
    fn mcdem_loop_details() {
        let text = "Loop time of 0.5 on 1 procs for 1000 steps with 400 atoms (1e6 particle-steps/s, 1 thread, 3 neighbour builds)\n\
                    Loop time of 0.5 on 1 procs for 1000 steps with 400 atoms (1e6 particle-steps/s, 2 threads, threaded in 87 % of steps, 12 neighbour builds, multi-contact update every 10 steps: full pass in 104 of 1000 steps)\n";
        let d = loop_details(text).unwrap();
        assert_eq!(
            d[0],
            LoopDetails { threads: 1, threaded_percent: None, neighbour_builds: 3, full_passes: None }
        );
        assert_eq!(
            d[1],
            LoopDetails {
                threads: 2,
                threaded_percent: Some(87.0),
                neighbour_builds: 12,
                full_passes: Some(104)
            }
        );
        let liggghts = "Loop time of 2.5 on 1 procs for 1000 steps with 514 atoms";
        assert!(loop_details(liggghts).unwrap_err().starts_with("no mcdem details in 'Loop time of 2.5"));
    }
}
