"""Does an independent style classifier read the shipped models' edits as the style they aim at?

    python experiments/style_classifier.py [--data DIR]

A multinomial logistic regression (L2, fitted with SciPy's L-BFGS; no part of the package) reads
two-second windows (half a second apart) of a walk: the mean and spread of each joint's rotation
in its parent's axes (rotation vector; spine, neck, head, arms and legs) and of the gait (the
hips' horizontal speed and height over the actor's height, both hands' swing along the facing
direction), read with this folder's own BVH reader and SciPy forward kinematics (a Bandai-Namco skeleton's
joint names). A clip's style
is the one its windows' summed log-probabilities favour. For each shipped model it is trained
on dataset-2's held-out takes of the model's action only (takes 9-16 of its three styles: never
in the model's training, never edited motion) and tested on the later held-out takes: unedited,
and those of the middle style exaggerated to 3 and diminished to 1 by the model (`exaggerate
--action A --axis X`, default settings, its timing included), and beyond: to 4 and to 0. The bar
of a shipped model: at least 70 % of the edits to 3 and to 1 read as the style aimed at.

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

import expressive_mocap as em
from expressive_mocap.exaggeration import exaggerate
from expressive_mocap.exaggeration.zoo import PEOPLE, ShippedModel, shipped_models
from independent import parse_bvh, scipy_fk
from setting import REPO, arguments, bandai_dir, described

TRAINING_TAKES = 8  # held-out takes 9-16 of each style train the classifier; the later ones test it
WINDOW, HOP = 2.0, 0.5  # seconds
JOINTS = ("Spine", "Chest", "Neck", "Head", "UpperArm", "LowerArm", "UpperLeg", "LowerLeg", "Foot")
L2 = 1e-2  # the penalty on the weights, per training window
CLASSES = 3  # a model's three styles


def clip_features(path: Path) -> np.ndarray:
    """The features ``[windows, D]`` of a BVH file (a Bandai-Namco skeleton's joint names)."""
    text = path.read_text()
    _, parents, _, _, _, frame_time = parse_bvh(text)
    names, rotations, positions = scipy_fk(text)
    index = {n: k for k, n in enumerate(names)}
    columns = []
    for joint in JOINTS:
        for name in [joint] if joint in index else [f"{joint}_L", f"{joint}_R"]:
            local = rotations[parents[index[name]]].inv() * rotations[index[name]]
            columns.append(local.as_rotvec())
    at = {n: positions[:, index[n]] for n in ("Hips", "Head", "Toes_L", "Toes_R", "Foot_L", "Foot_R")}
    height = np.percentile(at["Head"][:, 1] - np.minimum(at["Toes_L"][:, 1], at["Toes_R"][:, 1]), 95)
    rate = 1.0 / frame_time
    speed = np.linalg.norm(np.gradient(at["Hips"][:, [0, 2]], axis=0), axis=1) * rate / height
    forward = sum(at[f"Toes_{s}"] - at[f"Foot_{s}"] for s in "LR")
    forward[:, 1] = 0.0
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    hands = [np.sum((positions[:, index[f"Hand_{s}"]] - at["Hips"]) * forward, axis=1) / height for s in "LR"]
    per_frame = np.column_stack(columns + [speed, at["Hips"][:, 1] / height, *hands])
    size, hop = int(round(WINDOW * rate)), int(round(HOP * rate))
    starts = range(0, max(len(per_frame) - size, 0) + 1, hop)
    return np.array([np.concatenate([per_frame[s : s + size].mean(0), per_frame[s : s + size].std(0)]) for s in starts])


class Classifier:
    """Multinomial logistic regression on standardised features."""

    def __init__(self, features: list[np.ndarray], labels: list[int]):
        x = np.concatenate(features)
        y = np.concatenate([np.full(len(f), label) for f, label in zip(features, labels)])
        self.mean, self.scale = x.mean(0), x.std(0) + 1e-9
        x = (x - self.mean) / self.scale
        x = np.column_stack([x, np.ones(len(x))])
        onehot = np.eye(CLASSES)[y]

        def loss(flat: np.ndarray) -> tuple[float, np.ndarray]:
            w = flat.reshape(x.shape[1], CLASSES)
            logits = x @ w
            logits -= logits.max(1, keepdims=True)
            log_p = logits - np.log(np.exp(logits).sum(1, keepdims=True))
            value = -np.sum(onehot * log_p) / len(x) + L2 * np.sum(w[:-1] ** 2)
            grad = x.T @ (np.exp(log_p) - onehot) / len(x)
            grad[:-1] += 2 * L2 * w[:-1]
            return float(value), grad.ravel()

        start = np.zeros(x.shape[1] * CLASSES)
        self.weights = minimize(loss, start, jac=True, method="L-BFGS-B").x.reshape(x.shape[1], CLASSES)

    def style(self, features: np.ndarray) -> int:
        x = np.column_stack([(features - self.mean) / self.scale, np.ones(len(features))])
        logits = x @ self.weights
        log_p = (
            logits
            - np.log(np.exp(logits - logits.max(1, keepdims=True)).sum(1, keepdims=True))
            - logits.max(1, keepdims=True)
        )
        return int(np.argmax(log_p.sum(0)))


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    lines = [
        "# An independent style classifier on the shipped models' edits",
        "",
        described(__doc__),
        "",
        "`python experiments/style_classifier.py`. Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).",
    ]
    for shipped in shipped_models():
        lines += ["", *model_rows(dataset, shipped)]
        print(shipped.name, flush=True)
    (REPO / "experiments" / "STYLE_CLASSIFIER.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def model_rows(dataset: Path, shipped: ShippedModel) -> list[str]:
    """The classifier's readings for one shipped model: its table's lines."""
    styles = shipped.styles
    held = {s: sorted(dataset.glob(f"dataset-2_{shipped.action}_{s}_*.bvh"))[len(PEOPLE) :] for s in styles}
    train = {s: paths[:TRAINING_TAKES] for s, paths in held.items()}
    test = {s: paths[TRAINING_TAKES:] for s, paths in held.items()}
    classifier = Classifier(
        [clip_features(p) for s in styles for p in train[s]], [k for k, s in enumerate(styles) for _ in train[s]]
    )
    rows = []
    for k, style in enumerate(styles):
        read = [classifier.style(clip_features(p)) for p in test[style]]
        rows.append((f"unedited {style} takes", read, k))
    model = shipped.load()
    with tempfile.TemporaryDirectory() as work:
        for to in (3.0, 1.0, 4.0, 0.0):
            read = []
            for path in test[styles[1]]:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    out, _ = exaggerate(model, em.read_bvh(path), to)
                written = Path(work) / "edit.bvh"
                em.write_bvh(out, written)
                read.append(classifier.style(clip_features(written)))
            rows.append(
                (f"{styles[1]} takes {'exaggerated' if to > 2.0 else 'diminished'} to {to:g}", read, 2 * (to > 2))
            )
    lines = [
        f"## {shipped.name}: trained on {sum(len(v) for v in train.values())} held-out takes, "
        f"tested on {sum(len(v) for v in test.values())}",
        "",
        f"| clips | n | read as aimed (unedited: as their own style) | read as {' / '.join(styles)} |",
        "|---|---|---|---|",
    ]
    for label, read, aim in rows:
        counts = " / ".join(str(read.count(k)) for k in range(len(styles)))
        lines.append(f"| {label} | {len(read)} | {100 * np.mean(np.array(read) == aim):.0f} % | {counts} |")
    return lines


if __name__ == "__main__":
    main()
