#!/usr/bin/env python
"""Start-up of the command line: ``expressive-mocap --version`` and ``info FILE``, whole processes.

    python benches/bench_startup.py [--rounds 21] [--file FILE.bvh] [--write-results]

Each command line runs in a fresh process (``python -m expressive_mocap.cli ...``), the lines
alternated round after round; the median and the fastest of each are reported beside the bare
interpreter (``python -c pass``: what no package can save) and NumPy's import. The package's
modules are byte-compiled first, as an installed package's are. ``FILE`` defaults to the test
suite's small file (no data needed); the target is 0.1 s for each command line.
"""

from __future__ import annotations

import argparse
import datetime
import os
import subprocess
import sys
from pathlib import Path

from harness import byte_compile, check, clock, commit, cpu_name, log, median, rotated
from results import write_section

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FILE = REPO / "tests" / "data" / "mixed_orders.bvh"
TITLE = "Start-up and the command line: `expressive-mocap --version`, `info`"
TARGET_SECONDS = 0.1


def seconds(command: list[str], env: dict) -> float:
    started = clock()
    done = subprocess.run(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    elapsed = clock() - started
    check(done.returncode == 0, f"{' '.join(command)} failed: {done.stderr.decode(errors='replace')[-500:]}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=21, help="runs of each command line (default 21)")
    parser.add_argument("--file", type=Path, default=DEFAULT_FILE, help="the file `info` reads")
    parser.add_argument("--write-results", action="store_true", help="rewrite this section of benches/RESULTS.md")
    args = parser.parse_args()

    byte_compile(REPO / "python" / "expressive_mocap")
    env = {**os.environ, "PYTHONPATH": str(REPO / "python")}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    cli = [sys.executable, "-m", "expressive_mocap.cli"]
    lines = {
        "`python -c pass` (the interpreter alone, site hooks included)": [sys.executable, "-c", "pass"],
        "`python -c 'import numpy'`": [sys.executable, "-c", "import numpy"],
        "`--version`": [*cli, "--version"],
        f"`info {args.file.name}`": [*cli, "info", str(args.file)],
    }
    when, t0 = datetime.datetime.now(), clock()
    times: dict[str, list[float]] = {name: [] for name in lines}
    for r in range(args.rounds):
        for name in rotated(list(lines), r):
            times[name].append(seconds(lines[name], env))
    log(f"{args.rounds} rounds in {clock() - t0:.1f} s")

    rows = [
        f"- date: {when:%Y-%m-%d %H:%M}; machine: {cpu_name()}, {os.cpu_count()} cores; Python "
        f"{sys.version.split()[0]}; commit {commit(REPO)}; load average at the start "
        f"{', '.join(f'{x:.1f}' for x in os.getloadavg())}",
        f"- command: `python benches/bench_startup.py --rounds {args.rounds}`: fresh processes, "
        "alternated, the package byte-compiled; medians (fastest)",
        "",
        "| command line | ms, median (fastest) | target |",
        "|---|---|---|",
    ]
    verdicts = []
    for name, values in times.items():
        cli_line = name.startswith("`--version`") or name.startswith("`info")
        rows.append(
            f"| {name} | {1000 * median(values):.0f} ({1000 * min(values):.0f}) | "
            f"{f'{1000 * TARGET_SECONDS:.0f} ms' if cli_line else ''} |"
        )
        if cli_line:
            verdict = "pass" if median(values) < TARGET_SECONDS else "FAIL"
            verdicts.append(f"{name}: {1000 * median(values):.0f} ms (target {TARGET_SECONDS} s): **{verdict}**")
    notes = [
        "",
        "`--version` builds the top-level parser alone and loads no NumPy. `info` parses the header "
        "into a plain tree and checks the whole MOTION block with the Rust kernel `check_motion_block` "
        "(no array kept), so it loads no NumPy either (with `--backend numpy` it does: the twin parses "
        "into an array). tests/cli/test_cli.py checks the modules each command line loads.",
    ]
    text = "\n".join([*rows, "", *(f"- {v}" for v in verdicts), *notes]) + "\n"
    print(text)
    if args.write_results:
        write_section(TITLE, text, REPO / "benches" / "RESULTS.md")
        log(f"wrote the section {TITLE!r} of benches/RESULTS.md")


if __name__ == "__main__":
    main()
