"""Exaggeration on real walks (Davis & Kannappan's method): Bandai-Namco-Research-Motiondataset-2
(CC BY-NC 4.0), walks 'exhausted' < 'normal' < 'active' as intensities 1 < 2 < 3.

The dataset has no actor label, so takes stand in for people: "person" p (p = 1..8) is take p of
each style (walk_exhausted_00p, walk_normal_00p, walk_active_00p). A held-out 'normal' walk (take
12, in no person) is exaggerated beyond 'active' and diminished below 'exhausted'.

Writes experiments/EXAGGERATION.md and experiments/figures/exaggeration_*.png. Run:

    PYTHONPATH=python python experiments/exaggeration_experiment.py [DATA_DIR]
"""

from __future__ import annotations

import os

# One BLAS thread: on a busy machine OpenBLAS threads turn a 1 ms SVD of the 50 x 201 matrix into
# 300 ms (measured); the matrices here are far too small to gain from threads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import sys
import time
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap._utils.files import atomic_write
from expressive_mocap.exaggeration import (
    dof_positions,
    exaggerate,
    fit,
    leave_one_out,
    rank_agreement,
    swap_test,
    timing_validation,
    train,
    validation_table,
)
from expressive_mocap.exaggeration.validation import timing_table
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.viz.render import render

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = Path.home() / ".cache/motion-data/dataset/Bandai-Namco-Research-Motiondataset-2/data"
STYLES = ("exhausted", "normal", "active")
LEVELS = (1.0, 2.0, 3.0)
PEOPLE = 8
HELD_OUT = "walk_normal_012"
PROTOTYPE_UNION = 35  # DOFs in the throwaway prototype's union of 8 people (52% of 67)
CYCLES = ("all", "middle")  # the default (every cycle of a clip) and the paper's single cycle
CYCLE_MEANING = {
    "all": (
        "every cycle of a clip: their mean is the performance, predictability is measured over every one (the default)"
    ),
    "middle": "one cycle per clip, the one nearest the clip's middle (the paper's single cycle)",
}


def clip(data: Path, name: str) -> em.Motion:
    return em.read_bvh(data / f"dataset-2_{name}.bvh")


def best_of(fn, repeats: int = 7) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times) * 1000


def union_pooled(model) -> tuple[float, float]:
    """The union swap with the people's squared norms summed before the ratio (DOFs, positions)."""
    P = model.trajectories.shape[0]
    top, bottom = np.zeros(2), np.zeros(2)
    for p in range(P):
        light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
        swap = light.copy()
        swap[:, model.key] = heavy[:, model.key]
        poses = [dof_positions(model, x, model.person_reference[p]) for x in (light, heavy, swap)]
        top += [np.sum((swap - heavy) ** 2), np.sum((poses[2] - poses[1]) ** 2)]
        bottom += [np.sum((light - heavy) ** 2), np.sum((poses[0] - poses[1]) ** 2)]
    return tuple(np.sqrt(top / bottom))


def elbow_flexion(motion: em.Motion) -> np.ndarray:
    """Degrees ``[F, 2]`` (left, right) between the upper-arm and forearm bones (0 = straight arm)."""
    names, p = motion.skeleton.names, motion.positions()
    out = []
    for side in "LR":
        s, e, h = (names.index(f"{n}_{side}") for n in ("UpperArm", "LowerArm", "Hand"))
        u, f = p[:, e] - p[:, s], p[:, h] - p[:, e]
        out.append(
            np.degrees(
                np.arccos(np.clip(np.sum(u * f, 1) / np.linalg.norm(u, axis=1) / np.linalg.norm(f, axis=1), -1, 1))
            )
        )
    return np.stack(out, axis=1)


def readings_checked(people, default) -> list[str]:
    """The subsection on the readings of the paper measured as alternatives
    (experiments/exaggeration_variants.py), the cycles taken, and the union's pivotal DOFs."""
    import exaggeration_variants as variants

    lines = [
        "### Readings checked against the paper",
        "",
        "Each row reads one step differently (`experiments/exaggeration_variants.py` patches that one "
        "piece; the package is unchanged) and reruns the whole validation. Per person: share of DOFs "
        "swapped and ratio (random / best same-size in brackets); union: DOFs swapped, ratio over DOFs "
        "and over joint positions; warp: leave-one-person-out mean over DOFs (positions). Each is "
        "measured with every cycle of each clip (`all`, the default) and with the paper's single cycle "
        "(`middle`). Not listed because they cannot change the ranking: normalising predictability by "
        "the sum of all singular values instead of the kept ones (a constant factor per person, removed "
        "when E is normalised) and the column order of `A` (the SVD's `U` and `s` do not depend on it).",
        "",
        "| variant | read as | cycle | per person | union | ratio | positions | warp | Spearman |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    measured = {}
    for name, (what, _, _) in variants.VARIANTS.items():
        for cycle in CYCLES:
            m = measured[name, cycle] = variants.measure(people, name, cycle)
            u = m["union"]
            lines.append(
                f"| {name} | {what if cycle == CYCLES[0] else ''} | `{cycle}` | "
                f"{variants.span([100 * v for v in m['share']], '{:.0f}')}%, {variants.span(m['ratio'])} "
                f"({variants.span(m['random'], '{:.2f}')} / {variants.span(m['best'], '{:.2f}')}) | "
                f"{u.swapped} ({u.share:.0%}) | {u.ratio:.3f} ({u.random:.2f} / {u.best:.2f}) | "
                f"{u.ratio_positions:.3f} | {m['warp']:.3f} ({m['warp_positions']:.3f}) | {m['spearman']:.3f} |"
            )
    both = [
        f"{n} (`{c}`)"
        for (n, c), m in measured.items()
        if m["union"].ratio <= 0.30 and m["union"].ratio_positions <= 0.10
    ]
    former = measured["P-over-performances", "all"]["union"]
    lines += [
        "",
        "Rows that meet both union targets: " + (", ".join(both) if both else "none") + ". "
        "Two rows are the paper's wording taken literally where our reading fixes another: 'eigenvalue-weighted' "
        "(ours: `s_i / sum(s)`) and 'the sum of bone lengths of the joint's children' (ours: the whole subtree, "
        "'a shoulder moves the whole arm'). Neither says on which side the mean is taken out; `m^-1 q` (`q = m d`, "
        "the deviation in the joint's own mean frame) is the usual reading and the one the edit uses, and the DOF that "
        "reaches the share is part of the set ('accumulate until ... reached'). None of these readings was adopted. "
        "The one change from our reading that was adopted is the first row against `P-over-performances` (every cycle "
        f'averaged, predictability over the performances: the former `cycle="mean"` option; union {former.ratio:.3f} / '
        f"{former.ratio_positions:.3f}): with one sample per "
        "intensity the correlation behind predictability rests on three points, and for three points the correlation "
        "of "
        "pure noise follows the arcsine law (median |rho| 0.71); measured over every cycle it also sees how much a DOF "
        "varies from one step to the next. Which single cycle of each clip is taken moves the figures as much as any "
        "reading (`train(..., cycle=i)`, cycle `i` of each clip's left-foot cycles):",
        "",
        "| cycle | per person | union | ratio | positions | warp | Spearman |",
        "|---|---|---|---|---|---|---|",
    ]
    by_cycle = {}
    for cycle in (*CYCLES, 0, 1, 2, 3, -2, -1):
        m = variants.measure(people, "default", cycle)
        u = by_cycle[cycle] = m["union"]
        lines.append(
            f"| `{cycle}` | {variants.span([100 * v for v in m['share']], '{:.0f}')}%, "
            f"{variants.span(m['ratio'])} | {u.swapped} ({u.share:.0%}) | {u.ratio:.3f} | "
            f"{u.ratio_positions:.3f} | {m['warp']:.3f} ({m['warp_positions']:.3f}) | {m['spearman']:.3f} |"
        )
    single = {c: u for c, u in by_cycle.items() if c not in CYCLES}
    hits = [f"`{c}`" for c, u in single.items() if u.ratio <= 0.30 and u.ratio_positions <= 0.10]
    lines += [
        "",
        "With one cycle per clip the union ratios over DOFs range over "
        f"{min(u.ratio for u in single.values()):.3f}-{max(u.ratio for u in single.values()):.3f}, over positions "
        f"{min(u.ratio_positions for u in single.values()):.3f}-{max(u.ratio_positions for u in single.values()):.3f}"
        + (f" ({', '.join(hits)} meet both targets)" if hits else "")
        + ": the paper takes 'a single walk cycle' without saying which, and which one moves the "
        "result as much as the targets' margins. Choosing one because it meets them would be tuning; "
        "the default takes every cycle instead, which leaves no such choice and uses all the data.",
    ]
    # The union's tail: which single DOFs decide it (the default).
    P = default.trajectories.shape[0]
    tail = [d for d in np.argsort(-default.overall) if default.key[d] and default.person_key[:, d].sum() <= 2]
    outside = [d for d in np.argsort(-default.overall) if not default.key[d]][:4]
    base = swap_test(default)[-1]
    rows, moves = [], []
    for d in tail + outside:
        key = default.key.copy()
        key[d] = not key[d]
        u = swap_test(default, union_key=key)[-1]
        moves.append((abs(u.ratio - base.ratio), abs(u.ratio_positions - base.ratio_positions)))
        rows.append(
            f"| {'drop' if default.key[d] else 'add'} {default.dof_names[d]} | {default.overall[d]:.4f} | "
            f"{int(default.person_key[:, d].sum())} of {P} | {u.swapped} | {u.ratio:.3f} | {u.ratio_positions:.3f} |"
        )
    moves = np.max(moves, axis=0)
    lines += [
        "",
        f"Why the union's figures are fragile (`all`; {base.swapped} DOFs, {base.ratio:.3f} / "
        f"{base.ratio_positions:.3f}): its last members are key for only one or two of the {P} people, and one DOF "
        f"in or out moves the ratios by up to {moves[0]:.3f} over DOFs and {moves[1]:.3f} over positions. The union "
        "with one DOF toggled (its members key for at most two people, and the most expressive DOFs outside it):",
        "",
        "| DOF | mean E | key for | union | ratio | positions |",
        "|---|---|---|---|---|---|",
        *rows,
    ]
    lines.append("")
    return lines


def main() -> None:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_DATA
    figures = HERE / "figures"
    figures.mkdir(exist_ok=True)
    people = [[clip(data, f"walk_{s}_{p:03d}") for s in STYLES] for p in range(1, PEOPLE + 1)]
    report = ["# Exaggeration on Bandai-Namco dataset-2 walks", ""]
    report += [
        "Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0), walks `exhausted` < `normal` < `active` as "
        f'intensities 1 < 2 < 3. No actor label: "person" p (p = 1..{PEOPLE}) is take p of every style '
        f"(`walk_exhausted_00p`, `walk_normal_00p`, `walk_active_00p`); the held-out walk is `{HELD_OUT}` (in no "
        "person).",
        "Defaults of our reading of the paper (T = 50, rotation vectors relative to each person's "
        "mean, heading removed, hips height / actor height, 99% energy, share 0.9, lines), except "
        "where a row says otherwise, and except one choice: every cycle of a clip is used (its "
        "mean is the performance, predictability is measured over every cycle; `cycle = all`), "
        "where the paper takes one (`cycle = middle`, measured beside it throughout).",
        "Produced by `PYTHONPATH=python python experiments/exaggeration_experiment.py`.",
        "",
    ]
    models = {}
    for cycle in CYCLES:
        models[cycle] = train(people, LEVELS, cycle=cycle)
    report += ["## Swap test and leave-one-person-out warp", ""]
    report += [
        "Ratios `||swap - heavy|| / ||light - heavy||` (lower is better) over DOF trajectories "
        "and over world joint positions (pose and hips height, no path), with the random "
        "same-size set (mean of 200) and the best same-size set (largest light-heavy "
        "differences) in the same run. `union`: every person, the union key set, ratios averaged.",
        "",
    ]
    tests = {}
    for cycle, model in models.items():
        tests[cycle] = swap_test(model), leave_one_out(model), rank_agreement(model)
        report += [
            f"### cycle = `{cycle}` ({CYCLE_MEANING[cycle]})",
            "",
            "```",
            validation_table(*tests[cycle]),
            "```",
            "",
        ]
    default = models["all"]
    timed = timing_validation(default)
    report += [
        "### With and without timing (cycle = `all`)",
        "",
        "The ratios over world joint positions in time: each performance played for 2 s at 30 fps, cycle after "
        "cycle, at its own cycle duration, the hips travelling along the (heading-free) walking direction as far a "
        "cycle as its travel says. `swap`: the person's key DOFs swapped lightest -> heaviest, the lightest's timing "
        "kept; `+timing`: the heaviest's cycle duration and travel swapped in too. `warp`: the leave-one-person-out "
        "warp (the other people's mappings), the lightest's timing kept; `+timing`: the timing warped by the other "
        "people's timing mappings too. Without the timing the path and the phase drift apart from the heaviest's "
        "within the 2 s, so the ratios stay near 1 whatever the pose.",
        "",
        "```",
        timing_table(timed),
        "```",
        "",
    ]
    pooled = union_pooled(default)
    own_basis = np.any(
        [
            fit(default.trajectories[p : p + 1], default.levels, default.weights, cycles=default.cycles_of([p])).key
            for p in range(PEOPLE)
        ],
        axis=0,
    )
    union = tests["all"][0][-1]
    report += [
        "### The union's size",
        "",
        "The union ratio depends mostly on how many DOFs are swapped. Checked as causes of our smaller "
        f"union ({union.share:.0%} against the prototype's 52%) and ruled out, for `all`: pooling the "
        f"people's norms instead of averaging their ratios ({pooled[0]:.3f} / {pooled[1]:.3f} against "
        f"{union.ratio:.3f} / {union.ratio_positions:.3f}); a basis per person instead of the shared "
        f"one (a union of {int(own_basis.sum())} DOFs instead of {union.swapped}); the position ratio's "
        "frame (heading removed, hips at the origin, each person's rotations rebuilt from their own "
        "mean: the real poses, no path on the floor, which no DOF swap could carry). What differs is "
        "the ranking itself: our per-person key sets are a little smaller than the prototype's "
        f"(36-41%) and overlap more. Cut at the prototype's union size instead (the {PROTOTYPE_UNION} "
        "most expressive DOFs by the people's mean E; not the method's key set, for comparison only):",
        "",
        "| cycle | DOFs swapped | ratio | random | best | positions | random | best |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for cycle, model in models.items():
        top = np.zeros(model.n_dofs, dtype=bool)
        top[np.argsort(-model.overall)[:PROTOTYPE_UNION]] = True
        u = swap_test(model, union_key=top)[-1]
        report.append(
            f"| `{cycle}` | {u.swapped} ({u.share:.0%}) | {u.ratio:.3f} | {u.random:.3f} | {u.best:.3f} "
            f"| {u.ratio_positions:.3f} | {u.random_positions:.3f} | {u.best_positions:.3f} |"
        )
    report += ["| prototype | 35 (52%) | 0.27 | | | 0.075 | | |", ""]
    report += [
        "How much the union depends on which cycles are taken: the same method with cycles from right footstrikes "
        "instead of left (`train(..., foot=1)`; the basis is then aligned to the right foot's phase):",
        "",
        "| cycle | foot | union DOFs | ratio | positions | per person |",
        "|---|---|---|---|---|---|",
    ]
    for cycle in models:
        for foot in (0, 1):
            swaps = tests[cycle][0] if foot == 0 else swap_test(train(people, LEVELS, cycle=cycle, foot=1))
            u, pp = swaps[-1], swaps[:-1]
            report.append(
                f"| `{cycle}` | {'left' if foot == 0 else 'right'} | {u.swapped} ({u.share:.0%}) | {u.ratio:.3f} "
                f"| {u.ratio_positions:.3f} | {min(r.ratio for r in pp):.3f}-{max(r.ratio for r in pp):.3f} |"
            )
    report.append("")
    report += readings_checked(people, default)
    model = default
    model.plot(
        figures / "exaggeration_rank.png",
        title=f"Bandai dataset-2 walks, {PEOPLE} takes as people: expressiveness (red: key features)",
    )
    report += [
        "## Key features (cycle = `all`)",
        "",
        "![expressiveness](figures/exaggeration_rank.png)",
        "",
        "```",
        model.table(top=30),
        "```",
        "",
    ]

    # Exaggerate and diminish the held-out walk.
    walk = clip(data, HELD_OUT)
    rows, results = [], {}
    for k1 in (0.0, 4.0):
        for lock in (True, False):
            out, rep = exaggerate(model, walk, k1, lock_feet=lock)  # with timing (the default)
            results[k1, lock] = (out, rep)
            rows.append(
                f"| {rep.k0:.2f} (est.) | {k1:g} | {'yes' if lock else 'no'} | {rep.stance_speed_input:.1f} "
                f"| {rep.stance_speed_output:.1f} | {rep.stance_speed_output / rep.stance_speed_input:.2f} "
                f"| {rep.foot_correction:.1f} / {rep.foot_residual:.1f} | {len(rep.clamped)} | "
                + ", ".join(f"{n} {v:.0f}" for n, v in sorted(rep.largest_change.items(), key=lambda kv: -kv[1])[:4])
                + " |"
            )
    trained = np.concatenate([elbow_flexion(m) for person in people for m in person])
    margins = []
    for margin in (0.0, 0.1, 0.2, 0.5):
        out, rep = exaggerate(model, walk, 4.0, margin=margin)
        flexion = elbow_flexion(out).max(axis=0)
        margins.append(
            f"| {margin:g} | {flexion[0]:.0f} / {flexion[1]:.0f} | {len(rep.clamped)} | "
            + ", ".join(f"{n} {v:.0f}" for n, v in sorted(rep.largest_change.items(), key=lambda kv: -kv[1])[:4])
            + " |"
        )
    report += [
        f"## Exaggerating the held-out `{HELD_OUT}`",
        "",
        "`k0` estimated by least squares on the mappings, each key coefficient weighted by how well the mapping "
        "predicts it; every DOF clamped to the range seen in training (rotation-vector components measured from "
        "the people's mean rotations, as the edit measures them) widened by 10% of its width (the default margin); "
        "changes cross-faded over 0.15 s at cycle boundaries; foot locking: during the input's contacts each ankle "
        "and foot are pinned to the input's with two-bone leg IK, eased in and out over 0.1 s. Stance-foot speed: "
        "mean horizontal speed of ankle and toe over the input's contact frames (cm/s); ankle correction: the "
        "largest distance (cm) the IK moved an ankle / the largest it could not close (out of reach).",
        "",
        "| k0 | k1 | foot lock | stance speed in | out | ratio | ankle "
        "correction / left (cm) | DOFs clamped | largest changes (deg) |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "The margin and the elbows at k = 4 (elbow flexion: the angle between upper-arm and "
        f"forearm bones, 0 = straight; over every frame of the {3 * PEOPLE} training clips it "
        f"reaches {trained[:, 0].max():.0f} / {trained[:, 1].max():.0f} degrees left / right, the "
        f"input {elbow_flexion(walk)[:, 0].max():.0f} / {elbow_flexion(walk)[:, 1].max():.0f}):",
        "",
        "| margin | largest elbow flexion L / R (deg) | DOFs clamped | largest changes (deg) |",
        "|---|---|---|---|",
        *margins,
        "",
    ]
    for k1 in (0.0, 4.0):
        report += [f"Report for k1 = {k1:g} with foot locking:", "", "```", results[k1, True][1].text(), "```", ""]
    frames = slice(40, 120)
    render(
        [results[0.0, True][0][frames], walk[frames], results[4.0, True][0][frames]],
        figures / "exaggeration_walks.png",
        titles=["diminished (k = 0)", f"{HELD_OUT} (k0 = {results[4.0, True][1].k0:.2f})", "exaggerated (k = 4)"],
        poses=6,
    )
    report += ["![diminished, input, exaggerated](figures/exaggeration_walks.png)", ""]

    # Speed.
    one = people[0]
    rank_ms = best_of(lambda: train([one], LEVELS))
    long_walk = procedural_walk(999 / 30)
    exaggerate_ms = best_of(lambda: exaggerate(model, long_walk, 3.0, current=2.0))
    report += [
        "## Speed",
        "",
        "- ranking and mappings, one person, 3 intensities x 22 joints, after loading "
        f"(cycles, FK, contacts included): **{rank_ms:.1f} ms** (best of 7; target < 50 ms)",
        f"- exaggerating a {long_walk.n_frames}-frame walk (the procedural walk on the same "
        f"skeleton; foot locking on): **{exaggerate_ms:.1f} ms** (best of 7; target < 100 ms)",
        f"- kernels: {em.get_backend()}; BLAS threads: OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')} "
        "(with OpenBLAS's default threads on this busy 2-core machine the SVD alone took ~300 ms)",
        "",
    ]
    # The targets we set.
    ex = results[4.0, True][1]

    def reached(cycle: str) -> list[str]:
        swaps, warps, agreement = tests[cycle]
        per_person = [s for s in swaps if s.person != "union"]
        union = swaps[-1]
        return [
            f"{min(s.ratio for s in per_person):.3f}-{max(s.ratio for s in per_person):.3f}",
            "margins "
            f"{min(s.random - s.ratio for s in per_person):.3f}-{max(s.random - s.ratio for s in per_person):.3f}",
            f"{union.ratio:.3f} ({union.share:.0%} of DOFs swapped)",
            f"{union.ratio_positions:.3f}",
            f"mean {np.mean([w.ratio for w in warps]):.3f} (range "
            f"{min(w.ratio for w in warps):.3f}-{max(w.ratio for w in warps):.3f})",
            f"{agreement.mean:.3f} ({agreement.dofs} DOFs with E > 0); {agreement.mean_all:.3f} (all DOFs)",
        ]

    targets = [
        "per person ratio <= 0.40 at share 0.9",
        "... and at least 0.3 below random",
        "union ratio <= 0.30 over DOFs",
        "union ratio <= 0.10 over positions",
        "held-out-person warp <= 0.45",
        "rank agreement between people, Spearman (prototype: about 0.93)",
    ]
    report += [
        "## Against the targets we set",
        "",
        "| target | cycle = `all` (default) | cycle = `middle` |",
        "|---|---|---|",
        *(f"| {t} | {a} | {b} |" for t, a, b in zip(targets, reached("all"), reached("middle"))),
        "| exaggerated walk's stance-foot speed with foot locking <= 1.2x the "
        f"input's (k = 4) | {ex.stance_speed_output / ex.stance_speed_input:.2f}x | |",
        "",
    ]
    atomic_write(HERE / "EXAGGERATION.md", "\n".join(report).encode())
    print("\n".join(report))


if __name__ == "__main__":
    main()
