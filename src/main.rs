//! The `mcdem` command line.

use std::io::Read;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "mcdem", version, about = "Advanced multi-contact DEM for strongly deformed soft particles")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate the multi-contact kernel for one particle described in JSON (FILE or - for stdin)
    Contacts {
        /// JSON file, or - for standard input
        file: String,
    },
    /// Run a LIGGGHTS deck with the standalone engine: `mcdem run DECK [-var NAME VALUE]... [-log FILE]`
    Run {
        /// The input deck
        deck: PathBuf,
        /// Define an index variable before the deck is read (LIGGGHTS -var)
        #[arg(long = "var", short_alias = 'v', num_args = 2, value_names = ["NAME", "VALUE"], action = clap::ArgAction::Append, allow_hyphen_values = true)]
        var: Vec<String>,
        /// Log file (default log.liggghts; `none` for no log)
        #[arg(long = "log")]
        log: Option<PathBuf>,
        /// No progress bar even on a terminal
        #[arg(long)]
        no_progress: bool,
    },
    /// Run the validation suite and write the report
    Validate {
        /// Quick subset (CI)
        #[arg(long)]
        quick: bool,
        /// Output directory
        #[arg(long, default_value = "validation/report")]
        out: PathBuf,
    },
}

fn read_input(file: &str) -> Result<String, String> {
    if file == "-" {
        let mut s = String::new();
        std::io::stdin().read_to_string(&mut s).map_err(|e| format!("cannot read standard input: {e}"))?;
        Ok(s)
    } else {
        std::fs::read_to_string(file).map_err(|e| format!("cannot read {file}: {e}"))
    }
}

fn contacts(file: &str) -> Result<(), String> {
    let out = mcdem::contacts_cli::evaluate(&read_input(file)?)?;
    println!("{}", serde_json::to_string(&out).map_err(|e| e.to_string())?);
    Ok(())
}

fn validate(_quick: bool, out: PathBuf) -> Result<(), String> {
    let checks = mcdem::checks::run_all();
    println!("{:<20} {:>12} {:>12}  {:<6} what", "check", "error", "tolerance", "result");
    for c in &checks {
        let verdict = if c.passed { "pass" } else { "FAIL" };
        println!("{:<20} {:>12.3e} {:>12.3e}  {:<6} {}", c.name, c.error, c.tolerance, verdict, c.what);
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let path = out.join("physics_checks.json");
    let json = serde_json::to_string_pretty(&checks).map_err(|e| e.to_string())?;
    std::fs::write(&path, json).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let failed = checks.iter().filter(|c| !c.passed).count();
    println!("{} passed, {} failed", checks.len() - failed, failed);
    println!("wrote {}", path.display());
    if failed > 0 {
        return Err(format!("{failed} physics check(s) failed"));
    }
    Ok(())
}

fn run(deck: PathBuf, var: Vec<String>, log: Option<PathBuf>, no_progress: bool) -> Result<(), String> {
    let vars = var.chunks(2).map(|c| (c[0].clone(), c[1].clone())).collect();
    let opts = mcdem::deck::Options { vars, log, progress: !no_progress };
    mcdem::deck::run_file(&deck, &opts).map(|_| ()).map_err(|e| format!("ERROR: {e}"))
}

/// LIGGGHTS spells its options with one dash (`-var`, `-log`); accept both spellings.
fn liggghts_args() -> Vec<String> {
    std::env::args()
        .map(|a| match a.as_str() {
            "-var" => "--var".to_string(),
            "-log" => "--log".to_string(),
            _ => a,
        })
        .collect()
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(liggghts_args());
    let result = match cli.command {
        Command::Contacts { file } => contacts(&file),
        Command::Validate { quick, out } => validate(quick, out),
        Command::Run { deck, var, log, no_progress } => run(deck, var, log, no_progress),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.starts_with("ERROR: ") => {
            eprintln!("{e}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
