//! Resource limits: how much work and memory one input or argument may ask
//! for. A few bytes can describe millions of moves (a NURBS with control
//! points at 1e12, a circle of radius 1e6 written as lines, a raster step of
//! 1e-9): every place where the work grows faster than the input checks its
//! limit before doing the work, and says which limit and how to raise it.
//!
//! | name | default | what it bounds |
//! |---|---|---|
//! | `moves` | 50,000,000 | moves of one program: generated (raster points, counted from the grid before any drop) or written (with arcs written as lines and canned cycles spelled out, counted before the first byte) |
//! | `expansion` | 10,000 | moves one element becomes: one NURBS span sampled to the chord tolerance, one arc written as lines |
//! | `line-bytes` | 65,536 | bytes in one line of an NC program |
//! | `expression-depth` | 64 | nesting of parentheses and signs in one expression (Sinumerik, LinuxCNC); at most [`MAX_EXPRESSION_DEPTH`] (1,000), so the recursive parser never overflows its stack |
//! | `stl-triangles` | 50,000,000 | facets of one STL file (a binary file's count is checked before anything is allocated) |
//! | `stl-extent` | 1,000,000 | largest coordinate of an STL vertex, mm |
//! | `memory` | 4,000 | MB the work estimated up front may take (the grid of a raster, the samples of a gouge check); the `millplan` binary sets it by [`default_memory`]: half of what the process may really use |
//!
//! The numbers an NC program gives are bounded apart, by [`NC_EXTENT`]
//! (coordinates, mm, and rotary positions, degrees: 1,000,000) and
//! [`NC_RATE`] (feeds and spindle speeds: 1,000,000), and a dwell by
//! [`NC_DWELL`] (86,400 s).
//!
//! The pecks of one canned-cycle hole are bounded apart, by
//! `millplan_nc::MAX_PECKS` (1,000): a peck that small is below what any
//! target can write, and the readers refuse it at the cycle's line.

use std::fmt;

/// The plausibility limit on a coordinate, arc radius or cycle height an NC
/// program gives (mm), and on a rotary axis position (degrees): like the STL
/// extent, a number beyond it is no machine's and is refused at its line.
pub const NC_EXTENT: f64 = 1e6;

/// The plausibility range of a tool diameter a user gives (mm): below a
/// micrometre no tool exists and no NC format writes the size back (APT
/// writes six decimals); above the coordinate limit no machine holds it.
pub const TOOL_DIAMETER: (f64, f64) = (1e-3, NC_EXTENT);

/// The plausibility limit on a feed (mm/min, mm/rev or the inverse time's
/// 1/min) and a spindle speed (1/min) an NC program gives.
pub const NC_RATE: f64 = 1e6;

/// The plausibility limit on a dwell an NC program gives (s): a day. A
/// longer wait is a unit slip (`G82 … P` in milliseconds read as seconds,
/// or a runaway number), and would turn a cycle time into years.
pub const NC_DWELL: f64 = 86_400.0;

/// The highest `expression-depth` that `--limit` accepts: the expression
/// parser recurses once per level, and 1,000 levels take well under the
/// main thread's stack even in a debug build (tested with 1,000 nested
/// functions); a deeper limit would let an input overflow the stack.
pub const MAX_EXPRESSION_DEPTH: u64 = 1_000;

/// The default `memory` limit, bytes: half of the least of what bounds the
/// process — the machine's physical memory, the address space it may map
/// (`RLIMIT_AS`, `ulimit -v`) and its control group's `memory.max` — each
/// given only where the system sets it. Half, because the estimates count
/// the big arrays only: the program, the allocator's reserve and the
/// threads' stacks take the rest. With none known, [`Limits::default`]'s.
pub fn default_memory(
    physical: Option<u64>,
    address_space: Option<u64>,
    cgroup: Option<u64>,
) -> u64 {
    [physical, address_space, cgroup]
        .into_iter()
        .flatten()
        .filter(|&b| b > 0)
        .min()
        .map_or(Limits::default().memory, |b| b / 2)
}

/// The limits in force. [`Limits::default`] is the documented table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub moves: u64,
    pub expansion: u64,
    pub line_bytes: u64,
    pub expression_depth: u64,
    pub stl_triangles: u64,
    /// mm.
    pub stl_extent: f64,
    /// Bytes.
    pub memory: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            moves: 50_000_000,
            expansion: 10_000,
            line_bytes: 65_536,
            expression_depth: 64,
            stl_triangles: 50_000_000,
            stl_extent: 1e6,
            memory: 4_000_000_000,
        }
    }
}

/// Every limit's name as written in `--limit NAME=VALUE`, with what it bounds.
pub const NAMES: [(&str, &str); 7] = [
    ("moves", "moves of one program generated or written"),
    (
        "expansion",
        "moves from one NURBS span or one arc written as lines",
    ),
    ("line-bytes", "bytes in one line of an NC program"),
    (
        "expression-depth",
        "nesting of parentheses and signs in one expression (at most 1000)",
    ),
    ("stl-triangles", "facets of one STL file"),
    ("stl-extent", "largest STL coordinate, mm"),
    ("memory", "MB the work estimated up front may take"),
];

impl Limits {
    /// Sets the limit `name` from `value`: a number, optionally with a
    /// suffix k, M or G (thousand, million, billion); `memory` is in MB.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        let v = parse_amount(value).ok_or_else(|| {
            format!("`{value}` is not a positive number (optionally with k, M or G)")
        })?;
        let count = || -> Result<u64, String> {
            if !(1.0..=1e18).contains(&v) {
                Err(format!("`{value}` must be from 1 to 1e18"))
            } else {
                Ok(v as u64)
            }
        };
        match name {
            "moves" => self.moves = count()?,
            "expansion" => self.expansion = count()?,
            "line-bytes" => self.line_bytes = count()?,
            "expression-depth" => {
                let d = count()?;
                if d > MAX_EXPRESSION_DEPTH {
                    return Err(format!(
                        "`{value}` must be from 1 to {MAX_EXPRESSION_DEPTH} (deeper nesting would overflow the parser's stack)"
                    ));
                }
                self.expression_depth = d;
            }
            "stl-triangles" => self.stl_triangles = count()?,
            "stl-extent" => {
                if !(v > 0.0 && v <= 1e30) {
                    return Err(format!("`{value}` must be above 0 and at most 1e30 mm"));
                }
                self.stl_extent = v;
            }
            "memory" => self.memory = count()?.saturating_mul(1_000_000),
            _ => {
                return Err(format!(
                    "`{name}` is not a limit; the limits are {}",
                    NAMES.map(|(n, _)| n).join(", ")
                ))
            }
        }
        Ok(())
    }

    /// The value of limit `name` as it is written in `--limit` (memory in MB).
    pub fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "moves" => self.moves as f64,
            "expansion" => self.expansion as f64,
            "line-bytes" => self.line_bytes as f64,
            "expression-depth" => self.expression_depth as f64,
            "stl-triangles" => self.stl_triangles as f64,
            "stl-extent" => self.stl_extent,
            "memory" => (self.memory / 1_000_000) as f64,
            _ => return None,
        })
    }
}

fn parse_amount(s: &str) -> Option<f64> {
    let s = s.trim();
    let (num, mult) = match s.as_bytes().last()? {
        b'k' | b'K' => (&s[..s.len() - 1], 1e3),
        b'M' => (&s[..s.len() - 1], 1e6),
        b'G' => (&s[..s.len() - 1], 1e9),
        _ => (s, 1.0),
    };
    let v = num.trim().parse::<f64>().ok()? * mult;
    (v.is_finite() && v > 0.0).then_some(v)
}

/// A limit the input or the arguments would exceed: the limit's name, what
/// the work would need and the limit, worded for the user.
#[derive(Clone, Debug, PartialEq)]
pub struct Exceeded {
    /// The limit's name in `--limit NAME=VALUE`.
    pub name: &'static str,
    /// What would be needed, in words (`16777216 moves from one NURBS span`).
    pub needs: String,
    /// The limit in the same unit.
    pub limit: f64,
}

impl Exceeded {
    pub fn new(name: &'static str, needs: impl Into<String>, limit: f64) -> Exceeded {
        Exceeded {
            name,
            needs: needs.into(),
            limit,
        }
    }
}

impl fmt::Display for Exceeded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}, over the {} limit of {} (raise it with --limit {}=N)",
            self.needs,
            self.name,
            amount(self.limit),
            self.name
        )
    }
}

/// A count as written in messages: whole numbers plainly, huge ones in
/// scientific notation.
pub fn amount(v: f64) -> String {
    if !v.is_finite() {
        "more than can be counted".into()
    } else if v.abs() < 1e15 && v.fract() == 0.0 {
        format!("{}", v as i64)
    } else if v.abs() < 1e6 {
        format!("{v}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_sets_and_reads_back() {
        let mut l = Limits::default();
        for (name, _) in NAMES {
            l.set(name, "1k").expect(name);
            assert_eq!(l.get(name), Some(1000.0), "{name}");
        }
        assert_eq!(l.memory, 1_000_000_000);
        l.set("moves", "1.5M").expect("moves");
        assert_eq!(l.moves, 1_500_000);
    }

    #[test]
    fn bad_names_and_values_are_refused() {
        let mut l = Limits::default();
        assert!(l
            .set("movez", "1")
            .expect_err("no such limit")
            .contains("moves, expansion"));
        for v in ["", "0", "-5", "nan", "inf", "1e400", "5x", "0.5"] {
            assert!(l.set("moves", v).is_err(), "{v}");
        }
        assert_eq!(l, Limits::default());
        // Issue 34: a deeper limit let an input overflow the parser's stack.
        let e = l
            .set("expression-depth", "100000")
            .expect_err("over the cap");
        assert!(e.contains("1 to 1000"), "{e}");
        assert_eq!(l, Limits::default());
    }

    /// Issue 34: "`--resolution 0.005` on a 100 mm stock (3,400 MB
    /// estimated) passes the default memory limit (half the RAM) and aborts
    /// under a 4 GB address-space limit". The default is half of the least
    /// bound the process has.
    #[test]
    fn the_default_memory_limit_is_half_the_least_bound() {
        let gib = 1u64 << 30;
        assert_eq!(default_memory(Some(24 * gib), None, None), 12 * gib);
        // `ulimit -v 4000000` (KiB) under 24 GiB of RAM.
        let ulimit = 4_000_000 * 1024;
        assert_eq!(
            default_memory(Some(24 * gib), Some(ulimit), None),
            ulimit / 2
        );
        assert!(default_memory(Some(24 * gib), Some(ulimit), None) < 3_400_000_000);
        assert_eq!(default_memory(Some(24 * gib), None, Some(gib)), gib / 2);
        assert_eq!(
            default_memory(Some(24 * gib), Some(8 * gib), Some(2 * gib)),
            gib
        );
        assert_eq!(default_memory(None, None, None), Limits::default().memory);
        assert_eq!(
            default_memory(Some(0), None, None),
            Limits::default().memory
        );
    }

    #[test]
    fn exceeded_says_which_limit_and_how_to_raise_it() {
        let e = Exceeded::new("expansion", "16777216 moves from one NURBS span", 10_000.0);
        assert_eq!(
            e.to_string(),
            "16777216 moves from one NURBS span, over the expansion limit of 10000 (raise it with --limit expansion=N)"
        );
        assert_eq!(amount(f64::INFINITY), "more than can be counted");
        assert_eq!(amount(3.5e20), "3.500e20");
    }
}
