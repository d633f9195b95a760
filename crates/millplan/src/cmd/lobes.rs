//! `millplan lobes`: stability lobes by the zero-order approximation.

use crate::cmd::{arg, Range, MAX_SPINDLE};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use millplan_models::lobes::{
    immersion, EnvPoint, LobePoint, LobesError, Mode, Setup, Stability, MAX_LOBES,
};
use millplan_report::svg::{line_plot, Series};
use std::f64::consts::PI;
use std::path::PathBuf;

/// Stability lobes (zero-order approximation, Altintas & Budak; spec
/// process-models.md §3): the axial depth limit a_lim over spindle speed for
/// a tool with one mode per direction.
///
/// The mode of --fn/--k/--zeta is taken for x (feed) and, unless --fn-y or
/// --rigid-y is given, for y as well. At every speed the limit is the
/// smallest over every lobe that reaches it (all lobe numbers and both
/// eigenvalue roots, chatter frequencies from 0 up to a band that grows
/// until nothing above it can come lower); the deepest stable cut is the
/// largest limit over the speed range, with the speed and the lobe that
/// set it.
#[derive(clap::Args)]
pub struct Args {
    /// Natural frequency in x, Hz (1 to 100,000).
    #[arg(long = "fn")]
    pub fn_hz: f64,
    /// Modal stiffness in x, N/m (1 to 1e15).
    #[arg(long)]
    pub k: f64,
    /// Damping ratio in x (0.0001 to below 1).
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
    /// Tangential cutting coefficient Ktc, N/mm² (600 = 6·10⁸ N/m²; 1 to
    /// 100,000).
    #[arg(long)]
    pub kt: f64,
    /// Ratio Kr = Krc/Ktc (0 to 10).
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
    /// Lower end of the spindle-speed range, 1/min (default: 0.9 times the
    /// speed of the bottom of lobe 9). The range may span at most 500 lobes
    /// (counted at 1.25 times the highest natural frequency); a lower start
    /// is refused with the lowest one accepted.
    #[arg(long)]
    pub n_min: Option<f64>,
    /// Upper end of the spindle-speed range, 1/min (default: 1.3 times the
    /// speed of the bottom of lobe 0, at most 1,000,000).
    #[arg(long)]
    pub n_max: Option<f64>,
    /// Write the stability limit over the speed range as SVG (the envelope
    /// of all lobes, not each lobe, however many the range spans; clipped
    /// at 10 times the smallest limit in the range or just above the
    /// deepest stable cut, which is marked).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print JSON: the smallest limit, the deepest stable cut in the range,
    /// the lobes that set the envelope, the chatter band searched and the
    /// envelope as [speed, a_lim] pairs.
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
    arg("--kt", a.kt, Range::from(1.0, 1e5, "N/mm²"))?;
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
    if !(1..=64).contains(&a.flutes) {
        return Err(CliError::input("--flutes must be from 1 to 64"));
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
    let min = s.minimum().map_err(|e| CliError::input(e.to_string()))?;
    let (n_lo, n_hi) = range(&a, &s, &min)?;
    let st = s.stability(n_lo, n_hi).map_err(|e| match e {
        LobesError::TooManyLobes { .. } => CliError::input(format!("--n-min {n_lo}: {e}")),
        LobesError::Invalid(m) => CliError::input(m),
    })?;
    if let Some(p) = &a.output {
        let mut out = Outputs::plan(&[], &[("-o", Some(p))], true)?;
        out.write(p, plot(&st).as_bytes())?;
        out.commit()?;
    }
    if a.json {
        let j = serde_json::to_value(report(&s, &min, &st, [n_lo, n_hi]))
            .map_err(|e| CliError::internal(format!("JSON output: {e}")))?;
        crate::cmd::print_json(j);
    } else {
        print_text(&min, s.lobe_speed(&min, 0), &st, [n_lo, n_hi]);
    }
    Ok(EXIT_OK)
}

/// The speed range: the options, or the library's default around the
/// bottoms of lobes 9…0 (its top capped at the largest spindle speed).
fn range(a: &Args, s: &Setup, min: &LobePoint) -> CliResult<(f64, f64)> {
    let (lo, hi) = s.default_range(min);
    let n_lo = a.n_min.unwrap_or(lo);
    let n_hi = a.n_max.unwrap_or(hi.min(MAX_SPINDLE));
    arg("--n-min", n_lo, Range::positive(MAX_SPINDLE, "1/min"))?;
    arg("--n-max", n_hi, Range::positive(MAX_SPINDLE, "1/min"))?;
    if !(n_hi > n_lo) {
        return Err(CliError::input(format!(
            "--n-max {n_hi} must be above --n-min {n_lo}"
        )));
    }
    Ok((n_lo, n_hi))
}

/// The deepest stable cut in JSON.
#[derive(serde::Serialize)]
struct Deepest {
    a_lim_mm: f64,
    rpm: f64,
    /// Chatter frequency and lobe; absent where the value is the band's
    /// bound.
    fc_hz: Option<f64>,
    lobe: Option<u64>,
}

/// `lobes --json`.
#[derive(serde::Serialize)]
struct Report {
    a_lim_min_mm: f64,
    fc_hz: f64,
    /// Speed of lobe 0's bottom.
    rpm_at_min: f64,
    immersion_deg: [f64; 2],
    n_range: [f64; 2],
    deepest: Deepest,
    /// Lowest and highest lobe numbers that set the envelope.
    lobes: Option<[u64; 2]>,
    /// The chatter band searched, Hz: from 0 to this.
    band_hz: f64,
    /// Envelope values at or below this depth are exact; above, they are
    /// this lower bound.
    exact_below_mm: f64,
    max_lobes: f64,
    envelope: Vec<[f64; 2]>,
}

fn report(s: &Setup, min: &LobePoint, st: &Stability, n_range: [f64; 2]) -> Report {
    let d = st.deepest;
    Report {
        a_lim_min_mm: min.a_lim_mm,
        fc_hz: min.fc_hz,
        rpm_at_min: s.lobe_speed(min, 0),
        immersion_deg: [s.st.to_degrees(), s.ex.to_degrees()],
        n_range,
        deepest: Deepest {
            a_lim_mm: d.a_lim_mm,
            rpm: d.rpm,
            fc_hz: d.chatter.map(|c| c.fc_hz),
            lobe: d.chatter.map(|c| c.lobe),
        },
        lobes: st.lobes().map(|(lo, hi)| [lo, hi]),
        band_hz: st.band_hz,
        exact_below_mm: st.exact_below_mm,
        max_lobes: MAX_LOBES,
        envelope: st.envelope.iter().map(|p| [p.rpm, p.a_lim_mm]).collect(),
    }
}

fn print_text(min: &LobePoint, rpm_at_min: f64, st: &Stability, [n_lo, n_hi]: [f64; 2]) {
    outln!(
        "a_lim,min {} mm (chatter at {:.1} Hz, {rpm_at_min:.0} 1/min)",
        mm(min.a_lim_mm),
        min.fc_hz
    );
    let d = st.deepest;
    let why = match d.chatter {
        Some(c) => format!("lobe {}, chatter at {:.1} Hz", c.lobe, c.fc_hz),
        None => "at least: no lobe below this depth reaches that speed".into(),
    };
    outln!(
        "in {n_lo:.0}…{n_hi:.0} 1/min the deepest stable cut is {} mm at {:.0} 1/min ({why})",
        mm(d.a_lim_mm),
        d.rpm
    );
    if let Some((lo, hi)) = st.lobes() {
        outln!(
            "the limit there is set by lobes {lo}…{hi} (chatter frequencies 0…{:.0} Hz searched)",
            st.band_hz
        );
    }
}

/// A depth in mm to four decimals, or four digits where that would show
/// none.
fn mm(v: f64) -> String {
    if v >= 0.001 {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}

/// The envelope (every lobe's minimum, one curve, however many lobes the
/// range spans), clipped at 10 times its smallest value or 1.25 times the
/// deepest cut, whichever is higher, unless that cut lies above 100 times
/// the smallest value, so that the pockets stay readable; and a vertical
/// line at the deepest stable cut.
fn plot(st: &Stability) -> String {
    let floor = st
        .envelope
        .iter()
        .map(|p| p.a_lim_mm)
        .fold(f64::INFINITY, f64::min);
    // Room for the deepest cut unless it towers over the pockets (above
    // lobe 0 the limit grows without end).
    let deepest = st.deepest.a_lim_mm;
    let cap = if deepest <= 100.0 * floor {
        (10.0 * floor).max(1.25 * deepest)
    } else {
        10.0 * floor
    };
    let clipped = st.envelope.iter().any(|p| p.a_lim_mm > cap);
    let name = if clipped {
        format!("stability limit (clipped at {cap:.3} mm)")
    } else {
        "stability limit".to_string()
    };
    let points = |e: &[EnvPoint]| e.iter().map(|p| (p.rpm, p.a_lim_mm.min(cap))).collect();
    let d = st.deepest;
    let series = [
        Series {
            name: &name,
            color: "#000000",
            points: points(&st.envelope),
        },
        Series {
            name: "deepest stable cut",
            color: "#d62728",
            points: vec![(d.rpm, 0.0), (d.rpm, d.a_lim_mm.min(cap))],
        },
    ];
    line_plot(
        "Stability lobes (zero-order approximation)",
        "spindle speed [1/min]",
        "a_lim [mm]",
        &series,
    )
}
