"""What the shipped walks model does to held-out walks, as a viewer would measure it.

    python experiments/eval_shipped_walks.py [--data DIR]

Dataset-2's held-out walks (takes 9 on of exhausted, normal and active: never trained on) are
measured with the gait measures of experiments/exaggeration_sessions.py (this folder's own reader
and SciPy forward kinematics). Each held-out normal take is exaggerated to 3 and diminished to 1
by the shipped model as `exaggerate` without --model chooses it (the default settings, without
retiming: `--no-timing`); per measure, how far its mean moves from the normal takes' towards the active (to 3)
or the exhausted (to 1) takes' (1: all the way; the bar a shipped model is held to: at least 0.5). Also: stance feet
(the edit's mean stance-foot speed over the input's, through the input's contacts; bar 1.2x) and
hinges (the largest knee or elbow angle past straight, degrees: 0 when none bends backwards).

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import warnings

import numpy as np

import expressive_mocap as em
from exaggeration_sessions import MEASURES, gait
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.exaggeration import exaggerate
from expressive_mocap.exaggeration.edit import stance_foot_speed
from expressive_mocap.exaggeration.zoo import PEOPLE, candidates, choose
from expressive_mocap.viz.render import render_poses
from hinge_limits import BANDAI, Measure, summary
from setting import REPO, arguments, bandai_dir, described


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    takes = {
        s: sorted(dataset.glob(f"dataset-2_walk_{s}_*.bvh"))[len(PEOPLE) :] for s in ("exhausted", "normal", "active")
    }
    measured = {s: np.array([gait(em.read_bvh(p)) for p in paths]) for s, paths in takes.items()}
    models = candidates("walk", "energy")
    edited: dict[float, list[np.ndarray]] = {3.0: [], 1.0: []}
    feet, hinges = [], []
    for path in takes["normal"]:
        walk = em.read_bvh(path)
        _, model, _ = choose(walk, models)
        contacts = foot_contacts(walk)
        hinge = Measure(walk, BANDAI)  # flexion about the input's own axes: negative past straight
        for to in edited:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out, _ = exaggerate(model, walk, to, timing=False)
            edited[to].append(gait(out))
            feet.append(stance_foot_speed(out, contacts) / stance_foot_speed(walk, contacts))
            hinges.append(summary(hinge(out))[0])
    normal = measured["normal"].mean(0)
    lines = [
        "# The shipped walks model on held-out walks",
        "",
        described(__doc__),
        "",
        f"`python experiments/eval_shipped_walks.py`: {len(takes['normal'])} normal takes edited; held-out "
        f"exhausted / active takes: {len(takes['exhausted'])} / {len(takes['active'])}. Data: Bandai-Namco-"
        "Research-Motiondataset-2 (CC BY-NC 4.0). Speed and cadence move with timing only, left out here.",
        "",
        "| measure | exhausted | normal | active | normal to 1 | normal to 3 | share of the way to 1 | to 3 |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for k, (name, _) in enumerate(MEASURES):
        low, high = measured["exhausted"][:, k].mean(), measured["active"][:, k].mean()
        to1, to3 = np.mean([g[k] for g in edited[1.0]]), np.mean([g[k] for g in edited[3.0]])
        share1 = (to1 - normal[k]) / (low - normal[k]) if abs(low - normal[k]) > 1e-9 else float("nan")
        share3 = (to3 - normal[k]) / (high - normal[k]) if abs(high - normal[k]) > 1e-9 else float("nan")
        row = (name, f"{low:.1f}", f"{normal[k]:.1f}", f"{high:.1f}", f"{to1:.1f}", f"{to3:.1f}")
        lines.append("| " + " | ".join(row) + f" | {share1:.2f} | {share3:.2f} |")
    lines += [
        "",
        f"- stance feet, edit over input: mean {np.mean(feet):.2f}x, largest {np.max(feet):.2f}x (bar 1.2x)",
        f"- knees and elbows past straight: largest {np.max(hinges):.1f} degrees",
        "",
    ]
    walk = em.read_bvh(takes["normal"][0])
    _, model, _ = choose(walk, models)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        edits = [exaggerate(model, walk, to)[0] for to in (1.0, 3.0)]
    render_poses(
        [edits[0], walk, edits[1]],
        REPO / "experiments" / "figures" / "shipped_walk.png",
        ["to 1 (diminished)", f"{takes['normal'][0].stem} (held out)", "to 3 (exaggerated)"],
        poses=6,
    )
    lines += ["![a held-out normal walk diminished to 1 and exaggerated to 3](figures/shipped_walk.png)", ""]
    (REPO / "experiments" / "SHIPPED_WALKS.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
