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

impl View<'_> {
    /// `(t − t0, y)` of each sample, from `f(sample) = (t, y)`.
    fn ts<T>(&self, xs: &[T], f: impl Fn(&T) -> (f64, f64)) -> Vec<(f64, f64)> {
        xs.iter()
            .map(|x| {
                let (t, y) = f(x);
                (t - self.t0, y)
            })
            .collect()
    }

    /// Draws one chart into `file` (`title`, x and y axis labels) and lists it on the page
    /// under `html`.
    fn draw(&self, plots: &mut Vec<Plot>, file: &'static str, html: &'static str, c: Chart) {
        let (title, (xl, yl), lines, equal) = c;
        plots.push((
            file,
            html,
            chart(&self.out.join(file), &title, xl, yl, lines, equal),
        ));
    }
}

/// A chart: its title, the axis labels (x, y), its lines and whether the axes share a scale.
type Chart<'a> = (String, (&'a str, &'a str), Vec<Line<'a>>, bool);

fn grey(v: u8) -> RGBColor {
    RGBColor(v, v, v)
}

/// Fig. 17: the estimated path, with the mission's legs.
fn path_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, .. } = *v;
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
    let title = "Waypoint path (N vs E)".to_string();
    let chart = (title, ("east m", "north m"), lines, true);
    v.draw(plots, "path.png", "Waypoint path (paper A Fig. 17)", chart);
}

/// Fig. 16: hover — deviation from the hold point over the HOLD window, with the box; without
/// a hover, the estimated position over the whole flight.
fn hover_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, .. } = *v;
    let Some(h) = &f.hover else {
        let lines = vec![
            line("north", v.ts(&s.odom, |o| (o.0, o.1[0])), BLUE),
            line("east", v.ts(&s.odom, |o| (o.0, o.1[1])), RED),
            line("altitude", v.ts(&s.odom, |o| (o.0, -o.1[2])), GREEN),
        ];
        let chart = ("Estimated position".to_string(), ("t s", "m"), lines, false);
        let html = "Position over time (no hover in this flight; paper A Fig. 16)";
        return v.draw(plots, "hover.png", html, chart);
    };
    let win: Vec<_> = s
        .odom
        .iter()
        .filter(|o| o.0 >= h.t0_s && o.0 < h.t1_s)
        .collect();
    let span = h.t1_s - h.t0_s;
    let mut lines = Vec::new();
    for (k, name, sign, col) in [
        (0, "north", 1.0, BLUE),
        (1, "east", 1.0, RED),
        (2, "altitude", -1.0, GREEN),
    ] {
        let dev = win
            .iter()
            .map(|o| (o.0 - h.t0_s, sign * (o.1[k] - h.hold_ned_m[k])))
            .collect();
        lines.push(line(name, dev, col));
        let b = h.box_m[k];
        for y in [b, -b] {
            lines.push(line("", vec![(0.0, y), (span, y)], col));
        }
    }
    let title = format!(
        "Hover {:.0} s: box N {:.2} E {:.2} alt {:.2} m",
        span, h.box_m[0], h.box_m[1], h.box_m[2]
    );
    let chart = (title, ("t s (from hold start)", "m"), lines, false);
    let html = "Hover in HOLD: deviation from the hold point, with the box (paper A Fig. 16)";
    v.draw(plots, "hover.png", html, chart);
}

/// Fig. 18: velocity tracking.
fn velocity_plot(v: &View, plots: &mut Vec<Plot>) {
    let s = v.s;
    let lines = vec![
        line("v_N est", v.ts(&s.odom, |o| (o.0, o.2[0])), BLUE),
        dots(
            "v_N cmd",
            v.ts(&s.vel_cmd, |o| (o.0, o.1[0])),
            RGBColor(120, 120, 255),
        ),
        line("v_E est", v.ts(&s.odom, |o| (o.0, o.2[1])), RED),
        dots(
            "v_E cmd",
            v.ts(&s.vel_cmd, |o| (o.0, o.1[1])),
            RGBColor(255, 140, 140),
        ),
    ];
    let title = "Velocity: command vs estimate (NED)".to_string();
    let chart = (title, ("t s", "m/s"), lines, false);
    v.draw(
        plots,
        "velocity.png",
        "Velocity tracking (paper A Fig. 18)",
        chart,
    );
}

/// Fig. 5: attitude estimate vs accelerometer angles.
fn attitude_plot(v: &View, plots: &mut Vec<Plot>) {
    let s = v.s;
    let deg = |x: f64| x.to_degrees();
    let lines = vec![
        dots(
            "roll (accel)",
            v.ts(&s.acc_angles, |a| (a.0, deg(a.1))),
            RGBColor(255, 180, 180),
        ),
        dots(
            "pitch (accel)",
            v.ts(&s.acc_angles, |a| (a.0, deg(a.2))),
            RGBColor(180, 180, 255),
        ),
        line(
            "roll (estimate)",
            v.ts(&s.odom, |o| (o.0, deg(o.3[0]))),
            RED,
        ),
        line(
            "pitch (estimate)",
            v.ts(&s.odom, |o| (o.0, deg(o.3[1]))),
            BLUE,
        ),
    ];
    let title = "Roll/pitch: estimate vs accelerometer".to_string();
    let chart = (title, ("t s", "deg"), lines, false);
    let html = "Attitude estimate vs accelerometer angles (paper A Fig. 5)";
    v.draw(plots, "attitude.png", html, chart);
}

/// Fig. 9: vertical estimate vs barometer.
fn vertical_plot(v: &View, plots: &mut Vec<Plot>) {
    let s = v.s;
    let lines = vec![
        line("barometer", v.ts(&s.alt, |a| (a.0, a.1)), grey(160)),
        line("fused", v.ts(&s.alt, |a| (a.0, a.2)), BLUE),
    ];
    let chart = (
        "Altitude: fused vs barometer".to_string(),
        ("t s", "m"),
        lines,
        false,
    );
    let html = "Vertical estimate vs barometer (paper A Fig. 9)";
    v.draw(plots, "vertical.png", html, chart);
}

/// Paper B Fig. 13: ground-altitude fusion vs laser and sonar.
fn ground_plot(v: &View, plots: &mut Vec<Plot>) {
    let s = v.s;
    let lines = vec![
        dots("laser", v.ts(&s.alt, |a| (a.0, a.4)), RED),
        dots("sonar", v.ts(&s.alt, |a| (a.0, a.5)), GREEN),
        line("fusion", v.ts(&s.alt, |a| (a.0, a.3)), BLUE),
    ];
    let chart = (
        "Height above ground".to_string(),
        ("t s", "m"),
        lines,
        false,
    );
    let html = "Ground-altitude fusion vs laser and sonar (paper B Fig. 13)";
    v.draw(plots, "ground.png", html, chart);
}

/// Fig. 13: acceleration observer vs measured (skipped on older bags).
fn observer_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, .. } = *v;
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
                        v.ts(&s.accel_meas, |a| (a.0, a.1[k])),
                        grey(170),
                    ),
                    line("observer", v.ts(&s.accel_obs, |a| (a.0, a.1[k])), BLUE),
                ],
            ));
        }
        plots.push((
            "observer.png",
            "Acceleration observer vs measured acceleration (paper A Fig. 13)",
            panels(&v.out.join("observer.png"), "t s", pan),
        ));
    }
}

/// Fig. 12: the k1/k2 fit — measured north acceleration vs the fitted model with each window's
/// wind intercept, along the flight.
fn k_fit_plot(v: &View, plots: &mut Vec<Plot>) {
    let View { s, f, t0, .. } = *v;
    let Some(x) = &f.sysid else { return };
    let (k1, k2) = (x.k1_mps2_per_rad, x.k2_per_s);
    let samples = fcc_bridge::report::sysid::samples(
        s,
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
    let lines = vec![
        dots("measured (odometry velocity, differenced)", meas, grey(150)),
        line("fit (wind per window)", model, MAGENTA),
    ];
    let title =
        format!("North acceleration: measured vs k1·θ − k2·(v − w) (k1 {k1:.2}, k2 {k2:.3})");
    let chart = (title, ("t s", "m/s²"), lines, false);
    v.draw(
        plots,
        "k_fit.png",
        "k1/k2 fit with the wind (paper A Fig. 12)",
        chart,
    );
}

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

/// `report.html`: the summary text and every plot (or why it failed).
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
