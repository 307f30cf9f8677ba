//! Where everything goes on the screen: title, form, preview, optional error chart, gauge and
//! status lines. The view draws into these areas; the app asks for the preview's to size it.

use ratatui::layout::{Constraint, Layout, Rect};

/// Smallest terminal the layout works in.
pub const MIN_WIDTH: u16 = 40;
pub const MIN_HEIGHT: u16 = 12;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Areas {
    pub title: Rect,
    pub form: Rect,
    /// None when the terminal is below the minimum size.
    pub preview: Option<Rect>,
    pub chart: Option<Rect>,
    pub gauge: Rect,
    pub status: Rect,
}

/// Where everything goes in a terminal of size `area`.
pub fn layout(area: Rect, show_chart: bool) -> Areas {
    let [title, body, gauge, status] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Min(1),
        Constraint::Length(1),
        Constraint::Length(2),
    ])
    .areas(area);
    // At least 22 columns: a 10-column label, a space, and a value as long as `painterly`.
    let form_w = (area.width / 3).clamp(22, 30);
    let [form, right] =
        Layout::horizontal([Constraint::Length(form_w), Constraint::Min(1)]).areas(body);
    let (preview, chart) = if show_chart {
        let [p, c] =
            Layout::vertical([Constraint::Percentage(60), Constraint::Percentage(40)]).areas(right);
        (p, Some(c))
    } else {
        (right, None)
    };
    let big_enough = area.width >= MIN_WIDTH && area.height >= MIN_HEIGHT;
    Areas {
        title,
        form,
        preview: big_enough.then_some(preview),
        chart: chart.filter(|_| big_enough),
        gauge,
        status,
    }
}
