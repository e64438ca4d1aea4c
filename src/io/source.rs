//! Bounded, streaming input for the mesh parsers: opens a file (refusing
//! directories and devices), undoes gzip when the magic bytes say so, and hands
//! the parsers a byte stream with a hand-written tokenizer, fast number parsing
//! and a hard cap on the bytes read. Parsing straight from the stream means a
//! gzip bomb costs time bounded by the cap, never memory.

use super::{LoadLimits, ParseError, Place};
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Size of the read buffer: large enough that refills are rare, small enough to stay in L2.
const CHUNK: usize = 256 * 1024;

/// Longest token a text mesh may contain (a float with 17 significant digits
/// and an exponent needs about 25 bytes); longer runs are garbage, not numbers.
pub(crate) const MAX_TOKEN: usize = 64;

/// Longest PLY header line.
const MAX_HEADER_LINE: usize = 4096;

/// An opened mesh file, ready to stream.
pub(crate) struct Source {
    /// The (decompressed) bytes.
    pub stream: ByteStream,
    /// Size of the file on disk.
    pub file_len: u64,
    /// Whether the file was gzip-compressed (then `file_len` says nothing about the content size).
    pub compressed: bool,
}

/// Opens `path` for parsing: checks it is a regular file no larger than the
/// limit, and wraps a gzip decoder around it when the file starts with the gzip
/// magic bytes (RFC 1952: 0x1f 0x8b), whatever its extension.
pub(crate) fn open(path: &Path, limits: &LoadLimits) -> Result<Source, ParseError> {
    let meta = std::fs::metadata(path).map_err(|e| ParseError::new(None, e.to_string()))?;
    if meta.is_dir() {
        return Err(ParseError::new(None, "is a directory, not a mesh file".into()));
    }
    if !meta.is_file() {
        // Devices (/dev/zero), pipes and sockets have no size to bound the read by.
        return Err(ParseError::new(
            None,
            "is not a regular file (a device, pipe or socket); mesh files must be regular files".into(),
        ));
    }
    let file_len = meta.len();
    if file_len > limits.max_input_bytes {
        return Err(ParseError::new(
            None,
            format!(
                "file is {file_len} bytes, more than the {} byte limit for a mesh file",
                limits.max_input_bytes
            ),
        ));
    }
    let file = File::open(path).map_err(|e| ParseError::new(None, e.to_string()))?;
    let mut reader = BufReader::with_capacity(64 * 1024, file);
    let head = reader
        .fill_buf()
        .map_err(|e| ParseError::new(None, format!("cannot read: {e}")))?;
    let compressed = head.starts_with(&[0x1f, 0x8b]);
    let inner: Box<dyn Read> = if compressed {
        Box::new(Prefetch::spawn(flate2::bufread::MultiGzDecoder::new(reader)))
    } else {
        Box::new(reader)
    };
    Ok(Source {
        stream: ByteStream::new(inner, limits.max_input_bytes, compressed),
        file_len,
        compressed,
    })
}

/// A [`Source`] over bytes in memory ([`super::parse_mesh_bytes`]): gzip is
/// undone when the magic bytes say so, on this thread (no prefetch).
pub(crate) fn from_bytes(bytes: Vec<u8>, limits: &LoadLimits) -> Source {
    let file_len = bytes.len() as u64;
    let compressed = bytes.starts_with(&[0x1f, 0x8b]);
    let cursor = std::io::Cursor::new(bytes);
    let inner: Box<dyn Read> = if compressed {
        Box::new(flate2::bufread::MultiGzDecoder::new(cursor))
    } else {
        Box::new(cursor)
    };
    Source {
        stream: ByteStream::new(inner, limits.max_input_bytes, compressed),
        file_len,
        compressed,
    }
}

/// Runs a reader (the gzip decoder) on its own thread, a few chunks ahead of
/// the parser, so decompression and parsing overlap (on the full dragon they
/// take similar time). At most `DEPTH` chunks are in flight, so memory stays
/// bounded; when the parser stops early, the channel closes and the thread ends.
struct Prefetch {
    chunks: std::sync::mpsc::Receiver<std::io::Result<Vec<u8>>>,
    current: Vec<u8>,
    pos: usize,
    done: bool,
}

impl Prefetch {
    const DEPTH: usize = 4;

    fn spawn(mut inner: impl Read + Send + 'static) -> Self {
        let (send, chunks) = std::sync::mpsc::sync_channel(Self::DEPTH);
        std::thread::spawn(move || loop {
            let mut chunk = vec![0u8; CHUNK];
            let mut filled = 0;
            // Fill whole chunks: the decoder returns small pieces.
            let result = loop {
                match inner.read(&mut chunk[filled..]) {
                    Ok(0) => break Ok(()),
                    Ok(n) => {
                        filled += n;
                        if filled == CHUNK {
                            break Ok(());
                        }
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => break Err(e),
                }
            };
            chunk.truncate(filled);
            let end = filled == 0;
            let stop = match result {
                Ok(()) => send.send(Ok(chunk)).is_err() || end,
                Err(e) => {
                    if filled > 0 {
                        let _ = send.send(Ok(chunk));
                    }
                    let _ = send.send(Err(e));
                    true
                }
            };
            if stop {
                return;
            }
        });
        Self {
            chunks,
            current: Vec::new(),
            pos: 0,
            done: false,
        }
    }
}

impl Read for Prefetch {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while self.pos == self.current.len() {
            if self.done {
                return Ok(0);
            }
            match self.chunks.recv() {
                Ok(Ok(chunk)) if chunk.is_empty() => self.done = true,
                Ok(Ok(chunk)) => {
                    self.current = chunk;
                    self.pos = 0;
                }
                Ok(Err(e)) => {
                    self.done = true;
                    return Err(e);
                }
                Err(_) => self.done = true,
            }
        }
        let n = out.len().min(self.current.len() - self.pos);
        out[..n].copy_from_slice(&self.current[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// A byte stream with a text tokenizer (line counting, `#` comments) and
/// binary reads (byte offsets), reading at most `limit` bytes in all.
pub(crate) struct ByteStream {
    inner: Box<dyn Read>,
    buf: Box<[u8]>,
    pos: usize,
    end: usize,
    /// Stream offset of `buf[0]`.
    base: u64,
    limit: u64,
    eof: bool,
    compressed: bool,
    /// Current 1-based line (text formats).
    line: u64,
    /// Holds a token that straddles two buffer fills.
    scratch: Vec<u8>,
}

impl ByteStream {
    fn new(inner: Box<dyn Read>, limit: u64, compressed: bool) -> Self {
        Self {
            inner,
            buf: vec![0; CHUNK].into_boxed_slice(),
            pos: 0,
            end: 0,
            base: 0,
            limit,
            eof: false,
            compressed,
            line: 1,
            scratch: Vec::with_capacity(MAX_TOKEN),
        }
    }

    /// A stream over bytes in memory (tests, and the OBJ loader's pre-read).
    #[cfg(test)]
    pub(crate) fn from_bytes(bytes: Vec<u8>) -> Self {
        Self::new(Box::new(std::io::Cursor::new(bytes)), u64::MAX, false)
    }

    /// Current line (text formats).
    pub fn line(&self) -> u64 {
        self.line
    }

    /// Current byte offset in the (decompressed) stream.
    pub fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }

    /// The place to report for text formats.
    pub fn here(&self) -> Place {
        Place::Line(self.line)
    }

    /// Makes at least one byte available unless the stream is exhausted.
    /// Returns false at the end.
    #[inline]
    fn fill(&mut self) -> Result<bool, ParseError> {
        if self.pos < self.end {
            return Ok(true);
        }
        if self.eof {
            return Ok(false);
        }
        self.base += self.end as u64;
        self.pos = 0;
        self.end = 0;
        loop {
            match self.inner.read(&mut self.buf) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(false);
                }
                Ok(n) => {
                    self.end = n;
                    break;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    let what = if self.compressed {
                        "cannot decompress (corrupt or truncated gzip data)"
                    } else {
                        "cannot read"
                    };
                    return Err(ParseError::new(Some(Place::Byte(self.base)), format!("{what}: {e}")));
                }
            }
        }
        if self.base + self.end as u64 > self.limit {
            return Err(ParseError::new(
                Some(Place::Byte(self.limit)),
                format!(
                    "more than {} bytes{}: refusing to read further (limit for a mesh file)",
                    self.limit,
                    if self.compressed { " after decompression" } else { "" }
                ),
            ));
        }
        Ok(true)
    }

    // ---------------------------------------------------------------- text

    /// Reads one header line (PLY), without its terminator, with its line
    /// number. `None` at the end.
    pub fn header_line(&mut self) -> Result<Option<(u64, String)>, ParseError> {
        let number = self.line;
        let mut line = Vec::new();
        loop {
            if !self.fill()? {
                if line.is_empty() {
                    return Ok(None);
                }
                break;
            }
            let b = self.buf[self.pos];
            self.pos += 1;
            if b == b'\n' {
                self.line += 1;
                break;
            }
            line.push(b);
            if line.len() > MAX_HEADER_LINE {
                return Err(ParseError::new(
                    Some(Place::Line(number)),
                    format!("header line longer than {MAX_HEADER_LINE} bytes"),
                ));
            }
        }
        if line.last() == Some(&b'\r') {
            line.pop();
        }
        String::from_utf8(line)
            .map(|text| Some((number, text)))
            .map_err(|_| ParseError::new(Some(Place::Line(number)), "header line is not ASCII/UTF-8 text".into()))
    }

    /// Skips blanks, and line ends and `#` comments when `cross_lines`; stops
    /// before a line end otherwise. Returns the next byte without consuming it.
    #[inline]
    fn skip_blanks(&mut self, cross_lines: bool, comments: bool) -> Result<Option<u8>, ParseError> {
        loop {
            if !self.fill()? {
                return Ok(None);
            }
            let b = self.buf[self.pos];
            match b {
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'\n' if cross_lines => {
                    self.pos += 1;
                    self.line += 1;
                }
                b'#' if comments => self.skip_to_line_end()?,
                _ => return Ok(Some(b)),
            }
        }
    }

    /// Consumes everything up to (not including) the next `\n`.
    fn skip_to_line_end(&mut self) -> Result<(), ParseError> {
        loop {
            if !self.fill()? {
                return Ok(());
            }
            let rest = &self.buf[self.pos..self.end];
            match rest.iter().position(|&b| b == b'\n') {
                Some(i) => {
                    self.pos += i;
                    return Ok(());
                }
                None => self.pos = self.end,
            }
        }
    }

    /// Consumes the rest of the current line and its `\n`.
    pub fn next_line(&mut self) -> Result<(), ParseError> {
        self.skip_to_line_end()?;
        if self.fill()? {
            self.pos += 1;
            self.line += 1;
        }
        Ok(())
    }

    /// The next whitespace-separated token. With `cross_lines = false`, `None`
    /// means the current line has no more tokens (or the file ended); with
    /// `cross_lines = true`, `None` means the file ended. `comments` makes `#`
    /// start a comment that runs to the line end.
    pub fn token(&mut self, cross_lines: bool, comments: bool) -> Result<Option<&[u8]>, ParseError> {
        match self.skip_blanks(cross_lines, comments)? {
            None | Some(b'\n') => return Ok(None),
            Some(_) => {}
        }
        let start = self.pos;
        // Fast path: the token ends inside the buffer.
        let mut i = start;
        while i < self.end && !is_separator(self.buf[i], comments) {
            i += 1;
        }
        if i < self.end || self.eof {
            if i - start > MAX_TOKEN {
                return Err(self.too_long());
            }
            self.pos = i;
            return Ok(Some(&self.buf[start..i]));
        }
        // Slow path: the token straddles a refill.
        self.scratch.clear();
        self.scratch.extend_from_slice(&self.buf[start..self.end]);
        self.pos = self.end;
        loop {
            if self.scratch.len() > MAX_TOKEN {
                return Err(self.too_long());
            }
            if !self.fill()? {
                break;
            }
            let b = self.buf[self.pos];
            if is_separator(b, comments) {
                break;
            }
            self.scratch.push(b);
            self.pos += 1;
        }
        Ok(Some(&self.scratch))
    }

    fn too_long(&self) -> ParseError {
        ParseError::new(
            Some(self.here()),
            format!("a token longer than {MAX_TOKEN} bytes (binary data or garbage in a text file?)"),
        )
    }

    /// True when only blanks, line ends and (if `comments`) comments remain
    /// within the next `budget` bytes; used to detect data beyond the counts
    /// the header announced without reading a whole gzip bomb.
    pub fn rest_is_blank(&mut self, comments: bool, budget: u64) -> Result<bool, ParseError> {
        let stop = self.offset().saturating_add(budget);
        loop {
            if !self.fill()? {
                return Ok(true);
            }
            if self.offset() >= stop {
                return Ok(true);
            }
            match self.buf[self.pos] {
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                }
                b'#' if comments => {
                    self.skip_to_line_end()?;
                }
                _ => return Ok(false),
            }
        }
    }

    // -------------------------------------------------------------- binary

    /// Reads exactly `N` bytes; `Ok(None)` if the stream ends first.
    #[inline]
    pub fn read_array<const N: usize>(&mut self) -> Result<Option<[u8; N]>, ParseError> {
        let mut out = [0u8; N];
        if self.end - self.pos >= N {
            out.copy_from_slice(&self.buf[self.pos..self.pos + N]);
            self.pos += N;
            return Ok(Some(out));
        }
        for slot in out.iter_mut() {
            if !self.fill()? {
                return Ok(None);
            }
            *slot = self.buf[self.pos];
            self.pos += 1;
        }
        Ok(Some(out))
    }

    /// True if at least one more byte exists.
    pub fn has_more(&mut self) -> Result<bool, ParseError> {
        self.fill()
    }
}

/// Raw access for loaders that hand the text to another parser (OBJ); the
/// byte limit still applies.
impl Read for ByteStream {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if !self.fill().map_err(|e| std::io::Error::other(e.to_string()))? {
            return Ok(0);
        }
        let n = out.len().min(self.end - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

#[inline]
fn is_separator(b: u8, comments: bool) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c) || (comments && b == b'#')
}

/// Exact powers of ten in f32 (10^k is exact in f32 for k ≤ 10: 5^10 < 2^24).
const POW10_F32: [f32; 11] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];

/// Parses a decimal float. Fast path after Clinger (1990), "How to read
/// floating point numbers accurately": when the decimal significand fits in
/// f32's 24-bit mantissa and the power of ten is exact in f32, one correctly
/// rounded multiply or divide gives the correctly rounded result. Everything
/// else (long significands, big exponents, `nan`, `inf`) goes to the standard
/// library's correctly rounded parser.
#[inline]
pub(crate) fn parse_f32(s: &[u8]) -> Option<f32> {
    let (negative, body) = match s.first()? {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    let mut mantissa: u64 = 0;
    let mut exp10: i64 = 0;
    let mut digits = 0usize;
    let mut i = 0;
    while i < body.len() && body[i].is_ascii_digit() {
        mantissa = mantissa.wrapping_mul(10) + u64::from(body[i] - b'0');
        digits += 1;
        i += 1;
    }
    if i < body.len() && body[i] == b'.' {
        i += 1;
        while i < body.len() && body[i].is_ascii_digit() {
            mantissa = mantissa.wrapping_mul(10) + u64::from(body[i] - b'0');
            digits += 1;
            exp10 -= 1;
            i += 1;
        }
    }
    if digits == 0 {
        return parse_f32_slow(s);
    }
    if i < body.len() && (body[i] == b'e' || body[i] == b'E') {
        i += 1;
        let (exp_negative, start) = match body.get(i) {
            Some(b'-') => (true, i + 1),
            Some(b'+') => (false, i + 1),
            _ => (false, i),
        };
        let mut e: i64 = 0;
        i = start;
        while i < body.len() && body[i].is_ascii_digit() && e < 100_000 {
            e = e * 10 + i64::from(body[i] - b'0');
            i += 1;
        }
        if i == start {
            return None;
        }
        exp10 += if exp_negative { -e } else { e };
    }
    if i != body.len() || digits > 19 {
        return parse_f32_slow(s);
    }
    if mantissa <= 1 << 24 && (-10..=10).contains(&exp10) {
        let m = mantissa as f32;
        let v = if exp10 < 0 {
            m / POW10_F32[(-exp10) as usize]
        } else {
            m * POW10_F32[exp10 as usize]
        };
        return Some(if negative { -v } else { v });
    }
    parse_f32_slow(s)
}

#[cold]
fn parse_f32_slow(s: &[u8]) -> Option<f32> {
    std::str::from_utf8(s).ok()?.parse().ok()
}

/// Parses a decimal integer with an optional sign.
#[inline]
pub(crate) fn parse_i64(s: &[u8]) -> Option<i64> {
    let (negative, body) = match s.first()? {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    if body.is_empty() {
        return None;
    }
    let mut v: i64 = 0;
    for &b in body {
        if !b.is_ascii_digit() {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(i64::from(b - b'0'))?;
    }
    Some(if negative { -v } else { v })
}

/// Shows a token in an error message (lossy, shortened).
pub(crate) fn show(token: &[u8]) -> String {
    let s = String::from_utf8_lossy(&token[..token.len().min(32)]);
    if token.len() > 32 {
        format!("'{s}…'")
    } else {
        format!("'{s}'")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_float_matches_std() {
        let cases = [
            "0",
            "-0",
            "1",
            "0.032027",
            "-0.0503644",
            "123456.7",
            "1e5",
            "2.5E-3",
            "+7.25",
            "16777217",
            "0.1234567890123",
            "1e-40",
            "3.4028235e38",
            "1e39",
            "123456789012345678901",
            "5.",
            ".5",
            "-.25e+2",
        ];
        for c in cases {
            let want: f32 = c.parse().unwrap();
            let got = parse_f32(c.as_bytes()).unwrap();
            assert_eq!(got.to_bits(), want.to_bits(), "{c}");
        }
        assert!(parse_f32(b"nan").unwrap().is_nan());
        assert!(parse_f32(b"-inf").unwrap().is_infinite());
        for bad in ["", "-", ".", "1.2.3", "1e", "abc", "1x", "e5"] {
            assert_eq!(parse_f32(bad.as_bytes()), None, "{bad}");
        }
    }

    #[test]
    fn fast_float_random_agrees_with_std() {
        let mut state = 0x1234_5678_9abc_def0u64;
        for _ in 0..20_000 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let mantissa = (state >> 33) % 100_000_000;
            let exp = ((state >> 20) % 25) as i32 - 12;
            let s = format!("{mantissa}e{exp}");
            let want: f32 = s.parse().unwrap();
            assert_eq!(parse_f32(s.as_bytes()).unwrap().to_bits(), want.to_bits(), "{s}");
            let s = format!("-{}.{:07}", mantissa / 10_000_000, mantissa % 10_000_000);
            let want: f32 = s.parse().unwrap();
            assert_eq!(parse_f32(s.as_bytes()).unwrap().to_bits(), want.to_bits(), "{s}");
        }
    }

    #[test]
    fn integers() {
        assert_eq!(parse_i64(b"42"), Some(42));
        assert_eq!(parse_i64(b"-7"), Some(-7));
        assert_eq!(parse_i64(b"99999999999999999999"), None);
        assert_eq!(parse_i64(b"4.0"), None);
        assert_eq!(parse_i64(b"-"), None);
    }

    #[test]
    fn tokens_lines_and_comments() {
        let mut s = ByteStream::from_bytes(b"a b # c\n\n  d\te\n".to_vec());
        assert_eq!(s.token(false, true).unwrap(), Some(&b"a"[..]));
        assert_eq!(s.token(false, true).unwrap(), Some(&b"b"[..]));
        assert_eq!(s.token(false, true).unwrap(), None);
        assert_eq!(s.line(), 1);
        assert_eq!(s.token(true, true).unwrap(), Some(&b"d"[..]));
        assert_eq!(s.line(), 3);
        s.next_line().unwrap();
        assert_eq!(s.line(), 4);
        assert_eq!(s.token(true, true).unwrap(), None);
    }

    #[test]
    fn tokens_straddling_refills() {
        // Tokens of varying length across the 256 KiB buffer boundary.
        let mut text = String::new();
        let mut expected = Vec::new();
        let mut k = 0u64;
        while text.len() < 3 * CHUNK {
            let t = format!("{}", k * 7919 % 1_000_003);
            text.push_str(&t);
            text.push(if k.is_multiple_of(5) { '\n' } else { ' ' });
            expected.push(t);
            k += 1;
        }
        let mut s = ByteStream::from_bytes(text.into_bytes());
        for e in &expected {
            let t = s.token(true, false).unwrap().unwrap();
            assert_eq!(t, e.as_bytes());
        }
        assert_eq!(s.token(true, false).unwrap(), None);
    }

    #[test]
    fn binary_reads_across_refills() {
        let bytes: Vec<u8> = (0..(CHUNK + 10) as u32).map(|i| (i % 251) as u8).collect();
        let mut s = ByteStream::from_bytes(bytes.clone());
        let mut got = Vec::new();
        while let Some(b) = s.read_array::<3>().unwrap() {
            got.extend_from_slice(&b);
        }
        assert_eq!(got, bytes[..bytes.len() / 3 * 3]);
    }
}
