//! The pass pipeline: passes run in order over one program, sharing the
//! analyses they need (the part's mesh, its closest-point tree and vertex
//! normals, its drop-cutter tree) built once, on first use, by the
//! [`Context`].
//!
//! Every pass says what it reads ([`Need`]) and what it may change
//! ([`Changes`]); [`run`] times each pass (the `--timings` table), and in
//! debug builds and tests runs the IR verifier after it and checks that it
//! changed nothing it did not declare: a pass that changes only *how* the
//! program cuts (speeds, feeds) must leave every position where it was; one
//! that changes the *order* must still cut every point. [`PASSES`] lists them
//! all.

use crate::machine::Machine;
use millplan_geom::TriMesh;
use millplan_models::contact::Surface;
use millplan_nc::verify::{verify, Violation};
use millplan_nc::{same_position, Program};
use millplan_sim::dropcutter::DropMesh;
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

/// What a pass reads besides the program.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Need {
    /// The part surface (STL).
    Part,
    /// The machine's limits (spindle, feeds): always there, a default if not given.
    Machine,
}

/// What a pass may change.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Changes {
    /// Annotations only (a tool axis where only angles were known): no
    /// position, feed or speed.
    Annotations,
    /// *How* the program cuts: spindle speeds, feeds, feed modes; never a
    /// position, the number of moves or their kinds.
    How,
    /// The *order* of the cutting points and the links between them: every
    /// cutting point is still cut.
    Order,
    /// *What* is cut: positions may change.
    What,
}

/// A pass as the pass table describes it.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct PassInfo {
    pub name: &'static str,
    pub needs: &'static [Need],
    pub changes: Changes,
    /// One line on what it does.
    pub does: &'static str,
}

/// Every pass, in the order a full run would take them.
pub const PASSES: &[&PassInfo] = &[
    &crate::orient::INFO,
    &crate::reorder::INFO,
    &crate::speed::INFO,
    &crate::feed::INFO,
];

/// A transformation of the IR.
pub trait Pass {
    fn info(&self) -> &'static PassInfo;
    fn run(&mut self, p: &mut Program, cx: &Context) -> Result<(), PassError>;
}

#[derive(Debug, thiserror::Error)]
pub enum PassError {
    /// The pass cannot run on this program (no ball-end operation, invalid
    /// parameters): the user's input.
    #[error("{pass}: {message}")]
    Input { pass: &'static str, message: String },
    #[error("{pass} needs the part surface (--stl)")]
    NeedsPart { pass: &'static str },
    /// A bug: the pass broke an invariant of the IR.
    #[error("{pass} left an invalid program: {}", .violations.first().map(|v| v.to_string()).unwrap_or_default())]
    Verify {
        pass: &'static str,
        violations: Vec<Violation>,
    },
    /// A bug: the pass changed more than it declares.
    #[error("{pass} changed more than it may ({changes:?}): {message}")]
    Contract {
        pass: &'static str,
        changes: Changes,
        message: String,
    },
}

impl PassError {
    /// Whether the error is the input's (exit 2) rather than a bug.
    pub fn is_input(&self) -> bool {
        matches!(self, PassError::Input { .. } | PassError::NeedsPart { .. })
    }
}

/// Wall time of a pass or analysis.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Timing {
    pub name: String,
    pub seconds: f64,
}

/// Where passes report how far a phase of theirs has come: the phase's name,
/// the steps done and the steps it has in all. Within one phase the counts
/// only grow and the last report has `done == total`; a new name starts a new
/// phase. Called from any thread.
pub type Progress<'a> = dyn Fn(&str, usize, usize) + Sync + 'a;

/// What the passes of a run share: the machine, the part and the analyses of
/// it, each built once when a pass first asks for it.
pub struct Context<'a> {
    pub machine: Machine,
    mesh: Option<&'a TriMesh>,
    surface: OnceLock<Surface<'a>>,
    drop: OnceLock<DropMesh>,
    timings: Mutex<Vec<Timing>>,
    progress: Option<&'a Progress<'a>>,
    /// The phase last reported and how far it had come: reports from
    /// threads that arrive late (a smaller count of the same phase) are
    /// dropped, so the hook sees every phase's counts only grow.
    last: Mutex<(String, usize)>,
    /// Verify the IR and each pass's declared changes after every pass (on in
    /// debug builds and tests).
    pub verify: bool,
}

impl<'a> Context<'a> {
    pub fn new(machine: Machine) -> Context<'a> {
        Context {
            machine,
            mesh: None,
            surface: OnceLock::new(),
            drop: OnceLock::new(),
            timings: Mutex::new(Vec::new()),
            progress: None,
            last: Mutex::new((String::new(), 0)),
            verify: cfg!(debug_assertions),
        }
    }

    /// Passes report their progress to `f` (a bar, say); without it nobody
    /// hears of it.
    pub fn with_progress(mut self, f: &'a Progress<'a>) -> Context<'a> {
        self.progress = Some(f);
        self
    }

    /// Reports that `done` of the `total` steps of `phase` are done (see
    /// [`Progress`]); nothing without a hook. A count smaller than the one
    /// last reported for the same phase (a thread that came late) is dropped,
    /// and `done` is capped at `total`.
    pub fn progress(&self, phase: &str, done: usize, total: usize) {
        let Some(f) = self.progress else {
            return;
        };
        let done = done.min(total);
        let Ok(mut last) = self.last.lock() else {
            return;
        };
        if last.0 == phase {
            if done < last.1 {
                return;
            }
        } else {
            last.0 = phase.to_string();
        }
        last.1 = done;
        f(phase, done, total);
    }

    /// Verify the IR and each pass's declared changes after every pass, also
    /// in release builds.
    pub fn verifying(mut self) -> Context<'a> {
        self.verify = true;
        self
    }

    /// The part the passes work against.
    pub fn with_part(mut self, mesh: &'a TriMesh) -> Context<'a> {
        self.mesh = Some(mesh);
        self
    }

    /// The part with its closest-point tree already built (built while the
    /// program was being read, say).
    pub fn with_surface(mut self, surface: Surface<'a>) -> Context<'a> {
        self.mesh = Some(surface.mesh);
        self.surface = OnceLock::from(surface);
        self
    }

    pub fn mesh(&self) -> Option<&'a TriMesh> {
        self.mesh
    }

    /// Lets the closest-point tree and vertex normals go (the mesh stays):
    /// for a command done with them, so that what it allocates next can use
    /// their memory. A later [`Context::surface`] builds them again.
    pub fn release_surface(&mut self) {
        drop(self.surface.take());
    }

    /// The part's closest-point tree and vertex normals.
    pub fn surface(&self) -> Option<&Surface<'a>> {
        let mesh = self.mesh?;
        Some(
            self.surface
                .get_or_init(|| self.time("surface (BVH, vertex normals)", || Surface::new(mesh))),
        )
    }

    /// The part's drop-cutter tree.
    pub fn drop_mesh(&self) -> Option<&DropMesh> {
        let mesh = self.mesh?;
        Some(
            self.drop
                .get_or_init(|| self.time("drop-cutter tree", || DropMesh::new(mesh))),
        )
    }

    /// Runs `f`, recording its wall time under `name`.
    pub fn time<T>(&self, name: &str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let r = f();
        self.record(name, t.elapsed().as_secs_f64());
        r
    }

    pub fn record(&self, name: &str, seconds: f64) {
        if let Ok(mut v) = self.timings.lock() {
            v.push(Timing {
                name: name.to_string(),
                seconds,
            });
        }
    }

    /// Every timing recorded so far, in order.
    pub fn timings(&self) -> Vec<Timing> {
        self.timings.lock().map(|v| v.clone()).unwrap_or_default()
    }
}

/// What a pass must leave as it was, taken before it runs.
enum Before {
    None,
    /// Kinds and positions of every move, per operation.
    Moves(Vec<Vec<(&'static str, millplan_geom::DVec3, f64, f64)>>),
    /// The cutting points, sorted.
    Points(Vec<[f64; 3]>),
}

fn cutting_points(p: &Program) -> Vec<[f64; 3]> {
    let mut v: Vec<[f64; 3]> = p
        .moves()
        .filter(|m| m.is_cutting() && !m.end.is_nan())
        .map(|m| m.end.to_array())
        .collect();
    v.sort_by(|a, b| {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    v.dedup();
    v
}

fn snapshot(p: &Program, c: Changes) -> Before {
    match c {
        Changes::Annotations | Changes::How => Before::Moves(
            p.operations
                .iter()
                .map(|op| {
                    op.moves
                        .iter()
                        .map(|m| {
                            // Annotations keep feeds and speeds too.
                            let (f, s) = if c == Changes::Annotations {
                                (m.feed, m.spindle)
                            } else {
                                (0.0, 0.0)
                            };
                            (m.kind.name(), m.end, f, s)
                        })
                        .collect()
                })
                .collect(),
        ),
        Changes::Order => Before::Points(cutting_points(p)),
        Changes::What => Before::None,
    }
}

fn check(before: &Before, p: &Program, c: Changes) -> Result<(), String> {
    match before {
        Before::None => Ok(()),
        Before::Moves(ops) => {
            if ops.len() != p.operations.len() {
                return Err(format!(
                    "{} operations became {}",
                    ops.len(),
                    p.operations.len()
                ));
            }
            for (oi, (was, op)) in ops.iter().zip(&p.operations).enumerate() {
                if was.len() != op.moves.len() {
                    return Err(format!(
                        "operation {oi}: {} moves became {}",
                        was.len(),
                        op.moves.len()
                    ));
                }
                for (i, (w, m)) in was.iter().zip(&op.moves).enumerate() {
                    let (f, s) = if c == Changes::Annotations {
                        (m.feed, m.spindle)
                    } else {
                        (0.0, 0.0)
                    };
                    if w.0 != m.kind.name() || !same_position(w.1, m.end) || w.2 != f || w.3 != s {
                        return Err(format!("operation {oi} move {i} (line {}) changed", m.line));
                    }
                }
            }
            Ok(())
        }
        Before::Points(pts) => {
            let now = cutting_points(p);
            // Every point cut before is cut after (links may add points on the way).
            let missing = pts
                .iter()
                .filter(|q| {
                    now.binary_search_by(|x| {
                        x.iter()
                            .zip(q.iter())
                            .map(|(a, b)| a.total_cmp(b))
                            .find(|o| o.is_ne())
                            .unwrap_or(std::cmp::Ordering::Equal)
                    })
                    .is_err()
                })
                .count();
            if missing > 0 {
                return Err(format!("{missing} cutting points are no longer cut"));
            }
            Ok(())
        }
    }
}

/// Runs `passes` in order on `p`: each is timed, and with `cx.verify` the IR
/// and the pass's declared changes are checked after it.
pub fn run(passes: &mut [&mut dyn Pass], p: &mut Program, cx: &Context) -> Result<(), PassError> {
    for pass in passes.iter_mut() {
        let info = pass.info();
        if info.needs.contains(&Need::Part) && cx.mesh.is_none() {
            return Err(PassError::NeedsPart { pass: info.name });
        }
        let before = if cx.verify {
            cx.time("what the pass must keep, taken before it", || {
                snapshot(p, info.changes)
            })
        } else {
            Before::None
        };
        cx.time(info.name, || pass.run(p, cx))?;
        if cx.verify {
            cx.time("IR verified, the pass's declared changes checked", || {
                verify(p).map_err(|violations| PassError::Verify {
                    pass: info.name,
                    violations,
                })?;
                check(&before, p, info.changes).map_err(|message| PassError::Contract {
                    pass: info.name,
                    changes: info.changes,
                    message,
                })
            })?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_nc::text;

    /// A pass that does what its closure does, declaring `changes`.
    struct Probe(&'static PassInfo, fn(&mut Program));

    impl Pass for Probe {
        fn info(&self) -> &'static PassInfo {
            self.0
        }
        fn run(&mut self, p: &mut Program, _: &Context) -> Result<(), PassError> {
            (self.1)(p);
            Ok(())
        }
    }

    static HOW: PassInfo = PassInfo {
        name: "probe",
        needs: &[],
        changes: Changes::How,
        does: "test",
    };
    static ORDER: PassInfo = PassInfo {
        name: "probe",
        needs: &[Need::Part],
        changes: Changes::Order,
        does: "test",
    };

    fn program() -> Program {
        text::parse(
            "program - source=generated units=mm/declared
op name=-
  tool number=1 name=- line=0 cutter=ball d=10 r=5 e=0 f=5 a=0 b=0 h=0
  start (?, ?, ?)
  L1 rapid (0, 0, 10) F0 S0 per_minute
  L2 linear (0, 0, 0) F100 S5000 per_minute
  L3 linear (10, 0, 0) F100 S5000 per_minute
  L4 linear (20, 0, 0) F100 S5000 per_minute
",
        )
        .expect("parses")
    }

    fn with_verify(cx: Context) -> Context {
        Context { verify: true, ..cx }
    }

    #[test]
    fn a_pass_that_changes_only_how_passes() {
        let mut p = program();
        let cx = with_verify(Context::new(Machine::default()));
        let mut pass = Probe(&HOW, |p| p.operations[0].moves[2].spindle = 6000.0);
        run(&mut [&mut pass], &mut p, &cx).expect("speeds may change");
        assert_eq!(p.operations[0].moves[2].spindle, 6000.0);
        // Verifying, the snapshot before the pass and the checks after it
        // are timed too, so that the phases cover the run.
        let names: Vec<String> = cx.timings().into_iter().map(|t| t.name).collect();
        assert_eq!(names.len(), 3, "{names:?}");
        assert_eq!(names[1], "probe");
    }

    #[test]
    fn a_speed_pass_that_moves_the_tool_is_caught() {
        let mut p = program();
        let cx = with_verify(Context::new(Machine::default()));
        let mut pass = Probe(&HOW, |p| p.operations[0].moves[2].end.y = 0.5);
        let e = run(&mut [&mut pass], &mut p, &cx).expect_err("a position changed");
        assert!(matches!(e, PassError::Contract { .. }), "{e}");
    }

    #[test]
    fn a_pass_that_breaks_the_ir_is_caught() {
        let mut p = program();
        let cx = with_verify(Context::new(Machine::default()));
        let mut pass = Probe(&HOW, |p| p.operations[0].moves[1].feed = -1.0);
        let e = run(&mut [&mut pass], &mut p, &cx).expect_err("negative feed");
        assert!(matches!(e, PassError::Verify { .. }), "{e}");
    }

    #[test]
    fn a_reorder_that_drops_a_point_is_caught_and_needs_are_checked() {
        let mut p = program();
        let mut pass = Probe(&ORDER, |p| {
            p.operations[0].moves.pop();
        });
        let cx = with_verify(Context::new(Machine::default()));
        assert!(matches!(
            run(&mut [&mut pass], &mut p, &cx),
            Err(PassError::NeedsPart { .. })
        ));
        let mesh = millplan_geom::analytic::tessellate(
            &millplan_geom::analytic::DemoSurface::default(),
            5.0,
        );
        let cx = with_verify(Context::new(Machine::default()).with_part(&mesh));
        let e = run(&mut [&mut pass], &mut p, &cx).expect_err("a point is lost");
        assert!(e.to_string().contains("no longer cut"), "{e}");
        // Reversing the order keeps every point.
        let mut q = program();
        let mut rev = Probe(&ORDER, |p| p.operations[0].moves[1..].reverse());
        run(&mut [&mut rev], &mut q, &cx).expect("the same points in another order");
    }

    #[test]
    fn progress_reaches_the_hook_in_order_and_capped() {
        let heard = Mutex::new(Vec::new());
        let hook = |phase: &str, done: usize, total: usize| {
            heard
                .lock()
                .expect("lock")
                .push((phase.to_string(), done, total));
        };
        // Without a hook nothing happens.
        Context::new(Machine::default()).progress("a", 1, 2);
        let cx = Context::new(Machine::default()).with_progress(&hook);
        // A thread that came late (3 after 5) is dropped; past the total is
        // the total; a new phase starts from its own counts.
        for (phase, done) in [("a", 0), ("a", 5), ("a", 3), ("a", 12), ("b", 1), ("b", 1)] {
            cx.progress(phase, done, 10);
        }
        let got = heard.lock().expect("lock").clone();
        let want: Vec<(String, usize, usize)> = [("a", 0), ("a", 5), ("a", 10), ("b", 1), ("b", 1)]
            .into_iter()
            .map(|(p, d)| (p.to_string(), d, 10))
            .collect();
        assert_eq!(got, want);
    }
}
