//! Text fitted to terminal columns: parts of a status line kept whole or left out, values cut
//! at a word or with an ellipsis, words wrapped, and durations as a clock shows them. Never cut
//! mid-word where a line has room to say less (issue 37's status lines).

use ratatui::text::{Line, Span};

/// The spans of `parts` that fit in `width` columns, in order; a part that does not fit whole
/// is left out (never cut mid-word), and the later, smaller ones still get their chance.
pub(super) fn fit_parts(parts: Vec<Span<'_>>, width: usize) -> Line<'_> {
    let mut used = 0;
    let mut kept = Vec::new();
    for p in parts {
        let w = p.width();
        if used + w <= width {
            used += w;
            kept.push(p);
        }
    }
    Line::from(kept)
}

/// `s` within `w` columns, cut at a word boundary with an ellipsis if it is longer.
pub(super) fn clip_words(s: &str, w: usize) -> String {
    if s.chars().count() <= w {
        return s.to_string();
    }
    let head: String = s.chars().take(w.saturating_sub(1)).collect();
    match head.rfind(' ') {
        Some(i) if i > 0 => format!("{}…", head[..i].trim_end()),
        _ if w > 0 => format!("{head}…"),
        _ => String::new(),
    }
}

/// Words of `s` in lines of at most `w` columns (a longer word gets a line of its own, cut).
pub(super) fn wrap_words(s: &str, w: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in s.split_whitespace() {
        let (n, m) = (line.chars().count(), word.chars().count());
        if n > 0 && n + 1 + m > w {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    lines.into_iter().map(|l| clip_right(&l, w)).collect()
}

/// Keep the end of `s` (the part being typed, the file name of a path) within `w` columns.
pub(super) fn clip_left(s: &str, w: usize) -> String {
    let n = s.chars().count();
    if n <= w {
        s.to_string()
    } else if w == 0 {
        String::new()
    } else {
        let tail: String = s.chars().skip(n - (w - 1)).collect();
        format!("…{tail}")
    }
}

/// Keep the start of `s` within `w` columns.
pub(super) fn clip_right(s: &str, w: usize) -> String {
    if s.chars().count() <= w {
        s.to_string()
    } else if w == 0 {
        String::new()
    } else {
        let head: String = s.chars().take(w - 1).collect();
        format!("{head}…")
    }
}

/// `secs` as m:ss, or h:mm:ss from an hour; `--` when unknown.
pub(super) fn fmt_duration(secs: f64) -> String {
    if !secs.is_finite() {
        return "--".into();
    }
    let s = secs.round() as u64;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_the_end_or_the_start() {
        assert_eq!(clip_left("scenes/room.toml", 8), "…om.toml");
        assert_eq!(clip_right("independent", 9), "independ…");
        assert_eq!(clip_right("sobol", 9), "sobol");
        assert_eq!(clip_right("sobol", 0), "");
    }
}
