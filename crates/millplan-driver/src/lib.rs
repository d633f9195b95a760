//! The job API of millplan (as `rustc_interface` sits below `rustc`): a
//! [`Job`] holds the resolved inputs of one run — the program, the part, the
//! stock, the machine, the material, the tools — with every default chosen
//! in one place ([`defaults`]), builds each once (the tool bodies by
//! `ToolBody::for_operation`, the stock by `StockSpec::build`, the force
//! model, the load limits), runs the passes ([`Job::run`]), writes the
//! result and checks what it wrote from its own bytes ([`Job::finish`]), and
//! reports it ([`report`]). The binary parses arguments, reads the files,
//! builds the job, calls it and prints; it decides nothing.

pub mod checks;
pub mod defaults;
pub mod finish;
pub mod job;
pub mod passes;
pub mod report;
pub mod run;
pub mod target;
pub mod tools;

pub use finish::{Summary, Verdict, Written};
pub use job::{Inputs, Job, JobError, Options, UserLimits};
pub use passes::PassName;
pub use run::Outcome;
