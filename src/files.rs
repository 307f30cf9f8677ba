//! The one function through which the model readers (MTL, glTF and its buffers, texture images)
//! read a file: a regular file only (a directory, a device or a FIFO is refused from its
//! metadata, before anything is read), at most half the memory available, and one message
//! naming the file and what it was read as. It stands for the crate's input reader
//! (`input::read`), which it becomes where that exists.

use std::path::Path;

/// Where the memory available is unknown (no /proc/meminfo), the most read whole.
const FALLBACK_LIMIT: u64 = 4 << 30;

/// The whole of the regular file at `path`, read as `what` (`MTL file`, `texture`, ...).
/// Errors read `<path>: cannot read <what>: <reason>`.
pub fn read(path: &Path, what: &str) -> Result<Vec<u8>, String> {
    let fail = |reason: String| format!("{}: cannot read {what}: {reason}", path.display());
    let meta = std::fs::metadata(path).map_err(|e| fail(os_reason(&e)))?;
    if meta.is_dir() {
        return Err(fail("a directory, not a file".into()));
    }
    if !meta.is_file() {
        return Err(fail(
            "not a regular file (a device, FIFO or socket is never read)".into(),
        ));
    }
    let limit = size_limit();
    if meta.len() > limit {
        return Err(fail(format!(
            "{} is more than {}, half the memory available",
            human_bytes(meta.len()),
            human_bytes(limit)
        )));
    }
    std::fs::read(path).map_err(|e| fail(os_reason(&e)))
}

/// The most bytes read whole: half the memory available.
pub fn size_limit() -> u64 {
    available_memory().map_or(FALLBACK_LIMIT, |a| a / 2)
}

/// The memory the system says is available (Linux's MemAvailable), if it says.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn human_bytes(b: u64) -> String {
    format!("{:.1} MiB", b as f64 / (1 << 20) as f64)
}

/// An OS error's own words: `no such file or directory`, without `(os error 2)`.
fn os_reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    let text = text.split(" (os error ").next().unwrap_or(&text);
    let mut chars = text.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_lowercase().chain(chars).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusals_name_the_file_and_what_it_was_read_as() {
        let dir = tempfile::tempdir().unwrap();
        let e = read(dir.path(), "texture").unwrap_err();
        assert!(e.contains("cannot read texture: a directory"), "{e}");
        let e = read(&dir.path().join("none.png"), "texture").unwrap_err();
        assert!(
            e.ends_with("cannot read texture: no such file or directory"),
            "{e}"
        );
        let e = read(Path::new("/dev/zero"), "MTL file").unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        std::fs::write(dir.path().join("a.mtl"), "Kd 1 1 1\n").unwrap();
        assert_eq!(
            read(&dir.path().join("a.mtl"), "MTL file").unwrap().len(),
            9
        );
    }
}
