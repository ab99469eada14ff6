//! `mcdem-liggghts`: LIGGGHTS 3.8 (the installed library) with `pair_style gran model mc_advanced`
//! registered. Same command line as `liggghts`: `-in deck`, `-var NAME value`, `-log file`, `-echo`.

fn main() {
    std::process::exit(mcdem::liggghts::run_main());
}
