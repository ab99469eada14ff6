//! The Rust DEM on two (or more) threads gives the serial result bit for bit: pair forces are summed in
//! pair order (by blocks that own their particles and defer the rest, or from every pair's kept
//! result), and the multi-contact kernel runs per particle on
//! disjoint ranges (kept influence matrices included), whatever the thread count. That is what
//! lets the engine switch threads on and off by timing alone.

use std::path::{Path, PathBuf};

use mcdem::deck::{run_file, Options};
use mcdem::engine::PairThreads;

fn decks() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs")
}

/// The 514-particle hydrogel deck, two fast strokes; returns the piston-force file's bytes.
fn piston_force(dir: &Path, law: &str, geomtol: &str, threads: PairThreads, pool: usize) -> Vec<u8> {
    let out = dir.join(format!("piston_{law}_{geomtol}_{threads:?}_{pool}.txt"));
    let vars = [
        ("geomtol", geomtol.to_string()),
        ("law", law.to_string()),
        ("stroke", "1000".into()),
        ("strokes", "2".into()),
        ("every", "10".into()),
        ("out", out.display().to_string()),
        ("dir", decks().display().to_string()),
        ("data", mcdem::validate::packing::shipped().display().to_string()),
    ];
    let opts = Options {
        vars: vars.iter().map(|(k, v)| (k.to_string(), v.clone())).collect(),
        log: Some(PathBuf::from("none")),
        quiet: true,
        pair_threads: threads,
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(pool).build().unwrap();
    pool.install(|| run_file(&decks().join("hydrogel.in"), &opts)).unwrap();
    std::fs::read(out).unwrap()
}

#[test]
fn two_threads_give_the_serial_result_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    // Hertz, exact advanced MC, and advanced MC with kept influence matrices; two threads, and
    // three (more members than cores: the splits of every pass into more than two ranges).
    for (law, geomtol) in [("1", "0"), ("0", "0"), ("0", "1e-3")] {
        let serial = piston_force(tmp.path(), law, geomtol, PairThreads::Serial, 2);
        assert!(serial.len() > 1000, "law {law}: piston output too short");
        for pool in [2, 3] {
            let parallel = piston_force(tmp.path(), law, geomtol, PairThreads::Parallel, pool);
            assert!(
                serial == parallel,
                "law {law}, geomtol {geomtol}: {pool} threads changed the piston force"
            );
        }
    }
}

/// Both threaded pair passes give the serial state bit for bit, and each runs where it should: a
/// spatially sorted packing (19 652 or 2 048 spheres: few pair ends shared between the two blocks)
/// takes the blocks that own their particles; the same 2 048 spheres numbered in random order and
/// never sorted (about half of the ends shared) keep every pair's result. Positions, velocities,
/// angular velocities and the recorded pair forces after ten steps, Hertz and advanced MC.
#[test]
fn both_threaded_pair_passes_give_the_serial_state() {
    let cases = [
        (17, false, false, true, 2),
        (17, true, false, true, 2),
        (8, false, false, true, 2),
        (8, false, true, false, 2),
        (8, true, false, true, 3),
        (8, false, true, false, 3),
    ];
    for (k, advanced, scrambled, owned, threads) in cases {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let run = |threads: PairThreads| {
            let mut w = mcdem::bench::packing::scene(k, advanced).unwrap();
            if scrambled {
                scramble(&mut w);
            }
            w.pair_threads = threads;
            pool.install(|| {
                w.setup().unwrap();
                for _ in 0..10 {
                    w.step().unwrap();
                }
            });
            let state = (w.p.x.clone(), w.p.v.clone(), w.p.omega.clone(), w.stress_parts());
            (state, w.threaded_passes())
        };
        let ((serial, none), (parallel, passes)) = (run(PairThreads::Serial), run(PairThreads::Parallel));
        assert_eq!(none, (0, 0));
        let expected = if owned { (10, 0) } else { (0, 10) };
        let what = format!("k {k}, advanced {advanced}, scrambled {scrambled}, {threads} threads");
        assert_eq!(passes, expected, "{what}: (owned-block, kept) passes");
        assert!(serial == parallel, "{what}: threads changed the state");
    }
}

/// Renumbers the particles in a random order (same positions, sizes and velocities) and turns
/// spatial sorting off, so that a particle's partners are spread over the whole pair list.
fn scramble(w: &mut mcdem::engine::World) {
    let n = w.p.len();
    let mut order: Vec<usize> = (0..n).collect();
    let mut rng = mcdem::rng::Lcg64(0x2545f4914f6cdd1d);
    for i in (1..n).rev() {
        order.swap(i, (rng.next_u64() >> 33) as usize % (i + 1));
    }
    let old = std::mem::take(&mut w.p);
    for &i in &order {
        // 0.5 × (2r) is r exactly: the same radii and masses.
        w.p.push(old.id[i], old.typ[i], old.x[i], 2.0 * old.radius[i], old.density[i]);
        let m = w.p.len() - 1;
        w.p.v[m] = old.v[i];
        w.p.omega[m] = old.omega[i];
    }
    w.sort_every = 0;
}

/// The recorded pair forces behind the stress and coordination outputs are the same whichever
/// pass computed them: a dense frictional packing (the bench's, 2048 spheres), a few steps on one
/// and on two threads, Hertz and advanced MC.
#[test]
fn stress_and_coordination_do_not_depend_on_the_thread_count() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    for advanced in [false, true] {
        let run = |threads: PairThreads| {
            let mut w = mcdem::bench::packing::scene(8, advanced).unwrap();
            w.pair_threads = threads;
            pool.install(|| {
                w.setup().unwrap();
                for _ in 0..20 {
                    w.step().unwrap();
                }
            });
            (w.stress_parts(), w.pair_contacts())
        };
        let (serial, parallel) = (run(PairThreads::Serial), run(PairThreads::Parallel));
        let ((sc, _), z) = serial;
        assert!(z > 2048 * 4, "advanced {advanced}: the packing must be dense ({z} contacts)");
        assert!(sc[0][0] > 0.0 && sc[1][1] > 0.0 && sc[2][2] > 0.0, "advanced {advanced}: {sc:?}");
        assert!(serial == parallel, "advanced {advanced}: {serial:?} vs {parallel:?}");
    }
}
