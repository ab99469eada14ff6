//! Helpers shared by the integration tests.
pub mod frames;

/// A missing package fails the test unless the run says on purpose that this machine has none
/// (`MCDEM_NO_LIGGGHTS=1`, README); tests/run.sh installs them all. Returns whether it is there.
#[allow(dead_code)] // not every test binary checks for packages
pub fn present(ok: bool, what: &str) -> bool {
    if !ok {
        let skip = std::env::var("MCDEM_NO_LIGGGHTS").is_ok_and(|v| v == "1");
        assert!(skip, "{what} is missing (tests/run.sh installs it; MCDEM_NO_LIGGGHTS=1 skips on purpose)");
        eprintln!("MCDEM_NO_LIGGGHTS=1: {what} is missing, its checks are skipped on purpose");
    }
    ok
}
