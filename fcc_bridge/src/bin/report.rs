//! `fcc-report BAG [--out DIR] [--mission FILE]`: a flight's figures (summary.txt, summary.json,
//! report.html) and PNG plots from a bag written by `fcc-bridge --record`.

use clap::Parser;
use fcc_bridge::report::bag;
use fcc_bridge::report::{
    figures,
    plot::{chart, panels, Line},
};
use plotters::style::{RGBColor, BLUE, GREEN, MAGENTA, RED};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "fcc-report",
    about = "Figures and plots of a flight from its MCAP bag"
)]
struct Cli {
    bag: PathBuf,
    /// Output directory (default: BAG's name without .mcap + _report).
    #[arg(long)]
    out: Option<PathBuf>,
    /// The mission flown (legs for the cross-track figures).
    #[arg(long)]
    mission: Option<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let out = cli.out.clone().unwrap_or_else(|| {
        cli.bag.with_extension("").with_file_name(format!(
            "{}_report",
            cli.bag.file_stem().unwrap_or_default().to_string_lossy()
        ))
    });
    std::fs::create_dir_all(&out)?;
    let msgs = read_with_progress(&cli.bag)?;
    let mission = load_mission(cli.mission.as_deref())?;
    let s = figures::decode(&msgs);
    let f = figures::compute(&s, mission.as_ref());
    let text = f.to_string();
    print!("{text}");
    std::fs::write(out.join("summary.txt"), &text)?;
    std::fs::write(out.join("summary.json"), serde_json::to_string_pretty(&f)?)?;

    let v = View {
        s: &s,
        f: &f,
        out: &out,
        t0: s.odom.first().map_or(0.0, |o| o.0),
    };
    let mut plots: Vec<Plot> = Vec::new();
    for plot in [
        path_plot,
        hover_plot,
        velocity_plot,
        attitude_plot,
        vertical_plot,
        ground_plot,
        observer_plot,
        k_fit_plot,
    ] {
        plot(&v, &mut plots);
    }
    write_html(&out, &cli.bag, &text, &plots)?;
    let ok = plots.iter().filter(|p| p.2.is_ok()).count();
    eprintln!(
        "fcc-report: {ok} plots, summary.txt, summary.json and report.html in {}",
        out.display()
    );
    Ok(())
}

/// What the plots are drawn from: the decoded series, the figures, the output directory and
/// the time origin (the first odometry message).
struct View<'a> {
    s: &'a figures::Series,
    f: &'a figures::Figures,
    out: &'a Path,
    t0: f64,
}

/// A plot: its file, its title in the HTML, and whether it was drawn.
type Plot = (&'static str, &'static str, Result<(), String>);

/// Read the bag with a progress bar: the file is read (bytes), then decoded message by message
/// against the summary's message count; a bag without a summary (cut by SIGKILL) shows the
/// bytes decoded instead. A cut bag gives the messages before the cut, with a warning.
fn read_with_progress(path: &Path) -> anyhow::Result<Vec<bag::BagMsg>> {
    let pb = indicatif::ProgressBar::new(1);
    let style = |unit: bag::Progress| {
        let t = match unit {
            bag::Progress::FileBytes => "{msg} [{bar:40}] {bytes}/{total_bytes}",
            bag::Progress::Messages => "{msg} [{bar:40}] {human_pos}/{human_len} messages",
            bag::Progress::Bytes => "{msg} [{bar:40}] {bytes}/{total_bytes} (no summary)",
        };
        indicatif::ProgressStyle::with_template(t).unwrap()
    };
    let mut shown: Option<bag::Progress> = None;
    let (msgs, err) = bag::read_bag(path, |unit, d, t| {
        if shown != Some(unit) {
            shown = Some(unit);
            pb.set_style(style(unit));
            pb.set_message(match unit {
                bag::Progress::FileBytes => "reading bag",
                _ => "decoding",
            });
        }
        pb.set_length(t);
        pb.set_position(d);
    })?;
    pb.finish_and_clear();
    if let Some(e) = &err {
        eprintln!(
            "fcc-report: the bag is cut short ({e}); using the {} messages before the cut",
            msgs.len()
        );
    }
    Ok(msgs)
}

/// The mission flown, if given (`--mission FILE`).
fn load_mission(path: Option<&Path>) -> anyhow::Result<Option<fcc_mission::Mission>> {
    Ok(match path {
        Some(p) => Some(
            fcc_mission::from_yaml_str(&std::fs::read_to_string(p)?)
                .map_err(|e| anyhow::anyhow!("{}: {e:?}", p.display()))?,
        ),
        None => None,
    })
}

/// Fig. 17: the estimated path, with the mission's legs.
fn path_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, .. } = *v;
    let p = |name: &str| v.out.join(name);
    // Fig. 17: path, with the mission's legs.
    // From the arm command on: before it the estimate may still be settling on home.
    let path_en = s
        .odom
        .iter()
        .filter(|o| s.first_arm_cmd.is_none_or(|t| o.0 >= t))
        .map(|o| (o.1[1], o.1[0]))
        .collect();
    let mut lines = vec![line("estimated path", path_en, BLUE)];
    for l in &f.legs {
        let leg_en = vec![
            (l.from_ned_m[1], l.from_ned_m[0]),
            (l.to_ned_m[1], l.to_ned_m[0]),
        ];
        lines.push(line(if l.index == 0 { "legs" } else { "" }, leg_en, RED));
    }
    plots.push((
        "path.png",
        "Waypoint path (paper A Fig. 17)",
        chart(
            &p("path.png"),
            "Waypoint path (N vs E)",
            "east m",
            "north m",
            lines,
            true,
        ),
    ));
}

/// Fig. 16: hover, or the position over the whole flight without one.
fn hover_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    // Fig. 16: hover — deviation from the hold point over the HOLD window, with the box;
    // without a hover, the estimated position over the whole flight.
    match &f.hover {
        Some(h) => {
            let win: Vec<_> = s
                .odom
                .iter()
                .filter(|o| o.0 >= h.t0_s && o.0 < h.t1_s)
                .collect();
            let dev = |k: usize, sign: f64| -> Vec<(f64, f64)> {
                win.iter()
                    .map(|o| (o.0 - h.t0_s, sign * (o.1[k] - h.hold_ned_m[k])))
                    .collect()
            };
            let span = h.t1_s - h.t0_s;
            let mut lines = Vec::new();
            for (k, name, sign, col) in [
                (0, "north", 1.0, BLUE),
                (1, "east", 1.0, RED),
                (2, "altitude", -1.0, GREEN),
            ] {
                lines.push(Line {
                    name,
                    pts: dev(k, sign),
                    color: col,
                    dots: false,
                });
                let b = h.box_m[k];
                for y in [b, -b] {
                    lines.push(line("", vec![(0.0, y), (span, y)], col));
                }
            }
            plots.push((
                "hover.png",
                "Hover in HOLD: deviation from the hold point, with the box (paper A Fig. 16)",
                chart(
                    &p("hover.png"),
                    &format!(
                        "Hover {:.0} s: box N {:.2} E {:.2} alt {:.2} m",
                        span, h.box_m[0], h.box_m[1], h.box_m[2]
                    ),
                    "t s (from hold start)",
                    "m",
                    lines,
                    false,
                ),
            ));
        }
        None => plots.push((
            "hover.png",
            "Position over time (no hover in this flight; paper A Fig. 16)",
            chart(
                &p("hover.png"),
                "Estimated position",
                "t s",
                "m",
                vec![
                    line(
                        "north",
                        s.odom.iter().map(|o| (o.0 - t0, o.1[0])).collect(),
                        BLUE,
                    ),
                    line(
                        "east",
                        s.odom.iter().map(|o| (o.0 - t0, o.1[1])).collect(),
                        RED,
                    ),
                    line(
                        "altitude",
                        s.odom.iter().map(|o| (o.0 - t0, -o.1[2])).collect(),
                        GREEN,
                    ),
                ],
                false,
            ),
        )),
    }
}

/// Fig. 18: velocity tracking.
fn velocity_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    let c = |r, g, b| RGBColor(r, g, b);
    // Fig. 18: velocity tracking.
    plots.push((
        "velocity.png",
        "Velocity tracking (paper A Fig. 18)",
        chart(
            &p("velocity.png"),
            "Velocity: command vs estimate (NED)",
            "t s",
            "m/s",
            vec![
                line(
                    "v_N est",
                    s.odom.iter().map(|o| (o.0 - t0, o.2[0])).collect(),
                    BLUE,
                ),
                dots(
                    "v_N cmd",
                    s.vel_cmd.iter().map(|o| (o.0 - t0, o.1[0])).collect(),
                    c(120, 120, 255),
                ),
                line(
                    "v_E est",
                    s.odom.iter().map(|o| (o.0 - t0, o.2[1])).collect(),
                    RED,
                ),
                dots(
                    "v_E cmd",
                    s.vel_cmd.iter().map(|o| (o.0 - t0, o.1[1])).collect(),
                    c(255, 140, 140),
                ),
            ],
            false,
        ),
    ));
}

/// Fig. 5: attitude estimate vs accelerometer angles.
fn attitude_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    let c = |r, g, b| RGBColor(r, g, b);
    // Fig. 5: attitude estimate vs accelerometer angles.
    plots.push((
        "attitude.png",
        "Attitude estimate vs accelerometer angles (paper A Fig. 5)",
        chart(
            &p("attitude.png"),
            "Roll/pitch: estimate vs accelerometer",
            "t s",
            "deg",
            vec![
                dots(
                    "roll (accel)",
                    s.acc_angles
                        .iter()
                        .map(|a| (a.0 - t0, a.1.to_degrees()))
                        .collect(),
                    c(255, 180, 180),
                ),
                dots(
                    "pitch (accel)",
                    s.acc_angles
                        .iter()
                        .map(|a| (a.0 - t0, a.2.to_degrees()))
                        .collect(),
                    c(180, 180, 255),
                ),
                line(
                    "roll (estimate)",
                    s.odom
                        .iter()
                        .map(|o| (o.0 - t0, o.3[0].to_degrees()))
                        .collect(),
                    RED,
                ),
                line(
                    "pitch (estimate)",
                    s.odom
                        .iter()
                        .map(|o| (o.0 - t0, o.3[1].to_degrees()))
                        .collect(),
                    BLUE,
                ),
            ],
            false,
        ),
    ));
}

/// Fig. 9: vertical estimate vs barometer.
fn vertical_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    let c = |r, g, b| RGBColor(r, g, b);
    // Fig. 9: vertical estimate vs barometer.
    plots.push((
        "vertical.png",
        "Vertical estimate vs barometer (paper A Fig. 9)",
        chart(
            &p("vertical.png"),
            "Altitude: fused vs barometer",
            "t s",
            "m",
            vec![
                line(
                    "barometer",
                    s.alt.iter().map(|a| (a.0 - t0, a.1)).collect(),
                    c(160, 160, 160),
                ),
                line(
                    "fused",
                    s.alt.iter().map(|a| (a.0 - t0, a.2)).collect(),
                    BLUE,
                ),
            ],
            false,
        ),
    ));
}

/// Paper B Fig. 13: ground-altitude fusion vs laser and sonar.
fn ground_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    // Paper B Fig. 13: ground altitude fusion vs laser and sonar.
    plots.push((
        "ground.png",
        "Ground-altitude fusion vs laser and sonar (paper B Fig. 13)",
        chart(
            &p("ground.png"),
            "Height above ground",
            "t s",
            "m",
            vec![
                dots(
                    "laser",
                    s.alt.iter().map(|a| (a.0 - t0, a.4)).collect(),
                    RED,
                ),
                dots(
                    "sonar",
                    s.alt.iter().map(|a| (a.0 - t0, a.5)).collect(),
                    GREEN,
                ),
                line(
                    "fusion",
                    s.alt.iter().map(|a| (a.0 - t0, a.3)).collect(),
                    BLUE,
                ),
            ],
            false,
        ),
    ));
}

/// Fig. 13: acceleration observer vs measured (skipped on older bags).
fn observer_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    let c = |r, g, b| RGBColor(r, g, b);
    // Fig. 13: acceleration observer vs measured acceleration (skipped on older bags).
    if let Some(o) = &f.observer {
        let mut pan = Vec::new();
        for (k, axis) in [(0, "north"), (1, "east")] {
            pan.push((
                format!(
                    "Acceleration {axis}: observer vs measured (ratio of 1 s high-pass σ {:.3})",
                    o.ratio
                ),
                "m/s²",
                vec![
                    dots(
                        "measured (accelerometer, gravity removed)",
                        s.accel_meas.iter().map(|a| (a.0 - t0, a.1[k])).collect(),
                        c(170, 170, 170),
                    ),
                    line(
                        "observer",
                        s.accel_obs.iter().map(|a| (a.0 - t0, a.1[k])).collect(),
                        BLUE,
                    ),
                ],
            ));
        }
        plots.push((
            "observer.png",
            "Acceleration observer vs measured acceleration (paper A Fig. 13)",
            panels(&p("observer.png"), "t s", pan),
        ));
    }
}

/// Fig. 12: the k1/k2 fit along the flight.
fn k_fit_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, t0, .. } = *v;
    let p = |name: &str| v.out.join(name);
    let c = |r, g, b| RGBColor(r, g, b);
    // Fig. 12: k1/k2 fit — measured north acceleration vs the fitted model with each window's
    // wind intercept, along the flight.
    if let Some(x) = &f.sysid {
        let (k1, k2) = (x.k1_mps2_per_rad, x.k2_per_s);
        let samples = fcc_bridge::report::sysid::samples(
            &s,
            fcc_bridge::report::sysid::AccelSource::OdomDifferenced,
        );
        let mut meas = Vec::new();
        let mut model = Vec::new();
        let mut wi = 0;
        let wl = &x.window_list;
        for q in &samples {
            while wi + 1 < wl.len() && q.t_s > wl[wi].t1_s {
                wi += 1;
            }
            let Some(w) = wl.get(wi) else { break };
            let c = w.means.intercept_ne_mps2(k1 as f32, k2 as f32)[0] as f64;
            meas.push((q.t_s - t0, q.accel_ne_mps2[0]));
            model.push((q.t_s - t0, k1 * q.tilt_ne_rad[0] - k2 * q.vel_ne_mps[0] + c));
        }
        plots.push((
            "k_fit.png",
            "k1/k2 fit with the wind (paper A Fig. 12)",
            chart(
                &p("k_fit.png"),
                &format!(
                    "North acceleration: measured vs k1·θ − k2·(v − w) (k1 {k1:.2}, k2 {k2:.3})"
                ),
                "t s",
                "m/s²",
                vec![
                    dots(
                        "measured (odometry velocity, differenced)",
                        meas,
                        c(150, 150, 150),
                    ),
                    line("fit (wind per window)", model, MAGENTA),
                ],
                false,
            ),
        ));
    }
}

/// `report.html`: the summary text and every plot (or why it failed).
/// A line of a chart.
fn line(name: &str, pts: Vec<(f64, f64)>, color: RGBColor) -> Line<'_> {
    Line {
        name,
        pts,
        color,
        dots: false,
    }
}

/// Points of a chart.
fn dots(name: &str, pts: Vec<(f64, f64)>, color: RGBColor) -> Line<'_> {
    Line {
        name,
        pts,
        color,
        dots: true,
    }
}

fn write_html(out: &Path, bag: &Path, text: &str, plots: &[Plot]) -> std::io::Result<()> {
    let mut html = format!("<html><head><meta charset=\"utf-8\"><title>fcc flight report</title></head><body><h1>Flight report: {}</h1><pre>{}</pre>\n", bag.display(), text);
    for (file, title, r) in plots {
        match r {
            Ok(()) => html.push_str(&format!(
                "<h2>{title}</h2><img src=\"{file}\" width=\"900\">\n"
            )),
            Err(e) => {
                eprintln!("fcc-report: {file}: {e}");
                html.push_str(&format!("<h2>{title}</h2><p>plot failed: {e}</p>\n"));
            }
        }
    }
    html.push_str("</body></html>\n");
    std::fs::write(out.join("report.html"), html)
}
