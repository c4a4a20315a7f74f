"""Training the body-mechanics model (Boehs et al. III.B, IV): :func:`train_body_model` from
neutral clips to a :class:`~expressive_mocap.decoupling.body_model.BodyModel`, and under it
:func:`train_stacked_network`, the network on plain arrays.

Inputs ``X [N, 19]`` (the dynamic features of each frame), poses ``P [N, D]`` and ``groups [N]``
(a clip id per frame). Stages, each reported with train and test MSE on a 70/30 split by group
(no clip on both sides):

a. a denoising autoencoder on poses: ``P -> H tanh -> P`` (linear decoder), its input corrupted
   by masking 10-30% of the values and Gaussian noise;
b. a regression network ``X -> R tanh -> code`` onto the autoencoder's code (its tanh units);
c. the stack ``X -> R -> code -> decoder -> P``;
d. the stack fine-tuned end to end on ``(X, P)``;

plus the mean-pose baseline and a plain ``X -> H tanh -> P`` network for comparison. The result
is an :class:`~expressive_mocap.decoupling.network.Mlp` taking raw features and giving poses:
the z-scoring of ``X`` and the pose scaling are folded into its first and last layers, so inference (in Rust)
needs nothing else.

Optimiser: :func:`~expressive_mocap.decoupling.lbfgs.fit_lbfgs`, full-batch L-BFGS
(``scipy.optimize.minimize(method="L-BFGS-B", jac=True)``) on NumPy forward/backward passes in
float64. Full batch fits: 50k frames x 300 units is ~0.1 GB of
activations, and L-BFGS needs no learning rate or schedule to tune, which is what keeps a
training run reproducible and free of knobs. The denoising autoencoder's corruption is drawn
afresh for each of a few rounds (L-BFGS needs a fixed objective within a round).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from ..body.body import Body
from ..errors import ArgumentError
from ..motion import Motion
from ..rotations import quat
from .arms import arm_limbs
from .body_model import BodyModel, model_features, pose_vectors
from .features import FEATURE_NAMES
from .lbfgs import Log, Params, fit_lbfgs, init_params
from .lbfgs import stderr_log as _stderr
from .network import Layer, Mlp
from .pelvis import carried, find_pelvis
from .records import BodyModelSettings, Split, StageScores, TrainingReport
from .trunk import with_trunk

# --- splitting ---------------------------------------------------------------------------------


def split_by_group(groups, test_fraction: float = 0.3, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Row indices ``(train, test)``: whole groups go to one side, shuffled with ``seed``, test
    groups added until they hold ``test_fraction`` of the rows. ``groups [N]``: any hashable ids."""
    groups = np.asarray(groups)
    ids, inverse, counts = np.unique(groups, return_inverse=True, return_counts=True)
    if len(ids) < 2:
        raise ArgumentError(f"argument `groups`: a split by group needs at least 2 groups, got {len(ids)}")
    order = np.random.default_rng(seed).permutation(len(ids))
    cumulative = np.cumsum(counts[order])
    # Smallest number of groups reaching the fraction, leaving at least one group for training.
    n_test = int(np.clip(np.searchsorted(cumulative, test_fraction * len(groups)) + 1, 1, len(ids) - 1))
    is_test = np.zeros(len(ids), dtype=bool)
    is_test[order[:n_test]] = True
    test_rows = is_test[inverse.ravel()]
    return np.flatnonzero(~test_rows), np.flatnonzero(test_rows)


# --- normalisation folded into the network -----------------------------------------------------


def _zscore_stats(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean, std = a.mean(axis=0), a.std(axis=0)
    # Constant columns carry no information: leave them unscaled rather than divide by ~0.
    return mean, np.where(std > 1e-8 * max(float(std.max(initial=0.0)), 1e-300), std, 1.0)


def _fold_input(
    layer: tuple[np.ndarray, np.ndarray], mean: np.ndarray, std: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The layer acting on raw inputs that equals ``layer`` on ``(x - mean) / std``."""
    w, b = layer
    return w / std[:, None], b - (mean / std) @ w


def _fold_output(layer: tuple[np.ndarray, np.ndarray], mean: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The layer giving ``out * scale + mean`` where ``layer`` gave ``out``."""
    w, b = layer
    return w * scale, b * scale + mean


def _mlp(params: Params, activations: Sequence[str]) -> Mlp:
    return Mlp(Layer(w, b, act) for (w, b), act in zip(params, activations))


def corrupt(
    rng: np.random.Generator, z: np.ndarray, mask: tuple[float, float] = (0.1, 0.3), noise: float = 0.1
) -> np.ndarray:
    """Denoising input: per row a fraction drawn from ``mask`` of the values set to 0 (the mean,
    on z-scored poses), and Gaussian noise of std ``noise`` (in units of each column's std)."""
    fraction = rng.uniform(*mask, size=(len(z), 1))
    keep = rng.random(z.shape) >= fraction
    return z * keep + rng.normal(scale=noise, size=z.shape)


def _scores(predicted: np.ndarray, target: np.ndarray, variance: float) -> dict:
    mse = float(np.mean((predicted - target) ** 2))
    return {"mse": mse, "variance_explained": 1.0 - mse / variance if variance > 0 else float("nan")}


def _stage(
    net: Mlp,
    x: np.ndarray,
    y: np.ndarray,
    train: np.ndarray,
    test: np.ndarray,
    variance: float,
    *,
    seconds: float | None = None,
    hidden: int | None = None,
    iterations: int | None = None,
) -> StageScores:
    """Train and test MSE of ``net`` (run through the kernel backend, as at inference)."""
    tr, te = _scores(net(x[train]), y[train], variance), _scores(net(x[test]), y[test], variance)
    return StageScores(tr["mse"], te["mse"], te["variance_explained"], seconds, hidden, iterations)


# --- the stages --------------------------------------------------------------------------------


def train_autoencoder(
    poses: np.ndarray,
    hidden: int = 300,
    *,
    seed: int = 0,
    max_iter: int = 400,
    rounds: int = 4,
    mask: tuple[float, float] = (0.1, 0.3),
    noise: float = 0.1,
    weight_decay: float = 1e-6,
    log: Log | None = _stderr,
) -> Mlp:
    """Denoising autoencoder ``poses [N, D] -> H tanh -> [N, D]`` (linear decoder), as an
    :class:`Mlp` on raw poses (layer 0 the encoder, layer 1 the decoder).

    ``max_iter`` L-BFGS iterations in all, split over ``rounds`` with fresh corruption each.
    """
    poses = np.asarray(poses, dtype=np.float64)
    rng = np.random.default_rng(seed)
    mean, std = _zscore_stats(poses)
    scale = float(np.sqrt(np.mean(std**2)))  # one number: the loss keeps the weighting of the pose MSE
    z, target = (poses - mean) / std, (poses - mean) / scale
    params = init_params(rng, (poses.shape[1], hidden, poses.shape[1]))
    acts = ("tanh", "linear")
    for r in range(rounds):
        iters = max_iter // rounds + (r < max_iter % rounds)
        params, _ = fit_lbfgs(
            params,
            acts,
            corrupt(rng, z, mask, noise),
            target,
            max_iter=iters,
            weight_decay=weight_decay,
            name=f"autoencoder H={hidden} round {r + 1}/{rounds}",
            log=log,
        )
    return _mlp([_fold_input(params[0], mean, std), _fold_output(params[1], mean, scale)], acts)


# Long (about 130 lines, half of them its docstring): the four stages share the split, the
# scalings and the report, and read best in the order of the paper's section.
def train_stacked_network(
    X,
    P,
    groups,
    unlabelled_poses=None,
    hidden: int = 300,
    regression_hidden: int = 300,
    *,
    seed: int = 0,
    test_fraction: float = 0.3,
    max_iter: int = 400,
    weight_decay: float = 1e-6,
    mask: tuple[float, float] = (0.1, 0.3),
    noise: float = 0.1,
    compare_plain: bool = True,
    log: Log | None = _stderr,
) -> tuple[Mlp, TrainingReport]:
    """Train the stacked body-mechanics network; returns it and a report of every stage.

    Args:
        X: features ``[N, F]`` (19 per frame), raw: z-scored here, the statistics folded into
            the network.
        P: poses ``[N, D]``.
        groups: ``[N]`` clip id of each row; the 70/30 split (``test_fraction``) is by group.
        unlabelled_poses: ``[M, D]`` extra poses for the autoencoder (the paper's large
            unlabelled set). Default: the training split of ``P``. Keep test clips out of it,
            or the autoencoder's test score is not held out.
        hidden: the autoencoder's code units ``H``; regression_hidden: the regression's ``R``.
        max_iter: L-BFGS iterations of each stage.

    Returns:
        ``(net, report)``: ``net`` an :class:`Mlp` ``[F] -> R tanh -> H tanh -> [D]`` on raw
        features; ``report`` a :class:`~expressive_mocap.decoupling.records.TrainingReport`
        with, per stage (``mean_pose``, ``autoencoder``, ``regression`` (in code units),
        ``stack``, ``fine_tuned``, ``plain``), ``train_mse``, ``test_mse``,
        ``test_variance_explained`` and ``seconds``; plus ``split`` and ``test_variance`` (the
        mean per-column variance of the test poses).
    """
    X, P, groups = np.asarray(X, dtype=np.float64), np.asarray(P, dtype=np.float64), np.asarray(groups)
    if X.ndim != 2 or P.ndim != 2 or len(X) != len(P):
        raise ArgumentError(
            f"arguments `X`, `P`: expected [N, F] and [N, D] with the same N, got {list(X.shape)} and {list(P.shape)}"
        )
    if groups.shape != (len(X),):
        raise ArgumentError(f"argument `groups`: expected shape [{len(X)}], got {list(groups.shape)}")
    train, test = split_by_group(groups, test_fraction, seed)
    variance = float(np.mean(P[test].var(axis=0)))
    split = Split(len(train), len(test), len(np.unique(groups[train])), len(np.unique(groups[test])))
    report: dict[str, StageScores] = {}
    mean_pose = P[train].mean(axis=0)
    mean_pose_mse = float(np.mean((P[test] - mean_pose) ** 2))
    report["mean_pose"] = StageScores(
        float(np.mean((P[train] - mean_pose) ** 2)), mean_pose_mse, 1.0 - mean_pose_mse / variance
    )

    # (a) autoencoder
    start = time.perf_counter()
    ae_poses = P[train] if unlabelled_poses is None else np.asarray(unlabelled_poses, dtype=np.float64)
    ae = train_autoencoder(
        ae_poses, hidden, seed=seed, max_iter=max_iter, mask=mask, noise=noise, weight_decay=weight_decay, log=log
    )
    report["autoencoder"] = _stage(ae, P, P, train, test, variance, seconds=time.perf_counter() - start, hidden=hidden)

    # (b) regression from z-scored features to the code (the encoder's tanh units on clean poses)
    start = time.perf_counter()
    encoder, decoder = ae.layers
    x_mean, x_std = _zscore_stats(X[train])
    xz = (X - x_mean) / x_std
    code = Mlp([encoder])(P)
    rng = np.random.default_rng(seed + 1)
    reg_acts = ("tanh", "tanh")
    reg, _ = fit_lbfgs(
        init_params(rng, (X.shape[1], regression_hidden, hidden)),
        reg_acts,
        xz[train],
        code[train],
        max_iter=max_iter,
        name="regression",
        weight_decay=weight_decay,
        log=log,
    )
    report["regression"] = _stage(
        _mlp(reg, reg_acts),
        xz,
        code,
        train,
        test,
        float(np.mean(code[test].var(axis=0))),
        seconds=time.perf_counter() - start,
    )

    # (c) stack: regression layers then the decoder, on raw features
    stack_acts = ("tanh", "tanh", "linear")
    to_raw = lambda params: _mlp([_fold_input(params[0], x_mean, x_std), *params[1:]], stack_acts)  # noqa: E731
    stacked = [reg[0], reg[1], (decoder.weights, decoder.bias)]
    report["stack"] = _stage(to_raw(stacked), X, P, train, test, variance)

    # (d) fine-tune end to end, on z-scored features and poses scaled as in the autoencoder
    start = time.perf_counter()
    p_mean, p_scale = P[train].mean(axis=0), float(np.sqrt(np.mean(P[train].var(axis=0)))) or 1.0
    scaled = (P - p_mean) / p_scale
    unfold = _fold_output((decoder.weights, decoder.bias), -p_mean / p_scale, 1.0 / p_scale)
    tuned, iters = fit_lbfgs(
        [reg[0], reg[1], unfold],
        stack_acts,
        xz[train],
        scaled[train],
        max_iter=max_iter,
        name="fine-tuning",
        weight_decay=weight_decay,
        log=log,
    )
    tuned[2] = _fold_output(tuned[2], p_mean, p_scale)
    net = to_raw(tuned)
    report["fine_tuned"] = _stage(
        net, X, P, train, test, variance, seconds=time.perf_counter() - start, iterations=iters
    )

    if compare_plain:
        start = time.perf_counter()
        plain = train_plain(
            X[train], P[train], hidden, seed=seed, max_iter=max_iter, weight_decay=weight_decay, log=log
        )
        report["plain"] = _stage(plain, X, P, train, test, variance, seconds=time.perf_counter() - start, hidden=hidden)
    return net, TrainingReport(
        split, variance, report["mean_pose"], report["autoencoder"], report["regression"], report["stack"],
        report["fine_tuned"], report.get("plain"),
    )  # fmt: skip


def train_plain(
    X,
    P,
    hidden: int = 300,
    *,
    seed: int = 0,
    max_iter: int = 400,
    weight_decay: float = 1e-6,
    log: Log | None = _stderr,
) -> Mlp:
    """A plain ``X [N, F] -> H tanh -> P [N, D]`` network (the comparison for the stack), as an
    :class:`Mlp` on raw features."""
    X, P = np.asarray(X, dtype=np.float64), np.asarray(P, dtype=np.float64)
    x_mean, x_std = _zscore_stats(X)
    p_mean, p_scale = P.mean(axis=0), float(np.sqrt(np.mean(P.var(axis=0)))) or 1.0
    acts = ("tanh", "linear")
    params = init_params(np.random.default_rng(seed + 2), (X.shape[1], hidden, P.shape[1]))
    params, _ = fit_lbfgs(
        params,
        acts,
        (X - x_mean) / x_std,
        (P - p_mean) / p_scale,
        max_iter=max_iter,
        weight_decay=weight_decay,
        name=f"plain H={hidden}",
        log=log,
    )
    return _mlp([_fold_input(params[0], x_mean, x_std), _fold_output(params[1], p_mean, p_scale)], acts)


def sweep_autoencoder(
    P,
    groups,
    hiddens: Sequence[int] = (300, 150, 50, 15),
    *,
    seed: int = 0,
    test_fraction: float = 0.3,
    log: Log | None = _stderr,
    max_iter: int = 400,
    rounds: int = 4,
    mask: tuple[float, float] = (0.1, 0.3),
    noise: float = 0.1,
    weight_decay: float = 1e-6,
) -> dict[int, StageScores]:
    """Train and test MSE of the autoencoder for each hidden size (the paper's 300/150/50/15),
    trained on the training split of ``P`` by group. ``max_iter``, ``rounds``, ``mask``, ``noise``
    and ``weight_decay``: as :func:`train_autoencoder` takes them."""
    P = np.asarray(P, dtype=np.float64)
    train, test = split_by_group(groups, test_fraction, seed)
    variance = float(np.mean(P[test].var(axis=0)))
    results = {}
    for hidden in hiddens:
        start = time.perf_counter()
        ae = train_autoencoder(
            P[train], hidden, seed=seed, max_iter=max_iter, rounds=rounds, mask=mask, noise=noise,
            weight_decay=weight_decay, log=log,
        )  # fmt: skip
        results[hidden] = scores = _stage(ae, P, P, train, test, variance, seconds=time.perf_counter() - start)
        if log:
            log(f"autoencoder H={hidden}: train MSE {scores.train_mse:.3g}, test MSE {scores.test_mse:.3g}")
    return results


def format_report(report: TrainingReport) -> str:
    """The report as a small table: one line per stage (:meth:`TrainingReport.table`)."""
    return report.table()


def synthetic_data(n_groups: int = 30, frames: int = 50, n_in: int = 19, d: int = 80, latent: int = 6, seed: int = 0):
    """A known problem for tests and benchmarks: ``(X [N, n_in], P [N, d], groups [N])`` with
    ``P = tanh(X A) B + noise``, poses on a ``latent``-dimensional manifold, features smooth
    within each clip (a random walk from the clip's own start) and off-centre, so z-scoring matters."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_in, latent)) * 1.5 / np.sqrt(n_in)
    b = rng.normal(size=(latent, d)) * 0.1
    z = np.concatenate(
        [
            rng.normal(size=n_in) + np.cumsum(rng.normal(scale=0.15, size=(frames, n_in)), axis=0)
            for _ in range(n_groups)
        ]
    )
    poses = np.tanh(z @ a) @ b + rng.normal(scale=1e-3, size=(len(z), d))
    return z * 2.0 + 5.0, poses, np.repeat(np.arange(n_groups), frames)


# --- from clips to a body model ----------------------------------------------------------------


def train_body_model(
    neutral: Sequence[Motion],
    unlabelled: Sequence[Motion] = (),
    *,
    hidden: int = 300,
    regression_hidden: int = 300,
    unlabelled_frames: int = 40_000,
    seed: int = 0,
    max_iter: int = 400,
    log=None,
) -> BodyModel:
    """Train a body-mechanics model on ``neutral`` clips (one skeleton; 70/30 split by clip),
    its autoencoder also on up to ``unlabelled_frames`` frames drawn from ``unlabelled`` clips
    (any clip, expressive ones included; the neutral test clips are left out of it, so the test
    scores stay held out). Progress goes to ``log`` (a callable taking a line)."""
    if not neutral:
        raise ArgumentError("training needs at least two neutral clips")
    skeleton = neutral[0].skeleton
    for motion in list(neutral) + list(unlabelled):
        if motion.skeleton.names != skeleton.names:
            raise ArgumentError("every training clip must have the same skeleton (joint names) as the first")
    roles = Body.of(skeleton).roles
    predicted = np.array([j for j in range(skeleton.n_joints) if skeleton.parents[j] >= 0 and j != roles.hips])
    # The poses the network learns: each clip's spine as if its pelvis held the training clips' posture.
    pelvis = find_pelvis(skeleton, roles, [m.rotations for m in neutral])
    poses = [carried(m.rotations, pelvis, inverse=True) for m in neutral]
    rotations = np.concatenate(poses)
    hemispheres = quat.mean_rotation(rotations[:, predicted])
    thigh_reference = quat.mean_rotation(rotations[:, list(roles.upper_legs)])

    X = np.concatenate([model_features(m, thigh_reference) for m in neutral])
    P = np.concatenate([pose_vectors(r, predicted, hemispheres) for r in poses])
    groups = np.concatenate([np.full(m.n_frames, k) for k, m in enumerate(neutral)])
    # The same split train_stacked_network makes: its test clips stay out of the autoencoder and
    # of the feature range.
    train_rows, test_rows = split_by_group(groups, 0.3, seed)
    extra = None
    if unlabelled:
        test_clips = {_fingerprint(neutral[k]) for k in np.unique(groups[test_rows])}
        kept = [
            pose_vectors(carried(m.rotations, pelvis, inverse=True), predicted, hemispheres)
            for m in unlabelled
            if _fingerprint(m) not in test_clips
        ]
        pool = np.concatenate(kept) if kept else np.zeros((0, P.shape[1]))
        drawn = np.random.default_rng(seed).choice(len(pool), size=min(unlabelled_frames, len(pool)), replace=False)
        extra = np.concatenate([pool[drawn], P[train_rows]])
    network, report = train_stacked_network(
        X, P, groups, extra, hidden, regression_hidden, seed=seed, max_iter=max_iter, log=log
    )
    settings = BodyModelSettings(
        hidden=hidden,
        regression_hidden=regression_hidden,
        seed=seed,
        max_iter=max_iter,
        neutral_clips=len(neutral),
        neutral_frames=int(len(X)),
        unlabelled_clips=len(unlabelled),
        unlabelled_frames=0 if extra is None else int(len(extra)),
        features="causal; floor = 5th percentile of toe heights; thigh hemisphere = training mean",
        feature_range=FEATURE_RANGE,
    )
    parts = (tuple(skeleton.names), predicted, hemispheres, thigh_reference, network, settings, report)
    model = BodyModel(*parts, feature_range=feature_range(X[train_rows]), pelvis=pelvis, arms=arm_limbs(skeleton))
    return with_trunk(model, skeleton, [neutral[k] for k in np.unique(groups[test_rows])])


FEATURE_RANGE = "lowest and highest of the training clips' features; thigh rotations not limited"


def feature_range(features: np.ndarray) -> np.ndarray:
    """``[2, 19]``: the range of ``features [N, 19]`` (lowest, highest of each) a body model
    trusts its network with. Clipping inputs into it keeps the network from extrapolating to
    speeds, contacts, air times or hips heights it never saw (a sprint, a crouch; on the shipped
    model, measured in experiments/SESSIONS.md: less expressive motion left in another session's
    neutral locomotion). Not narrower (percentiles): standing frames are under 1% of the shipped
    model's walks and runs, and would be read as walking. The thigh rotations keep [-1, 1], all
    a quaternion component can be: the network predicts the thighs from them, so a clipped thigh
    would turn any stance beyond the training range, or another session's thighs, expressive."""
    low, high = features.min(axis=0), features.max(axis=0)
    thighs = [k for k, name in enumerate(FEATURE_NAMES) if name.startswith("thigh_")]
    low[thighs], high[thighs] = -1.0, 1.0
    return np.stack([low, high])


def _fingerprint(motion: Motion) -> tuple:
    """Identifies a clip read twice (from the neutral and the unlabelled lists)."""
    return motion.n_frames, motion.rotations[0].tobytes(), motion.rotations[-1].tobytes()


__all__ = [
    "FEATURE_RANGE",
    "corrupt",
    "feature_range",
    "format_report",
    "split_by_group",
    "sweep_autoencoder",
    "synthetic_data",
    "train_autoencoder",
    "train_body_model",
    "train_plain",
    "train_stacked_network",
]
