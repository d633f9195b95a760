//! `millplan cut`: forces, torque, power and tool bending of one engagement.

use crate::cmd::{arg, tool_shape, Range, MAX_SPINDLE};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use millplan_models::cutter::Shape;
use millplan_models::force::case::{evaluate_case, CaseResult, CutCase};
use millplan_models::force::coeffs::{Coeffs, Law};
use millplan_models::force::converge::Refine;
use millplan_models::force::deflect::{Cantilever, DE_RATIO};
use millplan_models::force::edge::Tool;
use millplan_models::force::materials::Materials;
use millplan_models::force::{Grid, MinMax};
use millplan_models::leadtilt::Variant;
use millplan_report::svg::{line_plot, Series};
use std::path::{Path, PathBuf};

/// Cutting forces of one engagement (spec process-models.md §1–§2): a ball,
/// flat or bull end mill in a planar raster pass of depth --ap, the earlier
/// pass --ae away (or a slot), with lead and tilt for ball-end mills.
///
/// Lead and tilt (process-models §0, the convention of `millplan orient`):
/// in the feed frame (f the feed, n the surface normal, c = n × f, the side
/// the earlier passes are not on) lead turns the tool about c and tilt about
/// f, both right-handed, composed as R = Rx(tilt)·Ry(lead): the axis is
/// (sin L, −cos L·sin T, cos L·cos T). A positive lead leans the shank
/// toward the feed (the tip trails and does not cut); a positive tilt leans
/// it toward −c, the earlier passes' side (right of the feed, seen from the
/// shank). The lead and tilt `orient` reports give here the F_xy,max it
/// reported (same --variant).
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
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::FLUTES)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::HELIX_DEG, allow_hyphen_values = true)]
    pub helix: f64,
    /// Feed per tooth, mm.
    #[arg(long)]
    pub fz: f64,
    /// Axial depth of cut, mm.
    #[arg(long)]
    pub ap: f64,
    /// Stepover to the earlier pass, mm (the earlier passes lie on −y, the
    /// −c side of the feed frame).
    #[arg(long, conflicts_with = "slot", required_unless_present = "slot")]
    pub ae: Option<f64>,
    /// Full slot: no earlier pass.
    #[arg(long)]
    pub slot: bool,
    /// Lead angle, degrees: a right-handed turn about the cross-feed c;
    /// positive leans the shank toward the feed (+f), the tip trailing.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::LEAD_DEG, allow_hyphen_values = true)]
    pub lead: f64,
    /// Tilt angle, degrees: a right-handed turn about the feed f; positive
    /// leans the shank toward −c (the earlier passes' side, right of the
    /// feed seen from the shank).
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::TILT_DEG, allow_hyphen_values = true)]
    pub tilt: f64,
    /// Order of the two turns, as in `orient`: tilt-then-lead
    /// (process-models §0, R = Rx(tilt)·Ry(lead), axis (sin L, −cos L·sin T,
    /// cos L·cos T)) or lead-then-tilt (R = Ry(lead)·Rx(tilt), axis
    /// (sin L·cos T, −sin T, cos L·cos T)); same signs either way.
    #[arg(long, value_enum, default_value = "tilt-then-lead")]
    pub variant: VariantArg,
    /// Gauge length from the holder face to the tip, mm (default 3·D).
    #[arg(long)]
    pub stickout: Option<f64>,
    /// Fluted length, mm: makes the tool a stepped cantilever (shank D,
    /// flutes 0.8·D); without it the whole stick-out counts as fluted.
    #[arg(long)]
    pub flute_length: Option<f64>,
    /// Young's modulus of the tool, N/mm².
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::MODULUS)]
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
    /// Axial slice height, mm: the largest used. The model halves it (up to
    /// four times) until F_xy,max and T_max are estimated within 0.4 %.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::DZ)]
    pub dz: f64,
    /// Rotation step, degrees: the largest used, halved like --dz.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cut::DPHI_DEG)]
    pub dphi: f64,
    /// Use exactly --dz and --dphi, without refining them.
    #[arg(long)]
    pub fixed_grid: bool,
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
        let mut j = to_json(&r);
        j["orientation"] = orientation_json(&a);
        crate::cmd::print_json(j);
    } else {
        print_text(&r);
        if a.lead != 0.0 || a.tilt != 0.0 {
            let t = Variant::from(a.variant).axis(a.lead, a.tilt);
            outln!(
                "axis     ({:.4}, {:.4}, {:.4}) in the feed frame (f, c, n)",
                t.x,
                t.y,
                t.z
            );
        }
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
    let stickout = a
        .stickout
        .unwrap_or(millplan_driver::command_defaults::cut::STICKOUT_PER_D * d);
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
        refine: (!a.fixed_grid).then(Refine::default),
        cut: Variant::from(a.variant).cut(a.fz, n, a.lead, a.tilt),
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

/// The order of the lead and tilt turns (`--variant` of `cut` and `orient`).
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum VariantArg {
    LeadThenTilt,
    TiltThenLead,
}

impl From<VariantArg> for Variant {
    fn from(v: VariantArg) -> Variant {
        match v {
            VariantArg::LeadThenTilt => Variant::LeadThenTilt,
            VariantArg::TiltThenLead => Variant::TiltThenLead,
        }
    }
}

/// The lead, tilt and variant as given and the tool axis they make in the
/// feed frame (f, c, n).
fn orientation_json(a: &Args) -> serde_json::Value {
    let v = Variant::from(a.variant);
    serde_json::json!({
        "lead_deg": a.lead,
        "tilt_deg": a.tilt,
        "variant": v,
        "axis_fcn": v.axis(a.lead, a.tilt).to_array(),
    })
}

fn pair(m: MinMax) -> [f64; 2] {
    [m.min, m.max]
}

/// Ranges in the workpiece frame.
#[derive(serde::Serialize)]
struct WorkJson {
    fx: [f64; 2],
    fy: [f64; 2],
    fz: [f64; 2],
}

/// `cut --json`.
#[derive(serde::Serialize)]
struct CutJson {
    fxy_max: f64,
    fx: [f64; 2],
    fy: [f64; 2],
    fz: [f64; 2],
    mean: [f64; 3],
    workpiece: WorkJson,
    torque_max: f64,
    torque_mean: f64,
    power_w: f64,
    power_peak_w: f64,
    stress_mpa: f64,
    deflection_mm: f64,
    kappa_min_deg: Option<f64>,
    z_max: Option<f64>,
    /// The steps the integrals used, and their estimated relative errors.
    dz_mm: f64,
    dphi_deg: f64,
    error_dz: f64,
    error_dphi: f64,
}

fn to_json(r: &CaseResult) -> serde_json::Value {
    let (s, e) = (&r.summary, &r.evaluation);
    let j = CutJson {
        fxy_max: s.fxy_max,
        fx: pair(s.tool[0]),
        fy: pair(s.tool[1]),
        fz: pair(s.tool[2]),
        mean: s.mean,
        workpiece: WorkJson {
            fx: pair(s.work[0]),
            fy: pair(s.work[1]),
            fz: pair(s.work[2]),
        },
        torque_max: s.torque_max,
        torque_mean: s.torque_mean,
        power_w: s.power_w,
        power_peak_w: s.power_peak_w,
        stress_mpa: r.bending.stress,
        deflection_mm: r.bending.deflection,
        kappa_min_deg: e.kappa_min.map(f64::to_degrees),
        z_max: e.z_max,
        dz_mm: e.dz,
        dphi_deg: e.dphi.to_degrees(),
        error_dz: e.error_dz,
        error_dphi: e.error_dphi,
    };
    serde_json::to_value(j).unwrap_or_default()
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
    outln!(
        "grid     dz {} mm, dφ {}° (estimated error {:.2} % from dz, {:.2} % from dφ)",
        r.evaluation.dz,
        r.evaluation.dphi.to_degrees(),
        100.0 * r.evaluation.error_dz,
        100.0 * r.evaluation.error_dphi
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
