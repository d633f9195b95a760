//! The `--timings` table on standard error (the laps of a command are
//! `millplan_driver::timings::Clock`'s).
//!
//! A command records its phases in the order they ran, one after the other,
//! so that they add up to the run's wall time; an entry whose name starts
//! with two spaces is a part of the next phase that is not indented (a pass's
//! own steps, or work on another thread beside it) and is printed under it,
//! indented, and not added.

use millplan_plan::pipeline::Timing;

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
}

impl Table for Clock {
    fn print(&self, on: bool) {
        if on {
            print(self.entries(), self.started());
        }
    }
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
}
