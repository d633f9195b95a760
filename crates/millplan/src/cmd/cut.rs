//! `millplan cut`: forces, torque, power and tool bending of one engagement.

use crate::cmd::{arg, tool_shape, Range, MAX_SPINDLE};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use millplan_models::cutter::Shape;
use millplan_models::force::case::{evaluate_case, CaseResult, CutCase};
use millplan_models::force::coeffs::{Coeffs, Law};
use millplan_models::force::deflect::{Cantilever, DE_RATIO, E_CARBIDE};
use millplan_models::force::edge::Tool;
use millplan_models::force::materials::Materials;
use millplan_models::force::{Cut, Grid, MinMax};
use millplan_report::svg::{line_plot, Series};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Cutting forces of one engagement (spec process-models.md §1–§2): a ball,
/// flat or bull end mill in a planar raster pass of depth --ap, the earlier
/// pass --ae away (or a slot), with lead and tilt for ball-end mills.
///
/// Prints F_xy,max, the Fx/Fy/Fz ranges over a revolution in the tool frame
/// (x feed, z toward the shank; forces on the tool) and in the workpiece
/// frame, torque, power, bending stress and tip deflection.
#[derive(clap::Args)]
pub struct Args {
    /// Tool: ball:D, flat:D or bull:D:R (diameter, corner radius), mm.
    #[arg(long)]
    pub tool: String,
    /// Number of flutes.
    #[arg(long, default_value_t = 4)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = 30.0, allow_hyphen_values = true)]
    pub helix: f64,
    /// Feed per tooth, mm.
    #[arg(long)]
    pub fz: f64,
    /// Axial depth of cut, mm.
    #[arg(long)]
    pub ap: f64,
    /// Stepover to the earlier pass, mm (the earlier passes lie on −y).
    #[arg(long, conflicts_with = "slot", required_unless_present = "slot")]
    pub ae: Option<f64>,
    /// Full slot: no earlier pass.
    #[arg(long)]
    pub slot: bool,
    /// Lead angle, degrees (positive leans the shank toward the feed).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub lead: f64,
    /// Tilt angle, degrees.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub tilt: f64,
    /// Gauge length from the holder face to the tip, mm (default 3·D).
    #[arg(long)]
    pub stickout: Option<f64>,
    /// Fluted length, mm: makes the tool a stepped cantilever (shank D,
    /// flutes 0.8·D); without it the whole stick-out counts as fluted.
    #[arg(long)]
    pub flute_length: Option<f64>,
    /// Young's modulus of the tool, N/mm².
    #[arg(long, default_value_t = E_CARBIDE)]
    pub modulus: f64,
    /// Named material (`millplan force materials` lists them).
    #[arg(long, conflicts_with = "coeffs", required_unless_present = "coeffs")]
    pub material: Option<String>,
    /// Own coefficients KTC,KRC,KAC,KTE,KRE,KAE (N/mm², N/mm).
    #[arg(long, allow_hyphen_values = true)]
    pub coeffs: Option<String>,
    /// A TOML file of further materials (same form as the built-in table).
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Spindle speed, 1/min.
    #[arg(long)]
    pub n: f64,
    /// Axial slice height, mm.
    #[arg(long, default_value_t = 0.05)]
    pub dz: f64,
    /// Rotation step, degrees.
    #[arg(long, default_value_t = 1.0)]
    pub dphi: f64,
    /// Write the force curves over one revolution as CSV.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the force curves over one revolution as an SVG plot.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    let materials = load_materials(a.materials.as_deref())?;
    let case = build_case(&a, &materials)?;
    let r = evaluate_case(&case).map_err(CliError::input)?;
    let mut outputs = Outputs::plan(
        &[],
        &[("--csv", a.csv.as_deref()), ("--svg", a.svg.as_deref())],
        true,
    )?;
    if let Some(p) = &a.csv {
        outputs.write(p, curves_csv(&r).as_bytes())?;
    }
    if let Some(p) = &a.svg {
        outputs.write(p, curves_svg(&r).as_bytes())?;
    }
    outputs.commit()?;
    if a.json {
        crate::cmd::print_json(to_json(&r));
    } else {
        print_text(&r);
    }
    Ok(EXIT_OK)
}

/// The built-in materials plus those of `--materials`.
pub fn load_materials(path: Option<&Path>) -> CliResult<Materials> {
    let text = match path {
        Some(p) => Some(
            std::fs::read_to_string(p)
                .map_err(|e| CliError::input(format!("{}: cannot read: {e}", p.display())))?,
        ),
        None => None,
    };
    let origin = path.map(|p| p.display().to_string()).unwrap_or_default();
    Materials::load(text.as_deref().map(|t| (t, origin.as_str()))).map_err(CliError::input)
}

fn build_case(a: &Args, materials: &Materials) -> CliResult<CutCase> {
    let shape = tool_shape("--tool", &a.tool)?;
    if matches!(shape, Shape::Cone { .. }) {
        return Err(CliError::input("--tool: use ball:D, flat:D or bull:D:R"));
    }
    let d = 2.0 * shape.radius();
    arg("--fz", a.fz, Range::positive(5.0, "mm"))?;
    arg("--ap", a.ap, Range::positive(4.0 * d, "mm (at most 4·D)"))?;
    if let Some(ae) = a.ae {
        arg("--ae", ae, Range::positive(d, "mm (at most D)"))?;
    }
    arg("--lead", a.lead, Range::from(-80.0, 80.0, "degrees"))?;
    arg("--tilt", a.tilt, Range::from(-80.0, 80.0, "degrees"))?;
    arg("--helix", a.helix, Range::from(-70.0, 70.0, "degrees"))?;
    let n = arg("--n", a.n, Range::positive(MAX_SPINDLE, "1/min"))?;
    arg("--dz", a.dz, Range::from(0.001, 1.0, "mm"))?;
    arg("--dphi", a.dphi, Range::from(0.01, 10.0, "degrees"))?;
    let stickout = a.stickout.unwrap_or(3.0 * d);
    arg("--stickout", stickout, Range::positive(100.0 * d, "mm"))?;
    arg("--modulus", a.modulus, Range::positive(2e6, "N/mm²"))?;
    if !(1..=64).contains(&a.flutes) {
        return Err(CliError::input(format!(
            "--flutes {}: must be from 1 to 64",
            a.flutes
        )));
    }
    let law = match (&a.coeffs, &a.material) {
        (Some(c), _) => {
            Law::Rta(Coeffs::parse(c).map_err(|e| CliError::input(format!("--coeffs {e}")))?)
        }
        (None, Some(m)) => {
            materials
                .get(m)
                .map_err(|e| CliError::input(format!("--material: {e}")))?
                .law
        }
        (None, None) => return Err(CliError::input("give --material or --coeffs")),
    };
    let flute_len = a.flute_length.unwrap_or(stickout);
    Ok(CutCase {
        tool: Tool {
            shape,
            flutes: a.flutes,
            helix: a.helix.to_radians(),
            flute_length: flute_len,
        },
        law,
        grid: Grid {
            dz: a.dz,
            dphi: a.dphi.to_radians(),
        },
        cut: Cut {
            fz: a.fz,
            rpm: n,
            lead: a.lead.to_radians(),
            tilt: a.tilt.to_radians(),
        },
        ap: a.ap,
        ae: if a.slot { None } else { a.ae },
        holding: Cantilever {
            length: stickout,
            shank_d: d,
            flute_d: DE_RATIO * d,
            flute_length: a.flute_length,
            e: a.modulus,
        },
    })
}

fn pair(m: MinMax) -> [f64; 2] {
    [m.min, m.max]
}

fn to_json(r: &CaseResult) -> serde_json::Value {
    let s = &r.summary;
    json!({
        "fxy_max": s.fxy_max,
        "fx": pair(s.tool[0]), "fy": pair(s.tool[1]), "fz": pair(s.tool[2]),
        "mean": s.mean,
        "workpiece": {"fx": pair(s.work[0]), "fy": pair(s.work[1]), "fz": pair(s.work[2])},
        "torque_max": s.torque_max, "torque_mean": s.torque_mean,
        "power_w": s.power_w, "power_peak_w": s.power_peak_w,
        "stress_mpa": r.bending.stress, "deflection_mm": r.bending.deflection,
        "kappa_min_deg": r.evaluation.kappa_min.map(f64::to_degrees),
        "z_max": r.evaluation.z_max,
        "dphi_deg": r.evaluation.dphi.to_degrees(),
    })
}

fn print_text(r: &CaseResult) {
    let s = &r.summary;
    let rng = |m: MinMax| format!("{:9.1} … {:9.1} N", m.min, m.max);
    outln!("F_xy,max {:.1} N", s.fxy_max);
    outln!("           tool frame                workpiece frame");
    for (k, name) in ["Fx", "Fy", "Fz"].iter().enumerate() {
        outln!("{name}  {}   {}", rng(s.tool[k]), rng(s.work[k]));
    }
    outln!(
        "torque   max {:.1} N·mm, mean {:.1} N·mm",
        s.torque_max,
        s.torque_mean
    );
    outln!(
        "power    {:.1} W mean, {:.1} W peak",
        s.power_w,
        s.power_peak_w
    );
    outln!(
        "bending  {:.1} MPa (holder {:.1}, flute root {:.1}), deflection {:.2} µm",
        r.bending.stress,
        r.bending.stress_holder,
        r.bending.stress_flute_root,
        r.bending.deflection * 1000.0
    );
    if r.evaluation.cells == 0 {
        outln!("note: the edge touches no material in this engagement");
    }
}

fn curves_csv(r: &CaseResult) -> String {
    let mut s = String::from("phi_deg,fx,fy,fz,fx_w,fy_w,fz_w,torque\n");
    for p in r.evaluation.revolution() {
        let (t, w) = (p.tool, p.work);
        s.push_str(&format!(
            "{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}\n",
            p.phi.to_degrees(),
            t[0],
            t[1],
            t[2],
            w[0],
            w[1],
            w[2],
            p.torque
        ));
    }
    s
}

fn curves_svg(r: &CaseResult) -> String {
    let rev = r.evaluation.revolution();
    let series = |name: &'static str, color: &'static str, f: fn(&[f64; 3]) -> f64| Series {
        name,
        color,
        points: rev
            .iter()
            .map(|p| (p.phi.to_degrees(), f(&p.tool)))
            .collect(),
    };
    let fxy = Series {
        name: "F_xy",
        color: "#000000",
        points: rev
            .iter()
            .map(|p| (p.phi.to_degrees(), p.tool[0].hypot(p.tool[1])))
            .collect(),
    };
    line_plot(
        "Forces on the tool over one revolution (tool frame)",
        "spindle angle [deg]",
        "force [N]",
        &[
            series("Fx", "#d62728", |t| t[0]),
            series("Fy", "#2ca02c", |t| t[1]),
            series("Fz", "#1f77b4", |t| t[2]),
            fxy,
        ],
    )
}
