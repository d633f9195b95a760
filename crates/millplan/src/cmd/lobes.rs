//! `millplan lobes`: stability lobes by the zero-order approximation.

use crate::cmd::{arg, Range};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use millplan_models::lobes::{envelope, immersion, minimum, Lobe, Mode, Setup};
use millplan_report::svg::{line_plot, Series};
use serde_json::json;
use std::f64::consts::PI;
use std::path::PathBuf;

/// Stability lobes (zero-order approximation, Altintas & Budak; spec
/// process-models.md §3): the axial depth limit a_lim over spindle speed for
/// a tool with one mode per direction.
///
/// The mode of --fn/--k/--zeta is taken for x (feed) and, unless --fn-y or
/// --rigid-y is given, for y as well.
#[derive(clap::Args)]
pub struct Args {
    /// Natural frequency in x, Hz.
    #[arg(long = "fn")]
    pub fn_hz: f64,
    /// Modal stiffness in x, N/m.
    #[arg(long)]
    pub k: f64,
    /// Damping ratio in x.
    #[arg(long)]
    pub zeta: f64,
    /// Natural frequency in y, Hz (default: as x).
    #[arg(long, conflicts_with = "rigid_y")]
    pub fn_y: Option<f64>,
    /// Modal stiffness in y, N/m (default: as x).
    #[arg(long)]
    pub k_y: Option<f64>,
    /// Damping ratio in y (default: as x).
    #[arg(long)]
    pub zeta_y: Option<f64>,
    /// Treat y as rigid (flexible in x only).
    #[arg(long)]
    pub rigid_y: bool,
    /// Number of flutes.
    #[arg(long)]
    pub flutes: usize,
    /// Tangential cutting coefficient Ktc, N/mm² (600 = 6·10⁸ N/m²).
    #[arg(long)]
    pub kt: f64,
    /// Ratio Kr = Krc/Ktc.
    #[arg(long)]
    pub kr: f64,
    /// Full slot.
    #[arg(long, conflicts_with = "ae", required_unless_present = "ae")]
    pub slot: bool,
    /// Radial depth of cut, mm (needs --d).
    #[arg(long, requires = "d")]
    pub ae: Option<f64>,
    /// Tool diameter, mm.
    #[arg(long)]
    pub d: Option<f64>,
    /// Up-milling instead of down-milling (with --ae).
    #[arg(long)]
    pub up: bool,
    /// Lower end of the spindle-speed range, 1/min (default: around the
    /// bottoms of the lobes).
    #[arg(long)]
    pub n_min: Option<f64>,
    #[arg(long)]
    /// Upper end of the spindle-speed range, 1/min.
    pub n_max: Option<f64>,
    /// Number of lobes.
    #[arg(long, default_value_t = 10)]
    pub lobes: usize,
    /// Write the lobes as SVG.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

fn mode(hz: f64, k: f64, zeta: f64, which: &str) -> CliResult<Mode> {
    let m = Mode { fn_hz: hz, k, zeta };
    m.validate()
        .map_err(|e| CliError::input(format!("{which}: {e}")))?;
    Ok(m)
}

fn setup(a: &Args) -> CliResult<Setup> {
    let x = mode(a.fn_hz, a.k, a.zeta, "x mode (--fn, --k, --zeta)")?;
    let y = if a.rigid_y {
        None
    } else {
        let hz = a.fn_y.unwrap_or(a.fn_hz);
        Some(mode(
            hz,
            a.k_y.unwrap_or(a.k),
            a.zeta_y.unwrap_or(a.zeta),
            "y mode",
        )?)
    };
    arg("--kt", a.kt, Range::positive(1e5, "N/mm²"))?;
    arg("--kr", a.kr, Range::from(0.0, 10.0, ""))?;
    let (st, ex) = match (a.slot, a.ae, a.d) {
        (true, _, _) => (0.0, PI),
        (false, Some(ae), Some(d)) => {
            arg("--d", d, Range::positive(1000.0, "mm"))?;
            arg("--ae", ae, Range::positive(d, "mm (at most --d)"))?;
            immersion(ae, d, !a.up)
        }
        _ => return Err(CliError::input("give --slot, or --ae with --d")),
    };
    if !(1..=64).contains(&a.flutes) || !(1..=100).contains(&a.lobes) {
        return Err(CliError::input(
            "--flutes must be from 1 to 64 and --lobes from 1 to 100",
        ));
    }
    let s = Setup {
        x: Some(x),
        y,
        flutes: a.flutes,
        kt: a.kt * 1e6,
        kr: a.kr,
        st,
        ex,
    };
    s.validate().map_err(CliError::input)?;
    Ok(s)
}

pub fn run(a: Args) -> CliResult<i32> {
    let s = setup(&a)?;
    let (lo, hi) = s.band();
    let lobes = s.lobes(lo, hi, 20_000, a.lobes);
    let Some(min) = minimum(&lobes) else {
        return Err(CliError::input(
            "no chatter frequency gives a positive depth limit",
        ));
    };
    // Default range: around the bottoms of the lobes.
    let bottoms: Vec<f64> = lobes
        .iter()
        .filter_map(|l| minimum(std::slice::from_ref(l)))
        .map(|p| p.rpm)
        .collect();
    let n_lo = a
        .n_min
        .unwrap_or_else(|| 0.9 * bottoms.iter().cloned().fold(f64::INFINITY, f64::min));
    let n_hi = a
        .n_max
        .unwrap_or_else(|| 1.3 * bottoms.iter().cloned().fold(0.0, f64::max));
    arg("--n-min", n_lo, Range::positive(1e6, "1/min"))?;
    arg("--n-max", n_hi, Range::positive(1e6, "1/min"))?;
    if !(n_hi > n_lo) {
        return Err(CliError::input("--n-max must be above --n-min"));
    }
    let env = envelope(&lobes, n_lo, n_hi, 1000);
    if let Some(p) = &a.output {
        let mut out = Outputs::plan(&[], &[("-o", Some(p))], true)?;
        out.write(p, plot(&lobes, &env, n_lo, n_hi).as_bytes())?;
        out.commit()?;
    }
    if a.json {
        let j = json!({
            "a_lim_min_mm": min.a_lim_mm, "fc_hz": min.fc_hz, "rpm_at_min": min.rpm,
            "immersion_deg": [s.st.to_degrees(), s.ex.to_degrees()],
            "envelope": env.iter().map(|(n, a)| [*n, *a]).collect::<Vec<_>>(),
        });
        crate::cmd::print_json(j);
    } else {
        outln!(
            "a_lim,min {:.4} mm (chatter at {:.1} Hz, {:.0} 1/min)",
            min.a_lim_mm,
            min.fc_hz,
            min.rpm
        );
        let best = env
            .iter()
            .cloned()
            .fold((0.0, 0.0), |b, p| if p.1 > b.1 { p } else { b });
        outln!(
            "in {n_lo:.0}…{n_hi:.0} 1/min the deepest stable cut is {:.4} mm at {:.0} 1/min",
            best.1,
            best.0
        );
    }
    Ok(EXIT_OK)
}

fn plot(lobes: &[Lobe], env: &[(f64, f64)], n_lo: f64, n_hi: f64) -> String {
    let cap = 10.0 * env.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let mut series = vec![Series {
        name: "stability limit",
        color: "#000000",
        points: env.to_vec(),
    }];
    for l in lobes.iter().filter(|l| l.branch == 0).take(6) {
        let points: Vec<(f64, f64)> = l
            .points
            .iter()
            .filter(|p| p.rpm >= n_lo && p.rpm <= n_hi && p.a_lim_mm <= cap)
            .map(|p| (p.rpm, p.a_lim_mm))
            .collect();
        if !points.is_empty() {
            series.push(Series {
                name: "lobe",
                color: "#9ecae1",
                points,
            });
        }
    }
    line_plot(
        "Stability lobes (zero-order approximation)",
        "spindle speed [1/min]",
        "a_lim [mm]",
        &series,
    )
}
