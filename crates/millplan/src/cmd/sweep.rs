//! `millplan wd-sweep`: the working diameter over a grid of cases (thesis 1).

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::write_atomic;
use millplan_models::regression::{samples, Surrogate};
use millplan_models::wd::{self, Case, Neighbour, Side};
use millplan_report::svg::{line_plot, Series};
use std::fmt::Write;
use std::path::PathBuf;

/// Tabulate and plot the working diameter over tool diameter, depth of cut,
/// stepover, feed direction, inclination and up/down milling — the study design of
/// thesis 1 (D 6-8-10 mm, ap 0.1–1.0 mm, ae 1 mm, A_f 0–180°).
///
/// Writes OUT/wd_sweep.csv (one row per case) and OUT/wd_sweep.html with one SVG
/// plot per tool diameter and milling side; with --fit also reports how well the
/// regression surrogate (thesis 2) matches the geometric model.
#[derive(clap::Args)]
pub struct Args {
    /// Output folder.
    #[arg(short, long, default_value = "wd-sweep")]
    pub output: PathBuf,
    /// Tool diameters, mm.
    #[arg(long, value_delimiter = ',', default_value = "6,8,10")]
    pub d: Vec<f64>,
    /// Depths of cut, mm.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.25,0.5,0.75,1.0")]
    pub ap: Vec<f64>,
    /// Stepover to the machined neighbour, mm (0 = no neighbour).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub ae: Vec<f64>,
    /// Inclinations, degrees.
    #[arg(long, value_delimiter = ',', default_value = "0,10,20,30,45,60")]
    pub alpha: Vec<f64>,
    /// Feed-direction step over 0–180°, degrees.
    #[arg(long, default_value_t = 5.0)]
    pub af_step: f64,
    /// Also fit the regression surrogate and print R², RMSE and MAPE.
    #[arg(long)]
    pub fit: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    if !(a.af_step > 0.0)
        || a.d.iter().chain(&a.ap).any(|v| !(*v > 0.0))
        || a.alpha.iter().any(|v| !(0.0..90.0).contains(v))
    {
        return Err(CliError::input(
            "diameters and depths must be positive, inclinations in [0, 90), --af-step > 0",
        ));
    }
    std::fs::create_dir_all(&a.output)
        .map_err(|e| CliError::input(format!("{}: {e}", a.output.display())))?;
    let mut csv = String::from("d,ap,ae,alpha_deg,af_deg,uncut_side,milling,d_w,d_cc,n_at_vc63\n");
    let mut html = String::from("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Working diameter sweep</title></head><body style=\"font-family:sans-serif\"><h1>Working diameter sweep</h1>");
    let colors = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
    ];
    let steps = (180.0 / a.af_step).round() as usize;
    for &d in &a.d {
        for &ae in &a.ae {
            for side in [Side::Right, Side::Left] {
                // With M3: uncut on the right = climb (down) milling.
                let milling = if side == Side::Right { "down" } else { "up" };
                for &ap in &a.ap {
                    let mut series = Vec::new();
                    for (k, &alpha) in a.alpha.iter().enumerate() {
                        let mut pts = Vec::new();
                        for i in 0..=steps {
                            let af = (a.af_step * i as f64).min(180.0);
                            let c = Case {
                                d,
                                ap,
                                neighbour: if ae > 0.0 {
                                    Neighbour::One(ae)
                                } else {
                                    Neighbour::None
                                },
                                alpha: alpha.to_radians(),
                                af: af.to_radians(),
                                side,
                            };
                            let dw = wd::working_diameter(&c);
                            let _ = writeln!(
                                csv,
                                "{d},{ap},{ae},{alpha},{af},{},{milling},{dw:.5},{:.5},{:.1}",
                                if side == Side::Left { "left" } else { "right" },
                                wd::contact_diameter(d, c.alpha),
                                wd::spindle_speed(63.0, dw)
                            );
                            pts.push((af, dw));
                        }
                        series.push(Series {
                            name: "",
                            color: colors[k % colors.len()],
                            points: pts,
                        });
                    }
                    let names: Vec<String> = a.alpha.iter().map(|x| format!("α = {x}°")).collect();
                    for (s, n) in series.iter_mut().zip(&names) {
                        s.name = n;
                    }
                    let _ = write!(
                        html,
                        "<figure>{}</figure>",
                        line_plot(
                            &format!("D = {d} mm, ap = {ap} mm, ae = {ae} mm, {milling} milling"),
                            "relative feed direction A_f (°)",
                            "D_w (mm)",
                            &series
                        )
                    );
                }
            }
        }
    }
    if a.fit {
        let s = Surrogate::fit(&samples());
        let _ = write!(
            html,
            "<h2>Regression surrogate (thesis 2)</h2><p>{} samples, R² {:.4}, RMSE {:.4} mm, MAPE {:.2} %</p>",
            s.fit.samples, s.fit.r2, s.fit.rmse, s.fit.mape
        );
        println!(
            "regression surrogate: {} samples, R² {:.4}, RMSE {:.4} mm, MAPE {:.2} %",
            s.fit.samples, s.fit.r2, s.fit.rmse, s.fit.mape
        );
    }
    html.push_str("</body></html>");
    let (c, h) = (
        a.output.join("wd_sweep.csv"),
        a.output.join("wd_sweep.html"),
    );
    write_atomic(&c, csv.as_bytes(), &[])?;
    write_atomic(&h, html.as_bytes(), &[])?;
    println!("wrote {} and {}", c.display(), h.display());
    Ok(EXIT_OK)
}
