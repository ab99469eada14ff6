//! `mcdem compare` on real outputs, and the VTK files of `mcdem run` read back by an independent
//! reader (VTK's Python package, installed by tests/run.sh).
//!
//! The LIGGGHTS comparison needs `liggghts` (tests/run.sh installs it): without it the test fails,
//! unless MCDEM_NO_LIGGGHTS=1 says it is absent on purpose.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use polars::prelude::*;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mcdem(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcdem")).current_dir(dir).args(args).output().expect("mcdem starts")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// The nine-sphere die cell (liggghts_inputs/bcc_box.in) with Hertz contacts (stock LIGGGHTS has
/// no mc_advanced), 3000 steps, frames every `every` steps, written into `dir`; `extra` lines go
/// before the run (the VTK dumps).
fn bcc_args(dir: &Path, every: &str) -> Vec<String> {
    let decks = repo().join("liggghts_inputs");
    let v = |k: &str, x: &str| ["-var".to_string(), k.to_string(), x.to_string()];
    let mut a = Vec::new();
    for (k, x) in [
        ("dir", decks.to_str().unwrap()),
        ("law", "1"),
        ("every", every),
        ("out", "post/force.txt"),
        ("dump", "post/bcc.dump"),
    ] {
        a.extend(v(k, x));
    }
    std::fs::create_dir_all(dir.join("post")).unwrap();
    a
}

fn run_mcdem(dir: &Path, deck: &Path, vars: &[String]) {
    let mut args = vec!["run".to_string(), deck.to_str().unwrap().into(), "-log".into(), "none".into()];
    args.extend(vars.iter().cloned());
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = mcdem(dir, &args);
    assert!(o.status.success(), "mcdem run failed: {}", text(&o));
}

fn liggghts_wanted() -> bool {
    crate::common::present(Command::new("liggghts").arg("-h").output().is_ok(), "the liggghts binary")
}

#[test]
fn compare_passes_on_identical_files_and_names_a_changed_value() {
    let d = tempfile::tempdir().unwrap();
    let vars = bcc_args(d.path(), "500");
    run_mcdem(d.path(), &repo().join("liggghts_inputs/bcc_box.in"), &vars);
    let o = mcdem(d.path(), &["compare", "post/bcc.dump", "post/bcc.dump"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("rows in both"), "{}", text(&o));
    let o = mcdem(d.path(), &["compare", "post/force.txt", "post/force.txt", "--tol", "0"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));

    // One value changed: the y of atom 7 at step 2000, 1e-4 m on a range of about 3.4 mm.
    let dump = std::fs::read_to_string(d.path().join("post/bcc.dump")).unwrap();
    let at = dump.find("ITEM: TIMESTEP\n2000\n").expect("frame 2000");
    let row = dump[at..].find("\n7 ").map(|k| at + k + 1).expect("atom 7 at step 2000");
    let end = row + dump[row..].find('\n').unwrap();
    let mut cols: Vec<String> = dump[row..end].split_whitespace().map(String::from).collect();
    // Columns: id type x y z …
    let y: f64 = cols[3].parse().unwrap();
    cols[3] = format!("{}", y + 1e-4);
    let changed = format!("{}{}{}", &dump[..row], cols.join(" "), &dump[end..]);
    std::fs::write(d.path().join("post/changed.dump"), changed).unwrap();
    let o = mcdem(d.path(), &["compare", "post/bcc.dump", "post/changed.dump"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("column y ") && t.contains("timestep 2000, id 7"), "{t}");
}

#[test]
fn compare_unreadable_input_exits_2_naming_file_and_line() {
    let d = tempfile::tempdir().unwrap();
    let good = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\nITEM: ATOMS id type x \n1 1 0.5 \n2 1 0.25 \n";
    std::fs::write(d.path().join("a.dump"), good).unwrap();
    std::fs::write(d.path().join("b.dump"), good.replace("2 1 0.25 ", "2 0.25")).unwrap();
    let o = mcdem(d.path(), &["compare", "a.dump", "b.dump"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("compare: b.dump:11: expected 3 values, found 2"), "{}", text(&o));
    let o = mcdem(d.path(), &["compare", "a.dump", "missing.dump"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("missing.dump"), "{}", text(&o));
}

#[test]
fn compare_out_csv_round_trips() {
    let d = tempfile::tempdir().unwrap();
    let a = "# Time-averaged data for fix f\n# TimeStep v_disp f_p[3]\n100 0.001 2.5\n200 0.002 3.5\n";
    let b = "# Time-averaged data for fix f\n# TimeStep v_disp f_p[3]\n100 0.001 2.25\n200 0.002 3.5\n300 0.003 4\n";
    std::fs::write(d.path().join("a.txt"), a).unwrap();
    std::fs::write(d.path().join("b.txt"), b).unwrap();
    let o = mcdem(d.path(), &["compare", "a.txt", "b.txt", "--out", "j.csv", "--tol", "0.2"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("only in b.txt: TimeStep 300"), "{}", text(&o));
    let df = CsvReadOptions::default()
        .with_has_header(true)
        .try_into_reader_with_file_path(Some(d.path().join("j.csv")))
        .unwrap()
        .finish()
        .unwrap();
    let names: Vec<String> = df.get_column_names().iter().map(|s| s.to_string()).collect();
    assert_eq!(
        names,
        ["TimeStep", "v_disp_a", "v_disp_b", "v_disp_diff", "f_p[3]_a", "f_p[3]_b", "f_p[3]_diff"]
    );
    let col = |n: &str| -> Vec<Option<f64>> {
        df.column(n).unwrap().cast(&DataType::Float64).unwrap().f64().unwrap().into_iter().collect()
    };
    assert_eq!(col("TimeStep"), [Some(100.0), Some(200.0), Some(300.0)]);
    assert_eq!(col("f_p[3]_a"), [Some(2.5), Some(3.5), None]);
    assert_eq!(col("f_p[3]_b"), [Some(2.25), Some(3.5), Some(4.0)]);
    assert_eq!(col("f_p[3]_diff"), [Some(0.25), Some(0.0), None]);
}

#[test]
fn compare_liggghts_and_mcdem_runs_of_one_deck() {
    if !liggghts_wanted() {
        return;
    }
    let (ours, theirs) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let deck = repo().join("liggghts_inputs/bcc_box.in");
    run_mcdem(ours.path(), &deck, &bcc_args(ours.path(), "100"));
    let mut c = Command::new("liggghts");
    c.current_dir(theirs.path()).arg("-in").arg(&deck).args(["-log", "log.liggghts"]);
    c.args(bcc_args(theirs.path(), "100"));
    let o = c.output().unwrap();
    assert!(o.status.success(), "liggghts failed: {}", text(&o));
    // docs/compare.md: on this short, ordered deck the two engines agree to round-off and the
    // dump's 10 printed digits. The tolerance is set by omegaz, zero by symmetry up to round-off
    // (range ~1e-5 rad/s), whose differences reach ~2e-6 of that range; all else is below 1e-10.
    for f in ["post/bcc.dump", "post/force.txt"] {
        let (a, b) = (theirs.path().join(f), ours.path().join(f));
        let o = mcdem(ours.path(), &["compare", a.to_str().unwrap(), b.to_str().unwrap(), "--tol", "1e-5"]);
        assert_eq!(o.status.code(), Some(0), "{f}: {}", text(&o));
    }
}

/// Runs bcc_box.in with VTK dumps and a text dump every 1000 steps; returns the run directory.
fn vtk_run() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    let deck = std::fs::read_to_string(repo().join("liggghts_inputs/bcc_box.in")).unwrap();
    let vtk = "dump pv all custom/vtk 1000 post/p*.vtk id type type x y z vx vy vz radius\n\
               dump mv all mesh/vtk 1000 post/m*.vtk id stress stresscomponents vel\n";
    let deck =
        deck.replace("include         ${dir}/die_run.inc", &format!("{vtk}include ${{dir}}/die_run.inc"));
    assert!(deck.contains("custom/vtk"), "bcc_box.in changed: insert the VTK dumps elsewhere");
    std::fs::write(d.path().join("in.vtk"), deck).unwrap();
    run_mcdem(d.path(), &d.path().join("in.vtk"), &bcc_args(d.path(), "1000"));
    d
}

/// VTK's own Python reader (the `vtk` package; meshio's legacy reader has no POLYDATA, the
/// dataset LIGGGHTS writes) reads a file and prints what the test checks, as JSON.
fn read_vtk(path: &Path) -> serde_json::Value {
    let script = r#"
import json, sys, vtk
from vtk.util.numpy_support import vtk_to_numpy
r = vtk.vtkPolyDataReader()
r.SetFileName(sys.argv[1])
r.ReadAllFieldsOn()
r.Update()
if r.GetErrorCode() != 0:
    sys.exit("read error %d" % r.GetErrorCode())
d = r.GetOutput()
def arrays(a):
    return {a.GetArrayName(k): vtk_to_numpy(a.GetArray(k)).tolist() for k in range(a.GetNumberOfArrays())}
print(json.dumps({
    "points": vtk_to_numpy(d.GetPoints().GetData()).tolist() if d.GetPoints() else [],
    "cells": d.GetNumberOfCells(),
    "point_data": arrays(d.GetPointData()),
    "cell_data": arrays(d.GetCellData()),
}))
"#;
    let o = Command::new("python3").arg("-c").arg(script).arg(path).output().expect("python3 starts");
    assert!(o.status.success(), "python vtk could not read {}: {}", path.display(), text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn vtk_files_read_back_by_python_vtk_match_the_text_dump() {
    let d = vtk_run();
    let frames = mcdem::outputs::read_dump(&d.path().join("post/bcc.dump")).unwrap();
    for step in [1000u64, 3000] {
        let f = frames.iter().find(|f| f.step == step).expect("text frame");
        let v = read_vtk(&d.path().join(format!("post/p{step}.vtk")));
        let pts = v["points"].as_array().unwrap();
        assert_eq!(pts.len(), f.rows.len(), "point count at step {step}");
        // Points are VTK floats printed with %g (six significant digits, as LIGGGHTS): a relative
        // error up to 5e-6.
        let (x, vx, r) = (f.column("x").unwrap(), f.column("vx").unwrap(), f.column("radius").unwrap());
        let vv = v["point_data"]["v"].as_array().expect("vector array v");
        let rad = v["point_data"]["radius"].as_array().expect("array radius");
        for (k, row) in f.rows.iter().enumerate() {
            for a in 0..3 {
                let p = pts[k][a].as_f64().unwrap();
                assert!(
                    (p - row[x + a]).abs() <= 5e-6 * row[x + a].abs(),
                    "step {step} point {k}: {p} vs {}",
                    row[x + a]
                );
            }
            // Doubles: 11 digits in the VTK file, 10 in the text dump.
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12);
            assert!(close(vv[k][0].as_f64().unwrap(), row[vx]), "step {step} vx of point {k}");
            assert!(close(rad[k].as_f64().unwrap(), row[r]), "step {step} radius of point {k}");
        }
        // The walls: one cell per STL triangle (two meshes made of meshes/die_face.stl).
        let stl = std::fs::read_to_string(repo().join("liggghts_inputs/meshes/die_face.stl")).unwrap();
        let tris = stl.lines().filter(|l| l.trim_start().starts_with("facet")).count();
        let m = read_vtk(&d.path().join(format!("post/m{step}.vtk")));
        assert_eq!(m["cells"].as_u64().unwrap() as usize, 2 * tris, "mesh cells at step {step}");
        let cd = m["cell_data"].as_object().unwrap();
        for name in ["normal_stress_average", "shear_stress_average", "stress", "meshid", "v"] {
            assert!(cd.contains_key(name), "cell array {name} missing: {:?}", cd.keys());
        }
    }
}

/// The lines that give a legacy VTK file its structure (dataset, array names, sizes, types).
fn structure(path: &Path) -> Vec<String> {
    let t = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    t.lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_alphabetic() || c == '#'))
        .map(String::from)
        .collect()
}

#[test]
fn vtk_structure_matches_what_liggghts_writes() {
    if !liggghts_wanted() {
        return;
    }
    let ours = vtk_run();
    let theirs = tempfile::tempdir().unwrap();
    let o = Command::new("liggghts")
        .current_dir(theirs.path())
        .arg("-in")
        .arg(ours.path().join("in.vtk"))
        .args(["-log", "log.liggghts"])
        .args(bcc_args(theirs.path(), "1000"))
        .output()
        .unwrap();
    assert!(o.status.success(), "liggghts failed: {}", text(&o));
    for f in ["post/p1000.vtk", "post/m1000.vtk", "post/pboundingBox_1000.vtk"] {
        assert_eq!(structure(&ours.path().join(f)), structure(&theirs.path().join(f)), "{f}");
    }
}
