//! Terminal colour: choosing truecolor or 256 colours. How a colour becomes a 256-colour
//! palette entry is in [`super::dither`].

pub use super::dither::ansi256_rgb;

/// What the user asked for (`--color`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorChoice {
    /// COLORTERM=truecolor|24bit, then TERM ending in `-direct`, else 256 colours.
    #[default]
    Auto,
    Truecolor,
    #[value(name = "256")]
    Ansi256,
}

impl ColorChoice {
    pub fn name(self) -> &'static str {
        match self {
            ColorChoice::Auto => "auto",
            ColorChoice::Truecolor => "truecolor",
            ColorChoice::Ansi256 => "256",
        }
    }

    /// Resolve `auto` from the environment.
    pub fn resolve(self) -> ColorMode {
        match self {
            ColorChoice::Truecolor => ColorMode::Truecolor,
            ColorChoice::Ansi256 => ColorMode::Ansi256,
            ColorChoice::Auto => detect(
                std::env::var("COLORTERM").ok().as_deref(),
                std::env::var("TERM").ok().as_deref(),
            ),
        }
    }
}

/// What the preview actually sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorMode {
    Truecolor,
    Ansi256,
}

impl ColorMode {
    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Truecolor => "truecolor",
            ColorMode::Ansi256 => "256",
        }
    }

    pub fn toggled(self) -> Self {
        match self {
            ColorMode::Truecolor => ColorMode::Ansi256,
            ColorMode::Ansi256 => ColorMode::Truecolor,
        }
    }
}

/// COLORTERM first (what truecolor terminals set), then a `-direct` terminfo name (e.g.
/// `xterm-direct`), else 256 colours: the safe choice over SSH and inside tmux.
pub fn detect(colorterm: Option<&str>, term: Option<&str>) -> ColorMode {
    if let Some(c) = colorterm {
        let c = c.trim().to_ascii_lowercase();
        if c == "truecolor" || c == "24bit" {
            return ColorMode::Truecolor;
        }
    }
    if term.is_some_and(|t| t.ends_with("-direct")) {
        return ColorMode::Truecolor;
    }
    ColorMode::Ansi256
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_detection_order() {
        assert_eq!(
            detect(Some("truecolor"), Some("xterm")),
            ColorMode::Truecolor
        );
        assert_eq!(detect(Some("24bit"), None), ColorMode::Truecolor);
        assert_eq!(detect(None, Some("xterm-direct")), ColorMode::Truecolor);
        assert_eq!(detect(None, Some("tmux-256color")), ColorMode::Ansi256);
        assert_eq!(detect(Some(""), Some("screen")), ColorMode::Ansi256);
    }
}
