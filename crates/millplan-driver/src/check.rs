//! The physical ranges of the numbers a user gives, and the one message a
//! number outside its range gets. Every command checks its arguments here;
//! an `Err` is the user's input (the binary exits 2 with it).

/// The physical range of a numeric argument: above (or from) `lo`, up to
/// `hi`, in `unit`.
#[derive(Clone, Copy, Debug)]
pub struct Range {
    pub lo: f64,
    /// `lo` itself is outside (a positive quantity).
    pub lo_open: bool,
    pub hi: f64,
    pub unit: &'static str,
}

impl Range {
    /// Above 0, at most `hi`.
    pub const fn positive(hi: f64, unit: &'static str) -> Range {
        Range {
            lo: 0.0,
            lo_open: true,
            hi,
            unit,
        }
    }

    /// From `lo` to `hi`, both included.
    pub const fn from(lo: f64, hi: f64, unit: &'static str) -> Range {
        Range {
            lo,
            lo_open: false,
            hi,
            unit,
        }
    }

    fn holds(&self, v: f64) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        above && v <= self.hi
    }
}

/// Largest tool diameter any argument may give, mm.
pub const MAX_TOOL_D: f64 = 1000.0;
/// Largest feed, mm/min.
pub const MAX_FEED: f64 = 1e6;
/// Smallest feed an argument may give, mm/min: slower than any cut, and
/// still a feed in the words of every writer (three decimals, in inches
/// too; `--feed=1e-300` wrote F0, which its read-back refused).
pub const MIN_FEED: f64 = 0.1;
/// The range of a feed argument.
pub const FEED: Range = Range::from(MIN_FEED, MAX_FEED, "mm/min");
/// Largest spindle speed, 1/min.
pub const MAX_SPINDLE: f64 = 1e6;
/// The range of a spindle speed an argument writes into a program: from
/// the smallest the readers take as plausible (`raster --spindle=0.3` wrote
/// an S its own read-back refused).
pub const SPINDLE: Range = Range::from(millplan_nc::plausible::MIN_SPINDLE, MAX_SPINDLE, "1/min");
/// Largest cutting speed, m/min.
pub const MAX_VC: f64 = 1e4;

/// Checks a numeric argument: finite and in its range, else a message
/// naming the option, the value and the range.
pub fn arg(flag: &str, v: f64, r: Range) -> Result<f64, String> {
    if v.is_finite() && r.holds(v) {
        return Ok(v);
    }
    let unit = if r.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", r.unit)
    };
    let lo = millplan_geom::limits::amount(r.lo);
    let hi = millplan_geom::limits::amount(r.hi);
    // 1e-300 as written, not three hundred zeros.
    let v = if v != 0.0 && (v.abs() < 1e-4 || v.abs() >= 1e9) {
        format!("{v:e}")
    } else {
        format!("{v}")
    };
    Err(if r.lo_open {
        format!("{flag} {v}: must be a number above {lo} and at most {hi}{unit}")
    } else {
        format!("{flag} {v}: must be a number from {lo} to {hi}{unit}")
    })
}

/// A raster's `--stepover` (from D/1000) and `--step` for a tool of diameter `d`.
pub fn raster_spacing(d: f64, stepover: f64, step: f64) -> Result<(), String> {
    arg(
        "--stepover",
        stepover,
        Range::from((d / 1000.0).max(0.001), 1000.0, "mm (from D/1000)"),
    )?;
    arg("--step", step, Range::from(0.001, 1000.0, "mm"))?;
    Ok(())
}

/// A cutter as `--tool` gives it (`ball:D`, `flat:D`, `bull:D:R`, …), its
/// diameter at most [`MAX_TOOL_D`].
pub fn tool_shape(flag: &str, s: &str) -> Result<millplan_models::cutter::Shape, String> {
    let shape = millplan_models::cutter::Shape::parse(s).map_err(|e| format!("{flag} {e}"))?;
    let d = 2.0 * shape.radius();
    if !(d <= MAX_TOOL_D) {
        return Err(format!(
            "{flag} {s}: the diameter must be at most {MAX_TOOL_D} mm"
        ));
    }
    Ok(shape)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_number_outside_its_range_is_named_with_the_range() {
        assert_eq!(arg("--ap", 0.3, Range::positive(5.0, "mm")), Ok(0.3));
        assert_eq!(
            arg("--ap", -1.0, Range::positive(5.0, "mm")),
            Err("--ap -1: must be a number above 0 and at most 5 mm".to_string())
        );
        assert_eq!(
            arg("--n", 1e-300, Range::from(1.0, 10.0, "")),
            Err("--n 1e-300: must be a number from 1 to 10".to_string())
        );
        assert!(arg("--n", f64::NAN, Range::from(1.0, 10.0, "")).is_err());
        assert!(tool_shape("--tool", "ball:2000").is_err());
        assert!(tool_shape("--tool", "ball:10").is_ok());
    }
}
