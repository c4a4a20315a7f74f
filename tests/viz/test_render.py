"""`render` draws the same picture whatever the file's units, frame rate or walking direction:
sizes follow the figure, GIFs play in real time, views follow the walker, a legend says what the
shading means."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat
from expressive_mocap.viz import render as render_module

CMU = Path(__file__).resolve().parents[3] / "shared" / "data" / "other" / "cmu_scaled_131_03.bvh"


@pytest.fixture
def cmu_path() -> Path:
    """A CMU clip at 120 fps (in metres), from the project's shared data."""
    if not CMU.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI=true but {CMU} is missing")
        pytest.skip(f"{CMU} is not here (it comes with the project's shared/ folder)")
    return CMU


@pytest.fixture
def drawn(monkeypatch):
    """render_poses' figures, kept instead of saved: ``drawn(motions, **options) -> Figure``."""
    figures = []

    def draw(motions, **options):
        with monkeypatch.context() as patch:
            patch.setattr(render_module, "_save", lambda fig, plt, path: figures.append(fig))
            render_module.render_poses(motions, "unused.png", **options)
        return figures[-1]

    return draw


def lines_of(ax) -> np.ndarray:
    """The stick figures' line ends ``[L, 2, 2]`` of one panel (the floor line left out)."""
    return np.array(
        [
            line.get_xydata()
            for line in ax.lines
            if len(line.get_xydata()) == 2 and line.get_linestyle() == "-" and line.get_color() != "0.7"
        ]
    )


def gif_seconds(path: Path) -> tuple[float, list[int]]:
    with Image.open(path) as gif:
        delays = []
        for k in range(gif.n_frames):
            gif.seek(k)
            delays.append(gif.info["duration"])
    return sum(delays) / 1000, delays


def turned(motion: em.Motion, degrees: float) -> em.Motion:
    """The same motion turned about the vertical axis through the origin."""
    q = quat.about("Y", degrees)
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[:, 0] = quat.mul(q, rotations[:, 0])
    translations[:, 0] = quat.rotate(q, translations[:, 0])
    return em.Motion(motion.skeleton, rotations, translations, motion.frame_time)


def test_a_file_in_metres_draws_the_same_picture_as_in_centimetres(tmp_path, drawn):
    walk = procedural_walk(seconds=2.0)
    metres = walk.scaled(0.01)
    for motion, name in ((walk, "cm.png"), (metres, "m.png")):
        render_module.render([motion], tmp_path / name)
    cm_png, m_png = (np.asarray(Image.open(tmp_path / n).convert("L")) for n in ("cm.png", "m.png"))
    # Failed before: 10-unit margins made the metres picture 59 px tall against 297, its figure a speck.
    assert cm_png.shape == m_png.shape
    inked_cm, inked_m = (np.mean(png < 200) for png in (cm_png, m_png))
    assert inked_m == pytest.approx(inked_cm, rel=0.05)

    ax_cm, ax_m = drawn([walk]).axes[0], drawn([metres]).axes[0]  # both drawn in metres
    np.testing.assert_allclose(ax_m.get_xlim(), ax_cm.get_xlim(), rtol=1e-9)
    np.testing.assert_allclose(ax_m.get_ylim(), ax_cm.get_ylim(), rtol=1e-9)
    np.testing.assert_allclose(lines_of(ax_m), lines_of(ax_cm), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(
        [line.get_linewidth() for line in ax_m.lines], [line.get_linewidth() for line in ax_cm.lines], rtol=1e-9
    )


def test_panels_in_other_units_share_one_real_scale(drawn):
    """A clip in centimetres beside the same clip in metres: one figure, one height (file units
    drew the metres one a hundredth as tall; a CMU file beside a Bandai-Namco one a fifth)."""
    walk = procedural_walk(seconds=2.0)
    cm_panel, m_panel = drawn([walk, walk.scaled(0.01)]).axes[:2]
    np.testing.assert_allclose(lines_of(m_panel), lines_of(cm_panel), rtol=1e-9, atol=1e-9)
    heights = np.ptp(lines_of(cm_panel)[..., 1])
    assert 1.3 < heights < 2.0  # metres: the procedural actor stands about 1.6 m


@pytest.mark.parametrize("fps", [120.0, 30.0])
def test_a_gif_plays_in_real_time_whatever_the_frame_rate(tmp_path, fps):
    walk = procedural_walk(seconds=1.5).resample(fps=fps)
    render_module.render([walk], tmp_path / "walk.gif")
    seconds, delays = gif_seconds(tmp_path / "walk.gif")
    # Failed before: 3.62 s for 1.51 s at 120 fps (0.42x real time), 1.38 s for 1.53 s at 30 fps (1.11x).
    assert seconds == pytest.approx(walk.n_frames * walk.frame_time, abs=0.021)  # within the shortest delay
    assert min(delays) >= 20  # browsers play shorter delays as 100 ms


def test_the_cmu_clip_at_120_fps_plays_for_its_own_duration(tmp_path, cmu_path, capsys):
    clip = em.read_bvh(cmu_path)[:240]
    em.write_bvh(clip, tmp_path / "cmu.bvh")
    assert main(["render", str(tmp_path / "cmu.bvh"), "-o", str(tmp_path / "cmu.gif")]) == 0
    seconds, _ = gif_seconds(tmp_path / "cmu.gif")
    # Failed before: 4.80 s for a 2.00 s clip.
    assert seconds == pytest.approx(clip.n_frames * clip.frame_time, rel=0.02)
    assert "every 3 frames of 120 fps" in capsys.readouterr().out


def test_the_side_view_follows_the_walker_not_the_world(drawn):
    along_z = procedural_walk(seconds=2.0)
    along_x = turned(along_z, 90.0)
    hips = along_x.positions()[:, 1]
    assert hips[-1, 0] - hips[0, 0] > 200 and abs(hips[-1, 2] - hips[0, 2]) < 5  # the turned walk goes along +X
    for view in ("side", "front"):
        z, x = lines_of(drawn([along_z], view=view).axes[0]), lines_of(drawn([along_x], view=view).axes[0])
        # Failed before: the walk along X was drawn from its front in the "side" view, its poses piled up.
        np.testing.assert_allclose(x, z, atol=1e-6)
    side = lines_of(drawn([along_x], view="side").axes[0])
    first, last = side[: len(side) // 8], side[-len(side) // 8 :]
    assert last[..., 0].mean() - first[..., 0].mean() > 2.0  # walking to the right (drawn in metres)


def test_the_legend_says_what_the_shading_means(drawn):
    fig = drawn([procedural_walk(seconds=1.0)], poses=5)
    # Failed before: the figure had no legend.
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == ["first frame", "last frame"]
    assert "later ones darker" in legend.get_title().get_text()
    per_pose = len(lines_of(fig.axes[0])) // 5
    poses = [line for line in fig.axes[0].lines if line.get_color() != "0.7"]
    first, last = poses[0].get_color(), poses[-1].get_color()
    assert [h.get_color() for h in legend.legend_handles] == [first, last]
    assert poses[per_pose - 1].get_color() == first and poses[-per_pose].get_color() == last
