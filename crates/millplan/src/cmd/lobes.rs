//! `millplan lobes`: stability lobes by the zero-order approximation.

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use crate::timings::{Clock, Table as _};
use millplan_driver::lobes::LobesRequest;
use std::path::PathBuf;

/// Stability lobes (the zero-order approximation of Altintas and Budak, see
/// docs/forces.md): the axial depth limit a_lim over spindle speed for
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
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

fn request(a: &Args) -> LobesRequest {
    LobesRequest {
        fn_hz: a.fn_hz,
        k: a.k,
        zeta: a.zeta,
        fn_y: a.fn_y,
        k_y: a.k_y,
        zeta_y: a.zeta_y,
        rigid_y: a.rigid_y,
        flutes: a.flutes,
        kt: a.kt,
        kr: a.kr,
        slot: a.slot,
        ae: a.ae,
        d: a.d,
        up: a.up,
        n_min: a.n_min,
        n_max: a.n_max,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = Clock::start();
    let o = millplan_driver::lobes::run(&request(&a)).map_err(CliError::input)?;
    clock.lap("lobes and their envelope computed");
    if let Some(p) = &a.output {
        let mut out = Outputs::plan(&[], &[("-o", Some(p))], true)?;
        out.write(p, o.plot().as_bytes())?;
        out.commit()?;
        clock.lap("plot drawn, written and renamed into place");
    }
    crate::cmd::print_summary(a.json, || o.json(), || o.render_text());
    clock.end(a.timings.on);
    Ok(EXIT_OK)
}
