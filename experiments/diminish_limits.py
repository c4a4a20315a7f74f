"""Why do held-out normal walks diminished to 1 not read as exhausted to an independent classifier?

    python experiments/diminish_limits.py [--data DIR]

The classifier of style_classifier.py (trained on dataset-2's held-out takes 9-16 of each style,
tested on the later ones) reads each window's logit of exhausted over normal as a sum over its
features: here summed per group and averaged over the test takes, for the unedited exhausted and
normal takes and the normal takes diminished to 1 by the shipped model (default settings). The
groups: head and neck (a zero-length End Site at the head gives both almost no weight, so the
method never edits them); the other joints the model edits (any key DOF); the joints it leaves as
they were (no key DOF); the gait. Then variants: the classifier without head and neck
features; and models trained with a head bone of an eighth of the actor's height (the classical
proportion) at several key shares, which make head and neck key: their key DOFs of 67, swap test
(union; DOFs / positions), and how the same classifier reads their edits; and the shipped model's
edits with the current intensity stated as 2 (not estimated), and diminished to 0.5.

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np

import expressive_mocap as em
import expressive_mocap.exaggeration.training as training
import style_classifier as sc
from expressive_mocap.body import Body
from expressive_mocap.exaggeration import exaggerate, swap_test
from expressive_mocap.exaggeration.dofs import subtree_weights
from expressive_mocap.exaggeration.zoo import DEGREE, PEOPLE, shipped_models, training_clips
from setting import REPO, arguments, bandai_dir, described

HEAD_SHARE_OF_HEIGHT = 0.125
SHARES = (0.9, 0.97, 0.99)
HEAD = ("Neck", "Head")


def feature_joints() -> list[str]:
    """The joint (or "gait") of each classifier feature, in the classifier's order (means, then spreads)."""
    names = []
    for joint in sc.JOINTS:
        sides = [joint] if joint in ("Spine", "Chest", "Neck", "Head") else [f"{joint}_L", f"{joint}_R"]
        names += [n for n in sides for _ in range(3)]
    names += ["gait"] * 4
    return names * 2


def margins(classifier: sc.Classifier, paths: list[Path]) -> np.ndarray:
    """Per feature, the mean over ``paths`` (and their windows) of its part of the exhausted-over-normal logit."""
    parts = []
    for path in paths:
        x = (sc.clip_features(path) - classifier.mean) / classifier.scale
        w = classifier.weights[:-1]
        parts.append((x[:, :, None] * w[None]).mean(axis=0)[:, 0] - (x[:, :, None] * w[None]).mean(axis=0)[:, 1])
    return np.mean(parts, axis=0)


def edited(model, paths: list[Path], to: float, work: Path, current: float | None = None) -> list[Path]:
    """``paths`` taken to intensity ``to`` by ``model`` (default settings; the current intensity
    estimated unless ``current`` is given), written under ``work``."""
    out = []
    for path in paths:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            motion, _ = exaggerate(model, em.read_bvh(path), to, current=current)
        out.append(work / f"{path.stem}_{to:g}.bvh")
        em.write_bvh(motion, out[-1])
    return out


def with_head_bone(skeleton):
    """:func:`subtree_weights` with a head bone of HEAD_SHARE_OF_HEIGHT of the actor's height."""
    weights = subtree_weights(skeleton)
    body = Body.of(skeleton)
    joint = body.roles.head
    while joint >= 0:
        weights[joint] += HEAD_SHARE_OF_HEIGHT * body.actor_height
        joint = skeleton.parents[joint]
    return weights


def trained_classifier(styles, train: dict[str, list[Path]]) -> sc.Classifier:
    features = [sc.clip_features(p) for s in styles for p in train[s]]
    return sc.Classifier(features, [k for k, s in enumerate(styles) for _ in train[s]])


def group_rows(shipped, classifier, test: dict[str, list[Path]], dimmed: list[Path]) -> list[str]:
    """The logit by group of features, for the unedited takes and the diminished ones."""
    key_joints = {name.split(".")[0] for name in shipped.load().key_names()}
    group = np.array(
        [
            "head" if j in HEAD else "gait" if j == "gait" else "edited" if j in key_joints else "left"
            for j in feature_joints()
        ]
    )
    rows = []
    styles = shipped.styles
    for label, paths in (("unedited exhausted", test[styles[0]]), ("unedited normal", test[styles[1]]),
                         ("normal diminished to 1", dimmed)):  # fmt: skip
        m = margins(classifier, paths)
        cells = " | ".join(f"{m[group == g].sum():+.2f}" for g in ("head", "edited", "left", "gait"))
        rows.append(f"| {shipped.name} | {label} | {cells} | {m.sum():+.2f} |")
    return rows


def variant_rows(shipped, classifier, train, test, dimmed: list[Path], dataset: Path, work: Path) -> list[str]:
    """The classifier without head and neck on the shipped model's edits; models with a head bone."""
    styles, full_joints = shipped.styles, sc.JOINTS
    sc.JOINTS = tuple(j for j in full_joints if j not in HEAD)
    try:
        headless = trained_classifier(styles, train)
        read = [headless.style(sc.clip_features(p)) for p in dimmed]
    finally:
        sc.JOINTS = full_joints
    keys = int(shipped.load().key.sum())
    rows = [
        f"| {shipped.name} | shipped; classifier without head and neck | {keys} | - | {read.count(0)}/{len(read)} | - |"
    ]
    for label, to, current in (
        ("shipped; current intensity stated as 2", 1.0, 2.0),
        ("shipped; diminished to 0.5", 0.5, None),
    ):
        read = [
            classifier.style(sc.clip_features(p)) for p in edited(shipped.load(), test[styles[1]], to, work, current)
        ]
        rows.append(f"| {shipped.name} | {label} | {keys} | - | {read.count(0)}/{len(read)} | - |")
    clips = training_clips(dataset, shipped.action, shipped.axis)
    original = training.subtree_weights
    for share in SHARES:
        training.subtree_weights = with_head_bone
        try:
            variant = training.train(clips, (1.0, 2.0, 3.0), cycle="all", degree=DEGREE, share=share)
        finally:
            training.subtree_weights = original
        swap = swap_test(variant)[-1]
        down = [classifier.style(sc.clip_features(p)) for p in edited(variant, test[styles[1]], 1.0, work)]
        up = [classifier.style(sc.clip_features(p)) for p in edited(variant, test[styles[1]], 3.0, work)]
        heads = len([n for n in variant.key_names() if n.split(".")[0] in HEAD])
        rows.append(
            f"| {shipped.name} | head bone, share {share:g} ({heads} head/neck DOFs key) | {int(variant.key.sum())} "
            f"| {swap.ratio:.2f} / {swap.ratio_positions:.3f} | {down.count(0)}/{len(down)} | {up.count(2)}/{len(up)} |"
        )
    return rows


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    groups = [
        "| model | takes | head, neck | edited joints | joints left | gait | total |",
        "|---|---|---|---|---|---|---|",
    ]
    variants = [
        "| model | variant | key DOFs | swap ratio | diminished to 1 read exhausted | exaggerated to 3 read active |",
        "|---|---|---|---|---|---|",
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for shipped in shipped_models():
            held = {
                s: sorted(dataset.glob(f"dataset-2_{shipped.action}_{s}_*.bvh"))[len(PEOPLE) :] for s in shipped.styles
            }
            train = {s: p[: sc.TRAINING_TAKES] for s, p in held.items()}
            test = {s: p[sc.TRAINING_TAKES :] for s, p in held.items()}
            dimmed = edited(shipped.load(), test[shipped.styles[1]], 1.0, Path(tmp))
            classifier = trained_classifier(shipped.styles, train)
            groups += group_rows(shipped, classifier, test, dimmed)
            variants += variant_rows(shipped, classifier, train, test, dimmed, dataset, Path(tmp))
            print(shipped.name, flush=True)
    lines = [
        "# What diminishing a walk to exhausted leaves",
        "",
        described(__doc__),
        "",
        "`python experiments/diminish_limits.py`. Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).",
        "",
        "## The classifier's exhausted-over-normal logit, by group of features (mean per window)",
        "",
        *groups,
        "",
        "## Variants",
        "",
        *variants,
    ]
    (REPO / "experiments" / "DIMINISH.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
