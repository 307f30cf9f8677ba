//! The kitty graphics protocol's encoder: an RGB image, zlib-compressed and base64-encoded, sent
//! in chunks of at most 4096 bytes and placed at the cursor over a given number of cells.
//! See <https://sw.kovidgoyal.net/kitty/graphics-protocol/>.

use base64::Engine;
use std::io::Write;

/// Most base64 bytes in one escape sequence (the protocol's limit).
pub const CHUNK: usize = 4096;

/// Ask whether the terminal understands the protocol: a 1x1 image that is queried, not stored
/// (`a=q`). A terminal that does replies `ESC _ G i=31;OK ESC \`.
pub const QUERY: &[u8] = b"\x1b_Gi=31,s=1,v=1,a=q,t=d,f=24;AAAA\x1b\\";

/// Delete every image and placement (and free their data); `q=2`: no reply.
pub const DELETE_ALL: &[u8] = b"\x1b_Ga=d,d=A,q=2\x1b\\";

/// Delete the placements shown on screen, keeping the image data (for an overlay).
pub const HIDE_ALL: &[u8] = b"\x1b_Ga=d,d=a,q=2\x1b\\";

/// Transmit `rgb` (`w` x `h`, 3 bytes a pixel) as image `id` and show it at the cursor, scaled
/// to `cols` x `rows` cells, without moving the cursor (`C=1`). A new image with the same id
/// and placement id replaces the old one. `q=2`: the terminal sends no reply, so nothing
/// reaches the key reader.
pub fn encode(out: &mut Vec<u8>, id: u32, rgb: &[u8], w: u32, h: u32, cols: u16, rows: u16) {
    debug_assert_eq!(rgb.len(), (w * h * 3) as usize);
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    // Writing to a Vec cannot fail.
    let _ = z.write_all(rgb);
    let packed = z.finish().unwrap_or_default();
    let data = base64::engine::general_purpose::STANDARD.encode(packed);
    let chunks: Vec<&[u8]> = data.as_bytes().chunks(CHUNK).collect();
    let n = chunks.len();
    for (k, chunk) in chunks.into_iter().enumerate() {
        let more = u8::from(k + 1 < n);
        if k == 0 {
            let _ = write!(
                out,
                "\x1b_Ga=T,q=2,f=24,o=z,s={w},v={h},i={id},p=1,c={cols},r={rows},C=1,m={more};"
            );
        } else {
            let _ = write!(out, "\x1b_Gm={more};");
        }
        out.extend_from_slice(chunk);
        out.extend_from_slice(b"\x1b\\");
    }
}
