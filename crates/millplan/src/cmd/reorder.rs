//! `millplan reorder`: reorder finishing points so the working diameter changes
//! least between successive points (paper 000, thesis 5), with safe links.

use crate::cmd::{print_diagnostics, read_options, target_for, write_program, TargetArg, UnitArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::{read_program, read_surface, write_atomic};
use clap::ValueEnum;
use millplan_nc::write::WriteOptions;
use millplan_nc::Program;
use millplan_plan::reorder::{reorder, Method, ReorderParams, Start};
use millplan_plan::speed::apply;
use serde_json::json;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    /// The paper's greedy search over single points.
    Paper,
    /// Passes kept as units, improved by 2-opt on |Δn|, link length and turns.
    Optimised,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum StartArg {
    Lowest,
    Highest,
    Random,
}

/// Reorder the points of 3-axis ball-end finishing operations so the working
/// diameter, and with it the spindle speed for constant cutting speed, changes
/// as little as possible between successive points (paper 000, thesis 5).
///
/// Every cutting point is kept; links between points that are not neighbours
/// are direct only when the drop-cutter check proves them gouge-free, otherwise
/// the tool retracts, rapids and plunges. Spindle control (as `millplan speed`)
/// is applied to the result unless --no-speed. The JSON summary compares the
/// original and the reordered order.
#[derive(clap::Args)]
pub struct Args {
    pub path: PathBuf,
    #[arg(long)]
    pub stl: PathBuf,
    #[arg(long, value_enum, default_value = "paper")]
    pub method: MethodArg,
    /// Start of the paper's search, among the border points.
    #[arg(long, value_enum, default_value = "lowest")]
    pub start: StartArg,
    /// Start at this cutting point (index) instead.
    #[arg(long)]
    pub start_index: Option<usize>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Minimum number of candidates of the paper's search.
    #[arg(long, default_value_t = 4)]
    pub n_min: usize,
    /// D_w differences within this are ties, broken by continuing straight, mm.
    #[arg(long, default_value_t = 0.001)]
    pub tie: f64,
    /// Step guard of the paper search, mm: when every candidate would change
    /// D_w by more than this, the search looks farther (up to 32 × its radius)
    /// for one that does not, linking to it by a retract where it is not a
    /// neighbour. 0 runs the search exactly as published.
    #[arg(long, default_value_t = 0.5)]
    pub max_step: f64,
    #[command(flatten)]
    pub cut: super::CuttingData,
    /// Write the reordered points without spindle control.
    #[arg(long)]
    pub no_speed: bool,
    #[arg(long)]
    pub machine: Option<PathBuf>,
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    #[arg(short, long)]
    pub output: PathBuf,
    /// HTML report: both orders side by side (D_w and spindle speed along the
    /// path, the distribution of successive changes, the tour from above).
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    #[arg(long)]
    pub json: bool,
    #[arg(long, short)]
    pub quiet: bool,
}

/// Indicators of an order: successive changes of D_w (evaluated for the direction
/// each point is reached from and the material cut before it) and of the spindle
/// speed for constant cutting speed, plus path figures.
fn indicators(
    p: &Program,
    dw: &[f64],
    jump: &[bool],
    vc: f64,
    rapid_rate: f64,
) -> serde_json::Value {
    let n: Vec<f64> = dw
        .iter()
        .map(|d| millplan_models::wd::spindle_speed(vc, *d))
        .collect();
    // Changes between points cut one after the other; steps across jumps
    // (retract and plunge) are reported apart: the spindle has time there.
    let steps = |v: &[f64], across: bool| -> (f64, f64, f64) {
        let d: Vec<f64> = (1..v.len())
            .filter(|&k| jump[k] == across)
            .map(|k| (v[k] - v[k - 1]).abs())
            .collect();
        let min = d.iter().copied().fold(f64::INFINITY, f64::min);
        (
            if min.is_finite() { min } else { 0.0 },
            d.iter().copied().fold(0.0, f64::max),
            d.iter().sum(),
        )
    };
    let (dw_min, dw_max, _) = steps(dw, false);
    let (n_min, n_max, tv) = steps(&n, false);
    let (_, dw_jump_max, _) = steps(dw, true);
    let jumps = jump.iter().filter(|j| **j).count();
    let s = millplan_nc::stats::summarize(p, rapid_rate);
    json!({
        "delta_d_w": { "min": dw_min, "max": dw_max, "max_across_jumps": dw_jump_max },
        "jumps": jumps,
        "delta_n": { "min": n_min, "max": n_max },
        "total_variation_n": tv,
        "cutting_mm": s.cutting_mm,
        "link_mm": s.rapid_mm,
        "rapids": s.moves.rapid,
        "time_s": s.time_s,
        "points": dw.len(),
    })
}

pub fn run(a: Args) -> CliResult<i32> {
    if !(a.max_step >= 0.0) {
        return Err(CliError::input("--max-step must be ≥ 0 (mm)"));
    }
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let parsed = read_program(&a.path, read_options(a.units, None))?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    let (mesh, _) = read_surface(&a.stl)?;
    let mut rp = ReorderParams::new(match a.method {
        MethodArg::Paper => Method::Paper,
        MethodArg::Optimised => Method::Optimised,
    });
    rp.start = match (a.start_index, a.start) {
        (Some(i), _) => Start::Index(i),
        (None, StartArg::Lowest) => Start::Lowest,
        (None, StartArg::Highest) => Start::Highest,
        (None, StartArg::Random) => Start::Random(a.seed),
    };
    rp.n_min = a.n_min;
    rp.tie = a.tie;
    rp.max_step = (a.max_step > 0.0).then_some(a.max_step);
    rp.ap = a.cut.ap;
    rp.vc = a.cut.vc;
    let res = reorder(&parsed.program, &mesh, &rp)
        .map_err(|e| CliError::input(format!("{}: {e}", a.path.display())))?;
    let sp = a.cut.params();
    let before = indicators(
        &parsed.program,
        &res.dw_original,
        &res.jump_original,
        a.cut.vc,
        machine.rapid,
    );
    let after = indicators(
        &res.program,
        &res.dw_reordered,
        &res.jump_reordered,
        a.cut.vc,
        machine.rapid,
    );
    let html = a
        .report
        .as_ref()
        .map(|_| report(&parsed.program, &res, &before, &after, a.cut.vc));
    let program = if a.no_speed {
        res.program
    } else {
        apply(&res.program, &mesh, &machine, &sp)
            .map_err(|e| CliError::input(e.to_string()))?
            .program
    };
    let target = target_for(a.to, &a.output, parsed.program.source)?;
    let out = write_program(&program, WriteOptions::new(target), &a.path, a.quiet)?;
    write_atomic(&a.output, &out, &[a.path.as_path(), a.stl.as_path()])?;
    if let (Some(path), Some(html)) = (&a.report, &html) {
        write_atomic(path, html.as_bytes(), &[a.path.as_path(), a.stl.as_path()])?;
    }
    let j = json!({ "method": format!("{:?}", a.method).to_lowercase(), "original": before, "reordered": after, "stats": res.stats, "output": a.output.display().to_string() });
    if a.json {
        println!("{}", serde_json::to_string_pretty(&j).unwrap_or_default());
    } else {
        let row = |k: &str, f: &dyn Fn(&serde_json::Value) -> String| {
            println!("  {k:<28} {:>16} {:>16}", f(&before), f(&after))
        };
        println!("  {:<28} {:>16} {:>16}", "", "original", "reordered");
        row("successive |ΔD_w| max (mm)", &|v| {
            format!("{:.4}", v["delta_d_w"]["max"].as_f64().unwrap_or(0.0))
        });
        row("successive |Δn| max (1/min)", &|v| {
            format!("{:.0}", v["delta_n"]["max"].as_f64().unwrap_or(0.0))
        });
        row("Σ|Δn| (1/min)", &|v| {
            format!("{:.0}", v["total_variation_n"].as_f64().unwrap_or(0.0))
        });
        row("cutting length (mm)", &|v| {
            format!("{:.0}", v["cutting_mm"].as_f64().unwrap_or(0.0))
        });
        row("rapid length (mm)", &|v| {
            format!("{:.0}", v["link_mm"].as_f64().unwrap_or(0.0))
        });
        row("rapid moves", &|v| format!("{}", v["rapids"]));
        row("estimated time (s)", &|v| {
            format!("{:.0}", v["time_s"].as_f64().unwrap_or(0.0))
        });
        println!(
            "  {} direct links, {} retracts; wrote {}",
            res.stats.direct_links,
            res.stats.retracts,
            a.output.display()
        );
    }
    Ok(EXIT_OK)
}

/// The XY of the cutting moves of the ball-end operations, in program order.
fn cutting_xy(p: &Program) -> Vec<(f64, f64)> {
    p.operations
        .iter()
        .filter(|o| {
            o.tool
                .as_ref()
                .and_then(|t| t.cutter)
                .is_some_and(|c| c.kind == millplan_nc::CutterKind::Ball)
        })
        .flat_map(|o| o.moves.iter().filter(|m| m.is_cutting()))
        .map(|m| (m.end.x, m.end.y))
        .collect()
}

/// The HTML report: both orders side by side.
fn report(
    original: &Program,
    res: &millplan_plan::reorder::Reordered,
    before: &serde_json::Value,
    after: &serde_json::Value,
    vc: f64,
) -> String {
    use millplan_report::svg::{histogram, line_plot, map, Series};
    let (blue, orange) = ("#1f77b4", "#ff7f0e");
    let along = |v: &[f64], f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        v.iter()
            .enumerate()
            .map(|(k, d)| (k as f64, f(*d)))
            .collect()
    };
    let speed = |d: f64| millplan_models::wd::spindle_speed(vc, d);
    // Successive changes between points cut one after the other.
    let steps = |v: &[f64], jump: &[bool]| -> Vec<f64> {
        (1..v.len())
            .filter(|&k| !jump[k])
            .map(|k| (v[k] - v[k - 1]).abs())
            .collect()
    };
    let tour = |xy: Vec<(f64, f64)>| -> Vec<(f64, f64, f64)> {
        let n = xy.len().max(1) as f64;
        xy.into_iter()
            .enumerate()
            .map(|(k, (x, y))| (x, y, k as f64 / n))
            .collect()
    };
    let num = |v: &serde_json::Value, path: &[&str], digits: usize| -> String {
        let mut x = v;
        for k in path {
            x = &x[*k];
        }
        match x.as_f64() {
            Some(f) => format!("{f:.digits$}"),
            None => x.to_string(),
        }
    };
    let rows: Vec<(String, String)> = [
        ("successive |ΔD_w| max (mm)", &["delta_d_w", "max"][..], 4),
        (
            "|ΔD_w| max across jumps (mm)",
            &["delta_d_w", "max_across_jumps"],
            4,
        ),
        ("successive |Δn| max (1/min)", &["delta_n", "max"], 0),
        ("Σ|Δn| (1/min)", &["total_variation_n"], 0),
        ("jumps (retract or long link)", &["jumps"], 0),
        ("cutting length (mm)", &["cutting_mm"], 0),
        ("rapid length (mm)", &["link_mm"], 0),
        ("estimated time (s)", &["time_s"], 0),
    ]
    .iter()
    .map(|(k, path, digits)| {
        (
            k.to_string(),
            format!(
                "{} → {}",
                num(before, path, *digits),
                num(after, path, *digits)
            ),
        )
    })
    .collect();
    let figures = vec![
        (
            "Working diameter at each cutting point, in cutting order: the original order (blue) and the reordered one (orange).".to_string(),
            line_plot(
                "Working diameter along the path",
                "point in cutting order",
                "D_w (mm)",
                &[
                    Series { name: "original", color: blue, points: along(&res.dw_original, &|d| d) },
                    Series { name: "reordered", color: orange, points: along(&res.dw_reordered, &|d| d) },
                ],
            ),
        ),
        (
            format!("Spindle speed for a constant cutting speed of {vc} m/min (before machine limits), in cutting order."),
            line_plot(
                "Spindle speed along the path",
                "point in cutting order",
                "n (1/min)",
                &[
                    Series { name: "original", color: blue, points: along(&res.dw_original, &speed) },
                    Series { name: "reordered", color: orange, points: along(&res.dw_reordered, &speed) },
                ],
            ),
        ),
        (
            "Change of working diameter between points cut one after the other (steps across a retract or long link left out: the spindle has time there).".to_string(),
            histogram(
                "Successive |ΔD_w|",
                "|ΔD_w| (mm)",
                40,
                &[
                    ("original", blue, steps(&res.dw_original, &res.jump_original)),
                    ("reordered", orange, steps(&res.dw_reordered, &res.jump_reordered)),
                ],
            ),
        ),
        (
            "The original order seen from above, coloured from the first cutting point (0) to the last (1).".to_string(),
            map("Original order", "order", &tour(cutting_xy(original))),
        ),
        (
            "The reordered path seen from above, coloured from the first cutting point (0) to the last (1).".to_string(),
            map("Reordered", "order", &tour(cutting_xy(&res.program))),
        ),
    ];
    millplan_report::html::simple_report(
        "Toolpath reordering",
        "Paper 000, thesis 5: cutting points reordered so the working diameter, and with it the spindle speed for a constant cutting speed, changes as little as possible between successive points. Original → reordered.",
        &rows,
        &figures,
    )
}
