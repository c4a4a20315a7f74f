"""``render`` shows a bar of the GIF's frames on a terminal while it draws them, nothing
elsewhere unless asked, and nothing when told not to."""

from __future__ import annotations

import io
import re

from PIL import Image

from expressive_mocap.cli import main
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.viz.render import render


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_gif_shows_its_frames_drawn_on_a_terminal(tmp_path, monkeypatch):
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    render([procedural_walk(seconds=1.0)], tmp_path / "walk.gif")
    frames = Image.open(tmp_path / "walk.gif").n_frames
    text = terminal.getvalue()
    assert text.startswith("\rrender [") and text.endswith("\n")
    assert f"{frames} frames/{frames} frames (100%)" in text and f"wrote {tmp_path / 'walk.gif'}" in text
    counts = [(int(a), int(b)) for a, b in re.findall(r"(\d+) frames/(\d+) frames", text)]
    assert all(done <= total == frames for done, total in counts)


def test_no_bar_in_a_log_or_when_not_wanted_and_none_for_a_png(tmp_path, monkeypatch):
    walk = procedural_walk(seconds=1.0)
    log = io.StringIO()
    monkeypatch.setattr("sys.stderr", log)
    render([walk], tmp_path / "a.gif")  # stderr not a terminal: no bar
    assert log.getvalue() == ""
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    render([walk], tmp_path / "b.gif", progress=False)
    render([walk], tmp_path / "c.png")
    assert terminal.getvalue() == ""


def test_the_command_line_reports_progress_on_a_terminal(tmp_path, monkeypatch, capsys):
    walk = tmp_path / "walk.bvh"
    from expressive_mocap import write_bvh

    write_bvh(procedural_walk(seconds=1.0), walk)
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert main(["render", str(walk), "-o", str(tmp_path / "w.gif")]) == 0
    frames = Image.open(tmp_path / "w.gif").n_frames
    assert f"{frames} frames/{frames} frames (100%)" in terminal.getvalue()
