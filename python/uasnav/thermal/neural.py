"""Back-propagation neural network (BPNN) thermal model of gyro bias (thesis §4.2.3.1,
§4.2.5.2, §4.2.6.1): per axis a 1-n-n-1 network, tanh hidden layers, linear output, trained
by Levenberg–Marquardt.

Training follows the thesis (and MATLAB's ``trainlm`` it used): inputs mapped to [−1, 1]
over the calibrated range, outputs standardised; Nguyen–Widrow initial weights; the data
split 65/20/15 % uniformly over temperature; Levenberg–Marquardt steps
``(JᵀJ + μI) δ = Jᵀr`` with the analytic Jacobian and adaptive damping (μ ÷10 after a
successful step, ×10 after a failed one); early stopping when the validation error has not
improved for ``max_fail`` epochs (the best-validation weights are kept); several restarts,
keeping the one with the lowest validation error.

Inference goes through the Rust engine (``nav_core::mlp``) by default; :func:`forward` is
the NumPy reference it is tested against.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import jsoncheck as jc
from uasnav.errors import InputError, NumericalError
from uasnav.thermal._common import (
    BoolArray,
    FloatArray,
    NotFittedError,
    SelectionResult,
    check_fit_data,
    check_temp,
    choose,
    clip_temp,
    split_uniform,
    sr,
    subsample_uniform,
)
from uasnav.thermal.base import ModelDict, register_model
from uasnav.thermal.binning import bin_by_temperature
from uasnav.thermal.modelfile import dumps_model, save_model

#: Most neurons per hidden layer (the Rust engine's ``MAX_NEURONS``).
MAX_HIDDEN = 16
#: Largest weight or bias magnitude of a hidden layer in a model file. The network sees
#: normalised inputs (about ±1), so a weight of 10⁶ already turns a tanh into a step a millionth
#: of the calibrated range wide; larger ones (1e308: the model still predicts finite numbers,
#: silently a step function) are a corrupt or forged file, not a fit.
MAX_PARAMETER = 1e6


@dataclass
class Network:
    """Weights of one 1-n1-n2-1 network and its normalisation.

    ``u = in_gain·(T − in_offset)``; ``y = out_offset + out_scale·(w3·tanh(W2·tanh(W1·u + b1)
    + b2) + b3)``. Shapes: W1 (n1,), b1 (n1,), W2 (n2, n1), b2 (n2,), w3 (n2,), b3 float.
    """

    W1: FloatArray
    b1: FloatArray
    W2: FloatArray
    b2: FloatArray
    w3: FloatArray
    b3: float
    in_offset: float
    in_gain: float
    out_offset: float
    out_scale: float

    @property
    def n_params(self) -> int:
        return pack(self).size

    def to_dict(self) -> dict[str, Any]:
        """The network in the model-file layout (``layers`` weights are (out × in) lists)."""
        return {
            "input_norm": {"offset": self.in_offset, "scale": self.in_gain},
            "output_norm": {"offset": self.out_offset, "scale": self.out_scale},
            "layers": [
                {"activation": "tanh", "weights": self.W1[:, None].tolist(), "biases": self.b1.tolist()},
                {"activation": "tanh", "weights": self.W2.tolist(), "biases": self.b2.tolist()},
                {"activation": "linear", "weights": [self.w3.tolist()], "biases": [float(self.b3)]},
            ],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any], path: str = "model") -> Network:
        """Inverse of :meth:`to_dict` (two tanh hidden layers, linear output), every value
        checked (:class:`DataFormatError` naming its JSON path under ``path``): finite numbers,
        normalisation scales > 0, 1…:data:`MAX_HIDDEN` neurons per layer, consistent shapes."""
        d = jc.only(jc.obj(d, path), ("input_norm", "output_norm", "layers"), path)
        norms = []
        for key in ("input_norm", "output_norm"):
            q = jc.at(path, key)
            n = jc.only(jc.obj(jc.field(d, key, path), q), ("offset", "scale"), q)
            norms.append(
                (
                    jc.number(jc.field(n, "offset", q), jc.at(q, "offset")),
                    jc.number(jc.field(n, "scale", q), jc.at(q, "scale"), positive=True),
                )
            )
        lp = jc.at(path, "layers")
        layers = jc.array(jc.field(d, "layers", path), lp)
        if len(layers) != 3:
            raise jc.fail(lp, f"expected 3 layers (tanh, tanh, linear), got {len(layers)}")
        ws, bs = [], []
        fan_in = 1
        for i, (layer, act) in enumerate(zip(layers, ("tanh", "tanh", "linear"), strict=True)):
            q = jc.at(lp, i)
            e = jc.only(jc.obj(layer, q), ("activation", "weights", "biases"), q)
            jc.string(jc.field(e, "activation", q), jc.at(q, "activation"), (act,))
            top = 1 if i == 2 else MAX_HIDDEN
            # hidden layers only: the linear output layer's are bounded by the bias check at load
            lim = {"lo": -MAX_PARAMETER, "hi": MAX_PARAMETER} if i < 2 else {}
            b = jc.vector(jc.field(e, "biases", q), jc.at(q, "biases"), max_len=top, **lim)
            w = jc.matrix(jc.field(e, "weights", q), jc.at(q, "weights"), rows=b.size, cols=fan_in, **lim)
            ws.append(w)
            bs.append(b)
            fan_in = b.size
        if bs[2].size != 1:
            raise jc.fail(jc.at(jc.at(lp, 2), "biases"), f"the output layer has one neuron, got {bs[2].size}")
        return cls(
            W1=ws[0][:, 0].copy(),
            b1=bs[0],
            W2=ws[1],
            b2=bs[1],
            w3=ws[2][0].copy(),
            b3=float(bs[2][0]),
            in_offset=norms[0][0],
            in_gain=norms[0][1],
            out_offset=norms[1][0],
            out_scale=norms[1][1],
        )


def pack(net: Network) -> FloatArray:
    """Parameter vector ``[W1, b1, W2 (row-major), b2, w3, b3]``."""
    return np.concatenate([net.W1, net.b1, net.W2.ravel(), net.b2, net.w3, [net.b3]])


def unpack(p: FloatArray, n1: int, n2: int, like: Network) -> Network:
    """Inverse of :func:`pack` (normalisation copied from ``like``)."""
    i = 0

    def take(k: int) -> FloatArray:
        nonlocal i
        out = p[i : i + k]
        i += k
        return out

    W1, b1 = take(n1).copy(), take(n1).copy()
    W2 = take(n2 * n1).reshape(n2, n1).copy()
    b2, w3 = take(n2).copy(), take(n2).copy()
    b3 = float(take(1)[0])
    return Network(W1, b1, W2, b2, w3, b3, like.in_offset, like.in_gain, like.out_offset, like.out_scale)


def _hidden(net: Network, u: FloatArray) -> tuple[FloatArray, FloatArray]:
    a1 = np.tanh(np.outer(u, net.W1) + net.b1)
    a2 = np.tanh(a1 @ net.W2.T + net.b2)
    return a1, a2


def forward(net: Network, temp: FloatArray) -> tuple[FloatArray, FloatArray]:
    """NumPy reference: network output (n,) and its analytic derivative d/dT (n,) at temp (n,)
    °C, without clipping."""
    u = net.in_gain * (temp - net.in_offset)
    a1, a2 = _hidden(net, u)
    y = a2 @ net.w3 + net.b3
    d2 = (1.0 - a2**2) * net.w3  # ∂y/∂z2
    d1 = (d2 @ net.W2) * (1.0 - a1**2)  # ∂y/∂z1
    dy_du = d1 @ net.W1
    return net.out_offset + net.out_scale * y, net.out_scale * net.in_gain * dy_du


def _jacobian_into(net: Network, u: FloatArray, a1: FloatArray, a2: FloatArray, jac: FloatArray) -> None:
    """Analytic Jacobian ∂y/∂p (n, P) of the normalised output, in :func:`pack` order, written
    into ``jac`` from the forward pass's hidden activations (back-propagation per sample)."""
    n1, n2 = a1.shape[1], a2.shape[1]
    d2 = (1.0 - a2**2) * net.w3  # ∂y/∂z2
    d1 = (d2 @ net.W2) * (1.0 - a1**2)  # ∂y/∂z1
    np.multiply(d1, u[:, None], out=jac[:, :n1])
    jac[:, n1 : 2 * n1] = d1
    o = 2 * n1
    for j in range(n2):
        np.multiply(a1, d2[:, j : j + 1], out=jac[:, o + j * n1 : o + (j + 1) * n1])
    o += n2 * n1
    jac[:, o : o + n2] = d2
    jac[:, o + n2 : o + 2 * n2] = a2
    jac[:, -1] = 1.0


def _normalised_jacobian(net: Network, u: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Normalised output y(u) (n,) and analytic Jacobian ∂y/∂p (n, P) in :func:`pack` order."""
    a1, a2 = _hidden(net, u)
    jac = np.empty((u.size, pack(net).size))
    _jacobian_into(net, u, a1, a2, jac)
    return a2 @ net.w3 + net.b3, jac


def nguyen_widrow(n1: int, n2: int, rng: np.random.Generator) -> FloatArray:
    """Nguyen–Widrow initial parameters (pack order) for inputs in [−1, 1].

    Each hidden layer gets rows of norm β = 0.7·H^(1/N_in) (H neurons, N_in inputs) and biases
    uniform in [−β, β], spreading the neurons' active regions over the input interval; the
    output layer starts small and uniform in [−0.5, 0.5].
    """
    beta1 = 0.7 * n1
    w1 = beta1 * np.where(rng.uniform(-1, 1, n1) < 0, -1.0, 1.0)
    # Biases spread evenly over [−β, β] (with a little jitter) so the tanh transitions cover
    # the input interval, as MATLAB's initnw does for one input.
    b1 = (np.linspace(-beta1, beta1, n1) if n1 > 1 else np.zeros(1)) + rng.uniform(-0.1, 0.1, n1) * beta1
    beta2 = 0.7 * n2 ** (1.0 / n1)
    w2 = rng.uniform(-1, 1, (n2, n1))
    w2 *= beta2 / np.linalg.norm(w2, axis=1, keepdims=True)
    b2 = rng.uniform(-beta2, beta2, n2)
    w3 = rng.uniform(-0.5, 0.5, n2)
    b3 = rng.uniform(-0.5, 0.5, 1)
    return np.concatenate([w1, b1, w2.ravel(), b2, w3, b3])


@dataclass(frozen=True)
class TrainingRecord:
    """What one network's training did: epochs, stop reason, errors (normalised MSE)."""

    epochs: int
    stop: str
    train_mse: float
    val_mse: float
    test_mse: float
    restarts: int
    seconds: float


def train_lm(*args: Any, **kwargs: Any) -> tuple[Network, TrainingRecord]:
    """Train one 1-n-n-1 network by Levenberg–Marquardt (see :func:`_train_lm` for the
    parameters). BLAS runs single-threaded here: the products are tall and skinny (n × P with
    P = 13 for 1-2-2-1), gain nothing from threads and lose 2–3× to thread contention on a
    busy machine (measured: 5.7 s → 1.9 s per restart at n = 10⁵)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return _train_lm(*args, **kwargs)


def _train_lm(
    temp: FloatArray,
    target: FloatArray,
    hidden: int,
    *,
    range_c: tuple[float, float] | None = None,
    restarts: int = 3,
    max_epochs: int = 300,
    max_fail: int = 6,
    mu0: float = 1e-3,
    mu_max: float = 1e10,
    seed: int = 0,
    split_seed: int | None = None,
) -> tuple[Network, TrainingRecord]:
    """Train one 1-n-n-1 network on (temp (n,) °C, target (n,)) by Levenberg–Marquardt.

    Returns the network with the lowest validation error over ``restarts`` initialisations
    and its :class:`TrainingRecord`.
    """
    t0 = time.perf_counter()
    lo, hi = range_c if range_c is not None else (float(temp.min()), float(temp.max()))
    mean, std = float(np.mean(target)), float(np.std(target))
    if not std > 0:
        std = max(abs(mean), 1e-12)
    base = Network(
        np.zeros(hidden), np.zeros(hidden), np.zeros((hidden, hidden)), np.zeros(hidden), np.zeros(hidden),
        0.0, 0.5 * (lo + hi), 2.0 / (hi - lo), mean, std,
    )  # fmt: skip
    u = base.in_gain * (temp - base.in_offset)
    y = (target - mean) / std
    tr, va, te = split_uniform(temp, seed=seed if split_seed is None else split_seed)
    rng = np.random.default_rng(seed)
    best: tuple[float, FloatArray, TrainingRecord] | None = None
    P = nguyen_widrow(hidden, hidden, rng).size
    eye = np.eye(P)

    u_tr, y_tr, u_va, y_va = u[tr], y[tr], u[va], y[va]
    jac = np.empty((tr.size, P))

    def forward_n(p: FloatArray, uu: FloatArray) -> tuple[Network, FloatArray, FloatArray, FloatArray]:
        net = unpack(p, hidden, hidden, base)
        a1, a2 = _hidden(net, uu)
        return net, a1, a2, a2 @ net.w3 + net.b3

    def mse(p: FloatArray, idx: NDArray[np.intp]) -> float:
        out = forward_n(p, u[idx])[3]
        return float(np.mean((y[idx] - out) ** 2))

    for r in range(max(1, restarts)):
        p = nguyen_widrow(hidden, hidden, rng)
        mu = mu0
        best_val, best_p, fails = mse(p, va) if va.size else np.inf, p.copy(), 0
        stop, epoch = "max_epochs", 0
        # The forward pass of the accepted parameters is reused for the next Jacobian.
        state = forward_n(p, u_tr)
        for epoch in range(1, max_epochs + 1):  # noqa: B007
            net, a1, a2, out = state
            _jacobian_into(net, u_tr, a1, a2, jac)
            res = y_tr - out
            e0 = float(res @ res)
            jtj, jtr = jac.T @ jac, jac.T @ res
            if not np.isfinite(jtj).all():
                raise NumericalError("train_lm: Jacobian became non-finite")
            while True:
                try:
                    step = np.linalg.solve(jtj + mu * eye, jtr)
                except np.linalg.LinAlgError:
                    step = None
                if step is not None:
                    cand = p + step
                    cstate = forward_n(cand, u_tr)
                    r1 = y_tr - cstate[3]
                    if float(r1 @ r1) < e0:
                        p, mu, state = cand, max(mu / 10.0, 1e-20), cstate
                        break
                mu *= 10.0
                if mu > mu_max:
                    break
            if mu > mu_max:
                stop = "mu_max"
                break
            if float(np.linalg.norm(jtr)) < 1e-10 * tr.size:
                stop = "min_grad"
                break
            if va.size:
                rv = y_va - forward_n(p, u_va)[3]
                v = float(np.mean(rv**2))
                if v < best_val:
                    best_val, best_p, fails = v, p.copy(), 0
                else:
                    fails += 1
                    if fails >= max_fail:
                        stop = "validation"
                        break
            else:
                best_p = p.copy()
        rec = TrainingRecord(
            epochs=epoch,
            stop=stop,
            train_mse=mse(best_p, tr),
            val_mse=best_val if va.size else mse(best_p, tr),
            test_mse=mse(best_p, te) if te.size else float("nan"),
            restarts=r + 1,
            seconds=time.perf_counter() - t0,
        )
        if best is None or rec.val_mse < best[0]:
            best = (rec.val_mse, best_p, rec)
    assert best is not None
    rec = best[2]
    rec = TrainingRecord(rec.epochs, rec.stop, rec.train_mse, rec.val_mse, rec.test_mse, max(1, restarts),
                         time.perf_counter() - t0)  # fmt: skip
    return unpack(best[1], hidden, hidden, base), rec


@register_model
class NeuralBiasModel:
    """BPNN bias(T) per axis: 1-n-n-1, tanh hidden layers, linear output, LM-trained.

    Parameters
    ----------
    hidden : int
        Neurons per hidden layer n (1…16; the thesis selects 2).
    restarts : int
        Initialisations per axis; the lowest validation error wins.
    max_epochs, max_fail : int
        LM epoch limit and early-stopping patience (epochs without validation improvement).
    max_samples : int
        Training data beyond this many samples is subsampled evenly (LM cost is O(n·P²)).
    derivative_network : bool
        Also train the thesis' derivative networks (§4.2.6.1): networks fitted to ∂b/∂T
        estimated from the data binned every ``derivative_bin_c`` °C.
    derivative_bin_c : float
        Bin width (°C) for the data derivative.
    seed : int
        Seed of the split and the initial weights.
    engine : {"rust", "numpy"}
        Inference engine (the Rust ``nav_core::mlp`` or the NumPy reference).

    Attributes
    ----------
    networks_ : list of Network
        One per axis.
    derivative_networks_ : list of Network or None
    range_c_ : tuple of float
        Calibrated temperature range (°C).
    training_ : list of TrainingRecord
    """

    kind = "neural"

    def __init__(
        self,
        hidden: int = 2,
        *,
        restarts: int = 3,
        max_epochs: int = 300,
        max_fail: int = 6,
        max_samples: int = 100_000,
        derivative_network: bool = False,
        derivative_bin_c: float = 1.0,
        seed: int = 0,
        engine: str = "rust",
    ) -> None:
        self.hidden = hidden
        self.restarts = restarts
        self.max_epochs = max_epochs
        self.max_fail = max_fail
        self.max_samples = max_samples
        self.derivative_network = derivative_network
        self.derivative_bin_c = derivative_bin_c
        self.seed = seed
        self.engine = engine

    def fit(self, temp: ArrayLike, bias: ArrayLike) -> NeuralBiasModel:
        """Train one network per axis on temperatures (n,) °C and biases (n, k) rad/s."""
        if not (isinstance(self.hidden, int | np.integer) and 1 <= self.hidden <= MAX_HIDDEN):
            raise InputError(f"hidden: expected an integer in 1…{MAX_HIDDEN}, got {self.hidden!r}")
        # Bounds that keep training finite in time (restarts × epochs LM steps per axis).
        for name, lo, hi in (
            ("restarts", 1, 100),
            ("max_epochs", 1, 100_000),
            ("max_fail", 1, 100_000),
            ("max_samples", 20, 10_000_000),
            ("seed", 0, 2**63 - 1),
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | np.integer) or not lo <= v <= hi:
                raise InputError(f"{name}: expected an integer in {lo}…{hi}, got {v!r}")
        if not (np.isfinite(self.derivative_bin_c) and self.derivative_bin_c > 0):
            raise InputError(f"derivative_bin_c: expected a bin width > 0 °C, got {self.derivative_bin_c}")
        if self.engine not in ("rust", "numpy"):
            raise InputError(f"engine: expected 'rust' or 'numpy', got {self.engine!r}")
        t, b = check_fit_data(temp, bias, min_samples=20)
        keep = subsample_uniform(t.size, self.max_samples)
        t, b = t[keep], b[keep]
        self.range_c_ = (float(t.min()), float(t.max()))
        self.networks_, self.training_ = [], []
        for k in range(b.shape[1]):
            net, rec = train_lm(
                t, b[:, k], self.hidden, range_c=self.range_c_, restarts=self.restarts,
                max_epochs=self.max_epochs, max_fail=self.max_fail, seed=self.seed + k, split_seed=self.seed,
            )  # fmt: skip
            self.networks_.append(net)
            self.training_.append(rec)
        self.derivative_networks_: list[Network] | None = None
        if self.derivative_network:
            tc, db = data_derivative(t, b, self.derivative_bin_c)
            self.derivative_networks_ = [
                train_lm(tc, db[:, k], self.hidden, range_c=self.range_c_, restarts=self.restarts,
                         max_epochs=self.max_epochs, max_fail=self.max_fail, seed=self.seed + 100 + k,
                         split_seed=self.seed)[0]
                for k in range(db.shape[1])
            ]  # fmt: skip
        self._json: str | None = None
        return self

    def _check(self) -> None:
        if not hasattr(self, "networks_"):
            raise NotFittedError("NeuralBiasModel: call fit() or load_model() first")

    def model_json(self) -> str:
        """The model file text (cached; what the Rust engine parses)."""
        self._check()
        if getattr(self, "_json", None) is None:
            self._json = dumps_model(self)
        assert self._json is not None
        return self._json

    def _eval(self, temp: ArrayLike, derivative_networks: bool) -> tuple[FloatArray, FloatArray, BoolArray]:
        self._check()
        t = check_temp(temp)
        nets = self.derivative_networks_ if derivative_networks else self.networks_
        if nets is None:
            raise InputError("NeuralBiasModel: no derivative networks (fit with derivative_network=True)")
        tc, clipped = clip_temp(t, *self.range_c_, "NeuralBiasModel")
        if self.engine == "rust":
            from uasnav import _core

            v, d, _ = _core.mlp_evaluate_model(self.model_json(), t, True, derivative_networks)
            return v, d, clipped
        if self.engine != "numpy":
            raise InputError(f"engine: expected 'rust' or 'numpy', got {self.engine!r}")
        outs = [forward(n, tc) for n in nets]
        v = np.stack([o[0] for o in outs], axis=1)
        d = np.stack([o[1] for o in outs], axis=1)
        d[clipped] = 0.0
        return v, d, clipped

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[False] = ...) -> FloatArray: ...

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[True]) -> tuple[FloatArray, BoolArray]: ...

    def predict(
        self, temp: ArrayLike, *, return_clipped: bool = False
    ) -> FloatArray | tuple[FloatArray, BoolArray]:
        """Bias (n, k) rad/s at temperatures (n,) °C; clipped to the calibrated range with a
        :class:`TemperatureRangeWarning`; ``return_clipped`` adds the (n,) clip mask."""
        v, _, clipped = self._eval(temp, False)
        return (v, clipped) if return_clipped else v

    def derivative(self, temp: ArrayLike, *, method: str = "analytic") -> FloatArray:
        """∂bias/∂T (n, k) rad/s/°C: ``"analytic"`` differentiates the bias networks,
        ``"network"`` evaluates the networks trained on the data derivative (eq. 37)."""
        if method == "analytic":
            return self._eval(temp, False)[1]
        if method == "network":
            # Outside the calibrated range the clipped model is constant: its derivative is 0.
            v, _, clipped = self._eval(temp, True)
            v[clipped] = 0.0
            return v
        raise InputError(f"method: expected 'analytic' or 'network', got {method!r}")

    def to_dict(self) -> ModelDict:
        """The ``models`` / ``derivative_models`` entries of the model file."""
        self._check()
        return {
            "models": [n.to_dict() for n in self.networks_],
            "derivative_models": None
            if self.derivative_networks_ is None
            else [n.to_dict() for n in self.derivative_networks_],
        }

    @classmethod
    def from_dict(cls, d: ModelDict, range_c: tuple[float, float]) -> NeuralBiasModel:
        """Inverse of :meth:`to_dict`; every network checked by :meth:`Network.from_dict`."""
        models = jc.array(jc.field(d, "models"), "models")
        nets = [Network.from_dict(x, jc.at("models", i)) for i, x in enumerate(models)]
        m = cls(hidden=int(nets[0].b1.size))
        m.networks_ = nets
        dm = d.get("derivative_models")
        m.derivative_networks_ = (
            None
            if dm is None
            else [
                Network.from_dict(x, jc.at("derivative_models", i))
                for i, x in enumerate(jc.array(dm, "derivative_models"))
            ]
        )
        m.range_c_ = (float(range_c[0]), float(range_c[1]))
        m.training_ = []
        m._json = None
        return m

    def save(self, path: str | os.PathLike[str], training: ModelDict | None = None) -> None:
        """Write the model file atomically (see :mod:`uasnav.thermal.modelfile`)."""
        save_model(self, path, training=training)

    def __repr__(self) -> str:
        return f"NeuralBiasModel(hidden={self.hidden})"


def data_derivative(temp: FloatArray, bias: FloatArray, bin_c: float = 1.0) -> tuple[FloatArray, FloatArray]:
    """∂b/∂T of data: bias averaged in temperature bins of ``bin_c`` °C
    (:func:`uasnav.thermal.binning.bin_by_temperature`), then central differences between bin
    means (rad/s/°C) at the bins' mean temperatures (°C)."""
    tm, bm = bin_by_temperature(temp, bias, bin_c)
    if tm.size < 3:
        raise InputError(f"temp: span {np.ptp(temp):.2f} °C too small for derivative bins of {bin_c} °C")
    return tm, np.gradient(bm, tm, axis=0)


def select_hidden_neurons(
    temp: ArrayLike,
    bias: ArrayLike,
    candidates: tuple[int, ...] = tuple(range(1, 11)),
    *,
    rel_tol: float = 0.05,
    restarts: int = 2,
    max_samples: int = 5000,
    derivative: bool = False,
    derivative_bin_c: float = 1.0,
    seed: int = 0,
) -> SelectionResult:
    """Structure selection by Sr_NN (eq. 33), or Sr_TCZUPT (eq. 37) with ``derivative``.

    For each n, trains 1-n-n-1 networks per axis on the training subset and evaluates Sr on the
    held-out test subset (with ``derivative`` the target is the binned data derivative).
    """
    t, b = check_fit_data(temp, bias, min_samples=20)
    keep = subsample_uniform(t.size, max_samples)
    t, b = t[keep], b[keep]
    if derivative:
        t, b = data_derivative(t, b, derivative_bin_c)
    _, _, te = split_uniform(t, seed=seed)
    srs = []
    rng = (float(t.min()), float(t.max()))
    for n in candidates:
        res = np.empty((te.size, b.shape[1]))
        for k in range(b.shape[1]):
            net, _ = train_lm(t, b[:, k], n, range_c=rng, restarts=restarts, seed=seed + k, split_seed=seed)
            res[:, k] = b[te, k] - forward(net, t[te])[0]
        srs.append(sr(res))
    arr = np.asarray(srs)
    return SelectionResult(tuple(candidates), arr, choose(tuple(candidates), arr, rel_tol), rel_tol)
