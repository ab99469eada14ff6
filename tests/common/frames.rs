//! LIGGGHTS text outputs as polars DataFrames, for the tests that compare two engines or two runs.
//!
//! - `fix ave/time … file F`: read by polars' CSV reader (space separated, `#` comments); the column
//!   names come from the file's own `# TimeStep …` header line.
//! - `dump custom`: frames parsed by `mcdem::outputs` (the format is not CSV: a header block per
//!   frame) and laid out as one long table with a `step` column.
#![allow(dead_code)] // each test binary uses its own part

use std::path::Path;

use polars::prelude::*;

/// A `fix ave/time` output file; columns named as in its header (`TimeStep`, `f_piston_m[3]`, …).
pub fn ave_time(path: &Path) -> DataFrame {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let names: Vec<String> = text
        .lines()
        .find_map(|l| l.strip_prefix("# TimeStep"))
        .map(|rest| std::iter::once("TimeStep").chain(rest.split_whitespace()).map(String::from).collect())
        .unwrap_or_else(|| panic!("{}: no '# TimeStep' header", path.display()));
    let df = CsvReadOptions::default()
        .with_has_header(false)
        .map_parse_options(|o| o.with_separator(b' ').with_comment_prefix(Some("#")))
        .try_into_reader_with_file_path(Some(path.into()))
        .and_then(|r| r.finish())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        df.width() >= names.len(),
        "{}: {} columns for {} names",
        path.display(),
        df.width(),
        names.len()
    );
    // A trailing separator reads as one more (empty) column.
    let mut df = df.select(df.get_column_names_owned().into_iter().take(names.len())).unwrap();
    df.set_column_names(names).unwrap();
    df
}

/// A `dump custom` file as one table: `step`, then the dump's columns, one row per atom and frame.
pub fn dump(path: &Path) -> DataFrame {
    let frames = mcdem::outputs::read_dump(path).unwrap();
    let first = frames.first().unwrap_or_else(|| panic!("{}: no frame", path.display()));
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); first.columns.len() + 1];
    for f in &frames {
        assert_eq!(f.columns, first.columns, "{}: columns change at step {}", path.display(), f.step);
        for r in &f.rows {
            cols[0].push(f.step as f64);
            for (c, v) in cols[1..].iter_mut().zip(r) {
                c.push(*v);
            }
        }
    }
    let names = std::iter::once("step".to_string()).chain(first.columns.iter().cloned());
    DataFrame::new(names.zip(cols).map(|(n, c)| Column::new(n.into(), c)).collect()).unwrap()
}

/// One column as f64 values.
pub fn values(df: &DataFrame, name: &str) -> Vec<f64> {
    let s = df.column(name).unwrap_or_else(|e| panic!("{e}")).cast(&DataType::Float64).unwrap();
    s.f64().unwrap().into_no_null_iter().collect()
}

/// Rows whose `column` lies in (lo, hi].
pub fn rows_between(df: &DataFrame, column: &str, lo: f64, hi: f64) -> DataFrame {
    let s = df.column(column).unwrap().cast(&DataType::Float64).unwrap();
    let ca = s.f64().unwrap();
    let mask = ca.gt(lo) & ca.lt_eq(hi);
    df.filter(&mask).unwrap()
}

/// Both dumps sorted by (step, id), checked to hold the same frames and atoms.
pub fn aligned_dumps(a: &Path, b: &Path) -> (DataFrame, DataFrame) {
    let sort = |df: DataFrame| df.sort(["step", "id"], SortMultipleOptions::default()).unwrap();
    let (a, b) = (sort(dump(a)), sort(dump(b)));
    assert_eq!(a.shape(), b.shape(), "different frames or atom counts");
    assert_eq!(values(&a, "step"), values(&b, "step"));
    assert_eq!(values(&a, "id"), values(&b, "id"));
    (a, b)
}

/// Largest difference between two trajectories (dumps of the same deck by two engines or two rank
/// counts), per vector quantity (position, v, f, ω) present in the dumps, relative to the largest
/// magnitude that quantity reaches over the run; atoms matched by id, frames by step. Components
/// share their vector's scale (a component that is zero by symmetry carries only round-off), and ω
/// is also measured against the rotation rate the translation would give, max|v| / max r.
pub fn trajectory_difference(a: &Path, b: &Path) -> Vec<(&'static str, f64)> {
    let (da, db) = aligned_dumps(a, b);
    let groups: [(&str, [&str; 3]); 4] = [
        ("position", ["x", "y", "z"]),
        ("v", ["vx", "vy", "vz"]),
        ("f", ["fx", "fy", "fz"]),
        ("omega", ["omegax", "omegay", "omegaz"]),
    ];
    let has = |c: &str| db.get_column_names().iter().any(|n| n.as_str() == c);
    let mut out: Vec<(&'static str, f64, f64)> = Vec::new();
    for (name, cols) in groups {
        if !cols.iter().all(|c| has(c)) {
            continue;
        }
        let (mut scale, mut diff) = (0.0_f64, 0.0_f64);
        for c in cols {
            for (p, q) in values(&da, c).iter().zip(values(&db, c)) {
                scale = scale.max(p.abs()).max(q.abs());
                diff = diff.max((p - q).abs());
            }
        }
        out.push((name, diff, scale));
    }
    let vscale = out.iter().find(|g| g.0 == "v").map(|g| g.2);
    if let (Some(v), true) = (vscale, has("radius")) {
        let rmax = values(&db, "radius").into_iter().fold(0.0, f64::max);
        if let Some(w) = out.iter_mut().find(|g| g.0 == "omega") {
            w.2 = w.2.max(v / rmax);
        }
    }
    out.into_iter().map(|(n, d, s)| (n, if s > 0.0 { d / s } else { 0.0 })).collect()
}

/// Largest difference between two runs' frames over `columns` (frames parsed by
/// `mcdem::outputs::read_dump`, e.g. `dump local`), each column's differences relative to its
/// largest magnitude in `b`. The frames must match in step and row count. A column that is zero
/// throughout in `b` must stay zero: any difference over a zero scale is infinite.
pub fn frame_difference(a: &[mcdem::outputs::Frame], b: &[mcdem::outputs::Frame], columns: &[usize]) -> f64 {
    assert_eq!(a.len(), b.len(), "frame counts differ");
    let mut worst = 0.0_f64;
    for &c in columns {
        let scale = b.iter().flat_map(|f| f.rows.iter().map(move |r| r[c].abs())).fold(0.0, f64::max);
        for (fa, fb) in a.iter().zip(b) {
            assert_eq!((fa.step, fa.rows.len()), (fb.step, fb.rows.len()), "frames differ");
            for (ra, rb) in fa.rows.iter().zip(&fb.rows) {
                let d = (ra[c] - rb[c]).abs();
                if d > 0.0 {
                    worst = worst.max(d / scale);
                }
            }
        }
    }
    worst
}
