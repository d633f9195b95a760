//! ISO 965-1 tolerance classes of ISO general purpose metric threads from the
//! standard's tables (spec `kinematics-access-tools.md` §4.7: "Implement
//! tables, not the formula").
//!
//! A class such as `6H`, `5H`, `6G`, `4h`, `6g` or `4H5H` (pitch-diameter
//! tolerance first, crest-diameter tolerance second) gives limits of size
//! from the basic profile (ISO 724), a fundamental deviation (EI for G/H, es
//! for g/h) and the tolerances T_D2, T_D1 (internal) or T_d2, T_d (external).
//!
//! # Where the numbers come from
//!
//! The standard's own text is not reproduced here: every value below was
//! taken only when two independent public sources state it (or one states it and a second
//! one's published limits of size reproduce it and no neighbouring R 40
//! value does). A value that one source alone gives is left out (0 in the
//! tables) and a class that needs it is refused with the reason.
//!
//! - MH31: Machinery's Handbook, 31st ed. (2025), Table 11 "ANSI Standard
//!   Pitch-Diameter Tolerances of External Metric Threads, Td2, ISO 965/1,
//!   ASME B1.13M-2005", <https://online.flippingbook.com/view/954046886/655/>.
//!   Confirms every T_d2 row of the ranges 1.4–22.4 mm and the rows P = 1,
//!   1.5, 2 and 3 of 22.4–45 mm (grades 4–8).
//! - MH27: Machinery's Handbook, 27th ed., Table 8 "Minor Diameter
//!   Tolerances of Internal Metric Threads TD1, ISO 965/1",
//!   <https://www.yumpu.com/en/document/view/11356742/threads-and-threading-sportpilotinfo/74>.
//!   Confirms T_D1 for P = 0.2 to 0.7 (grades 4–8).
//! - BS: a transcription of BS ISO 965-1 Tables 1 and 3–6 (fundamental
//!   deviations, T_D1, T_d, T_D2, T_d2) in
//!   <https://github.com/Bob-SpringMtTech/Engineering>, `Threads.py`, class
//!   `ThreadM`, commit 386b73f. The one source with every table; it carries
//!   typing errors that the others expose (T_d2 grade 9 at 11.2–22.4 mm,
//!   P = 1.25 reads 365 where MH31 gives 265; its f column repeats the e
//!   column from P = 0.5 on and its e column has lost signs), so no value
//!   rests on it alone.
//! - TL: limits of size of classes 6H and 6g, M0.25–M600, in
//!   <https://github.com/adrianschlatter/threadlib>, `design/metric_thread.csv`,
//!   commit 3830919 ("the numbers given in the norm"). Internal limits to
//!   0.001 mm confirm T_D2(6) and T_D1(6) of every row; external limits are
//!   printed to 0.01 mm above M10 and confirm T_d2(6) and T_d(6) only where no
//!   neighbouring R 40 value would print the same. It has its own slips
//!   (M2.6×0.45, M5.5×0.5, M9×1, M11×1.5, M18×2.5, M33×3.5, M52×5 disagree
//!   with its neighbours of the same row; see the tests).
//! - YA: Yamawa tap catalogue 2021, "Comparison of pitch diameter tolerance"
//!   (4H, 5H and 6H T_D2 and the 6G EI of the coarse sizes M1.6–M9),
//!   <http://docs.steelcam.org/yamawa/obshij-katalog-yamawa-2021-page645>.
//! - AS: ASME B1.13M limits of 6g and 4g6g external threads M1.6–M10 with
//!   their allowance (es) and tolerance columns, "Metric Pitch Diameter Roll
//!   Threads", <https://scribd.com/document/604040407/Metric-Pitch-Diameter-Roll-Threads>.
//!
//! Fundamental deviations: the standard's formula es(g) = −(15 + 11P) µm,
//! rounded to the R 40 series, reproduces BS at every pitch but P = 0.75
//! (formula 24, BS and AS 22). It counts as the second source for the g/G
//! deviation at P = 0.2, 0.25 and 1.75–6, where no second table was found;
//! rounded to the micrometre instead of R 40 it is wrong at P = 2 (37 against
//! 38) and P = 4 (59 against 60). The e and f positions are not offered: BS
//! is the only table found and its e and f columns are the corrupted ones.

use crate::thread::ThreadError;

/// The basic major diameter ranges of Tables 4 and 5, mm: over the first,
/// up to and including the second.
pub const RANGES: [(f64, f64); 6] = [
    (1.4, 2.8),
    (2.8, 5.6),
    (5.6, 11.2),
    (11.2, 22.4),
    (22.4, 45.0),
    (45.0, 90.0),
];

/// Tolerances of grades 4 to 8 (index = grade − 4), µm; 0 where the standard
/// has none or no second source confirmed one.
type Grades = [u16; 5];

/// Per pitch (µm): the g/G fundamental deviation |es| = EI (µm), T_D1 grades
/// 4–8 and T_d grades 4, 6, 8 (µm).
///
/// g/G: BS and AS for P = 0.35–1.5 (YA agrees for the coarse pitches), BS and
/// the R 40 formula for the others. T_D1: BS and MH27 for P ≤ 0.7, BS and
/// TL (6H minor diameters) for grade 6 of every pitch. T_d(6): BS and AS for
/// P ≤ 1.5, BS and TL (6g major diameters, unique at their precision) for
/// P = 2–4.5, 5.5 and 6; P = 1.75 and 5 are printed too coarsely in TL to
/// decide between R 40 neighbours and are left out, as are grades 4 and 8.
const BY_PITCH: &[(u32, u16, Grades, [u16; 3])] = &[
    (200, 17, [38, 0, 0, 0, 0], [0, 0, 0]),
    (250, 18, [45, 56, 0, 0, 0], [0, 0, 0]),
    (350, 19, [63, 80, 100, 0, 0], [0, 85, 0]),
    (400, 19, [71, 90, 112, 0, 0], [0, 95, 0]),
    (450, 20, [80, 100, 125, 0, 0], [0, 100, 0]),
    (500, 20, [90, 112, 140, 180, 0], [0, 106, 0]),
    (600, 21, [100, 125, 160, 200, 0], [0, 125, 0]),
    (700, 22, [112, 140, 180, 224, 0], [0, 140, 0]),
    (750, 22, [0, 0, 190, 0, 0], [0, 140, 0]),
    (800, 24, [0, 0, 200, 0, 0], [0, 150, 0]),
    (1000, 26, [0, 0, 236, 0, 0], [0, 180, 0]),
    (1250, 28, [0, 0, 265, 0, 0], [0, 212, 0]),
    (1500, 32, [0, 0, 300, 0, 0], [0, 236, 0]),
    (1750, 34, [0, 0, 335, 0, 0], [0, 0, 0]),
    (2000, 38, [0, 0, 375, 0, 0], [0, 280, 0]),
    (2500, 42, [0, 0, 450, 0, 0], [0, 335, 0]),
    (3000, 48, [0, 0, 500, 0, 0], [0, 375, 0]),
    (3500, 53, [0, 0, 560, 0, 0], [0, 425, 0]),
    (4000, 60, [0, 0, 600, 0, 0], [0, 475, 0]),
    (4500, 63, [0, 0, 670, 0, 0], [0, 500, 0]),
    (5000, 71, [0, 0, 710, 0, 0], [0, 0, 0]),
    (5500, 75, [0, 0, 750, 0, 0], [0, 560, 0]),
    (6000, 80, [0, 0, 800, 0, 0], [0, 600, 0]),
];

/// Per diameter range (index into [`RANGES`]) and pitch (µm): T_d2 and T_D2,
/// grades 4–8 (µm). These rows are the pitches the standard tabulates for
/// the range (those of ISO 261's coarse and fine series).
///
/// T_d2: BS and MH31 for every grade MH31 shows (ranges 0–3, and P = 1, 1.5,
/// 2, 3 of range 4; MH31's last figure of P = 3, grade 8 is cut to "0.31",
/// which only R 40's 0.315 fits). Grade 6 of the other rows: BS and TL (6g
/// pitch diameters, unique at their precision).
/// T_D2: grade 6 of every row from BS and TL (6H pitch diameters; TL's
/// M14, M16 and M18 ×1.25 rows read 170 where its M12×1.25 row and BS read
/// 180, see the tests); grades 4 and 5 from BS and YA for the coarse rows
/// YA lists. Grades 7 and 8 of T_D2 were found in BS only.
const BY_RANGE: &[(u8, u32, Grades, Grades)] = &[
    (0, 200, [32, 40, 50, 0, 0], [0, 0, 0, 0, 0]),
    (0, 250, [36, 45, 56, 0, 0], [0, 0, 0, 0, 0]),
    (0, 350, [40, 50, 63, 80, 0], [53, 67, 85, 0, 0]),
    (0, 400, [42, 53, 67, 85, 0], [56, 71, 90, 0, 0]),
    (0, 450, [45, 56, 71, 90, 0], [60, 75, 95, 0, 0]),
    (1, 350, [42, 53, 67, 85, 0], [0, 0, 90, 0, 0]),
    (1, 500, [48, 60, 75, 95, 0], [63, 80, 100, 0, 0]),
    (1, 600, [53, 67, 85, 106, 0], [71, 90, 112, 0, 0]),
    (1, 700, [56, 71, 90, 112, 0], [75, 95, 118, 0, 0]),
    (1, 750, [56, 71, 90, 112, 0], [75, 95, 118, 0, 0]),
    (1, 800, [60, 75, 95, 118, 150], [80, 100, 125, 0, 0]),
    (2, 750, [63, 80, 100, 125, 0], [0, 0, 132, 0, 0]),
    (2, 1000, [71, 90, 112, 140, 180], [95, 118, 150, 0, 0]),
    (2, 1250, [75, 95, 118, 150, 190], [100, 125, 160, 0, 0]),
    (2, 1500, [85, 106, 132, 170, 212], [0, 0, 180, 0, 0]),
    (3, 1000, [75, 95, 118, 150, 190], [0, 0, 160, 0, 0]),
    (3, 1250, [85, 106, 132, 170, 212], [0, 0, 180, 0, 0]),
    (3, 1500, [90, 112, 140, 180, 224], [0, 0, 190, 0, 0]),
    (3, 1750, [95, 118, 150, 190, 236], [0, 0, 200, 0, 0]),
    (3, 2000, [100, 125, 160, 200, 250], [0, 0, 212, 0, 0]),
    (3, 2500, [106, 132, 170, 212, 265], [0, 0, 224, 0, 0]),
    (4, 1000, [80, 100, 125, 160, 200], [0, 0, 170, 0, 0]),
    (4, 1500, [95, 118, 150, 190, 236], [0, 0, 200, 0, 0]),
    (4, 2000, [106, 132, 170, 212, 265], [0, 0, 224, 0, 0]),
    (4, 3000, [125, 160, 200, 250, 315], [0, 0, 265, 0, 0]),
    (4, 3500, [0, 0, 212, 0, 0], [0, 0, 280, 0, 0]),
    (4, 4000, [0, 0, 224, 0, 0], [0, 0, 300, 0, 0]),
    (4, 4500, [0, 0, 236, 0, 0], [0, 0, 315, 0, 0]),
    (5, 1500, [0, 0, 160, 0, 0], [0, 0, 212, 0, 0]),
    (5, 2000, [0, 0, 180, 0, 0], [0, 0, 236, 0, 0]),
    (5, 3000, [0, 0, 212, 0, 0], [0, 0, 280, 0, 0]),
    (5, 4000, [0, 0, 236, 0, 0], [0, 0, 315, 0, 0]),
    (5, 5000, [0, 0, 250, 0, 0], [0, 0, 335, 0, 0]),
    (5, 5500, [0, 0, 265, 0, 0], [0, 0, 355, 0, 0]),
    (5, 6000, [0, 0, 280, 0, 0], [0, 0, 375, 0, 0]),
];

/// One half of a class: a tolerance grade and a position letter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Tolerance {
    pub grade: u8,
    pub position: char,
}

/// A tolerance class: `6H` (both halves alike) or `4H5H` (pitch diameter 4H,
/// minor diameter 5H); `5g6g` for an external thread.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Class {
    /// Tolerance of the pitch diameter.
    pub pitch: Tolerance,
    /// Tolerance of the crest diameter (minor of an internal thread, major of
    /// an external one).
    pub crest: Tolerance,
}

impl Class {
    /// Parses `6H`, `4H5H`, `6g`, `5g6g` (positions G, H, e, f, g, h; grades
    /// 3–9 are read, the tables decide which exist).
    pub fn parse(s: &str) -> Result<Class, ThreadError> {
        let t = s.trim();
        let bad = || {
            ThreadError::Invalid(format!(
                "`{s}` is not a tolerance class: write a grade and a position, e.g. 6H, 6g, 4H5H"
            ))
        };
        let half = |h: &str| -> Option<Tolerance> {
            let mut c = h.chars();
            let grade = c.next()?.to_digit(10)? as u8;
            let position = c.next()?;
            (c.next().is_none() && (3..=9).contains(&grade) && "GHefgh".contains(position))
                .then_some(Tolerance { grade, position })
        };
        let (pitch, crest) = match t.len() {
            2 => {
                let h = half(t).ok_or_else(bad)?;
                (h, h)
            }
            4 if t.is_ascii() => (
                half(&t[..2]).ok_or_else(bad)?,
                half(&t[2..]).ok_or_else(bad)?,
            ),
            _ => return Err(bad()),
        };
        if pitch.position != crest.position {
            return Err(ThreadError::Invalid(format!(
                "`{s}`: both halves of a class take the same position letter (e.g. 4H5H, 5g6g)"
            )));
        }
        Ok(Class { pitch, crest })
    }

    /// Internal thread (G, H)?
    pub fn internal(&self) -> bool {
        self.pitch.position.is_ascii_uppercase()
    }
}

impl std::fmt::Display for Class {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}{}", self.pitch.grade, self.pitch.position)?;
        if self.crest != self.pitch {
            write!(f, "{}{}", self.crest.grade, self.crest.position)?;
        }
        Ok(())
    }
}

/// Limits of size of a thread in a class, mm.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ClassLimits {
    pub internal: bool,
    /// EI (internal) or es (external), µm.
    pub fundamental_deviation_um: i32,
    /// T_D2 or T_d2, µm.
    pub pitch_tolerance_um: u16,
    /// Pitch diameter D2 or d2: (min, max).
    pub pitch: (f64, f64),
    /// Minor diameter D1 (internal) or major diameter d (external): (min,
    /// max); `None` when the crest tolerance has no confirmed value.
    pub crest: Option<(f64, f64)>,
    /// T_D1 or T_d, µm, when known.
    pub crest_tolerance_um: Option<u16>,
    /// Why `crest` is missing.
    pub crest_missing: Option<String>,
    /// Minimum major diameter of an internal thread (D + EI); the standard
    /// sets no maximum.
    pub major_min: Option<f64>,
}

/// Index of the diameter range holding `d` (over the lower limit, up to and
/// including the upper).
pub fn range_of(d: f64) -> Option<usize> {
    RANGES.iter().position(|&(lo, hi)| d > lo && d <= hi)
}

/// A pitch in whole micrometres, if it is one.
fn pitch_um(p: f64) -> Option<u32> {
    let u = (p * 1000.0).round();
    ((p * 1000.0 - u).abs() < 1e-6 && u > 0.0 && u < 1e7).then_some(u as u32)
}

fn grade_value(g: &Grades, grade: u8) -> Option<u16> {
    let i = usize::from(grade).checked_sub(4)?;
    g.get(i).copied().filter(|&v| v > 0)
}

/// The fundamental deviation |es| = EI of position g/G at pitch `p_um`, µm.
pub fn g_deviation_um(p_um: u32) -> Option<u16> {
    BY_PITCH.iter().find(|r| r.0 == p_um).map(|r| r.1)
}

/// T_D1 (grade 4–8), µm.
pub fn td1_um(p_um: u32, grade: u8) -> Option<u16> {
    BY_PITCH
        .iter()
        .find(|r| r.0 == p_um)
        .and_then(|r| grade_value(&r.2, grade))
}

/// T_d (grades 4, 6, 8), µm.
pub fn td_um(p_um: u32, grade: u8) -> Option<u16> {
    let i = match grade {
        4 => 0,
        6 => 1,
        8 => 2,
        _ => return None,
    };
    BY_PITCH
        .iter()
        .find(|r| r.0 == p_um)
        .map(|r| r.3[i])
        .filter(|&v| v > 0)
}

fn range_row(range: usize, p_um: u32) -> Option<&'static (u8, u32, Grades, Grades)> {
    BY_RANGE
        .iter()
        .find(|r| usize::from(r.0) == range && r.1 == p_um)
}

/// T_d2 (external pitch diameter, grades 4–8), µm.
pub fn td2_um(range: usize, p_um: u32, grade: u8) -> Option<u16> {
    range_row(range, p_um).and_then(|r| grade_value(&r.2, grade))
}

/// T_D2 (internal pitch diameter, grades 4–8), µm.
pub fn td2_internal_um(range: usize, p_um: u32, grade: u8) -> Option<u16> {
    range_row(range, p_um).and_then(|r| grade_value(&r.3, grade))
}

/// Every (range, pitch µm) row of the tables.
pub fn rows() -> impl Iterator<Item = (usize, u32)> {
    BY_RANGE.iter().map(|r| (usize::from(r.0), r.1))
}

/// Every pitch (µm) of the per-pitch table.
pub fn pitches() -> impl Iterator<Item = u32> {
    BY_PITCH.iter().map(|r| r.0)
}

/// A basic diameter D − k·P in whole micrometres (ISO 965-2 prints limits to
/// 0.001 mm; the deviations and tolerances are whole micrometres, so rounding
/// the basic size first is the same as rounding each limit).
fn basic_um(d: f64, p: f64, k: f64) -> i64 {
    ((d - k * p) * 1000.0).round() as i64
}

fn mm(um: i64) -> f64 {
    um as f64 / 1000.0
}

/// Limits of size of `M<d>x<p>` in `class`. An error when the pitch diameter
/// cannot be toleranced from confirmed values (the reason says which value is
/// missing); a crest tolerance without a confirmed value leaves `crest` empty.
pub fn class_limits(d: f64, p: f64, class: &Class) -> Result<ClassLimits, ThreadError> {
    let name = format!("M{d}x{p}");
    let unknown = |why: String| ThreadError::Unknown(name.clone(), class.to_string(), why);
    let range = range_of(d).ok_or_else(|| {
        unknown(format!(
            "the tables here cover basic major diameters over 1.4 up to 90 mm, not {d} mm"
        ))
    })?;
    let (lo, hi) = RANGES[range];
    let pu = pitch_um(p)
        .filter(|&pu| range_row(range, pu).is_some())
        .ok_or_else(|| {
            let listed: Vec<String> = BY_RANGE
                .iter()
                .filter(|r| usize::from(r.0) == range)
                .map(|r| format!("{}", f64::from(r.1) / 1000.0))
                .collect();
            unknown(format!(
                "ISO 965-1 tabulates pitches {} mm for {lo} < D ≤ {hi} mm, not {p}",
                listed.join(", ")
            ))
        })?;
    let position = class.pitch.position;
    let deviation =
        match position {
            'H' | 'h' => 0,
            'G' | 'g' => i32::from(
                g_deviation_um(pu)
                    .ok_or_else(|| unknown(format!("no confirmed g/G deviation for P = {p} mm")))?,
            ),
            _ => return Err(unknown(
                "positions e and f are not available: the one table found for their deviations \
                 is corrupted in those columns (see the sources in the documentation)"
                    .into(),
            )),
        };
    let internal = class.internal();
    let fd = if internal { deviation } else { -deviation };
    let grade = class.pitch.grade;
    let (t2, what) = if internal {
        (td2_internal_um(range, pu, grade), "T_D2")
    } else {
        (td2_um(range, pu, grade), "T_d2")
    };
    let t2 = t2.ok_or_else(|| {
        unknown(format!(
            "no confirmed {what} for grade {grade} at {lo} < D ≤ {hi} mm, P = {p} mm (confirmed grades: {})",
            (4..=8)
                .filter(|&g| if internal {
                    td2_internal_um(range, pu, g).is_some()
                } else {
                    td2_um(range, pu, g).is_some()
                })
                .map(|g| g.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })?;
    let d2 = basic_um(d, p, 3.0 * 3f64.sqrt() / 8.0);
    let t2 = i64::from(t2);
    let fdl = i64::from(fd);
    let pitch = if internal {
        (mm(d2 + fdl), mm(d2 + fdl + t2))
    } else {
        (mm(d2 + fdl - t2), mm(d2 + fdl))
    };
    let cg = class.crest.grade;
    let (tc, cname) = if internal {
        (td1_um(pu, cg), "T_D1")
    } else {
        (td_um(pu, cg), "T_d")
    };
    let crest = tc.map(|t| {
        let t = i64::from(t);
        if internal {
            let d1 = basic_um(d, p, 5.0 * 3f64.sqrt() / 8.0);
            (mm(d1 + fdl), mm(d1 + fdl + t))
        } else {
            let dm = (d * 1000.0).round() as i64;
            (mm(dm + fdl - t), mm(dm + fdl))
        }
    });
    Ok(ClassLimits {
        internal,
        fundamental_deviation_um: fd,
        pitch_tolerance_um: t2 as u16,
        pitch,
        crest,
        crest_tolerance_um: tc,
        crest_missing: tc
            .is_none()
            .then(|| format!("no confirmed {cname} for grade {cg} at P = {p} mm")),
        major_min: internal.then(|| mm((d * 1000.0).round() as i64 + fdl)),
    })
}
