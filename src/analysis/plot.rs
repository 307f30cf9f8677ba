//! The convergence plot: error against render time on log-log axes, one colour per series
//! (labelled `integrator/sampler`), its fitted slope in the legend, and a 1/sqrt(t) guide. Drawn
//! with plotters into memory and encoded as PNG by `image`, so the file is written atomically
//! like every other output.
//!
//! Text needs a font and a fresh machine may have none, so DejaVu Sans (Bitstream Vera licence,
//! `assets/DejaVuSans-LICENSE.txt`) is embedded in the binary and registered with plotters.

use crate::analysis::convergence::{fit_series, Fit, Metric, Series};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::sync::OnceLock;

const FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

/// Size of the PNG.
pub const WIDTH: u32 = 1000;
pub const HEIGHT: u32 = 680;

/// Line colours, one per series (colour-blind-safe Okabe-Ito hues).
const COLOURS: [RGBColor; 6] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
];

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("the embedded font could not be loaded")]
    Font,
    #[error("nothing to plot: no series has two or more checkpoints")]
    Empty,
    #[error("cannot draw the plot: {0}")]
    Draw(String),
    #[error("cannot encode the plot: {0}")]
    Encode(image::ImageError),
}

// Not `#[from]`: that would make the image error this one's source too, and a chain printed
// with `{:#}` would say it twice.
impl From<image::ImageError> for PlotError {
    fn from(e: image::ImageError) -> Self {
        PlotError::Encode(e)
    }
}

fn register() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

/// What to draw.
pub struct PlotSpec<'a> {
    pub title: &'a str,
    pub series: &'a [Series],
    /// The error drawn as solid lines and fitted: measured RMSE when there is a reference.
    pub metric: Metric,
    /// Fit over checkpoints at or after this time (see `convergence::fit_start`).
    pub fit_from: f64,
}

/// Tick positions m * 10^k (m from `mantissas`) inside [lo, hi]: the 1-2-5 labels of a log axis
/// (plotters' own log ticks leave a range under a decade nearly unlabelled).
fn ticks(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return out;
    }
    for k in (lo.log10().floor() as i32)..=(hi.log10().ceil() as i32) {
        for m in mantissas {
            let v = m * 10f64.powi(k);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
    }
    out
}

const ALL_DIGITS: [f64; 9] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];

/// Labelled ticks: 1-2-5 per decade, or every digit when that would leave fewer than three.
fn labelled_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let t = ticks(lo, hi, &[1.0, 2.0, 5.0]);
    if t.len() >= 3 {
        t
    } else {
        ticks(lo, hi, &ALL_DIGITS)
    }
}

/// A dashed stroke for a legend entry at (x, y), 24 px wide like the solid ones.
macro_rules! dashed_legend {
    ($x:expr, $y:expr, $style:expr) => {
        EmptyElement::at(($x, $y))
            + PathElement::new(vec![(0, 0), (9, 0)], $style)
            + PathElement::new(vec![(15, 0), (24, 0)], $style)
    };
}

/// A readable tick label: up to three significant digits, no exponent for usual magnitudes.
fn tick(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn legend_text(name: &str, metric: Metric, fit: Option<Fit>) -> String {
    match fit {
        Some(f) => format!("{name} {}: slope {:.2}", metric.name(), f.slope),
        None => format!("{name} {}", metric.name()),
    }
}

/// Draw the plot and return the PNG bytes.
pub fn convergence_png(spec: &PlotSpec) -> Result<Vec<u8>, PlotError> {
    register()?;
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    draw(spec, &mut buf).map_err(|e| PlotError::Draw(e.to_string()))?;
    let img = image::RgbImage::from_raw(WIDTH, HEIGHT, buf)
        .ok_or_else(|| PlotError::Draw("image buffer has the wrong size".into()))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)?;
    Ok(bytes.into_inner())
}

/// The error may borrow the pixel buffer (plotters' error types carry the backend's lifetime).
type DrawResult<'b> = Result<(), Box<dyn std::error::Error + 'b>>;

fn draw<'b>(spec: &PlotSpec, buf: &'b mut [u8]) -> DrawResult<'b> {
    // Lines to draw: the chosen metric solid, and the estimate dashed beside a measured one.
    let metrics: Vec<Metric> = match spec.metric {
        Metric::Measured => vec![Metric::Measured, Metric::Estimated],
        Metric::Estimated => vec![Metric::Estimated],
    };
    let line = |s: &Series, m: Metric| -> Vec<(f64, f64)> {
        s.points
            .iter()
            .filter_map(|c| m.of(c).map(|e| (c.seconds, e)))
            .filter(|(t, e)| *t > 0.0 && *e > 0.0)
            .collect()
    };
    let all: Vec<(f64, f64)> = spec
        .series
        .iter()
        .flat_map(|s| metrics.iter().flat_map(move |&m| line(s, m)))
        .collect();
    if all.len() < 2 {
        return Err(Box::new(PlotError::Empty));
    }
    let (t_lo, t_hi) = all.iter().fold((f64::INFINITY, 0f64), |(lo, hi), p| {
        (lo.min(p.0), hi.max(p.0))
    });
    let (e_lo, e_hi) = all.iter().fold((f64::INFINITY, 0f64), |(lo, hi), p| {
        (lo.min(p.1), hi.max(p.1))
    });

    // The 1/sqrt(t) guide runs 30% below the first series' fit at the middle of its range: near
    // the data without hiding it, and a line parallel to it converges at the Monte Carlo rate.
    let guide = spec
        .series
        .first()
        .and_then(|s| fit_series(s, spec.metric, spec.fit_from))
        .map(|f| {
            let mid = (f.from_seconds * t_hi).sqrt();
            let c = 0.7 * f.at(mid) * mid.sqrt();
            move |t: f64| c / t.sqrt()
        });
    let (mut y_lo, mut y_hi) = (e_lo, e_hi);
    if let Some(g) = &guide {
        y_lo = y_lo.min(g(t_hi));
        y_hi = y_hi.max(g(t_lo));
    }
    let (x0, x1) = (t_lo / 1.3, t_hi * 1.3);
    let (y0, y1) = (y_lo / 1.3, y_hi * 1.3);

    let root = BitMapBackend::with_buffer(buf, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(spec.title, (FAMILY, 26))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (x0..x1)
                .log_scale()
                .with_key_points(labelled_ticks(x0, x1))
                .with_light_points(ticks(x0, x1, &ALL_DIGITS)),
            (y0..y1)
                .log_scale()
                .with_key_points(labelled_ticks(y0, y1))
                .with_light_points(ticks(y0, y1, &ALL_DIGITS)),
        )?;
    let fmt = |v: &f64| tick(*v);
    chart
        .configure_mesh()
        .x_desc("render time (s), scene build excluded")
        .y_desc(match spec.metric {
            Metric::Measured => "RMSE against the reference",
            Metric::Estimated => "estimated RMSE",
        })
        .axis_desc_style((FAMILY, 20))
        .label_style((FAMILY, 16))
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;

    for (i, s) in spec.series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        for &m in &metrics {
            let pts = line(s, m);
            if pts.is_empty() {
                continue;
            }
            let label = legend_text(&s.label(), m, fit_series(s, m, spec.fit_from));
            if m == spec.metric {
                chart
                    .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(3)))?
                    .label(label)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3))
                    });
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
            } else {
                let style = colour.mix(0.8).stroke_width(2);
                chart
                    .draw_series(DashedLineSeries::new(pts, 6, 5, style))?
                    .label(label)
                    .legend(move |(x, y)| dashed_legend!(x, y, style));
            }
        }
    }
    if let Some(g) = guide {
        let n = 32;
        let pts: Vec<(f64, f64)> = (0..=n)
            .map(|k| {
                let t = t_lo * (t_hi / t_lo).powf(k as f64 / n as f64);
                (t, g(t))
            })
            .collect();
        let style = RGBColor(110, 110, 110).stroke_width(1);
        chart
            .draw_series(DashedLineSeries::new(pts, 4, 6, style))?
            .label("1/√t guide (slope -0.5)")
            .legend(move |(x, y)| dashed_legend!(x, y, style));
    }
    // Say what the legend's slopes are, in the empty lower-left corner of the plot.
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    root.draw(&Text::new(
        format!(
            "slope: least-squares fit of ln(error) on ln(t) over checkpoints at t ≥ {}",
            tick(spec.fit_from) + " s"
        ),
        (xr.start + 12, yr.end - 30),
        (FAMILY, 16).into_font().color(&RGBColor(80, 80, 80)),
    ))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 18))
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(160, 160, 160))
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(0.01), "0.01");
        assert_eq!(tick(0.02), "0.02");
        assert_eq!(tick(0.0123456), "0.0123");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(0.5), "0.5");
        assert_eq!(tick(20.0), "20");
        assert_eq!(tick(150.0), "150");
    }
}
