//! Reading the two inputs of `mcdem compare` into polars DataFrames.
//!
//! Two kinds of LIGGGHTS text output are understood, told apart by their content:
//! - `dump custom` files (`ITEM: TIMESTEP` … `ITEM: ATOMS id …`, one or many frames), parsed by the
//!   crate's one dump reader ([`crate::outputs::parse_dump`]) and laid out as one long table keyed
//!   by (`timestep`, `id`);
//! - tables of `fix ave/time … file` and `fix print … file`: `#` comment lines, then one row of
//!   values per output step. `fix ave/time` names its columns in its last comment line
//!   (`# TimeStep f_a[1] …`); `fix print` writes only `# Fix print output for fix ID` (or its
//!   `title`, written as a plain first line), so its columns are named `c1`, `c2`, … unless that
//!   line has exactly one word per value. The first column is the step the rows are joined on.

use std::path::Path;

use polars::prelude::*;

use crate::outputs::parse_dump;

/// What a file holds, and so how its rows are joined.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Dump,
    Table,
}

impl Kind {
    pub fn describe(self) -> &'static str {
        match self {
            Kind::Dump => "dump custom",
            Kind::Table => "table (fix ave/time or fix print)",
        }
    }
}

/// One input read: its rows as a DataFrame (key columns first, then every value column as f64),
/// the names of the key columns, and notes for the report (dropped or non-numeric columns).
#[derive(Debug)]
pub struct Input {
    pub name: String,
    pub kind: Kind,
    pub frame: DataFrame,
    pub keys: Vec<String>,
    /// Value columns that are compared (numeric), in file order.
    pub values: Vec<String>,
    pub notes: Vec<String>,
    /// Number of frames (dumps) or rows (tables), for the report.
    pub count: usize,
}

/// Reads a file and tells its kind from the content. Errors name the file and line.
pub fn read(path: &Path) -> Result<Input, String> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
    parse(&text, &name)
}

/// Parses the text of one input (see [`read`]); `name` is used in messages.
pub fn parse(text: &str, name: &str) -> Result<Input, String> {
    let first = text.lines().enumerate().find(|(_, l)| !l.trim().is_empty());
    match first {
        None => Err(format!("{name}: empty file")),
        Some((_, l)) if l.starts_with("ITEM:") => {
            if text.contains("ITEM: ENTRIES") {
                return Err(format!(
                    "{name}: a 'dump local' file: its rows carry no atom id to join on (compare 'dump custom' files or tables)"
                ));
            }
            dump(text, name)
        }
        Some(_) => table(text, name),
    }
}

fn dump(text: &str, name: &str) -> Result<Input, String> {
    let frames = parse_dump(text, name)?;
    let first = frames.first().ok_or_else(|| format!("{name}: no frame"))?;
    let mut notes = Vec::new();
    // A dump's column set is fixed by its `dump` command; a change means two files were
    // concatenated, and the rows could not be laid out in one table.
    if let Some(f) = frames.iter().find(|f| f.columns != first.columns) {
        return Err(format!(
            "{name}: the columns change at timestep {} (one table needs one column set)",
            f.step
        ));
    }
    let id_at =
        first.column("id").ok_or_else(|| format!("{name}: the dump has no 'id' column to join on"))?;
    // A repeated column (`id type type x …`, common in decks written for custom/vtk) carries the
    // same values twice: the first is kept.
    let mut keep: Vec<usize> = Vec::new();
    for (k, c) in first.columns.iter().enumerate() {
        if first.columns[..k].contains(c) {
            notes.push(format!("{name}: column '{c}' repeated: the first is compared"));
        } else if k != id_at {
            keep.push(k);
        }
    }
    let rows: usize = frames.iter().map(|f| f.rows.len()).sum();
    let mut step = Vec::with_capacity(rows);
    let mut id = Vec::with_capacity(rows);
    let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(rows); keep.len()];
    for f in &frames {
        for r in &f.rows {
            let v = r[id_at];
            if v.fract() != 0.0 || !v.is_finite() {
                return Err(format!("{name}: timestep {}: atom id '{v}' is not an integer", f.step));
            }
            step.push(f.step);
            id.push(v as i64);
            for (c, &k) in cols.iter_mut().zip(&keep) {
                c.push(r[k]);
            }
        }
    }
    let values: Vec<String> = keep.iter().map(|&k| first.columns[k].clone()).collect();
    let mut columns = vec![Column::new("timestep".into(), step), Column::new("id".into(), id)];
    columns.extend(values.iter().zip(cols).map(|(n, c)| Column::new(n.as_str().into(), c)));
    let frame = DataFrame::new(columns).map_err(|e| format!("{name}: {e}"))?;
    check_unique(&frame, &["timestep", "id"], name)?;
    Ok(Input {
        name: name.into(),
        kind: Kind::Dump,
        frame,
        keys: vec!["timestep".into(), "id".into()],
        values,
        notes,
        count: frames.len(),
    })
}

fn table(text: &str, name: &str) -> Result<Input, String> {
    let mut header: Option<Vec<String>> = None;
    let mut rows: Vec<(usize, Vec<&str>)> = Vec::new();
    for (no, line) in text.lines().enumerate() {
        if let Some(c) = line.strip_prefix('#') {
            if !rows.is_empty() {
                // `fix ave/time` in vector mode and files appended by several runs interleave
                // comments with rows: refuse rather than guess which header applies.
                return Err(format!("{name}:{}: comment line after data rows", no + 1));
            }
            header = Some(c.split_whitespace().map(str::to_owned).collect());
        } else if rows.is_empty() && line.split_whitespace().next().is_some_and(|w| w.parse::<f64>().is_err())
        {
            // `fix print … title "…"` writes its title as the first line, without a `#`.
            header = Some(line.split_whitespace().map(str::to_owned).collect());
        } else if !line.trim().is_empty() {
            let words: Vec<&str> = line.split_whitespace().collect();
            if let Some((_, w)) = rows.first() {
                if words.len() != w.len() {
                    return Err(format!(
                        "{name}:{}: expected {} values, found {}",
                        no + 1,
                        w.len(),
                        words.len()
                    ));
                }
            }
            rows.push((no + 1, words));
        }
    }
    let width = rows.first().map(|(_, w)| w.len()).ok_or_else(|| format!("{name}: no data rows"))?;
    let mut notes = Vec::new();
    let names: Vec<String> = match header {
        Some(h) if h.len() == width => h,
        _ => {
            notes.push(format!("{name}: no header naming the {width} columns: named c1..c{width}"));
            (1..=width).map(|k| format!("c{k}")).collect()
        }
    };
    let mut seen = std::collections::HashSet::new();
    if let Some(dup) = names.iter().find(|n| !seen.insert(n.as_str())) {
        return Err(format!("{name}: column '{dup}' named twice in the header"));
    }
    // The step column must be numeric in every row; other columns are compared when numeric in
    // every row, and reported as not compared otherwise (a `fix print` label such as `time`).
    let step_name = names[0].clone();
    let mut steps = Vec::with_capacity(rows.len());
    for (line, w) in &rows {
        let s: f64 = w[0].parse().map_err(|_| format!("{name}:{line}: step '{}' is not a number", w[0]))?;
        if s.fract() != 0.0 || !s.is_finite() {
            return Err(format!("{name}:{line}: step '{}' is not an integer", w[0]));
        }
        steps.push(s as i64);
    }
    let mut columns = vec![Column::new(step_name.as_str().into(), steps)];
    let mut values = Vec::new();
    for (k, n) in names.iter().enumerate().skip(1) {
        let parsed: Result<Vec<f64>, _> = rows.iter().map(|(_, w)| w[k].parse::<f64>()).collect();
        match parsed {
            Ok(v) => {
                columns.push(Column::new(n.as_str().into(), v));
                values.push(n.clone());
            }
            Err(_) => notes.push(format!("{name}: column '{n}' is not numeric in every row: not compared")),
        }
    }
    let frame = DataFrame::new(columns).map_err(|e| format!("{name}: {e}"))?;
    check_unique(&frame, &[step_name.as_str()], name)?;
    Ok(Input {
        name: name.into(),
        kind: Kind::Table,
        frame,
        keys: vec![step_name],
        values,
        notes,
        count: rows.len(),
    })
}

/// Rows are joined on their keys, so a key repeated within one file (two runs appended to one
/// file, a frame written twice) would pair rows arbitrarily: an error naming the first repeat.
fn check_unique(df: &DataFrame, keys: &[&str], name: &str) -> Result<(), String> {
    let mask = df
        .select(keys.iter().copied())
        .and_then(|k| k.is_duplicated())
        .map_err(|e| format!("{name}: {e}"))?;
    if let Some(i) = mask.into_iter().position(|d| d == Some(true)) {
        let at: Vec<String> = keys
            .iter()
            .map(|k| {
                format!(
                    "{k} {}",
                    df.column(k).and_then(|c| c.get(i)).map(|v| v.to_string()).unwrap_or_default()
                )
            })
            .collect();
        return Err(format!("{name}: {} appears more than once: rows cannot be paired", at.join(", ")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUMP: &str = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\nITEM: ATOMS id type type x \n2 1 1 0.5 \n1 1 1 0.25 \n";

    #[test]
    fn dump_is_keyed_and_drops_a_repeated_column() {
        let i = parse(DUMP, "d").unwrap();
        assert_eq!(i.kind, Kind::Dump);
        assert_eq!(i.values, ["type", "x"]);
        assert_eq!(i.frame.width(), 4);
        assert!(i.notes[0].contains("'type' repeated"));
    }

    #[test]
    fn ave_time_names_columns_from_the_last_comment() {
        let t = "# Time-averaged data for fix f\n# TimeStep f_p[1] f_p[3]\n100 1 2\n200 3 4\n";
        let i = parse(t, "a").unwrap();
        assert_eq!((i.kind, i.keys[0].as_str()), (Kind::Table, "TimeStep"));
        assert_eq!(i.values, ["f_p[1]", "f_p[3]"]);
    }

    #[test]
    fn fix_print_title_names_columns() {
        let i = parse("step t fz\n500 time 3.3e-05\n1000 time 8.6e-05\n", "p").unwrap();
        assert_eq!((i.keys[0].as_str(), i.values.clone()), ("step", vec!["fz".to_string()]));
    }

    #[test]
    fn fix_print_columns_are_numbered_and_labels_skipped() {
        let t = "# Fix print output for fix p\n100 time 0.1\n200 time 0.2\n";
        let i = parse(t, "p").unwrap();
        assert_eq!(i.values, ["c3"]);
        assert!(i.notes.iter().any(|n| n.contains("'c2' is not numeric")));
    }

    #[test]
    fn malformed_inputs_name_file_and_line() {
        let e = parse("# TimeStep a b\n1 2 3\n2 3\n", "t").unwrap_err();
        assert_eq!(e, "t:3: expected 3 values, found 2");
        let e = parse("# TimeStep a\n1 2\n1 3\n", "t").unwrap_err();
        assert!(e.contains("TimeStep 1 appears more than once"), "{e}");
        let e = parse(&DUMP.replace("\n1 1 1 0.25 ", "\n1 1 0.25 "), "d").unwrap_err();
        assert_eq!(e, "d:11: expected 4 values, found 3");
    }
}
