//! `millplan lobes`: the request checked into the stability setup, the
//! speed range, the typed summary, the text and the plot.

use crate::check::{arg, Range, MAX_SPINDLE};
use millplan_models::lobes::{
    immersion, EnvPoint, LobePoint, LobesError, Mode, Setup, Stability, MAX_LOBES,
};
use millplan_report::svg::{line_plot, Series};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// The options of `millplan lobes`.
#[derive(Clone, Debug)]
pub struct LobesRequest {
    pub fn_hz: f64,
    pub k: f64,
    pub zeta: f64,
    pub fn_y: Option<f64>,
    pub k_y: Option<f64>,
    pub zeta_y: Option<f64>,
    pub rigid_y: bool,
    pub flutes: usize,
    pub kt: f64,
    pub kr: f64,
    pub slot: bool,
    pub ae: Option<f64>,
    pub d: Option<f64>,
    pub up: bool,
    pub n_min: Option<f64>,
    pub n_max: Option<f64>,
}

/// The lobes of a request over its speed range.
pub struct LobesOutcome {
    pub setup: Setup,
    pub min: LobePoint,
    pub stability: Stability,
    pub n_range: [f64; 2],
}

/// Checks the request and computes the lobes.
pub fn run(a: &LobesRequest) -> Result<LobesOutcome, String> {
    let s = setup(a)?;
    let min = s.minimum().map_err(|e| e.to_string())?;
    let (n_lo, n_hi) = range(a, &s, &min)?;
    let st = s.stability(n_lo, n_hi).map_err(|e| match e {
        LobesError::TooManyLobes { .. } => format!("--n-min {n_lo}: {e}"),
        LobesError::Invalid(m) => m,
    })?;
    Ok(LobesOutcome {
        setup: s,
        min,
        stability: st,
        n_range: [n_lo, n_hi],
    })
}

impl LobesOutcome {
    /// What `lobes --json` prints.
    pub fn json(&self) -> Report {
        report(&self.setup, &self.min, &self.stability, self.n_range)
    }

    /// The text summary.
    pub fn render_text(&self) -> String {
        let rpm_at_min = self.setup.lobe_speed(&self.min, 0);
        render_text(&self.min, rpm_at_min, &self.stability, self.n_range)
    }

    /// The envelope as an SVG plot.
    pub fn plot(&self) -> String {
        plot(&self.stability)
    }
}

fn mode(hz: f64, k: f64, zeta: f64, which: &str) -> Result<Mode, String> {
    let m = Mode { fn_hz: hz, k, zeta };
    m.validate().map_err(|e| format!("{which}: {e}"))?;
    Ok(m)
}

fn setup(a: &LobesRequest) -> Result<Setup, String> {
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
            arg("--d", d, Range::positive(crate::check::MAX_TOOL_D, "mm"))?;
            arg("--ae", ae, Range::positive(d, "mm (at most --d)"))?;
            immersion(ae, d, !a.up)
        }
        _ => return Err("give --slot, or --ae with --d".into()),
    };
    if !(1..=64).contains(&a.flutes) {
        return Err("--flutes must be from 1 to 64".into());
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
    s.validate()?;
    Ok(s)
}

/// The speed range: the options, or the library's default around the
/// bottoms of lobes 9…0 (its top capped at the largest spindle speed).
fn range(a: &LobesRequest, s: &Setup, min: &LobePoint) -> Result<(f64, f64), String> {
    let (lo, hi) = s.default_range(min);
    let n_lo = a.n_min.unwrap_or(lo);
    let n_hi = a.n_max.unwrap_or(hi.min(MAX_SPINDLE));
    arg("--n-min", n_lo, Range::positive(MAX_SPINDLE, "1/min"))?;
    arg("--n-max", n_hi, Range::positive(MAX_SPINDLE, "1/min"))?;
    if !(n_hi > n_lo) {
        return Err(format!("--n-max {n_hi} must be above --n-min {n_lo}"));
    }
    Ok((n_lo, n_hi))
}

/// The deepest stable cut in JSON.
#[derive(serde::Serialize)]
pub struct Deepest {
    a_lim_mm: f64,
    rpm: f64,
    /// Chatter frequency and lobe; absent where the value is the band's
    /// bound.
    fc_hz: Option<f64>,
    lobe: Option<u64>,
}

/// `lobes --json`.
#[derive(serde::Serialize)]
pub struct Report {
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

fn render_text(min: &LobePoint, rpm_at_min: f64, st: &Stability, [n_lo, n_hi]: [f64; 2]) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "a_lim,min {} mm (chatter at {:.1} Hz, {rpm_at_min:.0} 1/min)",
        mm(min.a_lim_mm),
        min.fc_hz
    );
    let d = st.deepest;
    let why = match d.chatter {
        Some(c) => format!("lobe {}, chatter at {:.1} Hz", c.lobe, c.fc_hz),
        None => "at least: no lobe below this depth reaches that speed".into(),
    };
    let _ = writeln!(
        o,
        "in {n_lo:.0}…{n_hi:.0} 1/min the deepest stable cut is {} mm at {:.0} 1/min ({why})",
        mm(d.a_lim_mm),
        d.rpm
    );
    if let Some((lo, hi)) = st.lobes() {
        let _ = writeln!(
            o,
            "the limit there is set by lobes {lo}…{hi} (chatter frequencies 0…{:.0} Hz searched)",
            st.band_hz
        );
    }
    o
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
