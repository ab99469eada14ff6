//! `mcdem compare A B`: the differences between two LIGGGHTS-format outputs of one deck (two
//! engines, two versions, two machines), column by column, in polars.
//!
//! Exit status: 0 when every shared numeric column agrees within `--tol` of its range, 1 when one
//! does not (the worst is named with its timestep and id, or step), 2 when an input cannot be read
//! (the message names the file and line). See docs/compare.md.

mod diff;
mod read;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use polars::prelude::*;

pub use diff::{compare, ColumnDiff, Comparison};
pub use read::{parse, read, Input, Kind};

/// The command line of `mcdem compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// First output: a `dump custom` text file, or a `fix ave/time` / `fix print` table
    pub a: PathBuf,
    /// Second output, of the same kind
    pub b: PathBuf,
    /// Largest accepted difference, relative to each column's range over both files (the
    /// absolute difference for a column whose range is zero)
    #[arg(long, default_value_t = 1e-6)]
    pub tol: f64,
    /// Write the joined rows (keys, then `COL_a`, `COL_b`, `COL_diff` = a − b per column):
    /// FILE.csv or FILE.parquet
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Compare only these value columns (comma-separated), e.g. the load of a force table whose
    /// lateral components are noise
    #[arg(long, value_delimiter = ',')]
    pub columns: Vec<String>,
}

/// The verdict of one comparison.
#[derive(Debug, PartialEq, Eq)]
pub enum Verdict {
    Pass,
    /// The message names the worst column and where.
    Fail(String),
}

/// Runs the command: prints the report, returns the exit status (0, 1, or 2 with a message).
pub fn cli(args: &Args) -> ExitCode {
    match run(args, &mut std::io::stdout()) {
        Ok(Verdict::Pass) => ExitCode::SUCCESS,
        Ok(Verdict::Fail(why)) => {
            eprintln!("compare: FAILED: {why}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("compare: {e}");
            ExitCode::from(2)
        }
    }
}

/// Reads, compares, writes the report to `out` and the joined frame to `--out`.
pub fn run(args: &Args, out: &mut dyn std::io::Write) -> Result<Verdict, String> {
    if !(args.tol >= 0.0 && args.tol.is_finite()) {
        return Err(format!("--tol {}: expected a finite number >= 0", args.tol));
    }
    if let Some(p) = &args.out {
        out_format(p)?;
    }
    let mut a = read(&args.a)?;
    let mut b = read(&args.b)?;
    if !args.columns.is_empty() {
        for c in &args.columns {
            if !a.values.contains(c) && !b.values.contains(c) {
                return Err(format!("--columns: no numeric column '{c}' in {} or {}", a.name, b.name));
            }
        }
        for i in [&mut a, &mut b] {
            i.values.retain(|v| args.columns.contains(v));
        }
    }
    let mut c = compare(&a, &b)?;
    let report = report(&a, &b, &c, args.tol);
    out.write_all(report.as_bytes()).map_err(|e| format!("cannot write the report: {e}"))?;
    if let Some(p) = &args.out {
        write_frame(&mut c.joined, p)?;
    }
    Ok(verdict(&c, args.tol))
}

#[derive(Clone, Copy)]
enum OutFormat {
    Csv,
    Parquet,
}

fn out_format(p: &Path) -> Result<OutFormat, String> {
    match p.extension().and_then(|e| e.to_str()) {
        Some("csv") => Ok(OutFormat::Csv),
        Some("parquet") => Ok(OutFormat::Parquet),
        _ => Err(format!("--out {}: expected a name ending in .csv or .parquet", p.display())),
    }
}

fn write_frame(df: &mut DataFrame, p: &Path) -> Result<(), String> {
    let fail = |e: &dyn std::fmt::Display| format!("cannot write {}: {e}", p.display());
    let mut f = std::fs::File::create(p).map_err(|e| fail(&e))?;
    match out_format(p)? {
        OutFormat::Csv => CsvWriter::new(&mut f).finish(df).map_err(|e| fail(&e)),
        OutFormat::Parquet => ParquetWriter::new(&mut f).finish(df).map(|_| ()).map_err(|e| fail(&e)),
    }
}

/// Pass when rows were paired and every shared numeric column is within `tol` without NaN; else
/// the worst column (NaN first: a NaN is never within tolerance).
pub fn verdict(c: &Comparison, tol: f64) -> Verdict {
    if c.both_rows == 0 {
        return Verdict::Fail("no row is present in both files (no shared timestep and id, or step)".into());
    }
    if c.shared.is_empty() {
        return Verdict::Fail("the files share no numeric column".into());
    }
    if let Some(d) = c.shared.iter().find(|d| d.nans > 0) {
        let row = d.first_nan_row.expect("a NaN row was recorded");
        return Verdict::Fail(format!(
            "column {}: NaN in {} row(s), the first at {}",
            d.name,
            d.nans,
            diff::at(&c.joined, &c.keys, row)
        ));
    }
    let worst = c.shared.iter().filter(|d| d.rel > tol).max_by(|x, y| x.rel.total_cmp(&y.rel));
    match worst {
        None => Verdict::Pass,
        Some(d) => {
            let scale = if d.zero_range { "absolute (the column's range is zero)" } else { "of its range" };
            Verdict::Fail(format!(
                "column {} differs by {:.3e} {scale}, above --tol {:e}, at {} (a = {}, b = {})",
                d.name,
                d.rel,
                tol,
                diff::at(&c.joined, &c.keys, d.worst_row.expect("a worst row exists when rel > 0")),
                d.worst_values.0,
                d.worst_values.1
            ))
        }
    }
}

fn list(rows: &[String]) -> String {
    const SHOWN: usize = 5;
    let mut s = rows.iter().take(SHOWN).cloned().collect::<Vec<_>>().join("; ");
    if rows.len() > SHOWN {
        s.push_str(&format!("; … ({} more)", rows.len() - SHOWN));
    }
    s
}

/// The printed report: inputs, pairing, one line per shared column, one-sided columns and rows.
pub fn report(a: &Input, b: &Input, c: &Comparison, tol: f64) -> String {
    let mut s = String::new();
    for i in [a, b] {
        let what = match i.kind {
            Kind::Dump => format!("dump custom, {} frames, {} rows", i.count, i.frame.height()),
            Kind::Table => format!("{}, {} rows", i.kind.describe(), i.count),
        };
        s.push_str(&format!("{}: {what}\n", i.name));
    }
    for n in a.notes.iter().chain(&b.notes) {
        s.push_str(&format!("note: {n}\n"));
    }
    s.push_str(&format!(
        "joined on ({}): {} rows in both, {} only in {}, {} only in {}\n",
        c.keys.join(", "),
        c.both_rows,
        c.only_a_rows.len(),
        a.name,
        c.only_b_rows.len(),
        b.name
    ));
    let w = c.shared.iter().map(|d| d.name.len()).max().unwrap_or(6).max(6);
    s.push_str(&format!(
        "{:<w$}  {:>12}  {:>12}  {:>12}  {:<4}  worst at\n",
        "column", "max|a-b|", "max rel", "rms", ""
    ));
    for d in &c.shared {
        let ok = if d.nans > 0 {
            "NaN"
        } else if d.rel > tol {
            "FAIL"
        } else {
            "ok"
        };
        let rel = if d.zero_range { format!("{:.3e}*", d.rel) } else { format!("{:.3e}", d.rel) };
        let at = d
            .worst_row
            .filter(|_| d.max_abs > 0.0)
            .map(|r| diff::at(&c.joined, &c.keys, r))
            .unwrap_or_default();
        s.push_str(&format!(
            "{:<w$}  {:>12.3e}  {:>12}  {:>12.3e}  {ok:<4}  {at}\n",
            d.name, d.max_abs, rel, d.rms
        ));
    }
    if c.shared.iter().any(|d| d.zero_range) {
        s.push_str("* zero range over both files: the absolute difference is judged against --tol\n");
    }
    for (cols, i) in [(&c.only_a_cols, a), (&c.only_b_cols, b)] {
        if !cols.is_empty() {
            s.push_str(&format!("columns only in {} (not compared): {}\n", i.name, cols.join(" ")));
        }
    }
    for (rows, i) in [(&c.only_a_rows, a), (&c.only_b_rows, b)] {
        if !rows.is_empty() {
            s.push_str(&format!("only in {}: {}\n", i.name, list(rows)));
        }
    }
    s
}

#[cfg(test)]
mod tests;
