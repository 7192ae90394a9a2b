//! Fixed-size multilayer perceptron (MLP) inference with the analytic input derivative
//! (thesis §4.2.3.1 and §4.2.6.1: the back-propagation network that models gyro bias against
//! temperature, and its derivative ∂b/∂T used by the TCZUPT filter).
//!
//! The networks are small, scalar-in / scalar-out: one input (temperature, °C), one or two
//! hidden layers of at most [`MAX_NEURONS`] neurons (tanh, logistic or linear), one output
//! neuron (usually linear). Input and output are normalised by affine maps:
//!
//! ```text
//! u  = gain_in · (x − offset_in)                 normalised input
//! a₁ = f₁(W₁ u + b₁),  a₂ = f₂(W₂ a₁ + b₂)        hidden layers
//! v  = g(w₃ · a₂ + b₃)                            normalised output
//! y  = offset_out + scale_out · v
//! ```
//!
//! The derivative dy/dx is propagated forward alongside the value (forward-mode
//! differentiation, one pass): `ȧ₁ = f₁'(z₁) ⊙ W₁ · gain_in`, `ȧ₂ = f₂'(z₂) ⊙ (W₂ ȧ₁)`,
//! `ẏ = scale_out · g'(z₃) · (w₃ · ȧ₂)`, with `tanh' = 1 − tanh²`, `σ' = σ(1 − σ)`.
//!
//! Storage is fixed-size (`[T; 16]`, `[[T; 16]; 16]`): evaluation never allocates and never
//! panics, so it runs per sample on a microcontroller. Weights come either from slices (e.g.
//! `const` arrays compiled into firmware, see [`Mlp::new`]) or, with the `std` feature, from
//! the uasnav thermal-model JSON file ([`json`]).
use crate::{NavError, Real};
use num_traits::Float;

/// Maximum number of neurons per hidden layer.
pub const MAX_NEURONS: usize = 16;
/// Maximum number of hidden layers.
pub const MAX_HIDDEN_LAYERS: usize = 2;

/// Transfer function of a layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activation {
    /// Hyperbolic tangent ("tan-sigmoid"), exact (libm).
    Tanh,
    /// Logistic sigmoid `1 / (1 + e^{−z})` ("log-sigmoid").
    Logistic,
    /// Identity ("linear").
    Linear,
    /// Opt-in fast tanh: the [7/6] Padé approximant
    /// `x(135135 + 17325x² + 378x⁴ + x⁶) / (135135 + 62370x² + 3150x⁴ + 28x⁶)`, saturated to ±1
    /// for |x| ≥ 4.97. Maximum absolute error [`FAST_TANH_MAX_ERROR`] (at |x| ≈ 4.97; below
    /// 1e-9 for |x| < 1.5), derivative `1 − a²` off by at most twice that. Never chosen
    /// implicitly: only [`Mlp::with_fast_tanh`] or an explicit layer spec selects it.
    TanhFast,
}

/// Maximum absolute error of [`Activation::TanhFast`] against the exact tanh (tested on a
/// dense grid over ±20).
pub const FAST_TANH_MAX_ERROR: f64 = 9.7e-5;

#[inline(always)]
fn tanh_pade<T: Real>(z: T) -> T {
    let one = T::one();
    let sat = crate::scalar::lit::<T>(4.97);
    if z >= sat {
        return one;
    }
    if z <= -sat {
        return -one;
    }
    let l = crate::scalar::lit::<T>;
    let z2 = z * z;
    let num = z * (l(135135.0) + z2 * (l(17325.0) + z2 * (l(378.0) + z2)));
    let den = l(135135.0) + z2 * (l(62370.0) + z2 * (l(3150.0) + l(28.0) * z2));
    let a = num / den;
    // The approximant overshoots 1 by < 1e-4 just below the saturation point.
    if a > one {
        one
    } else if a < -one {
        -one
    } else {
        a
    }
}

impl Activation {
    /// Value and derivative of the transfer function at `z`.
    #[inline(always)]
    fn eval<T: Real>(self, z: T) -> (T, T) {
        match self {
            Activation::Tanh => {
                let a = Float::tanh(z);
                (a, T::one() - a * a)
            }
            Activation::Logistic => {
                let a = T::one() / (T::one() + Float::exp(-z));
                (a, a * (T::one() - a))
            }
            Activation::Linear => (z, T::one()),
            Activation::TanhFast => {
                let a = tanh_pade(z);
                (a, T::one() - a * a)
            }
        }
    }

    /// Parses the names used in the model file (`"tanh"`, `"logistic"`, `"linear"`; MATLAB's
    /// `"tansig"`, `"logsig"`, `"purelin"` are accepted too).
    pub fn from_name(name: &str) -> Result<Self, NavError> {
        match name {
            "tanh" | "tansig" => Ok(Activation::Tanh),
            "logistic" | "logsig" | "sigmoid" => Ok(Activation::Logistic),
            "linear" | "purelin" | "identity" => Ok(Activation::Linear),
            _ => Err(NavError::InvalidParameter {
                what: "activation",
                reason: "unknown activation (expected tanh, logistic or linear)",
            }),
        }
    }
}

/// An affine map `y = offset + scale·x` (output side) or `u = gain·(x − offset)` (input side).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Affine<T> {
    /// Offset, in the physical unit (°C on the input side, rad/s on the output side).
    pub offset: T,
    /// Gain (input side: 1/°C) or scale (output side: rad/s per normalised unit).
    pub scale: T,
}

impl<T: Real> Affine<T> {
    /// The identity map.
    pub fn identity() -> Self {
        Affine {
            offset: T::zero(),
            scale: T::one(),
        }
    }
}

/// One layer given as borrowed slices, e.g. from `const` arrays.
#[derive(Debug, Clone, Copy)]
pub struct LayerSpec<'a, T> {
    /// Weights, row-major `(outputs × inputs)`: `weights[j * inputs + i]` connects input `i`
    /// to neuron `j`.
    pub weights: &'a [T],
    /// Biases ("thresholds"), one per neuron.
    pub biases: &'a [T],
    /// Transfer function of the layer.
    pub activation: Activation,
}

/// Value and input derivative of a network at one input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MlpOutput<T> {
    /// Network output y(x) (output unit, e.g. rad/s).
    pub value: T,
    /// dy/dx (output unit per input unit, e.g. rad/s/°C).
    pub derivative: T,
    /// True if the input was outside the calibrated range and was clipped to it
    /// ([`Mlp::eval_clipped`] only; always false from [`Mlp::eval`]).
    pub clipped: bool,
}

/// A scalar-in / scalar-out MLP with one or two hidden layers of ≤ [`MAX_NEURONS`] neurons.
#[derive(Debug, Clone, PartialEq)]
pub struct Mlp<T> {
    n1: usize,
    n2: usize,
    w1: [T; MAX_NEURONS],
    b1: [T; MAX_NEURONS],
    f1: Activation,
    w2: [[T; MAX_NEURONS]; MAX_NEURONS],
    b2: [T; MAX_NEURONS],
    f2: Activation,
    w3: [T; MAX_NEURONS],
    b3: T,
    g: Activation,
    input: Affine<T>,
    output: Affine<T>,
    range: (T, T),
}

fn bad(what: &'static str, reason: &'static str) -> NavError {
    NavError::InvalidParameter { what, reason }
}

impl<T: Real> Mlp<T> {
    /// Builds a network from its layers (1 or 2 hidden layers followed by the 1-neuron output
    /// layer), the input and output normalisation and the calibrated input range
    /// `(min, max)` (input unit, °C for thermal models).
    ///
    /// Every weight must be finite and the shapes consistent; otherwise an
    /// [`NavError::InvalidParameter`] / [`NavError::LengthMismatch`] / [`NavError::NonFinite`]
    /// names the offending part.
    pub fn new(
        layers: &[LayerSpec<'_, T>],
        input: Affine<T>,
        output: Affine<T>,
        range: (T, T),
    ) -> Result<Self, NavError> {
        if layers.len() < 2 || layers.len() > MAX_HIDDEN_LAYERS + 1 {
            return Err(bad(
                "layers",
                "expected 1 or 2 hidden layers plus one output layer",
            ));
        }
        let z = T::zero();
        let mut m = Mlp {
            n1: 0,
            n2: 0,
            w1: [z; MAX_NEURONS],
            b1: [z; MAX_NEURONS],
            f1: layers[0].activation,
            w2: [[z; MAX_NEURONS]; MAX_NEURONS],
            b2: [z; MAX_NEURONS],
            f2: Activation::Linear,
            w3: [z; MAX_NEURONS],
            b3: z,
            g: layers[layers.len() - 1].activation,
            input,
            output,
            range,
        };
        for l in layers {
            crate::error::check_finite("layer weights", l.weights)?;
            crate::error::check_finite("layer biases", l.biases)?;
        }
        crate::error::check_finite("normalisation", &[input.offset, input.scale])?;
        crate::error::check_finite("normalisation", &[output.offset, output.scale])?;
        crate::error::check_finite("range", &[range.0, range.1])?;
        if range.0 > range.1 {
            return Err(bad("range", "minimum exceeds maximum"));
        }
        // First hidden layer: one input.
        let h1 = &layers[0];
        let n1 = h1.biases.len();
        if n1 == 0 || n1 > MAX_NEURONS {
            return Err(bad("hidden layer 1", "needs 1 to 16 neurons"));
        }
        if h1.weights.len() != n1 {
            return Err(NavError::LengthMismatch {
                what: "hidden layer 1 weights (n1 × 1)",
                expected: n1,
                got: h1.weights.len(),
            });
        }
        m.n1 = n1;
        m.w1[..n1].copy_from_slice(h1.weights);
        m.b1[..n1].copy_from_slice(h1.biases);
        // Second hidden layer, if any. With one hidden layer we store it as an identity
        // layer so that evaluation has one code path.
        let last_hidden = if layers.len() == 3 {
            let h2 = &layers[1];
            let n2 = h2.biases.len();
            if n2 == 0 || n2 > MAX_NEURONS {
                return Err(bad("hidden layer 2", "needs 1 to 16 neurons"));
            }
            if h2.weights.len() != n2 * n1 {
                return Err(NavError::LengthMismatch {
                    what: "hidden layer 2 weights (n2 × n1)",
                    expected: n2 * n1,
                    got: h2.weights.len(),
                });
            }
            for j in 0..n2 {
                m.w2[j][..n1].copy_from_slice(&h2.weights[j * n1..(j + 1) * n1]);
            }
            m.b2[..n2].copy_from_slice(h2.biases);
            m.f2 = h2.activation;
            n2
        } else {
            for j in 0..n1 {
                m.w2[j][j] = T::one();
            }
            n1
        };
        m.n2 = last_hidden;
        let out = &layers[layers.len() - 1];
        if out.biases.len() != 1 {
            return Err(bad("output layer", "must have exactly one neuron"));
        }
        if out.weights.len() != last_hidden {
            return Err(NavError::LengthMismatch {
                what: "output layer weights (1 × n)",
                expected: last_hidden,
                got: out.weights.len(),
            });
        }
        m.w3[..last_hidden].copy_from_slice(out.weights);
        m.b3 = out.biases[0];
        Ok(m)
    }

    /// The same network with its tanh layers evaluated by [`Activation::TanhFast`] (opt-in
    /// speed for a documented accuracy cost, see [`FAST_TANH_MAX_ERROR`]).
    pub fn with_fast_tanh(mut self) -> Self {
        for f in [&mut self.f1, &mut self.f2, &mut self.g] {
            if *f == Activation::Tanh {
                *f = Activation::TanhFast;
            }
        }
        self
    }

    /// Neurons per hidden layer `(n1, n2)` (`n2 == n1` for a one-hidden-layer network).
    pub fn hidden_sizes(&self) -> (usize, usize) {
        (self.n1, self.n2)
    }

    /// Calibrated input range `(min, max)` (input unit).
    pub fn range(&self) -> (T, T) {
        self.range
    }

    /// Output and dy/dx at `x` (input unit), without clipping: the raw network, also outside
    /// the calibrated range. One forward pass; no allocation.
    #[inline]
    pub fn eval(&self, x: T) -> MlpOutput<T> {
        let u = self.input.scale * (x - self.input.offset);
        let du = self.input.scale;
        let z = T::zero();
        let mut a1 = [z; MAX_NEURONS];
        let mut d1 = [z; MAX_NEURONS];
        for j in 0..self.n1 {
            let (a, fp) = self.f1.eval(self.w1[j] * u + self.b1[j]);
            a1[j] = a;
            d1[j] = fp * self.w1[j] * du;
        }
        let mut zo = self.b3;
        let mut dzo = z;
        for j in 0..self.n2 {
            let mut s = self.b2[j];
            let mut ds = z;
            let row = &self.w2[j];
            for i in 0..self.n1 {
                s += row[i] * a1[i];
                ds += row[i] * d1[i];
            }
            let (a, fp) = self.f2.eval(s);
            zo += self.w3[j] * a;
            dzo += self.w3[j] * fp * ds;
        }
        let (v, gp) = self.g.eval(zo);
        MlpOutput {
            value: self.output.offset + self.output.scale * v,
            derivative: self.output.scale * gp * dzo,
            clipped: false,
        }
    }

    /// Like [`Mlp::eval`] but the input is clipped to the calibrated range (never
    /// extrapolates): outside it the value is held at the boundary, the derivative of the
    /// clipped model is 0, and `clipped` is set. A NaN input is an error.
    #[inline]
    pub fn eval_clipped(&self, x: T) -> Result<MlpOutput<T>, NavError> {
        if !Float::is_finite(x) {
            return Err(NavError::NonFinite {
                what: "mlp input",
                index: 0,
            });
        }
        if x < self.range.0 || x > self.range.1 {
            let xc = if x < self.range.0 {
                self.range.0
            } else {
                self.range.1
            };
            let o = self.eval(xc);
            return Ok(MlpOutput {
                value: o.value,
                derivative: T::zero(),
                clipped: true,
            });
        }
        Ok(self.eval(x))
    }

    /// Evaluates a batch: `value[k]`, `derivative[k]` at `x[k]`; with `clip` the inputs are
    /// clipped to the calibrated range and the number of clipped samples is returned.
    pub fn eval_batch(
        &self,
        x: &[T],
        value: &mut [T],
        derivative: &mut [T],
        clip: bool,
    ) -> Result<usize, NavError> {
        if value.len() != x.len() {
            return Err(NavError::LengthMismatch {
                what: "value buffer",
                expected: x.len(),
                got: value.len(),
            });
        }
        if derivative.len() != x.len() {
            return Err(NavError::LengthMismatch {
                what: "derivative buffer",
                expected: x.len(),
                got: derivative.len(),
            });
        }
        let mut n_clipped = 0;
        for (k, &xk) in x.iter().enumerate() {
            let o = if clip {
                self.eval_clipped(xk).map_err(|_| NavError::NonFinite {
                    what: "mlp input",
                    index: k,
                })?
            } else {
                self.eval(xk)
            };
            n_clipped += usize::from(o.clipped);
            value[k] = o.value;
            derivative[k] = o.derivative;
        }
        Ok(n_clipped)
    }
}

#[cfg(feature = "std")]
pub mod json;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    // A 1-2-2-1 network with arbitrary, non-symmetric weights.
    const W1: [f64; 2] = [0.8, -1.3];
    const B1: [f64; 2] = [0.1, 0.4];
    const W2: [f64; 4] = [0.5, -0.7, 1.1, 0.3];
    const B2: [f64; 2] = [-0.2, 0.05];
    const W3: [f64; 2] = [1.5, -0.6];
    const B3: [f64; 1] = [0.02];

    fn net(act: Activation) -> Mlp<f64> {
        Mlp::new(
            &[
                LayerSpec {
                    weights: &W1,
                    biases: &B1,
                    activation: act,
                },
                LayerSpec {
                    weights: &W2,
                    biases: &B2,
                    activation: act,
                },
                LayerSpec {
                    weights: &W3,
                    biases: &B3,
                    activation: Activation::Linear,
                },
            ],
            Affine {
                offset: 10.0,
                scale: 0.05,
            },
            Affine {
                offset: 1e-3,
                scale: 2e-4,
            },
            (-20.0, 40.0),
        )
        .unwrap()
    }

    /// Closed form of the same network written out by hand.
    fn by_hand(x: f64) -> f64 {
        let u = 0.05 * (x - 10.0);
        let h1 = [(0.8 * u + 0.1).tanh(), (-1.3 * u + 0.4).tanh()];
        let h2 = [
            (0.5 * h1[0] - 0.7 * h1[1] - 0.2).tanh(),
            (1.1 * h1[0] + 0.3 * h1[1] + 0.05).tanh(),
        ];
        1e-3 + 2e-4 * (1.5 * h2[0] - 0.6 * h2[1] + 0.02)
    }

    #[test]
    fn matches_closed_form() {
        let m = net(Activation::Tanh);
        for &x in &[-20.0, -3.3, 0.0, 17.0, 33.3, 40.0] {
            let o = m.eval(x);
            assert!((o.value - by_hand(x)).abs() < 1e-16, "x = {x}");
        }
    }

    #[test]
    fn single_hidden_linear_network_is_affine() {
        // Linear hidden layer: y = 3 + 2·(4·(x − 1) + 0.5) → slope 8 everywhere.
        let m = Mlp::new(
            &[
                LayerSpec {
                    weights: &[4.0],
                    biases: &[0.5],
                    activation: Activation::Linear,
                },
                LayerSpec {
                    weights: &[2.0],
                    biases: &[0.0],
                    activation: Activation::Linear,
                },
            ],
            Affine {
                offset: 1.0,
                scale: 1.0,
            },
            Affine {
                offset: 3.0,
                scale: 1.0,
            },
            (0.0, 10.0),
        )
        .unwrap();
        let o = m.eval(2.0);
        assert_eq!(o.value, 3.0 + 2.0 * (4.0 + 0.5));
        assert_eq!(o.derivative, 8.0);
        assert_eq!(m.hidden_sizes(), (1, 1));
    }

    #[test]
    fn logistic_derivative_closed_form() {
        // y = σ(x): dy/dx = σ(1 − σ); at 0 → 0.5, 0.25.
        let m = Mlp::new(
            &[
                LayerSpec {
                    weights: &[1.0],
                    biases: &[0.0],
                    activation: Activation::Logistic,
                },
                LayerSpec {
                    weights: &[1.0],
                    biases: &[0.0],
                    activation: Activation::Linear,
                },
            ],
            Affine::identity(),
            Affine::identity(),
            (-1.0, 1.0),
        )
        .unwrap();
        let o = m.eval(0.0);
        assert!((o.value - 0.5).abs() < 1e-15 && (o.derivative - 0.25).abs() < 1e-15);
    }

    #[test]
    fn fast_tanh_error_is_as_documented() {
        let mut worst: f64 = 0.0;
        let mut worst_small: f64 = 0.0;
        for i in -200_000..=200_000 {
            let x = f64::from(i) * 1e-4;
            let e = (tanh_pade(x) - x.tanh()).abs();
            worst = worst.max(e);
            if x.abs() < 1.5 {
                worst_small = worst_small.max(e);
            }
        }
        assert!(
            worst <= FAST_TANH_MAX_ERROR && worst > 0.9 * FAST_TANH_MAX_ERROR,
            "{worst}"
        );
        assert!(worst_small < 1e-9, "{worst_small}");
        // Whole network: output error bounded by the propagated activation error.
        let exact = net(Activation::Tanh);
        let fast = net(Activation::Tanh).with_fast_tanh();
        for i in -20..=40 {
            let x = f64::from(i);
            let (a, b) = (exact.eval(x), fast.eval(x));
            // |Δy| ≤ scale_out·Σ|w3|·(ε + Σ|W2|·ε) with the test weights: 2e-4·2.1·3.6·ε.
            assert!((a.value - b.value).abs() < 2e-4 * 2.1 * 3.6 * FAST_TANH_MAX_ERROR);
            assert!((a.derivative - b.derivative).abs() < 1e-6 * a.derivative.abs().max(1e-6));
        }
    }

    #[test]
    fn clipping_holds_boundary_and_flags() {
        let m = net(Activation::Tanh);
        let o = m.eval_clipped(55.0).unwrap();
        assert!(o.clipped);
        assert_eq!(o.value, m.eval(40.0).value);
        assert_eq!(o.derivative, 0.0);
        let inside = m.eval_clipped(20.0).unwrap();
        assert!(!inside.clipped);
        assert!(m.eval_clipped(f64::NAN).is_err());
        let x = [0.0, 50.0, -30.0];
        let (mut v, mut d) = ([0.0; 3], [0.0; 3]);
        assert_eq!(m.eval_batch(&x, &mut v, &mut d, true).unwrap(), 2);
        assert!(m.eval_batch(&x, &mut v[..2], &mut d, true).is_err());
    }

    #[test]
    fn rejects_bad_shapes() {
        let l = |w: &'static [f64], b: &'static [f64]| LayerSpec {
            weights: w,
            biases: b,
            activation: Activation::Tanh,
        };
        let id = Affine::identity();
        assert!(Mlp::new(&[l(&[1.0], &[0.0])], id, id, (0.0, 1.0)).is_err());
        assert!(Mlp::new(
            &[l(&[1.0, 2.0], &[0.0]), l(&[1.0], &[0.0])],
            id,
            id,
            (0.0, 1.0)
        )
        .is_err());
        assert!(Mlp::new(
            &[l(&[1.0], &[0.0]), l(&[1.0], &[0.0, 1.0])],
            id,
            id,
            (0.0, 1.0)
        )
        .is_err());
        assert!(Mlp::new(
            &[l(&[f64::NAN], &[0.0]), l(&[1.0], &[0.0])],
            id,
            id,
            (0.0, 1.0)
        )
        .is_err());
        assert!(Mlp::new(&[l(&[1.0], &[0.0]), l(&[1.0], &[0.0])], id, id, (1.0, 0.0)).is_err());
        let big = [0.0; 17];
        assert!(Mlp::new(
            &[
                LayerSpec {
                    weights: &big,
                    biases: &big,
                    activation: Activation::Tanh
                },
                l(&[1.0], &[0.0])
            ],
            id,
            id,
            (0.0, 1.0)
        )
        .is_err());
        assert!(Activation::from_name("relu").is_err());
        assert_eq!(Activation::from_name("tansig"), Ok(Activation::Tanh));
    }

    #[test]
    fn f32_agrees_with_f64() {
        let to32 = |a: &[f64]| a.iter().map(|&v| v as f32).collect::<std::vec::Vec<_>>();
        let (w1, b1, w2, b2, w3, b3) = (
            to32(&W1),
            to32(&B1),
            to32(&W2),
            to32(&B2),
            to32(&W3),
            to32(&B3),
        );
        let m32 = Mlp::<f32>::new(
            &[
                LayerSpec {
                    weights: &w1,
                    biases: &b1,
                    activation: Activation::Tanh,
                },
                LayerSpec {
                    weights: &w2,
                    biases: &b2,
                    activation: Activation::Tanh,
                },
                LayerSpec {
                    weights: &w3,
                    biases: &b3,
                    activation: Activation::Linear,
                },
            ],
            Affine {
                offset: 10.0,
                scale: 0.05,
            },
            Affine {
                offset: 1e-3,
                scale: 2e-4,
            },
            (-20.0, 40.0),
        )
        .unwrap();
        let m64 = net(Activation::Tanh);
        for &x in &[-10.0f32, 5.0, 30.0] {
            let a = m32.eval(x);
            let b = m64.eval(f64::from(x));
            assert!((f64::from(a.value) - b.value).abs() < 1e-9);
            assert!((f64::from(a.derivative) - b.derivative).abs() < 1e-9);
        }
    }

    proptest! {
        #[test]
        fn derivative_matches_central_difference(
            x in -25.0f64..45.0,
            act in prop_oneof![Just(Activation::Tanh), Just(Activation::Logistic)],
        ) {
            let m = net(act);
            let h = 1e-4;
            let fd = (m.eval(x + h).value - m.eval(x - h).value) / (2.0 * h);
            let d = m.eval(x).derivative;
            // Central difference error O(h²·y''') plus rounding ~1e-16·|y|/h.
            prop_assert!((d - fd).abs() < 1e-10 + 1e-6 * d.abs(), "d = {d}, fd = {fd}");
        }

        #[test]
        fn random_weights_derivative(
            w in proptest::collection::vec(-3.0f64..3.0, 3 * 3 + 3 * 3 + 3 + 3 + 3 + 1),
            x in -5.0f64..5.0,
        ) {
            let (w1, rest) = w.split_at(3);
            let (b1, rest) = rest.split_at(3);
            let (w2, rest) = rest.split_at(9);
            let (b2, rest) = rest.split_at(3);
            let (w3, b3) = rest.split_at(3);
            let b3 = &b3[..1];
            let m = Mlp::new(
                &[
                    LayerSpec { weights: w1, biases: b1, activation: Activation::Tanh },
                    LayerSpec { weights: w2, biases: b2, activation: Activation::Tanh },
                    LayerSpec { weights: w3, biases: b3, activation: Activation::Linear },
                ],
                Affine::identity(),
                Affine::identity(),
                (-5.0, 5.0),
            ).unwrap();
            let h = 1e-5;
            let fd = (m.eval(x + h).value - m.eval(x - h).value) / (2.0 * h);
            prop_assert!((m.eval(x).derivative - fd).abs() < 1e-7);
        }
    }
}
