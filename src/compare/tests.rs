use super::*;

fn frame(step: u64, rows: &[(i64, f64, f64)]) -> String {
    let mut s = format!(
        "ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\nITEM: ATOMS id x radius \n",
        rows.len()
    );
    for (id, x, r) in rows {
        s.push_str(&format!("{id} {x} {r} \n"));
    }
    s
}

fn both(a: &str, b: &str) -> (Input, Input, Comparison) {
    let (a, b) = (parse(a, "a").unwrap(), parse(b, "b").unwrap());
    let c = compare(&a, &b).unwrap();
    (a, b, c)
}

const ROWS: [(i64, f64, f64); 3] = [(1, 0.0, 0.5), (2, 1.0, 0.5), (3, 2.0, 0.5)];

#[test]
fn identical_dumps_pass() {
    let d = frame(0, &ROWS) + &frame(10, &ROWS);
    let (_, _, c) = both(&d, &d);
    assert_eq!((c.both_rows, c.shared.len()), (6, 2));
    assert_eq!(verdict(&c, 0.0), Verdict::Pass);
}

#[test]
fn a_changed_value_names_column_timestep_and_id() {
    let a = frame(0, &ROWS) + &frame(10, &ROWS);
    let mut changed = ROWS;
    changed[1].1 = 1.002;
    let b = frame(0, &ROWS) + &frame(10, &changed);
    let (_, _, c) = both(&a, &b);
    let x = &c.shared[0];
    // Range of x over both files is 2: a difference of 0.002 is 1e-3 of it.
    assert!((x.rel - 1e-3).abs() < 1e-12 && (x.max_abs - 0.002).abs() < 1e-12);
    let Verdict::Fail(why) = verdict(&c, 1e-6) else { panic!("should fail") };
    assert!(why.contains("column x") && why.contains("timestep 10, id 2"), "{why}");
    assert_eq!(verdict(&c, 2e-3), Verdict::Pass);
}

#[test]
fn zero_range_is_judged_absolutely() {
    let mut r = ROWS;
    r[0].2 = 0.5 + 1e-9;
    let (a, b, c) = both(&frame(0, &ROWS), &frame(0, &r));
    let radius = &c.shared[1];
    assert!(!radius.zero_range, "the range spans both files, 1e-9 here");
    let (_, _, c0) = both(&frame(0, &ROWS), &frame(0, &ROWS));
    assert!(c0.shared[1].zero_range && c0.shared[1].rel == 0.0);
    assert!(report(&a, &b, &c, 1e-6).contains("radius"));
}

#[test]
fn nan_fails_and_is_located() {
    let mut r = ROWS;
    r[2].1 = f64::NAN;
    let (_, _, c) = both(&frame(0, &ROWS), &frame(0, &r));
    let Verdict::Fail(why) = verdict(&c, 1.0) else { panic!("NaN must fail") };
    assert!(why.contains("NaN") && why.contains("id 3"), "{why}");
}

#[test]
fn one_sided_frames_rows_and_columns_are_listed_not_failed() {
    let a = frame(0, &ROWS) + &frame(10, &ROWS);
    let b = frame(0, &ROWS[..2]);
    let (_, _, c) = both(&a, &b);
    assert_eq!(c.only_a_rows, ["timestep 0, id 3", "timestep 10 (whole frame)"]);
    assert_eq!(verdict(&c, 0.0), Verdict::Pass);
    let t = |h: &str| format!("# TimeStep {h}\n100 1 2\n200 3 4\n");
    let (_, _, c) = both(&t("p q"), &t("p r"));
    assert_eq!((c.only_a_cols.clone(), c.only_b_cols.clone()), (vec!["q".into()], vec!["r".into()]));
    assert_eq!(verdict(&c, 0.0), Verdict::Pass);
}

#[test]
fn no_shared_rows_fails_and_kinds_must_match() {
    let (_, _, c) = both(&frame(0, &ROWS), &frame(5, &ROWS));
    assert!(matches!(verdict(&c, 1.0), Verdict::Fail(w) if w.contains("no row")));
    let d = parse(&frame(0, &ROWS), "d").unwrap();
    let t = parse("# TimeStep x\n0 1\n", "t").unwrap();
    let Err(e) = compare(&d, &t) else { panic!("a dump and a table must not compare") };
    assert!(e.contains("same kind"), "{e}");
}

#[test]
fn tables_join_on_their_step_column() {
    let a = "# Time-averaged data for fix f\n# TimeStep f_p[3]\n100 1.0\n200 2.0\n300 3.0\n";
    let b = "# Time-averaged data for fix f\n# TimeStep f_p[3]\n200 2.5\n300 3.0\n";
    let (_, _, c) = both(a, b);
    assert_eq!(c.only_a_rows, ["TimeStep 100"]);
    let Verdict::Fail(why) = verdict(&c, 0.1) else { panic!() };
    assert!(why.contains("column f_p[3]") && why.contains("TimeStep 200"), "{why}");
    let names: Vec<String> = c.joined.get_column_names().iter().map(|s| s.to_string()).collect();
    assert_eq!(names, ["TimeStep", "f_p[3]_a", "f_p[3]_b", "f_p[3]_diff"]);
}

#[test]
fn columns_option_restricts_the_comparison() {
    let d = tempfile::tempdir().unwrap();
    let (a, b) = (d.path().join("a.txt"), d.path().join("b.txt"));
    std::fs::write(&a, "# TimeStep f[1] f[3]\n100 0.01 5\n200 -0.01 6\n").unwrap();
    std::fs::write(&b, "# TimeStep f[1] f[3]\n100 0.02 5\n200 -0.01 6\n").unwrap();
    let args = |columns: Vec<String>| Args { a: a.clone(), b: b.clone(), tol: 1e-3, out: None, columns };
    let mut sink = Vec::new();
    assert!(matches!(run(&args(vec![]), &mut sink), Ok(Verdict::Fail(w)) if w.contains("f[1]")));
    assert_eq!(run(&args(vec!["f[3]".into()]), &mut sink), Ok(Verdict::Pass));
    assert!(run(&args(vec!["g".into()]), &mut sink).unwrap_err().contains("no numeric column 'g'"));
}
