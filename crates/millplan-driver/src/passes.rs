//! The passes `optimise` can run, what each needs and changes, and which of
//! them a job's inputs allow.

use crate::job::Job;
use millplan_plan::pipeline::{Changes, PASSES};
use serde::Serialize;

/// A pass of the driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PassName {
    Speed,
    Reorder,
    Orient,
    Feed,
    Post,
}

/// Every pass in the order a default run takes them.
pub const ORDER: [PassName; 5] = [
    PassName::Speed,
    PassName::Reorder,
    PassName::Orient,
    PassName::Feed,
    PassName::Post,
];

/// One row of `--list-passes`.
#[derive(Clone, Debug, Serialize)]
pub struct PassRow {
    pub name: &'static str,
    pub needs: &'static str,
    pub changes: Changes,
    pub does: String,
}

impl PassName {
    pub fn name(self) -> &'static str {
        match self {
            PassName::Speed => "speed",
            PassName::Reorder => "reorder",
            PassName::Orient => "orient",
            PassName::Feed => "feed",
            PassName::Post => "post",
        }
    }

    pub fn parse(s: &str) -> Result<PassName, String> {
        ORDER
            .into_iter()
            .find(|p| p.name() == s.trim())
            .ok_or_else(|| {
                format!("unknown pass `{s}` (known: speed, reorder, orient, feed, post)")
            })
    }

    /// What the pass needs of the job, in words.
    pub fn needs(self) -> &'static str {
        match self {
            PassName::Speed => "part (--stl), a ball-end operation",
            PassName::Reorder => "part (--stl), a three-axis ball-end operation",
            PassName::Orient => "part (--stl), stock, material, five-axis CL (tool axes)",
            PassName::Feed => "stock (--stock), material (--material)",
            PassName::Post => "machine kinematics (--machine with [kinematics]), five-axis CL",
        }
    }

    /// The row of the pass table: the library's own words where the
    /// pipeline lists the pass (`PASSES`).
    pub fn row(self) -> PassRow {
        let lib = PASSES
            .iter()
            .find(|p| p.name == self.name() && self != PassName::Orient);
        let (changes, does) = match (self, lib) {
            (_, Some(p)) => (p.changes, p.does.to_string()),
            (PassName::Orient, _) => (Changes::What, "lead and tilt per ball-end operation from the forces on the simulated stock (§2.4)".into()),
            _ => (Changes::What, "five-axis CL through the machine's kinematics to joint positions".into()),
        };
        PassRow {
            name: self.name(),
            needs: self.needs(),
            changes,
            does: if self == PassName::Reorder {
                format!("{does}; the speed pass runs again on a new order")
            } else {
                does
            },
        }
    }
}

/// The pass table, in [`ORDER`].
pub fn table() -> Vec<PassRow> {
    ORDER.iter().map(|p| p.row()).collect()
}

/// The table of `optimise --list-passes` in words: each pass, what it
/// needs and what it changes.
pub fn table_text() -> String {
    table()
        .iter()
        .map(|r| {
            format!(
                "{:<8} needs: {}\n         changes: {:?}; {}",
                r.name, r.needs, r.changes, r.does
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Parses `--passes a,b,c`: known names, each once, in the order given.
pub fn parse_list(s: &str) -> Result<Vec<PassName>, String> {
    let mut v: Vec<PassName> = Vec::new();
    for w in s.split(',').filter(|w| !w.trim().is_empty()) {
        let p = PassName::parse(w)?;
        if v.contains(&p) {
            return Err(format!("pass `{}` given twice", p.name()));
        }
        v.push(p);
    }
    if v.is_empty() {
        return Err("--passes: name at least one pass".into());
    }
    Ok(v)
}

fn has_ball(job: &Job, three_axis: bool) -> bool {
    job.inputs.program.operations.iter().any(|op| {
        let ball = job
            .body_of(op)
            .is_some_and(|b| matches!(b.shape, millplan_models::cutter::Shape::Ball { .. }));
        ball && op.moves.iter().any(|m| m.is_cutting())
            && (!three_axis || op.moves.iter().all(|m| m.orient.is_none()))
    })
}

/// Whether an operation is one the reorder pass works on.
fn reorderable(job: &Job) -> bool {
    let ball_d = job.speed_params().ball_d;
    let ops = job.inputs.program.operations.iter();
    ops.filter(|op| op.moves.iter().filter(|m| m.is_cutting()).nth(1).is_some())
        .any(|op| millplan_plan::reorder::reorderable(op, ball_d).is_some())
}

/// Whether `op` is five-axis CL: a cutting move, and a tool axis vector
/// on every cutting move (not rotary angles alone).
pub fn axis_vectors(op: &millplan_nc::Operation) -> bool {
    let mut cutting = op.moves.iter().filter(|m| m.is_cutting()).peekable();
    cutting.peek().is_some() && cutting.all(|m| op.orient(m).is_some_and(|o| o.axis.is_some()))
}

fn five_axis(job: &Job) -> bool {
    job.inputs
        .program
        .moves()
        .any(|m| m.is_cutting() && m.orient.is_some())
}

/// Why the load passes do not run when no cutting move meets the stock:
/// there are no loads to lean the tool on or to schedule feeds by, and
/// the feed pass would take every block for air.
pub const STOCK_MISSED: &str = "no cutting move of the program meets the stock (--stock): no load to act on, every block would read as air (is it the stock this program cuts?)";

/// Why `pass` cannot run on this job, `None` when it can.
pub fn missing(job: &Job, pass: PassName) -> Option<String> {
    why_not(job, pass).map(|w| w.why.to_string())
}

/// Why a pass cannot run: the program has nothing for it, or an input the
/// user can give is missing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WhyNot {
    pub why: &'static str,
    /// An option would let it run (no `--stl`, `--stock`, `--material`,
    /// `--machine` or kinematics); `false`: the program has nothing for it.
    pub option: bool,
}

/// Why `pass` cannot run on this job: what the program lacks is said
/// first (no option would make the pass run then), then the missing input.
pub fn why_not(job: &Job, pass: PassName) -> Option<WhyNot> {
    let i = &job.inputs;
    let part = i.part.is_some();
    let program = |why| Some(WhyNot { why, option: false });
    let option = |why| Some(WhyNot { why, option: true });
    match pass {
        PassName::Speed if !has_ball(job, false) => program("no ball-end operation"),
        PassName::Speed if !part => {
            option("no part (--stl): the working diameter needs the surface")
        }
        PassName::Reorder if !has_ball(job, true) => program("no three-axis ball-end operation"),
        PassName::Reorder if !reorderable(job) => program(
            "no three-axis ball-end operation of straight moves (arcs, canned cycles and turned frames are left as they are)",
        ),
        PassName::Reorder if !part => option("no part (--stl)"),
        PassName::Orient if !job.inputs.program.operations.iter().any(axis_vectors) => program(
            "no five-axis CL operation (tool axes as vectors on every cutting move): nothing to lean",
        ),
        PassName::Orient if !has_ball(job, false) => program("no ball-end operation"),
        PassName::Orient if !part => {
            option("no part (--stl): the contact points need the surface")
        }
        PassName::Orient if i.stock.is_none() => option("no stock (--stock)"),
        PassName::Orient if job.setup.is_none() => option("no material (--material)"),
        PassName::Feed if i.stock.is_none() => option("no stock (--stock)"),
        PassName::Feed if job.setup.is_none() => option("no material (--material)"),
        PassName::Feed | PassName::Orient if job.stock_missed => option(STOCK_MISSED),
        PassName::Post if !five_axis(job) => program("a three-axis program: nothing to post"),
        PassName::Post if !i.machine_given => option("no machine file (--machine)"),
        PassName::Post if i.machine.kinematics().is_none() => {
            option("the machine file has no [kinematics]")
        }
        _ => None,
    }
}

/// The passes the user named (`--passes`) checked before any work, and
/// again once the input's loads show whether it meets the stock: one
/// that a missing input keeps from running is refused, naming the input
/// (a pass the program has nothing for is skipped as in the default list).
pub fn check_named(job: &Job, order: &[PassName]) -> Result<(), String> {
    for &p in order {
        if let Some(w) = why_not(job, p).filter(|w| w.option) {
            let n = p.name();
            return Err(format!(
                "--passes names {n}, which cannot run: {}; give what it needs, or leave {n} out of --passes",
                w.why
            ));
        }
    }
    Ok(())
}
