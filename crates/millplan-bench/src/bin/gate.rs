//! The benchmark gate (see `crates/millplan-bench/gate.sh`, which builds the
//! binaries and runs this): generates the reduced workloads' inputs, runs each
//! workload of `millplan` under `valgrind --tool=cachegrind --cache-sim=no`
//! with `RAYON_NUM_THREADS=1`, and compares each instruction count with the
//! baseline file. Exit 1 when a count is more than 3 % above its baseline
//! (or a workload fails to run), 0 otherwise.
//!
//! Usage: `gate --millplan PATH [--baseline FILE] [--update] [--only NAME,...]
//! [--inputs DIR] [--made-with TEXT]`.

use millplan_bench::gate::{
    command_line, judge, parse_i_refs, report_line, write_inputs, Baseline, Verdict, WORKLOADS,
};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

struct Options {
    millplan: PathBuf,
    baseline: PathBuf,
    update: bool,
    only: Option<Vec<String>>,
    inputs: Option<PathBuf>,
    made_with: String,
}

fn options() -> Result<Options, String> {
    let mut o = Options {
        millplan: PathBuf::new(),
        baseline: millplan_bench::gate::default_baseline(),
        update: false,
        only: None,
        inputs: None,
        made_with: String::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--millplan" => o.millplan = value()?.into(),
            "--baseline" => o.baseline = value()?.into(),
            "--inputs" => o.inputs = Some(value()?.into()),
            "--made-with" => o.made_with = value()?,
            "--only" => o.only = Some(value()?.split(',').map(String::from).collect()),
            "--update" => o.update = true,
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    if o.millplan.as_os_str().is_empty() {
        return Err("--millplan PATH (the release binary to measure) is required".into());
    }
    Ok(o)
}

/// Runs one command line under cachegrind and returns its instruction count.
fn measure(millplan: &Path, args: &[String], ok_codes: &[i32]) -> Result<u64, String> {
    let out = Command::new("valgrind")
        .args([
            "--tool=cachegrind",
            "--cache-sim=no",
            "--cachegrind-out-file=/dev/null",
        ])
        .arg(millplan)
        .args(args)
        .env("RAYON_NUM_THREADS", "1")
        .env_remove("MILLPLAN_LIMITS")
        .output()
        .map_err(|e| format!("valgrind could not be started: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code().unwrap_or(-1);
    if !ok_codes.contains(&code) {
        return Err(format!("exit {code}:\n{stderr}"));
    }
    parse_i_refs(&stderr).ok_or_else(|| format!("no `I refs` in valgrind's output:\n{stderr}"))
}

/// CPU seconds (user + system) of this process's waited-for children so far,
/// from `/proc/self/stat` (Linux; 0 elsewhere): on a busy machine the wall
/// time of a workload says little about what it costs on a quiet one.
fn children_cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // The fields after the command name in parentheses; cutime and cstime
    // are fields 16 and 17 (13 and 14 after the name), in ticks of 1/100 s.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    (f.get(13).copied().unwrap_or(0.0) + f.get(14).copied().unwrap_or(0.0)) / 100.0
}

fn main() {
    let o = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("gate: {e}");
            std::process::exit(2);
        }
    };
    let baseline = match std::fs::read_to_string(&o.baseline) {
        Ok(t) => Baseline::parse(&t).unwrap_or_else(|e| {
            eprintln!("gate: {}: {e}", o.baseline.display());
            std::process::exit(2);
        }),
        Err(e) if o.update => {
            eprintln!("gate: {}: {e}; writing a new one", o.baseline.display());
            Baseline::default()
        }
        Err(e) => {
            eprintln!("gate: {}: {e}", o.baseline.display());
            std::process::exit(2);
        }
    };
    let tmp = tempfile::tempdir().unwrap_or_else(|e| {
        eprintln!("gate: no temporary folder: {e}");
        std::process::exit(2);
    });
    let dir = o.inputs.clone().unwrap_or_else(|| tmp.path().to_path_buf());
    let t = Instant::now();
    if let Err(e) = write_inputs(&dir) {
        eprintln!("gate: {}: {e}", dir.display());
        std::process::exit(2);
    }
    eprintln!("gate: inputs written in {:.1} s", t.elapsed().as_secs_f64());
    std::process::exit(run(&o, &baseline, &dir));
}

/// Measures every chosen workload; prints one line each; returns the exit code.
fn run(o: &Options, baseline: &Baseline, dir: &Path) -> i32 {
    let mut new = baseline.clone();
    let mut failed = Vec::new();
    let mut broken = Vec::new();
    for w in WORKLOADS {
        if o.only
            .as_ref()
            .is_some_and(|only| !only.iter().any(|n| n == w.name))
        {
            continue;
        }
        let (t, cpu) = (Instant::now(), children_cpu_s());
        let count = match measure(&o.millplan, &command_line(w, dir), w.ok_codes) {
            Ok(c) => c,
            Err(e) => {
                println!("{}: did not run: {e}", w.name);
                broken.push(w.name);
                continue;
            }
        };
        let base = baseline.counts.get(w.name).copied();
        let verdict = judge(base, count);
        println!(
            "{}  [under valgrind {:.0} s, {:.0} s of CPU]",
            report_line(w.name, base, count, &verdict),
            t.elapsed().as_secs_f64(),
            children_cpu_s() - cpu
        );
        if matches!(verdict, Verdict::Fail(_)) {
            failed.push(w.name);
        }
        new.counts.insert(w.name.to_string(), count);
    }
    if o.update && broken.is_empty() {
        if let Err(e) = std::fs::write(&o.baseline, new.render(&o.made_with)) {
            eprintln!("gate: {}: {e}", o.baseline.display());
            return 2;
        }
        println!("gate: baseline written to {}", o.baseline.display());
        return 0;
    }
    failed.extend(broken);
    if failed.is_empty() {
        println!("gate: every workload within +3 % of its baseline");
        0
    } else {
        println!(
            "gate: FAILED: {} (more than +3 % over the baseline, or did not run); if the change is deliberate, run `crates/millplan-bench/gate.sh --update` and say why in the commit",
            failed.join(", ")
        );
        1
    }
}
