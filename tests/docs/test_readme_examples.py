"""The command examples of the README and of docs/*.md, run as written on the real clips they name
(placeholders such as walk.bvh and wave.bvh stand for the dataset-2 clips below), page after page in
the order of PAGES (a page's commands may use what an earlier one wrote), each distinct command
once, in one folder; then every BVH
they write is checked for plausibility: no hips step longer than 5 cm a frame at 30 fps or than
the inputs' own longest (in the file's units, relative to its actor's height), and an exaggerated
walk's stance feet no higher than the input's (foot locking). Data: Bandai-Namco-Research-
Motiondataset, CC BY-NC 4.0."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.body import actor_height
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.roles import JointRoles
from expressive_mocap.cli import main

REPO = Path(__file__).resolve().parents[2]
BANDAI_ACTOR_CM = 140.9  # the Bandai skeleton's actor height: 5 cm a frame is relative to it
PLACEHOLDERS = {
    "walk.bvh": "dataset-2_walk_normal_001.bvh",
    "clip.bvh": "dataset-2_walk_normal_001.bvh",
    "wave.bvh": "dataset-2_wave-right-hand_normal_001.bvh",
    "other_session_walk.bvh": "dataset-1_walk_normal_001.bvh",
}
NOT_RUN = {
    "info broken.bvh": "shows an error message for a file the pages do not give",
    "--body-model": "needs the user's own SMPL-family body model, never shipped (see tests/skeletons/test_smpl.py)",
}
# The pages whose examples run, in this order: the README's tour, then the manual. A page's commands
# may use an earlier one's outputs (exaggerate --model walks.npz after rank ... -o walks.npz).
PAGES = [
    "README.md",
    "docs/demo.md",
    "docs/bvh.md",
    "docs/skeletons.md",
    "docs/positions.md",
    "docs/skeletons-results.md",
    "docs/decoupling.md",
    "docs/decoupling-results.md",
    "docs/exaggeration.md",
    "docs/exaggeration-results.md",
    "docs/models.md",
    "docs/preprocessing.md",
    "docs/training.md",
    "docs/torch.md",
    "docs/cluster.md",
    "docs/ml_datasets.md",
    "docs/speed.md",
    "docs/safety.md",
    "docs/methods.md",
    "docs/data.md",
    "docs/development.md",
]


def page_commands(page: str) -> list[str]:
    """Every `expressive-mocap ...` line of a page's ```sh and ```text blocks (after `$ ` in
    transcripts), without trailing comments, in order; `validate ...` is given the model written
    before it."""
    text = (REPO / page).read_text()
    commands = []
    for block in re.findall(r"```(?:sh|text)\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = line.removeprefix("$ ")
            if re.match(r"(EXPRESSIVE_MOCAP_BACKEND=\w+ )?expressive-mocap [a-z]", line):
                command = line.split(" #")[0].strip().replace("validate ...", "validate --model walks.npz")
                if not any(skip in command for skip in NOT_RUN):
                    commands.append(command)
    return commands


def readme_commands() -> list[str]:
    """The commands of every page of PAGES, page after page."""
    return [command for page in PAGES for command in page_commands(page)]


def python_examples(page: str) -> list[str]:
    """The ```python blocks of a page."""
    return re.findall(r"```python\n(.*?)```", (REPO / page).read_text(), re.S)


def test_the_readme_python_example_runs_and_prints_what_it_says(tmp_path, monkeypatch, capsys):
    """The README's Python example, run as written on the demo's walk and wave (no data needed):
    each `print(...)` prints what the comment on its line says (up to its colon), and the files it
    writes read back as the demo's 121 frames, the wave's hand moved by the edits."""
    [example] = python_examples("README.md")
    assert 8 <= len([line for line in example.splitlines() if line.strip()]) <= 14, "about ten lines"
    monkeypatch.chdir(tmp_path)
    exec(compile(example, "README.md (Python example)", "exec"), {"__name__": "readme_example"})
    prints = [line for line in example.splitlines() if line.startswith("print(")]
    promised = [line.split("#", 1)[1].split(":")[0].strip() for line in prints]
    assert capsys.readouterr().out.splitlines() == promised
    from expressive_mocap.procedural import walk_and_wave

    walk, waving = walk_and_wave()
    hand = waving.skeleton.index("Hand_R")
    waving_hand = waving.positions()[:, hand]
    for name, farther in (("wave150.bvh", True), ("no_wave.bvh", False)):
        edited = em.read_bvh(tmp_path / name)
        assert edited.n_frames == waving.n_frames == 121 and edited.skeleton.names == waving.skeleton.names
        # 150%: the hand goes farther from the walk's than the wave takes it; 0%: back near the walk's.
        off_walk = np.linalg.norm(edited.positions()[:, hand] - walk.positions()[:, hand], axis=1).mean()
        wave_off_walk = np.linalg.norm(waving_hand - walk.positions()[:, hand], axis=1).mean()
        assert (off_walk > wave_off_walk) if farther else (off_walk < 0.25 * wave_off_walk), (name, off_walk)


def test_every_page_of_the_manual_is_run():
    pages = {"README.md"} | {f"docs/{p.name}" for p in (REPO / "docs").glob("*.md")}
    assert pages == set(PAGES), (
        f"add the new pages to PAGES, in an order their commands run in: {sorted(pages ^ set(PAGES))}"
    )


def real_arguments(
    command: str, dataset1: Path, dataset2: Path, other: Path | None = None
) -> tuple[list[str], str | None]:
    """The command's arguments with the README's clip names made paths, and the backend it sets."""
    backend = None
    if command.startswith("EXPRESSIVE_MOCAP_BACKEND="):
        setting, command = command.split(" ", 1)
        backend = setting.split("=", 1)[1]
    args = []
    for token in shlex.split(command)[1:]:
        token = PLACEHOLDERS.get(token, token)
        ranged = re.fullmatch(r"\.\.\.(\w+)_00\{(\d)\.\.(\d)\}\.bvh", token)  # ...exhausted_00{1..8}.bvh
        if ranged:
            args += [
                str(dataset2 / f"dataset-2_walk_{ranged[1]}_00{k}.bvh")
                for k in range(int(ranged[2]), int(ranged[3]) + 1)
            ]
        elif token.startswith("dataset-2_"):
            args.append(str(dataset2 / token))
        elif token.startswith("dataset-1_"):
            args.append(str(dataset1 / token))
        elif token == "Bandai-Namco-Research-Motiondataset-2/data":
            args.append(str(dataset2))
        elif other is not None and (other / token).is_file():  # the non-Bandai files (CMU, Xia-style)
            args.append(str(other / token))
        elif token == "mocap/":  # an archive mixing skeletons: the non-Bandai files beside Bandai walks
            args.append(str(_mixed_archive(dataset2, other)))
        else:
            args.append(token)
    return args, backend


def hips_steps(motion: em.Motion) -> tuple[float, float]:
    """The longest hips step between frames and the motion's pace (the 90th percentile step), per
    frame at 30 fps, in cm of a Bandai-sized actor."""
    roles = JointRoles.find(motion.skeleton)
    hips = motion.positions()[:, roles.hips]
    steps = np.linalg.norm(np.diff(hips, axis=0), axis=1) * motion.fps / 30
    scale = BANDAI_ACTOR_CM / actor_height(motion.skeleton)
    return float(steps.max()) * scale, float(np.percentile(steps, 90)) * scale


def _mixed_archive(dataset2: Path, other: Path | None) -> Path:
    folder = Path("mocap")
    if not folder.exists():
        folder.mkdir()
        for path in [*(other.glob("*.bvh") if other else []), *sorted(dataset2.glob("dataset-2_walk_normal_*"))[:3]]:
            (folder / path.name).symlink_to(path)
    return folder


def test_the_readme_examples_run_and_their_outputs_are_plausible(
    bandai1_dir, bandai2_dir, other_dir, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    commands = readme_commands()
    assert any(c.startswith("expressive-mocap blend ") for c in commands) and len(commands) >= 15
    longest_input_step = {}
    done = set()
    for command in commands:
        args, backend = real_arguments(command, bandai1_dir, bandai2_dir, other_dir)
        if (backend, *args) in done:  # the README's tour repeats a few of the manual's examples
            continue
        done.add((backend, *args))
        with em.use_backend(backend or "auto"):
            status = main(args)
        err = capsys.readouterr().err
        assert status == 0, f"{command}: {err}"
        inputs = [Path(a) for a in args if a.endswith(".bvh") and Path(a).is_absolute()]
        outputs = [Path(a) for a in args if a.endswith(".bvh") and not Path(a).is_absolute() and Path(a).exists()]
        if args[0] == "decouple":
            outputs = sorted(tmp_path.glob(f"{args[args.index('-o') + 1]}_*.bvh"))
        for path in inputs:
            longest_input_step.setdefault(path, hips_steps(em.read_bvh(path)))
        for path in outputs:
            step, pace_out = hips_steps(em.read_bvh(path))
            # A jump is a step beyond the output's own pace: an exaggerated walk is faster throughout.
            allowed = max(
                [5.0]
                + [1.05 * longest * max(1.0, pace_out / pace) for longest, pace in map(longest_input_step.get, inputs)]
            )
            assert step <= allowed, (
                f"{command}: {path.name} moves its hips {step:.1f} cm in a frame (allowed {allowed:.1f})"
            )
    # The exaggerated walk keeps its stance feet down (foot locking): never above the input's. It is
    # retimed (faster), so its own contacts are compared with the input's highest stance ankle.
    walk = em.read_bvh(bandai2_dir / PLACEHOLDERS["walk.bvh"])
    heavier = em.read_bvh(tmp_path / "heavier.bvh")
    roles = JointRoles.find(walk.skeleton)
    contacts, heavier_contacts = foot_contacts(walk), foot_contacts(heavier)
    for side, foot in enumerate(roles.feet):
        highest = walk.positions()[contacts[:, side], foot, 1].max()
        rise = heavier.positions()[heavier_contacts[:, side], foot, 1].max() - highest
        assert rise <= 1.0, f"a stance foot rises {rise:.2f} cm above the input's"
