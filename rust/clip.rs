//! The whole per-clip work of `expressive-mocap preprocess` as one task: the MOTION block
//! parsed and decoded, forward kinematics, dynamic features and foot contacts. Run clip by clip
//! on a thread pool, each clip's intermediate arrays (channel values, local and world poses) are
//! made and dropped inside its task, so an archive never holds them all and the allocator reuses
//! the same memory clip after clip; only the arrays asked for leave the task. (Handed to NumPy
//! and kept for a whole batch instead, the intermediates made the two cores fight over fresh
//! pages and held `preprocess` to 1.6x the speed of one core.)

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::decode::{read_motion_block, ChannelLayout};
use crate::error::{zeros, KernelError, Result};
use crate::fk::forward_kinematics;
use crate::forms::{write_gradient, write_matrix};
use crate::gait::{clip_gait, BodyScale, FeatureRequest, GaitJoints, GaitParams};

/// What to compute for every clip of one skeleton.
#[derive(Debug, Clone)]
#[allow(clippy::struct_excessive_bools)] // one flag per output, named
pub struct ClipRequest<'a> {
    /// The skeleton's parent indices (-1 for the root), parents before children.
    pub parents: &'a [i64],
    pub roles: GaitJoints,
    pub params: GaitParams,
    /// Keep the world positions `[F, J, 3]`.
    pub positions: bool,
    /// Keep the local rotations: quaternions `[F, J, 4]` (x, y, z, w) when `rotation_columns`
    /// is 0, else their matrices, the first `rotation_columns` columns (2: the 6D form
    /// `[F, J, 6]`, column after column; 3: the whole matrix `[F, J, 9]`, row after row).
    pub rotations: bool,
    pub rotation_columns: usize,
    /// Keep the world positions' time derivative `[F, J, 3]` (as `forms::clip_gradient`).
    pub velocities: bool,
    /// One causal feature array `[F, 19]` per request (e.g. a dataset's and a model's).
    pub features: &'a [FeatureRequest],
    /// Keep the offline foot contacts `[F, 2]`.
    pub contacts: bool,
}

/// One clip: its MOTION block (the bytes after the `Frame Time` line), frame count, channel
/// layout, frame time (seconds) and body scale.
#[derive(Debug, Clone, Copy)]
pub struct ClipInput<'a> {
    pub block: &'a [u8],
    pub frames: usize,
    pub layout: ChannelLayout<'a>,
    pub frame_time: f64,
    pub scale: BodyScale,
}

/// The arrays a [`ClipRequest`] asked for, flattened row-major.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClipOutputs {
    pub positions: Option<Vec<f64>>,
    pub rotations: Option<Vec<f64>>,
    pub velocities: Option<Vec<f64>>,
    pub features: Vec<Vec<f64>>,
    pub contacts: Option<Vec<bool>>,
}

/// Everything `request` asks for of one clip, as `read_motion_block`, `forward_kinematics`,
/// `clip_gait` and the `forms` kernels give it (the same numbers, bit for bit). The stored forms
/// of model-ready datasets are made here, inside the clip's task, from arrays still in cache:
/// made after the call, from a batch's arrays, they cost a quarter of a run (copies, and
/// NumPy glue holding the GIL).
///
/// # Errors
/// `KernelError::Parse` for a malformed MOTION block (its line counted from the block's first);
/// `KernelError::Argument` when the layout, parents, roles or rotation columns do not fit.
pub fn clip_outputs(clip: &ClipInput<'_>, request: &ClipRequest<'_>) -> Result<ClipOutputs> {
    if ![0, 2, 3].contains(&request.rotation_columns) {
        return Err(KernelError::argument(
            "rotation_columns",
            format!(
                "expected 0 (quaternions), 2 (6d) or 3 (the whole matrix), got {}",
                request.rotation_columns
            ),
        ));
    }
    let (rotations, translations) = read_motion_block(clip.block, clip.frames, &clip.layout)?;
    let (_, positions) = forward_kinematics(&rotations, &translations, request.parents)?;
    let joints = request.parents.len();
    let gait = |features: Option<&FeatureRequest>, contacts: bool| {
        clip_gait(
            &positions,
            &rotations,
            joints,
            clip.frame_time,
            clip.scale,
            &request.roles,
            &request.params,
            features,
            contacts,
        )
    };
    let mut out = ClipOutputs::default();
    // The contacts come with the first feature request (or alone): one contact pass per clip.
    let mut contacts_wanted = request.contacts;
    for feature_request in request.features {
        let computed = gait(Some(feature_request), contacts_wanted)?;
        out.features.push(computed.features.unwrap_or_default());
        if contacts_wanted {
            out.contacts = computed.contacts;
            contacts_wanted = false;
        }
    }
    if contacts_wanted {
        out.contacts = gait(None, true)?.contacts;
    }
    if request.velocities {
        let mut velocities = zeros("positions", positions.len())?;
        write_gradient(&positions, 3 * joints, |_| clip.frame_time, &mut velocities);
        out.velocities = Some(velocities);
    }
    out.positions = request.positions.then_some(positions);
    out.rotations = match (request.rotations, request.rotation_columns) {
        (false, _) => None,
        (true, 0) => Some(rotations),
        (true, columns) => {
            let mut matrices = zeros("rotations", rotations.len() / 4 * 3 * columns)?;
            for (q, dst) in rotations
                .chunks_exact(4)
                .zip(matrices.chunks_exact_mut(3 * columns))
            {
                write_matrix(q, dst, |v| v);
            }
            Some(matrices)
        }
    };
    Ok(out)
}

/// Why a clip's file was not read: the system's error, or what was found instead of a regular
/// file of at most the bound. `errno` and `message` are those of Python's `io.open_input`, so
/// both backends name a refused file the same way.
#[derive(Debug)]
pub enum ReadError {
    Os(std::io::Error),
    Refused { errno: i32, message: String },
}

// The classic values, the same on Linux and macOS (as Python's io.open_input raises them).
const EISDIR: i32 = 21;
const EINVAL: i32 = 22;
const EFBIG: i32 = 27;

/// The bytes of the regular file at `path` (symlinks followed), at most `limit` of them, as
/// Python's `io.read_input` reads them: opened without blocking (opening a FIFO to read waits
/// for a writer), then the opened file itself checked, so nothing can be swapped in after the
/// check: a FIFO, device, socket or folder is refused, and so is a file larger than `limit`
/// (e.g. a link to /dev/zero, which never ends, or a file that grows while it is read).
///
/// # Errors
/// `ReadError::Os` when the file cannot be opened or read, `ReadError::Refused` otherwise.
pub fn read_input(path: &Path, limit: u64) -> std::result::Result<Vec<u8>, ReadError> {
    let (file, size) = open_checked(path, limit)?;
    // O_NONBLOCK is left set: it does not change how a regular file is read.
    let mut data = Vec::with_capacity(usize::try_from(size).unwrap_or(0).saturating_add(1));
    file.take(limit.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(ReadError::Os)?;
    if data.len() as u64 > limit {
        let message = format!("more than the {} bytes read at most", grouped(limit));
        return Err(ReadError::Refused {
            errno: EFBIG,
            message,
        });
    }
    Ok(data)
}

/// The first `count` bytes of the regular file at `path` (all of it if shorter) and its size,
/// the file opened and checked as [`read_input`] does (Python's `files.read_beginning`).
///
/// # Errors
/// As [`read_input`].
pub fn read_beginning(
    path: &Path,
    count: usize,
    limit: u64,
) -> std::result::Result<(Vec<u8>, u64), ReadError> {
    let (file, size) = open_checked(path, limit)?;
    let mut data = Vec::with_capacity(count.min(usize::try_from(size).unwrap_or(count)));
    file.take(count as u64)
        .read_to_end(&mut data)
        .map_err(ReadError::Os)?;
    Ok((data, size))
}

/// The regular file at `path`, opened without blocking, and its size, or why it is refused: not
/// a regular file (checked on the opened file itself), or larger than `limit`.
fn open_checked(path: &Path, limit: u64) -> std::result::Result<(File, u64), ReadError> {
    let file = open_nonblocking(path).map_err(|error| open_error(path, error))?;
    let meta = file.metadata().map_err(ReadError::Os)?;
    if !meta.is_file() {
        let errno = if meta.is_dir() { EISDIR } else { EINVAL };
        let message = not_regular(meta.file_type());
        return Err(ReadError::Refused { errno, message });
    }
    if meta.len() > limit {
        let message = format!(
            "{} bytes, more than the {} bytes read at most",
            grouped(meta.len()),
            grouped(limit)
        );
        return Err(ReadError::Refused {
            errno: EFBIG,
            message,
        });
    }
    Ok((file, meta.len()))
}

/// The error of a failed open; one of what is neither a regular file nor a folder says what it
/// is (a socket cannot be opened at all: ENXIO).
fn open_error(path: &Path, error: std::io::Error) -> ReadError {
    match std::fs::metadata(path) {
        Ok(meta) if !meta.is_file() && !meta.is_dir() => ReadError::Refused {
            errno: error.raw_os_error().unwrap_or(EINVAL),
            message: not_regular(meta.file_type()),
        },
        _ => ReadError::Os(error),
    }
}

fn not_regular(kind: std::fs::FileType) -> String {
    format!(
        "{}, not a regular file: only regular files are read",
        file_kind(kind)
    )
}

#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

/// What a file of this type is, in words (Python's `io.file_kind`).
fn file_kind(kind: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        for (found, name) in [
            (kind.is_fifo(), "a FIFO"),
            (kind.is_char_device(), "a character device"),
            (kind.is_block_device(), "a block device"),
            (kind.is_socket(), "a socket"),
        ] {
            if found {
                return name;
            }
        }
    }
    if kind.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

/// `n` with thousands separators, as Python's `f"{n:,}"`.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rotations::Order;

    // Two joints play every role: the kernels only need valid indices here.
    const ROLES: GaitJoints = GaitJoints {
        hips: 0,
        upper_legs: [0, 1],
        feet: [1, 1],
        toes: [1, 0],
    };
    const PARAMS: GaitParams = GaitParams {
        height_threshold: 0.05,
        speed_threshold: 0.5,
        min_duration: 0.1,
        floor_percentile: 5.0,
    };
    const SCALE: BodyScale = BodyScale {
        height: 170.0,
        hips_rest_height: 90.0,
    };
    const PARENTS: [i64; 2] = [-1, 0];
    const BLOCK: &[u8] =
        b"0 90 0 10 20 30 5 0 0\n1 90 2 12 18 33 -5 1 0\n2 91 4 14 16 36 -15 2 0\n";

    /// `f` given two joints in a chain, each with a ZXY rotation, the root with a position.
    fn with_layout<R>(f: impl FnOnce(ChannelLayout<'_>) -> R) -> R {
        let (rotation_columns, orders, position_columns, offsets): (
            Vec<i64>,
            Vec<Order>,
            Vec<i64>,
            Vec<f64>,
        ) = (
            vec![3, 4, 5, 6, 7, 8],
            vec![[2, 0, 1]; 2],
            vec![0, 1, 2, -1, -1, -1],
            vec![0.0, 90.0, 0.0, 0.0, 40.0, 0.0],
        );
        f(ChannelLayout {
            channels: 9,
            rotation_columns: &rotation_columns,
            orders: &orders,
            position_columns: &position_columns,
            offsets: &offsets,
        })
    }

    fn request(features: &[FeatureRequest]) -> ClipRequest<'_> {
        ClipRequest {
            parents: &PARENTS,
            roles: ROLES,
            params: PARAMS,
            positions: true,
            rotations: true,
            rotation_columns: 0,
            velocities: false,
            features,
            contacts: true,
        }
    }

    #[test]
    fn outputs_are_those_of_the_kernels_one_by_one() {
        with_layout(|layout| {
            let features = [
                FeatureRequest {
                    floor: Some(0.0),
                    thigh_reference: None,
                },
                FeatureRequest {
                    floor: None,
                    thigh_reference: None,
                },
            ];
            let clip = ClipInput {
                block: BLOCK,
                frames: 3,
                layout,
                frame_time: 1.0 / 30.0,
                scale: SCALE,
            };
            let out = clip_outputs(&clip, &request(&features)).unwrap();

            let (rotations, translations) = read_motion_block(BLOCK, 3, &layout).unwrap();
            let (_, positions) = forward_kinematics(&rotations, &translations, &PARENTS).unwrap();
            let alone = |f: Option<&FeatureRequest>, c| {
                clip_gait(
                    &positions,
                    &rotations,
                    2,
                    1.0 / 30.0,
                    SCALE,
                    &ROLES,
                    &PARAMS,
                    f,
                    c,
                )
                .unwrap()
            };
            assert_eq!(out.positions.as_ref(), Some(&positions));
            assert_eq!(out.rotations.as_ref(), Some(&rotations));
            let expected: Vec<_> = features
                .iter()
                .map(|f| alone(Some(f), false).features.unwrap())
                .collect();
            assert_eq!(out.features, expected);
            assert_eq!(out.contacts, alone(None, true).contacts);

            let only_contacts = ClipRequest {
                positions: false,
                rotations: false,
                ..request(&[])
            };
            let out = clip_outputs(&clip, &only_contacts).unwrap();
            assert_eq!(
                out,
                ClipOutputs {
                    contacts: alone(None, true).contacts,
                    ..ClipOutputs::default()
                }
            );
        });
    }

    #[test]
    fn stored_forms_are_the_forms_kernels_of_the_clips_arrays() {
        with_layout(|layout| {
            let clip = ClipInput {
                block: BLOCK,
                frames: 3,
                layout,
                frame_time: 0.25,
                scale: SCALE,
            };
            let plain = clip_outputs(&clip, &request(&[])).unwrap();
            let (positions, quats) = (plain.positions.unwrap(), plain.rotations.unwrap());
            let starts = [0_i64];
            let velocities =
                crate::forms::clip_gradient(&positions, 6, &starts, &[0.25; 3]).unwrap();
            for columns in [2, 3] {
                let formed = ClipRequest {
                    rotation_columns: columns,
                    velocities: true,
                    ..request(&[])
                };
                let out = clip_outputs(&clip, &formed).unwrap();
                let matrices = crate::forms::matrix_columns(&quats, columns).unwrap();
                let ours: Vec<f32> = out.rotations.unwrap().iter().map(|&v| v as f32).collect();
                assert_eq!(ours, matrices);
                assert_eq!(out.velocities.as_ref(), Some(&velocities));
                assert_eq!(out.positions.as_ref(), Some(&positions));
            }
            let odd = ClipRequest {
                rotation_columns: 1,
                ..request(&[])
            };
            assert!(clip_outputs(&clip, &odd).is_err());
        });
    }

    #[test]
    fn a_bad_block_or_skeleton_is_an_error() {
        with_layout(|layout| {
            let short = ClipInput {
                block: b"0 90 0 10 20 30 5 0\n",
                frames: 1,
                layout,
                frame_time: 1.0 / 30.0,
                scale: SCALE,
            };
            assert!(matches!(
                clip_outputs(&short, &request(&[])),
                Err(crate::error::KernelError::Parse { line: 0, .. })
            ));
            let clip = ClipInput {
                block: b"0 90 0 10 20 30 5 0 0\n",
                ..short
            };
            assert!(clip_outputs(
                &clip,
                &ClipRequest {
                    parents: &[-1, 5],
                    ..request(&[])
                }
            )
            .is_err());
            let far = GaitJoints {
                toes: [1, 2],
                ..ROLES
            };
            assert!(clip_outputs(
                &clip,
                &ClipRequest {
                    roles: far,
                    ..request(&[])
                }
            )
            .is_err());
        });
    }

    #[test]
    fn grouped_is_pythons_thousands_separator() {
        let cases = [
            (0, "0"),
            (999, "999"),
            (1000, "1,000"),
            (536_870_912, "536,870,912"),
            (u64::MAX, "18,446,744,073,709,551,615"),
        ];
        for (n, text) in cases {
            assert_eq!(grouped(n), text);
        }
    }

    fn refused(result: std::result::Result<Vec<u8>, ReadError>) -> (i32, String) {
        match result {
            Err(ReadError::Refused { errno, message }) => (errno, message),
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn only_regular_files_within_the_bound_are_read() {
        let folder =
            std::env::temp_dir().join(format!("expressive-mocap-read-{}", std::process::id()));
        std::fs::create_dir_all(&folder).unwrap();
        let file = folder.join("clip.bvh");
        std::fs::write(&file, b"0123456789").unwrap();
        assert_eq!(read_input(&file, 10).unwrap(), b"0123456789");
        assert_eq!(
            refused(read_input(&file, 9)),
            (EFBIG, "10 bytes, more than the 9 bytes read at most".into())
        );
        assert_eq!(refused(read_input(&folder, 10)).0, EISDIR);
        assert!(
            matches!(read_input(&folder.join("gone.bvh"), 10), Err(ReadError::Os(e)) if e.kind() == std::io::ErrorKind::NotFound)
        );
        #[cfg(unix)]
        {
            // A FIFO without a writer: refused at once, never waited on; /dev/zero never ends.
            let fifo = folder.join("pipe.bvh");
            let made = std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap();
            assert!(made.success());
            assert_eq!(
                refused(read_input(&fifo, 10)),
                (
                    EINVAL,
                    "a FIFO, not a regular file: only regular files are read".into()
                )
            );
            assert_eq!(
                refused(read_input(Path::new("/dev/zero"), 10)).1,
                "a character device, not a regular file: only regular files are read"
            );
            // A socket cannot even be opened (ENXIO): still named.
            let socket = folder.join("sock.bvh");
            let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
            assert_eq!(
                refused(read_input(&socket, 10)).1,
                "a socket, not a regular file: only regular files are read"
            );
        }
        std::fs::remove_dir_all(&folder).unwrap();
    }
}
