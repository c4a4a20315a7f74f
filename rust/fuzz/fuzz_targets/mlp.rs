//! MLP inference with arbitrary layer shapes (chained or not, zero, overflowing), lengths,
//! activations and values, in float64 and float32.
#![no_main]
use _core::mlp::{mlp_forward, Activation, Layer};
use arbitrary::Unstructured;
use expressive_mocap_fuzz::{count, floats};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut run = || -> arbitrary::Result<()> {
        let (rows, n_layers, chained) = (count(&mut u)?, u.int_in_range(0..=4_usize)?, u.ratio(3, 4)?);
        let mut shapes = Vec::new();
        let mut inputs = u.int_in_range(0..=8_usize)?;
        for _ in 0..n_layers {
            let outputs = if u.ratio(1, 16)? { count(&mut u)? } else { u.int_in_range(0..=8_usize)? };
            shapes.push((if chained { inputs } else { count(&mut u)? }, outputs, if u.arbitrary()? { Activation::Tanh } else { Activation::Linear }));
            inputs = outputs;
        }
        let mut parameters = Vec::new();
        for &(inputs, outputs, _) in &shapes {
            parameters.push((floats(&mut u, inputs.saturating_mul(outputs))?, floats(&mut u, outputs)?));
        }
        let first = shapes.first().map_or(0, |s| s.0);
        let x = floats(&mut u, rows.saturating_mul(first))?;
        let layers: Vec<Layer<f64>> = shapes.iter().zip(&parameters).map(|(&(inputs, outputs, activation), (w, b))| Layer { weights: w, bias: b, inputs, outputs, activation }).collect();
        if let Ok(y) = mlp_forward(&x, rows, &layers) {
            assert_eq!(y.len(), rows * shapes.last().map_or(0, |s| s.1));
        }
        // The same network in float32.
        let to32 = |v: &Vec<f64>| v.iter().map(|&a| a as f32).collect::<Vec<f32>>();
        let parameters32: Vec<(Vec<f32>, Vec<f32>)> = parameters.iter().map(|(w, b)| (to32(w), to32(b))).collect();
        let layers32: Vec<Layer<f32>> = shapes.iter().zip(&parameters32).map(|(&(inputs, outputs, activation), (w, b))| Layer { weights: w, bias: b, inputs, outputs, activation }).collect();
        let _ = mlp_forward(&to32(&x), rows, &layers32);
        Ok(())
    };
    let _ = run();
});
