//! Cutting forces along a whole program (spec `process-models.md` §1–§2): the
//! program runs stroke by stroke through its stock, and every cutting stroke's
//! engagement is handed to the force model before the stroke is removed.
//!
//! A stroke is loaded all along it: the tool is placed at its end and then
//! every dexel back toward its start ([`sample_distances`]), each pose against
//! the stock as the strokes before it left it ([`StockEngagement`]); the
//! model asks only about edge points where the chip is positive, the half of
//! the tool ahead of the feed, which is material this stroke has not yet
//! removed. A move's loads are the largest of its samples', and the feed it
//! is allowed meets every sample's limits, so a long move through material
//! that ends in air is loaded where it cuts.
//!
//! Cutting data per stroke: the spindle speed of its IR move, the feed from
//! the stroke's length and time (so per-minute, per-revolution and
//! inverse-time feeds all count), the feed per tooth fz = v/(n·z). The tool
//! frame is the stock simulation's ([`tool_frame`]: z along the axis, x the
//! feed normal to it). The feed's component along the axis is the lead angle
//! (a ramp, or a vertical tool climbing a slope: the feed vector in the tool
//! frame is (cos lead, 0, sin lead), exactly what §1.2 needs). The chip, and
//! so every load the feed is limited by, depends on nothing else: the tilt
//! turns only the workpiece frame, which without the surface normal is taken
//! as the feed frame of a tool with no tilt (`tilt = 0`).

use millplan_geom::{DVec2, DVec3};
use millplan_models::force::coeffs::Law;
use millplan_models::force::converge::{Converged, ConvergedModel, Refine};
use millplan_models::force::deflect::{Cantilever, DE_RATIO, E_CARBIDE};
use millplan_models::force::edge::Tool;
use millplan_models::force::engage::Engagement;
use millplan_models::force::engage::SECTORS;
use millplan_models::force::feed::{Limits, Loads};
use millplan_models::force::materials::{fz_max_for, ChipLoads, FzSource};
use millplan_models::force::quadrature::Run;
use millplan_models::force::{Cut, Engaged, ForceModel, Grid, Summary};
use millplan_nc::{Move, Program};
use millplan_sim::stock::engage::tool_frame;
use millplan_sim::stock::path::{Stroke, Strokes};
use millplan_sim::stock::sim::{continues, Simulator, CUT_EPS};
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::{SectorTops, Stock};

/// The stock seen from the tool at one pose: tool-frame points (origin at the
/// tip, z along the axis, x the feed) turned into part coordinates and looked
/// up in the stock.
pub struct StockEngagement<'a> {
    stock: &'a Stock,
    tip: DVec3,
    x: DVec3,
    y: DVec3,
    z: DVec3,
    /// Highest height above the tip worth slicing.
    z_hi: f64,
    /// Material counts from this far below a column's top, mm.
    lift: f64,
    /// For a vertical tool, the highest material by distance from the axis
    /// and by angle about it ([`Stock::sector_tops`]); empty otherwise.
    sectors: SectorTops<SECTORS>,
}

/// The share of a dexel's size an edge point must lie below a column's top
/// to count as in material. The columns sample the surface a tool left at
/// their centres, so the tool at a pose next to its own cut finds up to half
/// a cell's slope of "material" that is not there; on a ball-end raster over
/// a curved part that noise alone loads a second run over the finished part
/// with a sixth of the first run's F_xy. A fifth of a cell removes nearly
/// all of it and changes a straight pass beside an earlier one by under 1 %
/// against the analytic planar raster (tests/feed.rs).
pub const LIFT_SHARE: f64 = 0.2;

impl<'a> StockEngagement<'a> {
    /// The tool of radius `radius` at `tip` with unit axis `axis` moving
    /// along `feed`. The band of heights is bounded by the highest material
    /// under the tool's reach (a tilted tool's shadow on the XY grid).
    pub fn new(
        stock: &'a Stock,
        radius: f64,
        tip: DVec3,
        axis: DVec3,
        feed: DVec3,
        flute: f64,
    ) -> Self {
        let (x, y, z) = tool_frame(axis, feed);
        let lift = LIFT_SHARE * stock.grid.res;
        let cos_g = z.z;
        let sin_g = (1.0 - cos_g * cos_g).max(0.0).sqrt();
        let mut sectors = SectorTops::default();
        // A vertical tool's slices are level circles: one pass over the
        // cells it can reach gives the highest material at every distance
        // from the axis and angle about it, which bounds every slice at once.
        let vertical = z == DVec3::Z && x.z == 0.0 && y.z == 0.0;
        let z_hi = if vertical {
            let frame = (x.truncate(), y.truncate());
            let top = stock.sector_tops(tip.truncate(), radius, frame, &mut sectors);
            (top - tip.z).clamp(0.0, flute)
        } else if cos_g > 0.2 {
            // The tool up to the flute length covers this XY rectangle.
            let top_c = tip + z * flute;
            let lo = tip.truncate().min(top_c.truncate()) - DVec2::splat(radius);
            let hi = tip.truncate().max(top_c.truncate()) + DVec2::splat(radius);
            let top = stock.max_top_in(lo, hi);
            // A point h up the axis lies at least h·cos γ − R·sin γ above the tip.
            ((top - tip.z + radius * sin_g) / cos_g).clamp(0.0, flute)
        } else {
            flute
        };
        StockEngagement {
            stock,
            tip,
            x,
            y,
            z,
            z_hi,
            lift,
            sectors,
        }
    }

    /// The tool frame's axes in part coordinates.
    pub fn frame(&self) -> (DVec3, DVec3, DVec3) {
        (self.x, self.y, self.z)
    }
}

impl Engagement for StockEngagement<'_> {
    fn z_range(&self, _tool: &Tool) -> (f64, f64) {
        (0.0, self.z_hi)
    }

    #[inline]
    fn contains(&self, p: [f64; 3]) -> bool {
        let q = self.tip + self.x * p[0] + self.y * p[1] + self.z * p[2];
        self.stock.contains(DVec3::new(q.x, q.y, q.z + self.lift))
    }

    /// A point at distance r from the axis lies in a tile whose centre is
    /// within the table's slack of r, and in the sectors that tile was
    /// entered under; it is in material only where a top rises above the
    /// level rounded to f32, exactly the comparison of `contains`.
    fn sectors(&self, z: f64, r: f64) -> u64 {
        let Some(last) = self.sectors.bins.len().checked_sub(1) else {
            return u64::MAX;
        };
        let (res, slack) = (self.stock.grid.res, self.sectors.slack);
        let a = (((r / res - slack).max(0.0)) as usize).min(last);
        let b = (((r / res + slack).max(0.0)) as usize).min(last);
        // The level as `contains` compares it with the tops.
        let level = ((self.tip.z + z) + self.lift) as f32;
        if !self.sectors.rings[a..=b].iter().any(|t| *t > level) {
            return 0;
        }
        let mut high = [f32::NEG_INFINITY; SECTORS];
        for bin in &self.sectors.bins[a..=b] {
            for (h, t) in high.iter_mut().zip(bin) {
                *h = h.max(*t);
            }
        }
        let mut mask = 0u64;
        for (s, t) in high.iter().enumerate() {
            mask |= u64::from(*t > level) << s;
        }
        mask
    }
}

/// How the forces are modelled: the law (material), the flutes and helix of
/// every tool, the discretisation and the tool as a cantilever.
#[derive(Clone, Copy, Debug)]
pub struct ForceSetup {
    pub law: Law,
    pub flutes: usize,
    /// Helix angle, rad.
    pub helix: f64,
    /// The steps of the force integrals: the coarsest with `refine`, else
    /// exactly these.
    pub grid: Grid,
    /// Refine the steps per load sample until the peaks converge
    /// ([`ConvergedModel`]; on by default, `None` uses `grid` as it is).
    pub refine: Option<Refine>,
    /// Gauge length from the holder face to the tip, mm (default 3·D).
    pub stickout: Option<f64>,
    /// Fluted length, mm: a stepped cantilever (default: the whole
    /// stick-out fluted, the Tunc–Budak form).
    pub flute_length: Option<f64>,
    /// Young's modulus of the tool, N/mm².
    pub modulus: f64,
}

impl ForceSetup {
    pub fn new(law: Law, flutes: usize) -> ForceSetup {
        ForceSetup {
            law,
            flutes,
            helix: 30f64.to_radians(),
            grid: Grid::default(),
            // Converged per load sample: with the weighted ends of
            // `force::quadrature` the slice height rarely needs halving,
            // and the rotation step is refined around the peaks only.
            refine: Some(Refine::default()),
            stickout: None,
            flute_length: None,
            modulus: E_CARBIDE,
        }
    }

    /// The force model and cantilever of one tool body.
    fn tool(&self, body: &ToolBody) -> Result<ToolForces, String> {
        let d = 2.0 * body.radius();
        let stickout = self.stickout.unwrap_or(3.0 * d);
        // The edge up to the body's flutes, never beyond what can cut.
        let flute = body
            .flute
            .min(self.flute_length.unwrap_or(stickout))
            .min(stickout);
        let tool = Tool {
            shape: body.shape,
            flutes: self.flutes,
            helix: self.helix,
            flute_length: flute,
        };
        let holding = Cantilever {
            length: stickout,
            shank_d: d,
            flute_d: DE_RATIO * d,
            flute_length: self.flute_length.filter(|l| *l < stickout),
            e: self.modulus,
        };
        holding.validate()?;
        // Without refinement the model never halves a step.
        let refine = self.refine.unwrap_or(Refine {
            halvings: 0,
            ..Refine::default()
        });
        Ok(ToolForces {
            model: ConvergedModel::new(tool, self.law, self.grid, refine)?,
            holding,
            radius: body.radius(),
            flute,
        })
    }
}

struct ToolForces {
    model: ConvergedModel,
    holding: Cantilever,
    radius: f64,
    flute: f64,
}

/// Limits of the feed scheduling (§2.3); `None` leaves a quantity free.
/// The spindle chart of the machine adds its power and torque at each
/// block's speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedLimits {
    /// F_xy,max, N.
    pub fxy: Option<f64>,
    /// T_max, N·mm.
    pub torque: Option<f64>,
    /// Mean power, W.
    pub power: Option<f64>,
    /// Bending stress, MPa.
    pub stress: Option<f64>,
    /// Tip deflection, mm.
    pub deflection: Option<f64>,
    /// Factor of safety on power, torque and stress.
    pub fos: f64,
    /// Smallest feed per tooth, mm (never above a tool's largest).
    pub fz_min: f64,
    /// Largest feed per tooth for every tool, mm; `None`: each tool's from
    /// `chip_loads` at its diameter.
    pub fz_max: Option<f64>,
    /// The material's chip loads by tool diameter; `None`: the documented
    /// fallback
    /// [`millplan_models::force::materials::FALLBACK_FZ_SHARE`]·D.
    pub chip_loads: Option<ChipLoads>,
}

/// How far over a limit a load may be and still count as meeting it: 0.5 %,
/// within the model's own resolution (the chip at the force grid's angular
/// step, the dexels' sampling of the engagement, the §2.3 iteration's 1 %
/// stop). A move over by less is reported as within the resolution, not as
/// over the limit.
pub const LIMIT_TOLERANCE: f64 = 0.005;

/// The feed-per-tooth range of one tool, and where its top came from.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FzRange {
    /// Tool diameter, mm.
    pub diameter: f64,
    pub fz_min: f64,
    pub fz_max: f64,
    pub source: FzSource,
}

impl FeedLimits {
    /// The feed-per-tooth range of a tool of diameter `d` (mm): `fz_max`
    /// as given, else the material's chip load, else 0.02·D; `fz_min` no
    /// higher than that.
    pub fn fz_range(&self, d: f64) -> FzRange {
        let (fz_max, source) = match self.fz_max {
            Some(f) => (f, FzSource::Given),
            None => fz_max_for(self.chip_loads.as_ref(), d),
        };
        FzRange {
            diameter: d,
            fz_min: self.fz_min.min(fz_max),
            fz_max,
            source,
        }
    }

    /// The iteration's limits at spindle speed `rpm` on `machine` for a tool
    /// of diameter `d` (mm).
    pub fn at(&self, rpm: f64, d: f64, machine: &crate::machine::Machine) -> Limits {
        let chart = machine.spindle_limit(rpm);
        let min = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let fz = self.fz_range(d);
        Limits {
            fxy: self.fxy,
            torque: min(self.torque, chart.map(|c| c.torque * 1000.0)),
            power: min(self.power, chart.map(|c| c.power * 1000.0)),
            stress: self.stress,
            deflection: self.deflection,
            fos: self.fos,
            fz_min: fz.fz_min,
            fz_max: fz.fz_max,
        }
    }

    /// The tightest ratio limit/load of `loads` at spindle speed `rpm` (the
    /// feed range plays no part) and its constraint.
    pub fn ratio(
        &self,
        rpm: f64,
        machine: &crate::machine::Machine,
        loads: &Loads,
    ) -> Option<(f64, millplan_models::force::feed::Constraint)> {
        self.at(rpm, 1.0, machine).ratio(loads)
    }
}

/// What one IR move met: its cutting data and the largest loads of its strokes.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MoveForces {
    /// Index of the move over the whole program.
    pub index: u32,
    pub line: u32,
    pub rapid: bool,
    /// A cutting move whose edge met no material.
    pub air: bool,
    /// A cutting move that removed material the model could not load (the
    /// spindle stopped, or no edge point ahead of the feed in material): its
    /// feed is kept.
    pub unmodelled: bool,
    /// Time at the move's start and its duration, s.
    pub t_start_s: f64,
    pub seconds: f64,
    /// Spindle speed, 1/min; feed, mm/min; feed per tooth, mm.
    pub rpm: f64,
    pub feed: f64,
    pub fz: f64,
    /// Lead angle of the feed against the tool axis, degrees.
    pub lead_deg: f64,
    /// Engaged edge cells (slice × angle) of the most loaded stroke.
    pub cells: usize,
    /// The steps the force integrals chose for the most loaded stroke: slice
    /// height, mm, and rotation step, degrees.
    pub dz_mm: f64,
    pub dphi_deg: f64,
    pub removed_mm3: f64,
    /// F_xy,max, N.
    pub fxy_max: f64,
    /// Fx, Fy, Fz ranges over a revolution in the tool frame, N.
    pub fx: [f64; 2],
    pub fy: [f64; 2],
    pub fz_force: [f64; 2],
    /// The mean force over the move's loaded poses (each a mean over a
    /// revolution, a pose in air zero), tool frame: the static load.
    #[serde(skip)]
    pub mean: millplan_models::force::mean::MeanForce,
    /// N·mm.
    pub torque_max: f64,
    pub torque_mean: f64,
    /// W.
    pub power_w: f64,
    pub stress_mpa: f64,
    pub deflection_mm: f64,
    /// The feed per tooth the limits allow (scheduling only), mm.
    pub fz_allowed: Option<f64>,
    /// The constraint that binds there.
    pub binding: Option<&'static str>,
    /// Where even the smallest feed per tooth leaves the power over its
    /// limit (scheduling only): the share of the move's spindle speed at
    /// which it is met. At a given chip the torque does not depend on the
    /// speed, so the power is proportional to it; after a constant-cutting-
    /// speed pass has raised the speed, the feed alone cannot always bring
    /// the power back down.
    pub speed_share: Option<f64>,
    /// In a [`LimitUse::Coarse`] run (zero in any other): its samples'
    /// loads less and plus [`EARLY_MARGIN`] times their estimated error,
    /// the largest of each ([`Bound`]).
    #[serde(skip)]
    pub low: Bound,
    #[serde(skip)]
    pub high: Bound,
}

impl MoveForces {
    fn merge(&mut self, s: &Summary, l: &Loads, cells: usize, model: &ForceModel) {
        let mm =
            |a: [f64; 2], m: millplan_models::force::MinMax| [a[0].min(m.min), a[1].max(m.max)];
        self.fx = mm(self.fx, s.tool[0]);
        self.fy = mm(self.fy, s.tool[1]);
        self.fz_force = mm(self.fz_force, s.tool[2]);
        if l.fxy_max >= self.fxy_max {
            self.cells = cells;
            self.dz_mm = model.dz();
            self.dphi_deg = model.dphi().to_degrees();
        }
        self.fxy_max = self.fxy_max.max(l.fxy_max);
        self.torque_max = self.torque_max.max(l.torque_max);
        self.torque_mean = self.torque_mean.max(l.torque_mean);
        self.power_w = self.power_w.max(l.power_w);
        self.stress_mpa = self.stress_mpa.max(l.stress_mpa);
        self.deflection_mm = self.deflection_mm.max(l.deflection_mm);
    }

    /// The loads as the scheduler's quantities.
    pub fn loads(&self) -> Loads {
        Loads {
            fxy_max: self.fxy_max,
            torque_max: self.torque_max,
            torque_mean: self.torque_mean,
            power_w: self.power_w,
            stress_mpa: self.stress_mpa,
            deflection_mm: self.deflection_mm,
        }
    }
}

/// The forces of a whole program.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ForceRun {
    /// One entry per simulated move, in program order.
    pub moves: Vec<MoveForces>,
    /// Strokes whose engagement was evaluated.
    pub evaluated: usize,
    /// Moves not simulated (unknown position or axis, no tool).
    pub skipped: usize,
    /// Source line of the first of them.
    pub skipped_line: Option<u32>,
}

/// The largest loads of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Maxima {
    pub fxy: f64,
    pub torque: f64,
    pub power: f64,
    pub stress: f64,
    pub deflection: f64,
}

/// The steps the force integrals chose over a run (of the most loaded
/// stroke of every loaded move).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Steps {
    /// Smallest and largest slice height, mm.
    pub dz_mm: [f64; 2],
    /// Smallest and largest rotation step, degrees.
    pub dphi_deg: [f64; 2],
    /// Loaded moves whose steps were refined below the given grid's.
    pub refined_moves: usize,
    pub loaded_moves: usize,
}

/// Why a pass that needs the spindle speed refuses a move that cut with the
/// spindle stopped (at its line).
pub const STOPPED_SPINDLE: &str = "this move removes material with the spindle at 0 1/min (S0, the spindle off, or no speed given): its cutting forces need a spindle speed; give the block an S word";

/// What a user who runs `feed` or `force` on a program without S words is
/// told besides [`STOPPED_SPINDLE`]: the option that supplies the speed.
pub const SPINDLE_OPTION: &str =
    "or, for a program that gives no spindle speed at all, give it with --spindle RPM";

/// Gives every move of `p` that runs with the spindle at 0 (the program
/// wrote no S word for it) the spindle speed `rpm`, as a user states it for
/// a program without S words; moves with a speed keep theirs. Returns how
/// many moves got `rpm`.
pub fn supply_spindle(p: &mut Program, rpm: f64) -> usize {
    let mut n = 0;
    for m in p.operations.iter_mut().flat_map(|o| o.moves.iter_mut()) {
        if !(m.spindle > 0.0) {
            m.spindle = rpm;
            n += 1;
        }
    }
    n
}

impl ForceRun {
    /// The line of the first move that removed material with the spindle
    /// stopped (an `S0` copied from the source, or no speed at all): its
    /// loads cannot be modelled, so `feed` and `force` refuse it there
    /// ([`STOPPED_SPINDLE`]) rather than keep or report it as unloaded.
    pub fn stopped_spindle(&self) -> Option<u32> {
        self.moves
            .iter()
            .find(|m| m.unmodelled && !(m.rpm > 0.0))
            .map(|m| m.line)
    }

    /// The steps chosen, against the coarsest `grid`.
    pub fn steps(&self, grid: &Grid) -> Steps {
        let mut s = Steps {
            dz_mm: [f64::INFINITY, 0.0],
            dphi_deg: [f64::INFINITY, 0.0],
            ..Steps::default()
        };
        for m in self.moves.iter().filter(|m| m.cells > 0) {
            s.loaded_moves += 1;
            s.dz_mm = [s.dz_mm[0].min(m.dz_mm), s.dz_mm[1].max(m.dz_mm)];
            s.dphi_deg = [s.dphi_deg[0].min(m.dphi_deg), s.dphi_deg[1].max(m.dphi_deg)];
            // A model's steps are the grid's or shorter by less than a third
            // (whole slices fill the flute, whole angles a tooth period).
            let finer = m.dz_mm < 0.75 * grid.dz || m.dphi_deg < 0.75 * grid.dphi.to_degrees();
            s.refined_moves += usize::from(finer);
        }
        if s.loaded_moves == 0 {
            (s.dz_mm, s.dphi_deg) = ([0.0; 2], [0.0; 2]);
        }
        s
    }

    /// The largest of the moves' [`MoveForces::low`]: the program's
    /// largest converged loads do not lie below it by the error estimate.
    pub fn floor(&self) -> Bound {
        let mut f = Bound::default();
        for m in &self.moves {
            f.raise(&m.low);
        }
        f
    }

    /// The largest loads over every move.
    pub fn maxima(&self) -> Maxima {
        let mut x = Maxima::default();
        for m in &self.moves {
            x.fxy = x.fxy.max(m.fxy_max);
            x.torque = x.torque.max(m.torque_max);
            x.power = x.power.max(m.power_w);
            x.stress = x.stress.max(m.stress_mpa);
            x.deflection = x.deflection.max(m.deflection_mm);
        }
        x
    }

    /// Moves whose loads exceed their limits (the factor of safety and the
    /// spindle chart at their speed included) by more than
    /// [`LIMIT_TOLERANCE`].
    pub fn over_limits(&self, lim: &FeedLimits, m: &crate::machine::Machine) -> Vec<&MoveForces> {
        self.by_limit_ratio(lim, m, |r| r < 1.0 / (1.0 + LIMIT_TOLERANCE))
    }

    /// Moves over a limit by no more than [`LIMIT_TOLERANCE`]: within the
    /// model's resolution.
    pub fn within_tolerance(
        &self,
        lim: &FeedLimits,
        m: &crate::machine::Machine,
    ) -> Vec<&MoveForces> {
        let lowest = 1.0 / (1.0 + LIMIT_TOLERANCE);
        self.by_limit_ratio(lim, m, |r| (lowest..1.0 - 1e-9).contains(&r))
    }

    /// Modelled cutting moves whose tightest ratio limit/load passes `keep`.
    fn by_limit_ratio(
        &self,
        lim: &FeedLimits,
        m: &crate::machine::Machine,
        keep: impl Fn(f64) -> bool,
    ) -> Vec<&MoveForces> {
        self.moves
            .iter()
            .filter(|x| !x.rapid && !x.unmodelled)
            .filter(|x| {
                lim.ratio(x.rpm, m, &x.loads())
                    .is_some_and(|(r, _)| keep(r))
            })
            .collect()
    }
}

/// The IR moves of a program by their index over the whole program.
pub fn moves_by_index(p: &Program) -> Vec<&Move> {
    p.operations.iter().flat_map(|op| op.moves.iter()).collect()
}

/// What a force run does with load limits.
#[derive(Clone, Copy, Debug)]
pub enum LimitUse<'a> {
    /// No limits: every load sample is converged unless it lies below its
    /// move's largest by more than its error.
    None,
    /// The coarsest grid only, no sample refined: a first look at the
    /// program that gives [`ForceRun::floor`] for a [`LimitUse::Largest`]
    /// run.
    Coarse,
    /// Only the program's largest loads are wanted (limits learned from
    /// the input, the figures before a pass): a sample is refined only
    /// where it may reach `floor` ([`ForceRun::floor`] of a
    /// [`LimitUse::Coarse`] run, below which the program's largest loads do
    /// not lie by the error estimate) or its move's largest so far. The
    /// program's largest loads come out as in a [`LimitUse::None`] run
    /// within that estimate; a move that cannot reach them carries the
    /// coarsest grid's error.
    Largest {
        floor: Bound,
        /// By move index: the moves whose samples may reach `floor` (the
        /// others are neither evaluated nor listed in the run).
        moves: &'a [bool],
    },
    /// A run that checks the limits: a sample whose loads, with their
    /// estimated error, stay below every limit is not refined further (it
    /// cannot be over a limit), so such loads carry the coarser grid's error.
    Check(&'a FeedLimits, &'a crate::machine::Machine),
    /// Checks, and finds the feed per tooth each stroke's limits allow
    /// (§2.3, the iteration reusing the stroke's engaged cells).
    Schedule(&'a FeedLimits, &'a crate::machine::Machine),
}

impl<'a> LimitUse<'a> {
    /// Whether the move of index `mv` is evaluated at all.
    fn evaluates(&self, mv: u32) -> bool {
        match self {
            LimitUse::Largest { moves, .. } => moves[mv as usize],
            _ => true,
        }
    }

    fn limits(&self) -> Option<(&'a FeedLimits, &'a crate::machine::Machine)> {
        match *self {
            LimitUse::None | LimitUse::Coarse | LimitUse::Largest { .. } => None,
            LimitUse::Check(l, m) | LimitUse::Schedule(l, m) => Some((l, m)),
        }
    }
}

/// Runs `strokes` (of `program`) through `stock`, evaluating the forces of
/// every cutting stroke, using the limits as `limits` says.
/// `progress(done)` is called now and then.
///
/// The strokes run in order through one stock, yet in parallel: one thread
/// removes material only (a small share of the work) and hands a copy of the
/// simulator to each part of the program as it reaches the part's first
/// stroke, and the parts' engagements and forces run on the other threads.
/// Every stroke meets exactly the stock it would meet in one sequential run,
/// so the result does not depend on the number of threads.
pub fn simulate(
    program: &Program,
    strokes: &Strokes,
    stock: Stock,
    setup: &ForceSetup,
    schedule: LimitUse<'_>,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<ForceRun, String> {
    simulate_in_parts(program, strokes, stock, setup, schedule, progress, MIN_PART)
}

/// [`simulate`] taking each load sample's engaged cells on the coarsest
/// grid from `memo` where it holds them for these strokes on this stock
/// ([`EngagementMemo::fits`]; else as [`simulate`]). The run is the one
/// [`simulate`] gives: the cells depend on the path and the stock only,
/// not on the feeds or the spindle speeds.
pub fn simulate_with(
    program: &Program,
    strokes: &Strokes,
    stock: Stock,
    setup: &ForceSetup,
    schedule: LimitUse<'_>,
    progress: &(dyn Fn(usize) + Sync),
    memo: Option<&EngagementMemo>,
) -> Result<ForceRun, String> {
    let key = memo.map(|_| memo_key(strokes, &stock, setup));
    let memo = match memo {
        Some(m) if Some(m.key) == key => Memo::Use(m),
        _ => Memo::Off,
    };
    run_parts(
        program, strokes, stock, setup, schedule, progress, MIN_PART, memo,
    )
    .map(|r| r.0)
}

/// The engaged cells on the coarsest grid of every load sample of a force
/// run (as runs of slices, [`Run`]: 8 bytes where the cells take about 60),
/// kept so that a later run over the same strokes and stock (the
/// program with other feeds or spindle speeds: the feed pass after the
/// input's loads, the check of what it wrote) need not find them again:
/// finding them is most of a run's work (the stock's columns looked up
/// over the tool's reach at every sample). Finer grids are not kept: they
/// are few, and where a run needs one it looks at the stock.
#[derive(Debug, Default)]
pub struct EngagementMemo {
    /// The strokes' and the stock's digests and the coarsest grid.
    key: u64,
    /// In stroke order, each over a range of strokes.
    parts: Vec<MemoPart>,
}

/// The memo of one part of a run.
#[derive(Debug, Default)]
struct MemoPart {
    /// The first stroke.
    first: usize,
    /// By stroke from `first`: its samples' range in `samples`, `None`
    /// where the stroke was not evaluated (or the memo was full).
    strokes: Vec<Option<(u32, u32)>>,
    /// By sample: its runs' range in `runs`.
    samples: Vec<(u32, u32)>,
    runs: Vec<Run>,
}

/// Runs of cells an [`EngagementMemo`] holds at most (8 bytes each: 128
/// MB, besides 8 bytes a sample and 12 a stroke; a 100,000-move finishing
/// program on a 0.1 mm stock needs about 15 M): beyond them a part records
/// no more, and later runs find those strokes' cells on the stock as
/// [`simulate`] does.
pub const MEMO_RUNS: usize = 16 << 20;

/// The most memory an [`EngagementMemo`]'s runs take: [`MEMO_RUNS`] of 8
/// bytes. A caller under a memory limit gives it less
/// ([`simulate_largest_within`]).
pub const MEMO_BYTES: usize = MEMO_RUNS * 8;

impl EngagementMemo {
    /// Whether the memo was recorded over `strokes` on `stock` with
    /// `setup`'s coarsest grid.
    pub fn fits(&self, strokes: &Strokes, stock: &Stock, setup: &ForceSetup) -> bool {
        self.key == memo_key(strokes, stock, setup)
    }

    /// Memory it holds, bytes.
    pub fn memory_bytes(&self) -> usize {
        self.parts
            .iter()
            .map(|p| p.strokes.capacity() * 12 + p.samples.capacity() * 8 + p.runs.capacity() * 8)
            .sum()
    }

    /// The runs of sample `j` of stroke `g`, where recorded.
    fn runs(&self, g: usize, j: usize) -> Option<&[Run]> {
        let at = self
            .parts
            .partition_point(|p| p.first <= g)
            .checked_sub(1)?;
        let part = &self.parts[at];
        let (a, b) = (*part.strokes.get(g - part.first)?)?;
        let k = a as usize + j;
        if k >= b as usize {
            return None;
        }
        let (c0, c1) = part.samples[k];
        Some(&part.runs[c0 as usize..c1 as usize])
    }
}

/// What an [`EngagementMemo`] is valid for.
fn memo_key(strokes: &Strokes, stock: &Stock, setup: &ForceSetup) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    strokes.fingerprint().hash(&mut h);
    stock.fingerprint().hash(&mut h);
    // Every setting of the model (its grid, flutes, helix, and the flute
    // length and stick-out each tool's model is cut to), as printed: the
    // shortest text of a float is its value.
    format!("{setup:?}").hash(&mut h);
    h.finish()
}

/// What a run does with an [`EngagementMemo`].
#[derive(Clone, Copy)]
enum Memo<'a> {
    Off,
    /// Keep every sample's cells (at most this many runs in all, and at
    /// most [`MEMO_RUNS`]).
    Record(usize),
    Use(&'a EngagementMemo),
}

/// A part's side of a [`Memo`] as its strokes run.
enum PartMemo<'a> {
    Off,
    Record {
        part: MemoPart,
        /// Runs recorded by every part so far.
        total: &'a std::sync::atomic::AtomicUsize,
        /// The most runs all parts may record.
        cap: usize,
        full: bool,
    },
    Use(&'a EngagementMemo),
}

impl<'a> PartMemo<'a> {
    fn new(memo: Memo<'a>, first: usize, total: &'a std::sync::atomic::AtomicUsize) -> Self {
        match memo {
            Memo::Off => PartMemo::Off,
            Memo::Use(m) => PartMemo::Use(m),
            Memo::Record(cap) => PartMemo::Record {
                part: MemoPart {
                    first,
                    ..MemoPart::default()
                },
                total,
                cap: cap.min(MEMO_RUNS),
                full: false,
            },
        }
    }

    /// The runs of sample `j` of stroke `g` where the memo used holds them.
    fn runs(&self, g: usize, j: usize) -> Option<&'a [Run]> {
        match *self {
            PartMemo::Use(m) => m.runs(g, j),
            _ => None,
        }
    }

    fn recording(&self) -> bool {
        matches!(self, PartMemo::Record { .. })
    }

    /// Stroke `g`'s samples follow.
    fn start(&mut self, g: usize) {
        if let PartMemo::Record { part, .. } = self {
            let i = g - part.first;
            if part.strokes.len() <= i {
                part.strokes.resize(i + 1, None);
            }
            let n = part.samples.len() as u32;
            part.strokes[i] = Some((n, n));
        }
    }

    /// The next sample of stroke `g` engaged the cells of `runs`. A stroke
    /// whose samples cannot all be kept (the memo full, or a sample's runs
    /// not given) is kept not at all.
    fn record(&mut self, g: usize, runs: Option<&[Run]>) {
        use std::sync::atomic::Ordering;
        let PartMemo::Record {
            part,
            total,
            cap,
            full,
        } = self
        else {
            return;
        };
        let i = g - part.first;
        let Some(runs) = runs else {
            part.strokes[i] = None;
            return;
        };
        if !*full {
            let n = total.fetch_add(runs.len(), Ordering::Relaxed) + runs.len();
            *full = n > *cap || part.samples.len() >= u32::MAX as usize - 1;
        }
        if *full {
            part.strokes[i] = None;
            return;
        }
        let c0 = part.runs.len() as u32;
        part.runs.extend_from_slice(runs);
        part.samples.push((c0, part.runs.len() as u32));
        if let Some((_, end)) = &mut part.strokes[i] {
            *end += 1;
        }
    }

    fn into_part(self) -> Option<MemoPart> {
        match self {
            PartMemo::Record { mut part, .. } => {
                part.strokes.shrink_to_fit();
                part.samples.shrink_to_fit();
                part.runs.shrink_to_fit();
                Some(part)
            }
            _ => None,
        }
    }
}

/// A bound on F_xy (N), torque (N·mm), power (W), stress (MPa) and
/// deflection (mm), each tool's stress and deflection from its own
/// cantilever: from below, loads the program's (or a move's) largest
/// converged loads do not lie under by the error estimate (its samples'
/// loads less [`EARLY_MARGIN`] times their estimated error); from above,
/// loads its samples' converged loads do not exceed (plus that error), as
/// the refinement compares them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bound {
    pub fxy: f64,
    pub torque: f64,
    pub power: f64,
    pub stress: f64,
    pub deflection: f64,
}

impl Bound {
    /// The five of `l` times `k`.
    fn of(l: &Loads, k: f64) -> Bound {
        Bound {
            fxy: l.fxy_max * k,
            torque: l.torque_max * k,
            power: l.power_w * k,
            stress: l.stress_mpa * k,
            deflection: l.deflection_mm * k,
        }
    }

    fn raise(&mut self, b: &Bound) {
        self.fxy = self.fxy.max(b.fxy);
        self.torque = self.torque.max(b.torque);
        self.power = self.power.max(b.power);
        self.stress = self.stress.max(b.stress);
        self.deflection = self.deflection.max(b.deflection);
    }

    /// Whether loads bounded above by `self` reach `floor` in any of the
    /// five (else every sample below it is settled by [`under_floor`]).
    fn reaches(&self, floor: &Bound) -> bool {
        !(self.fxy < floor.fxy
            && self.torque < floor.torque
            && self.power < floor.power
            && self.stress < floor.stress
            && self.deflection < floor.deflection)
    }
}

/// The forces of a program where only its largest loads must be
/// converged: a [`LimitUse::Coarse`] run gives every move's loads on the
/// coarsest grid and the floor ([`ForceRun::floor`]); a [`LimitUse::Largest`]
/// run then steps the stock through the program again and evaluates only
/// the moves whose samples may reach the floor, refining as a
/// [`LimitUse::None`] run does. A move that cannot reach it keeps the first
/// run's loads, which are what the second would give it (every sample
/// settled on the coarsest grid). Should the maxima found lie below the
/// floor (the error estimate failed from below), every move is converged
/// in a third run. The runs cut copies of `stock` one after the other;
/// `progress` hears each of the first two runs' strokes as half of the
/// total.
pub fn simulate_largest(
    program: &Program,
    strokes: &Strokes,
    stock: &Stock,
    setup: &ForceSetup,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<ForceRun, String> {
    simulate_largest_kept(program, strokes, stock, setup, progress).map(|r| r.0)
}

/// [`simulate_largest`], and the engaged cells of its first run on the
/// coarsest grid, which its later runs use and which a later
/// [`simulate_with`] over the same strokes and stock may use (the feed
/// pass, the check of the program it wrote).
pub fn simulate_largest_kept(
    program: &Program,
    strokes: &Strokes,
    stock: &Stock,
    setup: &ForceSetup,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(ForceRun, EngagementMemo), String> {
    simulate_largest_within(program, strokes, stock, setup, progress, MEMO_BYTES)
}

/// [`simulate_largest_kept`] with a memo of at most `memo_bytes` of runs
/// (what a memory limit leaves; 0 keeps none). The loads are the same
/// whatever it holds: a stroke it does not hold finds its cells on the
/// stock.
pub fn simulate_largest_within(
    program: &Program,
    strokes: &Strokes,
    stock: &Stock,
    setup: &ForceSetup,
    progress: &(dyn Fn(usize) + Sync),
    memo_bytes: usize,
) -> Result<(ForceRun, EngagementMemo), String> {
    let n = strokes.strokes.len();
    let (first, memo) = run_parts(
        program,
        strokes,
        stock.clone(),
        setup,
        LimitUse::Coarse,
        &|d| progress(d / 2),
        MIN_PART,
        Memo::Record(memo_bytes / 8),
    )?;
    let memo = memo.expect("recorded");
    let with = |u: LimitUse<'_>, progress: &(dyn Fn(usize) + Sync)| {
        run_parts(
            program,
            strokes,
            stock.clone(),
            setup,
            u,
            progress,
            MIN_PART,
            Memo::Use(&memo),
        )
        .map(|r| r.0)
    };
    let floor = first.floor();
    let mut moves = vec![false; moves_by_index(program).len()];
    for m in &first.moves {
        if m.high.reaches(&floor) {
            moves[m.index as usize] = true;
        }
    }
    let use_ = LimitUse::Largest {
        floor,
        moves: &moves,
    };
    let second = with(use_, &|d| progress(n / 2 + d / 2))?;
    // The second run holds the moves it evaluated only, in program order.
    let mut run = first;
    let mut slots = run.moves.iter_mut();
    for b in second.moves {
        if let Some(a) = slots.by_ref().find(|a| a.index == b.index) {
            *a = b;
        }
    }
    run.evaluated += second.evaluated;
    // The floor rests on the error estimate from below: a program whose
    // largest loads came out under it was misjudged, and is run again with
    // every move converged.
    let max = run.maxima();
    let met = max.fxy >= floor.fxy
        && max.torque >= floor.torque
        && max.power >= floor.power
        && max.stress >= floor.stress
        && max.deflection >= floor.deflection;
    if !met {
        let all = with(LimitUse::None, &|d| progress(d))?;
        return Ok((all, memo));
    }
    Ok((run, memo))
}

/// Strokes of the smallest part [`simulate`] hands to a thread: below that,
/// copying the stock costs more than the part's forces. Sampled along every
/// stroke and converged, a stroke's forces take about a millisecond (the
/// demo's raster: 4.7 samples a stroke, 0.55 ms a sample), while a copy of
/// a 10-megabyte stock takes a few: 500 strokes keep the copies under 1 %
/// and let a program of a few thousand strokes use every core.
pub const MIN_PART: usize = 500;

/// [`simulate`] with parts of at least `min_part` strokes (the result is the
/// same for any size; tests split short programs with it).
pub fn simulate_in_parts(
    program: &Program,
    strokes: &Strokes,
    stock: Stock,
    setup: &ForceSetup,
    schedule: LimitUse<'_>,
    progress: &(dyn Fn(usize) + Sync),
    min_part: usize,
) -> Result<ForceRun, String> {
    run_parts(
        program,
        strokes,
        stock,
        setup,
        schedule,
        progress,
        min_part,
        Memo::Off,
    )
    .map(|r| r.0)
}

/// [`simulate_in_parts`] with an [`EngagementMemo`] recorded or used.
#[allow(clippy::too_many_arguments)]
fn run_parts(
    program: &Program,
    strokes: &Strokes,
    stock: Stock,
    setup: &ForceSetup,
    schedule: LimitUse<'_>,
    progress: &(dyn Fn(usize) + Sync),
    min_part: usize,
    memo: Memo<'_>,
) -> Result<(ForceRun, Option<EngagementMemo>), String> {
    use std::sync::atomic::AtomicUsize;
    use std::sync::Mutex;
    let key = matches!(memo, Memo::Record(_)).then(|| memo_key(strokes, &stock, setup));
    let recorded = AtomicUsize::new(0);
    let tools: Vec<ToolForces> = strokes
        .tools
        .iter()
        .map(|b| setup.tool(b))
        .collect::<Result<_, _>>()?;
    let ir = moves_by_index(program);
    let all = &strokes.strokes;
    let stock_bytes = stock.memory_bytes();
    let bounds = part_bounds(all, rayon::current_num_threads(), stock_bytes, min_part);
    let done = AtomicUsize::new(0);
    let parts: Vec<Mutex<Option<Part>>> = (1..bounds.len()).map(|_| Mutex::new(None)).collect();
    let cx = PartContext {
        ir: &ir,
        tools: &tools,
        strokes,
        schedule,
        done: &done,
        progress,
        memo,
        recorded: &recorded,
    };
    let sim = Simulator::new(stock);
    if bounds.len() == 2 {
        let mut sim = sim;
        *parts[0].lock().expect("not poisoned") = Some(cx.run(&mut sim, 0..all.len(), 0.0));
    } else {
        rayon::scope(|sc| {
            let mut sim = Some(sim);
            let mut t = 0.0;
            for (c, w) in bounds.windows(2).enumerate() {
                let (range, t0, cx, slot) = (w[0]..w[1], t, &cx, &parts[c]);
                let Some(cur) = sim.as_mut() else { break };
                // The last part takes the simulator itself; the others a copy,
                // while this thread removes their strokes to reach the next.
                let mut own = if c + 2 == bounds.len() {
                    sim.take().expect("checked above")
                } else {
                    let own = cur.clone();
                    for s in &all[range.clone()] {
                        t += s.minutes * 60.0;
                    }
                    own
                };
                let run_range = range.clone();
                sc.spawn(move |_| {
                    let part = cx.run(&mut own, run_range, t0);
                    *slot.lock().expect("not poisoned") = Some(part);
                });
                if let Some(cur) = sim.as_mut() {
                    for s in &all[range] {
                        cur.step(s, &strokes.tools[s.tool as usize]);
                    }
                }
            }
        });
    }
    let mut run = ForceRun {
        skipped: strokes.skipped.total(),
        skipped_line: strokes.skipped.first_line,
        ..ForceRun::default()
    };
    let mut kept = key.map(|key| EngagementMemo {
        key,
        parts: Vec::new(),
    });
    for p in parts {
        let p = p
            .into_inner()
            .expect("not poisoned")
            .expect("every part ran");
        run.evaluated += p.evaluated;
        run.moves.extend(p.moves);
        if let (Some(k), Some(m)) = (kept.as_mut(), p.memo) {
            k.parts.push(m);
        }
    }
    for m in &mut run.moves {
        finish_move(m);
    }
    Ok((run, kept))
}

/// What every part of a force run shares.
struct PartContext<'a> {
    ir: &'a [&'a Move],
    tools: &'a [ToolForces],
    strokes: &'a Strokes,
    schedule: LimitUse<'a>,
    done: &'a std::sync::atomic::AtomicUsize,
    progress: &'a (dyn Fn(usize) + Sync),
    memo: Memo<'a>,
    /// Cells recorded into the memo by every part.
    recorded: &'a std::sync::atomic::AtomicUsize,
}

/// The moves of one part of the program.
struct Part {
    moves: Vec<MoveForces>,
    evaluated: usize,
    memo: Option<MemoPart>,
}

impl PartContext<'_> {
    /// Strokes `range`, starting at time `t` (s) with `sim` as the strokes
    /// before them left it.
    fn run(&self, sim: &mut Simulator, range: std::ops::Range<usize>, mut t: f64) -> Part {
        use std::sync::atomic::Ordering;
        let mut part = Part {
            moves: Vec::new(),
            evaluated: 0,
            memo: None,
        };
        let mut memo = PartMemo::new(self.memo, range.start, self.recorded);
        let (all, range_start) = (&self.strokes.strokes[..], range.start);
        for (k, s) in all[range].iter().enumerate() {
            if k % 4096 == 4095 {
                (self.progress)(self.done.fetch_add(4096, Ordering::Relaxed) + 4096);
            }
            if !self.schedule.evaluates(s.mv) {
                // Only the stock and the clock go on.
                t += s.minutes * 60.0;
                sim.step(s, &self.strokes.tools[s.tool as usize]);
                continue;
            }
            let new_move = part.moves.last().is_none_or(|m| m.index != s.mv);
            if new_move {
                let mv = self.ir.get(s.mv as usize).copied();
                part.moves.push(MoveForces {
                    index: s.mv,
                    line: s.line,
                    rapid: s.rapid,
                    t_start_s: t,
                    rpm: mv.map_or(0.0, |m| m.spindle),
                    fx: [f64::INFINITY, f64::NEG_INFINITY],
                    fy: [f64::INFINITY, f64::NEG_INFINITY],
                    fz_force: [f64::INFINITY, f64::NEG_INFINITY],
                    ..MoveForces::default()
                });
            }
            let m = part.moves.last_mut().expect("pushed above");
            m.rapid &= s.rapid;
            t += s.minutes * 60.0;
            m.seconds += s.minutes * 60.0;
            let body = &self.strokes.tools[s.tool as usize];
            if !s.rapid {
                let g = range_start + k;
                let from_cut = continues(all, g) && !all[g - 1].rapid;
                let stroke = StrokeRun {
                    tf: &self.tools[s.tool as usize],
                    stock: &sim.stock,
                    s,
                    index: g,
                    from_cut,
                    schedule: self.schedule,
                };
                if let Some(n) = stroke_forces(&stroke, m, &mut memo) {
                    part.evaluated += n;
                }
            }
            m.removed_mm3 += sim.step(s, body).removed;
        }
        part.memo = memo.into_part();
        part
    }
}

/// Stroke indices where the program is cut into parts for the threads:
/// 0, the parts' first strokes, and the stroke count. A part starts with a
/// new move (a move's strokes stay together); there are a few parts per
/// thread, so that one slow part does not leave a thread idle, each holding
/// its own copy of the stock (together at most a quarter of a gigabyte, and
/// never for a program too short to be worth it).
fn part_bounds(
    strokes: &[Stroke],
    threads: usize,
    stock_bytes: usize,
    min_part: usize,
) -> Vec<usize> {
    let n = strokes.len();
    let by_memory = (256usize << 20) / stock_bytes.max(1);
    let parts = (4 * threads).min(n / min_part.max(1)).min(by_memory).max(1);
    let mut b = vec![0];
    if threads > 1 {
        for c in 1..parts {
            let mut k = c * n / parts;
            while k < n && k > 0 && strokes[k].mv == strokes[k - 1].mv {
                k += 1;
            }
            if k < n && k > *b.last().expect("starts with 0") {
                b.push(k);
            }
        }
    }
    b.push(n);
    b
}

/// Most poses one stroke is evaluated at: a longer stroke's samples spread
/// wider than the dexel size (work stays bounded by the stroke count).
pub const MAX_SAMPLES: usize = 4096;

/// Where along a stroke of length `len` (mm) its load is evaluated: the
/// distances from its start, the end first, then every `step` (the stock's
/// dexel size, widened to `len / MAX_SAMPLES` on a very long stroke) back
/// toward the start, so the tool is seen where it enters material, all
/// along it, and where it leaves. A stroke that continues a cutting stroke
/// (`from_cut`) starts inside the cut the tool just made: there samples
/// closer than one step to the start are left out, since the dexels cannot
/// tell the chip ahead of the tool from that cut; a stroke from air is
/// sampled down to its start.
pub fn sample_distances(len: f64, step: f64, from_cut: bool) -> impl Iterator<Item = f64> {
    let h = step.max(len / MAX_SAMPLES as f64).max(1e-9);
    let lowest = if from_cut { h * (1.0 - 1e-9) } else { 1e-9 };
    // The end always; then back toward the start.
    std::iter::once(len).chain(
        (1..=MAX_SAMPLES)
            .map(move |j| len - j as f64 * h)
            .take_while(move |d| *d >= lowest),
    )
}

/// Evaluates one cutting stroke into its move at every sample along it
/// ([`sample_distances`]): the move's loads are the largest of its samples',
/// its allowed feed per tooth the one that meets every sample's limits.
/// Returns the number of evaluations.
/// One cutting stroke as [`stroke_forces`] evaluates it.
struct StrokeRun<'a> {
    tf: &'a ToolForces,
    /// The stock as the strokes before this one left it.
    stock: &'a Stock,
    s: &'a Stroke,
    /// Its index over the run's strokes.
    index: usize,
    /// Whether it continues a cutting stroke ([`sample_distances`]).
    from_cut: bool,
    schedule: LimitUse<'a>,
}

fn stroke_forces(r: &StrokeRun, m: &mut MoveForces, memo: &mut PartMemo) -> Option<usize> {
    let (tf, stock, s, schedule) = (r.tf, r.stock, r.s, r.schedule);
    let d = s.p1 - s.p0;
    let len = d.length();
    if !(len > 1e-9 && s.minutes > 0.0) {
        return None;
    }
    let v = len / s.minutes;
    let flutes = tf.model.tool().flutes as f64;
    m.feed = m.feed.max(v);
    if !(m.rpm > 0.0) {
        return None;
    }
    let fz = v / (m.rpm * flutes);
    m.fz = m.fz.max(fz);
    let limits = schedule
        .limits()
        .map(|(lim, machine)| lim.at(m.rpm, 2.0 * tf.radius, machine));
    let scheduling = matches!(schedule, LimitUse::Schedule(..));
    memo.start(r.index);
    let mut evals = 0;
    for (j, dist) in sample_distances(len, stock.grid.res, r.from_cut).enumerate() {
        let t = dist / len;
        let (tip, axis) = (s.p0 + d * t, s.axis_at(t));
        let eng = || StockEngagement::new(stock, tf.radius, tip, axis, d, tf.flute);
        let (x, _, z) = tool_frame(axis, d);
        let lead = d.dot(z).atan2(d.dot(x));
        m.lead_deg = lead.to_degrees();
        let cut = Cut {
            fz,
            rpm: m.rpm,
            lead,
            tilt: 0.0,
        };
        // The grid refined until this sample's peaks converge. When
        // scheduling, it is converged at the highest feed per tooth the
        // schedule may give the move (the loads there are the largest the
        // schedule can meet) and evaluated again at the move's own; else
        // at the move's own. A sample whose loads there, with their
        // estimated error, stay below the move's largest so far cannot
        // decide the move's loads or its feed, nor one whose loads stay
        // below every limit: it is not refined further.
        let top = match &limits {
            Some(l) if scheduling => l.fz_max.max(fz),
            _ => fz,
        };
        let most = (m.fxy_max, m.torque_max, m.power_w);
        let below = |e: &millplan_models::force::Evaluation| match schedule {
            LimitUse::Coarse => true,
            LimitUse::Largest { floor, .. } => {
                settled(e, most, None, &tf.holding) || under_floor(e, &floor, &tf.holding)
            }
            _ => settled(e, most, limits.as_ref(), &tf.holding),
        };
        // Every sample from the coarsest grid, so that its loads do not
        // depend on the samples before it (nor on where the program was
        // split over the threads).
        let at_top = Cut { fz: top, ..cut };
        let base = tf.model.base();
        let conv = match memo.runs(r.index, j) {
            Some(runs) => {
                let cells = Engaged::from_cells(&at_top, base.cells_of_runs(runs));
                tf.model.converge_cells(&at_top, cells, eng, below)
            }
            None => {
                let e = eng();
                let cells = if memo.recording() {
                    let (cells, runs) = base.engaged_runs(&at_top, &e);
                    memo.record(r.index, runs.as_deref());
                    cells
                } else {
                    base.engaged(&at_top, &e)
                };
                tf.model.converge_cells(&at_top, cells, move || e, below)
            }
        };
        evals += 1 + (conv.halvings.0 + conv.halvings.1) as usize;
        if conv.cells.is_empty() {
            m.mean.add_air();
            continue;
        }
        let sum = if top == fz {
            conv.evaluation.summary()
        } else {
            evals += 1;
            conv.evaluate_at(&cut).summary()
        };
        m.mean.add(&sum);
        if matches!(schedule, LimitUse::Coarse) {
            bound(m, &conv.evaluation, &tf.holding);
        }
        m.merge(
            &sum,
            &Loads::new(&sum, &tf.holding),
            conv.cells.len(),
            conv.model,
        );
        if let Some(lim) = limits.as_ref().filter(|_| scheduling) {
            let prev = m.fz_allowed;
            evals += tighten(&cut, &conv, &tf.holding, lim, m);
            // The finer grids were chosen around the peaks at `top`; at the
            // lower feed this sample allows, a peak may lie where they did
            // not look. Converged again there, it is checked once more.
            if let Some(a) = m.fz_allowed.filter(|a| prev != Some(*a) && *a < top) {
                let at = Cut { fz: a, ..cut };
                // The same cells on the coarsest grid (they do not depend
                // on the feed per tooth).
                let again = tf.model.converge_cells(&at, conv.cells.clone(), eng, below);
                evals += 1 + (again.halvings.0 + again.halvings.1) as usize;
                evals += tighten(&cut, &again, &tf.holding, lim, m);
            }
        }
    }
    Some(evals)
}

/// Raises the move's [`Bound`]s to the sample evaluated as `e`: its loads
/// less and plus [`EARLY_MARGIN`] times their estimated error (the
/// factor [`settled`] compares with).
fn bound(m: &mut MoveForces, e: &millplan_models::force::Evaluation, holding: &Cantilever) {
    let l = Loads::new(&e.summary(), holding);
    let err = EARLY_MARGIN * (e.error_dz + e.error_dphi);
    m.low.raise(&Bound::of(&l, (1.0 - err).max(0.0)));
    m.high.raise(&Bound::of(&l, 1.0 + err));
}

/// Whether a sample evaluated as `e` stays below `floor` in all five loads
/// with [`EARLY_MARGIN`] times its estimated error: it cannot decide any of
/// the program's largest loads (the comparison [`Bound::reaches`] makes
/// from the move's [`MoveForces::high`]).
fn under_floor(
    e: &millplan_models::force::Evaluation,
    floor: &Bound,
    holding: &Cantilever,
) -> bool {
    let l = Loads::new(&e.summary(), holding);
    !Bound::of(&l, 1.0 + EARLY_MARGIN * (e.error_dz + e.error_dphi)).reaches(floor)
}

/// How many times its estimated error a sample's loads must stay below the
/// move's largest so far for its grid not to be refined further.
pub const EARLY_MARGIN: f64 = 3.0;

/// Whether a load sample's evaluation `e` settles what its move needs
/// without refining further: its loads with their estimated error (times
/// [`EARLY_MARGIN`]) stay below the move's largest so far (`fxy`, `torque`,
/// `power`), or, when scheduling (`limits`), below every limit.
fn settled(
    e: &millplan_models::force::Evaluation,
    (fxy, torque, power): (f64, f64, f64),
    limits: Option<&Limits>,
    holding: &Cantilever,
) -> bool {
    let s = e.summary();
    let k = 1.0 + EARLY_MARGIN * (e.error_dz + e.error_dphi);
    let under_move = s.fxy_max * k < fxy && s.torque_max * k < torque && s.power_w * k < power;
    under_move
        || limits.is_some_and(|l| l.ratio(&Loads::new(&s, holding)).is_none_or(|(r, _)| r > k))
}

/// Lowers the move's allowed feed per tooth until this sample's limits are
/// met there too (feeds only lower the loads, so every earlier sample stays
/// within its limits). Returns the evaluations used.
fn tighten(
    cut: &Cut,
    conv: &Converged,
    holding: &Cantilever,
    lim: &Limits,
    m: &mut MoveForces,
) -> usize {
    let mut evals = 0;
    let start = match m.fz_allowed {
        Some(a) => {
            let s = conv.evaluate_at(&Cut { fz: a, ..*cut }).summary();
            evals += 1;
            let loads = Loads::new(&s, holding);
            match lim.ratio(&loads) {
                Some((r, _)) if r < 1.0 && a > lim.fz_min => a,
                Some((r, _)) if r < 1.0 => {
                    slow_for_power(lim, &loads, m);
                    return evals;
                }
                _ => return evals,
            }
        }
        None => cut.fz,
    };
    let (f, c, n, loads) = allowed_fz(&Cut { fz: start, ..*cut }, conv, holding, lim);
    if m.fz_allowed.is_none_or(|a| f < a) {
        m.fz_allowed = Some(f);
        m.binding = Some(c);
    }
    if let Some(l) = loads.filter(|_| m.fz_allowed == Some(f)) {
        slow_for_power(lim, &l, m);
    }
    evals + n
}

/// Where the loads at the move's allowed feed per tooth still leave the
/// power over its limit, the share of the spindle speed that meets it
/// (power ∝ speed at a given chip; 0.1 % under, as [`allowed_fz`] does),
/// the smallest over the move's samples.
fn slow_for_power(lim: &Limits, loads: &Loads, m: &mut MoveForces) {
    let power = Limits {
        fxy: None,
        torque: None,
        stress: None,
        deflection: None,
        ..*lim
    };
    if let Some((r, _)) = power.ratio(loads).filter(|(r, _)| *r < 1.0) {
        let share = r * 0.999;
        m.speed_share = Some(m.speed_share.map_or(share, |s| s.min(share)));
    }
}

/// The feed per tooth at which the tightest limit is met (§2.3), never above
/// it: the iteration from `cut.fz` stops within 1 %, and a feed still over a
/// limit (its loads evaluated at that very feed) is lowered until it is not
/// (or sits on fz_min). Returns the feed, the binding constraint's name,
/// the evaluations used and the loads at the feed returned.
fn allowed_fz(
    cut: &Cut,
    conv: &Converged,
    holding: &Cantilever,
    lim: &Limits,
) -> (f64, &'static str, usize, Option<Loads>) {
    use millplan_models::force::feed::iterate_feed;
    let eval = |fz: f64| {
        let s = conv.evaluate_at(&Cut { fz, ..*cut }).summary();
        Loads::new(&s, holding)
    };
    let sched = iterate_feed(cut.fz, lim, 0.01, 20, eval);
    let mut fz = sched.fz;
    let mut n = sched.sequence.len();
    let mut binding = sched.binding.map_or("none", |c| c.name());
    // An iteration stopped by its count left its last feed unevaluated.
    let mut loads = if sched.converged {
        sched.loads
    } else {
        n += 1;
        Some(eval(fz))
    };
    for _ in 0..20 {
        let Some((r, _)) = loads.and_then(|l| lim.ratio(&l)) else {
            break;
        };
        if r >= 1.0 || fz <= lim.fz_min {
            break;
        }
        fz = (fz * r * 0.999).max(lim.fz_min);
        if fz == lim.fz_min {
            binding = "feed-range";
        }
        loads = Some(eval(fz));
        n += 1;
    }
    (fz, binding, n, loads)
}

fn finish_move(m: &mut MoveForces) {
    let fixed = |a: &mut [f64; 2]| {
        if a[0] > a[1] {
            *a = [0.0, 0.0];
        }
    };
    fixed(&mut m.fx);
    fixed(&mut m.fy);
    fixed(&mut m.fz_force);
    if m.rapid {
        return;
    }
    let removed = m.removed_mm3 > CUT_EPS * 1e-2;
    if m.cells == 0 && m.fxy_max == 0.0 {
        m.air = !removed;
        m.unmodelled = removed;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_models::force::engage::FnEngagement;

    #[test]
    fn a_load_within_half_a_percent_of_its_limit_is_within_the_resolution() {
        let limits = FeedLimits {
            fxy: Some(100.0),
            torque: None,
            power: None,
            stress: None,
            deflection: None,
            fos: 1.0,
            fz_min: 0.01,
            fz_max: None,
            chip_loads: None,
        };
        let mv = |index: u32, fxy_max: f64| MoveForces {
            index,
            line: index + 10,
            rpm: 6000.0,
            fxy_max,
            ..MoveForces::default()
        };
        let run = ForceRun {
            moves: vec![
                mv(0, 99.0),
                mv(1, 100.0),
                mv(2, 100.04),
                mv(3, 100.49),
                mv(4, 100.6),
            ],
            ..ForceRun::default()
        };
        let m = crate::machine::Machine::default();
        let lines = |v: Vec<&MoveForces>| v.iter().map(|x| x.index).collect::<Vec<_>>();
        assert_eq!(lines(run.over_limits(&limits, &m)), [4]);
        assert_eq!(lines(run.within_tolerance(&limits, &m)), [2, 3]);
    }

    #[test]
    fn the_largest_feed_per_tooth_comes_from_the_material_by_diameter() {
        let materials = millplan_models::force::materials::Materials::builtin();
        let chip = |name: &str| materials.get(name).expect("built in").chip_loads;
        let limits = |fz_max: Option<f64>, name: &str| FeedLimits {
            fxy: None,
            torque: None,
            power: None,
            stress: None,
            deflection: None,
            fos: 1.0,
            fz_min: 0.01,
            fz_max,
            chip_loads: chip(name),
        };
        // Issue 30: a D16 tool in Ti6Al4V got 0.02·D = 0.32 mm per tooth;
        // the table's 12–16 mm column gives 0.06 mm.
        let ti = limits(None, "ti6al4v").fz_range(16.0);
        assert_eq!((ti.fz_max, ti.source), (0.06, FzSource::Material));
        // Between the table's rows, linear in D; below the first, in
        // proportion to D, with fz_min never above fz_max.
        let al = limits(None, "al7075");
        assert!((al.fz_range(9.0).fz_max - 0.07).abs() < 1e-12);
        let small = al.fz_range(1.5);
        assert!((small.fz_max - 0.005).abs() < 1e-12 && small.fz_min == small.fz_max);
        assert_eq!(al.fz_range(40.0).fz_max, 0.16);
        // A material without chip loads: the documented 0.02·D.
        let hss = limits(None, "al7075-hss").fz_range(10.0);
        assert!((hss.fz_max - 0.2).abs() < 1e-12 && hss.source == FzSource::Diameter);
        // The user's value wins for every tool.
        let given = limits(Some(0.1), "ti6al4v").fz_range(16.0);
        assert_eq!((given.fz_max, given.source), (0.1, FzSource::Given));
    }

    #[test]
    fn samples_run_from_a_strokes_end_back_to_its_start() {
        let near = |a: Vec<f64>, b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
        };
        let from_air: Vec<f64> = sample_distances(0.35, 0.1, false).collect();
        assert!(
            near(from_air.clone(), &[0.35, 0.25, 0.15, 0.05]),
            "{from_air:?}"
        );
        // After a cut, not within a step of the start.
        let after_cut: Vec<f64> = sample_distances(0.35, 0.1, true).collect();
        assert!(
            near(after_cut.clone(), &[0.35, 0.25, 0.15]),
            "{after_cut:?}"
        );
        // A short stroke in a chain: its end, as before sampling.
        let short: Vec<f64> = sample_distances(0.19, 0.1, true).collect();
        assert!(near(short.clone(), &[0.19]), "{short:?}");
        let tiny: Vec<f64> = sample_distances(0.01, 0.1, true).collect();
        assert!(near(tiny.clone(), &[0.01]), "{tiny:?}");
        // A very long stroke: at most MAX_SAMPLES, evenly spread to its start.
        let long: Vec<f64> = sample_distances(1000.0, 0.01, false).collect();
        assert!(long.len() <= MAX_SAMPLES + 1 && long.len() >= MAX_SAMPLES - 1);
        assert!(long
            .last()
            .is_some_and(|d| *d < 1000.0 / MAX_SAMPLES as f64 + 1e-9));
    }

    #[test]
    fn skipping_slices_by_the_rings_never_changes_the_engaged_cells() {
        // A stock with a wavy top, partly cut by a slot, and a vertical D10
        // ball at many poses near its surface: the cells found with the
        // ring bound are those found asking every point.
        let mut stock = Stock::from_columns(
            millplan_sim::stock::Grid::covering(
                DVec2::new(-15.0, -15.0),
                DVec2::new(15.0, 15.0),
                0.1,
            ),
            |x, y| vec![[-10.0, 0.8 * (0.3 * x).sin() + 0.5 * (0.2 * y).cos()]],
        );
        let body = ToolBody::new(millplan_models::cutter::Shape::Ball { radius: 5.0 });
        let mut sim = Simulator::new(stock.clone());
        let slot = Stroke {
            mv: 0,
            line: 0,
            tool: 0,
            rapid: false,
            p0: DVec3::new(-12.0, 2.0, -0.6),
            p1: DVec3::new(12.0, 2.0, -0.6),
            a0: DVec3::Z,
            a1: DVec3::Z,
            minutes: 0.1,
        };
        sim.step(&slot, &body);
        stock = sim.stock;
        let setup = ForceSetup::new(
            millplan_models::force::materials::Materials::builtin()
                .get("al7075")
                .expect("built in")
                .law,
            2,
        );
        let tf = setup.tool(&body).expect("valid tool");
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pruned = 0;
        for _ in 0..300 {
            let tip = DVec3::new(
                20.0 * next() - 10.0,
                20.0 * next() - 10.0,
                2.0 * next() - 1.8,
            );
            let a = std::f64::consts::TAU * next();
            let feed = DVec3::new(a.cos(), a.sin(), 0.4 * next() - 0.2);
            let eng = StockEngagement::new(&stock, 5.0, tip, DVec3::Z, feed, tf.flute);
            let (x, _, z) = eng.frame();
            let cut = Cut {
                fz: 0.1,
                rpm: 10000.0,
                lead: feed.dot(z).atan2(feed.dot(x)),
                tilt: 0.0,
            };
            let every = FnEngagement {
                z_lo: 0.0,
                z_hi: eng.z_hi,
                f: |p| eng.contains(p),
            };
            let fast = tf.model.base().engaged(&cut, &eng);
            assert_eq!(
                fast,
                tf.model.base().engaged(&cut, &every),
                "tip {tip}, feed {feed}"
            );
            pruned += (0..200)
                .map(|k| eng.sectors(k as f64 * 0.05, 2.0).count_zeros())
                .sum::<u32>();
        }
        assert!(
            pruned > 0,
            "the bound skipped nothing: the test would not see an error"
        );
    }

    #[test]
    fn the_adapter_finds_material_ahead_and_bounds_its_heights() {
        // A 10 mm block; a vertical D10 ball 0.5 mm deep at x = 5 feeding +x.
        let stock = Stock::block(
            DVec3::new(0.0, -10.0, -10.0),
            DVec3::new(20.0, 10.0, 0.0),
            0.1,
        );
        let e = StockEngagement::new(
            &stock,
            5.0,
            DVec3::new(5.0, 0.0, -0.5),
            DVec3::Z,
            DVec3::X,
            30.0,
        );
        let (lo, hi) = e.z_range(&Tool {
            shape: millplan_models::cutter::Shape::Ball { radius: 5.0 },
            flutes: 2,
            helix: 0.5,
            flute_length: 30.0,
        });
        assert_eq!(lo, 0.0);
        assert!(
            (hi - 0.5).abs() < 1e-6,
            "material reaches 0.5 mm above the tip, got {hi}"
        );
        // Ahead (+x in the tool frame) and below the top: material.
        assert!(e.contains([2.0, 0.0, 0.3]));
        // Above the block's top: none.
        assert!(!e.contains([2.0, 0.0, 0.7]));
        // Within a fifth of a cell below the top: not yet material.
        assert!(!e.contains([2.0, 0.0, 0.49]));
        // The tool frame follows the feed: feeding −y, tool-frame +x is world −y.
        let e = StockEngagement::new(
            &stock,
            5.0,
            DVec3::new(5.0, 9.9, -0.5),
            DVec3::Z,
            -DVec3::Y,
            30.0,
        );
        assert!(e.contains([2.0, 0.0, 0.3]), "ahead is −y, inside the block");
        assert!(
            !e.contains([-2.0, 0.0, 0.3]),
            "behind is +y, beyond the block's edge at 10"
        );
    }
}
