//! Parsing the MOTION number block of a BVH file: one frame per line, `channels` numbers a line.
//!
//! This is most of a BVH file's bytes, so it is the one part of reading done in Rust.
//! Large blocks are split at line boundaries and parsed on several threads.

use rayon::prelude::*;

use crate::error::{KernelError, Result};

/// Blocks larger than this are split into chunks parsed in parallel.
const PARALLEL_BLOCK_BYTES: usize = 1 << 20;

/// Parse `frames` lines of `channels` finite numbers each from `block`.
///
/// Blank lines (whitespace only) are skipped, so trailing newlines and CRLF endings are fine.
/// Returns the values frame-major, `frames * channels` long.
///
/// # Errors
/// `KernelError::Parse` naming the 0-based line within `block` when a token is not a number,
/// a number is NaN or infinite, a line has the wrong number of values, or the block holds
/// fewer or more than `frames` frames.
pub fn parse_motion_block(block: &[u8], frames: usize, channels: usize) -> Result<Vec<f64>> {
    if channels == 0 {
        // Frame lines of a skeleton without channels are blank.
        return match block.split(|&b| b == b'\n').position(|l| !is_blank(l)) {
            None => Ok(Vec::new()),
            Some(line) => Err(KernelError::Parse { line, message: "expected 0 values (the hierarchy has no CHANNELS)".into() }),
        };
    }
    let chunks = split_at_lines(block, if block.len() > PARALLEL_BLOCK_BYTES { rayon::current_num_threads() * 4 } else { 1 });
    let parsed: Vec<Result<Chunk>> = if chunks.len() > 1 {
        chunks.par_iter().map(|c| parse_chunk(c, channels)).collect()
    } else {
        chunks.iter().map(|c| parse_chunk(c, channels)).collect()
    };

    let mut values = Vec::with_capacity(frames.saturating_mul(channels).min(block.len() / 2 + channels));
    let mut lines_before = 0;
    let mut frames_found = 0;
    for (chunk, result) in chunks.iter().zip(parsed) {
        let chunk_result = result.map_err(|e| shift_line(e, lines_before))?;
        if frames_found + chunk_result.frames > frames {
            return Err(too_many_frames(block, frames));
        }
        frames_found += chunk_result.frames;
        values.extend_from_slice(&chunk_result.values);
        lines_before += count_lines(chunk);
    }
    if frames_found < frames {
        // Point at the last line of the block, where the missing frames should have been.
        let last_line = lines_before + usize::from(!block.is_empty() && !block.ends_with(b"\n"));
        return Err(KernelError::Parse {
            line: last_line.saturating_sub(1),
            message: format!("truncated MOTION block: Frames says {frames}, but only {frames_found} frame lines follow"),
        });
    }
    Ok(values)
}

struct Chunk {
    values: Vec<f64>,
    frames: usize,
}

/// Split into about `parts` pieces, each ending just after a newline (the last at the end).
fn split_at_lines(block: &[u8], parts: usize) -> Vec<&[u8]> {
    let target = block.len() / parts.max(1) + 1;
    let mut pieces = Vec::with_capacity(parts);
    let mut rest = block;
    while rest.len() > target {
        match rest[target..].iter().position(|&b| b == b'\n') {
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

fn count_lines(chunk: &[u8]) -> usize {
    chunk.iter().filter(|&&b| b == b'\n').count()
}

fn shift_line(error: KernelError, lines_before: usize) -> KernelError {
    match error {
        KernelError::Parse { line, message } => KernelError::Parse { line: line + lines_before, message },
        other => other,
    }
}

/// Error path only: find the line of frame `frames + 1`.
fn too_many_frames(block: &[u8], frames: usize) -> KernelError {
    let line = block
        .split(|&b| b == b'\n')
        .enumerate()
        .filter(|(_, l)| !is_blank(l))
        .nth(frames)
        .map_or(0, |(i, _)| i);
    KernelError::Parse { line, message: format!("more frame lines than Frames says ({frames})") }
}

fn is_blank(line: &[u8]) -> bool {
    line.iter().all(u8::is_ascii_whitespace)
}

fn parse_chunk(chunk: &[u8], channels: usize) -> Result<Chunk> {
    let mut values = Vec::with_capacity(chunk.len() / 6);
    let mut frames = 0;
    for (line_index, line) in chunk.split(|&b| b == b'\n').enumerate() {
        let before = values.len();
        parse_line(line, &mut values).map_err(|message| KernelError::Parse { line: line_index, message })?;
        let found = values.len() - before;
        if found == 0 {
            continue;
        }
        if found != channels {
            return Err(KernelError::Parse {
                line: line_index,
                message: format!("expected {channels} values (the CHANNELS of the hierarchy), found {found}"),
            });
        }
        frames += 1;
    }
    Ok(Chunk { values, frames })
}

/// Append every whitespace-separated number of `line` to `out`.
fn parse_line(line: &[u8], out: &mut Vec<f64>) -> std::result::Result<(), String> {
    let mut i = 0;
    loop {
        while i < line.len() && line[i].is_ascii_whitespace() {
            i += 1;
        }
        if i == line.len() {
            return Ok(());
        }
        let rest = &line[i..];
        // The number must be the whole token: what follows it is whitespace or the line's end.
        match fast_float2::parse_partial::<f64, _>(rest) {
            Ok((v, used)) if rest.get(used).is_none_or(u8::is_ascii_whitespace) => {
                if !v.is_finite() {
                    return Err(format!("{:?} is not a finite number (NaN and infinity are not allowed)", show(token_at(rest))));
                }
                out.push(v);
                i += used;
            }
            _ => return Err(format!("{:?} is not a number", show(token_at(rest)))),
        }
    }
}

fn token_at(rest: &[u8]) -> &[u8] {
    &rest[..rest.iter().position(u8::is_ascii_whitespace).unwrap_or(rest.len())]
}

fn show(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(&token[..token.len().min(40)]).into_owned();
    if token.len() > 40 { text + "…" } else { text }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_crlf_tabs_exponents_and_trailing_blank_lines() {
        let v = parse_motion_block(b"1 2.5e1\t-3\r\n+4 .5 6E-1\r\n\r\n", 2, 3).unwrap();
        assert_eq!(v, vec![1.0, 25.0, -3.0, 4.0, 0.5, 0.6]);
    }

    #[test]
    fn names_the_line_of_a_bad_token() {
        let e = parse_motion_block(b"1 2\n3 x\n", 2, 2).unwrap_err();
        assert!(matches!(e, KernelError::Parse { line: 1, .. }), "{e:?}");
    }

    #[test]
    fn rejects_nan_wrong_counts_and_truncation() {
        assert!(matches!(parse_motion_block(b"1 nan\n", 1, 2), Err(KernelError::Parse { line: 0, .. })));
        assert!(matches!(parse_motion_block(b"1 2\n3\n", 2, 2), Err(KernelError::Parse { line: 1, .. })));
        assert!(matches!(parse_motion_block(b"1 2\n", 2, 2), Err(KernelError::Parse { .. })));
        assert!(matches!(parse_motion_block(b"1 2\n3 4\n", 1, 2), Err(KernelError::Parse { line: 1, .. })));
    }

    #[test]
    fn parallel_chunks_agree_with_serial_and_count_lines_across_chunks() {
        let mut text = String::new();
        for f in 0..60_000 {
            text.push_str(&format!("{f} {}.25 -1e-3\n", f * 2));
        }
        assert!(text.len() > PARALLEL_BLOCK_BYTES);
        let v = parse_motion_block(text.as_bytes(), 60_000, 3).unwrap();
        assert_eq!(v.len(), 180_000);
        assert_eq!(v[3 * 59_999], 59_999.0);
        text.push_str("1 2 oops\n");
        let e = parse_motion_block(text.as_bytes(), 60_001, 3).unwrap_err();
        assert!(matches!(e, KernelError::Parse { line: 60_000, .. }), "{e:?}");
    }
}
