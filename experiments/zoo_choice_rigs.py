"""The shipped models' automatic choice on other skeletons: held-out takes retargeted first.

    python experiments/zoo_choice_rigs.py [--other DIR] [--data DIR]

``exaggerate`` without ``--model`` carries its input onto the models' canonical body and picks
the shipped model that fits best, or refuses (no model of that action). Here every action of
dataset-2 in the three energy styles, its held-out takes (the first :data:`TAKES` after the eight
the models were trained on), is retargeted onto each synthetic rig and onto the skeletons of the
shared folder's walks, then given to that choice exactly as the command makes it (carried onto
the canonical body, then ``zoo.choose``). Counted per rig: right (a model of the take's own
action, or a refusal when no model of that action ships), refused (none, though one of its
action ships) and wrong (another action's model). The Bandai-Namco skeleton itself is the first
row. Written to ZOO_CHOICE_RIGS.md.

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database; the 21-joint walks of the shared folder.
"""

from __future__ import annotations

import collections
import tempfile
import warnings
from pathlib import Path

import expressive_mocap as em
from expressive_mocap.errors import MocapError
from expressive_mocap.exaggeration.zoo import ACTIONS, AXES, PEOPLE, choose, shipped_models
from expressive_mocap.skeletons.canonical import carried_for
from expressive_mocap.skeletons.retargeting import retarget
from setting import REPO, arguments, bandai_dir, described, rig_targets

TAKES = 2  # held-out takes of each action and style


def outcome(motion: em.Motion, models, action: str, ships: set[str]) -> str:
    """right, refused or wrong: the choice ``exaggerate`` makes for ``motion`` (a take of ``action``)."""
    carried = carried_for(motion, models[0].load())
    on_model = motion if carried is None else carried.body
    try:
        picked = choose(on_model, models)[0].action
    except MocapError:
        picked = None
    expected = action if action in ships else None
    return "right" if picked == expected else "refused" if picked is None else "wrong"


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    count = TAKES
    models = shipped_models()
    ships = {m.action for m in models}
    takes = [
        (action, path)
        for action in ACTIONS
        for style in AXES["energy"]
        for path in sorted(dataset.glob(f"dataset-2_{action}_{style}_*.bvh"))[len(PEOPLE) : len(PEOPLE) + count]
    ]
    counts: dict[str, collections.Counter] = {}
    wrong: dict[str, list[str]] = collections.defaultdict(list)
    with tempfile.TemporaryDirectory() as work:
        targets = {"bandai": None, **rig_targets(args.other, Path(work))}
        for rig, target in targets.items():
            goal = None if target is None else em.read_bvh(target)
            counts[rig] = collections.Counter()
            for action, path in takes:
                motion = em.read_bvh(path)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    moved = motion if goal is None else retarget(motion, goal)
                    result = outcome(moved, models, action, ships)
                counts[rig][result] += 1
                if result != "right":
                    wrong[rig].append(f"{path.stem} ({result})")
            print(rig, dict(counts[rig]), flush=True)
    total = len(takes)
    lines = [
        "# The shipped models' choice on other skeletons (`experiments/zoo_choice_rigs.py`)",
        "",
        described(__doc__),
        "",
        f"Shipped: {', '.join(sorted(m.name for m in models))}. Takes: {total} "
        f"({len(ACTIONS)} actions x {len(AXES['energy'])} energy styles x {count} held-out takes).",
        "",
        "| rig | right | refused | wrong | not right |",
        "|---|---|---|---|---|",
    ]
    for rig, c in counts.items():
        missed = ", ".join(wrong[rig][:6]) + (" ..." if len(wrong[rig]) > 6 else "")
        lines.append(f"| {rig} | {c['right']}/{total} | {c['refused']} | {c['wrong']} | {missed} |")
    (REPO / "experiments" / "ZOO_CHOICE_RIGS.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
