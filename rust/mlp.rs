//! Batched inference of small multilayer perceptrons (dense layers, tanh or linear).
//!
//! A network is a list of layers `y = act(x W + b)` with `W` `[in, out]` (row-major, as NumPy
//! stores `x @ W`) and `b` `[out]`. The batch is cut into blocks of rows; each block runs through
//! every layer with one GEMM a layer (`matrixmultiply`), blocks in parallel with rayon. The same
//! code serves `f32` and `f64` through the small [`Scalar`] trait.

use rayon::prelude::*;

use crate::error::{product, zeros, KernelError, Result, Zeroable};

/// Rows a block: big enough that a 300 x 300 GEMM amortises packing the weights (about
/// 23 MFLOP a layer), small enough that a block's activations stay in L2.
const BLOCK_ROWS: usize = 128;

/// Activation applied after a layer's affine map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activation {
    Linear,
    Tanh,
}

impl Activation {
    /// `"linear"` or `"tanh"`.
    ///
    /// # Errors
    /// `KernelError::Argument` naming `activations` and the layer for any other name.
    pub fn parse(name: &str, layer: usize) -> Result<Self> {
        match name {
            "linear" => Ok(Self::Linear),
            "tanh" => Ok(Self::Tanh),
            other => Err(KernelError::argument(
                "activations",
                format!(
                    "layer {layer}: unknown activation {other:?} (expected \"tanh\" or \"linear\")"
                ),
            )),
        }
    }
}

/// One dense layer, borrowed: `weights` `[inputs, outputs]` row-major, `bias` `[outputs]`.
#[derive(Debug, Clone, Copy)]
pub struct Layer<'a, T> {
    pub weights: &'a [T],
    pub bias: &'a [T],
    pub inputs: usize,
    pub outputs: usize,
    pub activation: Activation,
}

/// The floats a network runs in: a GEMM and a tanh.
pub trait Scalar: Zeroable + Send + Sync + 'static {
    const ZERO: Self;
    /// `c = a b + c` with `a` `[m, k]`, `b` `[k, n]`, `c` `[m, n]`, all row-major and dense.
    fn gemm_acc(m: usize, k: usize, n: usize, a: &[Self], b: &[Self], c: &mut [Self]);
    #[must_use]
    fn tanh(self) -> Self;
}

macro_rules! scalar {
    ($t:ty, $gemm:path, $tanh:path) => {
        impl Scalar for $t {
            const ZERO: Self = 0.0;

            fn gemm_acc(m: usize, k: usize, n: usize, a: &[Self], b: &[Self], c: &mut [Self]) {
                let fits = |len: usize, rows: usize, columns: usize| {
                    rows.checked_mul(columns).is_some_and(|size| len >= size)
                };
                assert!(
                    fits(a.len(), m, k) && fits(b.len(), k, n) && fits(c.len(), m, n),
                    "gemm_acc: slices too short"
                );
                // SAFETY: the lengths were checked above; strides describe dense row-major
                // matrices inside those slices, and `c` does not alias `a` or `b` (&mut).
                unsafe {
                    $gemm(
                        m,
                        k,
                        n,
                        1.0,
                        a.as_ptr(),
                        k as isize,
                        1,
                        b.as_ptr(),
                        n as isize,
                        1,
                        1.0,
                        c.as_mut_ptr(),
                        n as isize,
                        1,
                    );
                }
            }

            fn tanh(self) -> Self {
                $tanh(self)
            }
        }
    };
}

scalar!(f32, matrixmultiply::sgemm, tanh_f32);
scalar!(f64, matrixmultiply::dgemm, tanh_f64);

/// tanh in float32 within a few ulp (Eigen's rational approximation, `ptanh_float`): no libm
/// call and no branch, so the loop over a layer vectorises (libm's tanh cost 4x the GEMM).
#[must_use]
pub fn tanh_f32(x: f32) -> f32 {
    const CLAMP: f32 = 7.905_311;
    const A: [f32; 7] = [
        4.893_524_6e-3,
        6.372_619_3e-4,
        1.485_722_4e-5,
        5.122_297e-8,
        -8.604_672e-11,
        2.000_188e-13,
        -2.760_768_5e-16,
    ];
    const B: [f32; 4] = [4.893_525e-3, 2.268_434_6e-3, 1.185_347_1e-4, 1.198_258_4e-6];
    let c = x.clamp(-CLAMP, CLAMP);
    let c2 = c * c;
    let p = c
        * (A[0] + c2 * (A[1] + c2 * (A[2] + c2 * (A[3] + c2 * (A[4] + c2 * (A[5] + c2 * A[6]))))));
    let q = B[0] + c2 * (B[1] + c2 * (B[2] + c2 * B[3]));
    // Below 4e-4 tanh(x) = x to float32 precision (and the ratio would lose it).
    if x.abs() < 4e-4 {
        x
    } else {
        p / q
    }
}

/// tanh in float64 within ~2e-16 absolute and ~1e-15 relative: `(1 - e) / (1 + e)` with
/// `e = exp(-2|x|)` from a vectorisable exp, and the odd Taylor series below |x| = 0.1 where
/// `1 - e` would cancel. Branch-free for the same reason as [`tanh_f32`].
#[must_use]
pub fn tanh_f64(x: f64) -> f64 {
    // Taylor coefficients of tanh: x - x^3/3 + 2x^5/15 - 17x^7/315 + ...; at |x| = 0.1 the first
    // term left out (x^17) is below 1e-19.
    const T: [f64; 8] = [
        1.0,
        -1.0 / 3.0,
        2.0 / 15.0,
        -17.0 / 315.0,
        62.0 / 2835.0,
        -1382.0 / 155_925.0,
        21844.0 / 6_081_075.0,
        -929_569.0 / 638_512_875.0,
    ];
    // tanh(20) = 1 - 8e-18: 1 in float64. Not `min`, which would turn NaN into 20 (and
    // tanh(NaN) into 1: found by tests/ops/test_kernel_misuse.py).
    let a = if x.abs() > 20.0 { 20.0 } else { x.abs() };
    let e = exp_neg(-2.0 * a);
    let big = (1.0 - e) / (1.0 + e);
    let x2 = x * x;
    let small = x
        * (T[0]
            + x2 * (T[1]
                + x2 * (T[2] + x2 * (T[3] + x2 * (T[4] + x2 * (T[5] + x2 * (T[6] + x2 * T[7])))))));
    if a < 0.1 {
        small
    } else {
        big.copysign(x)
    }
}

/// `1/n!` for n = 0..=13: the Taylor coefficients of exp.
const fn inverse_factorials() -> [f64; 14] {
    let mut c = [1.0; 14];
    let mut n = 1;
    while n < 14 {
        c[n] = c[n - 1] / n as f64;
        n += 1;
    }
    c
}

/// exp(y) for y in [-40, 0] to ~1 ulp: y = k ln2 + r with |r| <= ln2 / 2, a degree-13 Taylor
/// polynomial for exp(r), and 2^k built in the exponent bits. The rounding of y / ln2 uses the
/// 1.5 * 2^52 trick instead of `round()`, which is a libm call without SSE4.1.
fn exp_neg(y: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    const C: [f64; 14] = inverse_factorials();
    let t = y * std::f64::consts::LOG2_E + MAGIC;
    let k = t - MAGIC;
    let r = (y - k * LN2_HI) - k * LN2_LO;
    let mut p = C[13];
    for c in C[..13].iter().rev() {
        p = p * r + c;
    }
    let k_int = t.to_bits() as i64 - MAGIC.to_bits() as i64;
    p * f64::from_bits(((k_int + 1023) << 52) as u64)
}

/// Check that the layers chain (each layer's inputs = the previous layer's outputs) and that
/// every slice has the length its shape says.
///
/// # Errors
/// `KernelError::Argument` naming `weights`, `biases` or `x` and the layer at fault.
pub fn check_layers<T>(layers: &[Layer<'_, T>], x_columns: usize) -> Result<()> {
    if layers.is_empty() {
        return Err(KernelError::argument(
            "weights",
            "a network needs at least one layer",
        ));
    }
    let mut previous = x_columns;
    for (i, layer) in layers.iter().enumerate() {
        if layer.inputs == 0 || layer.outputs == 0 {
            return Err(KernelError::argument("weights", format!("layer {i} has shape [{}, {}]: every layer needs at least one input and one output", layer.inputs, layer.outputs)));
        }
        if layer.inputs != previous {
            let what = if i == 0 {
                format!("`x` has {previous} columns")
            } else {
                format!("layer {} has {previous} outputs", i - 1)
            };
            let name = if i == 0 { "x" } else { "weights" };
            return Err(KernelError::argument(
                name,
                format!("layer {i} takes {} inputs but {what}", layer.inputs),
            ));
        }
        if layer.weights.len() != product("weights", layer.inputs, layer.outputs)? {
            return Err(KernelError::argument(
                "weights",
                format!(
                    "layer {i}: {} values for shape [{}, {}]",
                    layer.weights.len(),
                    layer.inputs,
                    layer.outputs
                ),
            ));
        }
        if layer.bias.len() != layer.outputs {
            return Err(KernelError::argument(
                "biases",
                format!(
                    "layer {i}: expected {} values, got {}",
                    layer.outputs,
                    layer.bias.len()
                ),
            ));
        }
        previous = layer.outputs;
    }
    Ok(())
}

/// Outputs `[rows, out]` of the network for inputs `x` `[rows, in]` (row-major).
///
/// Rows are independent, so the result does not depend on how the batch is cut into blocks or
/// threads (each row's arithmetic is the same in every block).
///
/// # Errors
/// `KernelError::Argument` when `x` is not `rows x in` or the layers do not chain (see
/// [`check_layers`]).
pub fn mlp_forward<T: Scalar>(x: &[T], rows: usize, layers: &[Layer<'_, T>]) -> Result<Vec<T>> {
    let inputs = layers.first().map_or(0, |l| l.inputs);
    check_layers(layers, inputs)?;
    if x.len() != product("x", rows, inputs)? {
        return Err(KernelError::argument(
            "x",
            format!("{} values for {rows} rows of {inputs} inputs", x.len()),
        ));
    }
    let outputs = layers[layers.len() - 1].outputs;
    let mut out = zeros("weights", product("weights", rows, outputs)?)?;
    if rows == 0 {
        return Ok(out);
    }
    let width = layers.iter().map(|l| l.outputs).max().unwrap_or(0);
    let buffers = || {
        (
            vec![T::ZERO; BLOCK_ROWS * width],
            vec![T::ZERO; BLOCK_ROWS * width],
        )
    };
    let block = |(a, b): &mut (Vec<T>, Vec<T>), (x_block, out_block): (&[T], &mut [T])| {
        forward_block(x_block, layers, a, b, out_block);
    };
    let flops_per_row: usize = layers.iter().map(|l| l.inputs * l.outputs).sum();
    // Parallel once there are two blocks and enough arithmetic to pay for waking threads.
    if rows > BLOCK_ROWS && rows.saturating_mul(flops_per_row) >= 1 << 20 {
        x.par_chunks(BLOCK_ROWS * inputs)
            .zip(out.par_chunks_mut(BLOCK_ROWS * outputs))
            .for_each_init(buffers, block);
    } else {
        let mut scratch = buffers();
        x.chunks(BLOCK_ROWS * inputs)
            .zip(out.chunks_mut(BLOCK_ROWS * outputs))
            .for_each(|pair| block(&mut scratch, pair));
    }
    Ok(out)
}

/// One block of rows through every layer; activations ping-pong between `a` and `b`, and the
/// last layer writes straight into `out`.
fn forward_block<T: Scalar>(
    x: &[T],
    layers: &[Layer<'_, T>],
    a: &mut [T],
    b: &mut [T],
    out: &mut [T],
) {
    let rows = x.len() / layers[0].inputs;
    let (mut current, mut next) = (a, b);
    for (i, layer) in layers.iter().enumerate() {
        let input: &[T] = if i == 0 {
            x
        } else {
            &current[..rows * layer.inputs]
        };
        let target: &mut [T] = if i + 1 == layers.len() {
            &mut *out
        } else {
            &mut next[..rows * layer.outputs]
        };
        for row in target.chunks_exact_mut(layer.outputs) {
            row.copy_from_slice(layer.bias);
        }
        T::gemm_acc(
            rows,
            layer.inputs,
            layer.outputs,
            input,
            layer.weights,
            target,
        );
        if layer.activation == Activation::Tanh {
            for v in target.iter_mut() {
                *v = v.tanh();
            }
        }
        std::mem::swap(&mut current, &mut next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layer<'a>(
        weights: &'a [f64],
        bias: &'a [f64],
        inputs: usize,
        activation: Activation,
    ) -> Layer<'a, f64> {
        Layer {
            weights,
            bias,
            inputs,
            outputs: bias.len(),
            activation,
        }
    }

    #[test]
    fn two_layers_by_hand() {
        // x [2, 2] -> tanh(x W1 + b1) [2, 3] -> (.) W2 + b2 [2, 1]
        let x = [1.0, 2.0, -1.0, 0.5];
        let w1 = [0.1, 0.2, 0.3, -0.4, 0.5, -0.6];
        let b1 = [0.0, 0.1, -0.1];
        let w2 = [1.0, -2.0, 0.5];
        let b2 = [0.25];
        let layers = [
            layer(&w1, &b1, 2, Activation::Tanh),
            layer(&w2, &b2, 3, Activation::Linear),
        ];
        let y = mlp_forward(&x, 2, &layers).unwrap();
        for (r, got) in y.iter().enumerate() {
            let xr = &x[2 * r..2 * r + 2];
            let h: Vec<f64> = (0..3)
                .map(|j| (xr[0] * w1[j] + xr[1] * w1[3 + j] + b1[j]).tanh())
                .collect();
            let expected = h[0] * w2[0] + h[1] * w2[1] + h[2] * w2[2] + b2[0];
            assert!(
                (got - expected).abs() < 1e-14,
                "row {r}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn blocks_and_threads_do_not_change_rows() {
        // 1000 rows cross the parallel threshold; each row must equal the row run alone.
        let (inputs, hidden) = (7, 33);
        let w1: Vec<f32> = (0..inputs * hidden)
            .map(|i| ((i * 37 % 101) as f32 / 50.0) - 1.0)
            .collect();
        let b1: Vec<f32> = (0..hidden).map(|i| i as f32 / 100.0).collect();
        let w2: Vec<f32> = (0..hidden * 5)
            .map(|i| ((i * 13 % 29) as f32 / 14.0) - 1.0)
            .collect();
        let b2 = [0.5f32; 5];
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
                outputs: 5,
                activation: Activation::Linear,
            },
        ];
        let x: Vec<f32> = (0..1000 * inputs)
            .map(|i| ((i * 7919 % 1000) as f32 / 500.0) - 1.0)
            .collect();
        let all = mlp_forward(&x, 1000, &layers).unwrap();
        for r in [0, 127, 128, 999] {
            let one = mlp_forward(&x[r * inputs..(r + 1) * inputs], 1, &layers).unwrap();
            for (a, b) in one.iter().zip(&all[r * 5..r * 5 + 5]) {
                assert!(
                    (a - b).abs() <= 1e-5 * (1.0 + b.abs()),
                    "row {r}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn fast_tanh_matches_libm() {
        let (mut worst32, mut worst64_abs, mut worst64_rel) = (0.0f64, 0.0f64, 0.0f64);
        for i in -400_000..=400_000 {
            let x = f64::from(i) * 5e-5 + if i % 3 == 0 { 1e-9 } else { 0.0 };
            let exact = x.tanh();
            let ours32 = f64::from(tanh_f32(x as f32));
            let exact32 = f64::from((x as f32).tanh());
            worst32 = worst32.max((ours32 - exact32).abs() / exact32.abs().max(1e-30));
            let ours = tanh_f64(x);
            worst64_abs = worst64_abs.max((ours - exact).abs());
            worst64_rel = worst64_rel.max((ours - exact).abs() / exact.abs().max(1e-300));
        }
        assert!(tanh_f64(f64::NAN).is_nan() && tanh_f32(f32::NAN).is_nan());
        for x in [0.0, -0.0, 1e-300, -1e-12, 30.0, -30.0, 1e6, f64::MAX] {
            assert!(
                (tanh_f64(x) - x.tanh()).abs() <= 1e-15 * x.tanh().abs().max(1e-300),
                "{x}"
            );
            assert!(
                (tanh_f32(x as f32) - (x as f32).tanh()).abs()
                    <= 1e-6 * (x as f32).tanh().abs().max(1e-30),
                "{x}"
            );
        }
        eprintln!("tanh errors: f32 rel {worst32:e}, f64 abs {worst64_abs:e} rel {worst64_rel:e}");
        assert!(worst32 < 1e-6, "float32 relative error {worst32}");
        assert!(
            worst64_abs < 5e-16 && worst64_rel < 2e-15,
            "float64 errors {worst64_abs} {worst64_rel}"
        );
    }

    #[test]
    fn zero_rows_give_an_empty_output() {
        let layers = [layer(&[1.0, 2.0], &[0.0, 0.0], 1, Activation::Tanh)];
        assert_eq!(mlp_forward(&[], 0, &layers).unwrap(), Vec::<f64>::new());
    }

    #[test]
    fn errors_name_the_argument_and_the_layer() {
        let w = [0.0; 6];
        let b3 = [0.0; 3];
        let b2 = [0.0; 2];
        let message = |r: Result<Vec<f64>>| r.unwrap_err().to_string();
        assert!(message(mlp_forward(&[0.0; 4], 2, &[])).contains("at least one layer"));
        let broken = [
            layer(&w, &b3, 2, Activation::Tanh),
            layer(&w, &b3, 2, Activation::Linear),
        ];
        let m = message(mlp_forward(&[0.0; 4], 2, &broken));
        assert!(
            m.contains("`weights`")
                && m.contains("layer 1 takes 2 inputs but layer 0 has 3 outputs"),
            "{m}"
        );
        let short_bias = [Layer {
            weights: &w,
            bias: &b2,
            inputs: 2,
            outputs: 3,
            activation: Activation::Tanh,
        }];
        assert!(message(mlp_forward(&[0.0; 4], 2, &short_bias)).contains("`biases`: layer 0"));
        let good = [layer(&w, &b3, 2, Activation::Tanh)];
        assert!(message(mlp_forward(&[0.0; 5], 2, &good)).contains("`x`"));
        assert!(Activation::parse("relu", 4)
            .unwrap_err()
            .to_string()
            .contains("layer 4"));
    }

    #[test]
    fn overflowing_or_unallocatable_shapes_are_errors() {
        let w = [0.0; 2];
        let huge = [Layer {
            weights: &w,
            bias: &w,
            inputs: usize::MAX / 2 + 1,
            outputs: 2,
            activation: Activation::Linear,
        }];
        assert!(mlp_forward(&[0.0; 2], 1, &huge).is_err());
        // A real 1 x 2 layer fed rows that overflow rows x inputs.
        let small = [layer(&w, &w[..2], 1, Activation::Linear)];
        assert!(mlp_forward(&[0.0; 2], usize::MAX, &small).is_err());
        // rows x outputs too big to allocate: an error, not an abort.
        let wide = [Layer {
            weights: &w,
            bias: &w,
            inputs: 1,
            outputs: 2,
            activation: Activation::Linear,
        }];
        assert!(mlp_forward::<f64>(&[], 0, &wide).unwrap().is_empty());
        assert!(crate::error::zeros::<f64>("x", usize::MAX / 4).is_err());
    }
}
