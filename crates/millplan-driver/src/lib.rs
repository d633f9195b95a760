//! The job API of millplan (as `rustc_interface` sits below `rustc`): a
//! [`Job`] holds the resolved inputs of one run — the program, the part, the
//! stock, the machine, the material, the tools — with every default chosen
//! in one place ([`defaults`]), builds each once (the tool bodies by
//! `ToolBody::for_operation`, the stock by `StockSpec::build`, the force
//! model, the load limits), runs the passes ([`Job::run`]), writes the
//! result and checks what it wrote from its own bytes ([`Job::finish`]), and
//! reports it ([`report`]). The binary parses arguments, reads the files,
//! builds the job, calls it and prints; it decides nothing.

pub mod check;
pub mod checks;
pub mod command_defaults;
pub mod convert;
pub mod cut;
pub mod defaults;
pub mod demo;
pub mod directions;
pub mod explain;
pub mod feed;
pub mod finish;
pub mod force;
pub mod given;
pub mod gouge;
pub mod inspect;
pub mod io;
pub mod job;
pub mod limits;
pub mod lobes;
pub mod message;
pub mod orient;
pub mod passes;
pub mod post;
pub mod raster;
pub mod reorder;
pub mod report;
pub mod robot;
pub mod robot_pass;
pub mod round;
pub mod run;
pub mod setup;
pub mod simulate;
pub mod speed;
pub mod sweep;
pub mod target;
pub mod thread;
pub mod timings;
pub mod tool;
pub mod tools;
pub mod watch;
pub mod wd;

pub use finish::{Summary, Verdict, Written};
pub use job::{Inputs, Job, JobError, Options, OptionsRequest, UserLimits};
pub use passes::PassName;
pub use run::Outcome;

/// A cutter by its profile, as `--tool` names it.
pub use millplan_models::cutter::Shape;
/// The named materials of the force model (the built-in table and a user's
/// TOML), as the commands load them.
pub use millplan_models::force::materials::Materials;
/// A check of a written program and its findings.
pub use millplan_plan::safety::Check;
/// A program cut into strokes for the stock.
pub use millplan_sim::stock::path::Strokes;
/// The stock, why one cannot be built, and a run's report over it.
pub use millplan_sim::stock::remaining::Remaining;
pub use millplan_sim::stock::run::{run as simulate_stock, SimReport};
pub use millplan_sim::stock::spec::StockError;
/// A stock as the user names it (`box:…`, `offset:MM`, `stl:FILE`).
pub use millplan_sim::stock::spec::StockSpec;
pub use millplan_sim::stock::Stock;
