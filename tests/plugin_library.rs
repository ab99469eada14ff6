//! The bindings to LIGGGHTS's `library.h`: open an instance inside this process, run a deck, read
//! per-atom arrays and check them against the deck's own dump.
//!
//! A test binary of its own: MPI_Init in a process leaves OpenMPI variables in its environment,
//! and the `mcdem-liggghts` children that other tests start would inherit them.
#![cfg(feature = "liggghts")]

use std::path::{Path, PathBuf};

use tempfile::TempDir;

fn decks() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("liggghts_inputs")
}

/// Last frame of a `dump custom` file as rows of numbers (id first).
fn last_frame(path: &Path) -> Vec<Vec<f64>> {
    mcdem::outputs::read_dump(path).unwrap().pop().expect("a frame").rows
}

#[test]
fn library_interface_opens_an_instance_and_reads_atoms() {
    // Everything in one test: MPI is initialised once per process.
    let tmp = TempDir::new().unwrap();
    let log = tmp.path().join("lib.log");
    let mut l = mcdem::liggghts::Liggghts::open(&["-log", log.to_str().unwrap(), "-screen", "none"]).unwrap();
    let deck = decks().join("two_particles.in");
    let dump = tmp.path().join("lib.dump");
    // Every output of the deck into the temporary directory (the contact dump too: its default
    // name would land in the working directory, the checkout).
    let contacts = tmp.path().join("lib_contacts.dump");
    l.commands([
        format!("variable dir index {}", decks().display()).as_str(),
        format!("variable dump index {}", dump.display()).as_str(),
        format!("variable contacts index {}", contacts.display()).as_str(),
        "variable steps index 200",
    ])
    .unwrap();
    l.file(&deck).unwrap();
    assert_eq!(l.natoms(), 2);
    let ids = l.atom_ids().unwrap();
    let x = l.atom_vec3("x").unwrap();
    let r = l.atom_scalar("radius").unwrap();
    let last = last_frame(&dump);
    for (k, id) in ids.iter().enumerate() {
        let row = last.iter().find(|row| row[0] as i64 == *id).expect("atom in dump");
        for c in 0..3 {
            assert!((row[2 + c] - x[k][c]).abs() <= 1e-9 * x[k][c].abs().max(1e-3), "atom {id} x[{c}]");
        }
        assert_eq!(r[k], 0.001);
    }
}
