//! Back ends: G-code dialects and APT/CL. Writers produce bytes; the binary puts
//! them in files (through a temporary file and a rename).

pub mod apt;
pub mod gcode;

use crate::ir::*;
use millplan_geom::DVec3;

/// Something the target cannot express, which stops writing.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct WriteError {
    pub message: String,
}

/// Where finished text goes while a large program is written: about every
/// [`FLUSH_AT`] bytes the writer hands its buffer's contents over and goes on
/// in the same buffer, so a program of any size is written in a few
/// megabytes. What is left at the end stays in the buffer for the caller.
pub type Sink<'a> = &'a mut dyn FnMut(&[u8]) -> Result<(), WriteError>;

/// Buffer size at which a writer with a [`Sink`] hands its text over.
pub const FLUSH_AT: usize = 1 << 22;

/// Hands `out` to `sink` once it holds [`FLUSH_AT`] bytes.
#[inline]
fn maybe_flush(out: &mut Vec<u8>, sink: &mut Option<Sink>) -> Result<(), WriteError> {
    if let Some(s) = sink {
        if out.len() >= FLUSH_AT {
            s(out)?;
            out.clear();
        }
    }
    Ok(())
}

/// Room a writer reserves for `moves` moves of about `per` bytes each: all of
/// it without a sink, a flush's worth with one.
fn room(moves: usize, per: usize, sink: &Option<Sink>) -> usize {
    let all = moves * per + 1024;
    if sink.is_some() {
        all.min(FLUSH_AT + (1 << 16))
    } else {
        all
    }
}

/// Fast fixed-decimal number formatting with trailing zeros removed
/// (`12.5`, `-0.25`, `3`), the inner loop of every writer.
#[derive(Clone, Copy, Debug)]
pub struct NumFmt {
    pub decimals: u32,
    /// Keep a trailing decimal point on whole numbers (`3.`), as Fanuc wants.
    pub trailing_point: bool,
    /// Write `+` on positive numbers (Heidenhain).
    pub plus: bool,
    /// Drop the leading zero (`.5`).
    pub no_leading_zero: bool,
}

impl NumFmt {
    pub fn push(&self, out: &mut Vec<u8>, v: f64) {
        let scale = 10u64.pow(self.decimals) as f64;
        let r = (v * scale).round();
        if !r.is_finite() || r.abs() >= 9.0e18 {
            out.extend_from_slice(format!("{v}").as_bytes());
            return;
        }
        let neg = r < 0.0;
        let mut n = r.abs() as u64;
        let div = 10u64.pow(self.decimals);
        let int = n / div;
        n %= div;
        if neg && (int != 0 || n != 0) {
            out.push(b'-');
        } else if self.plus {
            out.push(b'+');
        }
        if int != 0 || !self.no_leading_zero || n == 0 {
            push_uint(out, int);
        }
        let mut d = self.decimals;
        let mut frac = n;
        while d > 0 && frac.is_multiple_of(10) {
            frac /= 10;
            d -= 1;
        }
        if d > 0 {
            out.push(b'.');
            let s = frac;
            let mut digits = [b'0'; 20];
            let mut x = s;
            for k in (0..d as usize).rev() {
                digits[k] = b'0' + (x % 10) as u8;
                x /= 10;
            }
            out.extend_from_slice(&digits[..d as usize]);
        } else if self.trailing_point {
            out.push(b'.');
        }
    }
}

/// Appends the decimal digits of `v` (no allocation: this runs for every
/// number of every block).
fn push_uint(out: &mut Vec<u8>, mut v: u64) {
    let mut b = [0u8; 20];
    let mut i = b.len();
    loop {
        i -= 1;
        b[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&b[i..]);
}

/// Is this arc in a principal plane (normal along ±X, ±Y or ±Z)? Returns the axis index.
pub fn principal_plane(a: &Arc) -> Option<usize> {
    let n = a.normal.abs();
    (0..3).find(|&k| (n[k] - 1.0).abs() < 1e-9)
}

/// Points (after the start) that follow an arc within `tol`.
pub fn arc_points(a: &Arc, start: DVec3, end: DVec3, tol: f64) -> Vec<DVec3> {
    let step = if a.radius > tol {
        2.0 * (1.0 - tol / a.radius).acos()
    } else {
        a.sweep
    };
    let n = ((a.sweep / step.max(1e-6)).ceil() as usize).clamp(1, 100_000);
    (1..=n)
        .map(|k| {
            if k == n {
                end
            } else {
                a.point_at(start, end, k as f64 / n as f64)
            }
        })
        .collect()
}

/// Explicit moves (rapid, feed down with pecks, rapid out) for one hole of a cycle,
/// along the tool axis `axis` from the cycle point `p`.
pub fn cycle_moves(c: &Cycle, p: DVec3, axis: DVec3) -> Vec<(MoveKind, DVec3, f64)> {
    let at = |h: f64| p + axis * h;
    let mut v = vec![(MoveKind::Rapid, at(c.clearance.max(c.bottom)), 0.0)];
    let total = c.clearance - c.bottom;
    match c.peck {
        Some(q) if q > 0.0 && q < total => {
            let mut depth = c.clearance;
            while depth - q > c.bottom + 1e-9 {
                depth -= q;
                v.push((MoveKind::Linear, at(depth), c.feed));
                v.push((MoveKind::Rapid, at(c.clearance), 0.0));
                v.push((MoveKind::Rapid, at(depth + 0.5_f64.min(q / 2.0)), 0.0));
            }
            v.push((MoveKind::Linear, at(c.bottom), c.feed));
        }
        _ => v.push((MoveKind::Linear, at(c.bottom), c.feed)),
    }
    v.push((MoveKind::Rapid, at(c.retract.max(c.clearance)), 0.0));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_handed_to_a_sink_is_the_text_written_whole() {
        use crate::generate::{raster, Raster};
        use millplan_geom::analytic::DemoSurface;
        // About 460,000 moves: several flushes in both writers.
        let (p, _) = raster(
            &DemoSurface::default(),
            &Raster {
                stepover: 0.25,
                step: 0.03,
                ..Raster::default()
            },
        );
        assert!(p.move_count() > 400_000);
        type Write = fn(&Program, &mut Vec<u8>, Option<Sink>) -> Result<(), WriteError>;
        let writers: [Write; 2] = [
            |p, out, sink| apt::write_apt_to(p, out, sink),
            |p, out, sink| {
                gcode::write_gcode_to(p, gcode::GcodeOptions::new(Dialect::Fanuc), out, sink)
            },
        ];
        for w in writers {
            let mut whole = Vec::new();
            w(&p, &mut whole, None).expect("writes");
            assert!(whole.len() > 2 * FLUSH_AT);
            let (mut streamed, mut flushes) = (Vec::new(), 0);
            let mut buf = Vec::new();
            {
                let mut sink = |b: &[u8]| {
                    flushes += 1;
                    streamed.extend_from_slice(b);
                    Ok(())
                };
                w(&p, &mut buf, Some(&mut sink)).expect("writes");
            }
            streamed.extend_from_slice(&buf);
            assert!(flushes >= 2 && buf.len() < FLUSH_AT + (1 << 16));
            assert!(streamed == whole, "streamed text differs");
            // A sink that fails stops the writer with its error.
            let mut fail = |_: &[u8]| {
                Err(WriteError {
                    message: "disk full".into(),
                })
            };
            let e = w(&p, &mut Vec::new(), Some(&mut fail)).expect_err("fails");
            assert_eq!(e.message, "disk full");
        }
    }

    fn f(v: f64, decimals: u32, tp: bool, plus: bool, nlz: bool) -> String {
        let mut o = Vec::new();
        NumFmt {
            decimals,
            trailing_point: tp,
            plus,
            no_leading_zero: nlz,
        }
        .push(&mut o, v);
        String::from_utf8(o).expect("ascii")
    }

    #[test]
    fn formats_numbers() {
        assert_eq!(f(12.5, 4, false, false, false), "12.5");
        assert_eq!(f(-0.25, 4, false, false, true), "-.25");
        assert_eq!(f(3.0, 4, true, false, false), "3.");
        assert_eq!(f(-0.00001, 4, false, false, false), "0");
        assert_eq!(f(1.23456789, 4, false, true, false), "+1.2346");
        assert_eq!(f(-120.2591, 4, false, false, false), "-120.2591");
        assert_eq!(f(0.0, 3, true, false, true), "0.");
    }
}
