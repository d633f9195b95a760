//! The machine file's TOML layouts: the machine file itself, and the two
//! older single-purpose files that must keep reading. Which one a text is
//! follows from its top-level keys, whose sets do not overlap (`name` aside,
//! which both the machine file and the speed-only file have): a file mixing
//! them is refused, never guessed.

use super::{
    Axes, Control, CurvePoint, InverseTimeF, LinearAxis, Machine, MachineError, Modal,
    PostSettings, RotaryDrive, SpindleCurve,
};
use crate::timing::{Planner, PlannerKind, Profile};
use millplan_models::kinematics::Kinematics;
use millplan_nc::write::Target;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// The layout a machine file was written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// The machine file: `[control]`, `[spindle]`, `[feed]`, `[kinematics]`,
    /// `[axes.*]`, `[modal]` (`examples/machine.toml`).
    Machine,
    /// The old spindle/feed file of `speed` and `reorder`: top-level
    /// `spindle_min`, `spindle_max`, `spindle_accel`, `feed_min`, `feed_max`,
    /// `rapid`, `dialect`.
    SpeedOnly,
    /// The old kinematics file of `setup`: top-level `kind`, `rot_point`,
    /// `offset`, `tool_offset`, `pivot`, `[first]`, `[second]`; the spindle
    /// and feeds are then [`Machine::default`]'s.
    KinematicsOnly,
}

const MACHINE_KEYS: &[&str] = &[
    "control",
    "spindle",
    "feed",
    "kinematics",
    "axes",
    "modal",
    "post",
];
const SPEED_KEYS: &[&str] = &[
    "spindle_min",
    "spindle_max",
    "spindle_accel",
    "feed_min",
    "feed_max",
    "rapid",
    "dialect",
];
const KINEMATICS_KEYS: &[&str] = &[
    "kind",
    "rot_point",
    "offset",
    "tool_offset",
    "pivot",
    "first",
    "second",
];

impl Layout {
    fn of_key(key: &str) -> Option<Layout> {
        if MACHINE_KEYS.contains(&key) {
            Some(Layout::Machine)
        } else if SPEED_KEYS.contains(&key) {
            Some(Layout::SpeedOnly)
        } else if KINEMATICS_KEYS.contains(&key) {
            Some(Layout::KinematicsOnly)
        } else {
            // `name`, or a typo the layout's own reader will name.
            None
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Layout::Machine => "the machine file ([control], [spindle], [feed], [kinematics], ...)",
            Layout::SpeedOnly => "the old speed-only file (spindle_min, feed_max, ...)",
            Layout::KinematicsOnly => "the old kinematics-only file (kind, [first], [second], ...)",
        }
    }

    /// How a field named in the machine file's terms is spelt in this layout.
    fn spelling(self, field: &str) -> String {
        match self {
            Layout::Machine => field.to_string(),
            Layout::SpeedOnly => match field {
                "spindle.min" => "spindle_min",
                "spindle.max" => "spindle_max",
                "spindle.accel" => "spindle_accel",
                "feed.min" => "feed_min",
                "feed.max" => "feed_max",
                "feed.rapid" => "rapid",
                "control.dialect" => "dialect",
                other => other,
            }
            .to_string(),
            Layout::KinematicsOnly => field
                .strip_prefix("kinematics.")
                .unwrap_or(field)
                .to_string(),
        }
    }
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// A reader's error, located, with the field it is about when its place is
/// one (the toml crate names the key of an unknown field, not of a value of
/// the wrong type).
fn toml_error(text: &str, root: Option<&DeTable<'_>>, e: &toml::de::Error) -> MachineError {
    let span = e.span();
    let mut field = None;
    // An empty span is the toml crate's "somewhere in the document" (a field
    // missing at the top level): it belongs to no key.
    if let (Some(root), Some(span)) = (root, span.as_ref().filter(|s| !s.is_empty())) {
        field_at(root, span, "", &mut field);
    }
    MachineError {
        at: span.map(|s| line_col(text, s.start)),
        field,
        message: e.message().trim().to_string(),
    }
}

/// The deepest key path whose key or value spans all of `span`. A table
/// opened by a `[header]` spans only its header, so every branch is searched.
fn field_at(
    table: &DeTable<'_>,
    span: &std::ops::Range<usize>,
    prefix: &str,
    best: &mut Option<String>,
) {
    let holds = |s: std::ops::Range<usize>| s.start <= span.start && span.end <= s.end;
    // A path that extends another is longer: the longest is the deepest.
    fn note(best: &mut Option<String>, path: &str) {
        if best.as_ref().is_none_or(|b| b.len() < path.len()) {
            *best = Some(path.to_string());
        }
    }
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if holds(k.span()) || holds(v.span()) {
            note(best, &path);
        }
        match v.get_ref() {
            DeValue::Table(t) => field_at(t, span, &path, best),
            DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    let path = format!("{path}[{i}]");
                    if holds(item.span()) {
                        note(best, &path);
                    }
                    if let DeValue::Table(t) = item.get_ref() {
                        field_at(t, span, &path, best);
                    }
                }
            }
            _ => {}
        }
    }
}

/// The value at a field path such as `spindle.curve[2].power`, or the
/// deepest part of it the file spells out (a defaulted field has no place).
fn locate<'a>(root: &'a Spanned<DeTable<'a>>, path: &str) -> Option<std::ops::Range<usize>> {
    let mut span = None;
    let mut table = root.get_ref();
    let mut value: Option<&Spanned<DeValue<'a>>> = None;
    for part in path.split('.') {
        let (key, index) = match part.split_once('[') {
            Some((k, i)) => (k, i.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        if let Some(v) = value {
            table = v.get_ref().as_table()?;
        }
        let (_, v) = table.iter().find(|(k, _)| k.get_ref() == key)?;
        span = Some(v.span());
        value = Some(v);
        if let Some(i) = index {
            let item = v.get_ref().as_array()?.get(i)?;
            span = Some(item.span());
            value = Some(item);
        }
    }
    span
}

/// The layout of a parsed file, from its top-level keys.
fn layout(text: &str, root: &DeTable<'_>) -> Result<Layout, MachineError> {
    let mut keys: Vec<(&Spanned<toml::de::DeString<'_>>, Layout)> = root
        .iter()
        .filter_map(|(k, _)| Layout::of_key(k.get_ref()).map(|l| (k, l)))
        .collect();
    keys.sort_by_key(|(k, _)| k.span().start);
    let Some(&(first, first_layout)) = keys.first() else {
        // Nothing but perhaps `name`: the machine file's reader says what is missing.
        return Ok(Layout::Machine);
    };
    match keys.iter().find(|(_, l)| *l != first_layout) {
        None => Ok(first_layout),
        Some(&(other, other_layout)) => Err(MachineError {
            at: Some(line_col(text, other.span().start)),
            field: Some(other.get_ref().to_string()),
            message: format!(
                "belongs to {}, but `{}` (line {}) to {}: a file is written in one layout \
                 (see examples/machine.toml)",
                other_layout.describe(),
                first.get_ref(),
                line_col(text, first.span().start).0,
                first_layout.describe(),
            ),
        }),
    }
}

/// Reads and validates a machine file in any layout.
pub(super) fn read(text: &str) -> Result<(Machine, Layout), MachineError> {
    let root = DeTable::parse(text).map_err(|e| toml_error(text, None, &e))?;
    let layout = layout(text, root.get_ref())?;
    let reader_error = |e: toml::de::Error| toml_error(text, Some(root.get_ref()), &e);
    let machine = match layout {
        Layout::Machine => toml::from_str::<MachineFile>(text)
            .map_err(reader_error)?
            .into_machine(),
        Layout::SpeedOnly => toml::from_str::<SpeedFile>(text)
            .map_err(reader_error)?
            .into_machine(),
        Layout::KinematicsOnly => Ok(Machine {
            kinematics: Some(toml::from_str(text).map_err(reader_error)?),
            ..Machine::default()
        }),
    }
    .and_then(|m| m.validate().map(|()| m));
    // Name the field as this layout spells it, and point at it in the text.
    machine.map(|m| (m, layout)).map_err(|mut e| {
        if let Some(f) = e.field.take() {
            let f = layout.spelling(&f);
            if e.at.is_none() {
                e.at = locate(&root, &f).map(|s| line_col(text, s.start));
            }
            e.field = Some(f);
        }
        e
    })
}

/// Writes `m` in the machine-file layout.
pub(super) fn write(m: &Machine) -> Result<String, MachineError> {
    let mut axes = AxesFile {
        x: nonempty(m.axes.x),
        y: nonempty(m.axes.y),
        z: nonempty(m.axes.z),
        ..AxesFile::default()
    };
    if let Some(k) = &m.kinematics {
        for (drive, name) in [m.axes.first, m.axes.second]
            .into_iter()
            .zip(k.kind.rotary_names())
        {
            let slot = match name {
                'A' => &mut axes.a,
                'B' => &mut axes.b,
                _ => &mut axes.c,
            };
            *slot = nonempty(drive);
        }
    }
    let file = MachineFile {
        name: m.name.clone(),
        control: {
            let mut c = ControlFile {
                dialect: m.control.dialect.map(|t| t.name().to_string()),
                g93_f: m.control.g93_f,
                g93_rapids: m.control.g93_rapids,
                spindle_decimals: m.control.spindle_decimals,
                ..ControlFile::default()
            };
            c.set_planner(&m.control.planner);
            c
        },
        spindle: SpindleFile {
            min: m.spindle_min,
            max: m.spindle_max,
            accel: m.spindle_accel,
            curve: m.spindle_curve.as_ref().map(|c| c.points().to_vec()),
        },
        feed: FeedFile {
            min: m.feed_min,
            max: m.feed_max,
            air: m.feed_air,
            rapid: m.rapid,
        },
        kinematics: m.kinematics.clone(),
        axes,
        modal: m.modal.clone(),
        post: m.post,
    };
    toml::to_string(&file).map_err(|e| MachineError {
        at: None,
        field: None,
        message: format!("cannot be written as TOML: {e}"),
    })
}

fn nonempty<T: Default + PartialEq>(v: T) -> Option<T> {
    (v != T::default()).then_some(v)
}

fn default_name() -> String {
    "machine".into()
}
fn default_feed_min() -> f64 {
    1.0
}
fn default_rapid() -> f64 {
    15000.0
}
fn yes() -> bool {
    true
}
fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

/// The control's name in the file (with the aliases shops use) → writer target.
fn target(name: &str) -> Result<Target, MachineError> {
    match name.to_ascii_lowercase().as_str() {
        "fanuc" | "iso" | "haas" => Ok(Target::Fanuc),
        "sinumerik" | "siemens" => Ok(Target::Sinumerik),
        "heidenhain" => Ok(Target::Heidenhain),
        "linuxcnc" => Ok(Target::LinuxCnc),
        "apt" => Ok(Target::Apt),
        _ => Err(MachineError::invalid(
            "control.dialect",
            format!("unknown dialect `{name}` (fanuc, sinumerik, heidenhain, linuxcnc, apt)"),
        )),
    }
}

/// The old `speed`/`reorder` file, exactly as it read before the machine file.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SpeedFile {
    #[serde(default = "default_name")]
    name: String,
    spindle_min: f64,
    spindle_max: f64,
    spindle_accel: f64,
    #[serde(default = "default_feed_min")]
    feed_min: f64,
    feed_max: f64,
    #[serde(default = "default_rapid")]
    rapid: f64,
    #[serde(default)]
    dialect: Option<String>,
}

impl SpeedFile {
    fn into_machine(self) -> Result<Machine, MachineError> {
        Ok(Machine {
            name: self.name,
            spindle_min: self.spindle_min,
            spindle_max: self.spindle_max,
            spindle_accel: self.spindle_accel,
            feed_min: self.feed_min,
            feed_max: self.feed_max,
            rapid: self.rapid,
            control: Control {
                dialect: self.dialect.as_deref().map(target).transpose()?,
                ..Control::default()
            },
            ..Machine::default()
        })
    }
}

#[derive(serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
struct MachineFile {
    #[serde(default = "default_name")]
    name: String,
    #[serde(default)]
    control: ControlFile,
    spindle: SpindleFile,
    feed: FeedFile,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    kinematics: Option<Kinematics>,
    #[serde(default, skip_serializing_if = "is_default")]
    axes: AxesFile,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    modal: Option<Modal>,
    #[serde(default, skip_serializing_if = "is_default")]
    post: PostSettings,
}

#[derive(serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
struct ControlFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dialect: Option<String>,
    #[serde(default = "inverse_minutes")]
    g93_f: InverseTimeF,
    #[serde(default = "yes")]
    g93_rapids: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    spindle_decimals: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    planner: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    blend_accel_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    arc_tangential_share: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lookahead: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    plain_lookahead: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    jerk: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    path_accel: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    profile: Option<Profile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    block_time: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    blend_mm: Option<f64>,
}

impl ControlFile {
    /// The planner the file names, its family's defaults where it gives no
    /// parameter.
    fn planner(&self) -> Result<Planner, MachineError> {
        let kind = match self.planner.as_deref() {
            None => PlannerKind::Generic,
            Some(n) => PlannerKind::from_name(&n.to_ascii_lowercase()).ok_or_else(|| {
                MachineError::invalid(
                    "control.planner",
                    format!(
                        "unknown planner `{n}` (generic, linuxcnc-2.9, fanuc, sinumerik, heidenhain)"
                    ),
                )
            })?,
        };
        let d = Planner::of(kind);
        Ok(Planner {
            kind,
            blend_accel_scale: self.blend_accel_scale.unwrap_or(d.blend_accel_scale),
            arc_tangential_share: self.arc_tangential_share.unwrap_or(d.arc_tangential_share),
            lookahead: self.lookahead.unwrap_or(d.lookahead),
            plain_lookahead: self.plain_lookahead.unwrap_or(d.plain_lookahead),
            jerk: self.jerk.or(d.jerk),
            path_accel: self.path_accel.or(d.path_accel),
            profile: self.profile.unwrap_or(d.profile),
            block_time_s: self.block_time.unwrap_or(d.block_time_s),
            blend_mm: self.blend_mm.unwrap_or(d.blend_mm),
        })
    }

    /// The file's `[control]` planner keys for `p`: none for the default
    /// generic planner, else its name and every parameter.
    fn set_planner(&mut self, p: &Planner) {
        if *p == Planner::default() {
            return;
        }
        self.planner = Some(p.kind.name().to_string());
        self.blend_accel_scale = Some(p.blend_accel_scale);
        self.arc_tangential_share = Some(p.arc_tangential_share);
        self.lookahead = Some(p.lookahead);
        self.plain_lookahead = Some(p.plain_lookahead);
        self.jerk = p.jerk;
        self.path_accel = p.path_accel;
        self.profile = Some(p.profile);
        self.block_time = Some(p.block_time_s);
        self.blend_mm = Some(p.blend_mm);
    }
}

fn inverse_minutes() -> InverseTimeF {
    InverseTimeF::InverseMinutes
}

impl Default for ControlFile {
    fn default() -> Self {
        ControlFile {
            dialect: None,
            g93_f: inverse_minutes(),
            g93_rapids: true,
            spindle_decimals: None,
            planner: None,
            blend_accel_scale: None,
            arc_tangential_share: None,
            lookahead: None,
            plain_lookahead: None,
            jerk: None,
            path_accel: None,
            profile: None,
            block_time: None,
            blend_mm: None,
        }
    }
}

#[derive(serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
struct SpindleFile {
    min: f64,
    max: f64,
    accel: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    curve: Option<Vec<CurvePoint>>,
}

#[derive(serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
struct FeedFile {
    #[serde(default = "default_feed_min")]
    min: f64,
    max: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    air: Option<f64>,
    #[serde(default = "default_rapid")]
    rapid: f64,
}

/// Axes by the letters a program uses; rotary ones must be axes of the
/// kinematics.
#[derive(Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
struct AxesFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    x: Option<LinearAxis>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    y: Option<LinearAxis>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    z: Option<LinearAxis>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    a: Option<RotaryDrive>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    b: Option<RotaryDrive>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    c: Option<RotaryDrive>,
}

impl MachineFile {
    fn into_machine(self) -> Result<Machine, MachineError> {
        let mut axes = Axes {
            x: self.axes.x.unwrap_or_default(),
            y: self.axes.y.unwrap_or_default(),
            z: self.axes.z.unwrap_or_default(),
            ..Axes::default()
        };
        for (letter, drive) in [('A', self.axes.a), ('B', self.axes.b), ('C', self.axes.c)] {
            let Some(drive) = drive else { continue };
            let field = format!("axes.{}", letter.to_ascii_lowercase());
            let Some(k) = &self.kinematics else {
                return Err(MachineError::invalid(
                    field,
                    "a rotary axis needs [kinematics] (its kind says which axes there are)",
                ));
            };
            let [first, second] = k.kind.rotary_names();
            if letter == first {
                axes.first = drive;
            } else if letter == second {
                axes.second = drive;
            } else {
                return Err(MachineError::invalid(
                    field,
                    format!(
                        "the {} kinematics has no {letter} axis (its rotary axes are {first} and {second})",
                        kind_name(k)
                    ),
                ));
            }
        }
        Ok(Machine {
            name: self.name,
            spindle_min: self.spindle.min,
            spindle_max: self.spindle.max,
            spindle_accel: self.spindle.accel,
            spindle_curve: self.spindle.curve.map(SpindleCurve::new).transpose()?,
            feed_min: self.feed.min,
            feed_max: self.feed.max,
            feed_air: self.feed.air,
            rapid: self.feed.rapid,
            control: Control {
                dialect: self.control.dialect.as_deref().map(target).transpose()?,
                g93_f: self.control.g93_f,
                g93_rapids: self.control.g93_rapids,
                spindle_decimals: self.control.spindle_decimals,
                planner: self.control.planner()?,
            },
            kinematics: self.kinematics,
            axes,
            modal: self.modal,
            post: self.post,
        })
    }
}

/// `kind` as the file spells it.
fn kind_name(k: &Kinematics) -> String {
    toml::Value::try_from(k.kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_else(|| format!("{:?}", k.kind))
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_models::kinematics::KinKind;

    const EXAMPLE: &str = include_str!("../../../../examples/machine.toml");

    fn err(text: &str) -> MachineError {
        Machine::from_toml(text).expect_err("invalid")
    }

    #[test]
    fn line_col_counts_characters() {
        let t = "a = 1\nµm = 2\n";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 6), (2, 1));
        // After the two-byte µ: column 2.
        assert_eq!(line_col(t, 8), (2, 2));
    }

    /// The old speed-only file reads exactly as before, into the same numbers.
    #[test]
    fn old_speed_file_reads() {
        let t = "spindle_min = 100\nspindle_max = 12000\nspindle_accel = 3000\nfeed_max = 10000\ndialect = \"heidenhain\"\n";
        let (m, layout) = Machine::read(t).expect("valid");
        assert_eq!(layout, Layout::SpeedOnly);
        assert_eq!(
            (m.spindle_min, m.spindle_max, m.spindle_accel),
            (100.0, 12000.0, 3000.0)
        );
        // The old defaults: feed_min 1, rapid 15000.
        assert_eq!((m.feed_min, m.feed_max, m.rapid), (1.0, 10000.0, 15000.0));
        assert_eq!(m.target(), Some(Target::Heidenhain));
        assert_eq!(m.name, "machine");
        assert_eq!(m.kinematics(), None);
        // The `speed` end-to-end test's file, every key given.
        let t = "name = \"VMC\"\nspindle_min = 1000\nspindle_max = 12000\nspindle_accel = 4000\nfeed_min = 10\nfeed_max = 8000\nrapid = 20000\ndialect = \"iso\"\n";
        let m = Machine::from_toml(t).expect("valid");
        assert_eq!(
            (m.name.as_str(), m.feed_min, m.rapid, m.target()),
            ("VMC", 10.0, 20000.0, Some(Target::Fanuc))
        );
        // What it refused, it still refuses, naming the field as it is spelt there.
        let e = err("spindle_min = 100\nspindle_max = 50\nspindle_accel = 1\nfeed_max = 1\n");
        assert_eq!(e.field.as_deref(), Some("spindle_max"), "{e}");
        assert_eq!(e.at, Some((2, 15)), "{e}");
        let e = err("spindle_max = 50\n");
        assert!(e.message.contains("spindle_min"), "{e}");
        let e =
            err("spindle_min = 1\nspindle_max = 50\nspindle_accel = 1\nfeed_max = 10\ntypo = 1\n");
        assert!(e.message.contains("typo"), "{e}");
        assert_eq!(e.field.as_deref(), Some("typo"), "{e}");
        assert_eq!(e.at, Some((5, 1)), "{e}");
        let e = err("spindle_min = 1\nspindle_max = 50\nspindle_accel = 1\nfeed_max = 10\ndialect = \"okuma\"\n");
        assert_eq!(e.field.as_deref(), Some("dialect"), "{e}");
        assert_eq!(e.at, Some((5, 11)), "{e}");
        assert!(e.message.contains("okuma"), "{e}");
    }

    /// The old kinematics-only file of `setup` becomes the default machine with
    /// that kinematics.
    #[test]
    fn old_kinematics_file_reads() {
        let t = "kind = \"table-bc\"\nrot_point = [1, 2, 3]\n[first]\nmin = -30\nmax = 110\n[second]\nsign = -1\n";
        let (m, layout) = Machine::read(t).expect("valid");
        assert_eq!(layout, Layout::KinematicsOnly);
        let k = Kinematics::from_toml(t).expect("valid");
        assert_eq!(
            m,
            Machine {
                kinematics: Some(k),
                ..Machine::default()
            }
        );
        let k = m.kinematics().expect("kinematics");
        assert_eq!(
            (k.kind, k.second.sign, k.first.max, k.rot_point),
            (KinKind::TableBc, -1.0, Some(110.0), [1.0, 2.0, 3.0])
        );
        let e = err("kind = \"table-ac\"\n[first]\nmin = -30\nsgn = 1\n");
        assert!(e.message.contains("sgn"), "{e}");
        assert_eq!(e.at, Some((4, 1)), "{e}");
        let e = err("kind = \"head-bc\"\n[first]\nsign = 2\n");
        assert_eq!(
            (e.field.as_deref(), e.at),
            (Some("first.sign"), Some((3, 8))),
            "{e}"
        );
        let e = err("kind = \"table-ac\"\n[second]\nmin = nan\n");
        assert_eq!(e.field.as_deref(), Some("second.min"), "{e}");
        assert!(err("kind = \"table-xy\"\n").message.contains("table-xy"));
    }

    #[test]
    fn layouts_are_never_mixed() {
        // The old speed keys beside the machine file's tables.
        let e =
            err("spindle_min = 100\n[spindle]\nmin = 1\nmax = 2\naccel = 3\n[feed]\nmax = 10\n");
        assert_eq!(e.field.as_deref(), Some("spindle"), "{e}");
        assert_eq!(e.at, Some((2, 2)), "{e}");
        assert!(e.message.contains("spindle_min"), "{e}");
        // `kind` at the top of a machine file instead of under [kinematics].
        let e = err("[spindle]\nmin = 1\nmax = 2\naccel = 3\n[feed]\nmax = 10\n[first]\nmin = 0\n");
        assert_eq!(e.field.as_deref(), Some("first"), "{e}");
        assert!(e.message.contains("kinematics-only"), "{e}");
        // The two old files in one.
        let e = err("kind = \"table-ac\"\nspindle_min = 1\n");
        assert_eq!(e.field.as_deref(), Some("spindle_min"), "{e}");
        assert_eq!(e.at, Some((2, 1)), "{e}");
        // A file of nothing but a name is a machine file missing its spindle.
        let e = err("name = \"x\"\n");
        assert!(e.message.contains("spindle"), "{e}");
        let e = err("");
        assert!(e.message.contains("spindle"), "{e}");
    }

    #[test]
    fn syntax_errors_are_located() {
        let e = err("[spindle]\nmin = 1\nmax = = 2\n");
        assert_eq!(e.at.map(|a| a.0), Some(3), "{e}");
        assert_eq!(e.field, None);
    }

    const MINIMAL: &str = "[spindle]\nmin = 500\nmax = 18000\naccel = 6000\n[feed]\nmax = 20000\n";

    #[test]
    fn minimal_machine_file_takes_the_documented_defaults() {
        let (m, layout) = Machine::read(MINIMAL).expect("valid");
        assert_eq!(layout, Layout::Machine);
        assert_eq!(
            m,
            Machine {
                name: "machine".into(),
                ..Machine::default()
            }
        );
        assert_eq!(m.control.g93_f, InverseTimeF::InverseMinutes);
        assert!(m.control.g93_rapids);
        assert_eq!(m.control.spindle_decimals, None);
    }

    /// Bad values in the machine file: named as spelt there, pointed at.
    #[test]
    fn machine_file_rejects_bad_values() {
        let with = |extra: &str| format!("{MINIMAL}{extra}");
        let check = |text: String, field: &str, line: usize| {
            let e = err(&text);
            assert_eq!(e.field.as_deref(), Some(field), "{e}");
            assert_eq!(e.at.map(|a| a.0), Some(line), "{e}\n{text}");
        };
        check(
            MINIMAL.replace("max = 18000", "max = nan"),
            "spindle.max",
            3,
        );
        check(
            MINIMAL.replace("accel = 6000", "accel = -inf"),
            "spindle.accel",
            4,
        );
        check(MINIMAL.replace("min = 500", "min = -1"), "spindle.min", 2);
        check(MINIMAL.replace("max = 20000", "max = inf"), "feed.max", 6);
        check(with("rapid = 0\n"), "feed.rapid", 7);
        check(with("min = 30000\n"), "feed.max", 6);
        check(
            with("[control]\nspindle_decimals = 9\n"),
            "control.spindle_decimals",
            8,
        );
        check(
            with("[control]\ndialect = \"mazatrol\"\n"),
            "control.dialect",
            8,
        );
        check(with("[axes.x]\nmin = 300\nmax = -300\n"), "axes.x.max", 9);
        check(with("[axes.z]\naccel = nan\n"), "axes.z.accel", 8);
        check(with("[axes.c]\nvelocity = 100\n"), "axes.c", 7);
        check(
            with("[kinematics]\nkind = \"table-ac\"\n[axes.b]\nvelocity = 100\n"),
            "axes.b",
            9,
        );
        check(
            with("[kinematics]\nkind = \"table-ac\"\n[axes.c]\nvelocity = -100\n"),
            "axes.c.velocity",
            10,
        );
        check(
            with("[kinematics]\nkind = \"table-ac\"\noffset = [0, inf, 0]\n"),
            "kinematics.offset[1]",
            9,
        );
        check(
            with("[kinematics]\nkind = \"table-ac\"\n[kinematics.first]\nmin = 30\nmax = -120\n"),
            "kinematics.first.min",
            10,
        );
        check(
            with_curve("{ speed = 0, torque = 80 },\n  { speed = 20000, power = nan }"),
            "spindle.curve[1].power",
            7,
        );
        check(
            with_curve("{ speed = 600, torque = 80 },\n  { speed = 20000, power = 15 }"),
            "spindle.curve",
            5,
        );
        check(
            with("[modal]\nx = [{ frequency = 900, damping = 0.02, stiffness = 2e7 }]\ny = [{ frequency = 900, damping = 0, stiffness = 2e7 }]\n"),
            "modal.y[0].damping",
            9,
        );
        check(
            with("[modal]\nx = [{ frequency = 900, damping = 0.02, stiffness = 2e7 }]\ny = []\n"),
            "modal.y",
            9,
        );
        // Typos are errors, located.
        let e = err(&with("[axes.x]\nvelocty = 100\n"));
        assert!(e.message.contains("velocty"), "{e}");
        assert_eq!(e.field.as_deref(), Some("axes.x.velocty"), "{e}");
        assert_eq!(e.at, Some((8, 1)), "{e}");
        let e = err(&with("[control]\ng93_f = \"minutes\"\n"));
        assert!(e.message.contains("minutes"), "{e}");
        assert_eq!(e.at.map(|a| a.0), Some(8), "{e}");
        assert_eq!(e.field.as_deref(), Some("control.g93_f"), "{e}");
        // A value of the wrong type: the toml crate says what, the place says where.
        let e = err(&with("[spindle.curve]\nspeed = 1\n"));
        assert_eq!(e.field.as_deref(), Some("spindle.curve"), "{e}");
        let e = err(&with_curve("{ speed = \"fast\", torque = 1 }"));
        assert_eq!(e.field.as_deref(), Some("spindle.curve[0].speed"), "{e}");
        assert_eq!(e.at, Some((6, 13)), "{e}");
        // A missing field belongs to its table; at the top, to no key.
        let e = err("[spindle]\nmin = 1\nmax = 2\naccel = 3\n");
        assert!(e.message.contains("feed"), "{e}");
        assert_eq!(e.field, None, "{e}");
        let e = err(&MINIMAL.replace("accel = 6000\n", ""));
        assert!(e.message.contains("accel"), "{e}");
        assert_eq!(e.field.as_deref(), Some("spindle"), "{e}");
        let e = err(&with(
            "[modal]\nx = [{ frequency = 900, damping = 0.02, stiffness = 2e7 }]\n",
        ));
        assert!(e.message.contains("`y`"), "{e}");
        assert_eq!(e.field.as_deref(), Some("modal"), "{e}");
        // Rotary travel lives in the kinematics, not beside the drive.
        let e = err(&with(
            "[kinematics]\nkind = \"table-ac\"\n[axes.a]\nmin = -120\n",
        ));
        assert!(e.message.contains("min"), "{e}");
    }

    fn with_curve(points: &str) -> String {
        MINIMAL.replace(
            "accel = 6000\n",
            &format!("accel = 6000\ncurve = [\n  {points},\n]\n"),
        )
    }

    #[test]
    fn rotary_drives_go_to_the_kinematics_axes() {
        let t = format!("{MINIMAL}[kinematics]\nkind = \"table-ab\"\n[axes.a]\nvelocity = 5000\n[axes.b]\naccel = 700\n");
        let m = Machine::from_toml(&t).expect("valid");
        assert_eq!(m.axes.first.velocity, Some(5000.0));
        assert_eq!(m.axes.second.accel, Some(700.0));
        assert_eq!(m.axes.first.accel, None);
    }

    /// The example in the repository reads, validates and sets every field
    /// (so it cannot fall behind the format); the patterns below list every
    /// field without `..`, so a new one does not compile until it is thought
    /// about here and in the example.
    #[test]
    fn example_machine_file_reads_and_covers_every_field() {
        let (m, layout) = Machine::read(EXAMPLE).expect("the example is valid");
        assert_eq!(layout, Layout::Machine);
        let Machine {
            name,
            spindle_min: _,
            spindle_max: _,
            spindle_accel: _,
            spindle_curve,
            feed_min: _,
            feed_max: _,
            feed_air,
            rapid: _,
            control:
                Control {
                    dialect,
                    g93_f: _,
                    g93_rapids: _,
                    spindle_decimals,
                    planner,
                },
            kinematics,
            axes:
                Axes {
                    x,
                    y,
                    z,
                    first,
                    second,
                },
            modal,
            post,
        } = &m;
        assert_ne!(name, "machine");
        assert_ne!(*post, PostSettings::default(), "the example sets [post]");
        assert!(dialect.is_some() && spindle_decimals.is_some() && feed_air.is_some());
        // The planner and every one of its parameters, each set in the
        // example (to its family's default or not).
        assert_eq!(planner.kind, PlannerKind::Fanuc);
        for key in [
            "planner",
            "blend_accel_scale",
            "arc_tangential_share",
            "lookahead",
            "plain_lookahead",
            "jerk",
            "path_accel",
            "profile",
            "block_time",
            "blend_mm",
        ] {
            assert!(
                EXAMPLE.lines().any(|l| l.starts_with(&format!("{key} = "))),
                "examples/machine.toml sets no `{key}`"
            );
        }
        let curve = spindle_curve.as_ref().expect("curve");
        assert!(curve
            .points()
            .iter()
            .any(|p| p.power.is_some() && p.torque.is_some()));
        assert!(curve.points().iter().any(|p| p.power.is_none()));
        assert!(curve.points().iter().any(|p| p.torque.is_none()));
        let k = kinematics.as_ref().expect("kinematics");
        let full = |a: &millplan_models::kinematics::RotaryAxis| a.min.is_some() && a.max.is_some();
        assert!(full(&k.first) || full(&k.second));
        for a in [x, y, z] {
            let LinearAxis {
                min,
                max,
                velocity,
                accel,
                jerk,
            } = a;
            assert!(min.is_some() && max.is_some() && velocity.is_some() && accel.is_some());
            assert!(jerk.is_some());
        }
        for d in [first, second] {
            let RotaryDrive {
                velocity,
                accel,
                jerk,
            } = d;
            assert!(velocity.is_some() && accel.is_some() && jerk.is_some());
        }
        let modal = modal.as_ref().expect("modal");
        assert!(!modal.x.is_empty() && !modal.y.is_empty());
        // Every key the canonical form writes is in the example, and the
        // example has none it would not write (no defaulted key left out).
        let canonical = m.to_toml().expect("writes");
        assert_eq!(keys(&canonical), keys(EXAMPLE), "{canonical}");
    }

    /// Every key path of a TOML text, array indices dropped.
    fn keys(text: &str) -> std::collections::BTreeSet<String> {
        fn walk(prefix: &str, v: &DeValue<'_>, out: &mut std::collections::BTreeSet<String>) {
            match v {
                DeValue::Table(t) => {
                    for (k, v) in t.iter() {
                        let p = if prefix.is_empty() {
                            k.get_ref().to_string()
                        } else {
                            format!("{prefix}.{}", k.get_ref())
                        };
                        walk(&p, v.get_ref(), out);
                    }
                }
                DeValue::Array(a) => {
                    for v in a.iter() {
                        walk(prefix, v.get_ref(), out);
                    }
                }
                _ => {
                    out.insert(prefix.to_string());
                }
            }
        }
        let root = DeTable::parse(text).expect("parses");
        let mut out = std::collections::BTreeSet::new();
        walk("", &DeValue::Table(root.into_inner()), &mut out);
        out
    }

    /// Written in the machine-file layout, every form reads back equal.
    #[test]
    fn written_machine_reads_back_equal() {
        let old_speed = "spindle_min = 100\nspindle_max = 12000\nspindle_accel = 3000\nfeed_max = 10000\ndialect = \"sinumerik\"\n";
        let old_kin = "kind = \"head-b-table-c\"\npivot = 250.5\n[first]\nmin = -90\nmax = 90\n[second]\nsign = -1\n";
        for text in [EXAMPLE, MINIMAL, old_speed, old_kin] {
            let m = Machine::from_toml(text).expect("valid");
            let written = m.to_toml().expect("writes");
            let (again, layout) = Machine::read(&written).expect("reads back");
            assert_eq!(layout, Layout::Machine);
            assert_eq!(again, m, "{written}");
        }
    }
}
