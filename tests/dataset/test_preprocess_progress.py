"""The progress bar of ``preprocess``: its count of files done and its total count the same unit,
BVH files (a mirror image is not a file), whatever ``--mirror`` adds to the dataset."""

from __future__ import annotations

import io
import re
import zipfile

from expressive_mocap._utils.progress import Progress
from expressive_mocap.dataset import load_dataset, preprocess

# Short dataset-2 clips (Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0).
CLIPS = ("raise-up-both-hands_active_022", "raise-up-both-hands_active_025", "wave-left-hand_active_011")


class Terminal(io.StringIO):
    def isatty(self):
        return True


class EveryUpdate(Progress):
    """A bar drawn at every update (a terminal's is drawn at most 10 times a second)."""

    def update(self, amount: float = 1, note: str = "") -> None:
        self.shown = -1e9
        super().update(amount, note)


def test_with_mirror_the_bar_counts_files_on_both_sides(bandai2_dir, tmp_path, monkeypatch):
    archive = tmp_path / "clips.zip"
    with zipfile.ZipFile(archive, "w") as out:
        for clip in CLIPS:
            out.write(bandai2_dir / f"dataset-2_{clip}.bvh", f"dataset-2_{clip}.bvh")
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monkeypatch.setattr("expressive_mocap.dataset.run.Progress", EveryUpdate)
    summary = preprocess(archive, tmp_path / "m", mirror=True, batch_mb=0.01)  # a clip a batch
    ds = load_dataset(tmp_path / "m")
    assert summary.clips_ok == 2 * len(CLIPS) and summary.clips_mirrored == len(CLIPS)
    shown = re.findall(r"(\d+)/(\d+) files, ([\d,]+) frames", terminal.getvalue())
    done = [int(d) for d, _, _ in shown]
    assert len(shown) >= len(CLIPS) + 1  # each batch's update, then the close
    assert {int(t) for _, t, _ in shown} == {len(CLIPS)}  # the total: the archive's files
    assert done == sorted(done) and done[0] >= 1 and done[-1] == len(CLIPS)  # never past it
    assert int(shown[-1][2].replace(",", "")) == len(ds.positions)  # frames: every row stored, images too
