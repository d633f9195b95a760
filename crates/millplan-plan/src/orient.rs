//! Tool axes from machine rotary angles: a posted program writes `B-30. C45.`,
//! whose tool axis only the machine's kinematics knows. This pass fills in
//! [`Orient::axis`](millplan_nc::Orient) wherever the program gives angles
//! only, so that the analyses and the writers that need a tool axis (APT
//! output, gouge checks, five-axis posting) have one. Nothing else changes.

use crate::pipeline::{Changes, Context, Pass, PassError, PassInfo};
use millplan_models::kinematics::{KinKind, Kinematics};
use millplan_nc::Program;

pub static INFO: PassInfo = PassInfo {
    name: "orient",
    needs: &[],
    changes: Changes::Annotations,
    does: "tool axes from the rotary angles a program gives, through the machine's kinematics",
};

/// Indices into A, B, C of a machine's first (tilting) and second rotary axis.
pub(crate) fn letters(kind: KinKind) -> (usize, usize) {
    match kind {
        KinKind::TableAc => (0, 2),
        KinKind::TableAb => (0, 1),
        KinKind::TableBc | KinKind::HeadBc | KinKind::HeadBTableC => (1, 2),
    }
}

/// The pass, with the kinematics it resolves through.
pub struct ResolveOrientation {
    pub kinematics: Kinematics,
    /// Orientations given as angles that now have a tool axis.
    pub resolved: usize,
    /// Orientations whose angles do not name both of the machine's rotary
    /// axes (an axis never commanded, or one the machine does not have).
    pub unresolved: usize,
}

impl ResolveOrientation {
    pub fn new(kinematics: Kinematics) -> ResolveOrientation {
        ResolveOrientation {
            kinematics,
            resolved: 0,
            unresolved: 0,
        }
    }
}

impl Pass for ResolveOrientation {
    fn info(&self) -> &'static PassInfo {
        &INFO
    }

    fn run(&mut self, p: &mut Program, _: &Context) -> Result<(), PassError> {
        let (f, s) = letters(self.kinematics.kind);
        let other = 3 - f - s;
        for op in &mut p.operations {
            for o in &mut op.orients {
                if o.axis.is_some() || !o.has_angles() {
                    continue;
                }
                let a = o.angles;
                // An axis the machine does not have must stand at zero.
                let foreign = a[other].is_some_and(|v| v.abs() > 1e-9);
                match (a[f], a[s]) {
                    (Some(first), Some(second)) if !foreign => {
                        o.axis = Some(
                            self.kinematics
                                .tool_axis(first.to_degrees(), second.to_degrees())
                                .normalize(),
                        );
                        self.resolved += 1;
                    }
                    _ => self.unresolved += 1,
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::Machine;
    use crate::pipeline::run;
    use millplan_geom::DVec3;
    use millplan_nc::text;

    /// IR in → IR out: angles of an A/C table become the axis the spec's
    /// forward kinematics gives (A 90°, C 0°: the tool along −Y of the part).
    #[test]
    fn angles_become_tool_axes() {
        let before = text::parse(
            "program - source=fanuc units=mm/declared
op name=-
  tool number=1 name=- line=1
  start (?, ?, ?)
  orient axis=- abc=(1.5707963267948966, -, 0)
  orient axis=- abc=(-, 0.3, -)
  L2 rapid (0, 0, 50) F0 S0 per_minute orient#0
  L3 rapid (0, 0, 40) F0 S0 per_minute orient#1
",
        )
        .expect("parses");
        let mut p = before.clone();
        let cx = Context::new(Machine::default()).verifying();
        let mut pass = ResolveOrientation::new(Kinematics::new(KinKind::TableAc));
        run(&mut [&mut pass], &mut p, &cx).expect("runs");
        let axis = p.operations[0].orients[0].axis.expect("resolved");
        let want = Kinematics::new(KinKind::TableAc).tool_axis(90.0, 0.0);
        assert!((axis - want).length() < 1e-12);
        assert!(
            (axis - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-9
                || (axis - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-9
        );
        // A B angle on an A/C machine names an axis it does not have.
        assert_eq!(p.operations[0].orients[1].axis, None);
        assert_eq!((pass.resolved, pass.unresolved), (1, 1));
        // Nothing but the axis changed.
        let mut q = p.clone();
        q.operations[0].orients[0].axis = None;
        assert_eq!(q, before);
    }
}
