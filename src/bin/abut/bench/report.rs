//! The speed-against-error report: the fitted exponent, the Pareto front and the plot; and
//! what every bench report needs (the machine's description, the output's errors).

use super::*;

/// Least-squares slope of log t against log n.
pub(super) fn exponent(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0.ln(), a.1 + p.1.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = points.iter().fold((0.0, 0.0), |a, p| {
        let dx = p.0.ln() - mx;
        (a.0 + dx * (p.1.ln() - my), a.1 + dx * dx)
    });
    num / den
}

/// Rows on the Pareto front of (time per increment, position error): no other row is at least
/// as fast and as accurate and better in one.
pub(super) fn pareto(rows: &[Row]) -> Vec<usize> {
    let err = |r: &Row| r.errors.position.max(1e-12);
    (0..rows.len())
        .filter(|&i| {
            !rows.iter().enumerate().any(|(j, r)| {
                j != i
                    && r.steady_ms <= rows[i].steady_ms
                    && err(r) <= err(&rows[i])
                    && (r.steady_ms < rows[i].steady_ms || err(r) < err(&rows[i]))
            })
        })
        .collect()
}

pub(super) fn plot(
    rows: &[Row],
    front: &[usize],
    path: &std::path::Path,
    title: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    let root = SVGBackend::new(path, (1000, 680)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let err = |r: &Row| r.errors.position.max(1e-9);
    let (t_lo, t_hi) = rows.iter().fold((f64::MAX, 0.0f64), |a, r| {
        (a.0.min(r.steady_ms), a.1.max(r.steady_ms))
    });
    let (e_lo, e_hi) = rows.iter().fold((f64::MAX, 0.0f64), |a, r| {
        (a.0.min(err(r)), a.1.max(err(r)))
    });
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 16))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (t_lo * 0.7..t_hi * 1.4).log_scale(),
            (e_lo * 0.5..e_hi * 2.0).log_scale(),
        )
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("time per increment, steady state [ms]")
        .y_desc("final position error [facet sizes]")
        .draw()
        .map_err(|e| e.to_string())?;
    let backends: Vec<String> = {
        let mut b: Vec<String> = rows.iter().map(|r| r.backend.clone()).collect();
        b.sort();
        b.dedup();
        b
    };
    let colours = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    for (k, b) in backends.iter().enumerate() {
        let c = colours[k % colours.len()];
        chart
            .draw_series(
                rows.iter()
                    .filter(|r| &r.backend == b)
                    .map(|r| Circle::new((r.steady_ms, err(r)), 4, c.filled())),
            )
            .map_err(|e| e.to_string())?
            .label(b.clone())
            .legend(move |(x, y)| Circle::new((x, y), 4, c.filled()));
    }
    let mut f: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| (rows[i].steady_ms, err(&rows[i])))
        .collect();
    f.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(f.clone(), BLACK.stroke_width(2)))
        .map_err(|e| e.to_string())?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    chart
        .draw_series(f.iter().map(|&p| Circle::new(p, 7, BLACK.stroke_width(2))))
        .map_err(|e| e.to_string())?;
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

/// The machine the bench runs on: CPU model, cores and memory, for the reports' headers.
pub(crate) fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mem = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines().next().and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|k| k.parse::<f64>().ok())
            })
        })
        .map_or(String::new(), |kb| format!(", {:.0} GiB", kb / 1048576.0));
    format!("{cpu}, {cores} cores{mem}")
}

/// A bench output file or directory that cannot be written, as abut's error.
pub(crate) fn io_err(p: &std::path::Path, e: std::io::Error) -> abut::Error {
    abut::Error::BadParameter {
        name: "bench output",
        value: format!("{}: {e}", p.display()),
        expected: "a writable directory",
    }
}
