//! Five-axis machine kinematics (spec `kinematics-access-tools.md` §1): forward
//! kinematics (joints → tool tip and tool axis in the workpiece frame) and the
//! two-stage inverse (tool axis → both rotary solutions; tip + angles → linear
//! joints) for table-table A/C, B/C and A/B machines, the B/C head-head and a
//! B-head on a C-table.
//!
//! Conventions: right-handed active rotations R_x, R_y, R_z; angles in radians
//! inside, degrees in G-code and machine files; the tool axis K points from the
//! tip up the spindle. Each rotary axis has a sign (+1 or −1) that maps the
//! programmed angle to the angle of these formulas, because machines disagree on
//! rotation sense (LinuxCNC's trt and 5-axis modules rotate opposite to RS274).

use millplan_geom::{DMat3, DVec3};

/// The machine's rotary-axis arrangement.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum KinKind {
    /// A tilting table carrying a C rotary table ("xyzac-trt"); offset = (0, D_y, D_z).
    TableAc,
    /// B tilting table carrying C ("xyzbc-trt"); offset = (D_x, 0, D_z).
    TableBc,
    /// A table on a B cradle ("xyzab_tdr"); offset = (D_x, 0, D_z).
    TableAb,
    /// B tilting head on a C rotating head ("5axiskins"); `pivot` from tip to pivot.
    HeadBc,
    /// B tilting head, C rotary table ("maxkins"-like); `pivot` from tip to pivot.
    HeadBTableC,
}

impl KinKind {
    /// The letters of the (first, second) rotary axes as a G-code program names them.
    pub fn rotary_names(self) -> [char; 2] {
        match self {
            KinKind::TableAc => ['A', 'C'],
            KinKind::TableAb => ['A', 'B'],
            KinKind::TableBc | KinKind::HeadBc | KinKind::HeadBTableC => ['B', 'C'],
        }
    }
}

/// A value of a kinematics description out of its range: the field (a dotted
/// path such as `first.min`) and what is wrong with it.
#[derive(Clone, Debug, PartialEq)]
pub struct KinematicsError {
    pub field: String,
    pub message: String,
}

impl std::fmt::Display for KinematicsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// One rotary axis: programmed-angle limits in degrees (`None`: unlimited) and sign.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryAxis {
    #[serde(default)]
    pub min: Option<f64>,
    #[serde(default)]
    pub max: Option<f64>,
    #[serde(default = "one")]
    pub sign: f64,
}

fn one() -> f64 {
    1.0
}

impl Default for RotaryAxis {
    fn default() -> Self {
        RotaryAxis {
            min: None,
            max: None,
            sign: 1.0,
        }
    }
}

impl RotaryAxis {
    fn allows(&self, deg: f64) -> bool {
        self.min.map(|m| deg >= m - 1e-9).unwrap_or(true)
            && self.max.map(|m| deg <= m + 1e-9).unwrap_or(true)
    }
}

/// A five-axis machine. `first` is the tilting axis (A or B; for A/B machines the
/// A table), `second` the rotary axis (C; for A/B machines the B cradle).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Kinematics {
    pub kind: KinKind,
    /// Pivot point R of the tables in machine coordinates, mm.
    #[serde(default)]
    pub rot_point: [f64; 3],
    /// Offsets between the rotary axes, mm (see [`KinKind`]).
    #[serde(default)]
    pub offset: [f64; 3],
    /// Tool length added along Z (table machines), mm.
    #[serde(default)]
    pub tool_offset: f64,
    /// Tip-to-pivot distance of a tilting head, tool length included, mm.
    #[serde(default)]
    pub pivot: f64,
    #[serde(default)]
    pub first: RotaryAxis,
    #[serde(default)]
    pub second: RotaryAxis,
}

/// Joint positions: linear axes (mm) and the two rotary axes as programmed (degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joints {
    pub xyz: DVec3,
    pub first: f64,
    pub second: f64,
}

fn rx(a: f64) -> DMat3 {
    DMat3::from_rotation_x(a)
}
fn ry(a: f64) -> DMat3 {
    DMat3::from_rotation_y(a)
}
fn rz(a: f64) -> DMat3 {
    DMat3::from_rotation_z(a)
}

/// Below this tilt (radians) the rotary angle is undefined: it keeps its previous value.
pub const POLE: f64 = 1e-9;

impl Kinematics {
    pub fn new(kind: KinKind) -> Kinematics {
        Kinematics {
            kind,
            rot_point: [0.0; 3],
            offset: [0.0; 3],
            tool_offset: 0.0,
            pivot: 0.0,
            first: RotaryAxis::default(),
            second: RotaryAxis::default(),
        }
    }

    pub fn from_toml(text: &str) -> Result<Kinematics, String> {
        let k: Kinematics = toml_from_str(text)?;
        k.check().map_err(|e| e.to_string())?;
        Ok(k)
    }

    /// Every number finite, signs ±1, each rotary range ordered. NaN would
    /// pass the range tests of the inverse (every comparison with it is
    /// false) and silently unlimit an axis, so it is refused here.
    pub fn check(&self) -> Result<(), KinematicsError> {
        let err = |field: String, message: &str| {
            Err(KinematicsError {
                field,
                message: message.to_string(),
            })
        };
        // Within the plausibility limit of a program's coordinates: a
        // rotation point at 1e20 mm turns every posted point into inf.
        let far = |x: f64| !(x.abs() <= millplan_geom::limits::NC_EXTENT);
        const FAR: &str = "must be a finite length within ±1000000 mm";
        for (name, v) in [("rot_point", self.rot_point), ("offset", self.offset)] {
            if let Some(i) = v.iter().position(|&x| far(x)) {
                return err(format!("{name}[{i}]"), FAR);
            }
        }
        for (name, v) in [("tool_offset", self.tool_offset), ("pivot", self.pivot)] {
            if far(v) {
                return err(name.into(), FAR);
            }
        }
        for (n, a) in [("first", self.first), ("second", self.second)] {
            if a.sign != 1.0 && a.sign != -1.0 {
                return err(format!("{n}.sign"), "must be 1 or -1");
            }
            for (end, v) in [("min", a.min), ("max", a.max)] {
                if v.is_some_and(|v| !(v.abs() <= millplan_geom::limits::NC_EXTENT)) {
                    return err(
                        format!("{n}.{end}"),
                        "must be a finite angle within ±1000000 degrees; leave it out for no limit",
                    );
                }
            }
            if let (Some(lo), Some(hi)) = (a.min, a.max) {
                if lo > hi {
                    return err(format!("{n}.min"), "is above max");
                }
            }
        }
        Ok(())
    }

    fn r(&self) -> DVec3 {
        DVec3::from_array(self.rot_point)
    }

    /// Angles of the formulas (radians) from programmed degrees.
    fn angles(&self, j: &Joints) -> (f64, f64) {
        (
            self.first.sign * j.first.to_radians(),
            self.second.sign * j.second.to_radians(),
        )
    }

    /// Tool axis in the workpiece frame for the rotary positions (degrees).
    pub fn tool_axis(&self, first: f64, second: f64) -> DVec3 {
        let (a, c) = self.angles(&Joints {
            xyz: DVec3::ZERO,
            first,
            second,
        });
        match self.kind {
            KinKind::TableAc => rz(c).transpose() * rx(a).transpose() * DVec3::Z,
            KinKind::TableBc => rz(c).transpose() * ry(a).transpose() * DVec3::Z,
            KinKind::TableAb => rx(a) * ry(c) * DVec3::Z,
            KinKind::HeadBc => DVec3::new(-a.sin() * c.cos(), -a.sin() * c.sin(), a.cos()),
            KinKind::HeadBTableC => rz(c).transpose() * (ry(a) * DVec3::Z),
        }
    }

    /// Forward kinematics: tool tip and tool axis in the workpiece frame.
    pub fn forward(&self, j: &Joints) -> (DVec3, DVec3) {
        let (a, c) = self.angles(j);
        let r = self.r();
        // The table kinds turn the tip and the axis by the same matrices
        // (the expressions of `tip` and `tool_axis`, the sines taken once).
        let table = |first: DMat3, d: DVec3| {
            let (zt, ft) = (rz(c).transpose(), first.transpose());
            (r + zt * (ft * (j.xyz - r - d) + d), zt * ft * DVec3::Z)
        };
        match self.kind {
            KinKind::TableAc => {
                let d = DVec3::new(0.0, self.offset[1], self.offset[2] + self.tool_offset);
                table(rx(a), d)
            }
            KinKind::TableBc => {
                let d = DVec3::new(self.offset[0], 0.0, self.offset[2] + self.tool_offset);
                table(ry(a), d)
            }
            KinKind::TableAb => {
                let d = DVec3::new(self.offset[0], 0.0, self.offset[2]);
                let t = DVec3::new(0.0, 0.0, self.tool_offset);
                let tip = r + d + t + rx(a) * (ry(c) * (j.xyz - r - t) - d);
                (tip, self.tool_axis(j.first, j.second))
            }
            KinKind::HeadBc => {
                let k = self.tool_axis(j.first, j.second);
                (j.xyz - k * self.pivot + DVec3::new(0.0, 0.0, self.pivot), k)
            }
            KinKind::HeadBTableC => {
                // The head puts the tip at joints + L·e_z − L·K_m (machine frame);
                // the table turns the part by C about the Z axis through R.
                let km = ry(a) * DVec3::Z;
                let tip_m = j.xyz + DVec3::new(0.0, 0.0, self.pivot) - km * self.pivot;
                let tip = r + rz(c).transpose() * (tip_m - r);
                (tip, self.tool_axis(j.first, j.second))
            }
        }
    }

    /// The tool tip of [`Kinematics::forward`] alone (half the trigonometry:
    /// a post samples tip paths by the million).
    pub fn tip(&self, j: &Joints) -> DVec3 {
        let (a, c) = self.angles(j);
        let r = self.r();
        match self.kind {
            KinKind::TableAc => {
                let d = DVec3::new(0.0, self.offset[1], self.offset[2] + self.tool_offset);
                r + rz(c).transpose() * (rx(a).transpose() * (j.xyz - r - d) + d)
            }
            KinKind::TableBc => {
                let d = DVec3::new(self.offset[0], 0.0, self.offset[2] + self.tool_offset);
                r + rz(c).transpose() * (ry(a).transpose() * (j.xyz - r - d) + d)
            }
            _ => self.forward(j).0,
        }
    }

    /// Both rotary solutions (programmed degrees) for a unit tool axis, the
    /// principal one first. At the pole the rotary angle is `keep`.
    pub fn orientation_ik(&self, k: DVec3, keep: f64) -> [(f64, f64); 2] {
        let k = k.normalize();
        let (s1, s2) = (self.first.sign, self.second.sign);
        let deg = |a: f64, c: f64| ((a / s1).to_degrees(), (c / s2).to_degrees());
        let kz = k.z.clamp(-1.0, 1.0);
        let keep_r = s2 * keep.to_radians();
        let (a, c) = match self.kind {
            KinKind::TableAc => {
                let a = kz.acos();
                (
                    a,
                    if a.sin() < POLE {
                        keep_r
                    } else {
                        k.x.atan2(k.y)
                    },
                )
            }
            KinKind::TableBc => {
                let a = kz.acos();
                (
                    a,
                    if a.sin() < POLE {
                        keep_r
                    } else {
                        k.y.atan2(-k.x)
                    },
                )
            }
            KinKind::TableAb => {
                // B = asin(K_x), A = atan2(−K_y, K_z); `second` is B.
                let b = k.x.clamp(-1.0, 1.0).asin();
                let a = if b.cos() < POLE {
                    s1 * keep.to_radians()
                } else {
                    (-k.y).atan2(k.z)
                };
                return [
                    deg(a, b),
                    deg(a + std::f64::consts::PI, std::f64::consts::PI - b),
                ];
            }
            KinKind::HeadBc => {
                let a = kz.acos();
                (
                    a,
                    if a.sin() < POLE {
                        keep_r
                    } else {
                        (-k.y).atan2(-k.x)
                    },
                )
            }
            KinKind::HeadBTableC => {
                let a = kz.acos();
                (
                    a,
                    if a.sin() < POLE {
                        keep_r
                    } else {
                        (-k.y).atan2(k.x)
                    },
                )
            }
        };
        [deg(a, c), deg(-a, c + std::f64::consts::PI)]
    }

    /// Linear joints that put the tip at `tip` with the rotary axes at (first, second).
    pub fn position_ik(&self, tip: DVec3, first: f64, second: f64) -> DVec3 {
        let (a, c) = self.angles(&Joints {
            xyz: DVec3::ZERO,
            first,
            second,
        });
        let r = self.r();
        match self.kind {
            KinKind::TableAc => {
                let d = DVec3::new(0.0, self.offset[1], self.offset[2] + self.tool_offset);
                r + d + rx(a) * (rz(c) * (tip - r) - d)
            }
            KinKind::TableBc => {
                let d = DVec3::new(self.offset[0], 0.0, self.offset[2] + self.tool_offset);
                r + d + ry(a) * (rz(c) * (tip - r) - d)
            }
            KinKind::TableAb => {
                let d = DVec3::new(self.offset[0], 0.0, self.offset[2]);
                let t = DVec3::new(0.0, 0.0, self.tool_offset);
                r + t + ry(-c) * (rx(-a) * (tip - r - d - t) + d)
            }
            KinKind::HeadBc => {
                let k = self.tool_axis(first, second);
                tip + k * self.pivot - DVec3::new(0.0, 0.0, self.pivot)
            }
            KinKind::HeadBTableC => {
                let km = ry(a) * DVec3::Z;
                let tip_m = r + rz(c) * (tip - r);
                tip_m + km * self.pivot - DVec3::new(0.0, 0.0, self.pivot)
            }
        }
    }

    /// Whether some inverse solution of the unit tool axis `k` lies inside the
    /// rotary limits (angles may be wound by whole turns to get there).
    pub fn reaches(&self, k: DVec3) -> bool {
        let fits =
            |axis: &RotaryAxis, deg: f64| (-2..=2).any(|w| axis.allows(deg + 360.0 * w as f64));
        self.orientation_ik(k, 0.0)
            .iter()
            .any(|&(f, s)| fits(&self.first, f) && fits(&self.second, s))
    }

    /// The joint solutions for a tip and tool axis that lie within the rotary
    /// limits; the rotary angle of unlimited axes is taken nearest `near`.
    pub fn inverse(&self, tip: DVec3, k: DVec3, near: f64) -> Vec<Joints> {
        self.orientation_ik(k, near)
            .into_iter()
            .filter_map(|(f, s)| {
                let s = if self.second.min.is_none() && self.second.max.is_none() {
                    s + 360.0 * ((near - s) / 360.0).round()
                } else {
                    s
                };
                let f = if self.first.min.is_none()
                    && self.first.max.is_none()
                    && self.kind == KinKind::TableAb
                {
                    f + 360.0 * ((0.0 - f) / 360.0).round()
                } else {
                    f
                };
                (self.first.allows(f) && self.second.allows(s)).then(|| Joints {
                    xyz: self.position_ik(tip, f, s),
                    first: f,
                    second: s,
                })
            })
            .collect()
    }
}

fn toml_from_str(text: &str) -> Result<Kinematics, String> {
    toml::from_str(text).map_err(|e| e.to_string())
}

#[cfg(test)]
#[allow(clippy::approx_constant)] // the oracles are the spec's six-digit table values
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn near(a: DVec3, b: [f64; 3], tol: f64) {
        assert!((a - DVec3::from_array(b)).length() < tol, "{a:?} vs {b:?}");
    }

    /// Spec §5, numeric oracles (LinuxCNC trtfuncs.c, 5axiskins.c, xyzab_tdr_kins).
    #[test]
    fn spec_oracles() {
        let ac = Kinematics::new(KinKind::TableAc);
        let s = ac.orientation_ik(DVec3::ONE.normalize(), 0.0);
        assert!((s[0].0 - 54.735610).abs() < 1e-6 && (s[0].1 - 45.0).abs() < 1e-9);
        assert!(
            (s[1].0 + 54.735610).abs() < 1e-6
                && ((s[1].1 - 225.0).abs() < 1e-9 || (s[1].1 + 135.0).abs() < 1e-9)
        );
        let s = ac.orientation_ik(DVec3::new(0.0, -0.5, 0.8660254), 0.0);
        assert!((s[0].0 - 30.0).abs() < 1e-5 && (s[0].1.abs() - 180.0).abs() < 1e-9);
        assert_eq!(
            ac.orientation_ik(DVec3::Z, 17.0)[0],
            (0.0, 17.0),
            "pole: C keeps its value"
        );
        near(
            ac.tool_axis(45.0, 30.0),
            [0.353553, 0.612372, 0.707107],
            1e-6,
        );
        near(
            ac.position_ik(DVec3::new(10.0, 20.0, 30.0), 30.0, 60.0),
            [-12.320508, 1.160254, 35.310889],
            1e-6,
        );
        let mut ac2 = ac.clone();
        ac2.rot_point = [10.0, -5.0, 2.0];
        ac2.offset = [0.0, 3.0, 20.0];
        ac2.tool_offset = 100.0;
        near(
            ac2.position_ik(DVec3::new(3.0, 4.0, 5.0), 35.0, -120.0),
            [21.294229, 63.930648, 25.334510],
            1e-6,
        );
        near(
            ac2.forward(&Joints {
                xyz: DVec3::new(12.3, 45.6, -78.9),
                first: 35.0,
                second: -120.0,
            })
            .0,
            [72.277587, 33.611793, -69.869884],
            1e-6,
        );

        let bc = Kinematics::new(KinKind::TableBc);
        near(
            bc.tool_axis(45.0, 30.0),
            [-0.612372, 0.353553, 0.707107],
            1e-6,
        );
        let s = bc.orientation_ik(bc.tool_axis(45.0, 30.0), 0.0);
        assert!(
            (s[0].0 - 45.0).abs() < 1e-9 && (s[0].1 - 30.0).abs() < 1e-9,
            "C = 30, not the doc's 150: {s:?}"
        );
        near(
            bc.position_ik(DVec3::new(10.0, 20.0, 30.0), 30.0, 60.0),
            [4.330127, 18.660254, 32.141016],
            1e-6,
        );
        let mut bc2 = bc.clone();
        bc2.rot_point = [10.0, -5.0, 2.0];
        bc2.offset = [-4.0, 0.0, 20.0];
        bc2.tool_offset = 100.0;
        near(
            bc2.position_ik(DVec3::new(3.0, 4.0, 5.0), -30.0, -120.0),
            [77.745191, -3.437822, 28.322142],
            1e-6,
        );

        let ab = Kinematics::new(KinKind::TableAb);
        near(
            ab.tool_axis(25.0, -40.0),
            [-0.642788, -0.323744, 0.694272],
            1e-6,
        );
        let s = ab.orientation_ik(ab.tool_axis(25.0, -40.0), 0.0);
        assert!((s[0].0 - 25.0).abs() < 1e-9 && (s[0].1 + 40.0).abs() < 1e-9);
        assert!(
            (s[1].0 - 205.0).abs() < 1e-9 && (s[1].1 - 220.0).abs() < 1e-9,
            "other branch (−155 ≡ 205, 220): {s:?}"
        );
        let mut ab2 = ab.clone();
        ab2.rot_point = [10.0, -5.0, 2.0];
        ab2.offset = [5.0, 0.0, 7.0];
        ab2.tool_offset = 3.0;
        near(
            ab2.position_ik(DVec3::new(3.0, 4.0, 5.0), 25.0, -40.0),
            [2.614374, 0.198442, 7.088221],
            1e-6,
        );

        let mut hh = Kinematics::new(KinKind::HeadBc);
        hh.pivot = 250.0;
        near(
            hh.forward(&Joints {
                xyz: DVec3::new(1.0, 2.0, 3.0),
                first: 45.0,
                second: 30.0,
            })
            .0,
            [154.093109, 90.388348, 76.223305],
            1e-6,
        );
        let (tip, k) = hh.forward(&Joints {
            xyz: DVec3::ZERO,
            first: 30.0,
            second: 0.0,
        });
        near(tip, [125.0, 0.0, 33.493649], 1e-6);
        near(k, [-0.5, 0.0, 0.866025], 1e-6);
    }

    #[test]
    fn signs_and_limits() {
        let mut ac = Kinematics::new(KinKind::TableAc);
        ac.first.sign = -1.0;
        // A negative-sense A axis: the same axis vector needs the opposite angle.
        near(
            ac.tool_axis(-45.0, 30.0),
            [0.353553, 0.612372, 0.707107],
            1e-6,
        );
        ac.first.sign = 1.0;
        ac.first.min = Some(0.0);
        ac.first.max = Some(110.0);
        let sols = ac.inverse(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(0.0, -0.5, 0.8660254),
            170.0,
        );
        assert_eq!(sols.len(), 1, "only A ≥ 0 is allowed");
        assert!(
            (sols[0].second - 180.0).abs() < 1e-9,
            "C nearest 170: {sols:?}"
        );
        let t = "kind = \"table-bc\"\nrot_point = [1, 2, 3]\n[first]\nmin = -30\nmax = 110\n[second]\nsign = -1\n";
        let k = Kinematics::from_toml(t).expect("valid");
        assert_eq!(
            (k.kind, k.second.sign, k.first.max),
            (KinKind::TableBc, -1.0, Some(110.0))
        );
        assert!(Kinematics::from_toml("kind = \"table-xy\"").is_err());
        let e = Kinematics::from_toml("kind = \"table-ac\"\n[first]\nmin = -30\nsgn = 1\n")
            .expect_err("a misspelt key");
        assert!(e.contains("sgn") && e.contains("line 4"), "{e}");
        assert!(Kinematics::from_toml("kind = \"head-bc\"\n[first]\nsign = 2\n").is_err());
    }

    #[test]
    fn check_names_the_field_out_of_range() {
        let field = |t: &str| {
            Kinematics::from_toml(t)
                .expect_err("out of range")
                .split(':')
                .next()
                .map(str::to_string)
        };
        let f = |s: &str| Some(s.to_string());
        assert_eq!(
            field("kind = \"table-ac\"\n[first]\nsign = 2\n"),
            f("first.sign")
        );
        assert_eq!(
            field("kind = \"table-ac\"\n[second]\nmin = nan\n"),
            f("second.min")
        );
        assert_eq!(
            field("kind = \"table-ac\"\n[first]\nmax = inf\n"),
            f("first.max")
        );
        assert_eq!(
            field("kind = \"table-ac\"\n[first]\nmin = 10\nmax = -10\n"),
            f("first.min")
        );
        assert_eq!(
            field("kind = \"table-ac\"\nrot_point = [0, nan, 0]\n"),
            f("rot_point[1]")
        );
        assert_eq!(field("kind = \"head-bc\"\npivot = -inf\n"), f("pivot"));
        // A locked axis (min = max) is a range, not an error.
        Kinematics::from_toml("kind = \"table-ac\"\n[first]\nmin = 0\nmax = 0\n")
            .expect("locked axis");
    }

    #[test]
    fn rotary_names_follow_the_arrangement() {
        assert_eq!(KinKind::TableAc.rotary_names(), ['A', 'C']);
        assert_eq!(KinKind::TableAb.rotary_names(), ['A', 'B']);
        assert_eq!(KinKind::TableBc.rotary_names(), ['B', 'C']);
        assert_eq!(KinKind::HeadBc.rotary_names(), ['B', 'C']);
        assert_eq!(KinKind::HeadBTableC.rotary_names(), ['B', 'C']);
    }

    /// The machine of kind number `kind` (of five) with every offset set,
    /// for the properties below.
    fn offset_machine(kind: usize) -> Kinematics {
        let kinds = [
            KinKind::TableAc,
            KinKind::TableBc,
            KinKind::TableAb,
            KinKind::HeadBc,
            KinKind::HeadBTableC,
        ];
        let mut k = Kinematics::new(kinds[kind]);
        k.rot_point = [10.0, -5.0, 2.0];
        k.offset = [-4.0, 3.0, 20.0];
        k.tool_offset = 100.0;
        k.pivot = 250.0;
        k
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn inverse_of_forward_is_identity(
            kind in 0usize..5, x in -300.0..300.0f64, y in -300.0..300.0f64, z in -300.0..300.0f64,
            a in -85.0..85.0f64, c in -179.0..179.0f64, sign in any::<bool>(),
        ) {
            prop_assume!(a.abs() > 0.5);
            let mut k = offset_machine(kind);
            if sign { k.second.sign = -1.0; }
            let j = Joints { xyz: DVec3::new(x, y, z), first: a, second: c };
            let (tip, axis) = k.forward(&j);
            prop_assert!((axis.length() - 1.0).abs() < 1e-12);
            let sols = k.inverse(tip, axis, c);
            prop_assert_eq!(sols.len(), 2);
            for s in &sols {
                let (t2, k2) = k.forward(s);
                prop_assert!((t2 - tip).length() < 1e-9, "{:?} {:?}", t2, tip);
                prop_assert!((k2 - axis).length() < 1e-9);
            }
            // One of the two branches is the joints we started from.
            let same = |s: &Joints| (s.xyz - j.xyz).length() < 1e-7 && (s.first - a).abs() < 1e-7 && (s.second - c).abs() < 1e-7;
            prop_assert!(sols.iter().any(same), "{:?} vs {:?}", sols, j);
        }

        /// `forward` takes its sines once for both results: the tip of
        /// `tip` and the axis of `tool_axis`, to the bit.
        #[test]
        fn forward_is_tip_and_tool_axis_to_the_bit(
            kind in 0usize..5, x in -300.0..300.0f64, y in -300.0..300.0f64, z in -300.0..300.0f64,
            a in -120.0..120.0f64, c in -400.0..400.0f64, sign in any::<bool>(),
        ) {
            let mut k = offset_machine(kind);
            if sign { k.first.sign = -1.0; }
            let j = Joints { xyz: DVec3::new(x, y, z), first: a, second: c };
            let (tip, axis) = k.forward(&j);
            let bits = |v: DVec3| v.to_array().map(f64::to_bits);
            prop_assert_eq!(bits(tip), bits(k.tip(&j)));
            prop_assert_eq!(bits(axis), bits(k.tool_axis(a, c)));
        }
    }
}
