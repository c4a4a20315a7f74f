"""Progress on stderr: redrawn in place on a terminal, plain lines elsewhere, nothing when quiet."""

import io

from expressive_mocap._utils.progress import Progress, line_log


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_terminal_gets_one_line_redrawn_with_counts_rate_and_time_left():
    out = Terminal()
    bar = Progress(10, "reading", "files", stream=out)
    bar.shown = -1e9  # draw at the next update
    bar.update(4)
    bar.close()
    text = out.getvalue()
    assert (
        text.startswith("\rreading [########............] 4 files/10 files (40%)")
        and "files/s" in text
        and "left" in text
    )
    assert text.count("\n") == 1 and text.endswith("\n") and text.count("\r") == 2


def test_elsewhere_plain_lines_and_quiet_means_nothing():
    out = io.StringIO()
    with Progress(3, "clips", stream=out, every=0.0) as bar:
        for _ in range(3):
            bar.update()
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue() and len(lines) == 4 and lines[-1].startswith("clips 3/3 (100%)")
    quiet = io.StringIO()
    with Progress(3, "clips", stream=quiet, enabled=False) as bar:
        bar.update(3)
    assert quiet.getvalue() == ""


def test_line_log_redraws_running_lines_only_on_a_terminal():
    terminal, plain = Terminal(), io.StringIO()
    for stream in (terminal, plain):
        log = line_log(stream=stream)
        log("fit: iteration 1/3\r")
        log("fit: iteration 2/3\r")
        log("fit: 3 iterations")
    assert terminal.getvalue().count("\n") == 1 and "iteration 2/3" in terminal.getvalue()
    assert plain.getvalue().splitlines() == ["fit: iteration 1/3", "fit: 3 iterations"]  # running lines every 10 s


def test_commands_reading_many_clips_show_a_bar_on_a_terminal_and_nothing_quick_in_logs(mixed_path, monkeypatch):
    from expressive_mocap.cli import common

    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert len(common.read_all([str(mixed_path)] * 3, "clips")) == 3
    assert terminal.getvalue().startswith("\rreading clips [") and "3 files/3 files (100%)" in terminal.getvalue()
    log = io.StringIO()
    monkeypatch.setattr("sys.stderr", log)
    common.read_all([str(mixed_path)] * 3, "clips")
    assert log.getvalue() == ""  # under 10 s: no line in a log
