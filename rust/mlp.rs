//! Batched inference of small multilayer perceptrons (dense layers, tanh or linear).
//!
//! A network is a list of layers `y = act(x W + b)` with `W` `[in, out]` (row-major, as NumPy
//! stores `x @ W`) and `b` `[out]`. The batch is cut into blocks of rows; each block runs through
//! every layer with one GEMM a layer (`matrixmultiply`), blocks in parallel with rayon. The same
//! code serves `f32` and `f64` through the small [`Scalar`] trait.

use rayon::prelude::*;

use crate::error::{KernelError, Result};

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
            other => Err(KernelError::argument("activations", format!("layer {layer}: unknown activation {other:?} (expected \"tanh\" or \"linear\")"))),
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
pub trait Scalar: Copy + Send + Sync + 'static {
    const ZERO: Self;
    /// `c = a b + c` with `a` `[m, k]`, `b` `[k, n]`, `c` `[m, n]`, all row-major and dense.
    fn gemm_acc(m: usize, k: usize, n: usize, a: &[Self], b: &[Self], c: &mut [Self]);
    #[must_use]
    fn tanh(self) -> Self;
}

macro_rules! scalar {
    ($t:ty, $gemm:path) => {
        impl Scalar for $t {
            const ZERO: Self = 0.0;

            fn gemm_acc(m: usize, k: usize, n: usize, a: &[Self], b: &[Self], c: &mut [Self]) {
                assert!(a.len() >= m * k && b.len() >= k * n && c.len() >= m * n, "gemm_acc: slices too short");
                // SAFETY: the lengths were checked above; strides describe dense row-major
                // matrices inside those slices, and `c` does not alias `a` or `b` (&mut).
                unsafe {
                    $gemm(m, k, n, 1.0, a.as_ptr(), k as isize, 1, b.as_ptr(), n as isize, 1, 1.0, c.as_mut_ptr(), n as isize, 1);
                }
            }

            fn tanh(self) -> Self {
                <$t>::tanh(self)
            }
        }
    };
}

scalar!(f32, matrixmultiply::sgemm);
scalar!(f64, matrixmultiply::dgemm);

/// Check that the layers chain (each layer's inputs = the previous layer's outputs) and that
/// every slice has the length its shape says.
///
/// # Errors
/// `KernelError::Argument` naming `weights`, `biases` or `x` and the layer at fault.
pub fn check_layers<T>(layers: &[Layer<'_, T>], x_columns: usize) -> Result<()> {
    if layers.is_empty() {
        return Err(KernelError::argument("weights", "a network needs at least one layer"));
    }
    let mut previous = x_columns;
    for (i, layer) in layers.iter().enumerate() {
        if layer.inputs == 0 || layer.outputs == 0 {
            return Err(KernelError::argument("weights", format!("layer {i} has shape [{}, {}]: every layer needs at least one input and one output", layer.inputs, layer.outputs)));
        }
        if layer.inputs != previous {
            let what = if i == 0 { format!("`x` has {previous} columns") } else { format!("layer {} has {previous} outputs", i - 1) };
            let name = if i == 0 { "x" } else { "weights" };
            return Err(KernelError::argument(name, format!("layer {i} takes {} inputs but {what}", layer.inputs)));
        }
        if layer.weights.len() != layer.inputs * layer.outputs {
            return Err(KernelError::argument("weights", format!("layer {i}: {} values for shape [{}, {}]", layer.weights.len(), layer.inputs, layer.outputs)));
        }
        if layer.bias.len() != layer.outputs {
            return Err(KernelError::argument("biases", format!("layer {i}: expected {} values, got {}", layer.outputs, layer.bias.len())));
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
    if x.len() != rows * inputs {
        return Err(KernelError::argument("x", format!("{} values for {rows} rows of {inputs} inputs", x.len())));
    }
    let outputs = layers[layers.len() - 1].outputs;
    let mut out = vec![T::ZERO; rows * outputs];
    if rows == 0 {
        return Ok(out);
    }
    let width = layers.iter().map(|l| l.outputs).max().unwrap_or(0);
    let buffers = || (vec![T::ZERO; BLOCK_ROWS * width], vec![T::ZERO; BLOCK_ROWS * width]);
    let block = |(a, b): &mut (Vec<T>, Vec<T>), (x_block, out_block): (&[T], &mut [T])| {
        forward_block(x_block, layers, a, b, out_block);
    };
    let flops_per_row: usize = layers.iter().map(|l| l.inputs * l.outputs).sum();
    // Parallel once there are two blocks and enough arithmetic to pay for waking threads.
    if rows > BLOCK_ROWS && rows * flops_per_row >= 1 << 20 {
        x.par_chunks(BLOCK_ROWS * inputs).zip(out.par_chunks_mut(BLOCK_ROWS * outputs)).for_each_init(buffers, block);
    } else {
        let mut scratch = buffers();
        x.chunks(BLOCK_ROWS * inputs).zip(out.chunks_mut(BLOCK_ROWS * outputs)).for_each(|pair| block(&mut scratch, pair));
    }
    Ok(out)
}

/// One block of rows through every layer; activations ping-pong between `a` and `b`, and the
/// last layer writes straight into `out`.
fn forward_block<T: Scalar>(x: &[T], layers: &[Layer<'_, T>], a: &mut [T], b: &mut [T], out: &mut [T]) {
    let rows = x.len() / layers[0].inputs;
    let (mut current, mut next) = (a, b);
    for (i, layer) in layers.iter().enumerate() {
        let input: &[T] = if i == 0 { x } else { &current[..rows * layer.inputs] };
        let target: &mut [T] = if i + 1 == layers.len() { &mut *out } else { &mut next[..rows * layer.outputs] };
        for row in target.chunks_exact_mut(layer.outputs) {
            row.copy_from_slice(layer.bias);
        }
        T::gemm_acc(rows, layer.inputs, layer.outputs, input, layer.weights, target);
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

    fn layer<'a>(weights: &'a [f64], bias: &'a [f64], inputs: usize, activation: Activation) -> Layer<'a, f64> {
        Layer { weights, bias, inputs, outputs: bias.len(), activation }
    }

    #[test]
    fn two_layers_by_hand() {
        // x [2, 2] -> tanh(x W1 + b1) [2, 3] -> (.) W2 + b2 [2, 1]
        let x = [1.0, 2.0, -1.0, 0.5];
        let w1 = [0.1, 0.2, 0.3, -0.4, 0.5, -0.6];
        let b1 = [0.0, 0.1, -0.1];
        let w2 = [1.0, -2.0, 0.5];
        let b2 = [0.25];
        let layers = [layer(&w1, &b1, 2, Activation::Tanh), layer(&w2, &b2, 3, Activation::Linear)];
        let y = mlp_forward(&x, 2, &layers).unwrap();
        for (r, got) in y.iter().enumerate() {
            let xr = &x[2 * r..2 * r + 2];
            let h: Vec<f64> = (0..3).map(|j| (xr[0] * w1[j] + xr[1] * w1[3 + j] + b1[j]).tanh()).collect();
            let expected = h[0] * w2[0] + h[1] * w2[1] + h[2] * w2[2] + b2[0];
            assert!((got - expected).abs() < 1e-14, "row {r}: {got} vs {expected}");
        }
    }

    #[test]
    fn blocks_and_threads_do_not_change_rows() {
        // 1000 rows cross the parallel threshold; each row must equal the row run alone.
        let (inputs, hidden) = (7, 33);
        let w1: Vec<f32> = (0..inputs * hidden).map(|i| ((i * 37 % 101) as f32 / 50.0) - 1.0).collect();
        let b1: Vec<f32> = (0..hidden).map(|i| i as f32 / 100.0).collect();
        let w2: Vec<f32> = (0..hidden * 5).map(|i| ((i * 13 % 29) as f32 / 14.0) - 1.0).collect();
        let b2 = [0.5f32; 5];
        let layers = [
            Layer { weights: &w1, bias: &b1, inputs, outputs: hidden, activation: Activation::Tanh },
            Layer { weights: &w2, bias: &b2, inputs: hidden, outputs: 5, activation: Activation::Linear },
        ];
        let x: Vec<f32> = (0..1000 * inputs).map(|i| ((i * 7919 % 1000) as f32 / 500.0) - 1.0).collect();
        let all = mlp_forward(&x, 1000, &layers).unwrap();
        for r in [0, 127, 128, 999] {
            let one = mlp_forward(&x[r * inputs..(r + 1) * inputs], 1, &layers).unwrap();
            for (a, b) in one.iter().zip(&all[r * 5..r * 5 + 5]) {
                assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "row {r}: {a} vs {b}");
            }
        }
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
        let broken = [layer(&w, &b3, 2, Activation::Tanh), layer(&w, &b3, 2, Activation::Linear)];
        let m = message(mlp_forward(&[0.0; 4], 2, &broken));
        assert!(m.contains("`weights`") && m.contains("layer 1 takes 2 inputs but layer 0 has 3 outputs"), "{m}");
        let short_bias = [Layer { weights: &w, bias: &b2, inputs: 2, outputs: 3, activation: Activation::Tanh }];
        assert!(message(mlp_forward(&[0.0; 4], 2, &short_bias)).contains("`biases`: layer 0"));
        let good = [layer(&w, &b3, 2, Activation::Tanh)];
        assert!(message(mlp_forward(&[0.0; 5], 2, &good)).contains("`x`"));
        assert!(Activation::parse("relu", 4).unwrap_err().to_string().contains("layer 4"));
    }
}
