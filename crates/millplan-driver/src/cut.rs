//! `millplan cut`: the forces, torque, power and tool bending of one
//! engagement, from the request as the user gave it to the figures printed.

use crate::check::{arg, tool_shape, Range, MAX_SPINDLE};
use crate::command_defaults::cut::STICKOUT_PER_D;
use millplan_models::cutter::Shape;
use millplan_models::force::case::{evaluate_case, CaseResult, CutCase};
use millplan_models::force::coeffs::{Coeffs, Law};
use millplan_models::force::converge::Refine;
use millplan_models::force::deflect::{Cantilever, DE_RATIO};
use millplan_models::force::edge::Tool;
use millplan_models::force::materials::Materials;
use millplan_models::force::{Grid, MinMax};
pub use millplan_models::leadtilt::Variant;
use millplan_report::svg::{line_plot, Series};
use serde::Serialize;
use std::fmt::Write as _;

/// One engagement as the user describes it (the options of `millplan cut`).
#[derive(Clone, Debug)]
pub struct CutRequest {
    /// `ball:D`, `flat:D` or `bull:D:R`.
    pub tool: String,
    pub flutes: usize,
    /// Degrees.
    pub helix: f64,
    pub fz: f64,
    pub ap: f64,
    /// Stepover to the earlier pass; `None` with `slot`.
    pub ae: Option<f64>,
    pub slot: bool,
    /// Degrees.
    pub lead: f64,
    /// Degrees.
    pub tilt: f64,
    pub variant: Variant,
    pub stickout: Option<f64>,
    pub flute_length: Option<f64>,
    pub modulus: f64,
    pub material: Option<String>,
    /// Own coefficients `KTC,KRC,KAC,KTE,KRE,KAE`.
    pub coeffs: Option<String>,
    pub n: f64,
    pub dz: f64,
    /// Degrees.
    pub dphi: f64,
    pub fixed_grid: bool,
}

/// The evaluated engagement.
pub struct CutOutcome {
    pub result: CaseResult,
    pub lead: f64,
    pub tilt: f64,
    pub variant: Variant,
}

/// Checks the request, builds the case and evaluates it; an `Err` is the
/// user's input.
pub fn run(req: &CutRequest, materials: &Materials) -> Result<CutOutcome, String> {
    let case = build_case(req, materials)?;
    let result = evaluate_case(&case)?;
    Ok(CutOutcome {
        result,
        lead: req.lead,
        tilt: req.tilt,
        variant: req.variant,
    })
}

fn check(a: &CutRequest, d: f64) -> Result<(f64, f64), String> {
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
    let stickout = a.stickout.unwrap_or(STICKOUT_PER_D * d);
    arg("--stickout", stickout, Range::positive(100.0 * d, "mm"))?;
    let (lo, hi) = millplan_models::force::deflect::MODULUS_RANGE;
    arg("--modulus", a.modulus, Range::from(lo, hi, "N/mm²"))?;
    if !(1..=64).contains(&a.flutes) {
        return Err(format!("--flutes {}: must be from 1 to 64", a.flutes));
    }
    Ok((n, stickout))
}

fn law(a: &CutRequest, materials: &Materials) -> Result<Law, String> {
    match (&a.coeffs, &a.material) {
        (Some(c), _) => Ok(Law::Rta(
            Coeffs::parse(c).map_err(|e| format!("--coeffs {e}"))?,
        )),
        (None, Some(m)) => Ok(materials
            .get(m)
            .map_err(|e| format!("--material: {e}"))?
            .law),
        (None, None) => Err("give --material or --coeffs".into()),
    }
}

fn build_case(a: &CutRequest, materials: &Materials) -> Result<CutCase, String> {
    let shape = tool_shape("--tool", &a.tool)?;
    if matches!(shape, Shape::Cone { .. }) {
        return Err("--tool: use ball:D, flat:D or bull:D:R".into());
    }
    let d = 2.0 * shape.radius();
    let (n, stickout) = check(a, d)?;
    let law = law(a, materials)?;
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
        cut: a.variant.cut(a.fz, n, a.lead, a.tilt),
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

/// Ranges in the workpiece frame.
#[derive(Serialize)]
pub struct WorkJson {
    fx: [f64; 2],
    fy: [f64; 2],
    fz: [f64; 2],
}

/// The lead, tilt and variant as given and the tool axis they make in the
/// feed frame (f, c, n).
#[derive(Serialize)]
pub struct OrientationJson {
    lead_deg: f64,
    tilt_deg: f64,
    variant: Variant,
    axis_fcn: [f64; 3],
}

/// `cut --json`.
#[derive(Serialize)]
pub struct CutJson {
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
    orientation: OrientationJson,
}

impl CutOutcome {
    /// The figures of `cut --json`.
    pub fn json(&self) -> CutJson {
        let r = &self.result;
        let (s, e) = (&r.summary, &r.evaluation);
        CutJson {
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
            orientation: OrientationJson {
                lead_deg: self.lead,
                tilt_deg: self.tilt,
                variant: self.variant,
                axis_fcn: self.variant.axis(self.lead, self.tilt).to_array(),
            },
        }
    }

    /// The text report, one figure a line.
    pub fn render_text(&self) -> String {
        let r = &self.result;
        let s = &r.summary;
        let mut o = String::new();
        let rng = |m: MinMax| format!("{:9.1} … {:9.1} N", m.min, m.max);
        let _ = writeln!(o, "F_xy,max {:.1} N", s.fxy_max);
        let _ = writeln!(o, "           tool frame                workpiece frame");
        for (k, name) in ["Fx", "Fy", "Fz"].iter().enumerate() {
            let _ = writeln!(o, "{name}  {}   {}", rng(s.tool[k]), rng(s.work[k]));
        }
        let _ = writeln!(
            o,
            "torque   max {:.1} N·mm, mean {:.1} N·mm",
            s.torque_max, s.torque_mean
        );
        let _ = writeln!(
            o,
            "power    {:.1} W mean, {:.1} W peak",
            s.power_w, s.power_peak_w
        );
        let _ = writeln!(
            o,
            "bending  {:.1} MPa (holder {:.1}, flute root {:.1}), deflection {:.2} µm",
            r.bending.stress,
            r.bending.stress_holder,
            r.bending.stress_flute_root,
            r.bending.deflection * 1000.0
        );
        let _ = writeln!(
            o,
            "grid     dz {} mm, dφ {}° (estimated error {:.2} % from dz, {:.2} % from dφ)",
            r.evaluation.dz,
            r.evaluation.dphi.to_degrees(),
            100.0 * r.evaluation.error_dz,
            100.0 * r.evaluation.error_dphi
        );
        if r.evaluation.cells == 0 {
            let _ = writeln!(o, "note: the edge touches no material in this engagement");
        }
        if self.lead != 0.0 || self.tilt != 0.0 {
            let t = self.variant.axis(self.lead, self.tilt);
            let _ = writeln!(
                o,
                "axis     ({:.4}, {:.4}, {:.4}) in the feed frame (f, c, n)",
                t.x, t.y, t.z
            );
        }
        o
    }

    /// The force curves over one revolution as CSV.
    pub fn curves_csv(&self) -> String {
        let mut s = String::from("phi_deg,fx,fy,fz,fx_w,fy_w,fz_w,torque\n");
        for p in self.result.evaluation.revolution() {
            let (t, w) = (p.tool, p.work);
            let _ = writeln!(
                s,
                "{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}",
                p.phi.to_degrees(),
                t[0],
                t[1],
                t[2],
                w[0],
                w[1],
                w[2],
                p.torque
            );
        }
        s
    }

    /// The force curves over one revolution as an SVG plot.
    pub fn curves_svg(&self) -> String {
        let rev = self.result.evaluation.revolution();
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
}

/// The built-in materials plus those of a TOML text (`--materials`), named
/// `origin` in its errors.
pub fn materials(text: Option<(&str, &str)>) -> Result<Materials, String> {
    Materials::load(text)
}
