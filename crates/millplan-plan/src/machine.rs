//! What the machine can do: spindle and feed ranges, spindle acceleration, the
//! control dialect. Read from TOML; a sensible default is built in.

use millplan_nc::write::Target;

/// A machine description.
///
/// ```toml
/// name = "HSC 5-axis"
/// spindle_min = 500.0        # 1/min
/// spindle_max = 18000.0      # 1/min
/// spindle_accel = 6000.0     # 1/min per second
/// feed_min = 1.0             # mm/min
/// feed_max = 20000.0         # mm/min
/// rapid = 15000.0            # mm/min
/// dialect = "fanuc"          # fanuc | sinumerik | heidenhain | linuxcnc | apt
/// ```
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Machine {
    #[serde(default = "default_name")]
    pub name: String,
    pub spindle_min: f64,
    pub spindle_max: f64,
    pub spindle_accel: f64,
    #[serde(default = "default_feed_min")]
    pub feed_min: f64,
    pub feed_max: f64,
    #[serde(default = "default_rapid")]
    pub rapid: f64,
    #[serde(default)]
    pub dialect: Option<String>,
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

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MachineError {
    #[error("{0}")]
    Toml(String),
    #[error("{0}")]
    Invalid(String),
}

impl Default for Machine {
    /// A typical high-speed machining centre.
    fn default() -> Self {
        Machine {
            name: "default HSC machining centre".into(),
            spindle_min: 500.0,
            spindle_max: 18000.0,
            spindle_accel: 6000.0,
            feed_min: 1.0,
            feed_max: 20000.0,
            rapid: 15000.0,
            dialect: None,
        }
    }
}

impl Machine {
    pub fn from_toml(text: &str) -> Result<Machine, MachineError> {
        let m: Machine = toml::from_str(text).map_err(|e| MachineError::Toml(e.to_string()))?;
        m.validate()?;
        Ok(m)
    }

    pub fn validate(&self) -> Result<(), MachineError> {
        let ok = |c: bool, what: &str| {
            if c {
                Ok(())
            } else {
                Err(MachineError::Invalid(what.to_string()))
            }
        };
        ok(
            self.spindle_min >= 0.0 && self.spindle_min < self.spindle_max,
            "need 0 ≤ spindle_min < spindle_max",
        )?;
        ok(
            self.spindle_accel > 0.0,
            "spindle_accel must be positive (1/min per second)",
        )?;
        ok(
            self.feed_min > 0.0 && self.feed_min < self.feed_max,
            "need 0 < feed_min < feed_max",
        )?;
        ok(self.rapid > 0.0, "rapid must be positive")?;
        if let Some(d) = &self.dialect {
            ok(
                self.target().is_some(),
                &format!("unknown dialect `{d}` (fanuc, sinumerik, heidenhain, linuxcnc, apt)"),
            )?;
        }
        Ok(())
    }

    /// The dialect the machine's control reads, when the file names it.
    pub fn target(&self) -> Option<Target> {
        match self.dialect.as_deref()?.to_ascii_lowercase().as_str() {
            "fanuc" | "iso" | "haas" => Some(Target::Fanuc),
            "sinumerik" | "siemens" => Some(Target::Sinumerik),
            "heidenhain" => Some(Target::Heidenhain),
            "linuxcnc" => Some(Target::LinuxCnc),
            "apt" => Some(Target::Apt),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_and_validates() {
        let m = Machine::from_toml("spindle_min = 100\nspindle_max = 12000\nspindle_accel = 3000\nfeed_max = 10000\ndialect = \"heidenhain\"\n").expect("valid");
        assert_eq!(m.target(), Some(Target::Heidenhain));
        assert!(Machine::from_toml(
            "spindle_min = 100\nspindle_max = 50\nspindle_accel = 1\nfeed_max = 1\n"
        )
        .is_err());
        assert!(Machine::from_toml("spindle_max = 50\n").is_err());
        assert!(Machine::from_toml(
            "spindle_min = 1\nspindle_max = 50\nspindle_accel = 1\nfeed_max = 10\ntypo = 1\n"
        )
        .is_err());
        Machine::default().validate().expect("default is valid");
    }
}
