//! The checks of a written program against its input, before it is renamed
//! into place: what a shop must be able to bet a machine on.
//!
//! [`check`] runs every check the [`Inputs`] allow and returns one [`Check`]
//! each, in a fixed order:
//!
//! | check | refuses | needs |
//! |---|---|---|
//! | `ir` | a broken IR invariant ([`millplan_nc::verify`]) in the output; an input without an end of program (`Program::unterminated`) | — |
//! | `machine` | an S outside the machine's spindle range; a cutting feed ≤ 0 or above its maximum | a machine |
//! | `tip` | a tool tip away from where the input put it (per [`TipRule`]) | — |
//! | `stock` | a rapid through material, the shank or holder in material, on the initial stock — also when the input did it (marked `in_input`) | a stock |
//! | `gouge` | a gouge into the part — also when the input had it (marked `in_input`) deeper than [`Tolerances::input_gouge`]; a part the tool stands by in less than half of the cutting moves | a part |
//! | `loads` | a per-move peak load over its limit by more than [`Tolerances::load`] | a [`LoadCheck`] |
//!
//! A check whose inputs are missing says so (`skipped`) and passes; every
//! check says how much it looked at (`checked`, in `unit`). A finding names
//! the output's source line; a finding the input already had carries
//! `in_input`. Collisions on the stock and gouges are refused whether or
//! not the input had them: a program that cuts into the part or drives
//! through material is not safe to run because its source was not either.
//! Only a gouge of the input's no deeper than [`Tolerances::input_gouge`]
//! (the part's tessellation error) is reported without refusing
//! ([`Finding::refuses`]).
//! A collision is the input's where an input move with the same ends or the
//! same source line had it; a gouge where its deepest point lies on the
//! input's path. [`Check::fails_anew`] tells a check that refuses for a
//! fault of the passes' own from one that refuses only what the input did.
//!
//! The read-back of the written bytes ([`millplan_nc::readback`]) is the
//! check that ties the bytes to the IR these checks run on;
//! [`read_back_check`] reports it in the same form.

use crate::machine::Machine;
use millplan_geom::DVec3;
use millplan_models::cutter::Shape;
use millplan_models::kinematics::{Joints, Kinematics};
use millplan_nc::readback::ReadBack;
use millplan_nc::{known, EventKind, FeedMode, MoveKind, Operation, Program};
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{self, GougeParams, GougeReport};
use millplan_sim::stock::path::{strokes, PathOptions};
use millplan_sim::stock::run::{run as run_sim, Collision};
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::Stock;

/// Where the output's tool tips must be.
#[derive(Clone, Copy, Debug)]
pub enum TipRule<'a> {
    /// Move by move where the input put it (same operations, same moves, each
    /// end within [`Tolerances::tip`]; tool axes too where both give one):
    /// `speed`, `feed`, `convert`.
    Kept,
    /// Every cutting point of the input is a cutting point of the output, in
    /// any order (`reorder`: the links between them may change).
    SamePoints,
    /// The pass wrote machine positions (`post`): the tip of every output
    /// cutting move, through the machine's forward kinematics (or as written
    /// where the operation runs under TCP), lies on the input move of the
    /// same source line within the tolerance, and the last output move of a
    /// source line ends at that input move's end.
    MovedBy(&'a Kinematics),
    /// The ball centre stays where the input put it and the tool axis may
    /// turn (`orient`): for ball-end operations (by [`Inputs::tool_body`])
    /// tip + R·axis is compared move by move, other operations as `Kept`.
    CentreKept,
    /// Nothing can be checked against the input (`raster` has no input
    /// program).
    Free,
}

/// Tolerances of the checks, mm unless said.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Tolerances {
    /// How far an output tip may be from the input's.
    pub tip: f64,
    /// Material deeper than this met by a rapid, shank or holder is a collision.
    pub collision: f64,
    /// A tip lower than the drop-cutter height by more than this is a gouge.
    pub gouge: f64,
    /// A gouge the input already had refuses when deeper than this: a part's
    /// tessellation stands off the surface its program was cut on by its
    /// chord error (0.01–0.05 mm as CAM systems export), which is reported,
    /// not refused; deeper, the part or the program is wrong.
    pub input_gouge: f64,
    /// Sampling step of the gouge check along each move.
    pub gouge_step: f64,
    /// Relative: a load may exceed its limit by this share (the resolution
    /// of the force models, issue 30: 0.5 %).
    pub load: f64,
    /// Relative: an F may exceed the machine's maximum by this share (the
    /// written decimals).
    pub feed: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            tip: 0.001,
            collision: 0.01,
            gouge: 0.005,
            input_gouge: 0.05,
            gouge_step: 0.1,
            load: 0.005,
            feed: 1e-6,
        }
    }
}

/// One peak load of one output move: what the feed engineer's model says.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Load {
    /// Operation and move index of the output program.
    pub op: usize,
    #[serde(rename = "move")]
    pub mv: usize,
    /// What is limited (`fxy`, `torque`, `power`, `deflection`, ...).
    pub name: String,
    /// The move's peak value and its limit, in the same unit.
    pub value: f64,
    pub limit: f64,
}

/// Per-move peak loads of a program under the caller's force model: the
/// check compares them with their limits without knowing the model.
pub trait LoadCheck: Sync {
    /// Every (move, limited quantity) the model evaluated on `output`.
    fn loads(&self, output: &Program) -> Vec<Load>;
}

impl<F: Fn(&Program) -> Vec<Load> + Sync> LoadCheck for F {
    fn loads(&self, output: &Program) -> Vec<Load> {
        self(output)
    }
}

/// What the checks compare: the output against its input, on the machine,
/// the stock and the part.
#[derive(Clone, Copy)]
pub struct Inputs<'a> {
    /// The program the pass read.
    pub input: &'a Program,
    /// The program written (the IR the bytes were written from; the
    /// read-back ties the bytes to it). Its source lines name findings.
    pub output: &'a Program,
    /// The part's drop-cutter mesh (gouge check); `None` skips it.
    pub part: Option<&'a DropMesh>,
    /// The initial stock (collision check); `None` skips it. Cloned, not changed.
    pub stock: Option<&'a Stock>,
    /// The tool body of an operation: cutter, flutes, shank, holder (`None`
    /// leaves the operation out of the stock and gouge checks, counted).
    pub tool_body: &'a (dyn Fn(&Operation) -> Option<ToolBody> + Sync),
    /// The machine: spindle range, maximum feed, rapid rate; `None` skips
    /// the `machine` check (and simulates rapids at the default rate).
    pub machine: Option<&'a Machine>,
    pub tip: TipRule<'a>,
    pub tol: Tolerances,
    /// The output's per-move peak loads; `None` skips the `loads` check.
    pub loads: Option<&'a dyn LoadCheck>,
}

/// One finding of a check.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Finding {
    /// Source line of the output's move (`None`: the program as a whole, or
    /// a generated move).
    pub line: Option<u32>,
    pub message: String,
    /// The input has the same fault at the same move.
    pub in_input: bool,
    /// The finding refuses the output. All do but a gouge the input already
    /// had no deeper than [`Tolerances::input_gouge`]: the error of a part's
    /// tessellation against the surface the CAM system cut, reported only.
    pub refuses: bool,
}

/// The outcome of one check.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Check {
    /// `ir`, `machine`, `tip`, `stock`, `gouge`, `loads` or `read-back`.
    pub name: &'static str,
    /// No finding refuses the output.
    pub ok: bool,
    /// How much was checked, in `unit`.
    pub checked: usize,
    /// `moves`, `samples`, `strokes`, `loads`, `steps`.
    pub unit: &'static str,
    /// What was left out and why (`None`: nothing).
    pub skipped: Option<String>,
    pub findings: Vec<Finding>,
}

impl Check {
    fn new(name: &'static str, unit: &'static str) -> Check {
        Check {
            name,
            ok: true,
            checked: 0,
            unit,
            skipped: None,
            findings: Vec::new(),
        }
    }

    fn skip(name: &'static str, unit: &'static str, why: &str) -> Check {
        Check {
            skipped: Some(why.to_string()),
            ..Check::new(name, unit)
        }
    }

    /// The findings that refuse the output: none of a check that passed,
    /// all of one that failed.
    pub fn refusing(&self) -> impl Iterator<Item = &Finding> {
        let all = if self.ok { &[][..] } else { &self.findings[..] };
        all.iter().filter(|f| f.refuses)
    }

    /// Whether the check failed for a fault the input did not have (a
    /// failed check without findings counts as one).
    pub fn fails_anew(&self) -> bool {
        !self.ok && (self.findings.is_empty() || self.refusing().any(|f| !f.in_input))
    }

    /// The finding that refuses the output: the first that the input did
    /// not have, else the first.
    pub fn refusal(&self) -> Option<&Finding> {
        (self.refusing().find(|f| !f.in_input)).or_else(|| self.refusing().next())
    }
}

/// Runs every check the inputs allow (see the module docs), in the order
/// `ir`, `machine`, `tip`, `stock`, `gouge`, `loads`.
pub fn check(inputs: &Inputs) -> Vec<Check> {
    check_with_gouges(inputs).0
}

/// [`check`], and the gouge check's report of the output when a part was
/// given (for a command that prints its own gouge summary).
pub fn check_with_gouges(inputs: &Inputs) -> (Vec<Check>, Option<GougeReport>) {
    let (gouge, report) = match inputs.part {
        Some(p) => {
            let (c, r) = gouges_with_report(inputs, p);
            (c, Some(r))
        }
        None => (Check::skip("gouge", "samples", "no part given"), None),
    };
    let checks = vec![
        ir_with_end(inputs),
        machine_check(inputs),
        tip(inputs),
        match inputs.stock {
            Some(s) => stock(inputs, s),
            None => Check::skip("stock", "strokes", "no stock given"),
        },
        gouge,
        loads_check(inputs),
    ];
    (checks, report)
}

/// [`check`] for a pass that changes speeds and feeds only (`speed`, under
/// [`TipRule::Kept`]): where the tip check finds every position kept, the
/// program cuts what the input cut where the input cut it, and the stock
/// and gouge checks are not run again (skipped, saying so); otherwise all
/// of [`check`].
pub fn check_feeds_only(inputs: &Inputs) -> Vec<Check> {
    let t = tip(inputs);
    if !t.ok || !matches!(inputs.tip, TipRule::Kept) {
        return check(inputs);
    }
    let why =
        "positions kept (tip check): what the input cut, where it cut it; not simulated again";
    vec![
        ir_with_end(inputs),
        machine_check(inputs),
        t,
        Check::skip("stock", "strokes", why),
        Check::skip("gouge", "samples", why),
        loads_check(inputs),
    ]
}

fn machine_check(i: &Inputs) -> Check {
    match i.machine {
        Some(m) => machine(i.output, m, &i.tol),
        None => Check::skip("machine", "moves", "no machine given"),
    }
}

fn loads_check(i: &Inputs) -> Check {
    match i.loads {
        Some(l) => loads(i.output, l, i.tol.load),
        None => Check::skip("loads", "loads", "no load model given"),
    }
}

/// Whether no check refuses.
pub fn passed(checks: &[Check]) -> bool {
    checks.iter().all(|c| c.ok)
}

/// The refusing finding of the first check that failed for a fault the
/// input did not have, else of the first failed check.
pub fn first_refusal(checks: &[Check]) -> Option<(&Check, &Finding)> {
    fn of(c: &Check) -> Option<(&Check, &Finding)> {
        c.refusal().map(|f| (c, f))
    }
    (checks.iter().filter(|c| c.fails_anew()).find_map(of)).or_else(|| checks.iter().find_map(of))
}

fn line_of(l: u32) -> Option<u32> {
    (l > 0).then_some(l)
}

/// The read-back of the written bytes as a check: refused when the bytes
/// command something other than the program written.
pub fn read_back_check(r: &ReadBack) -> Check {
    let mut c = Check::new("read-back", "steps");
    match &r.equiv {
        Ok(w) => c.checked = w.steps + w.intermediate,
        Err(m) => {
            c.ok = false;
            c.findings.push(Finding {
                line: line_of(m.line_b),
                message: format!(
                    "the written program does not command what was written (line {} of the program written: {})",
                    m.line_a, m.message
                ),
                in_input: false,
                refuses: true,
            });
        }
    }
    c
}

/// The IR verifier on the output, and the input's end: a program read
/// without an end of program may have been cut short in its transfer, and
/// a pass's output, ended by its writer, would make it look whole (a user
/// trial: the first half of a finishing program written as Green, the
/// spindle stopped with the ball on the surface). Refused as the input's
/// own, at its last block.
fn ir_with_end(i: &Inputs) -> Check {
    let mut c = ir(i.output);
    if let Some(last) = i.input.unterminated {
        c.ok = false;
        c.findings.push(Finding {
            line: line_of(last),
            message: "the program has no end of program (M30, END PGM, FINI): it may have been cut short after this block, and the output, ended by its writer, would look whole".into(),
            in_input: true,
            refuses: true,
        });
    }
    c
}

/// The IR verifier on `p`.
pub fn ir(p: &Program) -> Check {
    let mut c = Check::new("ir", "moves");
    c.checked = p.move_count();
    if let Err(v) = millplan_nc::verify::verify(p) {
        c.ok = false;
        for v in v {
            let line =
                v.mv.and_then(|m| p.operations.get(v.op)?.moves.get(m))
                    .and_then(|m| line_of(m.line));
            c.findings.push(Finding {
                line,
                message: format!("IR invariant {:?} broken: {v}", v.rule),
                in_input: false,
                refuses: true,
            });
        }
    }
    c
}

/// Every S > 0 within the machine's spindle range; every cutting feed > 0
/// and, as a tip speed (per minute, or per revolution times S), at most the
/// machine's maximum feed. Inverse-time feeds are checked for F > 0 only
/// (their tip speed depends on the axes' motion). S = 0 (not given, as in a
/// CL file without SPINDL) is left to the passes that need it.
pub fn machine(p: &Program, m: &Machine, tol: &Tolerances) -> Check {
    let mut c = Check::new("machine", "moves");
    let max_f = m.feed_max * (1.0 + tol.feed);
    let (lo, hi) = (m.spindle_min - 0.5, m.spindle_max + 0.5);
    for op in &p.operations {
        for mv in &op.moves {
            c.checked += 1;
            let mut bad = |message: String| {
                c.findings.push(Finding {
                    line: line_of(mv.line),
                    message,
                    in_input: false,
                    refuses: true,
                })
            };
            if mv.spindle > 0.0 && !(lo..=hi).contains(&mv.spindle) {
                bad(format!(
                    "S{} outside the machine's spindle range {}..{} 1/min",
                    mv.spindle, m.spindle_min, m.spindle_max
                ));
            }
            if mv.kind == MoveKind::Rapid {
                continue;
            }
            let feed = match op.cycle(mv) {
                Some(cy) => cy.feed,
                None => mv.feed,
            };
            if !(feed > 0.0) {
                bad(format!("cutting feed F{feed} is not positive"));
                continue;
            }
            // A block that also turns a rotary axis: its F is the feed of
            // the axes together (degrees counted as mm) unless the control
            // runs TCP, not the tip's; the post bounds each axis's speed and
            // the tip's feed itself (`post::post`), so it is not read here.
            let rotary = op
                .orient(mv)
                .is_some_and(|o| o.angles.iter().any(Option::is_some));
            let tip = match mv.feed_mode {
                FeedMode::PerMinute if rotary => None,
                FeedMode::PerMinute => Some(feed),
                FeedMode::PerRev => (mv.spindle > 0.0).then_some(feed * mv.spindle),
                FeedMode::InverseTime => None,
            };
            if let Some(f) = tip.filter(|f| *f > max_f) {
                bad(format!(
                    "cutting feed {f} mm/min above the machine's maximum {} mm/min",
                    m.feed_max
                ));
            }
        }
    }
    c.ok = c.findings.is_empty();
    c
}

/// The tip of an operation's move in part coordinates.
fn part_point(op: &Operation, v: DVec3) -> DVec3 {
    op.frame.map_or(v, |f| f.to_parent(v))
}

/// Tool tips against the input under [`Inputs::tip`], within [`Tolerances::tip`].
pub fn tip(i: &Inputs) -> Check {
    let tol = i.tol.tip;
    match i.tip {
        TipRule::Kept => tip_kept(i.input, i.output, tol, &|_| None),
        TipRule::CentreKept => {
            let ball = |op: &Operation| match (i.tool_body)(op)?.shape {
                Shape::Ball { radius } => Some(radius),
                _ => None,
            };
            tip_kept(i.input, i.output, tol, &ball)
        }
        TipRule::SamePoints => tip_same_points(i.input, i.output, tol),
        TipRule::MovedBy(k) => tip_moved_by(i.input, i.output, k, tol),
        TipRule::Free => Check::skip("tip", "moves", "no input program to compare with"),
    }
}

/// Move by move; where `ball` gives an operation's ball radius, the ball
/// centres are compared instead of the tips and the axis may turn.
fn tip_kept(
    input: &Program,
    output: &Program,
    tol: f64,
    ball: &dyn Fn(&Operation) -> Option<f64>,
) -> Check {
    let mut c = Check::new("tip", "moves");
    let finding = |line: u32, message: String| Finding {
        line: line_of(line),
        message,
        in_input: false,
        refuses: true,
    };
    if input.operations.len() != output.operations.len() {
        c.ok = false;
        c.findings.push(finding(
            0,
            format!(
                "{} operations written where the input has {}",
                output.operations.len(),
                input.operations.len()
            ),
        ));
        return c;
    }
    let mut unknown_axis = 0;
    for (oi, (a, b)) in input.operations.iter().zip(&output.operations).enumerate() {
        let r = ball(b);
        if a.moves.len() != b.moves.len() && r.is_none() {
            // Written in other moves (a repeated point left out, a canned
            // cycle spelled out as lines, an arc as chords): the tips step
            // through the same path, whatever the feeds and speeds.
            let paths = millplan_nc::equiv::Tolerance::paths_only(tol);
            let (a, b) = (std::slice::from_ref(a), std::slice::from_ref(b));
            match millplan_nc::equiv::compare_operations(a, b, &paths) {
                Ok(w) => c.checked += w.steps,
                Err(m) => {
                    let line = if m.line_a > 0 { m.line_a } else { m.line_b };
                    let msg = format!("operation {}: {}", oi + 1, m.message);
                    c.findings.push(finding(line, msg));
                }
            }
            continue;
        }
        if a.moves.len() != b.moves.len() {
            let line = b.moves.first().map_or(0, |m| m.line);
            c.findings.push(finding(
                line,
                format!(
                    "operation {}: {} moves written where the input has {}",
                    oi + 1,
                    b.moves.len(),
                    a.moves.len()
                ),
            ));
            continue;
        }
        for (ma, mb) in a.moves.iter().zip(&b.moves) {
            let differs = match r {
                None => tip_differs(a, ma, b, mb, tol),
                Some(r) => match (centre(a, ma, r), centre(b, mb, r)) {
                    (Some(ca), Some(cb)) => centre_differs(ca, cb, tol),
                    _ => {
                        unknown_axis += 1;
                        continue;
                    }
                },
            };
            c.checked += 1;
            if let Some(m) = differs {
                c.findings.push(finding(mb.line, m));
            }
        }
    }
    if unknown_axis > 0 {
        c.skipped = Some(format!(
            "{unknown_axis} moves with the tool axis known only as machine angles"
        ));
    }
    c.ok = c.findings.is_empty();
    c
}

/// The tool axis of a move in part coordinates: +Z without an orientation,
/// `None` when only machine angles say where it points.
fn axis_part(op: &Operation, m: &millplan_nc::Move) -> Option<DVec3> {
    op.axis_in_part(m)
}

/// The ball centre of a move of a ball of radius `r`, part coordinates.
fn centre(op: &Operation, m: &millplan_nc::Move, r: f64) -> Option<DVec3> {
    Some(part_point(op, m.end) + axis_part(op, m)? * r)
}

fn centre_differs(a: DVec3, b: DVec3, tol: f64) -> Option<String> {
    let d = (a - b).length();
    if (0..3).any(|k| a[k].is_nan() != b[k].is_nan()) {
        return Some(
            "the ball centre is known where the input's is not, or not where it is".into(),
        );
    }
    let d = if d.is_nan() {
        (0..3)
            .filter(|&k| !a[k].is_nan())
            .map(|k| (a[k] - b[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    } else {
        d
    };
    (d > tol).then(|| {
        format!(
            "the ball centre ends {d:.4} mm from where the input put it ({:.4}, {:.4}, {:.4})",
            a.x, a.y, a.z
        )
    })
}

/// Why move `mb` of `b` is not where move `ma` of `a` was.
fn tip_differs(
    a: &Operation,
    ma: &millplan_nc::Move,
    b: &Operation,
    mb: &millplan_nc::Move,
    tol: f64,
) -> Option<String> {
    let (pa, pb) = (part_point(a, ma.end), part_point(b, mb.end));
    for k in 0..3 {
        if pa[k].is_nan() != pb[k].is_nan() {
            return Some(format!(
                "axis {} is {} where the input's is {}",
                ["X", "Y", "Z"][k],
                if pb[k].is_nan() { "unknown" } else { "set" },
                if pa[k].is_nan() { "unknown" } else { "set" }
            ));
        }
    }
    let d = (0..3)
        .filter(|&k| !pa[k].is_nan())
        .map(|k| (pa[k] - pb[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    if d > tol {
        return Some(format!(
            "the tip ends {d:.4} mm from where the input put it ({:.4}, {:.4}, {:.4})",
            pa.x, pa.y, pa.z
        ));
    }
    if let (Some(ka), Some(kb)) = (axis_part(a, ma), axis_part(b, mb)) {
        let dev = (ka - kb).length();
        if dev > 1e-6 {
            return Some(format!(
                "the tool axis turned by {:.4}° from the input's",
                2.0 * (dev / 2.0).min(1.0).asin().to_degrees()
            ));
        }
    }
    None
}

/// The known ends of the cutting moves of `p`, part coordinates, with
/// lines; a canned cycle's hole by the ends of its feed strokes (its pecks
/// and its bottom, as [`cycle_moves`] spells it out: the points a program
/// that writes the cycle as lines cuts to).
fn cutting_points(p: &Program) -> Vec<(DVec3, u32)> {
    use millplan_nc::write::{cycle_moves, CycleStep};
    let mut v = Vec::new();
    for op in &p.operations {
        for m in &op.moves {
            if m.kind == MoveKind::Rapid {
                continue;
            }
            let Some(end) = known(m.end) else { continue };
            let steps = op
                .cycle(m)
                .and_then(|c| cycle_moves(c, end, op.axis(m).unwrap_or(DVec3::Z)).ok());
            match steps {
                Some(steps) => v.extend(steps.into_iter().filter_map(|s| match s {
                    CycleStep::Feed(q, _) => Some((part_point(op, q), m.line)),
                    _ => None,
                })),
                None => v.push((part_point(op, end), m.line)),
            }
        }
    }
    v
}

fn tip_same_points(input: &Program, output: &Program, tol: f64) -> Check {
    let mut c = Check::new("tip", "moves");
    let cell = tol.max(1e-9) * 2.0;
    let key = |p: DVec3| [p.x, p.y, p.z].map(|v| (v / cell).floor() as i64);
    let mut grid: rustc_hash::FxHashMap<[i64; 3], Vec<DVec3>> = Default::default();
    for (p, _) in cutting_points(output) {
        grid.entry(key(p)).or_default().push(p);
    }
    let near = |p: DVec3| {
        let k = key(p);
        (-1..=1).any(|dx| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dz| {
                    grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz])
                        .is_some_and(|v| v.iter().any(|q| (*q - p).length() <= tol))
                })
            })
        })
    };
    for (p, line) in cutting_points(input) {
        c.checked += 1;
        if !near(p) {
            c.findings.push(Finding {
                line: None,
                message: format!(
                    "the input's cutting point of line {line} ({:.4}, {:.4}, {:.4}) is not cut by the output",
                    p.x, p.y, p.z
                ),
                in_input: false,
                refuses: true,
            });
        }
    }
    c.ok = c.findings.is_empty();
    c
}

/// The index (0 A, 1 B, 2 C) of a rotary axis letter.
fn letter_index(c: char) -> usize {
    match c {
        'A' => 0,
        'B' => 1,
        _ => 2,
    }
}

/// The tool tip of an output move in the workpiece frame: as written under
/// TCP, else through the forward kinematics of its joints.
fn posted_tip(op: &Operation, m: &millplan_nc::Move, k: &Kinematics, tcp: bool) -> Option<DVec3> {
    let end = known(m.end)?;
    if tcp {
        return Some(part_point(op, end));
    }
    Some(k.tip(&posted_joints(op, m, k)?))
}

/// The machine position a posted move ends at (no TCP).
fn posted_joints(op: &Operation, m: &millplan_nc::Move, k: &Kinematics) -> Option<Joints> {
    let end = known(m.end)?;
    let [f, s] = k.kind.rotary_names().map(letter_index);
    let angles = op.orient(m).map_or([None; 3], |o| o.angles);
    Some(Joints {
        xyz: end,
        first: angles[f].unwrap_or(0.0).to_degrees(),
        second: angles[s].unwrap_or(0.0).to_degrees(),
    })
}

/// How far the tip strays, inside the block from the machine position `a`
/// to that of `m`, from the input's moves `sg` of its line: the axes move
/// in straight lines, the tip is sampled where the post samples it
/// ([`crate::post::feed::tip_samples`]); 0 when the rotaries do not turn.
fn inner_deviation(
    op: &Operation,
    a: &Joints,
    m: &millplan_nc::Move,
    k: &Kinematics,
    sg: &[(DVec3, DVec3)],
) -> f64 {
    let Some(b) = posted_joints(op, m, k) else {
        return 0.0;
    };
    crate::post::feed::tip_samples(k, a, &b).map_or(0.0, |v| {
        v.iter()
            .map(|&t| line_distance(t, sg, false))
            .fold(0.0, f64::max)
    })
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

/// The input's cutting moves by source line: (start, end) in part
/// coordinates, in order (a spline span read from one line makes several),
/// flat and sorted by line (a map of a list per line took some 240 bytes a
/// move: a million-point CL file's check held 235 MB).
struct Segments {
    lines: Vec<u32>,
    segs: Vec<(DVec3, DVec3)>,
}

impl Segments {
    /// The segments of source line `line`, in order (none: empty).
    fn of_line(&self, line: u32) -> &[(DVec3, DVec3)] {
        let a = self.lines.partition_point(|&l| l < line);
        let n = self.lines[a..].partition_point(|&l| l == line);
        &self.segs[a..a + n]
    }
}

/// `tol`: arcs are cut into chords within a quarter of it.
fn input_segments(input: &Program, tol: f64) -> Segments {
    let (mut lines, mut segs) = (Vec::new(), Vec::new());
    for op in &input.operations {
        for (i, m) in op.moves.iter().enumerate() {
            if m.kind == MoveKind::Rapid || m.line == 0 {
                continue;
            }
            move_segments(op, i, tol, &mut |a, b| {
                lines.push(m.line);
                segs.push((a, b));
            });
        }
    }
    if !lines.is_sorted() {
        // Lines out of order (a program built in another order than its
        // source's): sorted, each line's segments kept in their order.
        let mut order: Vec<u32> = (0..lines.len() as u32).collect();
        order.sort_by_key(|&k| lines[k as usize]);
        segs = order.iter().map(|&k| segs[k as usize]).collect();
        lines = order.iter().map(|&k| lines[k as usize]).collect();
    }
    Segments { lines, segs }
}

/// The straight pieces of move `i` of `op` in part coordinates (an arc as
/// chords within `tol`/4); nothing for a move from or to an unknown
/// position or a canned cycle.
fn move_segments(op: &Operation, i: usize, tol: f64, out: &mut dyn FnMut(DVec3, DVec3)) {
    let m = &op.moves[i];
    let (Some(s), Some(e)) = (op.known_start(i), known(m.end)) else {
        return;
    };
    if m.cycle().is_some() {
        return;
    }
    match op.arc(m) {
        Some(a) => {
            let sag = (tol / 4.0).min(a.radius);
            let step = 2.0 * (1.0 - sag / a.radius).acos();
            let n = ((a.sweep / step.max(1e-6)).ceil() as usize).clamp(1, 4096);
            let mut p0 = s;
            for k in 1..=n {
                let p1 = a.point_at(s, e, k as f64 / n as f64);
                out(part_point(op, p0), part_point(op, p1));
                p0 = p1;
            }
        }
        None => out(part_point(op, s), part_point(op, e)),
    }
}

/// A program's path (every move with known ends, arcs as chords) in a
/// uniform grid of points sampled along it: was the tool ever here?
struct PathIndex {
    cell: f64,
    segs: Vec<(DVec3, DVec3)>,
    grid: rustc_hash::FxHashMap<[i64; 3], Vec<u32>>,
}

impl PathIndex {
    /// Near within `tol` (cells of at least 4·`tol`, at most some four
    /// million samples).
    /// A canned cycle's hole counts from its highest plane down to its
    /// bottom along the tool axis: the tool went there.
    fn new(p: &Program, tol: f64) -> PathIndex {
        let mut segs = Vec::new();
        for op in &p.operations {
            for (i, m) in op.moves.iter().enumerate() {
                move_segments(op, i, tol, &mut |a, b| segs.push((a, b)));
                if let (Some(c), Some(at)) = (op.cycle(m), known(m.end)) {
                    let axis = op.axis(m).unwrap_or(DVec3::Z);
                    let top = at + axis * c.retract.max(c.clearance).max(c.bottom);
                    segs.push((part_point(op, top), part_point(op, at + axis * c.bottom)));
                }
            }
        }
        Self::of(segs, tol)
    }

    /// The rapids of a program: its rapid moves, and its canned cycles'
    /// rapid steps as [`cycle_moves`] spells them out (from the hole's
    /// highest plane down to its feed plane, out of each peck).
    fn rapids(p: &Program, tol: f64) -> PathIndex {
        use millplan_nc::write::{cycle_moves, CycleStep};
        let mut segs = Vec::new();
        for op in &p.operations {
            for (i, m) in op.moves.iter().enumerate() {
                if m.kind == MoveKind::Rapid {
                    move_segments(op, i, tol, &mut |a, b| segs.push((a, b)));
                }
                let (Some(c), Some(at)) = (op.cycle(m), known(m.end)) else {
                    continue;
                };
                let axis = op.axis(m).unwrap_or(DVec3::Z);
                let mut last = at + axis * c.retract.max(c.clearance).max(c.bottom);
                // Up to the cycle's level if below it, across to the hole,
                // as the writers, the stock simulation and the time
                // estimate move it.
                if let Some(mut from) = op.known_start(i) {
                    if from.z < last.z {
                        let up = DVec3::new(from.x, from.y, last.z);
                        segs.push((part_point(op, from), part_point(op, up)));
                        from = up;
                    }
                    let across = DVec3::new(at.x, at.y, from.z);
                    segs.push((part_point(op, from), part_point(op, across)));
                    segs.push((part_point(op, across), part_point(op, last)));
                }
                for step in cycle_moves(c, at, axis).unwrap_or_default() {
                    match step {
                        CycleStep::Rapid(q) => {
                            segs.push((part_point(op, last), part_point(op, q)));
                            last = q;
                        }
                        CycleStep::Feed(q, _) => last = q,
                        CycleStep::Dwell(_) => {}
                    }
                }
            }
        }
        Self::of(segs, tol)
    }

    /// The path of the ball centres of a program's ball-end moves (each
    /// move from the previous move's centre to its own, arcs as their
    /// chords), under the tool bodies of `i`.
    fn centres(p: &Program, i: &Inputs, tol: f64) -> PathIndex {
        let mut segs = Vec::new();
        for op in &p.operations {
            let Some(r) = (i.tool_body)(op).and_then(|b| match b.shape {
                Shape::Ball { radius } => Some(radius),
                _ => None,
            }) else {
                continue;
            };
            let mut last = None;
            for m in &op.moves {
                let c = known(m.end).and_then(|_| centre(op, m, r));
                if let (Some(a), Some(b)) = (last, c) {
                    segs.push((a, b));
                }
                last = c;
            }
        }
        Self::of(segs, tol)
    }

    /// The index of the segments `segs`.
    fn of(segs: Vec<(DVec3, DVec3)>, tol: f64) -> PathIndex {
        let total: f64 = segs.iter().map(|(a, b)| (*b - *a).length()).sum();
        let cell = (total / 2e6).max(4.0 * tol).max(0.5);
        let mut grid: rustc_hash::FxHashMap<[i64; 3], Vec<u32>> = Default::default();
        for (k, (a, b)) in segs.iter().enumerate() {
            let n = ((*b - *a).length() / (cell / 2.0)).ceil() as usize;
            let mut last = None;
            for j in 0..=n {
                let key = Self::key(cell, a.lerp(*b, j as f64 / n.max(1) as f64));
                if last != Some(key) {
                    grid.entry(key).or_default().push(k as u32);
                    last = Some(key);
                }
            }
        }
        PathIndex { cell, segs, grid }
    }

    fn key(cell: f64, p: DVec3) -> [i64; 3] {
        [p.x, p.y, p.z].map(|v| (v / cell).floor() as i64)
    }

    /// Whether some segment passes within `tol` of `q`.
    fn near(&self, q: DVec3, tol: f64) -> bool {
        let k = Self::key(self.cell, q);
        (-1..=1).any(|dx| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dz| {
                    self.grid
                        .get(&[k[0] + dx, k[1] + dy, k[2] + dz])
                        .is_some_and(|v| {
                            v.iter().any(|&i| {
                                let (a, b) = self.segs[i as usize];
                                segment_distance(q, a, b) <= tol
                            })
                        })
                })
            })
        })
    }
}

/// How far `t` is from the input's moves of one line: from their last end
/// when `last`, else from the nearest of them.
fn line_distance(t: DVec3, segs: &[(DVec3, DVec3)], last: bool) -> f64 {
    if last {
        return segs
            .last()
            .map_or(f64::INFINITY, |(_, e)| (t - *e).length());
    }
    segs.iter()
        .map(|(s, e)| segment_distance(t, *s, *e))
        .fold(f64::INFINITY, f64::min)
}

fn tip_moved_by(input: &Program, output: &Program, k: &Kinematics, tol: f64) -> Check {
    let mut c = Check::new("tip", "moves");
    let segs = input_segments(input, tol);
    let mut unmatched = 0usize;
    for op in &output.operations {
        let tcp = op.events.iter().any(|e| e.kind == EventKind::Tcp(true));
        // Without TCP the control moves the axes in straight lines: the tip
        // between a block's ends must stay on the input's move too (a
        // branch change inside a cut keeps both ends on it). Seven
        // kinematics a block, so the blocks are shared over the threads.
        let inner: Vec<f64> = if tcp {
            Vec::new()
        } else {
            use rayon::prelude::*;
            (0..op.moves.len())
                .into_par_iter()
                .map(|i| {
                    let m = &op.moves[i];
                    let sg = segs.of_line(m.line);
                    let from = i
                        .checked_sub(1)
                        .and_then(|p| posted_joints(op, &op.moves[p], k));
                    match from {
                        Some(a) if m.kind != MoveKind::Rapid && !sg.is_empty() => {
                            inner_deviation(op, &a, m, k, sg)
                        }
                        _ => 0.0,
                    }
                })
                .collect()
        };
        for (i, m) in op.moves.iter().enumerate() {
            if m.kind == MoveKind::Rapid {
                continue;
            }
            // A line whose input moves have no known ends (the first move
            // from an unknown position) has nothing to compare with.
            let sg = Some(segs.of_line(m.line)).filter(|s| !s.is_empty());
            let (Some(sg), Some(t)) = (sg, posted_tip(op, m, k, tcp)) else {
                unmatched += 1;
                continue;
            };
            c.checked += 1;
            let inner = inner.get(i).copied().unwrap_or(0.0);
            if inner > tol {
                c.findings.push(Finding {
                    line: line_of(m.line),
                    message: format!(
                        "the tip inside the block, by forward kinematics with the axes moving in straight lines, is {inner:.4} mm from the input's move (tolerance {tol} mm)"
                    ),
                    in_input: false,
                    refuses: true,
                });
                continue;
            }
            let last = op.moves.get(i + 1).is_none_or(|n| n.line != m.line);
            let d = line_distance(t, sg, last);
            if d > tol {
                c.findings.push(Finding {
                    line: line_of(m.line),
                    message: format!(
                        "the tip by forward kinematics is {d:.4} mm from the input's {} (tolerance {tol} mm)",
                        if last { "point" } else { "move" }
                    ),
                    in_input: false,
                    refuses: true,
                });
            }
        }
    }
    if unmatched > 0 {
        c.skipped = Some(format!(
            "{unmatched} cutting moves with no input cutting move of their line or an unknown position"
        ));
    }
    c.ok = c.findings.is_empty();
    c
}

/// Global move index → (operation, move) of `p`.
fn move_index(p: &Program) -> Vec<(u32, u32)> {
    let mut v = Vec::with_capacity(p.move_count());
    for (oi, op) in p.operations.iter().enumerate() {
        v.extend((0..op.moves.len()).map(|i| (oi as u32, i as u32)));
    }
    v
}

/// The (start, end) of a move in part coordinates, unknown axes as NaN.
fn move_ends(p: &Program, at: (u32, u32)) -> (DVec3, DVec3) {
    let op = &p.operations[at.0 as usize];
    let i = at.1 as usize;
    (
        part_point(op, op.move_start(i)),
        part_point(op, op.moves[i].end),
    )
}

/// Whether the straight move `(a, b)` runs along `index` within `tol` all
/// the way (sampled every millimetre, ends included).
fn along(index: &PathIndex, (a, b): (DVec3, DVec3), tol: f64) -> bool {
    if !(a.is_finite() && b.is_finite()) {
        return false;
    }
    let n = ((b - a).length().ceil() as usize).clamp(1, 100_000);
    (0..=n).all(|k| index.near(a.lerp(b, k as f64 / n as f64), tol))
}

fn same_ends(a: (DVec3, DVec3), b: (DVec3, DVec3), tol: f64) -> bool {
    let close = |p: DVec3, q: DVec3| {
        (0..3).all(|k| (p[k].is_nan() && q[k].is_nan()) || (p[k] - q[k]).abs() <= tol)
    };
    close(a.0, b.0) && close(a.1, b.1)
}

/// The rapid and holder collisions of `p` on a copy of `stock`.
fn collisions(i: &Inputs, p: &Program, stock: &Stock) -> Simulated {
    let rapid = i.machine.map_or(Machine::default().rapid, |m| m.rapid);
    let s = strokes(
        p,
        |op| (i.tool_body)(op),
        &PathOptions {
            chord: stock.grid.res / 4.0,
            rapid_rate: rapid,
        },
    );
    let mut st = stock.clone();
    let rep = run_sim(&mut st, &s, i.tol.collision, &|_| {});
    let sk = s.skipped;
    let skipped = if sk.total() > 0 {
        format!(
            "{} moves not simulated: {} with no tool body, {} from or to an unknown position, {} with the axis known only as machine angles{}",
            sk.total(),
            sk.no_tool,
            sk.unknown_position,
            sk.unknown_axis,
            sk.first()
        )
    } else {
        String::new()
    };
    Simulated {
        rapid: rep.rapid_collisions,
        holder: rep.holder_collisions,
        skipped,
        strokes: s.strokes.len(),
    }
}

/// What [`collisions`] found.
struct Simulated {
    rapid: Vec<Collision>,
    holder: Vec<Collision>,
    /// Why moves were not simulated (empty: none was left out).
    skipped: String,
    strokes: usize,
}

/// Rapids through material and the shank or holder in material, simulated
/// on the initial stock; the input is run the same way and a collision at a
/// move with the ends or the source line of one of the input's is marked
/// `in_input` (and still refused).
pub fn stock(i: &Inputs, stock: &Stock) -> Check {
    let mut c = Check::new("stock", "strokes");
    let out = collisions(i, i.output, stock);
    c.checked = out.strokes;
    if !out.skipped.is_empty() {
        c.skipped = Some(out.skipped.clone());
    }
    if out.rapid.is_empty() && out.holder.is_empty() {
        return c;
    }
    let old = collisions(i, i.input, stock);
    let (oi, ii) = (move_index(i.output), move_index(i.input));
    // The input's: a collision of the same kind at a move with the same
    // ends, or from the same source line (a pass that moves the tip, such
    // as `orient`, keeps the lines); a rapid's also where the whole move
    // runs along the input's own rapids (a canned cycle written as lines
    // rapids where the cycle did).
    let rapids = std::cell::OnceCell::new();
    let was = |col: &Collision, old: &[Collision], rapid: bool| {
        let e = move_ends(i.output, oi[col.mv as usize]);
        let same = old.iter().any(|o| {
            (col.line != 0 && o.line == col.line)
                || same_ends(move_ends(i.input, ii[o.mv as usize]), e, i.tol.tip)
        });
        same || (rapid && !old.is_empty() && {
            let index = rapids.get_or_init(|| PathIndex::rapids(i.input, i.tol.tip));
            along(index, e, i.tol.tip)
        })
    };
    for (list, old, what, rapid) in [
        (&out.rapid, &old.rapid, "rapid through material", true),
        (
            &out.holder,
            &old.holder,
            "shank or holder in material",
            false,
        ),
    ] {
        for col in list {
            c.findings.push(Finding {
                line: line_of(col.line),
                message: format!(
                    "{what}, {:.3} mm deep ({:.3} mm³)",
                    col.depth, col.volume_mm3
                ),
                in_input: was(col, old, rapid),
                refuses: true,
            });
        }
    }
    c.ok = false;
    c
}

fn gouge_report(i: &Inputs, p: &Program, part: &DropMesh) -> GougeReport {
    let g = GougeParams {
        step: i.tol.gouge_step,
        tol: i.tol.gouge,
        rapids: true,
    };
    gouge::check(p, part, |op| (i.tool_body)(op), &g)
}

/// Gouges of the output into the part (rapids included). A gouge whose
/// deepest point lies on the input's path (within [`Tolerances::tip`]; a
/// canned cycle's hole from its highest plane to its bottom, which the
/// input's own check skips) is the input's, the same tool having been
/// there: reported `in_input`, and refused all the same. A move of the
/// output that leaves the input's path (a new link) and gouges deepest off
/// it is new.
pub fn gouges(i: &Inputs, part: &DropMesh) -> Check {
    gouges_with_report(i, part).0
}

/// [`gouges`] and the output's gouge report.
fn gouges_with_report(i: &Inputs, part: &DropMesh) -> (Check, GougeReport) {
    let mut c = Check::new("gouge", "samples");
    let out = gouge_report(i, i.output, part);
    c.checked = out.points_checked;
    let s = out.skipped;
    if s.total() > 0 {
        c.skipped = Some(format!(
            "{} moves not checked: {} with no tool body, {} with a tilted tool, {} canned cycles, {} from or to an unknown position{}",
            s.total(), s.no_tool, s.tilted, s.cycles, s.unknown_position, s.first()
        ));
    }
    // A part the tool stands by at less than half of the path is not the
    // program's part: no gouge found there proves anything. Refused, as the
    // input's: every pass keeps the tool's positions (or its ball centres),
    // so the input stands as far from the part.
    if out.mostly_off_part() {
        c.ok = false;
        c.findings.push(Finding {
            line: None,
            message: out.off_part_words(),
            in_input: true,
            refuses: true,
        });
    }
    if out.gouges.is_empty() {
        return (c, out);
    }
    // The deepest point of a gouge lies where the input's tool also went:
    // the same tool at the same place cuts the part as deep. A tilted
    // ball's own gouge is the input's where the input's ball had its
    // centre there (the lead/tilt pass keeps the centres, not the tips).
    let old = PathIndex::new(i.input, i.tol.tip);
    let old_centres = std::cell::OnceCell::new();
    for g in &out.gouges {
        let by_centre = |c: [f64; 3]| {
            old_centres
                .get_or_init(|| PathIndex::centres(i.input, i, i.tol.tip))
                .near(DVec3::from_array(c), i.tol.tip)
        };
        let in_input =
            old.near(DVec3::from_array(g.at), i.tol.tip) || g.ball_centre.is_some_and(by_centre);
        // The input's own gouge within the part's tessellation error is
        // reported only.
        let refuses = !in_input || g.depth > i.tol.input_gouge;
        c.ok &= !refuses;
        let allowed = if in_input && refuses {
            format!(
                ", beyond the {:.3} mm the input's own may be",
                i.tol.input_gouge
            )
        } else {
            String::new()
        };
        c.findings.push(Finding {
            line: line_of(g.line),
            message: format!(
                "gouge {:.4} mm deep into the part at ({:.3}, {:.3}, {:.3}){allowed}",
                g.depth, g.at[0], g.at[1], g.at[2],
            ),
            in_input,
            refuses,
        });
    }
    (c, out)
}

/// The output's per-move peak loads against their limits, each allowed
/// `tol` (relative) over.
pub fn loads(output: &Program, l: &dyn LoadCheck, tol: f64) -> Check {
    let mut c = Check::new("loads", "loads");
    let all = l.loads(output);
    c.checked = all.len();
    for x in &all {
        if !(x.value <= x.limit * (1.0 + tol)) {
            let line = output
                .operations
                .get(x.op)
                .and_then(|op| op.moves.get(x.mv))
                .map_or(0, |m| m.line);
            c.findings.push(Finding {
                line: line_of(line),
                message: format!(
                    "{} {:.4} over its limit {:.4} by {:.2} % (tolerance {:.2} %)",
                    x.name,
                    x.value,
                    x.limit,
                    (x.value / x.limit - 1.0) * 100.0,
                    tol * 100.0
                ),
                in_input: false,
                refuses: true,
            });
        }
    }
    c.ok = c.findings.is_empty();
    c
}
