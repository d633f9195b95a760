//! millplan's NC layer: the toolpath IR and its verifier, the front ends that read
//! APT/CL and G-code into it, and the back ends that write it out again.
//!
//! Nothing here touches the file system: readers take text (or lines), writers
//! produce text; the `millplan` binary does all I/O.

pub mod apt;
pub mod detect;
pub mod diag;
pub mod equiv;
pub mod gcode;
pub mod generate;
pub mod ir;
pub mod stats;
pub mod text;
pub mod transform;
pub mod verify;
pub mod write;

pub use diag::{Diagnostic, ParseError, Parsed, Severity};
pub use ir::*;

/// Reader settings shared by all front ends.
#[derive(Clone, Copy, Debug)]
pub struct ReadOptions {
    /// Force the source unit instead of reading or inferring it.
    pub units: Option<LengthUnit>,
    /// Feed (mm/min) given to cutting moves that come before any programmed feed.
    pub default_feed: f64,
    /// Chord tolerance (mm) for sampling splines into lines.
    pub chord_tol: f64,
    /// About how many moves the program holds (0: unknown). A hint: the first
    /// operation to get a move reserves room for them at once, instead of
    /// growing (copying, and touching fresh memory) step by step.
    pub expect_moves: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            units: None,
            default_feed: 1000.0,
            chord_tol: 0.002,
            expect_moves: 0,
        }
    }
}

/// Reads a program of any supported format from its text, detecting the format
/// from the content.
pub fn parse_program(src: &str, opts: ReadOptions) -> Result<Parsed, ParseError> {
    let mut r = detect::Reader::new(detect::detect(src), opts);
    for line in src.split('\n') {
        r.line(line)?;
    }
    r.finish()
}
