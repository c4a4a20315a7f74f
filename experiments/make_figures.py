"""Redraw the README's pictures: python experiments/make_figures.py [--data DIR]

The real-clip pictures use the Bandai-Namco-Research-Motiondataset (CC BY-NC 4.0), unpacked
from ../shared/data with its `unpack` script when --data is not given.
"""

from __future__ import annotations

import argparse
import subprocess
from pathlib import Path

import expressive_mocap as em
from expressive_mocap.body.contacts import cadence, foot_contacts
from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.viz.render import plot_contacts, render

HERE = Path(__file__).resolve().parent


def dataset_dir(given: str | None) -> Path:
    if given:
        return Path(given)
    unpack = HERE.parent.parent / "shared" / "data" / "unpack"
    out = subprocess.run(
        [str(unpack), str(Path.home() / ".cache" / "motion-data")], capture_output=True, text=True, check=True
    )
    return Path(out.stdout.strip()) / "Bandai-Namco-Research-Motiondataset-2" / "data"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", help="folder of dataset-2 BVH files")
    args = parser.parse_args()
    out = HERE / "figures"
    out.mkdir(exist_ok=True)
    data = dataset_dir(args.data)
    walks = [em.read_bvh(data / f"dataset-2_walk_{style}_001.bvh") for style in ("normal", "exhausted")]
    # The demo at the real clip's speed, with and without its wave, above 4 s of that clip.
    demo = walk_and_wave(seconds=4.0, speed=1.1)
    titles = [
        "procedural walk (demo), 1.1 m/s",
        "the same, waving the right arm",
        "dataset-2_walk_normal_001, 1.1 m/s (Bandai-Namco, CC BY-NC 4.0)",
    ]
    render([demo.walk, demo.waving, walks[0][30:151]], out / "demo_walk.png", titles=titles)
    render(walks, out / "bandai_walks.png", titles=["walk, normal", "walk, exhausted"], poses=6)
    contacts_figure(walks[0], out / "bandai_walk_contacts.png")
    skeletons_figure(data, out / "retargeted.png")
    print(f"wrote {out}")


def skeletons_figure(data: Path, path: Path) -> None:
    """A dataset-2 wave on the CMU and Xia-style skeletons, and the CMU walk on the Bandai one,
    each drawn in metres (the files' units differ)."""
    from expressive_mocap.body import find_joint_map, read_conventions, to_canonical
    from expressive_mocap.skeletons import retarget

    other = HERE.parent.parent / "shared" / "data" / "other"
    wave = em.read_bvh(data / "dataset-2_wave-left-hand_normal_001.bvh")
    cmu, xia = em.read_bvh(other / "cmu_scaled_131_03.bvh"), em.read_bvh(other / "dme_demo_3d_1.bvh")
    panels = [
        ("Bandai wave (22 joints, cm)", wave),
        ("on CMU's skeleton (31, m)", retarget(wave, cmu)),
        ("on a Xia-style skeleton", retarget(wave, xia)),
        ("CMU 131_03 on Bandai's", retarget(cmu[:600], wave)),
    ]
    in_metres = [to_canonical(m, read_conventions(m, find_joint_map(m.skeleton))) for _, m in panels]
    render(in_metres, path, titles=[t for t, _ in panels], poses=5, view="front")


def contacts_figure(walk: em.Motion, path: Path) -> None:
    contacts = foot_contacts(walk)
    title = (
        "dataset-2_walk_normal_001: foot contacts, "
        f"{cadence(contacts, walk.frame_time):.2f} steps/s (Bandai-Namco, CC BY-NC 4.0)"
    )
    plot_contacts(contacts, walk.frame_time, path, title=title)


if __name__ == "__main__":
    main()
