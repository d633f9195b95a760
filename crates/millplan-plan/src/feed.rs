//! The feed pass: a feed per block from the cutting forces (spec
//! `process-models.md` §2.3). The program runs through its stock
//! ([`crate::force::simulate`]); every cutting stroke gets the feed per tooth
//! at which its tightest limit (F_xy, torque, power, bending stress, tip
//! deflection, the spindle chart's power and torque at the block's speed) is
//! met; a block takes the smallest of its strokes' and their samples' along
//! them ([`crate::force::sample_distances`]). Blocks whose edge meets no
//! material run at the air feed ([`air_feed`]: the machine file's
//! `[feed] air`, else the tool's largest feed per tooth at the block's
//! speed, at most the machine's feed limit). A flat or bull-nose end mill
//! plunging into material (down its axis steeper than 45°) cuts with end
//! teeth the model does not load: its feed may be lowered, never raised
//! above the program's. Feeds then stay within the
//! machine's feed range, and changes between neighbouring blocks are brought
//! within the feed acceleration by lowering feeds only (a block decelerates
//! to its successor's feed within its own length, and reaches its own feed
//! from its predecessor's within its length), so no block ends up above the
//! feed its limits allow. Positions and feed modes are kept, and spindle
//! speeds but where the power stays over its limit at the smallest feed per
//! tooth (a constant-cutting-speed pass may have raised the speed that
//! far): at a given chip the power is proportional to the speed, so that
//! block's speed is lowered by the share that meets the limit
//! ([`MoveForces::speed_share`]). Canned cycles and moves the simulation
//! could not follow keep their feeds.

use crate::force::{self, FeedLimits, ForceRun, ForceSetup, MoveForces};
use crate::machine::Machine;
use crate::pipeline::{Changes, Context, Need, Pass, PassError, PassInfo};
use millplan_models::cutter::Shape;
use millplan_nc::{FeedMode, MoveKind, Operation, Program};
use millplan_sim::stock::path::{strokes, PathOptions};
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::Stock;
use std::collections::BTreeMap;

pub static INFO: PassInfo = PassInfo {
    name: "feed",
    needs: &[Need::Machine],
    changes: Changes::How,
    does:
        "a feed per block so the tightest force, torque, power, stress or deflection limit is met",
};

/// The tool body of an operation (`None` leaves the operation out).
pub type BodyFn = Box<dyn Fn(&Operation) -> Option<ToolBody> + Sync>;

/// What the feed pass needs besides the program and the machine.
pub struct FeedParams {
    pub setup: ForceSetup,
    pub limits: FeedLimits,
    /// Feed acceleration, mm/s².
    pub accel: f64,
    /// Chord tolerance of arcs in the simulation, mm.
    pub chord: f64,
    /// The limits among `limits` taken from the input's own largest loads
    /// (none was given), by name.
    pub learned: Vec<&'static str>,
}

/// How the feeds were set.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FeedChanges {
    /// Cutting blocks that got a feed from the forces.
    pub blocks: usize,
    /// Cutting blocks in air, set to the air feed ([`air_feed`]; still
    /// counted here when the feed acceleration lowers them).
    pub air_blocks: usize,
    /// Cutting blocks that keep their feed (canned cycles, moves not
    /// simulated, material the model could not load).
    pub kept_blocks: usize,
    /// What decided each block's feed: a limit's name, `feed-range` (fz or
    /// the machine's feed range), `power-speed` (the power over its limit
    /// even at the smallest feed per tooth: the spindle speed lowered in
    /// proportion, the feed per tooth kept), `accel` (lowered for the feed
    /// acceleration), `air`, `kept`, `plunge` (a flat or bull-nose end mill
    /// going down into material steeper than 45°: the model loads its flank,
    /// not its end teeth, so the feed is not raised above the program's).
    pub binding: BTreeMap<&'static str, usize>,
    /// Feeds written, mm/min.
    pub feed_min: f64,
    pub feed_max: f64,
}

/// The feed pass (see the module docs).
pub struct FeedPass {
    pub params: FeedParams,
    stock: Option<Stock>,
    body: BodyFn,
    /// The forces at the input's feeds with the feeds allowed, after the run.
    pub before: Option<ForceRun>,
    pub changes: Option<FeedChanges>,
    /// Engaged cells an earlier force run over the same path and stock
    /// found ([`force::simulate_with`]; used where it fits).
    pub memo: Option<std::sync::Arc<force::EngagementMemo>>,
}

impl FeedPass {
    /// `stock` is the material before the program; `body` the tool body of
    /// an operation (`None` leaves it out).
    pub fn new(params: FeedParams, stock: Stock, body: BodyFn) -> FeedPass {
        FeedPass {
            params,
            stock: Some(stock),
            body,
            before: None,
            changes: None,
            memo: None,
        }
    }
}

impl Pass for FeedPass {
    fn info(&self) -> &'static PassInfo {
        &INFO
    }

    fn run(&mut self, p: &mut Program, cx: &Context) -> Result<(), PassError> {
        let input = |message: String| PassError::Input {
            pass: INFO.name,
            message,
        };
        let stock = self
            .stock
            .take()
            .ok_or_else(|| input("the pass runs once per stock".into()))?;
        let m = &cx.machine;
        let s = strokes(
            p,
            &self.body,
            &PathOptions {
                chord: self.params.chord,
                rapid_rate: m.rapid,
            },
        );
        let total = s.strokes.len();
        let run = cx
            .time("forces and allowed feeds", || {
                force::simulate_with(
                    p,
                    &s,
                    stock,
                    &self.params.setup,
                    force::LimitUse::Schedule(&self.params.limits, m),
                    &|done| cx.progress("feed: forces", done, total),
                    self.memo.as_deref(),
                )
            })
            .map_err(input)?;
        cx.progress("feed: forces", total, total);
        let changes = cx.time("feeds smoothed and written", || {
            apply(p, &run, m, &self.params, &self.body)
        });
        self.before = Some(run);
        self.changes = Some(changes);
        Ok(())
    }
}

/// The machine's feed acceleration, mm/s²: the smallest its linear axes
/// give; `None` when it gives none.
pub fn machine_accel(m: &Machine) -> Option<f64> {
    [m.axes.x.accel, m.axes.y.accel, m.axes.z.accel]
        .into_iter()
        .flatten()
        .min_by(f64::total_cmp)
}

/// The feed-per-tooth range of every tool of a run.
pub fn fz_ranges(limits: &FeedLimits, tools: &[ToolBody]) -> Vec<crate::force::FzRange> {
    tools
        .iter()
        .map(|t| limits.fz_range(2.0 * t.radius()))
        .collect()
}

/// The feed (mm/min) of a cutting block that meets no material, at spindle
/// speed `rpm` with a tool of `flutes` whose largest feed per tooth is
/// `fz_max`: the machine file's `[feed] air`, else fz_max·z·n but never
/// below the block's own feed (`programmed`: a block in air is not slowed;
/// a tool given far smaller than the program's, a millimetre figure for
/// an inch tool, took a program's air feeds down to 15 mm/min), within the
/// machine's feed range.
pub fn air_feed(m: &Machine, fz_max: f64, flutes: f64, rpm: f64, programmed: f64) -> f64 {
    let v = m.feed_air.unwrap_or(if rpm > 0.0 {
        (fz_max * flutes * rpm).max(programmed)
    } else {
        programmed
    });
    v.clamp(m.feed_min, m.feed_max)
}

/// The feed (mm/min) each block asks for and why, before smoothing, and the
/// lower spindle speed of a block whose power the feed alone cannot bring
/// within its limit ([`MoveForces::speed_share`], no lower than the
/// machine's smallest); `fz_max` is the largest feed per tooth of the
/// block's tool.
fn target(
    mf: &MoveForces,
    m: &Machine,
    flutes: f64,
    fz_max: f64,
) -> (f64, &'static str, Option<f64>) {
    if mf.air {
        return (air_feed(m, fz_max, flutes, mf.rpm, mf.feed), "air", None);
    }
    match mf.fz_allowed {
        Some(fz) if !mf.unmodelled => {
            let rpm = mf
                .speed_share
                .map(|s| (mf.rpm * s).clamp(m.spindle_min.min(mf.rpm), mf.rpm));
            let v = fz * rpm.unwrap_or(mf.rpm) * flutes;
            let c = v.clamp(m.feed_min, m.feed_max);
            let why = match (c != v, rpm) {
                (true, _) => "feed-range",
                (false, Some(_)) => "power-speed",
                (false, None) => mf.binding.unwrap_or("none"),
            };
            (c, why, rpm)
        }
        _ => (mf.feed, "kept", None),
    }
}

/// Sets the feeds of `p` from `run` (see the module docs); `body` gives the
/// tool of an operation (its diameter decides the air feed's fz_max).
pub fn apply(
    p: &mut Program,
    run: &ForceRun,
    m: &Machine,
    params: &FeedParams,
    body: &BodyFn,
) -> FeedChanges {
    let flutes = params.setup.flutes as f64;
    let by_index: BTreeMap<u32, &MoveForces> = run.moves.iter().map(|x| (x.index, x)).collect();
    let mut ch = FeedChanges {
        feed_min: f64::INFINITY,
        feed_max: 0.0,
        ..FeedChanges::default()
    };
    let mut first = 0u32;
    for op in &mut p.operations {
        let tool = body(op);
        let d = tool.map_or(0.0, |b| 2.0 * b.radius());
        let fz_max = params.limits.fz_range(d).fz_max;
        // The model loads a flat or bull-nose end mill's flank, not its
        // end teeth: a plunge of one into material keeps its feed at most.
        let end_teeth = tool.is_some_and(|b| !matches!(b.shape, Shape::Ball { .. }));
        // Chains of consecutive feed blocks: (move index, length, feed, why).
        let mut chain: Vec<(usize, f64, f64, &'static str)> = Vec::new();
        let mut chains = Vec::new();
        for i in 0..op.moves.len() {
            let mv = op.moves[i];
            let mf = by_index.get(&(first + i as u32));
            let len = op.move_length(i);
            let schedulable =
                matches!(mv.kind, MoveKind::Linear | MoveKind::Arc(_)) && mv.feed > 0.0;
            match (schedulable, mf, len) {
                (true, Some(mf), Some(len)) if len > 0.0 => {
                    let (mut v, mut why, rpm) = target(mf, m, flutes, fz_max);
                    if end_teeth && !mf.air && v > mf.feed && plunges(op, i) {
                        (v, why) = (mf.feed, "plunge");
                    }
                    if let Some(n) = rpm {
                        op.moves[i].spindle = n;
                    }
                    chain.push((i, len, v, why));
                }
                _ => {
                    if mv.is_cutting() {
                        ch.kept_blocks += 1;
                        *ch.binding.entry("kept").or_default() += 1;
                    }
                    if !chain.is_empty() {
                        chains.push(std::mem::take(&mut chain));
                    }
                }
            }
        }
        chains.push(chain);
        first += op.moves.len() as u32;
        for c in chains.iter_mut().filter(|c| !c.is_empty()) {
            smooth(c, params.accel);
            for &(i, len, v, why) in c.iter() {
                set_feed(op, i, len, v);
                match why {
                    "air" => ch.air_blocks += 1,
                    "kept" => ch.kept_blocks += 1,
                    _ => ch.blocks += 1,
                }
                *ch.binding.entry(why).or_default() += 1;
                ch.feed_min = ch.feed_min.min(v);
                ch.feed_max = ch.feed_max.max(v);
            }
        }
    }
    if ch.feed_min > ch.feed_max {
        ch.feed_min = 0.0;
    }
    ch
}

/// Whether move `i` of `op` goes down along the tool axis more than it goes
/// sideways (steeper than 45°): a plunge, where a flat or bull-nose end mill
/// cuts with its end teeth.
fn plunges(op: &Operation, i: usize) -> bool {
    let m = &op.moves[i];
    let Some(start) = op.known_start(i) else {
        return false;
    };
    let d = m.end - start;
    if !d.is_finite() {
        return false;
    }
    let axis = op
        .orient(m)
        .and_then(|o| o.axis)
        .map_or(millplan_geom::DVec3::Z, |a| a.normalize());
    let down = -d.dot(axis);
    down > 0.0 && down * down > d.length_squared() - down * down
}

/// Lowers feeds (mm/min) so that neighbouring blocks differ by no more than
/// the acceleration `accel` (mm/s²) allows over a block's length; a lowered
/// block is marked `accel` (an air block stays `air`, a kept one `kept`).
fn smooth(c: &mut [(usize, f64, f64, &'static str)], accel: f64) {
    if !(accel > 0.0 && accel.is_finite()) {
        return;
    }
    // v in mm/min, s in mm: v² may grow by 2·a·s·3600 over a block.
    let k = 2.0 * accel * 3600.0;
    let mut lowered = vec![false; c.len()];
    for j in 1..c.len() {
        let cap = (c[j - 1].2 * c[j - 1].2 + k * c[j].1).sqrt();
        if c[j].2 > cap {
            c[j].2 = cap;
            lowered[j] = true;
        }
    }
    for j in (0..c.len().saturating_sub(1)).rev() {
        let cap = (c[j + 1].2 * c[j + 1].2 + k * c[j].1).sqrt();
        if c[j].2 > cap {
            c[j].2 = cap;
            lowered[j] = true;
        }
    }
    for (e, l) in c.iter_mut().zip(lowered) {
        // Only a clear change counts as the acceleration's doing.
        if l && e.3 != "kept" && e.3 != "air" {
            e.3 = "accel";
        }
    }
}

/// Writes feed `v` (mm/min) into move `i` in its own feed mode.
fn set_feed(op: &mut Operation, i: usize, len: f64, v: f64) {
    let mv = &mut op.moves[i];
    mv.feed = match mv.feed_mode {
        FeedMode::PerMinute => v,
        FeedMode::PerRev if mv.spindle > 0.0 => v / mv.spindle,
        FeedMode::PerRev => mv.feed,
        // 1 / block time in minutes.
        FeedMode::InverseTime => v / len,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block in air runs at the tool's largest chip load, never slower
    /// than it was programmed; the machine file's air feed when it gives one.
    #[test]
    fn a_block_in_air_is_never_slowed() {
        let mut m = Machine::default();
        // A 0.375 mm tool's chip load at 1000 1/min: 15 mm/min.
        assert_eq!(air_feed(&m, 0.0075, 2.0, 1000.0, 500.0), 500.0);
        assert_eq!(air_feed(&m, 0.08, 2.0, 10000.0, 500.0), 1600.0);
        assert_eq!(air_feed(&m, 0.08, 2.0, 0.0, 500.0), 500.0);
        m.feed_air = Some(2000.0);
        assert_eq!(air_feed(&m, 0.0075, 2.0, 1000.0, 500.0), 2000.0);
    }

    #[test]
    fn a_block_over_its_power_at_the_smallest_chip_runs_slower_at_that_chip() {
        let m = Machine::default();
        let mf = MoveForces {
            rpm: 16000.0,
            fz_allowed: Some(0.01),
            binding: Some("feed-range"),
            speed_share: Some(0.8),
            ..MoveForces::default()
        };
        let (v, why, rpm) = target(&mf, &m, 2.0, 0.08);
        assert_eq!(rpm, Some(12800.0));
        assert!((v - 0.01 * 12800.0 * 2.0).abs() < 1e-9, "{v}");
        assert_eq!(why, "power-speed");
        // Never below the machine's smallest speed.
        let slow = MoveForces {
            speed_share: Some(1e-4),
            ..mf
        };
        assert_eq!(target(&slow, &m, 2.0, 0.08).2, Some(m.spindle_min));
        // Without a shortfall the speed stays.
        let ok = MoveForces {
            speed_share: None,
            ..mf
        };
        assert_eq!(target(&ok, &m, 2.0, 0.08).2, None);
    }

    #[test]
    fn smoothing_only_lowers_and_keeps_within_the_acceleration() {
        let k = 2.0 * 1000.0 * 3600.0;
        let mut c: Vec<(usize, f64, f64, &'static str)> =
            [5000.0, 500.0, 8000.0, 8000.0, 300.0, 6000.0]
                .iter()
                .enumerate()
                .map(|(i, v)| (i, 0.5, *v, "fxy"))
                .collect();
        let before: Vec<f64> = c.iter().map(|e| e.2).collect();
        smooth(&mut c, 1000.0);
        for (j, e) in c.iter().enumerate() {
            assert!(e.2 <= before[j] + 1e-9, "block {j} raised");
            if j > 0 {
                let (a, b) = (c[j - 1].2, e.2);
                assert!(
                    b * b <= a * a + k * e.1 + 1e-6,
                    "accelerates too fast into {j}"
                );
                assert!(
                    a * a <= b * b + k * c[j - 1].1 + 1e-6,
                    "decelerates too late into {j}"
                );
            }
        }
        assert_eq!(c[1].2, 500.0, "the slow block stays");
        assert_eq!(c[0].3, "accel", "the block before the slow one slows down");
        assert_eq!(c[1].3, "fxy");
    }
}
