//! Reading the files ptui is given. Scenes, OBJ meshes, films, environment maps and reference
//! images all come through here (and so must any reader added later: MTL, glTF, textures), so
//! that no input can hang ptui or take all its memory:
//!
//! - An input is a regular file or a pipe the user named (`ptui render <(gen-scene)`, a FIFO, or
//!   `-` for standard input). A directory, a device (`/dev/zero`, `/dev/urandom`, a terminal) or
//!   a socket is refused from its metadata, before anything is read; a FIFO is opened without
//!   waiting, and one that no writer opens within [`WRITER_WAIT`] is refused too.
//! - A file is read whole only up to half the memory available ([`size_limit`]): a regular file
//!   larger than that is refused from its length, a pipe as soon as it passes it.
//! - Text has lines of at most [`MAX_LINE`] bytes, so binary data given as a scene or an OBJ
//!   fails at its first megabyte instead of being parsed.
//!
//! Every refusal is one [`InputError`]: the file, what it was read as, and why.

use crate::memory;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long a FIFO may stay without a writer before it is refused: a writer started beside ptui
/// (`mkfifo f; gen > f & ptui render f`) opens it in far less.
pub const WRITER_WAIT: Duration = Duration::from_millis(500);

/// Longest line of a text input: a scene or OBJ line is far shorter (a line of 1000 vertex
/// indices is ~10 KB); a longer one is binary data.
pub const MAX_LINE: usize = 1 << 20;

/// Where the memory available is unknown (no /proc/meminfo), the most read whole.
const FALLBACK_LIMIT: u64 = 4 << 30;

/// An input named by the user: a path, or standard input (`-`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    Path(PathBuf),
    Stdin,
}

impl Source {
    /// `-` is standard input; anything else a path.
    pub fn from_arg(arg: &str) -> Source {
        match arg {
            "-" => Source::Stdin,
            _ => Source::Path(PathBuf::from(arg)),
        }
    }

    /// How messages name it.
    pub fn name(&self) -> String {
        match self {
            Source::Path(p) => p.display().to_string(),
            Source::Stdin => "standard input".into(),
        }
    }
}

/// Why an input cannot be read: `<file>: cannot read <what>: <reason>`.
#[derive(Debug, thiserror::Error)]
#[error("{name}: cannot read {what}: {reason}")]
pub struct InputError {
    pub name: String,
    /// What the file was read as (`scene file`, `OBJ file`, ...).
    pub what: &'static str,
    pub reason: String,
}

/// Whether the input is text, whose lines are then held to [`MAX_LINE`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    Text,
    Binary,
}

/// The most bytes read whole: half the memory available, so that the file and what is built
/// from it both fit.
pub fn size_limit() -> u64 {
    memory::available().map_or(FALLBACK_LIMIT, |a| a / 2)
}

/// The whole of `source`, as UTF-8 text.
pub fn read_text(source: &Source, what: &'static str) -> Result<String, InputError> {
    let bytes = read(source, what, Content::Text)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        error(source, what, format!("not UTF-8 text (byte {at})"))
    })
}

/// The whole of `source`: a regular file or a pipe, within [`size_limit`]; text lines within
/// [`MAX_LINE`].
pub fn read(source: &Source, what: &'static str, content: Content) -> Result<Vec<u8>, InputError> {
    let fail = |reason: String| error(source, what, reason);
    let (mut file, kind) = match source {
        Source::Path(path) => open(path),
        Source::Stdin => stdin(),
    }
    .map_err(fail)?;
    let limit = size_limit();
    let mut buf = Vec::new();
    match kind {
        Kind::Regular(len) if len > limit => return Err(fail(too_large(len, limit))),
        Kind::Regular(len) => buf.reserve_exact(len as usize),
        // Whoever set standard input up has opened it: there is nothing to wait for.
        Kind::Pipe if *source == Source::Stdin => {}
        Kind::Pipe => buf = wait_for_writer(&file).map_err(fail)?,
    }
    read_limited(&mut file, buf, limit, content).map_err(fail)
}

/// A regular file opened for reading as it goes (a film, read pixel by pixel), with its length;
/// anything else is refused as [`read`] would.
pub fn open_regular(path: &Path, what: &'static str) -> Result<(File, u64), InputError> {
    let fail = |reason: String| error(&Source::Path(path.to_path_buf()), what, reason);
    match open(path).map_err(fail)? {
        (file, Kind::Regular(len)) => Ok((file, len)),
        (_, Kind::Pipe) => Err(fail(
            "a pipe; this must be a regular file (its length is checked before it is read)".into(),
        )),
    }
}

/// An image file read whole through [`read`], its format known from its first bytes (else from
/// its extension).
pub struct ImageFile {
    bytes: Vec<u8>,
    format: Option<image::ImageFormat>,
}

impl ImageFile {
    pub fn read(path: &Path, what: &'static str) -> Result<ImageFile, InputError> {
        let bytes = read(&Source::Path(path.to_path_buf()), what, Content::Binary)?;
        let format = image::guess_format(&bytes)
            .ok()
            .or_else(|| image::ImageFormat::from_path(path).ok());
        Ok(ImageFile { bytes, format })
    }

    /// A decoder of the bytes in memory, for the header or the pixels.
    pub fn reader(&self) -> image::ImageReader<std::io::Cursor<&[u8]>> {
        let mut reader = image::ImageReader::new(std::io::Cursor::new(self.bytes.as_slice()));
        if let Some(format) = self.format {
            reader.set_format(format);
        }
        reader
    }
}

fn error(source: &Source, what: &'static str, reason: String) -> InputError {
    InputError {
        name: source.name(),
        what,
        reason,
    }
}

fn too_large(len: u64, limit: u64) -> String {
    format!(
        "{} is more than {}, half the memory available",
        memory::human_bytes(len),
        memory::human_bytes(limit)
    )
}

/// An OS error's own words, once: `no such file or directory` (not its Display's `No such file
/// or directory (os error 2)`, whose number says nothing more).
pub fn os_reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    let text = match text.find(" (os error ") {
        Some(i) => &text[..i],
        None => &text,
    };
    let mut chars = text.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_lowercase().chain(chars).collect()
    })
}

/// What was opened: a regular file of that length, or a pipe.
enum Kind {
    Regular(u64),
    Pipe,
}

/// The file's kind from its metadata, or why it cannot be read.
fn kind_of(meta: &std::fs::Metadata) -> Result<Kind, String> {
    let t = meta.file_type();
    if t.is_file() {
        return Ok(Kind::Regular(meta.len()));
    }
    if t.is_dir() {
        return Err("a directory, not a file".into());
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Ok(Kind::Pipe);
        }
        if t.is_char_device() {
            return Err("a character device, not a file or a pipe".into());
        }
        if t.is_block_device() {
            return Err("a block device, not a file or a pipe".into());
        }
        if t.is_socket() {
            return Err("a socket, not a file or a pipe".into());
        }
    }
    Err("not a regular file or a pipe".into())
}

/// Opens `path` after its metadata says it is a file or a pipe (so no device is ever opened),
/// without waiting for a FIFO's writer, and checks the opened file again (it may have been
/// replaced in between).
fn open(path: &Path) -> Result<(File, Kind), String> {
    kind_of(&std::fs::metadata(path).map_err(|e| os_reason(&e))?)?;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    let file = options.open(path).map_err(|e| os_reason(&e))?;
    let kind = kind_of(&file.metadata().map_err(|e| os_reason(&e))?)?;
    Ok((file, kind))
}

/// Standard input, if it is a file or a pipe (not a terminal).
fn stdin() -> Result<(File, Kind), String> {
    use std::io::IsTerminal;
    if std::io::stdin().is_terminal() {
        return Err("it is a terminal: pipe the input in (`... - < scene.toml`)".into());
    }
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        let fd = std::io::stdin()
            .as_fd()
            .try_clone_to_owned()
            .map_err(|e| os_reason(&e))?;
        let file = File::from(fd);
        let kind = kind_of(&file.metadata().map_err(|e| os_reason(&e))?)?;
        Ok((file, kind))
    }
    #[cfg(not(unix))]
    {
        Err("not supported on this system".into())
    }
}

/// Waits up to [`WRITER_WAIT`] for a pipe opened without blocking to have data or a writer, then
/// makes reads block: a pipe whose writer is there but silent is waited for, as `cat` would. The
/// bytes already read (one at most) start the buffer.
#[cfg(unix)]
fn wait_for_writer(file: &File) -> Result<Vec<u8>, String> {
    use std::os::fd::AsRawFd;
    let fd = file.as_raw_fd();
    let start = std::time::Instant::now();
    let mut buf = Vec::new();
    loop {
        let left = WRITER_WAIT.saturating_sub(start.elapsed());
        let mut fds = libc::pollfd {
            fd,
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd, for the duration of the call. Linux reports neither data nor
        // a hang-up on a FIFO no writer has opened since we opened it: poll waits.
        let ready = unsafe { libc::poll(&mut fds, 1, left.as_millis().max(1) as libc::c_int) };
        if ready < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return Err(os_reason(&e));
        }
        if ready > 0 {
            // Data, or a writer came and went: reads now end at the end of what it wrote.
            break;
        }
        // Time is up. A writer that holds the pipe open without writing makes a read say "try
        // again"; with none, the read is at its end.
        let mut byte = [0u8; 1];
        // SAFETY: reads at most one byte into `byte`.
        let n = unsafe { libc::read(fd, byte.as_mut_ptr().cast(), 1) };
        if n > 0 {
            buf.push(byte[0]);
            break;
        }
        let e = std::io::Error::last_os_error();
        if n < 0 && e.kind() == std::io::ErrorKind::WouldBlock {
            break;
        }
        if n < 0 && e.kind() == std::io::ErrorKind::Interrupted {
            continue;
        }
        return Err(format!(
            "a pipe nobody writes to (no writer within {} s)",
            WRITER_WAIT.as_secs_f64()
        ));
    }
    // SAFETY: F_GETFL / F_SETFL on our own open descriptor.
    unsafe {
        let flags = libc::fcntl(fd, libc::F_GETFL);
        if flags < 0 || libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) < 0 {
            return Err(os_reason(&std::io::Error::last_os_error()));
        }
    }
    Ok(buf)
}

#[cfg(not(unix))]
fn wait_for_writer(_file: &File) -> Result<Vec<u8>, String> {
    Ok(Vec::new())
}

/// Reads `r` to its end after `buf`, refusing more than `limit` bytes and, for text, a line
/// longer than [`MAX_LINE`].
fn read_limited(
    r: &mut impl Read,
    mut buf: Vec<u8>,
    limit: u64,
    content: Content,
) -> Result<Vec<u8>, String> {
    let mut chunk = vec![0u8; 1 << 16];
    // Where the current line starts, and how many lines came before it.
    let (mut line_start, mut lines) = (0usize, 0usize);
    let mut scanned = 0usize;
    loop {
        let n = match r.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(os_reason(&e)),
        };
        buf.extend_from_slice(&chunk[..n]);
        if buf.len() as u64 > limit {
            return Err(format!(
                "more than {}, half the memory available",
                memory::human_bytes(limit)
            ));
        }
        if content == Content::Text {
            for (i, &b) in buf[scanned..].iter().enumerate() {
                if b == b'\n' {
                    line_start = scanned + i + 1;
                    lines += 1;
                }
            }
            scanned = buf.len();
            if buf.len() - line_start > MAX_LINE {
                return Err(long_line(lines + 1));
            }
        }
    }
    Ok(buf)
}

fn long_line(line: usize) -> String {
    format!(
        "line {line} is longer than {}: not a text file",
        memory::human_bytes(MAX_LINE as u64)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_lines_longer_than_the_limit_are_refused_where_they_start() {
        let mut text = b"a\nb\n".to_vec();
        text.extend(std::iter::repeat_n(b'x', MAX_LINE + 1));
        let err = read_limited(&mut text.as_slice(), Vec::new(), u64::MAX, Content::Text);
        assert_eq!(err.unwrap_err(), long_line(3));
        // The same bytes as binary are fine, and a line of exactly the limit is.
        assert!(read_limited(&mut text.as_slice(), Vec::new(), u64::MAX, Content::Binary).is_ok());
        let exact = vec![b'x'; MAX_LINE];
        assert!(read_limited(&mut exact.as_slice(), Vec::new(), u64::MAX, Content::Text).is_ok());
    }

    #[test]
    fn more_than_the_limit_is_refused() {
        let data = vec![b'\n'; 100];
        let err = read_limited(&mut data.as_slice(), Vec::new(), 99, Content::Text).unwrap_err();
        assert!(err.starts_with("more than 99 B"), "{err}");
        let ok = read_limited(&mut data.as_slice(), vec![b'a'], 101, Content::Text).unwrap();
        assert_eq!(ok.len(), 101);
    }

    #[test]
    fn what_is_not_a_file_or_a_pipe_is_refused_by_kind() {
        let read = |p: &str| read(&Source::from_arg(p), "scene file", Content::Text);
        let dir = read(".").unwrap_err();
        assert_eq!(
            dir.to_string(),
            ".: cannot read scene file: a directory, not a file"
        );
        let dev = read("/dev/zero").unwrap_err();
        assert!(dev.reason.starts_with("a character device"), "{dev}");
        let missing = read("no/such/file.toml").unwrap_err();
        assert_eq!(
            missing.to_string(),
            "no/such/file.toml: cannot read scene file: no such file or directory"
        );
    }
}
