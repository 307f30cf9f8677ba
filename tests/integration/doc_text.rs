//! Reading Markdown and shell the way the docs test needs: fenced code blocks, prose and its code
//! spans, link targets, and `ptui` command lines split like a shell would split them.

/// A fenced code block: its info string (`toml`, `sh`, ...), its text and the line it starts on.
pub struct Block {
    pub info: String,
    pub body: String,
    pub line: usize,
}

pub fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(info) = trimmed.strip_prefix("```") {
            match open.take() {
                Some(b) => out.push(b),
                None => {
                    open = Some(Block {
                        info: info.trim().to_string(),
                        body: String::new(),
                        line: i + 2,
                    })
                }
            }
        } else if let Some(b) = open.as_mut() {
            b.body.push_str(line);
            b.body.push('\n');
        }
    }
    out
}

/// The prose of `text` (outside code blocks), line by line, with its line numbers.
pub fn prose(text: &str) -> Vec<(usize, &str)> {
    let mut inside = false;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            inside = !inside;
        } else if !inside {
            out.push((i + 1, line));
        }
    }
    out
}

/// The inline code spans of the prose, with their line numbers (a span may not cross a line).
pub fn code_spans(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in prose(text) {
        let mut parts = line.split('`');
        parts.next();
        while let (Some(code), Some(_)) = (parts.next(), parts.next()) {
            out.push((n, code.to_string()));
        }
    }
    out
}

/// The lines of a code block with backslash continuations joined, and their offsets.
pub fn joined_lines(body: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in body.lines().enumerate() {
        let (start, mut text) = pending.take().unwrap_or((i, String::new()));
        match line.trim_end().strip_suffix('\\') {
            Some(head) => {
                text.push_str(head);
                text.push(' ');
                pending = Some((start, text));
            }
            None => {
                text.push_str(line);
                out.push((start, text));
            }
        }
    }
    out.extend(pending);
    out
}

/// The argument lists of the `ptui` commands on one shell line: `ptui` as a command word (at the
/// start, or after `;`, `|`, `&`, `(`, `do`, `exec`, or an opening quote that then ends the
/// command), split like a shell would, variables and GNU parallel's `{}` given a value.
pub fn ptui_commands(line: &str) -> Vec<Vec<String>> {
    let line = line.trim_start().trim_start_matches("$ ");
    let chars: Vec<char> = without_comment(line).chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts_word = i == 0 || " \t;|&(\"'".contains(chars[i - 1]);
        // Inside a quoted string (`--wrap "ptui merge ..."`), the command ends at its quote.
        let quote = (i > 0 && "\"'".contains(chars[i - 1])).then(|| chars[i - 1]);
        let is_ptui = chars[i..].starts_with(&['p', 't', 'u', 'i'])
            && chars
                .get(i + 4)
                .is_none_or(|c| " \t;|&)".contains(*c) || Some(*c) == quote);
        if !(starts_word && is_ptui) {
            i += 1;
            continue;
        }
        let (words, end) = shell_words(&chars[i + 4..], quote);
        out.push(words);
        i += 4 + end;
    }
    out
}

/// `line` up to its comment: an unquoted `#` at the start of a word.
fn without_comment(line: &str) -> &str {
    let mut q: Option<char> = None;
    let mut prev = ' ';
    for (i, c) in line.char_indices() {
        match q {
            Some(open) if c == open => q = None,
            Some(_) => {}
            None if c == '"' || c == '\'' => q = Some(c),
            None if c == '#' && prev.is_whitespace() => return &line[..i],
            None => {}
        }
        prev = c;
    }
    line
}

/// Words up to the end of the command: an unquoted `;`, `|`, `&`, `)`, GNU parallel's `:::`, or
/// the closing `quote`. Returns the words and how many characters were read.
fn shell_words(chars: &[char], quote: Option<char>) -> (Vec<String>, usize) {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut k = 0;
    let mut q: Option<char> = None;
    while k < chars.len() {
        let c = chars[k];
        match q {
            Some(open) if c == open => q = None,
            Some(_) => word.push(c),
            None if Some(c) == quote || ";|&)".contains(c) => break,
            None if c == '#' && !in_word => break,
            None if c == '"' || c == '\'' => {
                q = Some(c);
                in_word = true;
            }
            None if c == '\\' && k + 1 < chars.len() => {
                word.push(chars[k + 1]);
                in_word = true;
                k += 1;
            }
            None if c.is_whitespace() => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            None if c == '<' && chars.get(k + 1) == Some(&'(') => {
                // Process substitution: one word, a path.
                let close = chars[k..].iter().position(|&c| c == ')').unwrap_or(0);
                word.push_str("/dev/fd/63");
                in_word = true;
                k += close;
            }
            None => {
                word.push(c);
                in_word = true;
            }
        }
        k += 1;
    }
    if in_word {
        words.push(word);
    }
    if let Some(end) = words.iter().position(|w| w == ":::") {
        words.truncate(end);
    }
    (words.into_iter().map(|w| fill_in(&w)).collect(), k)
}

/// `$VAR`, `${VAR}`, `$((expr))` and `{}` stand for a value the example leaves open: 1.
fn fill_in(word: &str) -> String {
    let mut out = String::new();
    let chars: Vec<char> = word.chars().collect();
    let mut k = 0;
    while k < chars.len() {
        if chars[k] == '$' {
            out.push('1');
            k += 1;
            if chars.get(k) == Some(&'(') || chars.get(k) == Some(&'{') {
                let close = if chars[k] == '(' { ')' } else { '}' };
                while k < chars.len() && chars[k] != close {
                    k += 1;
                }
                while k < chars.len() && chars[k] == close {
                    k += 1;
                }
            } else {
                while k < chars.len() && (chars[k].is_alphanumeric() || chars[k] == '_') {
                    k += 1;
                }
            }
        } else if chars[k..].starts_with(&['{', '}']) {
            out.push('1');
            k += 2;
        } else {
            out.push(chars[k]);
            k += 1;
        }
    }
    out
}

#[test]
fn shell_lines_split_like_a_shell() {
    let words = |l: &str| ptui_commands(l);
    assert_eq!(
        words("ptui render cornell -o x.png   # a comment"),
        [["render", "cornell", "-o", "x.png"]]
    );
    assert_eq!(
        words("  --wrap \"ptui merge p/*.film -o f.exr\")"),
        [["merge", "p/*.film", "-o", "f.exr"]]
    );
    assert_eq!(
        words("parallel ptui render s.toml --shard {}/4 -o part-{}.film ::: 0 1"),
        [["render", "s.toml", "--shard", "1/4", "-o", "part-1.film"]]
    );
    assert_eq!(
        words("exec ptui render --resume \"$part\" -q; ptui scenes"),
        [vec!["render", "--resume", "1", "-q"], vec!["scenes"]]
    );
    assert!(words("ptui's estimator, ptui::analysis::stats").is_empty());
    assert!(words("cargo run --release   # ptui on cornell").is_empty());
    assert_eq!(words("ptui render <(gen) -o x.png")[0][1], "/dev/fd/63");
}

/// `(target)` of each Markdown link or image on a line, without its `#anchor`; web links and
/// bare anchors left out.
pub fn link_targets(line: &str) -> Vec<String> {
    line.match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &line[i + 2..];
            let target = &rest[..rest.find(')')?];
            let target = target.split('#').next().unwrap_or("");
            (!target.is_empty() && !target.contains("://") && !target.starts_with("mailto:"))
                .then(|| target.to_string())
        })
        .collect()
}
