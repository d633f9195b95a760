//! The resource limits of a run (the table is `millplan_geom::limits`):
//! the defaults, with `memory` half of what the process may use (memory,
//! `ulimit -v`, its cgroup's `memory.max`: the least), then
//! `$MILLPLAN_LIMITS` (`moves=1e8,memory=8000`), then every `--limit
//! NAME=VALUE` of the command line, later ones winning. The names of
//! cutting loads and of the feed-per-tooth range given to `--limit` are
//! kept apart, as given, for the commands that limit loads.

use millplan_geom::limits::{amount, default_memory, Exceeded, Limits};

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

/// The limits of a run and the load limits of its command line.
#[derive(Clone, Debug, PartialEq)]
pub struct RunLimits {
    pub resources: Limits,
    /// `--limit fxy=300,torque=2000`: each load's name and value as given,
    /// in order.
    pub loads: Vec<(String, String)>,
}

/// The documented defaults, with `memory` half of what this process may
/// really use (`millplan_geom::limits::default_memory`).
pub fn defaults() -> Limits {
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

/// `base` changed by `$MILLPLAN_LIMITS` (`env`) and then by the `--limit`
/// arguments (several NAME=VALUE may share one, separated by commas); the
/// error names where the bad item came from.
pub fn resolve(base: Limits, env: Option<&str>, args: &[String]) -> Result<RunLimits, String> {
    let mut l = base;
    let items = |s: &str| {
        s.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    for item in env.map(items).unwrap_or_default() {
        set(&mut l, &item).map_err(|e| format!("MILLPLAN_LIMITS: {e}"))?;
    }
    let mut loads = Vec::new();
    for a in args {
        for item in items(a) {
            let name = item
                .split_once('=')
                .map_or(item.as_str(), |(n, _)| n)
                .trim();
            let value = item.split_once('=').map(|(_, v)| v.trim());
            match value.filter(|_| LOAD_NAMES.contains(&name)) {
                Some(v) => loads.push((name.to_string(), v.to_string())),
                None => set(&mut l, &item).map_err(|e| format!("--limit {a}: {e}"))?,
            }
        }
    }
    Ok(RunLimits {
        resources: l,
        loads,
    })
}

fn set(l: &mut Limits, item: &str) -> Result<(), String> {
    let (name, value) = item
        .split_once('=')
        .ok_or_else(|| "write NAME=VALUE, e.g. moves=1e8".to_string())?;
    l.set(name.trim(), value.trim())
}

/// Refuses estimated work whose memory exceeds the `memory` limit; `what`
/// says what would take it (`a raster of 3.2e9 points`).
pub fn check_memory(limits: &Limits, what: &str, bytes: f64) -> Result<(), String> {
    if bytes <= limits.memory as f64 {
        return Ok(());
    }
    let e = Exceeded::new(
        "memory",
        format!(
            "{what} would take about {} MB",
            amount((bytes / 1e6).ceil())
        ),
        (limits.memory / 1_000_000) as f64,
    );
    Err(e.to_string())
}

/// What the `memory` limit leaves a force run's engagement memo
/// ([`millplan_plan::force::EngagementMemo`]) once the stock and the copy
/// each run cuts are counted (as the stock was checked against it), at most
/// the memo's own cap. The memo is a cache: with less it holds fewer
/// strokes, and the loads are the same.
pub fn memo_budget(memory: u64, stock: &millplan_sim::stock::Stock) -> usize {
    let left = memory.saturating_sub(2 * stock.memory_bytes() as u64);
    usize::try_from(left)
        .unwrap_or(usize::MAX)
        .min(millplan_plan::force::MEMO_BYTES)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The environment first, then the command line, later ones winning;
    /// load names kept apart as given.
    #[test]
    fn later_limits_win_and_loads_stay_apart() {
        let args = [
            "moves=2e3, fxy=300".to_string(),
            "moves=5000,torque=2".to_string(),
        ];
        let r = resolve(Limits::default(), Some("moves=1000,line-bytes=99"), &args).expect("ok");
        assert_eq!(r.resources.moves, 5000);
        assert_eq!(r.resources.line_bytes, 99);
        let loads = [
            ("fxy".to_string(), "300".to_string()),
            ("torque".into(), "2".into()),
        ];
        assert_eq!(r.loads, loads);
        let e = resolve(Limits::default(), Some("moves"), &[]).expect_err("bad env");
        assert!(e.starts_with("MILLPLAN_LIMITS: write NAME=VALUE"), "{e}");
        let e = resolve(Limits::default(), None, &["nonsense=1".into()]).expect_err("bad arg");
        assert!(e.starts_with("--limit nonsense=1: "), "{e}");
    }

    #[test]
    fn memory_beyond_the_limit_is_refused() {
        let l = Limits {
            memory: 1_000_000_000,
            ..Limits::default()
        };
        assert!(check_memory(&l, "a raster", 9e8).is_ok());
        let e = check_memory(&l, "a raster of 3.2e9 points", 2.5e9).expect_err("too big");
        assert!(
            e.contains("a raster of 3.2e9 points would take about 2500 MB"),
            "{e}"
        );
    }
}
