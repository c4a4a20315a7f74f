//! Timings of the Rust kernels themselves, without Python: MOTION block parsing, Euler angles
//! to quaternions, forward kinematics, dynamic features and MLP inference, on synthetic inputs
//! of realistic size.
//! Run with `cargo bench --bench kernels`; a plain timing main (stable Rust, no criterion):
//! each kernel is run a few times and the best and median wall times are printed.

use std::hint::black_box;
use std::time::{Duration, Instant};

use _core::features::{dynamic_features, FeatureParams};
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
    let mut text = String::new();
    for _ in 0..FRAMES {
        let line: Vec<String> = (0..channels)
            .map(|_| format!("{:.6}", noise.next() * 180.0))
            .collect();
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
