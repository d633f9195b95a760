//! Progress bars (indicatif) for work that can take longer than a second; they draw
//! on standard error only when it is a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A bar of `len` drawn with `template`, its message `what`; hidden unless
/// `show`.
fn styled(len: Option<u64>, template: &str, what: &str, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = len.map_or_else(ProgressBar::new_spinner, ProgressBar::new);
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar
}

/// A byte-count bar, shown only for inputs large enough to take a while.
pub fn bytes(total: u64, what: &str) -> ProgressBar {
    let template = "{msg} [{bar:30}] {bytes}/{total_bytes} {eta}";
    styled(Some(total), template, what, total >= 32 << 20)
}

/// A spinner with a message and the elapsed time, for work without a count.
pub fn spinner(what: &str, show: bool) -> ProgressBar {
    let bar = styled(None, "{spinner} {msg} {elapsed}", what, show);
    if show {
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
    }
    bar
}

/// A counting bar with an estimate of the time left, for a phase of `total`
/// steps: shown when `show` (not `-q`) and standard error is a terminal.
pub fn count(total: u64, what: &str, unit: &str, show: bool) -> ProgressBar {
    let template = format!("{{msg}} [{{bar:30}}] {{human_pos}}/{{human_len}} {unit}, {{eta}} left");
    styled(Some(total), &template, what, show)
}

/// A bar of the share done and the time left, for work whose steps have no
/// name of their own (its length is set by the first report).
pub fn fraction(what: &str, show: bool) -> ProgressBar {
    let template = "{msg} [{bar:30}] {percent:>3} %, {eta} left";
    styled(Some(1), template, what, show)
}

/// One bar for the phases a pipeline's passes report (`Context::progress`):
/// a new phase names itself and starts the count again.
pub struct Phases {
    bar: ProgressBar,
    phase: std::sync::Mutex<String>,
}

impl Phases {
    /// A bar drawn when `show` (not `-q`) and standard error is a terminal.
    pub fn new(show: bool) -> Phases {
        let bar = if show {
            ProgressBar::new(0)
        } else {
            ProgressBar::hidden()
        };
        if let Ok(style) =
            ProgressStyle::with_template("{msg} [{bar:30}] {human_pos}/{human_len}, {eta} left")
        {
            bar.set_style(style);
        }
        Phases {
            bar,
            phase: std::sync::Mutex::new(String::new()),
        }
    }

    /// What a pass reported: `done` of the `total` steps of `phase`.
    pub fn report(&self, phase: &str, done: usize, total: usize) {
        if self.bar.is_hidden() {
            return;
        }
        let Ok(mut p) = self.phase.lock() else {
            return;
        };
        if *p == phase {
            self.bar.set_length(total as u64);
            self.bar.set_position(done as u64);
            return;
        }
        // A new phase: name and counts change out of sight, so no frame shows
        // one phase's name with another's count.
        *p = phase.to_string();
        self.bar.set_draw_target(ProgressDrawTarget::hidden());
        self.bar.reset();
        self.bar.set_length(total as u64);
        self.bar.set_position(done as u64);
        self.bar.set_message(phase.to_string());
        self.bar.set_draw_target(ProgressDrawTarget::stderr());
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// What a run of the driver reports, drawn and printed
/// (`millplan_driver::watch::Watch`): the bytes of the program read, its
/// findings (none with `quiet`), the written program's (none with `-q`),
/// the strokes and the passes' phases done (no bar with `quiet`), the
/// checks' refusal.
pub struct Watch<'a> {
    path: &'a std::path::Path,
    quiet: bool,
    notes: bool,
    bars: bool,
    read: std::sync::Mutex<Option<ProgressBar>>,
    strokes: std::sync::Mutex<Option<ProgressBar>>,
    counted: std::sync::Mutex<Option<ProgressBar>>,
    phases: std::sync::OnceLock<Phases>,
    spinner: std::sync::Mutex<Option<ProgressBar>>,
    clock: std::sync::Mutex<crate::timings::Clock>,
}

impl<'a> Watch<'a> {
    /// A watch whose `--timings` clock starts now: `notes` unless `-q`,
    /// bars and the reader's findings unless `-q` or `--json`.
    pub fn new(path: &'a std::path::Path, quiet: bool, json: bool) -> Watch<'a> {
        Watch {
            path,
            quiet: quiet || json,
            notes: !quiet,
            bars: !(quiet || json),
            read: std::sync::Mutex::new(None),
            strokes: std::sync::Mutex::new(None),
            counted: std::sync::Mutex::new(None),
            phases: std::sync::OnceLock::new(),
            spinner: std::sync::Mutex::new(None),
            clock: std::sync::Mutex::new(crate::timings::Clock::start()),
        }
    }

    /// The bars shown under `--json` too (unless `-q`), as the commands
    /// that drew them before `--json` hid them do.
    pub fn bars_under_json(mut self) -> Watch<'a> {
        self.bars = self.notes;
        self
    }

    /// Prints the `--timings` table of the phases so far when `on`.
    pub fn print_timings(&self, on: bool) {
        use crate::timings::Table as _;
        self.clock
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .print(on);
    }
}

/// The bar in `slot`, taken and cleared.
fn clear(slot: &std::sync::Mutex<Option<ProgressBar>>) {
    if let Some(b) = slot.lock().unwrap_or_else(|e| e.into_inner()).take() {
        b.finish_and_clear();
    }
}

impl millplan_driver::watch::Watch for Watch<'_> {
    fn reading(&self, done: u64, total: u64) {
        let mut bar = self.read.lock().unwrap_or_else(|e| e.into_inner());
        bar.get_or_insert_with(|| bytes(total, "reading"))
            .set_position(done);
    }

    fn diagnostics(&self, found: &[millplan_nc::Diagnostic]) {
        clear(&self.read);
        crate::cmd::print_diagnostics(self.path, found, self.quiet);
    }

    fn diagnostics_written(&self, found: &[millplan_nc::Diagnostic]) {
        crate::cmd::print_diagnostics(self.path, found, !self.notes);
    }

    fn strokes(&self, done: usize, total: usize) {
        let mut bar = self.strokes.lock().unwrap_or_else(|e| e.into_inner());
        bar.get_or_insert_with(|| count(total as u64, "forces", "strokes", self.bars))
            .set_position(done as u64);
    }

    fn forces_done(&self) {
        clear(&self.strokes);
    }

    fn lap(&self, name: &str) {
        self.clock
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .lap(name);
    }

    fn phase(&self, phase: &str, done: usize, total: usize) {
        let bar = self.phases.get_or_init(|| Phases::new(self.bars));
        bar.report(phase, done, total);
    }

    fn phases_done(&self) {
        if let Some(b) = self.phases.get() {
            b.finish();
        }
    }

    fn busy(&self, what: Option<&str>) {
        clear(&self.spinner);
        if let Some(what) = what {
            *self.spinner.lock().unwrap_or_else(|e| e.into_inner()) =
                Some(spinner(what, self.bars));
        }
    }

    fn warning(&self, text: &str) {
        eprintln!("{text}");
    }

    fn refused(&self, lines: &[String], forced: bool) {
        for l in lines {
            eprintln!("{l}");
        }
        if forced {
            eprintln!("written anyway (--force)");
        }
    }

    fn findings(&self, path: &std::path::Path, found: &[millplan_nc::Diagnostic]) {
        crate::cmd::print_diagnostics(path, found, self.quiet);
    }

    fn note(&self, text: &str) {
        if !self.quiet {
            eprintln!("{text}");
        }
    }

    fn count(&self, what: &str, unit: Option<&str>, done: usize, total: usize) {
        let mut bar = self.counted.lock().unwrap_or_else(|e| e.into_inner());
        let bar = bar.get_or_insert_with(|| match unit {
            Some(unit) => count(total as u64, what, unit, self.bars),
            None => fraction(what, self.bars),
        });
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }

    fn counted(&self) {
        clear(&self.counted);
    }
}

impl Drop for Watch<'_> {
    /// A run that failed leaves no bar behind.
    fn drop(&mut self) {
        clear(&self.read);
        clear(&self.strokes);
        clear(&self.counted);
        clear(&self.spinner);
        if let Some(b) = self.phases.get() {
            b.finish();
        }
    }
}
