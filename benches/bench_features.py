#!/usr/bin/env python
"""Dynamic features (Boehs et al.'s decoupling inputs) on every dataset-2 walk clip, Rust vs the NumPy twin.

    python benches/bench_features.py [--data DIR] [--pattern 'dataset-2_walk*.bvh'] [--rounds 3]

Times, on motions already in memory: the kernels alone (foot contacts + features, inputs
prepared once) and the public ``dynamic_features`` (FK, roles and defaults included), per
backend, alternating; prints the best round of each. Only ratios taken in one run count.
Checked first (benches/harness.py; a failed check raises): the Rust kernels' foot contacts equal
the NumPy twin's and their features, and the public ``dynamic_features`` of both backends, agree
within 1e-12 on every clip.
Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap import reference
from expressive_mocap.body import Body
from expressive_mocap.decoupling import features

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_archive import find_data  # noqa: E402
from harness import Best, check_close, check_equal  # noqa: E402

FEATURE_TOL = 1e-12  # Rust against the NumPy twin (8.8e-15 measured on the walks)


def kernel_inputs(motion: em.Motion) -> tuple:
    body = Body.of(motion.skeleton)
    roles = body.roles
    positions = motion.positions()
    feet = np.ascontiguousarray(positions[:, [[roles.feet[0], roles.toes[0]], [roles.feet[1], roles.toes[1]]]])
    points = np.ascontiguousarray(positions[:, [roles.hips, *roles.upper_legs]])
    thighs = np.ascontiguousarray(motion.rotations[:, list(roles.upper_legs)])
    return feet, points, thighs, thighs[0].copy(), motion.frame_time, body.actor_height, body.hips_rest_height


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", help="folder of dataset-2 .bvh files, or the unpack root (default: run ../shared/data/unpack)"
    )
    parser.add_argument(
        "--pattern", default="dataset-2_walk*.bvh", help="clips to use (default: every walk, turns included)"
    )
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    if not em.rust_available():
        sys.exit("the Rust extension is not built")
    from expressive_mocap import _core

    paths = sorted(find_data(args.data).glob(args.pattern))
    motions = em.read_bvh_many(paths)
    frames = sum(m.n_frames for m in motions)
    prepared = [kernel_inputs(m) for m in motions]
    print(f"{len(paths)} clips ({args.pattern}), {frames} frames, {_core.num_threads} threads")

    def kernels(module, kept=None):
        for feet, points, thighs, ref, dt, height, hips in prepared:
            contacts = module.foot_contacts(feet, dt, 0.0, 0.05 * height, 0.5 * height, 3, True)
            values = module.dynamic_features(points, thighs, contacts, ref, dt, height, hips, 0.0, 10)
            if kept is not None:
                kept.append((contacts, values))
        return kept

    def public(name, kept=None):
        with em.use_backend(name):
            for motion in motions:
                values = features.dynamic_features(motion)
                if kept is not None:
                    kept.append(values)
        return kept

    rust, twin = kernels(_core, []), kernels(reference, [])
    check_equal(len(rust), len(paths), "clips through the kernels")
    for k, ((contacts, values), (twin_contacts, twin_values)) in enumerate(zip(rust, twin)):
        check_close(contacts, twin_contacts, f"foot contacts of clip {k}")
        check_close(values, twin_values, f"kernel features of clip {k}", atol=FEATURE_TOL)
    for k, (values, twin_values) in enumerate(zip(public("rust", []), public("numpy", []))):
        check_close(values, twin_values, f"dynamic_features of clip {k}", atol=FEATURE_TOL)
    del rust, twin

    cases = {
        "kernels, Rust": lambda: kernels(_core),
        "kernels, NumPy twin": lambda: kernels(reference),
        "dynamic_features, Rust": lambda: public("rust"),
        "dynamic_features, NumPy": lambda: public("numpy"),
    }
    best = Best()
    for _ in range(args.rounds):
        for label, run in cases.items():
            best.time(label, run)
    for label, seconds in best.items():
        print(f"{label:26s} {seconds * 1e3:8.1f} ms  {frames / seconds / 1e6:6.2f} M frames/s")
    print(
        f"Rust / NumPy: kernels {best['kernels, NumPy twin'] / best['kernels, Rust']:.1f}x, "
        f"end to end {best['dynamic_features, NumPy'] / best['dynamic_features, Rust']:.1f}x"
    )


if __name__ == "__main__":
    main()
