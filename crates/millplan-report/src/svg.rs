//! Small, dependency-free SVG plots: line plots, histograms and a top-view map
//! coloured by a value. Large series are thinned to a few thousand points.

use std::fmt::Write;

const W: f64 = 760.0;
const H: f64 = 300.0;
const ML: f64 = 64.0;
const MR: f64 = 16.0;
const MT: f64 = 44.0;
const MB: f64 = 44.0;

/// A series: name, colour and (x, y) points.
pub struct Series<'a> {
    pub name: &'a str,
    pub color: &'a str,
    pub points: Vec<(f64, f64)>,
}

fn nice_step(span: f64, target: usize) -> f64 {
    if !(span > 0.0) {
        return 1.0;
    }
    let raw = span / target as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let n = raw / mag;
    let m = if n < 1.5 {
        1.0
    } else if n < 3.5 {
        2.0
    } else if n < 7.5 {
        5.0
    } else {
        10.0
    };
    m * mag
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        ML + (x - self.x0) / (self.x1 - self.x0).max(1e-12) * (W - ML - MR)
    }
    fn py(&self, y: f64) -> f64 {
        H - MB - (y - self.y0) / (self.y1 - self.y0).max(1e-12) * (H - MT - MB)
    }
}

fn axes(s: &mut String, f: &Frame, title: &str, xlabel: &str, ylabel: &str) {
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {W} {H}" width="{W}" height="{H}" font-family="sans-serif" font-size="11">"#
    );
    let _ = write!(
        s,
        r#"<rect x="0" y="0" width="{W}" height="{H}" fill="white"/>"#
    );
    let _ = write!(
        s,
        r#"<text x="{}" y="16" font-size="13" font-weight="bold">{}</text>"#,
        ML,
        esc(title)
    );
    let xs = nice_step(f.x1 - f.x0, 8);
    let mut x = (f.x0 / xs).ceil() * xs;
    while x <= f.x1 + 1e-9 {
        let p = f.px(x);
        let _ = write!(
            s,
            r##"<line x1="{p:.1}" y1="{}" x2="{p:.1}" y2="{}" stroke="#eee"/><text x="{p:.1}" y="{}" text-anchor="middle">{}</text>"##,
            MT,
            H - MB,
            H - MB + 14.0,
            fmt_tick(x, xs)
        );
        x += xs;
    }
    let ys = nice_step(f.y1 - f.y0, 6);
    let mut y = (f.y0 / ys).ceil() * ys;
    while y <= f.y1 + 1e-9 {
        let p = f.py(y);
        let _ = write!(
            s,
            r##"<line x1="{ML}" y1="{p:.1}" x2="{}" y2="{p:.1}" stroke="#eee"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            W - MR,
            ML - 4.0,
            p + 4.0,
            fmt_tick(y, ys)
        );
        y += ys;
    }
    let _ = write!(
        s,
        r##"<rect class="plot-area" x="{ML}" y="{MT}" width="{}" height="{}" fill="none" stroke="#444"/>"##,
        W - ML - MR,
        H - MT - MB
    );
    let _ = write!(
        s,
        r#"<text class="axis-label" x="{}" y="{}" text-anchor="middle">{}</text>"#,
        (ML + W - MR) / 2.0,
        H - 8.0,
        esc(xlabel)
    );
    let _ = write!(
        s,
        r#"<text class="axis-label" transform="translate(14,{}) rotate(-90)" text-anchor="middle">{}</text>"#,
        (MT + H - MB) / 2.0,
        esc(ylabel)
    );
}

fn fmt_tick(v: f64, step: f64) -> String {
    let t = if step >= 1.0 {
        format!("{:.0}", v)
    } else {
        let d = (-step.log10().floor()) as usize;
        format!("{:.*}", d, v)
    };
    // A tick at zero reads 0, never -0 (or -0.00).
    if t.starts_with('-') && t[1..].bytes().all(|b| b == b'0' || b == b'.') {
        t[1..].to_string()
    } else {
        t
    }
}

fn thin(points: &[(f64, f64)], max: usize) -> Vec<(f64, f64)> {
    if points.len() <= max {
        return points.to_vec();
    }
    // Keep the min and max of each bucket so spikes stay visible.
    let bucket = points.len().div_ceil(max / 2);
    let mut out = Vec::with_capacity(max + 2);
    for c in points.chunks(bucket) {
        let lo = c.iter().min_by(|a, b| a.1.total_cmp(&b.1)).copied();
        let hi = c.iter().max_by(|a, b| a.1.total_cmp(&b.1)).copied();
        if let (Some(lo), Some(hi)) = (lo, hi) {
            if lo.0 <= hi.0 {
                out.push(lo);
                out.push(hi);
            } else {
                out.push(hi);
                out.push(lo);
            }
        }
    }
    out
}

fn bounds<'a>(pts: impl Iterator<Item = &'a (f64, f64)>) -> Frame {
    let mut f = Frame {
        x0: f64::INFINITY,
        x1: f64::NEG_INFINITY,
        y0: f64::INFINITY,
        y1: f64::NEG_INFINITY,
    };
    for (x, y) in pts {
        if x.is_finite() && y.is_finite() {
            f.x0 = f.x0.min(*x);
            f.x1 = f.x1.max(*x);
            f.y0 = f.y0.min(*y);
            f.y1 = f.y1.max(*y);
        }
    }
    if !f.x0.is_finite() {
        return Frame {
            x0: 0.0,
            x1: 1.0,
            y0: 0.0,
            y1: 1.0,
        };
    }
    let pad = ((f.y1 - f.y0) * 0.05).max(1e-9);
    Frame {
        y0: f.y0 - pad,
        y1: f.y1 + pad,
        ..f
    }
}

/// Line plot of one or more series.
pub fn line_plot(title: &str, xlabel: &str, ylabel: &str, series: &[Series]) -> String {
    let f = bounds(series.iter().flat_map(|s| s.points.iter()));
    let mut s = String::new();
    axes(&mut s, &f, title, xlabel, ylabel);
    for se in series {
        let pts = thin(&se.points, 4000);
        let mut d = String::with_capacity(pts.len() * 14);
        for (i, (x, y)) in pts.iter().enumerate() {
            let _ = write!(
                d,
                "{}{:.1},{:.1}",
                if i == 0 { "M" } else { "L" },
                f.px(*x),
                f.py(*y)
            );
        }
        let _ = write!(
            s,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1"/>"#,
            se.color
        );
    }
    let names: Vec<(&str, &str)> = series.iter().map(|se| (se.name, se.color)).collect();
    legend_row(&mut s, &names);
    s.push_str("</svg>");
    s
}

/// The legend in one row above the plot frame, never over the data.
fn legend_row(s: &mut String, entries: &[(&str, &str)]) {
    s.push_str(r#"<g class="legend">"#);
    let mut x = ML;
    for (name, color) in entries {
        let _ = write!(
            s,
            r#"<rect x="{x:.1}" y="{}" width="10" height="10" fill="{color}"/><text x="{:.1}" y="{}">{}</text>"#,
            MT - 19.0,
            x + 14.0,
            MT - 10.0,
            esc(name)
        );
        x += 30.0 + 6.5 * name.chars().count() as f64;
    }
    s.push_str("</g>");
}

/// Scatter plot (for value against position).
pub fn scatter(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    color: &str,
    points: &[(f64, f64)],
) -> String {
    let f = bounds(points.iter());
    let mut s = String::new();
    axes(&mut s, &f, title, xlabel, ylabel);
    let step = (points.len() / 6000).max(1);
    for (x, y) in points.iter().step_by(step) {
        let _ = write!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="1.2" fill="{color}" fill-opacity="0.5"/>"#,
            f.px(*x),
            f.py(*y)
        );
    }
    s.push_str("</svg>");
    s
}

/// Overlaid histograms of several samples on common bins.
pub fn histogram(
    title: &str,
    xlabel: &str,
    bins: usize,
    series: &[(&str, &str, Vec<f64>)],
) -> String {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (_, _, v) in series {
        for x in v.iter().filter(|x| x.is_finite()) {
            lo = lo.min(*x);
            hi = hi.max(*x);
        }
    }
    if !lo.is_finite() {
        lo = 0.0;
        hi = 1.0;
    }
    if hi - lo < 1e-9 {
        lo -= 0.5;
        hi += 0.5;
    }
    let w = (hi - lo) / bins as f64;
    let counts: Vec<Vec<usize>> = series
        .iter()
        .map(|(_, _, v)| {
            let mut c = vec![0usize; bins];
            for x in v.iter().filter(|x| x.is_finite()) {
                c[(((x - lo) / w) as usize).min(bins - 1)] += 1;
            }
            c
        })
        .collect();
    let ymax = counts.iter().flatten().copied().max().unwrap_or(1) as f64;
    let f = Frame {
        x0: lo,
        x1: hi,
        y0: 0.0,
        y1: ymax * 1.05,
    };
    let mut s = String::new();
    // The count is of what the series holds: its name when there is one.
    let ylabel = match series {
        [(name, _, _)] => format!("count of {name}"),
        _ => "count".to_string(),
    };
    axes(&mut s, &f, title, xlabel, &ylabel);
    for ((_, color, _), c) in series.iter().zip(&counts) {
        for (b, n) in c.iter().enumerate() {
            if *n == 0 {
                continue;
            }
            let x0 = f.px(lo + w * b as f64);
            let x1 = f.px(lo + w * (b + 1) as f64);
            let y = f.py(*n as f64);
            let _ = write!(
                s,
                r#"<rect x="{x0:.1}" y="{y:.1}" width="{:.1}" height="{:.1}" fill="{color}" fill-opacity="0.55"/>"#,
                (x1 - x0 - 0.5).max(0.5),
                f.py(0.0) - y
            );
        }
    }
    let names: Vec<(&str, &str)> = series.iter().map(|(n, c, _)| (*n, *c)).collect();
    legend_row(&mut s, &names);
    s.push_str("</svg>");
    s
}

/// Colour of t ∈ [0, 1] on a blue–green–yellow–red scale.
pub fn colormap(t: f64) -> String {
    let [r, g, b] = colormap_rgb(t);
    format!("rgb({r},{g},{b})")
}

/// [`colormap`] as RGB bytes (a value outside [0, 1] takes the end colour,
/// a non-finite one the low end).
pub fn colormap_rgb(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let stops = [
        (0.0, (49, 54, 149)),
        (0.35, (69, 170, 140)),
        (0.65, (240, 220, 60)),
        (1.0, (215, 48, 39)),
    ];
    for w in stops.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            let u = (t - t0) / (t1 - t0);
            let l = |a: i32, b: i32| (a as f64 + (b - a) as f64 * u).round() as u8;
            return [l(c0.0, c1.0), l(c0.1, c1.1), l(c0.2, c1.2)];
        }
    }
    [215, 48, 39]
}

/// Top view (X right, Y up, equal scales, ticks in mm) of points coloured
/// by a value, with a colour bar. The colours span the 2nd to 98th
/// percentile of the values, so that a thin border of extreme values does
/// not wash out the rest; values beyond take the end colours, and the bar
/// says so with the full range.
pub fn map(title: &str, label: &str, points: &[(f64, f64, f64)]) -> String {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for (x, y, _) in points.iter().filter(|p| p.0.is_finite() && p.1.is_finite()) {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let values: Vec<f64> = points.iter().map(|p| p.2).collect();
    let scale = crate::view3d::robust_scale("", &values);
    let (v0, v1) = scale.as_ref().map_or((0.0, 1.0), |s| (s.lo, s.hi));
    let (left, top, side) = (72.0, 40.0, 500.0);
    let span = (x1 - x0).max(y1 - y0).max(1e-9);
    let sx = |x: f64| left + (x - x0) / span * side;
    let sy = |y: f64| top + side - (y - y0) / span * side;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 760 620" width="760" height="620" font-family="sans-serif" font-size="11"><rect width="760" height="620" fill="white"/><text x="{left}" y="22" font-size="13" font-weight="bold">{}</text>"#,
        esc(title)
    );
    let _ = write!(
        s,
        r##"<rect class="plot-area map-area" x="{left}" y="{top}" width="{side}" height="{side}" fill="none" stroke="#444"/>"##
    );
    let step = nice_step(span, 6);
    let mut x = (x0 / step).ceil() * step;
    while x <= x0 + span + 1e-9 {
        let p = sx(x);
        let _ = write!(
            s,
            r##"<line x1="{p:.1}" y1="{}" x2="{p:.1}" y2="{}" stroke="#444"/><text x="{p:.1}" y="{}" text-anchor="middle">{}</text>"##,
            top + side,
            top + side + 5.0,
            top + side + 18.0,
            fmt_tick(x, step)
        );
        x += step;
    }
    let mut y = (y0 / step).ceil() * step;
    while y <= y0 + span + 1e-9 {
        let p = sy(y);
        let _ = write!(
            s,
            r##"<line x1="{}" y1="{p:.1}" x2="{left}" y2="{p:.1}" stroke="#444"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            left - 5.0,
            left - 8.0,
            p + 4.0,
            fmt_tick(y, step)
        );
        y += step;
    }
    let _ = write!(
        s,
        r#"<text class="axis-label" x="{}" y="{}" text-anchor="middle">X (mm)</text><text class="axis-label" transform="translate(18,{}) rotate(-90)" text-anchor="middle">Y (mm)</text>"#,
        left + side / 2.0,
        top + side + 36.0,
        top + side / 2.0
    );
    let stride = (points.len() / 20000).max(1);
    for (x, y, v) in points.iter().step_by(stride) {
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        let t = (v - v0) / (v1 - v0).max(1e-12);
        let _ = write!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="1.4" fill="{}"/>"#,
            sx(*x),
            sy(*y),
            colormap(t)
        );
    }
    colour_bar(&mut s, label, top, side, scale.as_ref());
    s.push_str("</svg>");
    s
}

/// The colour bar of [`map`] right of the plot, with the clipped range.
fn colour_bar(
    s: &mut String,
    label: &str,
    top: f64,
    side: f64,
    scale: Option<&crate::view3d::Scale>,
) {
    let bx = 610.0;
    for k in 0..50 {
        let t = k as f64 / 49.0;
        let _ = write!(
            s,
            r#"<rect x="{bx}" y="{:.1}" width="18" height="11" fill="{}"/>"#,
            top + side - (k as f64 + 1.0) * side / 50.0,
            colormap(t)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{bx}" y="{}">{}</text>"#,
        top - 8.0,
        esc(label)
    );
    if let Some(sc) = scale {
        let (hi_mark, lo_mark) = (
            if sc.max > sc.hi { "≥ " } else { "" },
            if sc.min < sc.lo { "≤ " } else { "" },
        );
        let _ = write!(
            s,
            r#"<text x="{}" y="{}">{hi_mark}{:.3}</text><text x="{}" y="{}">{lo_mark}{:.3}</text>"#,
            bx + 22.0,
            top + 8.0,
            sc.hi,
            bx + 22.0,
            top + side,
            sc.lo
        );
        let _ = write!(
            s,
            r#"<text x="{bx}" y="{}">colours: 2nd–98th percentile</text><text x="{bx}" y="{}">all values {:.3} … {:.3}</text>"#,
            top + side + 18.0,
            top + side + 32.0,
            sc.min,
            sc.max
        );
    }
}

/// How a direction shows on a sphere map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirClass {
    /// Outside the machine's reach and not needed.
    Out,
    /// Reachable by the machine.
    Reach,
    /// Needed by some facet and reachable.
    Used,
    /// Needed by a facet that no reachable direction serves.
    Missing,
}

/// The unit sphere of tool directions as two Lambert azimuthal equal-area discs
/// (upper hemisphere left, lower right; X right, Y up in each), one dot per grid
/// cell coloured by its class. Equal areas on the sphere stay equal on the page.
/// `limits`: curves of directions (the edges of what a machine's rotary ranges
/// reach) drawn as lines.
pub fn sphere_map(title: &str, cells: &[([f64; 3], DirClass)], limits: &[Vec<[f64; 3]>]) -> String {
    let (r0, cy) = (150.0, 200.0);
    let centres = [190.0, 530.0];
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 720 420" width="720" height="420" font-family="sans-serif" font-size="11"><rect width="720" height="420" fill="white"/><text x="40" y="22" font-size="13" font-weight="bold">{}</text>"#,
        esc(title)
    );
    for (k, cx) in centres.iter().enumerate() {
        let _ = write!(
            s,
            r##"<circle cx="{cx}" cy="{cy}" r="{r0}" fill="#fafafa" stroke="#888"/><circle cx="{cx}" cy="{cy}" r="{:.1}" fill="none" stroke="#ccc" stroke-dasharray="3 3"/><text x="{}" y="{}" text-anchor="middle">{}</text>"##,
            r0 * (2.0f64 * (1.0 - 45f64.to_radians().cos())).sqrt() / 2f64.sqrt(),
            cx,
            cy + r0 + 18.0,
            if k == 0 {
                "upper hemisphere (tool from above), 45° ring dashed"
            } else {
                "lower hemisphere (tool from below)"
            }
        );
    }
    // Lambert: radius √(2(1 − |z|)) reaches √2 at the equator.
    let project = |[x, y, z]: [f64; 3]| {
        let up = z >= 0.0;
        let rho = (2.0 * (1.0 - z.abs())).max(0.0).sqrt() / 2f64.sqrt();
        let h = (x * x + y * y).sqrt().max(1e-300);
        (
            up,
            centres[usize::from(!up)] + r0 * rho * x / h,
            cy - r0 * rho * y / h,
        )
    };
    for (d, class) in cells {
        let (_, px, py) = project(*d);
        let (fill, rad) = match class {
            DirClass::Out => ("#e4e4e4", 1.6),
            DirClass::Reach => ("#9ecae1", 2.2),
            DirClass::Used => ("#08519c", 3.0),
            DirClass::Missing => ("#d62728", 3.2),
        };
        let _ = write!(
            s,
            r#"<circle cx="{px:.1}" cy="{py:.1}" r="{rad}" fill="{fill}"/>"#
        );
    }
    // The limits, each curve cut where it passes to the other hemisphere.
    for curve in limits {
        let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
        let mut side = None;
        for d in curve {
            let (up, px, py) = project(*d);
            if side != Some(up) {
                pieces.push(Vec::new());
                side = Some(up);
            }
            if let Some(p) = pieces.last_mut() {
                p.push((px, py));
            }
        }
        for p in pieces.iter().filter(|p| p.len() > 1) {
            let pts: Vec<String> = p.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
            let _ = write!(
                s,
                r##"<polyline class="limit" points="{}" fill="none" stroke="#111" stroke-width="1.5"/>"##,
                pts.join(" ")
            );
        }
    }
    if !limits.is_empty() {
        s.push_str(r##"<line x1="680" y1="22" x2="700" y2="22" stroke="#111" stroke-width="1.5"/><text x="676" y="26" text-anchor="end">machine's rotary limits</text>"##);
    }
    let legend = [
        ("#9ecae1", "reachable"),
        ("#08519c", "used by a facet"),
        ("#d62728", "needed, out of reach"),
        ("#e4e4e4", "not reachable"),
    ];
    for (i, (c, t)) in legend.iter().enumerate() {
        let x = 40.0 + 160.0 * i as f64;
        let _ = write!(
            s,
            r#"<circle cx="{x}" cy="404" r="5" fill="{c}"/><text x="{}" y="408">{t}</text>"#,
            x + 9.0
        );
    }
    s.push_str("</svg>");
    s
}

#[cfg(test)]
mod tests {
    /// Issue 18: axis ticks read "-0".
    #[test]
    fn zero_ticks_have_no_sign() {
        assert_eq!(super::fmt_tick(-0.0, 1.0), "0");
        assert_eq!(super::fmt_tick(-1e-12, 0.25), "0.0");
        assert_eq!(super::fmt_tick(-0.5, 0.25), "-0.5");
        assert_eq!(super::fmt_tick(-20.0, 10.0), "-20");
    }

    use super::*;

    #[test]
    fn sphere_map_puts_poles_at_the_centres_and_the_equator_on_the_rim() {
        let svg = sphere_map(
            "s",
            &[
                ([0.0, 0.0, 1.0], DirClass::Used),
                ([1.0, 0.0, 0.0], DirClass::Reach),
                ([0.0, 0.0, -1.0], DirClass::Missing),
                ([0.0, -1.0, 0.0], DirClass::Out),
            ],
            &[vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]],
        );
        // A limit from the upper pole to the equator, then on in the lower
        // hemisphere: two pieces.
        assert!(svg.contains(r#"points="190.0,200.0 340.0,200.0""#), "{svg}");
        assert_eq!(svg.matches("<polyline").count(), 1, "{svg}");
        assert!(
            svg.contains(r##"cx="190.0" cy="200.0" r="3" fill="#08519c""##),
            "{svg}"
        );
        assert!(svg.contains(r##"cx="340.0" cy="200.0" r="2.2""##), "{svg}");
        assert!(svg.contains(r##"cx="530.0" cy="200.0" r="3.2""##), "{svg}");
        assert!(svg.contains(r##"cx="190.0" cy="350.0" r="1.6""##), "{svg}");
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
    }

    /// The number after `key="` in `svg` at each of its places.
    fn attrs(svg: &str, key: &str) -> Vec<f64> {
        svg.split(&format!(" {key}=\""))
            .skip(1)
            .filter_map(|r| r.split('"').next()?.parse().ok())
            .collect()
    }

    /// Every legend entry of a line plot and a histogram lies above the
    /// plot's area, never over its data; the histogram's count is of what
    /// its legend names (it read "points" over a legend of "facets").
    #[test]
    fn legends_stay_outside_the_data_and_labels_agree() {
        let pts: Vec<(f64, f64)> = (0..50).map(|i| (i as f64, i as f64)).collect();
        let series = |name, color| Series {
            name,
            color,
            points: pts.clone(),
        };
        let plot = line_plot(
            "p",
            "time [s]",
            "F [N]",
            &[series("input", "#1f77b4"), series("limit", "#000000")],
        );
        let hist = histogram(
            "Material left",
            "mm",
            30,
            &[("facets", "#1f77b4", vec![0.1, 0.2, 0.5])],
        );
        for svg in [&plot, &hist] {
            let area_top = svg
                .split(r#"class="plot-area" x=""#)
                .nth(1)
                .and_then(|r| attrs(r, "y").first().copied())
                .expect("plot area");
            let legend = svg.split(r#"<g class="legend">"#).nth(1).expect("legend");
            let legend = legend.split("</g>").next().expect("legend end");
            let ys = attrs(legend, "y");
            assert!(!ys.is_empty(), "{svg}");
            assert!(ys.iter().all(|y| *y <= area_top), "{ys:?} over {area_top}");
        }
        assert!(hist.contains(">count of facets<"), "{hist}");
        assert!(
            hist.contains(">facets<") && !hist.contains("points"),
            "{hist}"
        );
        assert!(hist.contains(">mm<"), "{hist}");
    }

    /// A top-view map names both axes in mm, puts ticks on them and colours
    /// by the 2nd–98th percentile: a thin border of large values does not
    /// set the scale, and the bar shows the clipped end (`≥`) and every
    /// value's range.
    #[test]
    fn maps_have_axes_in_mm_and_a_robust_clipped_scale() {
        let mut pts: Vec<(f64, f64, f64)> = (0..1000)
            .map(|i| ((i % 40) as f64, (i / 40) as f64, 0.1 + 0.0001 * i as f64))
            .collect();
        pts.extend((0..10).map(|i| (i as f64, -1.0, 5.0)));
        let svg = map("Material left", "left mm", &pts);
        assert!(
            svg.contains(">X (mm)<") && svg.contains(">Y (mm)<"),
            "{svg}"
        );
        assert_eq!(svg.matches(r#"class="axis-label""#).count(), 2);
        assert!(svg.contains(">colours: 2nd–98th percentile<"), "{svg}");
        assert!(svg.contains(">all values 0.100 … 5.000<"), "{svg}");
        let hi = svg
            .split(">≥ ")
            .nth(1)
            .and_then(|r| r.split('<').next())
            .and_then(|t| t.parse::<f64>().ok())
            .expect("the clipped top");
        assert!(hi < 0.25, "the border sets the scale: {hi}");
        let ticks = svg.matches(r#"text-anchor="middle">"#).count();
        assert!(ticks >= 4, "{svg}");
    }

    #[test]
    fn plots_are_well_formed_svg() {
        let pts: Vec<(f64, f64)> = (0..10000)
            .map(|i| (i as f64, (i as f64 * 0.01).sin()))
            .collect();
        for svg in [
            line_plot(
                "t",
                "x",
                "y",
                &[Series {
                    name: "a",
                    color: "#1f77b4",
                    points: pts.clone(),
                }],
            ),
            scatter("t", "x", "y", "#000", &pts),
            histogram(
                "h",
                "x",
                20,
                &[("a", "#f00", pts.iter().map(|p| p.1).collect())],
            ),
            map(
                "m",
                "v",
                &pts.iter().map(|p| (p.0, p.1, p.1)).collect::<Vec<_>>(),
            ),
        ] {
            assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
            assert!(!svg.contains("NaN") && !svg.contains("inf"));
        }
        assert_eq!(nice_step(10.0, 5), 2.0);
        assert_eq!(colormap(0.0), "rgb(49,54,149)");
    }
}
