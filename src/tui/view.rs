//! The view: a pure function of [`App`] drawn into a ratatui frame.
//!
//! ```text
//!  ptui  cornell 320x240  running  zoom fit  256 colours  half-block          ? help
//!  scene      cornell  │▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀▀
//!  width      320      │      preview (half-blocks), optional error chart below
//!  ...                 │
//!  [=========         ] 64/256 spp  0:12  ETA 0:36
//!  64 spp · 2.01 M samples/s · est. error 0.0123 (rel 0.031) · invalid 0 · 2 threads
//!  saved cornell-64spp-….png · accel: flat; light sampling: power
//! ```

use super::app::{App, Message};
use super::form::{Field, Shown};
use super::layout::{layout, MIN_HEIGHT, MIN_WIDTH};
use super::pick;
use super::text::{clip_left, clip_right, clip_words, fit_parts, fmt_duration, wrap_words};
use crate::session::{JobStatus, Snapshot};
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style, Stylize};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{
    Axis, Block, Borders, Chart, Clear, Dataset, Gauge, GraphType, Paragraph, Wrap,
};
use ratatui::Frame;

/// Width of the form's labels.
const LABEL: usize = 11;

pub fn draw(frame: &mut Frame, app: &App) {
    let area = frame.area();
    let areas = layout(area, app.show_chart);
    let Some(preview) = areas.preview else {
        let text = format!(
            "Terminal too small: {}x{}.\nptui needs at least {MIN_WIDTH}x{MIN_HEIGHT}.\nq quits.",
            area.width, area.height
        );
        frame.render_widget(Paragraph::new(text).wrap(Wrap { trim: true }), area);
        return;
    };
    draw_title(frame, app, areas.title);
    draw_form(frame, app, areas.form);
    if app.snapshot.is_some() {
        // Graphics: the cells stay blank, the main loop sends the pixels after the frame.
        if app.graphics.is_none() {
            app.preview
                .draw(frame.buffer_mut(), preview, app.color_mode);
            draw_marks(frame, app, preview);
        }
    } else {
        frame.render_widget(Paragraph::new("starting…").dark_gray(), preview);
    }
    if let Some(chart) = areas.chart {
        draw_chart(frame, app, chart);
    }
    draw_gauge(frame, app, areas.gauge);
    draw_status(frame, app, areas.status);
    if app.show_help {
        super::help::draw_help(frame, area);
    } else if app.show_details {
        draw_details(frame, app, area);
    }
}

/// Over the cell preview: the picked object's outline while it shows, and a crosshair at the
/// preview's centre in camera mode and with the outline.
fn draw_marks(frame: &mut Frame, app: &App, area: Rect) {
    let Some(g) = app.preview.geometry() else {
        return;
    };
    let flash = app
        .flash
        .as_ref()
        .filter(|f| f.area == area && f.geometry == g);
    if let Some(f) = flash {
        pick::draw_outline(frame.buffer_mut(), f);
    }
    if app.camera_mode || flash.is_some_and(|f| f.at_centre) {
        let (fx, fy) = app.centre();
        if let Some(cell) = pick::cell_of(&g, area, fx, fy) {
            pick::draw_crosshair(frame.buffer_mut(), cell);
        }
    }
}

fn state_name(app: &App) -> &'static str {
    if app.worker_panic.is_some() {
        return "failed";
    }
    match app.status() {
        None => "starting",
        Some(JobStatus::Running) => "running",
        Some(JobStatus::Paused) => "paused",
        Some(JobStatus::Done) => "done",
        Some(JobStatus::TargetReached) => "target error reached",
    }
}

fn draw_title(frame: &mut Frame, app: &App, area: Rect) {
    let s = app.settings();
    let zoom = match app.geometry() {
        Some(g) if g.sx <= 1.0 && app.view.zoom > 0 => "1:1".to_string(),
        _ if app.view.zoom == 0 => "fit".into(),
        _ => format!("{}x", 1u32 << app.view.zoom),
    };
    let mode = match (&app.graphics, app.color_mode) {
        (Some(g), _) => g.protocol.name(),
        (None, super::color::ColorMode::Truecolor) => "truecolor",
        (None, super::color::ColorMode::Ansi256) => "256 colours",
    };
    let shape = match (&app.graphics, app.halfblock) {
        (Some(_), _) => "pixels",
        (None, true) => "half-block",
        (None, false) => "spaces",
    };
    let help = "? help  i details ";
    let room = if area.width >= 60 {
        area.width as usize - help.len()
    } else {
        area.width as usize
    };
    let scene = clip_left(&app.scene_name, 24);
    // A scene edited in the TUI and not written back (W) is marked.
    let unsaved = if app.doc.as_ref().is_some_and(|d| d.dirty()) {
        "*"
    } else {
        ""
    };
    let mut parts = vec![
        Span::styled(" ptui ", Style::new().bold().reversed()),
        Span::raw(format!("  {scene}{unsaved} {}x{}", s.width, s.height)),
        Span::styled(format!("  {}", state_name(app)), Style::new().bold()),
    ];
    if app.camera_mode {
        parts.push(Span::styled("  camera mode", Style::new().bold().yellow()));
    }
    parts.extend([
        Span::raw(format!("  zoom {zoom}")),
        Span::raw(format!("  {mode}")),
        Span::raw(format!("  {shape}")),
    ]);
    frame.render_widget(fit_parts(parts, room), area);
    if area.width >= 60 {
        frame.render_widget(Line::from(help).right_aligned().dark_gray(), area);
    }
}

fn draw_form(frame: &mut Frame, app: &App, area: Rect) {
    let block = Block::new()
        .borders(Borders::RIGHT)
        .border_style(Style::new().dark_gray());
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let s = app.settings();
    let now = Shown {
        settings: &s,
        color_mode: app.color_mode,
        threads: app.threads,
        lens: app.lens(),
    };
    // The painterly knobs only while that integrator is in effect; the scene's fields after
    // the render's, each group under a heading.
    let mut rows: Vec<Option<Field>> = Vec::new();
    let heading = |rows: &mut Vec<Option<Field>>, f: Field| {
        let first = match f {
            Field::EnvIntensity => true,
            Field::Object(_) => !rows.iter().any(|r| matches!(r, Some(Field::Object(_)))),
            _ => false,
        };
        if first {
            rows.push(None);
        }
        rows.push(Some(f));
    };
    for f in app.fields() {
        heading(&mut rows, f);
    }
    let index = rows
        .iter()
        .position(|&f| f == Some(app.form.selected))
        .unwrap_or(0);
    // Scroll so the selected field stays visible in short terminals.
    let height = inner.height.max(1) as usize;
    let first = index.saturating_sub(height - 1);
    let value_w = (inner.width as usize).saturating_sub(LABEL + 1);
    let lines: Vec<Line> = rows
        .iter()
        .enumerate()
        .skip(first)
        .take(height)
        .map(|(k, row)| {
            let Some(field) = *row else {
                let title = match rows.get(k + 1) {
                    Some(Some(Field::EnvIntensity)) => "environment".to_string(),
                    _ => app
                        .picked
                        .as_ref()
                        .map_or(String::new(), |p| p.object.label()),
                };
                let text = format!("─ {} ", clip_left(&title, inner.width as usize - 3));
                let fill = (inner.width as usize).saturating_sub(text.chars().count());
                return Line::from(format!("{text}{}", "─".repeat(fill))).dark_gray();
            };
            let selected = field == app.form.selected;
            let value = match (&app.form.editing, selected) {
                (Some(text), true) => Span::styled(
                    clip_left(&format!("{text}_"), value_w),
                    Style::new().yellow().bold(),
                ),
                // A name from a short list reads best by its start, typed text and paths by
                // their end.
                _ if field.cycles() => {
                    Span::raw(clip_right(&app.field_value(field, &now), value_w))
                }
                _ => Span::raw(clip_left(&app.field_value(field, &now), value_w)),
            };
            let label = format!(" {:<w$}", field.label(), w = LABEL - 1);
            let label_style = if selected {
                Style::new().reversed()
            } else {
                Style::new().dark_gray()
            };
            Line::from(vec![
                Span::styled(label, label_style),
                Span::raw(" "),
                value,
            ])
        })
        .collect();
    frame.render_widget(Paragraph::new(lines), inner);
}

/// With adaptive sampling, the samples per pixel the passes came to on average.
fn mean_spp(snap: &Snapshot) -> String {
    let mean = snap.stats.samples_per_pixel(snap.image.pixels());
    if snap.samples_per_pass > 1.0 {
        format!(" ({mean:.1}/px)")
    } else {
        String::new()
    }
}

fn draw_gauge(frame: &mut Frame, app: &App, area: Rect) {
    if let Some((stage, total, done)) = &app.loading {
        // A scene loading: its stage, with a count where the stage has one.
        let (ratio, label) = match *total {
            0 => (0.0, format!("loading: {stage}…")),
            t => {
                let r = (*done as f64 / t as f64).clamp(0.0, 1.0);
                (r, format!("loading: {stage}  {:.0}%", 100.0 * r))
            }
        };
        let gauge = Gauge::default()
            .ratio(ratio)
            .label(Span::styled(label, Style::new().white().bold()))
            .gauge_style(Style::new().fg(Color::Cyan).bg(Color::Black));
        frame.render_widget(gauge, area);
        return;
    }
    let Some(snap) = &app.snapshot else {
        frame.render_widget(Line::from(" waiting for the first pass…").dark_gray(), area);
        return;
    };
    let done = snap.stats.complete_passes;
    let target = snap.target_spp.max(1);
    let elapsed = snap.stats.elapsed.as_secs_f64();
    // Remaining passes at the current sampling rate: with adaptive sampling the passes after the
    // pilot take more samples than the ones so far.
    let rate = snap.stats.samples_per_second();
    let per_pass = snap.samples_per_pass * snap.image.pixels() as f64;
    let eta = match snap.status {
        JobStatus::Running | JobStatus::Paused if done > 0 && rate > 0.0 => {
            fmt_duration(target.saturating_sub(done) as f64 * per_pass / rate)
        }
        JobStatus::Running | JobStatus::Paused => "--".into(),
        _ => "0:00".into(),
    };
    let label = format!("{done}/{target} spp  {}  ETA {eta}", fmt_duration(elapsed));
    let gauge = Gauge::default()
        .ratio((done as f64 / target as f64).clamp(0.0, 1.0))
        .label(Span::styled(label, Style::new().white().bold()))
        .gauge_style(Style::new().fg(Color::Blue).bg(Color::Black));
    frame.render_widget(gauge, area);
}

/// How to get truecolor when `auto` chose 256 colours, longest first: the status line shows the
/// longest that fits, the details view the first.
pub const COLOR_HINTS: [&str; 4] = [
    "256 colours (auto): for truecolor set COLORTERM=truecolor, in tmux \
     set -as terminal-features ',*:RGB', or press c",
    "256 colours: for truecolor set COLORTERM=truecolor (tmux: terminal-features RGB) or press c",
    "256 colours: press c for truecolor, i for how to get it by default",
    "256 colours: c for truecolor",
];

fn draw_status(frame: &mut Frame, app: &App, area: Rect) {
    let [first, second] =
        Layout::vertical([Constraint::Length(1), Constraint::Length(1)]).areas(area);
    let width = area.width as usize;
    if let Some(snap) = &app.snapshot {
        let err = if snap.error.is_known() {
            format!(
                " · est. error {:.4} (rel {:.3})",
                snap.error.rmse,
                snap.error.relative()
            )
        } else {
            " · est. error --".into()
        };
        let invalid = Span::styled(
            format!(" · invalid {}", snap.stats.invalid),
            if snap.stats.invalid > 0 {
                Style::new().red()
            } else {
                Style::new()
            },
        );
        let parts = vec![
            Span::raw(format!(
                " {} spp{}",
                snap.stats.complete_passes,
                mean_spp(snap)
            )),
            Span::raw(format!(
                " · {:.2} M samples/s",
                snap.stats.samples_per_second() / 1e6
            )),
            Span::raw(err),
            invalid,
        ];
        frame.render_widget(fit_parts(parts, width), first);
    }
    let mut parts = Vec::new();
    let mut left = width;
    // Each part takes what it needs of the row; later ones get what is left.
    let push = |parts: &mut Vec<Span<'static>>, left: &mut usize, span: Span<'static>| {
        *left = left.saturating_sub(span.width());
        parts.push(span);
    };
    if let Some(p) = &app.worker_panic {
        let text = clip_words(&format!(" render thread panicked: {p} (r restarts) "), left);
        push(
            &mut parts,
            &mut left,
            Span::styled(text, Style::new().white().on_red()),
        );
    }
    match &app.message {
        Some(Message::Info(m)) => {
            let text = clip_words(&format!(" {m} "), left);
            push(
                &mut parts,
                &mut left,
                Span::styled(text, Style::new().green()),
            );
        }
        Some(Message::Error(m)) => {
            let text = clip_words(&format!(" {m} "), left);
            push(
                &mut parts,
                &mut left,
                Span::styled(text, Style::new().red()),
            );
        }
        None => {}
    }
    if app.color_hint {
        if let Some(h) = COLOR_HINTS.iter().find(|h| h.chars().count() + 2 <= left) {
            let span = Span::styled(format!(" {h} "), Style::new().yellow());
            push(&mut parts, &mut left, span);
        }
    }
    let notes = app.notes.short();
    if !notes.is_empty() && notes.chars().count() < left {
        push(
            &mut parts,
            &mut left,
            Span::raw(format!(" {notes}")).dark_gray(),
        );
    }
    frame.render_widget(Line::from(parts), second);
}

/// Decade tick labels for a log10 axis from `lo` to `hi` (both integers).
fn decade_labels(lo: f64, hi: f64, unit: &str) -> Vec<Span<'static>> {
    let (lo, hi) = (lo as i32, hi as i32);
    let mid = lo + (hi - lo) / 2;
    let mut ks = vec![lo];
    if mid != lo && mid != hi {
        ks.push(mid);
    }
    if hi != lo {
        ks.push(hi);
    }
    ks.into_iter()
        .map(|k| {
            let v = 10f64.powi(k);
            let text = if (-3..=3).contains(&k) {
                format!("{v}{unit}")
            } else {
                format!("1e{k}{unit}")
            };
            Span::raw(text)
        })
        .collect()
}

/// Estimated RMSE against render time on log-log axes, with a 1/sqrt(t) guide through the
/// first point: an unbiased estimator's error follows the guide's slope.
fn draw_chart(frame: &mut Frame, app: &App, area: Rect) {
    let block = Block::new()
        .borders(Borders::TOP)
        .title(" est. error vs time (log-log, g hides) ")
        .border_style(Style::new().dark_gray());
    let pts: Vec<(f64, f64)> = app
        .history
        .iter()
        .map(|&(t, e)| (t.log10(), e.log10()))
        .collect();
    if pts.len() < 2 {
        frame.render_widget(
            Paragraph::new("collecting error estimates…")
                .dark_gray()
                .block(block),
            area,
        );
        return;
    }
    let (x0, y0) = pts[0];
    let x_hi = pts.iter().map(|p| p.0).fold(f64::MIN, f64::max);
    let guide = [(x0, y0), (x_hi, y0 - 0.5 * (x_hi - x0))];
    let (y_lo, y_hi) = pts
        .iter()
        .chain(guide.iter())
        .fold((f64::MAX, f64::MIN), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
    // Whole decades, an even number of them: ratatui spaces labels evenly, so the middle
    // label must sit at a whole decade too.
    let decades = |lo: f64, hi: f64| {
        let (lo, hi) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
        [lo, hi + (hi - lo) % 2.0]
    };
    let xb = decades(x0, x_hi);
    let yb = decades(y_lo, y_hi);
    let datasets = vec![
        Dataset::default()
            .name("1/sqrt(t)")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::new().dark_gray())
            .data(&guide),
        Dataset::default()
            .name("est. RMSE")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::new().cyan())
            .data(&pts),
    ];
    let chart = Chart::new(datasets)
        .block(block)
        .x_axis(
            Axis::default()
                .bounds(xb)
                .labels(decade_labels(xb[0], xb[1], "s"))
                .style(Style::new().dark_gray()),
        )
        .y_axis(
            Axis::default()
                .bounds(yb)
                .labels(decade_labels(yb[0], yb[1], ""))
                .style(Style::new().dark_gray()),
        );
    frame.render_widget(chart, area);
}

/// The details view (`i`): the settings and timings of the current render and the build's
/// notes in full, each value word-wrapped beside its label.
fn draw_details(frame: &mut Frame, app: &App, area: Rect) {
    let s = app.settings();
    let mut rows: Vec<(&str, String)> = vec![
        (
            "scene",
            format!("{} ({}x{})", app.scene_name, s.width, s.height),
        ),
        (
            "integrator",
            format!(
                "{}, {} sampler, seed {}, max depth {}",
                s.integrator.name(),
                s.sampler.name(),
                s.seed,
                s.max_depth
                    .map_or("none (roulette)".into(), |d| d.to_string())
            ),
        ),
        (
            "samples",
            format!(
                "target {} spp{}{}",
                s.spp,
                if s.adaptive { ", adaptive" } else { "" },
                s.target_error
                    .map_or(String::new(), |e| format!(", stop at rel. error {e}"))
            ),
        ),
        (
            "display",
            format!("exposure {}, tonemap {}", s.exposure, s.tonemap.name()),
        ),
        ("threads", app.threads.to_string()),
    ];
    if let Some(snap) = &app.snapshot {
        let st = &snap.stats;
        rows.push((
            "progress",
            format!(
                "{} spp{} in {}, {:.2} M samples/s, {:.1} M rays",
                st.complete_passes,
                mean_spp(snap),
                fmt_duration(st.elapsed.as_secs_f64()),
                st.samples_per_second() / 1e6,
                st.rays as f64 / 1e6
            ),
        ));
        rows.push((
            "error",
            format!(
                "est. {:.4} (rel {:.3}), invalid samples {}",
                snap.error.rmse,
                snap.error.relative(),
                st.invalid
            ),
        ));
    }
    rows.push((
        "scene build",
        format!("{:.1} ms", app.notes.build_time.as_secs_f64() * 1e3),
    ));
    if let Some(scene) = &app.scene {
        let s = app.settings();
        let camera = scene
            .camera
            .with_lens_settings(s.aperture, s.focus_distance);
        rows.push(("camera", camera.lens_text()));
    }
    rows.push(("accel", app.notes.accel.clone()));
    rows.push(("lights", app.notes.light_sampling.clone()));
    rows.push(("caustics", app.notes.caustics.clone()));
    if !app.notes.environment.is_empty() && app.notes.environment != "black" {
        rows.push(("sky", app.notes.environment.clone()));
    }
    if !app.notes.materials.is_empty() {
        rows.push(("materials", app.notes.materials.clone()));
    }
    for w in &app.notes.warnings {
        rows.push(("warning", w.clone()));
    }
    let colours = match (app.color_mode, app.form.color) {
        (super::color::ColorMode::Truecolor, _) => "truecolor".to_string(),
        (_, super::color::ColorChoice::Auto) => COLOR_HINTS[0].to_string(),
        _ => "256 colours (c for truecolor)".to_string(),
    };
    let colours = match &app.graphics {
        Some(g) => format!(
            "{} pixels; cells of {}x{} px, {} screen pixel(s) per image pixel",
            g.protocol.name(),
            g.cell.0,
            g.cell.1,
            g.scale()
        ),
        None => colours,
    };
    rows.push(("preview", colours));

    let w = area.width.min(100);
    let label_w = 12;
    let value_w = (w as usize).saturating_sub(label_w + 3).max(1);
    let mut lines = Vec::new();
    for (label, value) in rows {
        for (k, text) in wrap_words(&value, value_w).into_iter().enumerate() {
            let label = if k == 0 { label } else { "" };
            lines.push(Line::from(vec![
                Span::styled(format!(" {label:<11}"), Style::new().bold().yellow()),
                Span::raw(format!(" {text}")),
            ]));
        }
    }
    let h = (lines.len() as u16 + 2).min(area.height);
    let popup = Rect::new(
        area.x + (area.width - w) / 2,
        area.y + (area.height - h) / 2,
        w,
        h,
    );
    frame.render_widget(Clear, popup);
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(" details (any key closes) ")),
        popup,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::film::{ErrorEstimate, MeanImage};
    use crate::render::RenderStats;
    use crate::session::{BuildNotes, SessionEvent, Snapshot};
    use crate::settings::SettingsOverrides;
    use crate::tui::color::{ColorChoice, ColorMode};
    use ratatui::backend::TestBackend;
    use ratatui::Terminal;
    use std::sync::Arc;
    use std::time::Duration;

    /// What cornell's build reports (the long texts of issue 37).
    fn cornell_notes() -> BuildNotes {
        BuildNotes {
            accel: "flat scan, 9 objects (auto: the boxes do not separate the objects; camera \
                    rays would cost 21.7 tests vs 9 flat)"
                .into(),
            light_sampling: "1 emitter; 1 sphere light(s) cut by other spheres: only the cap \
                             on the shading point's side is sampled"
                .into(),
            caustics: "light-traced (2689 paths per pass towards 2 mirror/glass sphere(s); 81% \
                       of a pilot's paths reached the camera)"
                .into(),
            environment: "black".into(),
            materials: "diffuse x6, mirror, glass, emitter".into(),
            build_time: Duration::from_micros(400),
            warnings: Vec::new(),
        }
    }

    /// An app showing a synthetic 64x48 film (a gradient with a bright disc) at 32 of 128 spp
    /// after 2 s: everything the view shows is fixed, nothing depends on the clock.
    fn app(w: u16, h: u16) -> App {
        let cli = SettingsOverrides {
            width: Some(64),
            height: Some(48),
            spp: Some(128),
            ..Default::default()
        };
        let mut app = App::new(
            "cornell".into(),
            cli,
            ColorChoice::Auto,
            ColorMode::Ansi256,
            true,
        );
        app.threads = 2;
        app.on_worker(SessionEvent::Started {
            request: 0,
            job: 1,
            restarted: true,
            settings: app.settings(),
            scene_render: SettingsOverrides::default(),
            scene_name: "cornell".into(),
            scene: std::sync::Arc::new(crate::scene::load("cornell").expect("built-in")),
            notes: cornell_notes(),
            threads: 2,
        });
        let (fw, fh) = (64u32, 48u32);
        let mut rgb = Vec::new();
        for y in 0..fh {
            for x in 0..fw {
                let (dx, dy) = (x as f32 - 32.0, y as f32 - 20.0);
                let disc = if dx * dx + dy * dy < 100.0 { 1.0 } else { 0.0 };
                rgb.extend([x as f32 / 64.0, y as f32 / 48.0, disc]);
            }
        }
        let snap = Snapshot {
            job: 1,
            image: Arc::new(MeanImage::from_rgb(fw, fh, &rgb)),
            preview: None,
            stats: RenderStats {
                passes: 32,
                complete_passes: 32,
                samples: 32 * 64 * 48,
                rays: 0,
                light_rays: 0,
                light_paths: 0,
                invalid: 0,
                elapsed: Duration::from_secs(2),
            },
            error: ErrorEstimate {
                rmse: 0.0123,
                rel_mse: 0.0009,
            },
            target_spp: 128,
            samples_per_pass: 1.0,
            status: JobStatus::Running,
        };
        app.on_worker(SessionEvent::Progress(Arc::new(snap)));
        app.resize(w, h);
        app
    }

    fn render(app: &App) -> Terminal<TestBackend> {
        let mut t = Terminal::new(TestBackend::new(app.size.width, app.size.height)).unwrap();
        t.draw(|f| draw(f, app)).unwrap();
        t
    }

    #[test]
    fn main_layout() {
        let app = app(80, 24);
        insta::assert_snapshot!(render(&app).backend());
    }

    /// The app with the form set to painterly (as if cycled there) and `selected` selected.
    fn painterly_app(w: u16, h: u16, selected: Field) -> App {
        let mut app = app(w, h);
        app.form.overrides.integrator = Some(crate::settings::IntegratorKind::Painterly);
        app.form.overrides.painterly.stroke = Some(4);
        app.form.selected = selected;
        app
    }

    #[test]
    fn main_layout_painterly() {
        let app = painterly_app(80, 24, Field::Stroke);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn smallest_terminal_scrolls_past_the_painterly_fields() {
        // The form scrolls so the selected sampler is its last row; names too long for the
        // value column keep their start.
        let mut app = painterly_app(MIN_WIDTH, MIN_HEIGHT, Field::Sampler);
        app.form.overrides.sampler = Some(crate::sampling::SamplerKind::Independent);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn help_overlay() {
        let mut app = app(80, 24);
        app.show_help = true;
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn smallest_supported_terminal() {
        let app = app(MIN_WIDTH, MIN_HEIGHT);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn error_chart_panel() {
        let mut app = app(80, 24);
        // RMSE falling as 1/sqrt(t) from 0.1 at 0.1 s to 0.001 at 1000 s.
        app.history = (0..9)
            .map(|k| {
                let t = 10f64.powf(k as f64 / 2.0 - 1.0);
                (t, 0.1 / (10.0 * t).sqrt())
            })
            .collect();
        app.show_chart = true;
        app.resize(80, 24);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn main_layout_120x40() {
        let app = app(120, 40);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn details_view() {
        let mut app = app(80, 24);
        app.on_key(crossterm::event::KeyEvent::from(
            crossterm::event::KeyCode::Char('i'),
        ));
        assert!(app.show_details);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn details_view_120x40() {
        let mut app = app(120, 40);
        app.show_details = true;
        insta::assert_snapshot!(render(&app).backend());
    }

    /// The status rows of a screen as text.
    fn status_rows(t: &Terminal<TestBackend>) -> Vec<String> {
        let buf = t.backend().buffer();
        let h = buf.area.height;
        (h - 2..h)
            .map(|y| {
                (0..buf.area.width)
                    .map(|x| buf[(x, y)].symbol().to_string())
                    .collect()
            })
            .collect()
    }

    /// While a scene loads, the gauge row shows the stage and how far it has got.
    #[test]
    fn the_gauge_shows_a_scene_load() {
        let mut app = app(120, 40);
        let gauge_row = |t: &Terminal<TestBackend>| -> String {
            let buf = t.backend().buffer();
            let y = buf.area.height - 3;
            (0..buf.area.width).map(|x| buf[(x, y)].symbol()).collect()
        };
        app.loading = Some(("reading big.glb".into(), 200, 50));
        let row = gauge_row(&render(&app));
        assert!(row.contains("loading: reading big.glb  25%"), "{row}");
        app.loading = Some(("decoding big.glb: image 0".into(), 0, 0));
        let row = gauge_row(&render(&app));
        assert!(row.contains("loading: decoding big.glb: image 0…"), "{row}");
        app.loading = None;
        assert!(!gauge_row(&render(&app)).contains("loading"));
    }

    #[test]
    fn the_colour_hint_shows_until_a_key_is_pressed() {
        for (w, h, hint) in [(80, 24, COLOR_HINTS[2]), (120, 40, COLOR_HINTS[0])] {
            let mut app = app(w, h);
            let rows = status_rows(&render(&app));
            assert!(rows[1].contains(hint), "{w}: {rows:?}");
            app.on_key(crossterm::event::KeyEvent::from(
                crossterm::event::KeyCode::Tab,
            ));
            let rows = status_rows(&render(&app));
            assert!(!rows[1].contains("256 colours"), "{w}: {rows:?}");
            // Without the hint, the build notes take its place, in short.
            assert!(rows[1].contains(&app.notes.short()), "{w}: {rows:?}");
        }
        // Not when 256 colours were asked for.
        let mut app = app(80, 24);
        app.color_hint = false;
        app.form.color = ColorChoice::Ansi256;
        assert!(!status_rows(&render(&app))[1].contains("truecolor"));
    }

    #[test]
    fn status_rows_are_never_cut_mid_word() {
        // Every word on the status rows is a whole word of the texts they are made of, at both
        // widths, with and without the hint and a long message.
        for (w, h) in [(80, 24), (120, 40), (MIN_WIDTH, MIN_HEIGHT)] {
            for hint in [true, false] {
                let mut app = app(w, h);
                app.color_hint = hint;
                app.message = Some(Message::Info(
                    "saved /home/someone/renders/cornell-128spp-20261204-153000.png".into(),
                ));
                let mut source = COLOR_HINTS.join(" ");
                source.push_str(&format!(" {} ", app.notes.short()));
                source.push_str(" saved /home/someone/renders/cornell-128spp-20261204-153000.png ");
                source.push_str(
                    " 32 spp · 0.05 M samples/s · est. error 0.0123 (rel 0.030) · invalid 0",
                );
                let words: Vec<&str> = source.split_whitespace().collect();
                for row in status_rows(&render(&app)) {
                    for word in row.split_whitespace() {
                        let whole = word.strip_suffix('…').unwrap_or(word);
                        assert!(
                            words.contains(&whole),
                            "{w}x{h} hint {hint}: '{word}' cut in {row:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn short_notes_keep_the_first_clause_of_each() {
        assert_eq!(
            cornell_notes().short(),
            "flat scan, 9 objects · 1 emitter · caustics light-traced"
        );
        let bvh = BuildNotes {
            accel: "BVH, 1200 objects, 2399 nodes, built in 1.2 ms (auto: ...)".into(),
            light_sampling: "none (no emitters)".into(),
            caustics: String::new(),
            environment: "map builtin:sky (512x256), importance-sampled, MIS with BSDF sampling"
                .into(),
            materials: String::new(),
            build_time: Duration::ZERO,
            warnings: vec!["head.glb: 3 KHR_lights_punctual light(s) skipped".into()],
        };
        assert_eq!(
            bvh.short(),
            "BVH, 1200 objects · none · sky map · 1 warning (i)"
        );
    }

    #[test]
    fn too_small_terminal_says_so() {
        let app = app(30, 8);
        insta::assert_snapshot!(render(&app).backend());
    }

    #[test]
    fn preview_keeps_the_film_aspect_ratio() {
        // 64x48 film (4:3) in the 80x24 layout: count the cells holding image.
        let app = app(80, 24);
        let t = render(&app);
        let area = layout(app.size, app.show_chart).preview.unwrap();
        let buf = t.backend().buffer();
        let (mut cols, mut rows) = (0, 0);
        for y in area.top()..area.bottom() {
            let n = (area.left()..area.right())
                .filter(|&x| buf[(x, y)].symbol() == "▀")
                .count();
            if n > 0 {
                rows += 1;
                cols = cols.max(n);
            }
        }
        // Two sub-pixels per row: width / (2 rows) = 4:3 within one cell of rounding.
        let ratio = cols as f64 / (2.0 * rows as f64);
        assert!((ratio - 4.0 / 3.0).abs() < 0.1, "{cols}x{rows}: {ratio}");
    }
}
