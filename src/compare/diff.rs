//! Pairing the rows of two inputs (a polars full join on their keys) and the per-column
//! differences `mcdem compare` reports and judges.

use std::collections::BTreeSet;

use polars::prelude::*;

use super::read::{Input, Kind};

/// Marker columns added before the join: a null marker after the join means the row is missing
/// from that side. Dropped before the joined frame is written.
const IN_A: &str = "__in_a";
const IN_B: &str = "__in_b";

/// The differences of one shared numeric column over the rows present in both files.
#[derive(Debug, Clone)]
pub struct ColumnDiff {
    pub name: String,
    pub max_abs: f64,
    /// max |a − b| / (max − min over both files); the absolute difference when the range is zero.
    pub rel: f64,
    pub zero_range: bool,
    pub rms: f64,
    /// Where the largest difference is (row index into the joined frame).
    pub worst_row: Option<usize>,
    /// Rows where either value is NaN, and the first of them.
    pub nans: usize,
    pub first_nan_row: Option<usize>,
    /// The two values at the worst row.
    pub worst_values: (f64, f64),
}

/// Everything the report needs.
pub struct Comparison {
    pub joined: DataFrame,
    pub keys: Vec<String>,
    pub shared: Vec<ColumnDiff>,
    pub only_a_cols: Vec<String>,
    pub only_b_cols: Vec<String>,
    pub both_rows: usize,
    /// Rows present in one file only, as "timestep T" (a whole frame) or "timestep T, id I" /
    /// "STEP T" descriptions, in key order.
    pub only_a_rows: Vec<String>,
    pub only_b_rows: Vec<String>,
}

fn with_marker(df: &DataFrame, marker: &str) -> PolarsResult<DataFrame> {
    let mut df = df.clone();
    df.with_column(Column::new(marker.into(), vec![true; df.height()]))?;
    Ok(df)
}

fn suffixed(input: &Input, suffix: &str) -> PolarsResult<DataFrame> {
    // Only the keys and the compared columns (`--columns` may have left some out).
    let mut df = input.frame.select(input.keys.iter().chain(&input.values).map(String::as_str))?;
    for v in &input.values {
        df.rename(v, format!("{v}_{suffix}").into())?;
    }
    Ok(df)
}

/// Joins A and B on A's keys (B's step column renamed when a table names it differently) and
/// measures every shared numeric column.
pub fn compare(a: &Input, b: &Input) -> Result<Comparison, String> {
    if a.kind != b.kind {
        return Err(format!(
            "{} is a {} and {} a {}: compare two outputs of the same kind",
            a.name,
            a.kind.describe(),
            b.name,
            b.kind.describe()
        ));
    }
    let pe = |e: PolarsError| format!("joining {} and {}: {e}", a.name, b.name);
    let keys = a.keys.clone();
    let mut fb = suffixed(b, "b").map_err(pe)?;
    for (ka, kb) in keys.iter().zip(&b.keys) {
        if ka != kb {
            fb.rename(kb, ka.as_str().into()).map_err(pe)?;
        }
    }
    let fa = with_marker(&suffixed(a, "a").map_err(pe)?, IN_A).map_err(pe)?;
    let fb = with_marker(&fb, IN_B).map_err(pe)?;
    let args = JoinArgs::new(JoinType::Full).with_coalesce(JoinCoalesce::CoalesceColumns);
    let joined = fa
        .join(&fb, keys.iter().map(String::as_str), keys.iter().map(String::as_str), args, None)
        .and_then(|j| j.sort(keys.iter().map(String::as_str), SortMultipleOptions::default()))
        .map_err(pe)?;

    let present = |m: &str| -> Result<Vec<bool>, String> {
        let c = joined.column(m).map_err(pe)?;
        Ok(c.bool().map_err(pe)?.into_iter().map(|v| v == Some(true)).collect())
    };
    let (in_a, in_b) = (present(IN_A)?, present(IN_B)?);
    let both: Vec<bool> = in_a.iter().zip(&in_b).map(|(x, y)| *x && *y).collect();
    let both_rows = both.iter().filter(|x| **x).count();

    let only_a_cols: Vec<String> = a.values.iter().filter(|v| !b.values.contains(v)).cloned().collect();
    let only_b_cols: Vec<String> = b.values.iter().filter(|v| !a.values.contains(v)).cloned().collect();
    let mut shared = Vec::new();
    let mut diff_cols = Vec::new();
    for name in a.values.iter().filter(|v| b.values.contains(v)) {
        let col = |df: &DataFrame, n: &str| -> Result<Vec<Option<f64>>, String> {
            Ok(df.column(n).map_err(pe)?.f64().map_err(pe)?.into_iter().collect())
        };
        let va = col(&joined, &format!("{name}_a"))?;
        let vb = col(&joined, &format!("{name}_b"))?;
        let range = value_range(&col(&a.frame, name)?, &col(&b.frame, name)?);
        shared.push(measure(name, &va, &vb, &both, range));
        let d: Vec<Option<f64>> = va.iter().zip(&vb).map(|(x, y)| Some((*x)? - (*y)?)).collect();
        diff_cols.push(Column::new(format!("{name}_diff").into(), d));
    }
    let mut joined = joined;
    for d in diff_cols {
        joined.with_column(d).map_err(pe)?;
    }
    let only_a_rows = only_rows(&joined, &keys, a.kind, &in_a, &in_b, &b.frame)?;
    let only_b_rows = only_rows(&joined, &keys, a.kind, &in_b, &in_a, &a.frame)?;
    // Output order: keys, then per column its value in A, in B and their difference.
    let mut order: Vec<String> = keys.clone();
    for v in &a.values {
        order.push(format!("{v}_a"));
        if b.values.contains(v) {
            order.push(format!("{v}_b"));
            order.push(format!("{v}_diff"));
        }
    }
    order.extend(only_b_cols.iter().map(|v| format!("{v}_b")));
    let joined = joined.select(order).map_err(pe)?;
    Ok(Comparison { joined, keys, shared, only_a_cols, only_b_cols, both_rows, only_a_rows, only_b_rows })
}

/// max − min of a column over both files, NaN ignored (a NaN is reported on its own).
fn value_range(a: &[Option<f64>], b: &[Option<f64>]) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in a.iter().chain(b).flatten().filter(|v| !v.is_nan()) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if hi >= lo {
        hi - lo
    } else {
        0.0
    }
}

fn measure(name: &str, va: &[Option<f64>], vb: &[Option<f64>], both: &[bool], range: f64) -> ColumnDiff {
    let mut d = ColumnDiff {
        name: name.into(),
        max_abs: 0.0,
        rel: 0.0,
        zero_range: range <= 0.0,
        rms: 0.0,
        worst_row: None,
        nans: 0,
        first_nan_row: None,
        worst_values: (0.0, 0.0),
    };
    let (mut sum2, mut n) = (0.0, 0usize);
    for (i, ((x, y), &paired)) in va.iter().zip(vb).zip(both).enumerate() {
        let (Some(x), Some(y), true) = (x, y, paired) else { continue };
        if x.is_nan() || y.is_nan() {
            d.nans += 1;
            d.first_nan_row.get_or_insert(i);
            continue;
        }
        let e = (x - y).abs();
        sum2 += e * e;
        n += 1;
        if e > d.max_abs || d.worst_row.is_none() {
            d.max_abs = e;
            d.worst_row = Some(i);
            d.worst_values = (*x, *y);
        }
    }
    d.rms = if n > 0 { (sum2 / n as f64).sqrt() } else { 0.0 };
    // A column that never changes (a type, a radius in a monodisperse run) has no range to scale
    // by: its absolute difference is judged instead.
    d.rel = if d.zero_range { d.max_abs } else { d.max_abs / range };
    d
}

/// Describes the key values of one joined row: "timestep 100, id 5" or "TimeStep 100".
pub fn at(joined: &DataFrame, keys: &[String], row: usize) -> String {
    keys.iter()
        .map(|k| {
            let v = joined
                .column(k)
                .ok()
                .and_then(|c| c.get(row).ok())
                .map(|v| v.to_string())
                .unwrap_or_default();
            format!("{k} {v}")
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Rows present on this side only: a dump frame missing from the other file is named once as a
/// whole frame, other rows one by one.
fn only_rows(
    joined: &DataFrame,
    keys: &[String],
    kind: Kind,
    here: &[bool],
    there: &[bool],
    other: &DataFrame,
) -> Result<Vec<String>, String> {
    let rows: Vec<usize> = (0..here.len()).filter(|&i| here[i] && !there[i]).collect();
    if kind == Kind::Table {
        return Ok(rows.iter().map(|&i| at(joined, keys, i)).collect());
    }
    let steps = |df: &DataFrame| -> Result<Vec<Option<u64>>, String> {
        let c = df.column("timestep").map_err(|e| e.to_string())?;
        Ok(c.u64().map_err(|e| e.to_string())?.into_iter().collect())
    };
    let other_steps: BTreeSet<u64> = steps(other)?.into_iter().flatten().collect();
    let joined_steps = steps(joined)?;
    let mut out = Vec::new();
    let mut whole = BTreeSet::new();
    for i in rows {
        let s = joined_steps[i].unwrap_or_default();
        if !other_steps.contains(&s) {
            if whole.insert(s) {
                out.push(format!("timestep {s} (whole frame)"));
            }
        } else {
            out.push(at(joined, keys, i));
        }
    }
    Ok(out)
}
