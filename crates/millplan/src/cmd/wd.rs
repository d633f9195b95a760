//! `millplan wd`: the working diameter of one case.

use crate::error::{CliError, CliResult, EXIT_OK};
use clap::ValueEnum;
use millplan_driver::wd::{Side, WdRequest};

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

/// Working diameter of a ball-end mill for one case (the boundary method of
/// docs/usage.md): the tool diameter at the highest engaged point of the
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
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
}

pub fn run(a: Args) -> CliResult<i32> {
    let req = WdRequest {
        d: a.d,
        ap: a.ap,
        ae: a.ae,
        both: a.both,
        alpha: a.alpha,
        af: a.af,
        side: match a.side {
            SideArg::Left => Side::Left,
            SideArg::Right => Side::Right,
        },
        vc: a.vc,
        regression: matches!(a.model, ModelArg::Regression),
    };
    let o = millplan_driver::wd::run(&req).map_err(CliError::input)?;
    a.summary.print(&o, |o| o.render_text());
    Ok(EXIT_OK)
}
