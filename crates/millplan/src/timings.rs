//! The `--timings` table on standard error (the laps of a command are
//! `millplan_driver::timings::Clock`'s).
//!
//! A command records its phases in the order they ran, one after the other,
//! so that they add up to the run's wall time; an entry whose name starts
//! with two spaces is a part of the next phase that is not indented (a pass's
//! own steps, or work on another thread beside it) and is printed under it,
//! indented, and not added.

use millplan_driver::timings::lines;
use millplan_plan::pipeline::Timing;

/// Prints the table of `entries` and the total since `t0`.
pub fn print(entries: &[Timing], t0: std::time::Instant) {
    for l in lines(entries, t0.elapsed().as_secs_f64()) {
        eprintln!("{l}");
    }
}

pub use millplan_driver::timings::Clock;

/// The table of a [`Clock`]'s laps.
pub trait Table {
    /// Prints the table when `on`.
    fn print(&self, on: bool);

    /// The last lap, the summary printed; then the table when `on`.
    fn end(&mut self, on: bool);
}

impl Table for Clock {
    fn print(&self, on: bool) {
        if on {
            print(self.entries(), self.started());
        }
    }

    fn end(&mut self, on: bool) {
        self.lap("summary printed");
        self.print(on);
    }
}
