//! The tool a report names is the one each operation uses: the spindle
//! control's report names the ball of the ball-end operation, `force` and
//! `feed` every tool that cuts. SOLIDWORKS CAM preselects the next tool
//! (`SELECT/TOOL`) right after loading one (`LOAD/TOOL`): the ball `T8` was
//! shown as the flat `T17` it was preselected under.

use millplan_driver::speed::{cutting_tools, tool_name};
use millplan_nc::{parse_program, Program, ReadOptions};

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

/// A drill (T16, a cycle), a flat end mill D14 (T17) and a ball end mill
/// D14 (T8), each loaded as SOLIDWORKS CAM writes it: `LOAD/TOOL` of the
/// tool cutting next, then `SELECT/TOOL` of the one after.
const MULTI_TOOL: &str = "PARTNO/1
UNIT/MM
CUTTER/6.5,0,3.25,1.952797,31.,0,105.
LOAD/TOOL,16
SELECT/TOOL,17
SPINDL/3462,RPM,CLW
RAPID/
GOTO/67.5,107.5,25.
CYCLE/DEEP2,FEDTO,15.261,1STPECK,5.,SUBPECK,2.,MMPM,228.7,RAPTO,3.,RTRCTO,31.76
GOTO/67.5,107.5,-6.76
CYCLE/OFF
CUTTER/14.,0,7.,0,0,0,84.
LOAD/TOOL,17
SELECT/TOOL,8
SPINDL/3000,RPM,CLW
RAPID/
GOTO/0,0,5
FEDRAT/500,MMPM
GOTO/0,0,-2
GOTO/40,0,-2
GOTO/40,10,-2
CUTTER/14.,7.,0,7.,0,0,73.
LOAD/TOOL,8
SELECT/TOOL,17
SPINDL/3146,RPM,CLW
RAPID/
GOTO/0,20,5
FEDRAT/800,MMPM
GOTO/0,20,-1
GOTO/40,20,-1.5
GOTO/40,30,-1
";

fn program(src: &str) -> Program {
    parse_program(src, ReadOptions::default())
        .expect("reads")
        .program
}

/// The tool of a ball-end operation in the spindle report is the ball, by
/// the number its operation loaded; `force` and `feed` name every tool
/// that cuts, the flat and the ball, in their order.
#[test]
fn the_report_names_the_tool_each_operation_uses() {
    let p = program(MULTI_TOOL);
    let ball = tool_name(&p);
    assert!(ball.starts_with("T8"), "{ball}");
    assert!(ball.contains("D14.000 R7.000 (ball)"), "{ball}");
    assert!(!ball.contains("T17") && !ball.contains("T16"), "{ball}");
    let all = cutting_tools(&p);
    let (flat, ball_at) = (all.find("T17").expect(&all), all.find("T8").expect(&all));
    assert!(flat < ball_at, "{all}");
    assert!(
        !all.contains("T16"),
        "the drill's cycle is no cutting move: {all}"
    );
}

/// Without a ball the spindle report names the first cutting tool; without
/// any tool it says the program names none.
#[test]
fn without_a_ball_the_first_cutting_tool_is_named() {
    let flat_only: String = MULTI_TOOL
        .split("CUTTER/14.,7.")
        .next()
        .expect("head")
        .into();
    let t = tool_name(&program(&flat_only));
    assert!(t.starts_with("T17") && !t.contains("ball"), "{t}");
    let bare = program("UNIT/MM\nFEDRAT/500,MMPM\nGOTO/0,0,0\nGOTO/10,0,0\n");
    assert_eq!(tool_name(&bare), "not named by the program");
    assert_eq!(cutting_tools(&bare), "not named by the program");
}

/// The real SOLIDWORKS CAM program: its ball-end operation is T8.
#[test]
fn solidworks_multi_tool_program_names_the_ball_t8() {
    let Some(path) = shared_data::file("swcam-apt-stl-pairs/Interface-glue.apt") else {
        return;
    };
    let src = std::fs::read_to_string(path).expect("reads");
    let t = tool_name(&program(&src));
    assert!(t.starts_with("T8") && t.contains("(ball)"), "{t}");
    assert!(!t.contains("T17"), "{t}");
}
