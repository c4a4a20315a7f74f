//! The headers of an archive's files that repeat one already read: the same bytes from the
//! file's start through its MOTION line, then `Frames: N` and `Frame Time: T` lines in their
//! plainest form. Such a file's header is that one's, with its own frame count, frame time and
//! block start; anything else about it (another hierarchy, a blank line, an exponent, a NUL
//! byte near the start) is left to the full reader in Python, whose errors name the line.
//!
//! Why: an archive's files mostly share one hierarchy, and reading every header in Python (a few
//! system calls and a parse a file, each call letting other threads take the GIL) cost a tenth
//! of preprocessing dataset-2.

use crate::clip::{read_beginning, ReadError};

/// What a file's header adds to the one it repeats.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    pub frames: usize,
    pub frame_time: f64,
    /// Where the number block starts: the byte after the `Frame Time` line.
    pub block_start: usize,
}

/// Bytes of a file's start searched for NUL by the Python reader (`header._check_text`), after a
/// byte-order mark.
const TEXT_CHECK_BYTES: usize = 4096;
/// The reader's bound on frames (`header.BLOCK_BYTES_PER_JOINT_FRAME`, `header.MIN_JOINT_FRAMES`).
const BLOCK_BYTES_PER_JOINT_FRAME: u64 = 3;
const MIN_JOINT_FRAMES: u64 = 1 << 16;
const MAX_FRAME_DIGITS: usize = 18;

/// `data`, the first bytes of a file of `size` bytes (all it holds when shorter than asked for,
/// `whole`), read as `template` (a header's bytes through its MOTION line, of a skeleton of
/// `joints` joints) followed by plain `Frames:` and `Frame Time:` lines: their values, or None
/// when the file is anything but that, or when the Python reader would read it otherwise
/// (from its whole text, or refusing it).
#[must_use]
pub fn repeated_header(
    data: &[u8],
    size: u64,
    whole: bool,
    template: &[u8],
    joints: usize,
) -> Option<Timing> {
    if whole || template.is_empty() || !data.starts_with(template) {
        return None;
    }
    let bom = if data.starts_with(b"\xef\xbb\xbf") {
        3
    } else {
        0
    };
    let checked = data.len().min(bom + TEXT_CHECK_BYTES);
    if template.len() < checked && data[template.len()..checked].contains(&0) {
        return None;
    }
    let (frames_text, next) = line_value(data, template.len(), b"Frames:")?;
    let (time_text, block_start) = line_value(data, next, b"Frame Time:")?;
    if frames_text.is_empty()
        || frames_text.len() > MAX_FRAME_DIGITS
        || !frames_text.iter().all(u8::is_ascii_digit)
    {
        return None;
    }
    let frames: u64 = std::str::from_utf8(frames_text).ok()?.parse().ok()?;
    if !plain_decimal(time_text) {
        return None;
    }
    let frame_time: f64 = fast_float2::parse(time_text).ok()?;
    if !(frame_time.is_finite() && frame_time > 0.0) || block_start >= data.len() {
        return None;
    }
    let block_bytes = size.checked_sub(block_start as u64)?;
    let bound = (block_bytes / BLOCK_BYTES_PER_JOINT_FRAME).max(MIN_JOINT_FRAMES);
    if frames.checked_mul(joints as u64)? > bound {
        return None;
    }
    Some(Timing {
        frames: usize::try_from(frames).ok()?,
        frame_time,
        block_start,
    })
}

/// The value of the line at `start`, `key`, blanks, one token, blanks, CRs, then `\n` (the
/// Python reader's pattern, `\S*` a token): the token and where the next line starts, or None.
fn line_value<'a>(data: &'a [u8], start: usize, key: &[u8]) -> Option<(&'a [u8], usize)> {
    let line = data.get(start..)?;
    let end = line.iter().position(|&b| b == b'\n')?;
    let rest = skip_blanks(line[..end].strip_prefix(key)?);
    let token_end = rest
        .iter()
        .position(u8::is_ascii_whitespace)
        .unwrap_or(rest.len());
    let (token, tail) = rest.split_at(token_end);
    if !skip_blanks(tail).iter().all(|&b| b == b'\r') {
        return None;
    }
    Some((token, start + end + 1))
}

fn skip_blanks(bytes: &[u8]) -> &[u8] {
    let skip = bytes
        .iter()
        .take_while(|b| matches!(b, b' ' | b'\t'))
        .count();
    &bytes[skip..]
}

/// `digits` or `digits.digits`: the plainest of the reader's number forms.
fn plain_decimal(token: &[u8]) -> bool {
    let (whole, fraction) = match token.iter().position(|&b| b == b'.') {
        Some(dot) => (&token[..dot], Some(&token[dot + 1..])),
        None => (token, None),
    };
    !whole.is_empty()
        && whole.iter().all(u8::is_ascii_digit)
        && fraction.is_none_or(|f| !f.is_empty() && f.iter().all(u8::is_ascii_digit))
}

/// One file of [`repeated_headers`]: its values, its first bytes and size (to be read by the
/// full reader), or the error reading it.
#[derive(Debug)]
pub enum Head {
    Repeated(Timing),
    Other(Vec<u8>, u64),
    Failed(ReadError),
}

/// Each file of `paths` (regular files of at most `limit` bytes) read as [`repeated_header`]
/// reads it, from its first `count` bytes, in parallel.
#[must_use]
pub fn repeated_headers(
    paths: &[std::path::PathBuf],
    count: usize,
    limit: u64,
    template: &[u8],
    joints: usize,
) -> Vec<Head> {
    use rayon::prelude::*;
    paths
        .par_iter()
        .map(|path| match read_beginning(path, count, limit) {
            Err(error) => Head::Failed(error),
            Ok((data, size)) => {
                let whole = data.len() < count;
                match repeated_header(&data, size, whole, template, joints) {
                    Some(timing) => Head::Repeated(timing),
                    None => Head::Other(data, size),
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEMPLATE: &[u8] = b"HIERARCHY\nROOT a\n{\n}\nMOTION\n";

    fn file(tail: &[u8]) -> Vec<u8> {
        let mut data = TEMPLATE.to_vec();
        data.extend_from_slice(tail);
        data.resize(200, b'1');
        data
    }

    fn read(tail: &[u8]) -> Option<Timing> {
        repeated_header(&file(tail), 100_000, false, TEMPLATE, 2)
    }

    #[test]
    fn plain_lines_after_the_same_hierarchy_are_read() {
        let timing = read(b"Frames: 12\nFrame Time: 0.0333333\n").unwrap();
        assert_eq!(timing.frames, 12);
        assert_eq!(timing.frame_time.to_bits(), 0.033_333_3_f64.to_bits());
        assert_eq!(timing.block_start, TEMPLATE.len() + 33);
        for variant in [
            &b"Frames:\t12 \r\nFrame Time:  0.0333333\t\r\n"[..],
            b"Frames:12\nFrame Time:1\n",
        ] {
            assert!(read(variant).is_some(), "{variant:?}");
        }
    }

    #[test]
    fn anything_else_is_left_to_the_full_reader() {
        for variant in [
            &b"\nFrames: 12\nFrame Time: 0.03\n"[..], // a blank line
            b"frames: 12\nFrame Time: 0.03\n",        // another case
            b"Frames : 12\nFrame Time: 0.03\n",       // a blank before the colon
            b"Frames: 1 2\nFrame Time: 0.03\n",
            b"Frames: -1\nFrame Time: 0.03\n",
            b"Frames: 1234567890123456789\nFrame Time: 0.03\n",
            b"Frames: 12\nFrame Time: 3e-2\n",
            b"Frames: 12\nFrame Time: .03\n",
            b"Frames: 12\nFrame Time: 0\n",
            b"Frames: 12\nFrame Time: 0.03\r \n",
            b"Frames: 12\nFrame Time: nan\n",
            b"Frames: 99999\nFrame Time: 0.03\n", // more frames than the block can hold
            b"Frames: 12\nFrame Time: 0.03\n\0",  // a NUL byte in the first 4 KB
        ] {
            assert_eq!(
                read(variant),
                None,
                "{:?}",
                String::from_utf8_lossy(variant)
            );
        }
        let other = b"HIERARCHY\nROOT b\n{\n}\nMOTION\nFrames: 1\nFrame Time: 1\n1\n";
        assert_eq!(repeated_header(other, 100, false, TEMPLATE, 2), None);
        let short = file(b"Frames: 12\nFrame Time: 0.03\n");
        assert_eq!(repeated_header(&short, 200, true, TEMPLATE, 2), None); // the whole file
        let cut = &short[..TEMPLATE.len() + 20];
        assert_eq!(repeated_header(cut, 100_000, false, TEMPLATE, 2), None);
    }
}
