"""Dense networks as plain arrays (a list of ``(weights [in, out], bias [out])`` per layer):
initialisation, the forward and backward passes in NumPy (float64) and :func:`fit_lbfgs`, the
optimiser step every training stage of :mod:`.training` runs.

Full-batch L-BFGS (``scipy.optimize.minimize(method="L-BFGS-B", jac=True)``): it needs no
learning rate or schedule to tune, which keeps a training run reproducible and free of knobs.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Callable

import numpy as np

from .._utils.progress import line_log

Log = Callable[[str], None]
Params = list[tuple[np.ndarray, np.ndarray]]  # per layer (weights [in, out], bias [out])

stderr_log = line_log()  # progress lines on stderr, the running ones redrawn on a terminal


# --- networks as plain arrays: init, forward, backward, L-BFGS ---------------------------------


def init_params(rng: np.random.Generator, widths: Sequence[int]) -> Params:
    """Glorot-uniform weights and zero biases for layers ``widths[i] -> widths[i + 1]``."""
    params = []
    for a, b in zip(widths[:-1], widths[1:]):
        limit = np.sqrt(6.0 / (a + b))
        params.append((rng.uniform(-limit, limit, size=(a, b)), np.zeros(b)))
    return params


def forward_all(params: Params, activations: Sequence[str], x: np.ndarray) -> list[np.ndarray]:
    """Every layer's output ``[N, out_i]`` (input first), kept for the backward pass."""
    hs = [x]
    for (w, b), act in zip(params, activations):
        h = hs[-1] @ w + b
        hs.append(np.tanh(h, out=h) if act == "tanh" else h)
    return hs


def loss_and_grad(
    params: Params, activations: Sequence[str], x: np.ndarray, y: np.ndarray, weight_decay: float = 0.0
) -> tuple[float, Params]:
    """``mean((net(x) - y)^2) + weight_decay * sum(W^2)`` (biases not decayed) and its gradient,
    one ``(dW, db)`` per layer. ``x [N, in]``, ``y [N, out]``."""
    hs = forward_all(params, activations, x)
    error = hs[-1] - y
    loss = float(np.mean(error**2)) + weight_decay * sum(float(np.sum(w * w)) for w, _ in params)
    grad_h = error * (2.0 / error.size)
    grads: Params = []
    for i in range(len(params) - 1, -1, -1):
        w, _ = params[i]
        grad_a = grad_h * (1.0 - hs[i + 1] ** 2) if activations[i] == "tanh" else grad_h
        grads.append((hs[i].T @ grad_a + 2.0 * weight_decay * w, grad_a.sum(axis=0)))
        if i > 0:
            grad_h = grad_a @ w.T
    return loss, grads[::-1]


def _pack(params: Params) -> np.ndarray:
    return np.concatenate([a.ravel() for layer in params for a in layer])


def _unpack(flat: np.ndarray, like: Params) -> Params:
    out, start = [], 0
    for w, b in like:
        out.append((flat[start : start + w.size].reshape(w.shape), flat[start + w.size : start + w.size + b.size]))
        start += w.size + b.size
    return out


def fit_lbfgs(
    params: Params,
    activations: Sequence[str],
    x: np.ndarray,
    y: np.ndarray,
    *,
    max_iter: int,
    weight_decay: float,
    name: str,
    log: Log | None = stderr_log,
) -> tuple[Params, int]:
    """Minimise :func:`loss_and_grad` with L-BFGS from ``params``; returns the fitted
    parameters and the number of iterations run. Progress goes to ``log``: a running line
    (ending in ``\\r``) at each iteration with the time left, then the stage's last line."""
    from scipy.optimize import minimize

    state = {"loss": np.nan, "iter": 0, "start": time.perf_counter()}

    def objective(flat):
        loss, grads = loss_and_grad(_unpack(flat, params), activations, x, y, weight_decay)
        state["loss"] = loss
        return loss, _pack(grads)

    def progress(_flat):
        state["iter"] += 1
        if log:
            seconds = time.perf_counter() - state["start"]
            left = seconds / state["iter"] * (max_iter - state["iter"])
            log(
                f"{name}: iteration {state['iter']}/{max_iter}, loss {state['loss']:.4g}, {seconds:.1f} s, "
                f"at most {left:.0f} s left\r"
            )

    result = minimize(
        objective, _pack(params), jac=True, method="L-BFGS-B", callback=progress,
        options={"maxiter": max_iter, "maxcor": 20, "ftol": 1e-12, "gtol": 1e-9},
    )  # fmt: skip
    if log:
        log(
            f"{name}: {int(result.nit)} iterations, loss {state['loss']:.4g}, "
            f"{time.perf_counter() - state['start']:.1f} s"
        )
    return [(w.copy(), b.copy()) for w, b in _unpack(result.x, params)], int(result.nit)


__all__ = ["Log", "Params", "fit_lbfgs", "forward_all", "init_params", "loss_and_grad", "stderr_log"]
