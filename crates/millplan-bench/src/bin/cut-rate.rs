//! Single-engagement force evaluations per second (`millplan cut` target:
//! ≥ 10,000 at 1° rotation steps and 0.05 mm slices): a D16 4-flute ball-end
//! mill, 30° helix, constant Ti-like coefficients, planar raster engagements
//! with ap 0.5–1.5 mm, ae 0.5–3 mm, lead 0–15°, tilt −15–15°, spread over the
//! available cores (one task per engagement). The steps are refined per
//! engagement until the peaks converge (`force::converge`) from the default
//! grid; with `--fixed-grid` the default grid is used as it is.
//!
//! Usage: `cut-rate [ENGAGEMENTS] [--fixed-grid]` (default 100,000).

use millplan_models::cutter::Shape;
use millplan_models::force::coeffs::{Coeffs, Law};
use millplan_models::force::converge::{ConvergedModel, Refine};
use millplan_models::force::edge::Tool;
use millplan_models::force::engage::PlanarRaster;
use millplan_models::force::{Cut, Grid};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fixed = args.iter().any(|a| a == "--fixed-grid");
    let n: usize = args.iter().find_map(|s| s.parse().ok()).unwrap_or(100_000);
    let tool = Tool {
        shape: Shape::Ball { radius: 8.0 },
        flutes: 4,
        helix: 30f64.to_radians(),
        flute_length: 48.0,
    };
    // The spec's T4 set (its Kac, in §1.3's frame, is −Kac here).
    let law = Law::Rta(Coeffs::rta(1750.0, 550.0, -640.0, 24.0, 43.0, 0.0));
    let refine = Refine {
        halvings: if fixed { 0 } else { Refine::default().halvings },
        ..Refine::default()
    };
    let Ok(model) = ConvergedModel::new(tool, law, Grid::default(), refine) else {
        eprintln!("the benchmark tool is invalid");
        std::process::exit(1);
    };
    let mut s = 0x9e3779b97f4a7c15u64;
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let jobs: Vec<(Cut, PlanarRaster)> = (0..n)
        .filter_map(|_| {
            let (lead, tilt) = ((15.0 * r()).to_radians(), (-15.0 + 30.0 * r()).to_radians());
            let e = PlanarRaster::new(&tool, 0.5 + r(), Some(0.5 + 2.5 * r()), lead, tilt).ok()?;
            let c = Cut {
                fz: 0.05 + 0.15 * r(),
                rpm: 3000.0,
                lead,
                tilt,
            };
            Some((c, e))
        })
        .collect();
    let cpu0 = cpu_seconds();
    let t = std::time::Instant::now();
    use rayon::prelude::*;
    let out: Vec<_> = jobs.par_iter().map(|(c, e)| model.evaluate(c, e)).collect();
    let secs = t.elapsed().as_secs_f64();
    let cpu = cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    let peak = out.iter().map(|e| e.summary().fxy_max).fold(0.0, f64::max);
    let refined = out
        .iter()
        .filter(|e| e.dz < 0.04 || e.dphi < 0.9f64.to_radians())
        .count();
    println!("{refined} of {} engagements refined", out.len());
    println!(
        "{} engagements in {secs:.3} s on {} threads: {:.0} engagements/s (largest F_xy,max {peak:.0} N)",
        jobs.len(),
        rayon::current_num_threads(),
        jobs.len() as f64 / secs
    );
    // On a shared machine the wall clock includes waiting for the cores;
    // the process's CPU time does not.
    if let Some(c) = cpu.filter(|c| *c > 0.0) {
        println!(
            "CPU time {c:.2} s: {:.0} engagements per CPU-second",
            jobs.len() as f64 / c
        );
    }
}

/// User + system CPU time of this process from /proc/self/stat (Linux; clock
/// ticks of 1/100 s).
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name in parentheses; utime and stime are the
    // 14th and 15th fields of the line.
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
