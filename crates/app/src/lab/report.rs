//! What every experiment writes: its rows as CSV and JSON, a chart as SVG and PNG (plotters),
//! a progress bar (indicatif) and a short table on stdout.

use std::path::Path;

use anyhow::Context as _;
use plotters::prelude::*;
use serde::Serialize;

/// Writes `rows` to `<out>/<name>.csv` and `<out>/<name>.json`.
pub fn write_rows<T: Serialize>(out: &Path, name: &str, rows: &[T]) -> anyhow::Result<()> {
    let csv_path = out.join(format!("{name}.csv"));
    // Through JSON values, so that flattened structs and small arrays (resolutions) become
    // columns: arrays are written as "a×b×c".
    let values: Vec<serde_json::Value> = rows.iter().map(serde_json::to_value).collect::<Result<_, _>>()?;
    let mut w = csv::Writer::from_path(&csv_path).with_context(|| format!("writing {}", csv_path.display()))?;
    let headers: Vec<String> = match values.first() {
        Some(serde_json::Value::Object(o)) => o.keys().cloned().collect(),
        Some(_) => anyhow::bail!("{name}: rows must be structs"),
        None => Vec::new(),
    };
    w.write_record(&headers)?;
    let cell = |v: &serde_json::Value| match v {
        serde_json::Value::Null => String::new(),
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Array(a) => a.iter().map(|x| x.to_string()).collect::<Vec<_>>().join("×"),
        other => other.to_string(),
    };
    for v in &values {
        w.write_record(headers.iter().map(|h| cell(&v[h.as_str()])))?;
    }
    w.flush()?;
    let json_path = out.join(format!("{name}.json"));
    std::fs::write(&json_path, serde_json::to_string_pretty(rows)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    Ok(())
}

/// A progress bar over `len` steps.
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(len);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    pb.set_prefix(what.to_string());
    pb
}

/// One line of a chart.
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Drawn dashed (predictions, or a comparison's other family) instead of solid; on category
    /// charts (`x_names`), hollow marks instead of filled ones.
    pub predicted: bool,
}

/// A line chart; axes may be logarithmic (the data is plotted as log10 with real-valued tick
/// labels, which keeps one code path for both axis kinds).
#[derive(Clone, Debug)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
    /// Vertical markers: x and label (e.g. the auto-chosen m).
    pub markers: Vec<(f64, String)>,
    /// Names for integer x values (categories such as scenes), instead of numbers.
    pub x_names: Option<Vec<String>>,
}

impl Chart {
    /// A chart of `series` on log–log axes, without markers or category names.
    pub fn log_log(title: &str, x_label: &str, y_label: &str, series: Vec<Series>) -> Chart {
        Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: true,
            log_y: true,
            series,
            markers: vec![],
            x_names: None,
        }
    }
}

/// Colours that stay apart on white (no yellow): ten, so bench's ten structures per scene
/// never share one.
const PALETTE: [RGBColor; 10] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
];

fn tr(v: f64, log: bool) -> f64 {
    if log { v.max(1e-300).log10() } else { v }
}

fn tick(v: f64, log: bool) -> String {
    let mut x = if log { 10f64.powf(v) } else { v };
    if log && x > 0.0 {
        // Ticks fall at even steps of log10: two significant digits read better.
        let p = 10f64.powi(x.log10().floor() as i32 - 1);
        x = (x / p).round() * p;
    }
    if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e5 || x.abs() < 1e-3 {
        format!("{x:.1e}")
    } else if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.3}").trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, plotters::coord::Shift>, c: &Chart) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("drawing the chart: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let pts: Vec<(f64, f64)> = c
        .series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite() && (!c.log_x || p.0 > 0.0) && (!c.log_y || p.1 > 0.0))
        .map(|&(x, y)| (tr(x, c.log_x), tr(y, c.log_y)))
        .collect();
    anyhow::ensure!(!pts.is_empty(), "chart \"{}\" has no points", c.title);
    let (mut x0, mut x1) = pts.iter().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let (mut y0, mut y1) = pts.iter().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    if x1 - x0 < 1e-9 || c.x_names.is_some() {
        // Categories get half a slot of room on each side for their labels.
        (x0, x1) = (x0 - 0.5, x1 + 0.5);
    }
    if y1 - y0 < 1e-9 {
        (y0, y1) = (y0 - 0.5, y1 + 0.5);
    }
    let pad = (y1 - y0) * 0.05;
    // Headroom for the legend (upper right, ~17 px per entry on a 560 px chart), so it does not
    // cover the highest points.
    let entries = (c.series.len() + c.markers.len()) as f64;
    let top = (y1 - y0) * (0.07 * entries).max(0.05);
    let (y0, y1) = (if c.log_y { y0 - pad } else { (y0 - pad).min(0.0) }, y1 + top);
    let mut chart = ChartBuilder::on(&root)
        .caption(&c.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    // Category names (scene file names) overlap at the default size when there are many: the
    // label font shrinks so the longest name fits its slot (900 px wide charts).
    let x_font = match &c.x_names {
        Some(names) if !names.is_empty() => {
            let longest = names.iter().map(|n| n.chars().count()).max().unwrap_or(1).max(1) as f64;
            let slot = 780.0 / names.len() as f64;
            (slot / (0.55 * longest)).clamp(8.0, 15.0) as u32
        }
        _ => 15,
    };
    chart
        .configure_mesh()
        .x_label_style(("sans-serif", x_font))
        .x_desc(&c.x_label)
        .y_desc(&c.y_label)
        .x_label_formatter(&|v| match &c.x_names {
            Some(names) if (v - v.round()).abs() < 1e-6 => names.get(v.round() as usize).cloned().unwrap_or_default(),
            Some(_) => String::new(),
            None => tick(*v, c.log_x),
        })
        .y_label_formatter(&|v| tick(*v, c.log_y))
        .draw()
        .map_err(err)?;
    for (i, s) in c.series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()].to_rgba();
        let data: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite() && (!c.log_x || p.0 > 0.0) && (!c.log_y || p.1 > 0.0))
            .map(|&(x, y)| (tr(x, c.log_x), tr(y, c.log_y)))
            .collect();
        let style = ShapeStyle { color, filled: false, stroke_width: 2 };
        if c.x_names.is_some() {
            // Categories: marks only (a line between scenes would mean nothing), each series
            // shifted a little so equal values stay visible side by side; `predicted` series
            // (the comparison's other family) get hollow marks.
            let mark = ShapeStyle { filled: !s.predicted, ..style };
            let shift = (i as f64 - (c.series.len() as f64 - 1.0) / 2.0) * 0.6 / c.series.len().max(1) as f64;
            let data: Vec<(f64, f64)> = data.into_iter().map(|(x, y)| (x + shift, y)).collect();
            chart.draw_series(PointSeries::of_element(data, 6, mark, &|p, r, st| Circle::new(p, r, st))).map_err(err)?
        } else if s.predicted {
            chart.draw_series(DashedLineSeries::new(data, 6, 4, style)).map_err(err)?
        } else {
            let marks = data.clone();
            chart
                .draw_series(PointSeries::of_element(marks, 3, style, &|p, r, st| Circle::new(p, r, st)))
                .map_err(err)?;
            chart.draw_series(LineSeries::new(data, style)).map_err(err)?
        }
        .label(&s.label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
    }
    for (x, label) in &c.markers {
        let x = tr(*x, c.log_x);
        let style = ShapeStyle { color: BLACK.mix(0.6), filled: false, stroke_width: 1 };
        chart
            .draw_series(DashedLineSeries::new(vec![(x, y0), (x, y1)], 3, 3, style))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Registers the bundled font for PNG text (plotters draws bitmap text with ab_glyph).
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

/// Writes `<out>/<name>.svg` and `<out>/<name>.png`.
pub fn save_chart(out: &Path, name: &str, c: &Chart) -> anyhow::Result<()> {
    register_font();
    let svg = out.join(format!("{name}.svg"));
    draw(SVGBackend::new(&svg, (900, 560)).into_drawing_area(), c)?;
    let png = out.join(format!("{name}.png"));
    draw(BitMapBackend::new(&png, (900, 560)).into_drawing_area(), c)?;
    Ok(())
}

/// Prints rows as an aligned table.
pub fn print_table(headers: &[&str], rows: &[Vec<String>]) {
    let widths: Vec<usize> = (0..headers.len())
        .map(|i| rows.iter().map(|r| r[i].len()).chain([headers[i].len()]).max().unwrap_or(0))
        .collect();
    let line =
        |cells: Vec<&str>| cells.iter().zip(&widths).map(|(c, w)| format!("{c:>w$}")).collect::<Vec<_>>().join("  ");
    println!("{}", line(headers.to_vec()));
    for r in rows {
        println!("{}", line(r.iter().map(String::as_str).collect()));
    }
}

/// Least-squares slope and intercept of y against x.
pub fn fit_line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (sx, sy) = points.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| (sxy / sxx, my - sxy / sxx * mx))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_fitted_exactly_and_charts_are_written() {
        let (k, b) = fit_line(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]).unwrap();
        assert!((k - 2.0).abs() < 1e-12 && (b - 1.0).abs() < 1e-12);
        assert!(fit_line(&[(1.0, 1.0)]).is_none());
        assert_eq!(tick(2.0, true), "100");
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let c = Chart {
            title: "t".into(),
            x_label: "m".into(),
            y_label: "ns".into(),
            log_x: true,
            log_y: false,
            series: vec![
                Series { label: "a".into(), points: vec![(10.0, 1.0), (100.0, 2.0)], predicted: false },
                Series { label: "b".into(), points: vec![(10.0, 2.0), (100.0, 1.0)], predicted: true },
            ],
            markers: vec![(30.0, "auto".into())],
            x_names: None,
        };
        save_chart(dir, "c", &c).unwrap();
        let svg = std::fs::read_to_string(dir.join("c.svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("auto"));
        let png = image::open(dir.join("c.png")).unwrap().to_rgb8();
        assert_eq!(png.dimensions(), (900, 560));
        assert!(png.pixels().any(|p| p.0 != [255, 255, 255]), "the PNG is blank");
        #[derive(Serialize)]
        struct R {
            m: u32,
            r: Option<[u32; 2]>,
            t: f64,
        }
        write_rows(dir, "rows", &[R { m: 1, r: Some([1, 2]), t: 0.5 }, R { m: 2, r: None, t: 0.25 }]).unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("rows.csv")).unwrap(), "m,r,t\n1,1×2,0.5\n2,,0.25\n");
    }
}
