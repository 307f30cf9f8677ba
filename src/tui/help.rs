//! The key list (`?`): every key, grouped by the mode it applies in, in two columns where the
//! terminal is wide enough.

use super::form::Field;
use super::text::wrap_words;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph};
use ratatui::Frame;

/// (mode, [(keys, what they do)]).
pub const HELP: &[(&str, &[(&str, &str)])] = &[
    (
        "everywhere",
        &[
            ("Tab S-Tab", "select a form field"),
            ("Enter", "edit or step the field"),
            ("space", "pause / resume"),
            ("r", "restart from zero"),
            ("s / e", "save the PNG / EXR"),
            ("w", "write the film (.film)"),
            ("W", "write the scene file"),
            ("u / Ctrl-R", "undo / redo a scene edit"),
            ("v", "camera mode on / off"),
            ("o / click", "pick the object there"),
            ("F", "focus the lens there"),
            ("c / f", "colours / cell shape"),
            ("g / i", "error chart / details"),
            ("?", "this help"),
            ("q / Ctrl-C", "quit (Esc outside modes)"),
        ],
    ),
    (
        "preview (outside camera mode)",
        &[
            ("+ / - / 0", "zoom in / out / fit"),
            ("arrows hjkl", "pan the zoomed preview"),
            ("wheel", "zoom in / out"),
        ],
    ),
    (
        "camera mode (v)",
        &[
            ("arrows hjkl", "orbit the look-at point"),
            ("+ / -", "dolly in / out"),
            ("S-arrows HJKL", "pan camera and target"),
            ("[ / ]", "narrow / widen the view"),
            ("drag / wheel", "orbit / dolly"),
            ("v / Esc", "leave camera mode"),
        ],
    ),
    (
        "editing a field",
        &[
            ("Enter / Esc", "apply / cancel"),
            ("Ctrl-U", "clear; empty: default"),
        ],
    ),
];

const KEY_W: usize = 14;

fn section(title: &str, keys: &[(&str, &str)]) -> Vec<Line<'static>> {
    let mut lines = vec![Line::from(Span::styled(
        format!(" {title}"),
        Style::new().bold().underlined(),
    ))];
    lines.extend(keys.iter().map(|(k, what)| {
        Line::from(vec![
            Span::styled(format!(" {k:<KEY_W$}"), Style::new().bold().yellow()),
            Span::raw(what.to_string()),
        ])
    }));
    lines
}

/// The help box over the screen: the "everywhere" keys on the left and the modes' on the right
/// when 80 columns fit, else all in one column (cut at the bottom in a short terminal).
pub fn draw_help(frame: &mut Frame, area: Rect) {
    let columns: Vec<Vec<Line>> = {
        let all: Vec<Vec<Line>> = HELP.iter().map(|(t, k)| section(t, k)).collect();
        let (first, rest) = all.split_first().expect("sections");
        let rest: Vec<Line> = rest
            .iter()
            .enumerate()
            .flat_map(|(i, s)| {
                let gap = (i > 0).then(|| Line::from(""));
                gap.into_iter().chain(s.iter().cloned())
            })
            .collect();
        // The fields Enter steps, as the code has them (so the list cannot drift from it).
        let mut rest = rest;
        rest.push(Line::from(""));
        rest.push(Line::from(Span::styled(
            " Enter steps",
            Style::new().bold().underlined(),
        )));
        let steps = format!("{}, an object's choices and yes/no keys", Field::cycling());
        rest.extend(
            wrap_words(&steps, 37)
                .into_iter()
                .map(|l| Line::from(format!(" {l}"))),
        );
        if area.width >= 80 {
            vec![first.clone(), rest]
        } else {
            let mut one = first.clone();
            one.push(Line::from(""));
            one.extend(rest);
            vec![one]
        }
    };
    let col_w = 40u16;
    let w = (col_w * columns.len() as u16 + 2).min(area.width);
    let rows = columns.iter().map(Vec::len).max().unwrap_or(0) as u16;
    let h = (rows + 2).min(area.height);
    let popup = Rect::new(
        area.x + (area.width - w) / 2,
        area.y + (area.height - h) / 2,
        w,
        h,
    );
    frame.render_widget(Clear, popup);
    let block = Block::bordered()
        .title(" keys (any key closes) ")
        .style(Style::new().add_modifier(Modifier::empty()));
    let inner = block.inner(popup);
    frame.render_widget(block, popup);
    for (i, lines) in columns.into_iter().enumerate() {
        let x = inner.x + i as u16 * col_w;
        if x >= inner.right() {
            break;
        }
        let col = Rect::new(x, inner.y, col_w.min(inner.right() - x), inner.height);
        frame.render_widget(Paragraph::new(lines), col);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_the_app_takes_is_listed() {
        let listed: Vec<&str> = HELP
            .iter()
            .flat_map(|(_, keys)| keys.iter())
            .flat_map(|(k, _)| k.split([' ', '/']))
            .filter(|k| !k.is_empty())
            .collect();
        let letters = |s: &str| s.chars().all(|c| c.is_ascii_lowercase()) && s.len() > 1;
        // Keys written together ("hjkl", "HJKL") count letter by letter.
        let singles: Vec<String> = listed
            .iter()
            .filter(|k| letters(k) && k.len() <= 4 || k.chars().all(|c| c.is_ascii_uppercase()))
            .flat_map(|k| k.chars().map(String::from))
            .collect();
        for key in [
            "Tab", "S-Tab", "Enter", "space", "r", "s", "e", "w", "W", "u", "Ctrl-R", "v", "o",
            "click", "F", "c", "f", "g", "i", "?", "q", "Ctrl-C", "+", "-", "0", "arrows", "h",
            "j", "k", "l", "wheel", "S-arrows", "H", "J", "K", "L", "[", "]", "drag", "Esc",
            "Ctrl-U",
        ] {
            assert!(
                listed.contains(&key) || singles.iter().any(|s| s == key),
                "`{key}` is not in the help"
            );
        }
    }
}
