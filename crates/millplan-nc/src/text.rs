//! The IR's printable text form, used by golden tests and `millplan inspect --ir`.
//! One line per operation header, move and event, numbers to 4 decimals.

use crate::ir::*;
use millplan_geom::DVec3;
use std::fmt::Write;

fn v3(v: DVec3) -> String {
    format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z)
}

/// Prints a program in the IR's text form.
pub fn print(p: &Program) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "program {} dialect={} units={:?}/{:?}",
        p.name.as_deref().unwrap_or("-"),
        p.dialect.name(),
        p.units.source,
        p.units.origin
    );
    for (oi, op) in p.operations.iter().enumerate() {
        let _ = write!(s, "op {oi} name={}", op.name.as_deref().unwrap_or("-"));
        match &op.tool {
            Some(t) => {
                let _ = write!(
                    s,
                    " tool=T{}",
                    t.number.map(|n| n.to_string()).unwrap_or("?".into())
                );
                if let Some(n) = &t.name {
                    let _ = write!(s, " \"{n}\"");
                }
                if let Some(c) = &t.cutter {
                    let _ = write!(
                        s,
                        " {:?} d={:.4} r={:.4} e={:.4} f={:.4} a={:.2}deg b={:.2}deg h={:.4}",
                        c.kind,
                        c.d,
                        c.r,
                        c.e,
                        c.f,
                        c.alpha.to_degrees(),
                        c.beta.to_degrees(),
                        c.h
                    );
                }
            }
            None => s.push_str(" tool=none"),
        }
        s.push('\n');
        if let Some(f) = &op.frame {
            let _ = writeln!(
                s,
                "  frame origin={} x={} y={} z={}",
                v3(f.origin),
                v3(f.rot.x_axis),
                v3(f.rot.y_axis),
                v3(f.rot.z_axis)
            );
        }
        if let Some(st) = op.start {
            let _ = writeln!(s, "  start {}", v3(st));
        }
        let mut ev = op.events.iter().peekable();
        for (i, m) in op.moves.iter().enumerate() {
            while let Some(e) = ev.next_if(|e| e.at as usize <= i) {
                print_event(&mut s, e);
            }
            let _ = write!(s, "  L{} {:?} {}", m.line, m.kind, v3(m.end));
            match m.kind {
                MoveKind::Arc => {
                    if let Some(a) = op.arcs.get(m.aux as usize) {
                        let _ = write!(
                            s,
                            " centre={} normal={} r={:.4} sweep={:.3}deg",
                            v3(a.centre),
                            v3(a.normal),
                            a.radius,
                            a.sweep.to_degrees()
                        );
                    }
                }
                MoveKind::Cycle => {
                    if let Some(c) = op.cycles.get(m.aux as usize) {
                        let _ = write!(
                            s,
                            " cycle={} bottom={:.4} clear={:.4} retract={:.4} F{:.4}",
                            c.name, c.bottom, c.clearance, c.retract, c.feed
                        );
                    }
                }
                _ => {}
            }
            match op.orient(m) {
                Some(Orient::Vector(v)) => {
                    let _ = write!(s, " axis={}", v3(*v));
                }
                Some(Orient::Rotary(r)) => {
                    let f = |x: Option<f64>| {
                        x.map(|v| format!("{:.3}", v.to_degrees()))
                            .unwrap_or("-".into())
                    };
                    let _ = write!(s, " abc=({}, {}, {})", f(r[0]), f(r[1]), f(r[2]));
                }
                None => {}
            }
            if m.is_cutting() {
                let _ = write!(s, " F{:.4}", m.feed);
                if m.feed_mode != FeedMode::PerMinute {
                    let _ = write!(s, "/{:?}", m.feed_mode);
                }
            }
            let _ = writeln!(s, " S{:.1}", m.spindle);
        }
        for e in ev {
            print_event(&mut s, e);
        }
    }
    s
}

fn print_event(s: &mut String, e: &Event) {
    let _ = writeln!(s, "  L{} event {:?}", e.line, e.kind);
}
