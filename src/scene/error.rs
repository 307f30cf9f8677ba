//! Scene errors name the file, the line and column, the field, and the problem.

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A value the scene file got wrong.
    #[error("{file}:{location}{field}{message}", location = location(*.line, *.column), field = field_label(.field))]
    Invalid {
        file: String,
        line: Option<usize>,
        column: Option<usize>,
        field: Option<String>,
        message: String,
    },
    /// The file itself cannot be read (missing, a directory or a device, too large, not text).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    #[error("no scene file `{spec}` and no built-in scene of that name (built-ins: {builtins})")]
    NotFound { spec: String, builtins: String },
}

fn location(line: Option<usize>, column: Option<usize>) -> String {
    match (line, column) {
        (Some(l), Some(c)) => format!("{l}:{c}: "),
        (Some(l), None) => format!("{l}: "),
        _ => " ".into(),
    }
}

fn field_label(field: &Option<String>) -> String {
    match field {
        Some(f) if !f.is_empty() && f != "." => format!("field `{f}`: "),
        _ => String::new(),
    }
}

impl SceneError {
    /// An error at a byte span of the source text.
    pub fn at(
        file: &str,
        src: &str,
        span: Option<std::ops::Range<usize>>,
        field: Option<String>,
        message: impl Into<String>,
    ) -> Self {
        let (line, column) = match span {
            Some(span) => {
                let (l, c) = line_column(src, span.start);
                (Some(l), Some(c))
            }
            None => (None, None),
        };
        SceneError::Invalid {
            file: file.to_string(),
            line,
            column,
            field,
            message: message.into(),
        }
    }

    /// The problem alone, without the location (for tests and the TUI status line).
    pub fn message(&self) -> String {
        match self {
            SceneError::Invalid { message, .. } => message.clone(),
            other => other.to_string(),
        }
    }
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_column(src: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(src.len());
    let before = &src[..floor_char_boundary(src, offset)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}
