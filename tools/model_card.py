"""Write the shipped model's card: python tools/model_card.py

Reads the model's own report and settings (python/expressive_mocap/data/body_model.npz) and
the hidden-size sweep (experiments/sweep_autoencoder.json, from experiments/sweep_autoencoder.py), and writes
python/expressive_mocap/data/MODEL_CARD.md beside the model.
"""

from __future__ import annotations

import json
from pathlib import Path

from expressive_mocap.decoupling.body_model import BodyModel

REPO = Path(__file__).resolve().parent.parent
CARD = REPO / "python" / "expressive_mocap" / "data" / "MODEL_CARD.md"
SWEEP = REPO / "experiments" / "sweep_autoencoder.json"  # written by experiments/sweep_autoencoder.py
PAPER = {
    "autoencoder": "0.0131",
    "regression": "0.037",
    "fine_tuned": "0.0286",
    "stack": "",
    "mean_pose": "",
    "plain": "",
}
PAPER_SWEEP = {"300": "0.0131", "150": "0.0135", "50": "0.0156", "15": "0.0196"}
COMMAND = (
    "D=~/.cache/motion-data/dataset/Bandai-Namco-Research-Motiondataset-2/data\n"
    "expressive-mocap train $D/dataset-2_{walk,walk-turn-left,walk-turn-right,run}_normal_*.bvh \\\n"
    "    --unlabelled $D/dataset-2_*.bvh -o python/expressive_mocap/data/body_model.npz --max-iter 300"
)


def main() -> None:
    model = BodyModel.load()
    r, s = model.report, model.settings
    stages = [
        ("mean_pose", "predict the mean training pose (baseline)"),
        ("autoencoder", f"denoising autoencoder, {s.hidden} tanh units"),
        ("regression", f"regression features -> code, {s.regression_hidden} tanh units (code units)"),
        ("stack", "stack before fine-tuning"),
        ("fine_tuned", "stack fine-tuned end to end (the shipped network)"),
        ("plain", f"plain one-hidden-layer network, {s.hidden} tanh units"),
    ]
    scores = r.stages()
    rows = "\n".join(
        f"| {label} | {scores[key].train_mse:.3g} | {scores[key].test_mse:.3g} "
        f"| {scores[key].test_variance_explained:.3f} | {PAPER[key]} |"
        for key, label in stages
        if key in scores
    )
    sweep_file = SWEEP
    sweep = ""
    if sweep_file.exists():
        results = json.loads(sweep_file.read_text())
        sweep = "\n".join(
            f"| {h} | {v['train_mse']:.3g} | {v['test_mse']:.3g} | "
            f"{v['test_variance_explained']:.4f} | {PAPER_SWEEP.get(h, '')} |"
            for h, v in results.items()
        )
        sweep = (
            "\n## Autoencoder size\n\nThe same neutral clips and split, each autoencoder trained on the neutral "
            "training clips only (`python experiments/sweep_autoencoder.py`; the shipped one also learned "
            "40,000 frames of every kind of clip, which costs it some accuracy on neutral poses: 1.33e-4 against "
            "0.94e-4):\n\n| "
            "hidden units | train MSE | test MSE | test variance explained | paper (CMU) |\n|---|---|---|---|---|\n"
            + sweep
            + "\n"
        )
    split, mean_pose = r.split, r.mean_pose
    assert split is not None and mean_pose is not None and split.train_rows is not None
    assert s.unlabelled_frames is not None, "the shipped model records its training"
    assert model.trunk is not None and model.pelvis is not None, "the shipped model reads its trunk"
    card = f"""# Model card: the shipped body-mechanics model

`expressive_mocap/data/body_model.npz`, loaded by `BodyModel.load()` and used by default by
`decouple`, `modulate`, `mix`, `blend` and `calibrate`.

## What it does
From 19 causal dynamic features of a frame (hips velocity and its 1/3 s mean in the heading frame,
foot contacts, air time, relative hips height, thigh rotations: the inputs of Boehs, Vieira &
Pereira, "Decoupling Expressiveness and Body-Mechanics in Human Motion") it predicts the local
rotations of the 20 joints other than `joint_Root` and `Hips` that a neutral performer would
have: the body-mechanics component. It works on the 22-joint Bandai-Namco skeleton only
(joint names checked); other sessions of that skeleton need `calibrate` (see the README).

## Data
Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022; Kobayashi et
al., "Motion Capture Dataset for Practical Use of AI-based Motion Editing and Stylization",
arXiv:2306.08861), licensed **CC BY-NC 4.0**: this model is a derivative of that data and is for
non-commercial use under the same licence.
- neutral (supervised) set: `{{walk,walk-turn-left,walk-turn-right,run}}_normal_*`, {s.neutral_clips} clips, \
{s.neutral_frames} frames,
  split 70/30 **by clip**: {split.train_groups} training clips ({split.train_rows} frames), \
{split.test_groups} test clips ({split.test_rows} frames);
- autoencoder: also {s.unlabelled_frames} frames ({s.unlabelled_frames - split.train_rows} drawn at random \
from all
  {s.unlabelled_clips} dataset-2 clips, gestures included, with the neutral test clips left out, \
plus the neutral training frames).

## Settings
{json.dumps(s.to_json(), indent=1)}

Training: full-batch L-BFGS (SciPy) on NumPy forward/backward passes; the autoencoder's input
corrupted by masking 10-30% of values and Gaussian noise; then the regression onto its code; then
the stack fine-tuned end to end. Poses are unit quaternions (x, y, z, w) of the 20 joints, each
on the hemisphere of its mean training rotation (80 numbers a frame). Inputs are clipped into the
range of the training clips' speeds, contacts, air times and hips heights (`feature_range`, stored
in the file; the thigh rotations are not limited), so the network does not extrapolate to a
sprint or a crouch it never saw.

The trunk: the spine is learned and predicted as if the pelvis held the training clips' mean
posture (each clip's spine carried by its own mean pelvis posture's difference from it, stored as
`pelvis_*`), so a neutral trunk is upright in the world whatever the pelvis does; and the spine
and chest are read as one chain whose lean is at least as active as it reads against a threshold
of {model.trunk.scale:.3f} (`trunk_*`: the lean this network leaves on the held-out clips, at its
95th percentile, reads as 10 degrees). Both are set by `train`.

The arms: the upper arms and forearms are filtered in world axes (`arm_*`: the skeleton's parents
and those joints), so an arm the split finds inactive hangs in the world as the actor's does
whatever the body mechanics do to the trunk above it. Set by `train`; added to this file after
training, the network unchanged.

## Scores
Mean squared error per pose value (quaternion components), train and **test** (held-out clips),
and the share of the test poses' variance explained. The paper's figures are on CMU data with
another pose scale, so they are context, not a bar: on this data predicting the mean pose
already scores {mean_pose.test_mse:.3g}.

| stage | train MSE | test MSE | test variance explained | paper (CMU) |
|---|---|---|---|---|
{rows}
{sweep}
## How it was made
```sh
{COMMAND}
```
(the `{{...}}` is the shell's brace expansion: the four neutral contents in that order, each sorted;
the split depends on that order and on `--seed 0`). Then `python experiments/sweep_autoencoder.py`,
`python tools/model_card.py` (this card), `python experiments/eval_decoupling.py` (activity on real
clips, experiments/DECOUPLING.md),
`python experiments/decoupling_sessions.py --held-out --out SESSIONS.md` (another session, and the
idle arm of one-hand gestures: experiments/SESSIONS.md) and `python experiments/eval_trunk.py`
(leaning walks: experiments/TRUNK.md).
"""
    CARD.write_text(card)
    print(card)


if __name__ == "__main__":
    main()
