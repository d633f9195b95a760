//! The one rule for the dialect a program is written in: `--to`; else the
//! machine file's control, which the output file's extension must not
//! contradict; else the output file's extension; else the source's own
//! dialect. Never a silent default: a program whose target none of these
//! names is refused.

use millplan_nc::write::Target;
use millplan_nc::Dialect;
use millplan_plan::machine::Machine;
use std::path::Path;

/// The dialect to write `output` in (see the module docs); the error says
/// what the user must give.
pub fn output_target(
    to: Option<Target>,
    output: &Path,
    machine: Option<&Machine>,
    source: Dialect,
) -> Result<Target, String> {
    if let Some(t) = to {
        return Ok(t);
    }
    let by_name = output
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Target::from_extension);
    match (machine.and_then(Machine::target), by_name) {
        (Some(m), Some(n)) if m != n => Err(format!(
            "{}: the machine file says {} but the file name says {}: give --to",
            output.display(),
            m.name(),
            n.name()
        )),
        (Some(m), _) => Ok(m),
        (None, Some(n)) => Ok(n),
        (None, None) => Target::of(source).ok_or_else(|| {
            format!(
                "{}: say which dialect to write with --to (the file name's extension names none)",
                output.display()
            )
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fanuc_machine() -> Machine {
        let mut m = Machine::default();
        m.control.dialect = Some(Target::Fanuc);
        m
    }

    #[test]
    fn to_wins_then_machine_then_name_then_source() {
        let m = fanuc_machine();
        let p = Path::new("out.mpf");
        assert_eq!(
            output_target(Some(Target::Apt), p, Some(&m), Dialect::AptIso),
            Ok(Target::Apt)
        );
        assert!(output_target(None, p, Some(&m), Dialect::AptIso).is_err());
        let bare = Path::new("out");
        assert_eq!(
            output_target(None, bare, Some(&m), Dialect::AptIso),
            Ok(Target::Fanuc)
        );
        assert_eq!(
            output_target(None, p, None, Dialect::AptIso),
            Ok(Target::Sinumerik)
        );
        assert_eq!(
            output_target(None, bare, None, Dialect::AptIso),
            Ok(Target::Apt)
        );
    }
}
