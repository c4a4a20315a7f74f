//! Planted feet after retargeting (`expressive_mocap.skeletons.planting`): through each contact
//! run, each ankle follows a guide (the source's ankle carried into this motion's world) from
//! where this motion has it on average over the run, with two-bone leg IK (the foot keeps its
//! world rotation), eased in and out; clips laid end to end, each on its own.

use glam::{DQuat, DVec3};

use crate::error::{KernelError, Result};
use crate::fk::forward_kinematics;
use crate::ik::two_bone_ik_one;

/// Locking weights of one foot of one clip: 1 in contact, easing to 0 over `blend` frames
/// before and after each contact (smoothstep of the distance in frames).
fn contact_weights(contact: &[bool], blend: usize) -> Vec<f64> {
    let n = contact.len();
    let mut linear: Vec<f64> = contact.iter().map(|&c| f64::from(u8::from(c))).collect();
    for i in 1..=blend.min(n) {
        let ramp = 1.0 - i as f64 / (blend + 1) as f64;
        for f in i..n {
            if contact[f - i] {
                linear[f] = linear[f].max(ramp);
            }
        }
        for f in 0..n - i {
            if contact[f + i] {
                linear[f] = linear[f].max(ramp);
            }
        }
    }
    linear.iter().map(|&l| l * l * (3.0 - 2.0 * l)).collect()
}

/// Per frame of one clip, the mean of `gap` over the frame's contact run, or over the nearest
/// run by centre (the first of a tie); a clip without contact keeps its own values.
fn run_offsets(gap: &[DVec3], contact: &[bool]) -> Vec<DVec3> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (f, &c) in contact.iter().enumerate() {
        if c && (f == 0 || !contact[f - 1]) {
            runs.push((f, f + 1));
        } else if c {
            if let Some(run) = runs.last_mut() {
                run.1 = f + 1;
            }
        }
    }
    if runs.is_empty() {
        return gap.to_vec();
    }
    let means: Vec<DVec3> = runs
        .iter()
        .map(|&(a, b)| {
            let mut sum = DVec3::ZERO;
            for v in &gap[a..b] {
                sum += *v; // in frame order, as the twin's sums
            }
            sum / (b - a) as f64
        })
        .collect();
    let centres: Vec<f64> = runs
        .iter()
        .map(|&(a, b)| (a + b - 1) as f64 / 2.0)
        .collect();
    let mut out = Vec::with_capacity(gap.len());
    let mut current = 0; // the last run begun at or before the frame
    for f in 0..gap.len() {
        while current + 1 < runs.len() && runs[current + 1].0 <= f {
            current += 1;
        }
        let (a, b) = runs[current];
        let run = if a <= f && f < b {
            current
        } else {
            // The nearest centre: the run before the frame or the one after it.
            let before = if centres[current] <= f as f64 || current == 0 {
                current
            } else {
                current - 1
            };
            let after = (before + 1).min(runs.len() - 1);
            if (centres[after] - f as f64).abs() < (centres[before] - f as f64).abs() {
                after
            } else {
                before
            }
        };
        out.push(means[run]);
    }
    out
}

fn quat_at(values: &[f64], index: usize) -> DQuat {
    DQuat::from_slice(&values[4 * index..4 * index + 4])
}

fn vec_at(values: &[f64], index: usize) -> DVec3 {
    DVec3::from_slice(&values[3 * index..3 * index + 3])
}

/// The local rotations `[F, J, 4]` of a motion (`rotations` `[F, J, 4]`, `translations`
/// `[F, J, 3]`, `parents` `[J]`) with its feet planted: for each leg of `legs` (hip, knee, foot
/// joints; a leg of -1s is left as it is), through each run of `contacts` `[F, 2]`, the ankle
/// follows `guide` `[F, 2, 3]` from where the motion has it on average over the run, eased in
/// and out over `blend` frames; `starts` where clips laid end to end begin, then where the last
/// one ends (runs and easing stop there).
///
/// # Errors
/// `KernelError::Argument` when the lengths, legs or starts do not fit together.
#[allow(clippy::too_many_arguments, clippy::similar_names)]
pub fn plant_feet(
    rotations: &[f64],
    translations: &[f64],
    parents: &[i64],
    legs: &[[i64; 3]; 2],
    contacts: &[bool],
    guide: &[f64],
    starts: &[i64],
    blend: usize,
) -> Result<Vec<f64>> {
    let joints = parents.len();
    let (world, positions) = forward_kinematics(rotations, translations, parents)?;
    let frames = rotations.len() / (4 * joints);
    if contacts.len() != 2 * frames {
        return Err(KernelError::argument(
            "contacts",
            format!("expected {frames} x 2 flags, got {}", contacts.len()),
        ));
    }
    if guide.len() != 6 * frames {
        return Err(KernelError::argument(
            "guide",
            format!("expected {frames} x 2 x 3 values, got {}", guide.len()),
        ));
    }
    let ordered = starts.windows(2).all(|w| w[0] <= w[1]);
    if starts.first() != Some(&0) || starts.last() != Some(&(frames as i64)) || !ordered {
        return Err(KernelError::argument(
            "starts",
            format!("expected rising frame indices from 0 to {frames}"),
        ));
    }
    for leg in legs {
        let valid = leg
            .iter()
            .all(|&j| usize::try_from(j).is_ok_and(|j| j < joints));
        if !(valid || leg.iter().all(|&j| j == -1)) {
            return Err(KernelError::argument(
                "legs",
                format!("{leg:?} is not three joints below {joints} (or -1s)"),
            ));
        }
    }
    let mut out = rotations.to_vec();
    for (side, leg) in legs.iter().enumerate() {
        if leg[0] < 0 {
            continue;
        }
        let (hip, knee, foot) = (leg[0] as usize, leg[1] as usize, leg[2] as usize);
        let parent = parents[hip];
        for clip in starts.windows(2) {
            let (a, b) = (clip[0] as usize, clip[1] as usize);
            let contact: Vec<bool> = (a..b).map(|f| contacts[2 * f + side]).collect();
            let weights = contact_weights(&contact, blend);
            let gap: Vec<DVec3> = (a..b)
                .map(|f| vec_at(&positions, f * joints + foot) - vec_at(guide, 2 * f + side))
                .collect();
            let offsets = run_offsets(&gap, &contact);
            for (k, f) in (a..b).enumerate() {
                let w = weights[k];
                if w <= 0.0 {
                    continue;
                }
                let ankle = vec_at(&positions, f * joints + foot);
                let target = (1.0 - w) * ankle + w * (vec_at(guide, 2 * f + side) + offsets[k]);
                let world_hip = quat_at(&world, f * joints + hip);
                let (upper, lower) = two_bone_ik_one(
                    vec_at(&positions, f * joints + hip),
                    world_hip,
                    quat_at(&world, f * joints + knee),
                    vec_at(translations, f * joints + knee),
                    vec_at(translations, f * joints + foot),
                    target,
                );
                let local_hip = if parent >= 0 {
                    quat_at(&world, f * joints + parent as usize).conjugate() * upper
                } else {
                    upper
                };
                let local_knee = upper.conjugate() * lower;
                let local_foot = lower.conjugate() * quat_at(&world, f * joints + foot);
                for (joint, q) in [(hip, local_hip), (knee, local_knee), (foot, local_foot)] {
                    out[4 * (f * joints + joint)..][..4].copy_from_slice(&q.to_array());
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_ease_in_and_out_of_a_contact() {
        let mut contact = [false; 9];
        contact[4] = true;
        let w = contact_weights(&contact, 3);
        assert!(
            (w[4] - 1.0).abs() < 1e-15 && w[0] == 0.0 && w[8] == 0.0,
            "{w:?}"
        );
        assert!(w[3] > w[2] && w[2] > w[1] && w[1] > 0.0 && (w[3] - w[5]).abs() < 1e-15);
    }

    #[test]
    fn frames_outside_runs_take_the_nearest_run() {
        let gap: Vec<DVec3> = (0..6).map(|f| DVec3::splat(f as f64)).collect();
        let out = run_offsets(&gap, &[true, false, false, false, true, true]);
        assert_eq!(out[1].x, 0.0);
        assert_eq!(out[3].x, 4.5);
        assert_eq!(out[5].x, 4.5);
    }
}
