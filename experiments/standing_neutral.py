"""An experiment on the idle-arm leak: the body-mechanics network trained with standing clips too.

    python experiments/standing_neutral.py --write-clips DIR
    python experiments/standing_neutral.py --model NAME=FILE [--model NAME=FILE ...] [--out STANDING.md]

The shipped network learned its neutral poses from locomotion only, where moving hips come with
swinging arms; in energetic one-hand gestures the hips move with each wave, and the network
predicts the idle arm moving more than the actor's does (experiments/SESSIONS.md). Dataset-2 has no
neutral standing clip, so ``--write-clips`` makes some: each normal-style one-hand gesture of the
training side of the 70/30 split by clip (seed 0; the held-out side is what decoupling_sessions.py
measures), its gesturing arm (shoulder to hand) replaced by the mirror image of its idle arm, so
both arms rest while the body moves as it did. A candidate model is then trained with them:

    D=~/.cache/motion-data/dataset/Bandai-Namco-Research-Motiondataset-2/data
    expressive-mocap train $D/dataset-2_{walk,walk-turn-left,walk-turn-right,run}_normal_*.bvh \\
        DIR/*.bvh --unlabelled $D/dataset-2_*.bvh -o standing.npz --max-iter 300

(the same command without ``DIR/*.bvh`` is the shipped model's, MODEL_CARD.md: retrained, it
shows how much training alone moves the figures), and ``--model`` measures each model file (and
the shipped one) as decoupling_sessions.py does:
dataset-1 calibrated on its neutral locomotion (its forward walks held out) and the idle hand of
dataset-2's held-out one-hand gestures.

Data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import shlex
import time
from pathlib import Path

import expressive_mocap as em
from decoupling_sessions import ARM, ONE_HAND_2, gesture_split, session_one, session_two
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.skeletons.mirror import mirror

ROOT = Path.home() / ".cache" / "motion-data" / "dataset"
DATA1 = ROOT / "Bandai-Namco-Research-Motiondataset-1" / "data"
DATA2 = ROOT / "Bandai-Namco-Research-Motiondataset-2" / "data"


def write_clips(folder: Path) -> int:
    """The standing clips (see the module's notes) into ``folder``; how many."""
    train, _ = gesture_split(DATA2)  # the other side is what decoupling_sessions.py measures
    folder.mkdir(parents=True, exist_ok=True)
    count = 0
    for path in train:
        content, style = path.stem.split("_")[1:3]
        if style != "normal":
            continue
        motion = em.read_bvh(path)
        arm = [motion.skeleton.index(f"{j}_{ONE_HAND_2[content]}") for j in ARM]
        rotations = motion.rotations.copy()
        rotations[:, arm] = mirror(motion).rotations[:, arm]  # the idle arm's mirror image
        em.write_bvh(em.Motion(motion.skeleton, rotations, motion.translations, motion.frame_time),
                     folder / f"standing_{path.stem}.bvh")  # fmt: skip
        count += 1
    return count


def measures(model: BodyModel) -> dict:
    """The figures of decoupling_sessions.py that the experiment is about."""
    _, one = session_one(DATA1, model, lambda m, clips: m.calibrated(clips), held_out=True)
    _, two = session_two(DATA2, model)
    return {
        "walks": max(one["held_out"]) / one["gesture"],
        "loo": max(one["loo"]) / one["gesture"],
        "gesture": one["gesture"],
        "over": two["over_3cm"],
        "clips": two["clips"],
        "styles": two["styles"],
    }


def report(results: dict[str, dict]) -> list[str]:
    names = list(results)
    lines = [
        "| measure | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
        "| dataset-1 forward walks (held out), calibrated: larger hand / gesturing hand | "
        + " | ".join(f"{r['walks']:.3f}x" for r in results.values())
        + " |",
        "| dataset-1 calibration clips, each left out: larger hand / gesturing hand | "
        + " | ".join(f"{r['loo']:.3f}x" for r in results.values())
        + " |",
        "| dataset-1 gesturing hand (cm) | " + " | ".join(f"{r['gesture']:.1f}" for r in results.values()) + " |",
        f"| dataset-2 held-out one-hand gestures, idle hand at 3 cm or more (of {results[names[0]]['clips']}) | "
        + " | ".join(str(r["over"]) for r in results.values())
        + " |",
    ]
    for style in results[names[0]]["styles"]:
        cells = []
        for r in results.values():
            hand, over, original, body = r["styles"][style]
            cells.append(f"{hand:.2f} cm, {over} clips; about the shoulder {body:.2f} (actor {original:.2f})")
        lines.append(
            f"| {style}: idle hand, clips at 3 cm or more, its motion about the shoulder | " + " | ".join(cells) + " |"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write-clips", type=Path, metavar="DIR", help="write the standing clips into DIR")
    parser.add_argument("--model", action="append", default=[], metavar="NAME=FILE", help="a model file to measure")
    parser.add_argument("--out", help="markdown file written into experiments/ (default: print only)")
    args = parser.parse_args()
    if args.write_clips:
        print(f"{write_clips(args.write_clips)} standing clips written into {args.write_clips}")
        return
    started = time.time()
    models = {"shipped": BodyModel.load()}
    models.update({name: BodyModel.load(file) for name, file in (m.split("=", 1) for m in args.model)})
    results = {name: measures(model) for name, model in models.items()}
    text = "\n".join(
        [
            "# Experiment: the body-mechanics network trained with standing clips too",
            "",
            f"- date: {time.strftime('%Y-%m-%d %H:%M')}; command: `python experiments/standing_neutral.py "
            + " ".join(f"--model {shlex.quote(m)}" for m in args.model)
            + "` (how the clips and models were made: its docstring)",
            "- data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0",
            "",
            *report(results),
            "",
            f"(took {time.time() - started:.0f} s)",
        ]
    )
    if args.out:
        (Path(__file__).parent / args.out).write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
