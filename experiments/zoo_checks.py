"""The shipped exaggeration models on another capture session's check clips: which model each
gets, and what the walks model does to its walks.

    python experiments/zoo_checks.py [--data DIR]

Dataset-1 (another session, other actors) holds clips no model was trained or tuned on: its
forward walks, runs, dashes and one-hand waves (`bye`, `byebye`), 15 styles each. Each is given
to the package's automatic choice (`exaggerate` without --model): the model it picks, or a
refusal (a run, a dash or a wave: no shipped model is of their action). Then its two normal walks
are exaggerated to 3 and diminished to 1 by the walks model (`--action walk`, default settings) and
measured with the gait measures of experiments/exaggeration_sessions.py (this folder's own
reader and SciPy forward kinematics) against the session's own `active` and `tired` walks (the
takes of two seconds or more): the share of the way each measure moves (1: all the way).

Data: Bandai-Namco-Research-Motiondataset-1 (CC BY-NC 4.0).
"""

from __future__ import annotations

import collections
import warnings

import numpy as np

import expressive_mocap as em
from exaggeration_sessions import MEASURES, gait
from expressive_mocap.errors import MocapError
from expressive_mocap.exaggeration import exaggerate
from expressive_mocap.exaggeration.zoo import candidates, choose, shipped_models
from setting import REPO, arguments, bandai_dir, described

ACTIONS = ("walk", "run", "dash", "bye", "byebye")
MEASURED = 2.0  # seconds: the shortest walk measured


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data, number=1)
    models = shipped_models()
    picks: dict[str, collections.Counter] = {}
    for action in ACTIONS:
        picks[action] = collections.Counter()
        for path in sorted(dataset.glob(f"dataset-1_{action}_*.bvh")):
            motion = em.read_bvh(path)
            try:
                picked = choose(motion, models)[0].name
            except MocapError as refusal:
                picked = "refused"
                print(path.stem, str(refusal)[:160], flush=True)
            picks[action][picked] += 1
    # Gait needs a few steps: takes of two seconds or more (one of the normal walks lasts one).
    takes = {
        s: [p for p in sorted(dataset.glob(f"dataset-1_walk_{s}_*.bvh")) if em.read_bvh(p).duration >= MEASURED]
        for s in ("tired", "normal", "active")
    }
    measured = {s: np.array([gait(em.read_bvh(p)) for p in paths]).mean(0) for s, paths in takes.items()}
    edited: dict[float, list[np.ndarray]] = {1.0: [], 3.0: []}
    model = candidates("walk", "energy")[0].load()  # as `exaggerate --action walk` (the choice is above)
    for path in takes["normal"]:
        walk = em.read_bvh(path)
        for to in edited:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                edited[to].append(gait(exaggerate(model, walk, to)[0]))
    lines = [
        "# The shipped exaggeration models on another session's check clips",
        "",
        described(__doc__),
        "",
        "`python experiments/zoo_checks.py`. Data: Bandai-Namco-Research-Motiondataset-1 (CC BY-NC 4.0).",
        "",
        "| clips | n | picked |",
        "|---|---|---|",
    ]
    for action, counter in picks.items():
        said = ", ".join(f"{name} {n}" for name, n in counter.most_common())
        lines.append(f"| {action} | {sum(counter.values())} | {said} |")
    lines += [
        "",
        "| measure | tired | normal | active | normal to 1 | normal to 3 | share of the way to tired | to active |",
        "|---|---|---|---|---|---|---|---|",
    ]
    normal = measured["normal"]
    for k, (name, _) in enumerate(MEASURES):
        low, high = measured["tired"][k], measured["active"][k]
        to1, to3 = (np.mean([g[k] for g in edited[to]]) for to in (1.0, 3.0))
        shares = [(to - normal[k]) / (far - normal[k]) if abs(far - normal[k]) > 1e-9 else float("nan")
                  for to, far in ((to1, low), (to3, high))]  # fmt: skip
        lines.append(
            f"| {name} | {low:.1f} | {normal[k]:.1f} | {high:.1f} | {to1:.1f} | {to3:.1f} | "
            f"{shares[0]:.2f} | {shares[1]:.2f} |"
        )
    (REPO / "experiments" / "ZOO_CHECKS.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
