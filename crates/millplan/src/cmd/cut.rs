//! `millplan cut`: forces, torque, power and tool bending of one engagement.

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use millplan_driver::cut::{CutRequest, Variant};
use std::path::PathBuf;

/// Cutting forces of one engagement (the mechanistic edge-force model, see
/// docs/forces.md): a ball,
/// flat or bull end mill in a planar raster pass of depth --ap, the earlier
/// pass --ae away (or a slot), with lead and tilt for ball-end mills.
///
/// Lead and tilt (the convention of `millplan orient`, docs/leadtilt.md):
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
    /// (R = Rx(tilt)·Ry(lead), axis (sin L, −cos L·sin T,
    /// cos L·cos T)) or lead-then-tilt (R = Ry(lead)·Rx(tilt), axis
    /// (sin L·cos T, −sin T, cos L·cos T)); same signs either way.
    #[arg(long, value_enum, default_value = "tilt-then-lead")]
    pub variant: VariantArg,
    #[command(flatten)]
    pub model: crate::cmd::args::ForceModel,
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
    /// Write the force curves over one revolution as CSV.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the force curves over one revolution as an SVG plot.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
}

pub fn run(a: Args) -> CliResult<i32> {
    let materials = crate::io::read_materials(a.materials.as_deref())?;
    let r = millplan_driver::cut::run(&request(&a), &materials).map_err(CliError::input)?;
    let mut outputs = Outputs::plan(
        &a.materials.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        &[("--csv", a.csv.as_deref()), ("--svg", a.svg.as_deref())],
        true,
    )?;
    if let Some(p) = &a.csv {
        outputs.write(p, r.curves_csv().as_bytes())?;
    }
    if let Some(p) = &a.svg {
        outputs.write(p, r.curves_svg().as_bytes())?;
    }
    outputs.commit()?;
    crate::cmd::print_summary(a.summary.json, || r.json(), || r.render_text());
    Ok(EXIT_OK)
}

fn request(a: &Args) -> CutRequest {
    CutRequest {
        tool: a.tool.clone(),
        flutes: a.flutes,
        helix: a.helix,
        fz: a.fz,
        ap: a.ap,
        ae: a.ae,
        slot: a.slot,
        lead: a.lead,
        tilt: a.tilt,
        variant: a.variant.into(),
        stickout: a.model.stickout,
        flute_length: a.model.flute_length,
        modulus: a.model.modulus,
        material: a.material.clone(),
        coeffs: a.coeffs.clone(),
        n: a.n,
        dz: a.model.dz,
        dphi: a.model.dphi,
        fixed_grid: a.model.fixed_grid,
    }
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
