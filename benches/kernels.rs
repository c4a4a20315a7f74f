//! Timings of the Rust kernels themselves, without Python: MOTION block parsing, Euler angles
//! to quaternions, forward kinematics, dynamic features and MLP inference, on synthetic inputs
//! of realistic size.
//! Run with `cargo bench --bench kernels`; a plain timing main (stable Rust, no criterion):
//! each kernel is run a few times and the best and median wall times are printed. Every
//! kernel's output is checked before any time is printed (a failed check panics): the numbers
//! parsed back within 1e-6 of those written with 6 decimals, unit quaternions equal to the
//! product of the three axis rotations, FK of two frames against a plain composition, finite
//! features, and the network's first row against a plain f64 evaluation.

use std::hint::black_box;
use std::time::{Duration, Instant};

use glam::{DQuat, DVec3};

use _core::features::{dynamic_features, FeatureParams, N_FEATURES};
use _core::fk::forward_kinematics;
use _core::mlp::{mlp_forward, Activation, Layer};
use _core::parse::parse_motion_block;
use _core::rotations::euler_to_quat;

const FRAMES: usize = 10_000;
const JOINTS: usize = 25;
const RUNS: usize = 15;

/// A deterministic pseudo-random stream in [-1, 1).
struct Noise(u64);

impl Noise {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

fn unit_quats(noise: &mut Noise, count: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(count * 4);
    for _ in 0..count {
        let q = [noise.next(), noise.next(), noise.next(), noise.next() + 2.0];
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        out.extend(q.iter().map(|v| v / norm));
    }
    out
}

/// Stop the bench when a kernel's output is wrong: no figure for a wrong result.
fn check(ok: bool, what: &str) {
    assert!(ok, "check failed: {what}");
}

fn quat(v: &[f64]) -> DQuat {
    DQuat::from_xyzw(v[0], v[1], v[2], v[3])
}

fn vec3(v: &[f64]) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

fn time(name: &str, work: usize, unit: &str, mut run: impl FnMut()) {
    let mut times: Vec<Duration> = (0..RUNS)
        .map(|_| {
            let start = Instant::now();
            run();
            start.elapsed()
        })
        .collect();
    times.sort();
    let (best, median) = (times[0], times[RUNS / 2]);
    println!(
        "| {name} | {:.3} | {:.3} | {:.1} M {unit}/s |",
        best.as_secs_f64() * 1e3,
        median.as_secs_f64() * 1e3,
        work as f64 / best.as_secs_f64() / 1e6
    );
}

fn main() {
    let mut noise = Noise(7);
    let channels = 3 + 3 * JOINTS;
    let written: Vec<f64> = (0..FRAMES * channels)
        .map(|_| noise.next() * 180.0)
        .collect();
    let mut text = String::new();
    for row in written.chunks(channels) {
        let line: Vec<String> = row.iter().map(|v| format!("{v:.6}")).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    let block = text.into_bytes();

    let rotations = unit_quats(&mut noise, FRAMES * JOINTS);
    let translations: Vec<f64> = (0..FRAMES * JOINTS * 3)
        .map(|_| noise.next() * 10.0)
        .collect();
    let parents: Vec<i64> = (0..JOINTS as i64).map(|j| j - 1).collect();

    let points: Vec<f64> = (0..FRAMES * 9)
        .map(|_| noise.next() * 50.0 + 90.0)
        .collect();
    let thighs = unit_quats(&mut noise, FRAMES * 2);
    let contacts: Vec<bool> = (0..FRAMES * 2).map(|_| noise.next() > 0.0).collect();
    let reference = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let params = FeatureParams {
        frame_time: 1.0 / 30.0,
        height: 170.0,
        hips_rest_height: 95.0,
        floor: 0.0,
        window: 10,
    };

    // The shape of the shipped body-mechanics network: 19 features -> 2 x 256 tanh -> J x 4.
    let (inputs, hidden, outputs) = (19, 256, JOINTS * 4);
    let x: Vec<f32> = (0..FRAMES * inputs).map(|_| noise.next() as f32).collect();
    let w1: Vec<f32> = (0..inputs * hidden)
        .map(|_| noise.next() as f32 * 0.2)
        .collect();
    let w2: Vec<f32> = (0..hidden * hidden)
        .map(|_| noise.next() as f32 * 0.06)
        .collect();
    let w3: Vec<f32> = (0..hidden * outputs)
        .map(|_| noise.next() as f32 * 0.06)
        .collect();
    let (b1, b2, b3) = (
        vec![0.01f32; hidden],
        vec![0.01f32; hidden],
        vec![0.0f32; outputs],
    );
    let layers = [
        Layer {
            weights: &w1,
            bias: &b1,
            inputs,
            outputs: hidden,
            activation: Activation::Tanh,
        },
        Layer {
            weights: &w2,
            bias: &b2,
            inputs: hidden,
            outputs: hidden,
            activation: Activation::Tanh,
        },
        Layer {
            weights: &w3,
            bias: &b3,
            inputs: hidden,
            outputs,
            activation: Activation::Linear,
        },
    ];

    // Drawn last so the other kernels' inputs stay as they were. Four times FRAMES x JOINTS
    // (1M joint-frames, 3M angles): the per-angle sine and cosine dominate.
    let angles: Vec<f64> = (0..4 * FRAMES * JOINTS * 3)
        .map(|_| noise.next() * 180.0)
        .collect();
    let orders = [[2u8, 0, 1]; JOINTS];

    check_outputs(&Inputs {
        block: &block,
        written: &written,
        channels,
        angles: &angles,
        orders: &orders,
        rotations: &rotations,
        translations: &translations,
        parents: &parents,
        points: &points,
        thighs: &thighs,
        contacts: &contacts,
        reference: &reference,
        params: &params,
        x: &x,
        layers: &layers,
    });

    println!(
        "{FRAMES} frames, {JOINTS} joints, best and median of {RUNS} runs, {} rayon threads",
        rayon::current_num_threads()
    );
    println!("| kernel | best ms | median ms | throughput |\n|---|---|---|---|");
    time(
        &format!("parse_motion_block ({} MB)", block.len() / 1_000_000),
        FRAMES * channels,
        "numbers",
        || {
            black_box(parse_motion_block(black_box(&block), FRAMES, channels).unwrap());
        },
    );
    time("euler_to_quat (1M joints)", angles.len(), "angles", || {
        black_box(euler_to_quat(black_box(&angles), &orders).unwrap());
    });
    time("forward_kinematics", FRAMES * JOINTS, "joints", || {
        black_box(forward_kinematics(black_box(&rotations), &translations, &parents).unwrap());
    });
    time("dynamic_features", FRAMES, "frames", || {
        black_box(
            dynamic_features(black_box(&points), &thighs, &contacts, &reference, &params).unwrap(),
        );
    });
    time("mlp_forward (f32, 19-256-256-100)", FRAMES, "rows", || {
        black_box(mlp_forward(black_box(&x), FRAMES, &layers).unwrap());
    });
}

/// Every kernel's input, for [`check_outputs`].
struct Inputs<'a> {
    block: &'a [u8],
    written: &'a [f64],
    channels: usize,
    angles: &'a [f64],
    orders: &'a [[u8; 3]],
    rotations: &'a [f64],
    translations: &'a [f64],
    parents: &'a [i64],
    points: &'a [f64],
    thighs: &'a [f64],
    contacts: &'a [bool],
    reference: &'a [f64],
    params: &'a FeatureParams,
    x: &'a [f32],
    layers: &'a [Layer<'a, f32>],
}

/// Each kernel's output against what it must be, before anything is timed.
fn check_outputs(i: &Inputs) {
    let parsed = parse_motion_block(i.block, FRAMES, i.channels).unwrap();
    check(
        parsed.len() == i.written.len(),
        "parse_motion_block: value count",
    );
    check(
        parsed
            .iter()
            .zip(i.written)
            .all(|(p, w)| (p - w).abs() <= 1e-6),
        "parse_motion_block: values within 1e-6 of those written",
    );

    let quats = euler_to_quat(i.angles, i.orders).unwrap();
    check(
        quats.len() == i.angles.len() / 3 * 4,
        "euler_to_quat: quaternion count",
    );
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for (k, (q, a)) in quats.chunks(4).zip(i.angles.chunks(3)).enumerate() {
        let order = i.orders[k % i.orders.len()];
        let want = (0..3).fold(DQuat::IDENTITY, |acc, n| {
            acc * DQuat::from_axis_angle(axes[usize::from(order[n])], a[n].to_radians())
        });
        check(
            (quat(q).dot(want).abs() - 1.0).abs() <= 1e-12
                && (quat(q).length() - 1.0).abs() <= 1e-12,
            "euler_to_quat: unit quaternions equal to the axis rotations' product",
        );
    }

    let (world_rot, world_pos) =
        forward_kinematics(i.rotations, i.translations, i.parents).unwrap();
    check(
        world_rot.len() == FRAMES * JOINTS * 4 && world_pos.len() == FRAMES * JOINTS * 3,
        "forward_kinematics: output sizes",
    );
    for f in [0, FRAMES - 1] {
        let (mut rot, mut pos) = (DQuat::IDENTITY, DVec3::ZERO);
        for j in 0..JOINTS {
            let at = f * JOINTS + j;
            // The chain: each joint's parent is the one before it, joint 0 the root.
            pos = if j == 0 {
                vec3(&i.translations[3 * at..])
            } else {
                pos + rot * vec3(&i.translations[3 * at..])
            };
            rot = if j == 0 {
                quat(&i.rotations[4 * at..])
            } else {
                rot * quat(&i.rotations[4 * at..])
            };
            check(
                (quat(&world_rot[4 * at..]).dot(rot).abs() - 1.0).abs() <= 1e-12
                    && (vec3(&world_pos[3 * at..]) - pos).length() <= 1e-9,
                "forward_kinematics: world rotations and positions of a plain composition",
            );
        }
    }

    let features = dynamic_features(i.points, i.thighs, i.contacts, i.reference, i.params).unwrap();
    check(
        features.len() == FRAMES * N_FEATURES && features.iter().all(|v| v.is_finite()),
        "dynamic_features: 19 finite features a frame",
    );

    let outputs = i.layers.last().unwrap().outputs;
    let net = mlp_forward(i.x, FRAMES, i.layers).unwrap();
    check(net.len() == FRAMES * outputs, "mlp_forward: output size");
    let mut row: Vec<f64> = i.x[..i.layers[0].inputs]
        .iter()
        .map(|&v| f64::from(v))
        .collect();
    for layer in i.layers {
        row = (0..layer.outputs)
            .map(|o| {
                let sum = f64::from(layer.bias[o])
                    + (0..layer.inputs)
                        .map(|n| row[n] * f64::from(layer.weights[n * layer.outputs + o]))
                        .sum::<f64>();
                match layer.activation {
                    Activation::Tanh => sum.tanh(),
                    Activation::Linear => sum,
                }
            })
            .collect();
    }
    check(
        net[..outputs]
            .iter()
            .zip(&row)
            .all(|(&got, want)| (f64::from(got) - want).abs() <= 1e-3),
        "mlp_forward: the first row within 1e-3 of a plain f64 evaluation",
    );
}
