//! The phases of a command that runs them one after another, for its
//! `--timings` table: each lap is the time since the previous one, so the
//! laps add up to the wall time since the clock started, and each is named
//! for what ran in it.

use millplan_plan::pipeline::Timing;
use std::time::Instant;

/// A clock of laps.
pub struct Clock {
    t0: Instant,
    last: Instant,
    entries: Vec<Timing>,
}

impl Clock {
    /// A clock started now.
    pub fn start() -> Clock {
        let now = Instant::now();
        Clock {
            t0: now,
            last: now,
            entries: Vec::new(),
        }
    }

    /// Ends the phase `name`, which ran since the last lap.
    pub fn lap(&mut self, name: &str) {
        let now = Instant::now();
        self.entries.push(Timing {
            name: name.to_string(),
            seconds: (now - self.last).as_secs_f64(),
        });
        self.last = now;
    }

    /// The laps so far, in order.
    pub fn entries(&self) -> &[Timing] {
        &self.entries
    }

    /// When the clock started.
    pub fn started(&self) -> Instant {
        self.t0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laps_add_up_to_the_total() {
        let mut c = Clock::start();
        c.lap("one");
        std::thread::sleep(std::time::Duration::from_millis(5));
        c.lap("two");
        let sum: f64 = c.entries().iter().map(|t| t.seconds).sum();
        assert!((sum - (c.last - c.started()).as_secs_f64()).abs() < 1e-9);
        assert!(c.entries()[1].seconds >= 0.005);
    }
}
