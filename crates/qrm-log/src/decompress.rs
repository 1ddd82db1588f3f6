//! MCAP chunk decompression in pure Rust: zstd by `ruzstd`, lz4 frames by `lz4_flex`,
//! registered with `mcap`'s sans-I/O reader in place of its C bindings.
//!
//! Why not `mcap`'s own `zstd`/`lz4` features: they compile the C libraries from source, which
//! was about a tenth of a clean `cargo build --release`'s CPU and the one reason a build needed
//! a C compiler (issue 40; docs/build-time.md). Reading a bag is bounded by mapping, not by
//! decompression, so the pure-Rust decoders' speed is not what a user waits for.
//!
//! A chunk is decoded whole: [`ChunkDecoder::next_read_size`] asks for every compressed byte
//! of the chunk (the reader clamps the request to the chunk's remaining bytes and to the record
//! length limit), the first [`ChunkDecoder::decompress`] call decodes them all, and later calls
//! hand the output out in the pieces the reader asks for. Output beyond the record length limit
//! is refused, so a small chunk that inflates to gigabytes (a "zip bomb") is an error, not an
//! abort.

use std::io::Read;

use mcap::McapError;
use mcap::sans_io::decompressor::{DecompressResult, Decompressor};

/// The two chunk compressions the MCAP spec names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compression {
    /// Zstandard frames (`ros2 bag record`'s and Foxglove's default).
    Zstd,
    /// LZ4 frames.
    Lz4,
}

impl Compression {
    /// The chunk header's `compression` string.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Zstd => "zstd",
            Self::Lz4 => "lz4",
        }
    }

    /// Every compressed frame in `src`, decoded and concatenated; at most `limit` bytes.
    ///
    /// # Errors
    /// The decoder's message for a damaged or truncated frame, or the limit when the output
    /// would exceed it.
    pub fn decode(self, src: &[u8], limit: usize) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        let cap = u64::try_from(limit).unwrap_or(u64::MAX).saturating_add(1);
        match self {
            Self::Zstd => {
                let mut rest = src;
                while !rest.is_empty() {
                    if let Some(skip) = skippable_frame_len(rest)? {
                        rest = &rest[skip..];
                        continue;
                    }
                    let decoder = ruzstd::decoding::StreamingDecoder::new(&mut rest)
                        .map_err(|e| e.to_string())?;
                    let room = cap.saturating_sub(out.len() as u64);
                    decoder
                        .take(room)
                        .read_to_end(&mut out)
                        .map_err(|e| e.to_string())?;
                    if out.len() > limit {
                        break;
                    }
                }
            }
            Self::Lz4 => {
                lz4_flex::frame::FrameDecoder::new(src)
                    .take(cap)
                    .read_to_end(&mut out)
                    .map_err(|e| e.to_string())?;
            }
        }
        if out.len() > limit {
            return Err(format!("the chunk inflates past {limit} bytes"));
        }
        Ok(out)
    }
}

/// A zstd skippable frame at the start of `src` (magic 0x184D2A50–5F, then a 32-bit length):
/// its whole length, or `None` for an ordinary frame.
fn skippable_frame_len(src: &[u8]) -> Result<Option<usize>, String> {
    let Some(magic) = src.get(..4) else {
        return Ok(None);
    };
    let magic = u32::from_le_bytes([magic[0], magic[1], magic[2], magic[3]]);
    if magic & 0xFFFF_FFF0 != 0x184D_2A50 {
        return Ok(None);
    }
    let len = src
        .get(4..8)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        .ok_or("a skippable frame cut short")?;
    let whole = len.checked_add(8).filter(|w| *w <= src.len());
    whole
        .map(Some)
        .ok_or_else(|| "a skippable frame longer than its chunk".to_owned())
}

/// One compression's decoder as `mcap`'s reader drives it (see the module docs).
#[derive(Debug)]
pub struct ChunkDecoder {
    compression: Compression,
    limit: usize,
    out: Vec<u8>,
    at: usize,
    decoded: bool,
}

impl ChunkDecoder {
    /// A decoder for `compression` whose chunks may inflate to at most `limit` bytes.
    #[must_use]
    pub fn new(compression: Compression, limit: usize) -> Self {
        Self {
            compression,
            limit,
            out: Vec::new(),
            at: 0,
            decoded: false,
        }
    }
}

impl Decompressor for ChunkDecoder {
    fn next_read_size(&self) -> usize {
        if self.decoded { 0 } else { usize::MAX }
    }

    fn decompress(&mut self, src: &[u8], dst: &mut [u8]) -> mcap::McapResult<DecompressResult> {
        let mut consumed = 0;
        if !self.decoded {
            self.out = self
                .compression
                .decode(src, self.limit)
                .map_err(|e| McapError::DecompressionError(format!("{}: {e}", self.name())))?;
            self.decoded = true;
            consumed = src.len();
        }
        let n = dst.len().min(self.out.len() - self.at);
        dst[..n].copy_from_slice(&self.out[self.at..self.at + n]);
        self.at += n;
        Ok(DecompressResult { consumed, wrote: n })
    }

    fn reset(&mut self) -> mcap::McapResult<()> {
        self.out = Vec::new();
        self.at = 0;
        self.decoded = false;
        Ok(())
    }

    fn name(&self) -> &'static str {
        self.compression.name()
    }
}

/// `reader` with both decoders registered, each chunk bounded by `limit` bytes.
pub(crate) fn register(
    reader: &mut mcap::sans_io::LinearReader,
    limit: usize,
) -> mcap::McapResult<()> {
    for c in [Compression::Zstd, Compression::Lz4] {
        reader.add_decompressor(ChunkDecoder::new(c, limit))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// `hello qrm` as one zstd frame (one raw block), as `printf 'hello qrm' | zstd -c
    /// --no-check` writes it.
    const ZSTD_HELLO: [u8; 18] = [
        0x28, 0xb5, 0x2f, 0xfd, 0x00, 0x58, 0x49, 0x00, 0x00, 0x68, 0x65, 0x6c, 0x6c, 0x6f, 0x20,
        0x71, 0x72, 0x6d,
    ];

    #[test]
    fn zstd_frames_skippable_frames_and_lz4_frames_decode() {
        let one = Compression::Zstd.decode(&ZSTD_HELLO, 100);
        assert_eq!(one.as_deref(), Ok(&b"hello qrm"[..]), "{one:?}");
        // a skippable frame between two frames is skipped
        let mut two = ZSTD_HELLO.to_vec();
        two.extend([0x50, 0x2a, 0x4d, 0x18, 2, 0, 0, 0, 0xaa, 0xbb]);
        two.extend(ZSTD_HELLO);
        assert_eq!(
            Compression::Zstd.decode(&two, 100).unwrap(),
            b"hello qrmhello qrm"
        );
        let mut lz4 = Vec::new();
        {
            use std::io::Write;
            let mut w = lz4_flex::frame::FrameEncoder::new(&mut lz4);
            w.write_all(&b"scan ".repeat(1000)).unwrap();
            w.finish().unwrap();
        }
        assert_eq!(
            Compression::Lz4.decode(&lz4, 1 << 20).unwrap(),
            b"scan ".repeat(1000)
        );
    }

    #[test]
    fn damage_and_inflation_past_the_limit_are_errors() {
        assert!(Compression::Zstd.decode(&ZSTD_HELLO[..12], 100).is_err());
        assert!(Compression::Zstd.decode(&ZSTD_HELLO, 5).is_err());
        assert!(
            Compression::Zstd
                .decode(b"not a frame at all", 100)
                .is_err()
        );
        assert!(Compression::Lz4.decode(b"not a frame at all", 100).is_err());
        // a skippable frame claiming more bytes than there are
        assert!(
            Compression::Zstd
                .decode(&[0x5f, 0x2a, 0x4d, 0x18, 0xff, 0, 0, 0, 1], 100)
                .is_err()
        );
    }

    #[test]
    fn the_reader_gets_the_output_in_the_pieces_it_asks_for() {
        let mut d = ChunkDecoder::new(Compression::Zstd, 100);
        assert_eq!(d.next_read_size(), usize::MAX);
        let mut dst = [0u8; 4];
        let r = d.decompress(&ZSTD_HELLO, &mut dst).unwrap();
        assert_eq!((r.consumed, r.wrote), (ZSTD_HELLO.len(), 4));
        assert_eq!(&dst, b"hell");
        assert_eq!(d.next_read_size(), 0);
        let mut rest = [0u8; 10];
        let r = d.decompress(&[], &mut rest).unwrap();
        assert_eq!((r.consumed, r.wrote), (0, 5));
        assert_eq!(&rest[..5], b"o qrm");
        d.reset().unwrap();
        assert_eq!(d.next_read_size(), usize::MAX);
    }
}
