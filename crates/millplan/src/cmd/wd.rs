//! `millplan wd`: the working diameter of one case.

use crate::cmd::{arg, Range, MAX_TOOL_D, MAX_VC};
use crate::error::{CliError, CliResult, EXIT_OK};
use clap::ValueEnum;
use millplan_models::wd::{self, Case, Neighbour, Side};
use serde_json::json;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SideArg {
    Left,
    Right,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ModelArg {
    /// The geometric engagement model (exact).
    Geometric,
    /// The fitted least-squares surrogate (fast, approximate).
    Regression,
}

/// Working diameter of a ball-end mill for one case (paper 000; spec
/// working-diameter.md §1): the tool diameter at the highest engaged point of the
/// ball on a locally planar surface.
///
/// Angles in degrees: --alpha is the surface inclination (0 = flat); --af the feed
/// direction relative to uphill (0 = straight uphill, 180 = downhill, positive
/// counter-clockwise seen from outside the material); --side the side of the feed
/// the uncut material is on (with M3, right = climb milling). Without --ae there is
/// no neighbouring pass (first or isolated pass).
#[derive(clap::Args)]
pub struct Args {
    /// Ball diameter, mm.
    #[arg(long)]
    pub d: f64,
    /// Stock thickness along the surface normal, mm.
    #[arg(long)]
    pub ap: f64,
    /// Distance to the already machined neighbouring pass, mm.
    #[arg(long)]
    pub ae: Option<f64>,
    /// Both neighbouring passes are already machined (needs --ae).
    #[arg(long)]
    pub both: bool,
    /// Surface inclination, degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub alpha: f64,
    /// Feed direction relative to uphill, degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub af: f64,
    /// Side of the feed the uncut material is on.
    #[arg(long, value_enum, default_value = "left")]
    pub side: SideArg,
    /// Cutting speed, m/min: also print the spindle speed for it.
    #[arg(long)]
    pub vc: Option<f64>,
    /// Which model computes D_w: geometric (exact) or regression (the fitted
    /// surrogate).
    #[arg(long, value_enum, default_value = "geometric")]
    pub model: ModelArg,
    /// Print a machine-readable summary (JSON) on standard output; errors too, as JSON
    /// on standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    arg("--d", a.d, Range::positive(MAX_TOOL_D, "mm"))?;
    // The ball model's domain: the stock no thicker than the ball's radius.
    arg("--ap", a.ap, Range::positive(a.d / 2.0, "mm (at most D/2)"))?;
    if let Some(ae) = a.ae {
        arg("--ae", ae, Range::positive(MAX_TOOL_D, "mm"))?;
    }
    if !(0.0..90.0).contains(&a.alpha) {
        return Err(CliError::input(format!(
            "--alpha {}: must be a number from 0 to under 90 degrees",
            a.alpha
        )));
    }
    arg("--af", a.af, Range::from(-360.0, 360.0, "degrees"))?;
    if let Some(vc) = a.vc {
        arg("--vc", vc, Range::positive(MAX_VC, "m/min"))?;
    }
    if a.both && a.ae.is_none() {
        return Err(CliError::input("--both needs --ae"));
    }
    let neighbour = match (a.ae, a.both) {
        (None, _) => Neighbour::None,
        (Some(x), false) => Neighbour::One(x),
        (Some(x), true) => Neighbour::Both(x),
    };
    let af = (a.af + 180.0).rem_euclid(360.0) - 180.0;
    let c = Case {
        d: a.d,
        ap: a.ap,
        neighbour,
        alpha: a.alpha.to_radians(),
        af: af.to_radians(),
        side: match a.side {
            SideArg::Left => Side::Left,
            SideArg::Right => Side::Right,
        },
    };
    let dw = match a.model {
        ModelArg::Geometric => wd::working_diameter(&c),
        ModelArg::Regression => millplan_models::regression::Surrogate::standard().predict(&c),
    };
    let dcc = wd::contact_diameter(a.d, c.alpha);
    let d_mean_area = wd::mean_diameter(&c, wd::MeanWeighting::Area, 300);
    let d_mean_chip = wd::mean_diameter(&c, wd::MeanWeighting::ChipThickness, 300);
    let n = a.vc.map(|vc| wd::spindle_speed(vc, dw));
    if a.json {
        let j = json!({
            "d_w": dw, "d_cc": dcc, "d_mean_area": d_mean_area, "d_mean_chip": d_mean_chip,
            "n": n, "model": format!("{:?}", a.model).to_lowercase()
        });
        crate::cmd::print_json(j);
    } else {
        outln!("D_w  {dw:.3} mm  (working diameter, highest engaged point)");
        outln!("D_cc {dcc:.3} mm  (diameter at the contact point)");
        outln!("D_mean {d_mean_area:.3} mm by area, {d_mean_chip:.3} mm by chip thickness (over the engaged region)");
        if let Some(n) = n {
            outln!("n    {n:.0} 1/min for vc = {} m/min", a.vc.unwrap_or(0.0));
        }
    }
    Ok(EXIT_OK)
}
