//! Parsing the MOTION number block of a BVH file: one frame per line, `channels` numbers a line.
//!
//! This is most of a BVH file's bytes, so it is the one part of reading done in Rust. Each
//! parsed frame goes straight to a [`FrameSink`] (e.g. decoding into rotations), so no array of
//! raw channel values is ever built. Large blocks are split at line boundaries and parsed on
//! several threads, each writing its own frames of the output.

use rayon::prelude::*;

use crate::error::{product, zeros, KernelError, Result};

/// Blocks larger than this are split into chunks parsed in parallel.
const PARALLEL_BLOCK_BYTES: usize = 1 << 20;

/// Where parsed frames go: each frame's `channels` values become `widths().0` numbers of the
/// first output and `widths().1` of the second.
pub trait FrameSink: Sync {
    fn widths(&self) -> (usize, usize);
    fn emit(&self, values: &[f64], first: &mut [f64], second: &mut [f64]);
}

/// Keeps the values as they are: one output of `channels` numbers a frame.
struct Values(usize);

impl FrameSink for Values {
    fn widths(&self) -> (usize, usize) {
        (self.0, 0)
    }

    fn emit(&self, values: &[f64], first: &mut [f64], _: &mut [f64]) {
        first.copy_from_slice(values);
    }
}

/// Keeps nothing: the block is only checked.
struct Nothing;

impl FrameSink for Nothing {
    fn widths(&self) -> (usize, usize) {
        (0, 0)
    }

    fn emit(&self, _: &[f64], _: &mut [f64], _: &mut [f64]) {}
}

/// Check that `block` holds `frames` lines of `channels` finite numbers, as
/// [`parse_motion_block`] reads them, without keeping any value: a summary of a file
/// (`expressive-mocap info`) refuses what a read refuses, with no array to allocate.
///
/// # Errors
/// As [`parse_frames`].
pub fn check_motion_block(block: &[u8], frames: usize, channels: usize) -> Result<()> {
    parse_frames(block, frames, channels, &Nothing).map(|_| ())
}

/// Parse `frames` lines of `channels` finite numbers each from `block`.
///
/// Blank lines (whitespace only) are skipped, so trailing newlines and CRLF endings are fine.
/// Lines end at LF only: a lone CR is a blank (the header refuses CR-only files). Numbers are
/// fast-float2's whole tokens, the grammar of `expressive_mocap/tokens.py`.
/// Returns the values frame-major, `frames * channels` long.
///
/// # Errors
/// As [`parse_frames`].
pub fn parse_motion_block(block: &[u8], frames: usize, channels: usize) -> Result<Vec<f64>> {
    Ok(parse_frames(block, frames, channels, &Values(channels))?.0)
}

/// Parse `frames` frame lines of `channels` numbers and pass each frame to `sink`, which fills
/// `frames x widths` of the two returned outputs.
///
/// # Errors
/// `KernelError::Parse` naming the 0-based line within `block` of the first problem: a token
/// that is not a number, a NaN or infinite number, a line with the wrong number of values, a
/// frame line beyond `frames`, or (at the last line) fewer than `frames` frame lines.
pub fn parse_frames<S: FrameSink>(
    block: &[u8],
    frames: usize,
    channels: usize,
    sink: &S,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let (w0, w1) = sink.widths();
    if channels == 0 {
        // A skeleton without channels has blank frame lines; every frame decodes the same.
        if let Some(line) = lines(block).position(|l| !is_blank(l)) {
            return Err(KernelError::Parse {
                line,
                message: "expected 0 values (the hierarchy has no CHANNELS)".into(),
            });
        }
        // Still one (blank) line a frame: Frames cannot claim more than the block has.
        let found = lines(block).count();
        if frames > found {
            return Err(truncated(block, frames, found));
        }
        let (mut first, mut second) = outputs(frames, w0, w1)?;
        for f in 0..frames {
            sink.emit(
                &[],
                &mut first[f * w0..(f + 1) * w0],
                &mut second[f * w1..(f + 1) * w1],
            );
        }
        return Ok((first, second));
    }
    if block.len() > PARALLEL_BLOCK_BYTES {
        return parse_in_parallel(block, frames, channels, sink);
    }
    // A frame line takes at least 2 bytes a value ("0 0 ... 0\n"): never allocate more
    // frames than the block can hold, whatever Frames claims. One more than the block's whole
    // frames, so that a bad line after them is still reached and named, as the NumPy twin does.
    let room = frames.min(block.len() / channels.saturating_mul(2) + 1);
    let (mut first, mut second) = outputs(room, w0, w1)?;
    let end = parse_chunk(block, channels, room, sink, &mut first, &mut second)
        .map_err(|(line, message)| KernelError::Parse { line, message })?;
    if end.frames < frames {
        return Err(truncated(block, frames, end.frames));
    }
    if lines(&block[end.offset..]).any(|l| !is_blank(l)) {
        return Err(too_many_frames(block, frames));
    }
    Ok((first, second))
}

/// A large block: count frame lines per chunk first, so each chunk knows which frames of the
/// outputs are its own, then parse the chunks on all threads.
fn parse_in_parallel<S: FrameSink>(
    block: &[u8],
    frames: usize,
    channels: usize,
    sink: &S,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let (w0, w1) = sink.widths();
    let chunks = split_at_lines(block, rayon::current_num_threads() * 4);
    let counts: Vec<(usize, usize)> = chunks.par_iter().map(|c| count_lines(c)).collect();
    let total: usize = counts.iter().map(|&(frame_lines, _)| frame_lines).sum();
    let usable = total.min(frames);

    let (mut first, mut second) = outputs(usable, w0, w1)?;
    let mut jobs = Vec::with_capacity(chunks.len());
    let (mut rest0, mut rest1) = (first.as_mut_slice(), second.as_mut_slice());
    let (mut frames_before, mut lines_before) = (0, 0);
    for (chunk, &(frame_lines, newlines)) in chunks.iter().zip(&counts) {
        let take = frame_lines.min(usable - frames_before);
        let (out0, tail0) = rest0.split_at_mut(take * w0);
        let (out1, tail1) = rest1.split_at_mut(take * w1);
        (rest0, rest1) = (tail0, tail1);
        jobs.push((*chunk, lines_before, take, out0, out1));
        frames_before += take;
        lines_before += newlines;
    }
    let results: Vec<Result<ChunkEnd>> = jobs
        .into_par_iter()
        .map(|(chunk, first_line, take, out0, out1)| {
            parse_chunk(chunk, channels, take, sink, out0, out1).map_err(|(line, message)| {
                KernelError::Parse {
                    line: first_line + line,
                    message,
                }
            })
        })
        .collect();
    // The first problem in line order wins: chunks are in line order.
    results.into_iter().collect::<Result<Vec<ChunkEnd>>>()?;
    if total > frames {
        return Err(too_many_frames(block, frames));
    }
    if total < frames {
        return Err(truncated(block, frames, total));
    }
    Ok((first, second))
}

/// The two zeroed outputs of `frames` frames of `w0` and `w1` numbers.
fn outputs(frames: usize, w0: usize, w1: usize) -> Result<(Vec<f64>, Vec<f64>)> {
    Ok((
        zeros("frames", product("frames", frames, w0)?)?,
        zeros("frames", product("frames", frames, w1)?)?,
    ))
}

/// Split into about `parts` pieces, each ending just after a newline (the last at the end).
fn split_at_lines(block: &[u8], parts: usize) -> Vec<&[u8]> {
    let target = block.len() / parts.max(1) + 1;
    let mut pieces = Vec::with_capacity(parts);
    let mut rest = block;
    while rest.len() > target {
        match memchr::memchr(b'\n', &rest[target..]) {
            Some(nl) => {
                let (head, tail) = rest.split_at(target + nl + 1);
                pieces.push(head);
                rest = tail;
            }
            None => break,
        }
    }
    pieces.push(rest);
    pieces
}

/// The lines of `bytes`, split at '\n' (SIMD search: this runs over whole blocks).
fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut start = 0;
    memchr::memchr_iter(b'\n', bytes)
        .chain(std::iter::once(bytes.len()))
        .map(move |end| {
            let line = &bytes[start..end];
            start = end + 1;
            line
        })
}

/// Frame lines (not blank) and newlines in a chunk.
fn count_lines(chunk: &[u8]) -> (usize, usize) {
    let frame_lines = lines(chunk).filter(|l| !is_blank(l)).count();
    (frame_lines, memchr::memchr_iter(b'\n', chunk).count())
}

/// Error: fewer frame lines than `Frames` says. Points at the block's last line.
fn truncated(block: &[u8], frames: usize, found: usize) -> KernelError {
    let newlines = memchr::memchr_iter(b'\n', block).count();
    let last_line = newlines + usize::from(!block.is_empty() && !block.ends_with(b"\n"));
    KernelError::Parse {
        line: last_line.saturating_sub(1),
        message: format!(
            "truncated MOTION block: Frames says {frames}, but only {found} frame lines follow"
        ),
    }
}

/// Error: more frame lines than `Frames` says. Points at frame `frames + 1`.
fn too_many_frames(block: &[u8], frames: usize) -> KernelError {
    let line = lines(block)
        .enumerate()
        .filter(|(_, l)| !is_blank(l))
        .nth(frames)
        .map_or(0, |(i, _)| i);
    KernelError::Parse {
        line,
        message: format!("more frame lines than Frames says ({frames})"),
    }
}

fn is_blank(line: &[u8]) -> bool {
    line.iter().all(u8::is_ascii_whitespace)
}

/// Where a chunk's parse stopped: frames parsed, and the byte just after the last one's line.
struct ChunkEnd {
    frames: usize,
    offset: usize,
}

/// Parse up to `take` frame lines of a chunk into the sink, in one pass over its bytes.
/// Errors carry the line index within the chunk.
fn parse_chunk<S: FrameSink>(
    chunk: &[u8],
    channels: usize,
    take: usize,
    sink: &S,
    out0: &mut [f64],
    out1: &mut [f64],
) -> std::result::Result<ChunkEnd, (usize, String)> {
    let (w0, w1) = sink.widths();
    // A line cannot hold more values than half its bytes (a caller may pass any `channels`).
    let mut values = Vec::with_capacity(channels.min(chunk.len() / 2 + 1));
    let (mut i, mut line, mut frame) = (0, 0, 0);
    while frame < take && i < chunk.len() {
        values.clear();
        // One line: numbers separated by blanks, up to '\n' or the end.
        loop {
            while i < chunk.len() && chunk[i] != b'\n' && chunk[i].is_ascii_whitespace() {
                i += 1;
            }
            if i == chunk.len() || chunk[i] == b'\n' {
                i += 1;
                break;
            }
            let rest = &chunk[i..];
            if let Some((v, used)) = parse_plain(rest) {
                values.push(v);
                i += used;
                continue;
            }
            // The number must be the whole token: what follows it is whitespace or the end.
            match fast_float2::parse_partial::<f64, _>(rest) {
                Ok((v, used)) if rest.get(used).is_none_or(u8::is_ascii_whitespace) => {
                    if !v.is_finite() {
                        return Err((
                            line,
                            format!(
                                "{} is not a finite number (NaN and infinity are not allowed)",
                                show(token_at(rest))
                            ),
                        ));
                    }
                    values.push(v);
                    i += used;
                }
                _ => return Err((line, format!("{} is not a number", show(token_at(rest))))),
            }
        }
        if !values.is_empty() {
            if values.len() != channels {
                return Err((
                    line,
                    format!(
                        "expected {channels} values (the CHANNELS of the hierarchy), found {}",
                        values.len()
                    ),
                ));
            }
            sink.emit(
                &values,
                &mut out0[frame * w0..(frame + 1) * w0],
                &mut out1[frame * w1..(frame + 1) * w1],
            );
            frame += 1;
        }
        line += 1;
    }
    Ok(ChunkEnd {
        frames: frame,
        offset: i.min(chunk.len()),
    })
}

/// Exact powers of ten as f64: 10^k is exactly representable for k <= 22.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The common token of a MOTION block, `[+-]?digits[.digits]` then whitespace or the end, when
/// its digits (at most 19) make a mantissa `m <= 2^53`: `(value, bytes used)`, else `None`.
///
/// Such a value is `m / 10^k` with both exactly representable, so one IEEE division rounds it
/// correctly (Clinger's fast path). It is the very computation of fast-float2's own fast path,
/// sign applied after, so the bits match (`-0.000000` is -0.0) while skipping its general
/// grammar. Anything else (exponents, `.5`, `5.`, longer mantissas, inf/nan, odd bytes)
/// returns `None` and goes to fast-float2, errors and all.
#[inline]
fn parse_plain(token: &[u8]) -> Option<(f64, usize)> {
    let negative = token.first() == Some(&b'-');
    let mut i = usize::from(matches!(token.first(), Some(b'-' | b'+')));
    let mut m = 0_u64;
    let whole = digits(token, &mut i, &mut m);
    let fraction = if token.get(i) == Some(&b'.') {
        i += 1;
        match digits(token, &mut i, &mut m) {
            0 => return None,
            n => n,
        }
    } else {
        0
    };
    let end_ok = token.get(i).is_none_or(u8::is_ascii_whitespace);
    if whole == 0 || whole + fraction > 19 || m > 1 << 53 || !end_ok {
        return None;
    }
    let value = m as f64 / POW10[fraction];
    // The sign as a bit, not a branch (signs are random, measured 1.2x); value >= 0, so this
    // is -value for a '-', -0.0 included.
    Some((
        f64::from_bits(value.to_bits() | u64::from(negative) << 63),
        i,
    ))
}

/// Appends the ASCII digits at `token[*i..]` to the decimal mantissa `m` and steps past them;
/// returns how many there were. `m` wraps past 19 digits (the caller then refuses the token).
/// A byte at a time: 8 at a time (SWAR) measured no faster on these short runs of digits.
#[inline]
fn digits(token: &[u8], i: &mut usize, m: &mut u64) -> usize {
    let start = *i;
    while let Some(d) = token
        .get(*i)
        .map(|b| b.wrapping_sub(b'0'))
        .filter(|&d| d < 10)
    {
        *m = m.wrapping_mul(10).wrapping_add(u64::from(d));
        *i += 1;
    }
    *i - start
}

fn token_at(rest: &[u8]) -> &[u8] {
    &rest[..rest
        .iter()
        .position(u8::is_ascii_whitespace)
        .unwrap_or(rest.len())]
}

/// Bytes of a token shown in an error message: a 1 MB token must not make a 1 MB message.
const SHOWN_BYTES: usize = 40;

/// `token` quoted for an error message, exactly as the twin's `expressive_mocap.tokens.shown`
/// (the two backends' messages are compared): its first 40 bytes (undecodable bytes as U+FFFD),
/// control characters and line separators escaped so the message stays one line, then
/// `... (N bytes)` when it was cut.
fn show(token: &[u8]) -> String {
    use std::fmt::Write;
    let mut text = String::from("'");
    for c in String::from_utf8_lossy(&token[..token.len().min(SHOWN_BYTES)]).chars() {
        // Writing into a String cannot fail.
        let _ = match u32::from(c) {
            code @ (0..=0x1f | 0x7f..=0x9f) => write!(text, "\\x{code:02x}"),
            code @ (0x2028 | 0x2029) => write!(text, "\\u{code:04x}"),
            _ => write!(text, "{c}"),
        };
    }
    text.push('\'');
    if token.len() > SHOWN_BYTES {
        let _ = write!(text, "... ({} bytes)", token.len());
    }
    text
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // parsed values are exact
mod tests {
    use std::fmt::Write;

    use super::*;

    #[test]
    fn parses_crlf_tabs_exponents_and_trailing_blank_lines() {
        let v = parse_motion_block(b"1 2.5e1\t-3\r\n+4 .5 6E-1\r\n\r\n", 2, 3).unwrap();
        assert_eq!(v, vec![1.0, 25.0, -3.0, 4.0, 0.5, 0.6]);
    }

    #[test]
    fn check_refuses_exactly_what_parse_refuses() {
        let mut big = String::new();
        for f in 0..100_000 {
            let _ = writeln!(big, "{f} 1.5 -2");
        }
        let blocks: [(&[u8], usize, usize); 7] = [
            (b"1 2\n3 4\n", 2, 2),
            (b"1 2\n3 x\n", 2, 2),
            (b"1 2\n", 2, 2),
            (b"1 2\n3 4\n5 6\n", 2, 2),
            (b"1 nan\n", 1, 2),
            (b"\n\n", 2, 0),
            (big.as_bytes(), 100_000, 3),
        ];
        for (block, frames, channels) in blocks {
            let parsed = parse_motion_block(block, frames, channels).map(|_| ());
            let checked = check_motion_block(block, frames, channels);
            assert_eq!(format!("{parsed:?}"), format!("{checked:?}"));
        }
        assert!(
            big.len() > PARALLEL_BLOCK_BYTES,
            "the parallel path is checked too"
        );
        let mut bad = big.clone();
        bad.push_str("1 2 x\n");
        let e = check_motion_block(bad.as_bytes(), 100_001, 3).unwrap_err();
        assert!(
            matches!(e, KernelError::Parse { line: 100_000, .. }),
            "{e:?}"
        );
    }

    #[test]
    fn names_the_line_of_a_bad_token() {
        let e = parse_motion_block(b"1 2\n3 x\n", 2, 2).unwrap_err();
        assert!(matches!(e, KernelError::Parse { line: 1, .. }), "{e:?}");
        let e = parse_motion_block(b"1 2\n3 4x\n", 2, 2).unwrap_err();
        assert!(matches!(e, KernelError::Parse { line: 1, .. }), "{e:?}");
    }

    #[test]
    fn rejects_nan_wrong_counts_and_truncation() {
        assert!(matches!(
            parse_motion_block(b"1 nan\n", 1, 2),
            Err(KernelError::Parse { line: 0, .. })
        ));
        assert!(matches!(
            parse_motion_block(b"1 2\n3\n", 2, 2),
            Err(KernelError::Parse { line: 1, .. })
        ));
        assert!(matches!(
            parse_motion_block(b"1 2\n", 2, 2),
            Err(KernelError::Parse { line: 0, .. })
        ));
        assert!(matches!(
            parse_motion_block(b"1 2\n3 4\n", 1, 2),
            Err(KernelError::Parse { line: 1, .. })
        ));
    }

    #[test]
    fn no_channels_means_blank_frame_lines() {
        assert_eq!(
            parse_motion_block(b"\n\n", 2, 0).unwrap(),
            Vec::<f64>::new()
        );
        assert!(matches!(
            parse_motion_block(b"\n1\n", 2, 0),
            Err(KernelError::Parse { line: 1, .. })
        ));
    }

    #[test]
    fn parallel_chunks_agree_with_serial_and_count_lines_across_chunks() {
        let mut text = String::new();
        for f in 0..60_000 {
            let _ = writeln!(text, "{f} {}.25 -1e-3", f * 2);
            if f % 1000 == 0 {
                text.push('\n'); // blank lines shift frame and line numbers apart
            }
        }
        assert!(text.len() > PARALLEL_BLOCK_BYTES);
        let v = parse_motion_block(text.as_bytes(), 60_000, 3).unwrap();
        assert_eq!(v.len(), 180_000);
        assert_eq!(v[3 * 59_999], 59_999.0);
        let lines = text.lines().count();
        text.push_str("1 2 oops\n");
        let e = parse_motion_block(text.as_bytes(), 60_001, 3).unwrap_err();
        assert_eq!(
            e,
            KernelError::Parse {
                line: lines,
                message: "'oops' is not a number".into()
            }
        );
        let e = parse_motion_block(text.as_bytes(), 59_000, 3).unwrap_err();
        assert!(
            matches!(e, KernelError::Parse { line, .. } if line == 59_000 + 59),
            "{e:?}"
        );
    }

    #[test]
    fn a_long_or_odd_token_is_shown_cut_and_on_one_line() {
        let mut block = b"1 ".to_vec();
        block.resize(2 + (1 << 20), b'7');
        block.extend_from_slice(b"x\n");
        let e = parse_motion_block(&block, 1, 2).unwrap_err();
        let expected = format!("'{}'... (1048577 bytes) is not a number", "7".repeat(40));
        assert_eq!(
            e,
            KernelError::Parse {
                line: 0,
                message: expected
            }
        );
        assert_eq!(
            show(b"a\x0bb\x1b\xc2\x85\xe2\x80\xa8\xff"),
            "'a\\x0bb\\x1b\\x85\\u2028\u{fffd}'"
        );
    }

    #[test]
    fn absurd_counts_are_refused_without_allocating() {
        // Found by `cargo fuzz` (motion_block): Vec::with_capacity(channels) panicked.
        assert!(parse_motion_block(b"1 2\n", 1, usize::MAX).is_err());
        assert!(parse_motion_block(b"", 0, usize::MAX / 2 + 1)
            .unwrap()
            .is_empty());
        // No channels: one blank line a frame, so Frames cannot claim more lines than there are.
        let e = parse_motion_block(b"\n\n", usize::MAX, 0).unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
        assert_eq!(
            parse_motion_block(b"\n\n", 3, 0).unwrap(),
            Vec::<f64>::new()
        );
    }

    /// A deterministic stream of number-like tokens: signs, 0-9 whole digits with leading
    /// zeros, 0-17 fraction digits, mantissas near 2^53, and shapes fast-float2 must handle.
    fn tokens(count: usize) -> Vec<String> {
        const ODD: [&str; 33] = [
            "-0.000000",
            "-0",
            "+0.0",
            "1e5",
            "-2.5E-3",
            ".5",
            "-.5",
            "5.",
            "+5.",
            "1.2.3",
            "+-1",
            "-+1",
            "--1",
            "-",
            "+",
            ".",
            "nan",
            "-inf",
            "inf",
            "Infinity",
            "0x10",
            "1_0",
            "1,5",
            "30",
            "1.5x",
            "12345678x",
            "9007199254740992",
            "9007199254740993",
            "-9007199254740993.0",
            "0000000000000000001",
            "00000000000000000001",
            "900719925474099.3",
            "123456789012345678901234567890",
        ];
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 33) % n
        };
        (0..count)
            .map(|_| {
                if next(10) == 0 {
                    return ODD[next(ODD.len() as u64) as usize].to_string();
                }
                let mut t = ["", "-", "+", "-"][next(4) as usize].to_string();
                let digit = |d: u64| char::from(b'0' + d as u8);
                if next(4) == 0 {
                    // 15 to 20 digits: mantissas on both sides of 2^53 and of 19 digits.
                    let (len, dot) = (15 + next(6), next(21));
                    for k in 0..len {
                        if k == dot {
                            t.push('.');
                        }
                        t.push(digit(if k == 0 { 9 } else { next(10) }));
                    }
                    return t;
                }
                let whole = next(10);
                for k in 0..whole {
                    t.push(digit(if k == 0 && next(3) == 0 { 0 } else { next(10) }));
                }
                if next(5) != 0 {
                    t.push('.');
                    (0..next(18)).for_each(|_| t.push(digit(next(10))));
                }
                if t.is_empty() {
                    t.push('7'); // an empty token is no token
                }
                t
            })
            .collect()
    }

    /// What the block parser gave for a lone token before the plain fast path: fast-float2's
    /// whole token, finite.
    fn expected(token: &str) -> std::result::Result<f64, String> {
        match fast_float2::parse_partial::<f64, _>(token) {
            Ok((v, used)) if used == token.len() && v.is_finite() => Ok(v),
            Ok((_, used)) if used == token.len() => Err(format!(
                "'{token}' is not a finite number (NaN and infinity are not allowed)"
            )),
            _ => Err(format!("'{token}' is not a number")),
        }
    }

    #[test]
    fn the_plain_fast_path_gives_fast_float_bits_and_falls_back_on_anything_else() {
        let tokens = tokens(200_000);
        let mut plain = 0;
        for (k, token) in tokens.iter().enumerate() {
            // After the token: the end, or a byte that does or does not end it.
            let after = [
                &b""[..],
                b" ",
                b"\t1",
                b"\r\n",
                b"\x0c",
                b"\x0b",
                b"x",
                b".",
            ][k % 8];
            let bytes = [token.as_bytes(), after].concat();
            if let Some((v, used)) = parse_plain(&bytes) {
                plain += 1;
                let (w, len): (f64, usize) = fast_float2::parse_partial(&bytes).unwrap();
                assert_eq!(
                    (v.to_bits(), used),
                    (w.to_bits(), len),
                    "{token:?}{after:?}"
                );
                assert!(bytes.get(used).is_none_or(u8::is_ascii_whitespace));
            }
        }
        // Most tokens are plain: a fast path that never fires would pass the rest unseen.
        assert!(plain > tokens.len() / 4, "{plain}");
        assert_eq!(
            parse_plain(b"-0.000000").map(|(v, _)| v.to_bits()),
            Some((-0.0_f64).to_bits())
        );
        assert_eq!(parse_plain(b"92.855800\n"), Some((92.8558, 9)));
        for fallback in [
            "1e5",
            ".5",
            "5.",
            "1.2.3",
            "+-1",
            "nan",
            "inf",
            "9007199254740993",
        ] {
            assert_eq!(parse_plain(fallback.as_bytes()), None, "{fallback}");
        }
    }

    #[test]
    fn every_token_parses_or_fails_in_a_block_as_with_fast_float_alone() {
        for token in tokens(20_000) {
            // The token last in the block (no newline), in the middle, and before CRLF.
            for (block, value) in [(format!("1 {token}"), 1), (format!("{token} 2\r\n"), 0)] {
                let got = parse_motion_block(block.as_bytes(), 1, 2);
                match expected(&token) {
                    Ok(v) => assert_eq!(got.unwrap()[value].to_bits(), v.to_bits(), "{token}"),
                    Err(message) => {
                        assert_eq!(got.unwrap_err(), KernelError::Parse { line: 0, message });
                    }
                }
            }
        }
        // A large block of the good tokens, parsed in parallel chunks.
        let good: Vec<String> = tokens(300_000)
            .into_iter()
            .filter(|t| expected(t).is_ok())
            .take(6 * 30_000)
            .collect();
        let text: String = good.chunks(6).map(|line| line.join(" \t") + "\n").collect();
        assert!(text.len() > PARALLEL_BLOCK_BYTES);
        let got = parse_motion_block(text.as_bytes(), 30_000, 6).unwrap();
        let want: Vec<u64> = good
            .iter()
            .map(|t| expected(t).unwrap().to_bits())
            .collect();
        assert_eq!(got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
    }

    #[test]
    fn a_short_line_is_named_even_when_frames_claims_more_than_the_block_holds() {
        // Found by benches/fuzz_bvh.py --compare: a tighter allocation bound stopped before line 0.
        let e = parse_motion_block(b"1.5 91.0\n2", 4, 6).unwrap_err();
        assert!(
            matches!(e, KernelError::Parse { line: 0, ref message } if message.contains("expected 6 values")),
            "{e:?}"
        );
    }
}
