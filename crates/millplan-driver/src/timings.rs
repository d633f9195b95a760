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

    /// Records `seconds` of the next phase as its part `name` (printed
    /// indented under it, not added to the total).
    pub fn part(&mut self, name: &str, seconds: f64) {
        self.entries.push(Timing {
            name: format!("  {name}"),
            seconds,
        });
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

/// The `--timings` table: an entry whose name starts with two spaces is a
/// part of the next phase that is not indented (a pass's own steps, or work
/// on another thread beside it), printed under it, indented, and not added.
/// The lines of the table: each phase, its parts indented under it, and the
/// total (the wall time since `t0`, which the phases add up to).
pub fn lines(entries: &[Timing], total: f64) -> Vec<String> {
    let mut out = Vec::new();
    let mut parts: Vec<&Timing> = Vec::new();
    for t in entries {
        if t.name.starts_with("  ") {
            parts.push(t);
            continue;
        }
        out.push(format!("{:>8.3} s  {}", t.seconds, t.name));
        for p in parts.drain(..) {
            out.push(format!("  {:>8.3} s  {}", p.seconds, p.name.trim_start()));
        }
    }
    for p in parts {
        out.push(format!("  {:>8.3} s  {}", p.seconds, p.name.trim_start()));
    }
    out.push(format!("{total:>8.3} s  total (wall time of the run)"));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(name: &str, seconds: f64) -> Timing {
        Timing {
            name: name.into(),
            seconds,
        }
    }

    #[test]
    fn parts_print_under_their_phase() {
        let l = lines(
            &[
                t("read", 1.0),
                t("  contact", 0.5),
                t("  feeds", 0.25),
                t("speed", 0.875),
            ],
            2.0,
        );
        assert_eq!(
            l,
            [
                "   1.000 s  read",
                "   0.875 s  speed",
                "     0.500 s  contact",
                "     0.250 s  feeds",
                "   2.000 s  total (wall time of the run)",
            ]
        );
    }

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
