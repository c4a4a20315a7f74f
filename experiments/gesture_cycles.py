"""Arm actions as whole clips or as their own strokes: the shipped models' validation either way.

    python experiments/gesture_cycles.py [--data DIR] [--held-out N]

For each arm action of dataset-2 (raise-up and wave, left, right and both hands) and each style
axis of the shipped models (energy, age), an exaggeration model is trained from the zoo's recipe
(takes 1-8 of the axis' three styles as people) twice: with each clip time-normalised whole (what
ships) and with its gesture cycles (`cycle="gesture"`: one cycle per stroke of a wave, else the
span the hand moves in). Each is measured as benches/build_models.py measures a model: the swap
test over DOFs and positions, the worst leave-one-person-out warp, and the intensity estimate of
the held-out takes (from take 9 of each style; within 0.3 of their level, and the mean error).

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import expressive_mocap as em
from expressive_mocap.exaggeration import train
from expressive_mocap.exaggeration.zoo import ACTIONS, AXES, LOCOMOTION, fit, training_clips
from setting import REPO, bandai_dir, described

sys.path.insert(0, str(REPO / "benches"))  # the bench that builds the shipped models measures them
from build_models import figures, held_out  # noqa: E402

CHOICES = ("whole", "gesture")


def measured(dataset: Path, action: str, axis: str, cycle: str, count: int) -> dict:
    model = train(training_clips(dataset, action, axis), (1.0, 2.0, 3.0), cycle=cycle)
    clips = held_out(dataset, action, axis, count)
    fits = {}
    for _, _, path in clips:
        estimate = fit(model, em.read_bvh(path))
        fits[path] = (estimate.k, estimate.residual)
    return figures(model, clips, fits)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=Path.home() / ".cache" / "motion-data")
    parser.add_argument("--held-out", type=int, default=18, help="held-out takes per style (default 18)")
    args = parser.parse_args()
    dataset = bandai_dir(args.data)
    lines = [
        "# Arm actions: whole clips or their own strokes",
        "",
        described(__doc__),
        "",
        "`python experiments/gesture_cycles.py`. Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).",
        "",
        "| action | axis | cycles | swap ratio (DOFs / positions) | warp | estimate within 0.3 (error) |",
        "|---|---|---|---|---|---|",
    ]
    for axis in AXES:
        for action in (a for a in ACTIONS if a not in LOCOMOTION):
            for cycle in CHOICES:
                r = measured(dataset, action, axis, cycle, args.held_out)
                lines.append(
                    f"| {action} | {axis} | {cycle} | {r['swap_ratio']:.2f} / {r['swap_ratio_positions']:.2f} | "
                    f"{r['warp_ratio_worst']:.2f} | {100 * r['estimate_within']:.0f} % ({r['estimate_error']:.2f}) |"
                )
                print(lines[-1], flush=True)
    (REPO / "experiments" / "GESTURE_CYCLES.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
