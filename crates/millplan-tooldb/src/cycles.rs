//! NC fragments that measure a thread mill on the machine's laser and branch on
//! the result (spec §4.4): Heidenhain TNC (TCH PROBE 481/482/483 with Q340, Q260,
//! Q341; Q199 = 0 ok, 1 worn, 2 broken) and a generic Fanuc macro program.
//!
//! The axial measuring point PZ comes from the insert data (formula 2 of paper
//! 002); the fragment writes it where the cycle reads it: the tool table's L-OFFS
//! column on a TNC (`FN 17: SYSWRITE`), macro variable #101 for the Fanuc macro.

use crate::control::Kind;
use crate::db::ToolRecord;

/// What to measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    Length,
    Radius,
    Both,
}

/// Options of a measurement fragment.
#[derive(Clone, Debug)]
pub struct CycleOptions {
    pub kind: Kind,
    pub measure: Measure,
    /// Clearance height above the laser (Q260), mm.
    pub clearance: f64,
    /// Check each tooth (Q341 = 1).
    pub per_tooth: bool,
    /// Axial measuring point, mm.
    pub pz: Option<f64>,
}

/// Heidenhain plain-language program measuring `tool`.
pub fn heidenhain(tool: &ToolRecord, o: &CycleOptions) -> String {
    let (cycle, title) = match o.measure {
        Measure::Length => (481, "TOOL LENGTH"),
        Measure::Radius => (482, "TOOL RADIUS"),
        Measure::Both => (483, "MEASURE TOOL"),
    };
    let q340 = match o.kind {
        Kind::First => 0,
        Kind::Inspection => 1,
    };
    let name = format!("TMEAS{}", tool.number);
    let mut lines: Vec<String> = vec![
        format!("BEGIN PGM {name} MM"),
        format!(
            "; measure T{} {} on the laser ({})",
            tool.number,
            tool.name,
            if q340 == 0 {
                "first measurement"
            } else {
                "inspection"
            }
        ),
        format!("TOOL CALL {} Z", tool.number),
    ];
    if let Some(pz) = o.pz {
        lines.push(format!(
            "; PZ {pz:.3} mm: axial point of the radius measurement, from the insert data"
        ));
        // Tool table column L-OFFS (ID 50, NR 10) of this tool.
        lines.push(format!(
            "FN 17: SYSWRITE ID 50 NR 10 IDX{} = +{pz:.3}",
            tool.number
        ));
    }
    lines.push(format!("TCH PROBE {cycle} {title} ~"));
    lines.push(format!("  Q340={q340} ;CHECK ~"));
    lines.push(format!("  Q260=+{:.3} ;CLEARANCE HEIGHT ~", o.clearance));
    lines.push(format!(
        "  Q341={} ;PROBING THE TEETH",
        u8::from(o.per_tooth)
    ));
    lines.push("FN 9: IF +Q199 EQU +0 GOTO LBL \"OK\"".into());
    lines.push("FN 9: IF +Q199 EQU +2 GOTO LBL \"BROKEN\"".into());
    lines.push("; Q199 = 1: worn beyond LTOL/RTOL, the control has locked the tool".into());
    lines.push("FN 14: ERROR = 1 ; tool worn: change to the sister tool".into());
    lines.push("LBL \"BROKEN\"".into());
    lines.push("; Q199 = 2: broken beyond LBREAK/RBREAK: inspect the last thread".into());
    lines.push("FN 14: ERROR = 2 ; tool broken: part suspect".into());
    lines.push("LBL \"OK\"".into());
    lines.push(format!("END PGM {name} MM"));
    lines
        .iter()
        .enumerate()
        .map(|(i, l)| format!("{i} {l}\n"))
        .collect()
}

/// Fanuc macro-B program measuring `tool`: it calls a laser measuring macro (O9853,
/// as the machine builder installs it; adjust the number to yours) with the mode
/// and PZ, then branches on the status in #199 (0 ok, 1 worn, 2 broken).
pub fn fanuc(tool: &ToolRecord, o: &CycleOptions) -> String {
    let mode = match (o.kind, o.measure) {
        (Kind::First, _) => 0,
        (Kind::Inspection, _) => 1,
    };
    let what = match o.measure {
        Measure::Length => 1,
        Measure::Radius => 2,
        Measure::Both => 3,
    };
    let mut s = String::new();
    s.push_str("%\n");
    s.push_str(&format!(
        "O{:04} (MEASURE T{} {})\n",
        8000 + tool.number % 1000,
        tool.number,
        tool.name.to_ascii_uppercase()
    ));
    s.push_str(&format!("T{} M6\n", tool.number));
    s.push_str(&format!(
        "#101 = {:.3} (PZ AXIAL MEASURING POINT)\n",
        o.pz.unwrap_or(0.0)
    ));
    s.push_str(&format!(
        "#102 = {mode} (0 FIRST MEASUREMENT 1 INSPECTION)\n"
    ));
    s.push_str(&format!("#103 = {what} (1 LENGTH 2 RADIUS 3 BOTH)\n"));
    s.push_str(&format!(
        "#104 = {} (1 EACH TOOTH)\n",
        u8::from(o.per_tooth)
    ));
    s.push_str(&format!(
        "G65 P9853 T{} Z#101 Q#102 M#103 E#104 R{:.3}\n",
        tool.number, o.clearance
    ));
    s.push_str("IF [#199 EQ 0] GOTO 100\n");
    s.push_str("IF [#199 EQ 2] GOTO 200\n");
    s.push_str("#3000 = 1 (TOOL WORN - CHANGE TO SISTER TOOL)\n");
    s.push_str("N200 #3000 = 2 (TOOL BROKEN - INSPECT LAST THREAD)\n");
    s.push_str("N100 M99\n");
    s.push_str("%\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tool() -> ToolRecord {
        let mut t = ToolRecord::new(5, "MTE D13.7");
        t.iso.insert("INSL".into(), "14.0".into());
        t.iso.insert("TP".into(), "1.0".into());
        t
    }

    #[test]
    fn heidenhain_fragment_golden() {
        let o = CycleOptions {
            kind: Kind::Inspection,
            measure: Measure::Both,
            clearance: 100.0,
            per_tooth: true,
            pz: Some(0.5),
        };
        let want = "0 BEGIN PGM TMEAS5 MM
1 ; measure T5 MTE D13.7 on the laser (inspection)
2 TOOL CALL 5 Z
3 ; PZ 0.500 mm: axial point of the radius measurement, from the insert data
4 FN 17: SYSWRITE ID 50 NR 10 IDX5 = +0.500
5 TCH PROBE 483 MEASURE TOOL ~
6   Q340=1 ;CHECK ~
7   Q260=+100.000 ;CLEARANCE HEIGHT ~
8   Q341=1 ;PROBING THE TEETH
9 FN 9: IF +Q199 EQU +0 GOTO LBL \"OK\"
10 FN 9: IF +Q199 EQU +2 GOTO LBL \"BROKEN\"
11 ; Q199 = 1: worn beyond LTOL/RTOL, the control has locked the tool
12 FN 14: ERROR = 1 ; tool worn: change to the sister tool
13 LBL \"BROKEN\"
14 ; Q199 = 2: broken beyond LBREAK/RBREAK: inspect the last thread
15 FN 14: ERROR = 2 ; tool broken: part suspect
16 LBL \"OK\"
17 END PGM TMEAS5 MM
";
        assert_eq!(heidenhain(&tool(), &o), want);
    }

    #[test]
    fn fanuc_fragment_golden() {
        let o = CycleOptions {
            kind: Kind::First,
            measure: Measure::Radius,
            clearance: 50.0,
            per_tooth: false,
            pz: Some(0.5),
        };
        let want = "%
O8005 (MEASURE T5 MTE D13.7)
T5 M6
#101 = 0.500 (PZ AXIAL MEASURING POINT)
#102 = 0 (0 FIRST MEASUREMENT 1 INSPECTION)
#103 = 2 (1 LENGTH 2 RADIUS 3 BOTH)
#104 = 0 (1 EACH TOOTH)
G65 P9853 T5 Z#101 Q#102 M#103 E#104 R50.000
IF [#199 EQ 0] GOTO 100
IF [#199 EQ 2] GOTO 200
#3000 = 1 (TOOL WORN - CHANGE TO SISTER TOOL)
N200 #3000 = 2 (TOOL BROKEN - INSPECT LAST THREAD)
N100 M99
%
";
        assert_eq!(fanuc(&tool(), &o), want);
    }
}
