//! Foot contacts (Lee et al. 2002) with a temporal-continuity filter, and air time.
//!
//! Heights are along Y (up); speeds are backward differences per second.

use glam::DVec3;

use crate::error::{positive, product, zeros, KernelError, Result};

/// How contacts are detected and filtered. Lengths in the positions' units.
#[derive(Debug, Clone, Copy)]
pub struct ContactParams {
    /// Seconds between frames.
    pub frame_time: f64,
    /// Height (Y) of the floor.
    pub floor: f64,
    /// A point touches below this height above the floor...
    pub height_threshold: f64,
    /// ... and below this speed (units per second).
    pub speed_threshold: f64,
    /// Runs of contact or flight shorter than this many frames are noise.
    pub min_frames: usize,
    /// Hold filter (frame t uses frames <= t) instead of the offline run filter.
    pub causal: bool,
}

/// Contact flags `[F, S]` of `feet` feet from world positions `positions` `[F, S, P, 3]` of
/// `points` points per foot (ankle, toe).
///
/// A point touches when its height above the floor and its speed (`|x_t - x_{t-1}| / dt`;
/// frame 0 takes frame 1's speed offline, 0 when causal) are both below their thresholds; a
/// foot touches when any of its points does. Then [`absorb_short_runs`] (offline) or
/// [`hold_filter`] (causal) per foot.
///
/// # Errors
/// `KernelError::Argument` when the length is not a multiple of `feet x points x 3`, either
/// count is 0, `frame_time` is not positive or `min_frames` is 0.
pub fn foot_contacts(
    positions: &[f64],
    feet: usize,
    points: usize,
    params: &ContactParams,
) -> Result<Vec<bool>> {
    let per_frame = product("feet", product("feet", feet, points)?, 3)?;
    if per_frame == 0 || positions.len() % per_frame != 0 {
        return Err(KernelError::argument(
            "feet",
            format!(
                "length {} is not frames x {feet} feet x {points} points x 3",
                positions.len()
            ),
        ));
    }
    positive("frame_time", params.frame_time)?;
    if params.min_frames == 0 {
        return Err(KernelError::argument("min_frames", "must be at least 1"));
    }
    let frames = positions.len() / per_frame;
    if frames == 0 {
        // Nothing to detect; and `feet` may be huge when there are no frames (a hang, found by
        // `cargo fuzz`: the loop below ran once per foot).
        return Ok(Vec::new());
    }
    let point = |t: usize, s: usize, p: usize| {
        DVec3::from_slice(&positions[((t * feet + s) * points + p) * 3..][..3])
    };
    let speed = |t: usize, s: usize, p: usize| match t {
        0 if params.causal || frames < 2 => 0.0,
        0 => point(1, s, p).distance(point(0, s, p)) / params.frame_time,
        _ => point(t, s, p).distance(point(t - 1, s, p)) / params.frame_time,
    };
    let mut contacts = zeros("feet", frames * feet)?;
    for s in 0..feet {
        let mut raw: Vec<bool> = (0..frames)
            .map(|t| {
                (0..points).any(|p| {
                    point(t, s, p).y - params.floor < params.height_threshold
                        && speed(t, s, p) < params.speed_threshold
                })
            })
            .collect();
        if params.causal {
            hold_filter(&mut raw, params.min_frames);
        } else {
            absorb_short_runs(&mut raw, params.min_frames);
        }
        for (t, &flag) in raw.iter().enumerate() {
            contacts[t * feet + s] = flag;
        }
    }
    Ok(contacts)
}

/// Offline filter of one foot's flags: a run (of contact or of flight) shorter than
/// `min_frames` with a neighbour on both sides takes their value, shortest run first (earliest
/// among equals); runs touching either end of the clip are kept.
pub fn absorb_short_runs(signal: &mut [bool], min_frames: usize) {
    // (value, length) of each run of equal flags.
    let mut runs: Vec<(bool, usize)> = Vec::new();
    for &flag in signal.iter() {
        match runs.last_mut() {
            Some((value, length)) if *value == flag => *length += 1,
            _ => runs.push((flag, 1)),
        }
    }
    while runs.len() >= 3 {
        // The shortest interior run; min_by_key keeps the first of equal minima.
        let Some(i) = (1..runs.len() - 1).min_by_key(|&i| runs[i].1) else {
            break;
        };
        if runs[i].1 >= min_frames {
            break;
        }
        // Flipping run i merges it with both neighbours into one run.
        let merged = runs[i - 1].1 + runs[i].1 + runs[i + 1].1;
        runs[i - 1].1 = merged;
        runs.drain(i..=i + 1);
    }
    let mut t = 0;
    for (value, length) in runs {
        signal[t..t + length].fill(value);
        t += length;
    }
}

/// Causal filter of one foot's flags (hysteresis in time): the state starts as the first flag
/// and changes once the flags have disagreed with it for `min_frames` frames in a row, from
/// that frame on. Frame t uses flags `<= t` only.
pub fn hold_filter(signal: &mut [bool], min_frames: usize) {
    let Some(&first) = signal.first() else { return };
    let (mut state, mut streak) = (first, 0);
    for flag in signal.iter_mut() {
        streak = if *flag == state { 0 } else { streak + 1 };
        if streak >= min_frames {
            state = *flag;
            streak = 0;
        }
        *flag = state;
    }
}

/// Seconds since each foot last left contact, `[F, S]` from `contacts` `[F, S]`: 0 in contact,
/// `k * frame_time` at the k-th frame of a flight (a clip that starts in flight counts from one
/// frame before its start).
///
/// # Errors
/// `KernelError::Argument` when `feet` is 0 or does not divide the length, or `frame_time` is
/// not positive.
pub fn air_time(contacts: &[bool], feet: usize, frame_time: f64) -> Result<Vec<f64>> {
    if feet == 0 || contacts.len() % feet != 0 {
        return Err(KernelError::argument(
            "contacts",
            format!("length {} is not frames x {feet} feet", contacts.len()),
        ));
    }
    positive("frame_time", frame_time)?;
    let mut out = zeros("contacts", contacts.len())?;
    // Frames since the last contact, per foot (`feet` <= the length unless there are no frames).
    let mut since = vec![0_usize; if contacts.is_empty() { 0 } else { feet }];
    for (flags, times) in contacts.chunks(feet).zip(out.chunks_mut(feet)) {
        for s in 0..feet {
            since[s] = if flags[s] { 0 } else { since[s] + 1 };
            times[s] = since[s] as f64 * frame_time;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(text: &str) -> Vec<bool> {
        text.bytes().map(|b| b == b'#').collect()
    }

    #[test]
    fn short_runs_are_absorbed_shortest_first_and_ends_kept() {
        let mut s = flags("##...#.....##.###");
        absorb_short_runs(&mut s, 3);
        assert_eq!(s, flags("##.........######"));
        let mut one = flags("#");
        absorb_short_runs(&mut one, 3);
        assert_eq!(one, flags("#"));
    }

    #[test]
    fn hold_filter_waits_min_frames_before_switching() {
        let mut s = flags("...#..##...###..");
        hold_filter(&mut s, 3);
        assert_eq!(s, flags(".............###"));
    }

    #[test]
    fn air_time_counts_frames_since_contact() {
        let t = air_time(&flags("..##.."), 1, 0.5).unwrap();
        assert_eq!(t, [0.5, 1.0, 0.0, 0.0, 0.5, 1.0]);
    }

    #[test]
    fn a_foot_resting_for_ten_frames_is_one_contact() {
        // One foot, one point, high up but still on frames 20..=29 (speed 0 from 20 to 29).
        let mut positions = Vec::new();
        for t in 0..50 {
            let x = f64::from(if t < 19 {
                t
            } else if t <= 29 {
                19
            } else {
                t - 10
            });
            positions.extend([x, 0.0, 0.0]);
        }
        let params = ContactParams {
            frame_time: 0.1,
            floor: 0.0,
            height_threshold: 1.0,
            speed_threshold: 1.0,
            min_frames: 3,
            causal: false,
        };
        let contacts = foot_contacts(&positions, 1, 1, &params).unwrap();
        let frames: Vec<usize> = (0..50).filter(|&t| contacts[t]).collect();
        assert_eq!(frames, (20..30).collect::<Vec<_>>());
    }

    #[test]
    fn rejects_bad_arguments() {
        let params = ContactParams {
            frame_time: 0.1,
            floor: 0.0,
            height_threshold: 1.0,
            speed_threshold: 1.0,
            min_frames: 3,
            causal: false,
        };
        assert!(foot_contacts(&[0.0; 7], 1, 1, &params).is_err());
        assert!(foot_contacts(&[0.0; 6], 0, 1, &params).is_err());
        assert!(foot_contacts(
            &[0.0; 6],
            1,
            1,
            &ContactParams {
                min_frames: 0,
                ..params
            }
        )
        .is_err());
        assert!(foot_contacts(
            &[0.0; 6],
            1,
            1,
            &ContactParams {
                frame_time: 0.0,
                ..params
            }
        )
        .is_err());
        assert!(air_time(&[true; 3], 2, 0.1).is_err());
    }

    #[test]
    fn overflowing_counts_are_errors() {
        let params = ContactParams {
            frame_time: 0.1,
            floor: 0.0,
            height_threshold: 1.0,
            speed_threshold: 1.0,
            min_frames: 3,
            causal: false,
        };
        assert!(foot_contacts(&[0.0; 6], usize::MAX / 2 + 1, 2, &params).is_err());
        assert!(foot_contacts(&[0.0; 6], 1 << 62, 1 << 62, &params).is_err());
        // No frames of a huge number of feet: nothing to allocate or loop over per foot.
        assert_eq!(air_time(&[], usize::MAX, 0.1).unwrap(), Vec::<f64>::new());
        assert_eq!(
            foot_contacts(&[], 1 << 61, 1, &params).unwrap(),
            Vec::<bool>::new()
        );
    }
}
