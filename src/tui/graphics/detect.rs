//! Which graphics protocol the terminal speaks, found by asking it: a kitty graphics query, a
//! cell-size report request (`CSI 16 t`) and a primary device attributes request (`CSI c`),
//! which every terminal answers, last. A kitty reply before the DA1 reply means kitty graphics;
//! a `4` among the DA1 attributes means sixel. A terminal that never answers (or a tmux that
//! swallows the queries) times out: half-blocks then. TERM is never consulted.
//!
//! The queries are sent and answered before the input thread starts reading, so no reply byte
//! reaches the key handling. Keys typed meanwhile (a `q` pressed while a loaded machine starts
//! ptui) are read with the replies: they are handed back, in order, to be handled as keys
//! (`tui::event::keys_from_bytes`); they used to be dropped, and ptui then did not quit.

use super::kitty;
use std::io::{self, Write};
use std::time::{Duration, Instant};

/// What the terminal said about itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Support {
    pub kitty: bool,
    pub sixel: bool,
    /// Size of a cell in pixels, when it said.
    pub cell: Option<(u16, u16)>,
    /// The DA1 reply arrived (so the answers are complete).
    pub answered: bool,
}

/// Read the replies to the queries in `bytes`.
pub fn parse(bytes: &[u8]) -> Support {
    split(bytes).0
}

/// The replies to the queries in `bytes`, and every other byte (what the user typed), in order.
pub fn split(bytes: &[u8]) -> (Support, Vec<u8>) {
    let mut s = Support::default();
    let mut typed = Vec::new();
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] != 0x1b {
            typed.push(bytes[k]);
            k += 1;
            continue;
        }
        let rest = &bytes[k + 1..];
        if let Some(apc) = rest.strip_prefix(b"_G") {
            // ESC _ G i=31;OK ESC \ (or an error message instead of OK), up to and past the
            // terminator, which is no Esc key.
            let end = find(apc, b"\x1b\\");
            let body = &apc[..end.unwrap_or(apc.len())];
            if body.starts_with(b"i=31;") && body.ends_with(b"OK") {
                s.kitty = true;
            }
            k += 3 + end.map_or(apc.len(), |e| e + 2);
        } else if let Some(csi) = rest.strip_prefix(b"[") {
            let end = csi
                .iter()
                .position(|b| (0x40..=0x7e).contains(b))
                .unwrap_or(csi.len());
            let params = &csi[..end];
            match csi.get(end) {
                Some(b'c') if params.first() == Some(&b'?') => {
                    s.answered = true;
                    s.sixel = numbers(&params[1..]).iter().skip(1).any(|&n| n == 4);
                }
                Some(b't') if params.first() == Some(&b'6') => {
                    if let [6, h, w] = numbers(params)[..] {
                        if w > 0 && h > 0 && w <= 1000 && h <= 1000 {
                            s.cell = Some((w as u16, h as u16));
                        }
                    }
                }
                // Not a reply: a key (an arrow, Shift-Tab).
                _ => typed.extend_from_slice(&bytes[k..(k + 3 + end).min(bytes.len())]),
            }
            k += 3 + end;
        } else {
            // Esc, or Alt with a key.
            typed.push(0x1b);
            k += 1;
        }
    }
    (s, typed)
}

fn numbers(params: &[u8]) -> Vec<u32> {
    params
        .split(|&b| b == b';')
        .map(|p| {
            std::str::from_utf8(p)
                .ok()
                .and_then(|t| t.parse().ok())
                .unwrap_or(0)
        })
        .collect()
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Ask the terminal (in raw mode, before anything else reads stdin) and wait for the DA1 reply
/// at most `timeout`; with the answers, the bytes typed meanwhile.
#[cfg(unix)]
pub fn query(timeout: Duration) -> io::Result<(Support, Vec<u8>)> {
    let mut out = io::stdout();
    out.write_all(kitty::QUERY)?;
    out.write_all(b"\x1b[16t\x1b[c")?;
    out.flush()?;
    let deadline = Instant::now() + timeout;
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        let mut fds = libc::pollfd {
            fd: libc::STDIN_FILENO,
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd, for the duration of the call.
        let ready = unsafe { libc::poll(&mut fds, 1, left.as_millis().max(1) as libc::c_int) };
        if ready < 0 {
            let e = io::Error::last_os_error();
            if e.kind() == io::ErrorKind::Interrupted {
                continue;
            }
            return Err(e);
        }
        if ready == 0 {
            break;
        }
        // SAFETY: reads at most buf.len() bytes into buf.
        let n = unsafe { libc::read(libc::STDIN_FILENO, buf.as_mut_ptr().cast(), buf.len()) };
        if n <= 0 {
            break;
        }
        got.extend_from_slice(&buf[..n as usize]);
        if parse(&got).answered {
            break;
        }
    }
    Ok(split(&got))
}

#[cfg(not(unix))]
pub fn query(_timeout: Duration) -> io::Result<(Support, Vec<u8>)> {
    Ok((Support::default(), Vec::new()))
}

/// The cell size in pixels from the kernel's window size, if the terminal reports pixels.
#[cfg(unix)]
pub fn cell_size() -> Option<(u16, u16)> {
    // SAFETY: TIOCGWINSZ fills a winsize struct; a failure leaves it zeroed.
    let mut ws: libc::winsize = unsafe { std::mem::zeroed() };
    let ok = unsafe { libc::ioctl(libc::STDOUT_FILENO, libc::TIOCGWINSZ, &mut ws) } == 0;
    (ok && ws.ws_col > 0 && ws.ws_row > 0 && ws.ws_xpixel > 0 && ws.ws_ypixel > 0)
        .then(|| (ws.ws_xpixel / ws.ws_col, ws.ws_ypixel / ws.ws_row))
        .filter(|&(w, h)| w > 0 && h > 0)
}

#[cfg(not(unix))]
pub fn cell_size() -> Option<(u16, u16)> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kitty_reply_then_da1() {
        let s = parse(b"\x1b_Gi=31;OK\x1b\\\x1b[6;20;10t\x1b[?62;22c");
        assert_eq!(
            s,
            Support {
                kitty: true,
                sixel: false,
                cell: Some((10, 20)),
                answered: true
            }
        );
    }

    /// Keys typed while the terminal answers are handed back in order, replies taken out:
    /// a `q` pressed during the probe used to be dropped (and ptui did not quit).
    #[test]
    fn keys_typed_during_the_query_are_kept() {
        let (s, typed) = split(b"q\x1b_Gi=31;OK\x1b\\\x1b[A\x1b[6;20;10tj\x1b\x1b[?62;22c\r");
        assert!(s.kitty && s.answered && s.cell == Some((10, 20)));
        assert_eq!(typed, b"q\x1b[Aj\x1b\r");
        let (s, typed) = split(b"\x1b[?1;2c");
        assert!(s.answered && typed.is_empty());
    }

    #[test]
    fn sixel_from_da1_attributes() {
        // xterm -ti vt340, foot, mlterm: attribute 4 after the class.
        assert!(parse(b"\x1b[?63;1;2;4;6;9;15;22c").sixel);
        assert!(parse(b"\x1b[?62;4c").sixel);
        // tmux and a plain xterm: no 4 (and 64 is not 4).
        let tmux = parse(b"\x1b[?1;2c");
        assert!(tmux.answered && !tmux.sixel && !tmux.kitty);
        assert!(!parse(b"\x1b[?64;1;2;6;22c").sixel);
        // The class itself is not an attribute.
        assert!(!parse(b"\x1b[?4c").sixel);
    }

    #[test]
    fn a_kitty_error_or_no_reply_is_no_support() {
        assert!(!parse(b"\x1b_Gi=31;ENOTSUPPORTED:x\x1b\\\x1b[?62c").kitty);
        let none = parse(b"");
        assert!(!none.answered && !none.kitty && !none.sixel);
        // Typed keys among the replies are skipped.
        assert!(parse(b"q\x1b_Gi=31;OK\x1b\\x\x1b[?62;c").kitty);
    }
}
