//! The resource limits of this run (the table is `millplan_geom::limits`):
//! the defaults, with `memory` half of what the process may use (memory,
//! `ulimit -v`, its cgroup's `memory.max`: the least), then
//! `$MILLPLAN_LIMITS` (`moves=1e8,memory=8000`), then every `--limit
//! NAME=VALUE` of the command line, later ones winning.

use crate::error::{CliError, CliResult};
use millplan_geom::limits::{amount, default_memory, Exceeded, Limits};
use std::sync::OnceLock;

static LIMITS: OnceLock<Limits> = OnceLock::new();
static LOADS: OnceLock<Vec<(String, String)>> = OnceLock::new();

/// The names `--limit` gives to cutting loads and the feed-per-tooth range
/// (`millplan feed`, `millplan force`, `millplan optimise`) rather than to
/// resources.
pub const LOAD_NAMES: [&str; 7] = [
    "fxy",
    "torque",
    "power",
    "stress",
    "deflection",
    "fz_min",
    "fz_max",
];

/// The load limits of the command line (`--limit fxy=300,torque=2000`), as
/// given, in order.
pub fn loads() -> Vec<(String, String)> {
    LOADS.get().cloned().unwrap_or_default()
}

/// The limits in force (the defaults until [`init`] ran).
pub fn get() -> Limits {
    LIMITS.get().copied().unwrap_or_else(defaults)
}

/// The documented defaults, with `memory` half of what this process may
/// really use (`millplan_geom::limits::default_memory`).
fn defaults() -> Limits {
    Limits {
        memory: default_memory(total_memory(), address_space(), cgroup_memory()),
        ..Limits::default()
    }
}

/// Physical memory in bytes, where the system says.
fn total_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// The address space this process may map (`ulimit -v`), where limited.
fn address_space() -> Option<u64> {
    #[cfg(target_os = "linux")]
    {
        use rustix::process::{getrlimit, Resource};
        getrlimit(Resource::As).current
    }
    #[cfg(not(target_os = "linux"))]
    None
}

/// The least `memory.max` of this process's cgroup (v2) and the groups
/// above it, where one is set (`max` means none).
fn cgroup_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let rel = text.lines().find_map(|l| l.strip_prefix("0::"))?;
    let mut dir = std::path::Path::new("/sys/fs/cgroup").join(rel.trim_start_matches('/'));
    let mut least: Option<u64> = None;
    loop {
        let max = std::fs::read_to_string(dir.join("memory.max")).ok();
        if let Some(v) = max.and_then(|t| t.trim().parse::<u64>().ok()) {
            least = Some(least.map_or(v, |l| l.min(v)));
        }
        if dir == std::path::Path::new("/sys/fs/cgroup") || !dir.pop() {
            return least;
        }
    }
}

/// Settles the limits from the environment and the `--limit` arguments.
pub fn init(args: &[String]) -> CliResult<()> {
    let mut l = defaults();
    if let Some(env) = std::env::var_os("MILLPLAN_LIMITS") {
        let env = env.to_string_lossy().into_owned();
        for item in env.split(',').filter(|s| !s.trim().is_empty()) {
            set(&mut l, item).map_err(|e| CliError::input(format!("MILLPLAN_LIMITS: {e}")))?;
        }
    }
    let mut loads = Vec::new();
    for a in args {
        // Several NAME=VALUE may share one --limit, separated by commas.
        for item in a.split(',').filter(|s| !s.trim().is_empty()) {
            let name = item.split_once('=').map_or(item, |(n, _)| n).trim();
            if let Some(v) = item
                .split_once('=')
                .map(|(_, v)| v.trim())
                .filter(|_| LOAD_NAMES.contains(&name))
            {
                loads.push((name.to_string(), v.to_string()));
                continue;
            }
            set(&mut l, item).map_err(|e| CliError::input(format!("--limit {a}: {e}")))?;
        }
    }
    let _ = LOADS.set(loads);
    let _ = LIMITS.set(l);
    Ok(())
}

fn set(l: &mut Limits, item: &str) -> Result<(), String> {
    let (name, value) = item
        .split_once('=')
        .ok_or_else(|| "write NAME=VALUE, e.g. moves=1e8".to_string())?;
    l.set(name.trim(), value.trim())
}

/// Refuses estimated work whose memory exceeds the `memory` limit; `what`
/// says what would take it (`a raster of 3.2e9 points`).
pub fn check_memory(what: &str, bytes: f64) -> CliResult<()> {
    let l = get();
    if bytes <= l.memory as f64 {
        return Ok(());
    }
    let e = Exceeded::new(
        "memory",
        format!(
            "{what} would take about {} MB",
            amount((bytes / 1e6).ceil())
        ),
        (l.memory / 1_000_000) as f64,
    );
    Err(CliError::input(e.to_string()))
}
