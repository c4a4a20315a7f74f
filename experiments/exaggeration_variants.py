"""Readings of the paper (Davis & Kannappan) that the defaults could have taken differently, each
measured with the full validation table on the Bandai-Namco dataset-2 walks (CC BY-NC 4.0;
the same people and intensities as experiments/exaggeration_experiment.py). Prints one line per
variant and cycle choice; experiments/exaggeration_experiment.py writes the same measurements into
experiments/EXAGGERATION.md ("Readings checked against the paper").

    PYTHONPATH=python python experiments/exaggeration_variants.py [DATA_DIR] [VARIANT ...]
    PYTHONPATH=python python experiments/exaggeration_variants.py [DATA_DIR] --cycles all middle 0 -2

Each variant swaps one piece of the module for the alternative reading (monkeypatched here, the
package is unchanged) and runs train, swap_test, leave_one_out and rank_agreement as the
experiment does.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import sys
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np

import expressive_mocap.exaggeration as ex
import expressive_mocap.exaggeration.fitting as ex_fit
from expressive_mocap.rotations import quat

sys.path.insert(0, str(Path(__file__).resolve().parent))
from exaggeration_experiment import DEFAULT_DATA, LEVELS, PEOPLE, STYLES, clip  # noqa: E402

# Where each patchable piece is defined; a patch replaces it in every module of the package that uses it.
HOMES = {
    "fit": "fitting",
    "rotations_to_dofs": "dofs",
    "dofs_to_rotations": "dofs",
    "_key_set": "fitting",
    "subtree_weights": "dofs",
}
ORIGINAL = {name: getattr(sys.modules[f"expressive_mocap.exaggeration.{home}"], name) for name, home in HOMES.items()}


def make_fit(
    weighting: str = "s",
    over: str = "kept",
    observe: str = "kept",
    height_weight: float | None = None,
    samples: str = "cycles",
):
    """``fit`` with predictability weighted by ``s`` / ``s2`` (eigenvalues) of the ``kept`` vectors or
    of ``all`` of them and measured over every ``cycles`` or over the ``performances`` (each the mean
    of its cycles), observability over the ``kept`` basis or ``all`` vectors, and optionally the hips
    height DOF's weight replaced (a factor of the default)."""

    def fit(trajectories, levels, weights, *, cycles=None, share=0.9, energy=0.99, rank=None, degree=1):
        if samples == "performances":
            cycles = None
        out = ORIGINAL["fit"](
            trajectories, levels, weights, cycles=cycles, share=share, energy=energy, rank=rank, degree=degree
        )
        P, K, T, D = trajectories.shape
        levels = np.asarray(levels, dtype=np.float64)
        w = weights.copy()
        if height_weight is not None:
            w[-1] *= height_weight
        A = trajectories.transpose(2, 0, 1, 3).reshape(T, P * K * D)
        U, s, _ = np.linalg.svd(A, full_matrices=False)
        r = out.basis.shape[1]
        Uo = U if observe == "all" else U[:, :r]
        Co = np.einsum("tr,pktd->pkdr", Uo, trajectories)
        observability = np.linalg.norm(Co[:, 0] - Co[:, -1], axis=-1) * w
        n = len(s) if over == "all" else r
        rho = ex_fit._cycle_correlation(
            U[:, :n], ex_fit._single_cycles(trajectories) if cycles is None else cycles, levels, P
        )
        weight = s[:n] ** (2 if weighting == "s2" else 1)
        predictability = np.abs(rho) @ (weight / weight.sum())
        E = observability * predictability**2
        sums = E.sum(axis=1, keepdims=True)
        E = np.where(sums > 0, E / np.where(sums > 0, sums, 1.0), 0.0)
        person_key = np.stack([ex_fit._key_set(e, share) for e in E])
        return replace(out, expressiveness=E, overall=E.mean(axis=0), key=person_key.any(axis=0), person_key=person_key)

    return fit


def right_to_dofs(rotations, reference, representation, orders):
    """Rotation vector of ``q m^-1`` (the deviation in the parent's frame) instead of ``m^-1 q``."""
    return quat.log(quat.mul(rotations, quat.conjugate(reference)[None])).reshape(len(rotations), -1)


def right_to_rotations(dofs, reference, representation, orders):
    dofs = dofs.reshape(len(dofs), -1, 3)
    return quat.mul(quat.exp(dofs), reference[None])


def children_weights(skeleton):
    """``w_j``: the lengths of joint ``j``'s own bones only (to its children and End Sites), the
    paper's literal "sum of bone lengths of the joint's children", instead of the whole subtree."""
    weights = np.zeros(skeleton.n_joints)
    for j, off in skeleton.end_sites:
        weights[j] += float(np.linalg.norm(off))
    for j in range(1, skeleton.n_joints):
        weights[skeleton.parents[j]] += float(np.linalg.norm(skeleton.offsets[j]))
    return weights


def key_before_crossing(values, share):
    """The key set without the DOF that crosses ``share`` (every DOF whose cumulative sum stays below it)."""
    order = np.argsort(-values)
    reached = int(np.searchsorted(np.cumsum(values[order]), share - 1e-12))
    key = np.zeros(len(values), dtype=bool)
    key[order[:reached]] = True
    return key & (values > 0)


# name: (what is read differently, module patches, train options)
VARIANTS = {
    "default": ("our reading of the paper, as implemented", {}, {}),
    "P-over-performances": (
        "predictability over the performances (each the mean of its cycles) instead of over every cycle",
        {"fit": make_fit(samples="performances")},
        {},
    ),
    "mean-right": (
        "rotation vector of `q m^-1` (deviation in the parent's frame) instead of `m^-1 q`",
        {"rotations_to_dofs": right_to_dofs, "dofs_to_rotations": right_to_rotations},
        {},
    ),
    "euler": (
        "Euler channels relative to the mean (the package's option) instead of rotation vectors",
        {},
        {"representation": "euler"},
    ),
    "P-eigenvalues": (
        "predictability weighted by `s_i^2` (the paper's "
        "'eigenvalue-weighted', eigenvalues of `A A^T`) instead of `s_i`",
        {"fit": make_fit("s2")},
        {},
    ),
    "P-all-vectors": (
        "predictability summed over all 50 basis vectors instead of the kept `r`",
        {"fit": make_fit("s", over="all")},
        {},
    ),
    "P-all-eigenvalues": ("both of the above", {"fit": make_fit("s2", over="all")}, {}),
    "O-all-vectors": (
        "observability over all 50 basis vectors (the whole trajectory difference) instead of the kept `r`",
        {"fit": make_fit(observe="all")},
        {},
    ),
    "height-weight-0": (
        "hips height DOF weight 0 instead of the hips' subtree (no weight is defined for it)",
        {"fit": make_fit(height_weight=0.0)},
        {},
    ),
    "children-weights": (
        "`w_j` = the joint's own bones only (the paper's literal 'bone "
        "lengths of the joint's children') instead of the whole subtree",
        {"subtree_weights": children_weights},
        {},
    ),
    "no-crossing-DOF": (
        "key set stops before the DOF that crosses the share instead of including it",
        {"_key_set": key_before_crossing},
        {},
    ),
    "energy-0.95": ("basis keeps 95% of `sum(s^2)` instead of 99%", {}, {"energy": 0.95}),
    "energy-0.999": ("basis keeps 99.9% of `sum(s^2)` instead of 99%", {}, {"energy": 0.999}),
}


def _package_modules() -> list:
    return [m for n, m in list(sys.modules.items()) if n == ex.__name__ or n.startswith(ex.__name__ + ".")]


def _swap(name: str, old, new) -> None:
    """``name`` rebound from ``old`` to ``new`` in every module of the package that holds ``old``."""
    for module in _package_modules():
        if getattr(module, name, None) is old:
            setattr(module, name, new)


@contextmanager
def patched(names: dict):
    try:
        for name, value in names.items():
            _swap(name, ORIGINAL[name], value)
        yield
    finally:
        for name, value in names.items():
            _swap(name, value, ORIGINAL[name])


def measure(people, name: str = "default", cycle="all") -> dict:
    """Train with variant ``name`` and run the validation: the numbers of one row."""
    _, patches, options = VARIANTS[name]
    with patched(patches):
        model = ex.train(people, LEVELS, cycle=cycle, **options)
        swaps = ex.swap_test(model)
        warps = ex.leave_one_out(model)
        agreement = ex.rank_agreement(model)
    person, union = swaps[:-1], swaps[-1]
    return {
        "share": [r.share for r in person],
        "ratio": [r.ratio for r in person],
        "random": [r.random for r in person],
        "best": [r.best for r in person],
        "union": union,
        "warp": float(np.mean([w.ratio for w in warps])),
        "warp_positions": float(np.mean([w.ratio_positions for w in warps])),
        "spearman": agreement.mean,
        "height_key": bool(model.key[-1]),
    }


def span(values, fmt="{:.3f}") -> str:
    return f"{fmt.format(min(values))}-{fmt.format(max(values))}"


def summary(m: dict) -> str:
    u = m["union"]
    return (
        f"per person {span([100 * v for v in m['share']], '{:.0f}')}% ratio {span(m['ratio'])} "
        f"(random {span(m['random'])}, best {span(m['best'])}) | union {u.swapped} ({u.share:.0%}) "
        f"ratio {u.ratio:.3f} (random {u.random:.3f}, best {u.best:.3f}) pos. {u.ratio_positions:.3f} "
        f"(random {u.random_positions:.3f}, best {u.best_positions:.3f}) | warp {m['warp']:.3f} pos. "
        f"{m['warp_positions']:.3f} | Spearman {m['spearman']:.3f} | height key {m['height_key']}"
    )


def main() -> None:
    args = sys.argv[1:]
    data = Path(args.pop(0)) if args and Path(args[0]).is_dir() else DEFAULT_DATA
    cycles = ("all", "middle")
    if args and args[0] == "--cycles":  # the default method on other cycle choices
        args.pop(0)
        cycles = tuple(int(c) if c.lstrip("-").isdigit() else c for c in args)
        args = ["default"]
    names = args or list(VARIANTS)
    people = [[clip(data, f"walk_{s}_{p:03d}") for s in STYLES] for p in range(1, PEOPLE + 1)]
    for name in names:
        for cycle in cycles:
            print(f"{name:<18} {cycle!s:<6} {summary(measure(people, name, cycle))}", flush=True)


if __name__ == "__main__":
    main()
