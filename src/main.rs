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
    /// Nonlocal quasi-static reference (Gonzalez & Cuitiño 2012): solve a JSON scene along its loading path
    Nonlocal {
        /// Scene file (JSON, see docs/nonlocal.md)
        scene: PathBuf,
        /// Per-step CSV output (default: standard output)
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Also write every contact force, one CSV per step, into this directory
        #[arg(long)]
        contacts: Option<PathBuf>,
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

fn nonlocal(scene: PathBuf, out: Option<PathBuf>, contacts: Option<PathBuf>) -> Result<(), String> {
    let mut scene = mcdem::nonlocal::scene::Scene::load(&scene)?;
    let mut sink: Box<dyn std::io::Write> = match &out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).map_err(|e| format!("cannot create {}: {e}", p.display()))?,
        )),
        None => Box::new(std::io::stdout().lock()),
    };
    let summary = scene.run(&mut *sink, contacts.as_deref(), &mut |line| eprintln!("{line}"))?;
    sink.flush().map_err(|e| format!("cannot write output: {e}"))?;
    eprintln!("done: {} load steps in {:.2} s", summary.steps, summary.wall_seconds);
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Contacts { file } => contacts(&file),
        Command::Nonlocal { scene, out, contacts } => nonlocal(scene, out, contacts),
        Command::Validate { quick, out } => validate(quick, out),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
