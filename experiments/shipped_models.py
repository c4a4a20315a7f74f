"""One picture per shipped exaggeration model: a held-out take of its middle style diminished to
1, as it is, and exaggerated to 3.

    python experiments/shipped_models.py [--data DIR]

For every model that ships (`expressive-mocap models`), the first held-out take (take 9) of its
axis' middle style (normal) is edited by that model as `exaggerate --action A --axis X` edits it
(default settings, the current intensity estimated) to 1 and to 3, and the three are drawn side
by side as stick figures, seen from the side, at the same moments of the clip (the edits keep
their own timing, so their moments fall at the same share of each clip). Writes
experiments/figures/shipped_<action>.<axis>.png and the page docs/models.md.

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import warnings

import expressive_mocap as em
from expressive_mocap.exaggeration import exaggerate
from expressive_mocap.exaggeration.zoo import PEOPLE, shipped_models
from expressive_mocap.viz.render import render_poses
from setting import REPO, arguments, bandai_dir

PAGE = """# The shipped exaggeration models, one picture each

`expressive-mocap models` lists every model of the recipe, shipped or not, with its training
split and validation figures; `expressive_mocap/data/exaggeration/MODEL_CARD.md` is the card and
[exaggeration.md](exaggeration.md) says how `exaggerate` picks a model. Below, each shipped
model on a take it never saw (dataset-2's take 9 of the axis' middle style): diminished to 1, as
it is, and exaggerated to 3, drawn at the same moments of each clip. Made by
`python experiments/shipped_models.py`. Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC
4.0); the models are derivatives of it, for non-commercial use under the same licence.
"""


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    sections = [PAGE]
    for shipped in shipped_models():
        low, middle, high = shipped.styles
        path = dataset / f"dataset-2_{shipped.action}_{middle}_{len(PEOPLE) + 1:03d}.bvh"
        take = em.read_bvh(path)
        model = shipped.load()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            (down, report), (up, _) = (exaggerate(model, take, to) for to in (1.0, 3.0))
        name = f"shipped_{shipped.action}.{shipped.axis}.png"
        render_poses(
            [down, take, up],
            REPO / "experiments" / "figures" / name,
            [f"to 1 ({low})", f"{middle}, take {len(PEOPLE) + 1} (k0 {report.k0:.2f})", f"to 3 ({high})"],
            poses=6,
        )
        sections.append(
            f"## {shipped.action}, {shipped.axis} ({low} 1 < {middle} 2 < {high} 3)\n\n"
            f"![{path.stem} diminished to 1 and exaggerated to 3 by the {shipped.name} model]"
            f"(../experiments/figures/{name})\n"
        )
        print(shipped.name, flush=True)
    (REPO / "docs" / "models.md").write_text("\n".join(sections))


if __name__ == "__main__":
    main()
