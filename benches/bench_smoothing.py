"""What smoothing the decomposition in time costs a whole archive: python benches/bench_smoothing.py DATA [--rounds N]

``expressive-mocap preprocess DATA -o OUT --model -q`` with the split smoothed in time (the
default) and without (its widths set to 0, the same kernel), each round a fresh process per
setting, the order alternated; the medians and their ratio. Both in one run, so that a machine
slower or faster that hour changes both alike.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUN = """
import sys
import expressive_mocap.decoupling.algebra as algebra
if sys.argv[1] == "off":
    algebra.BODY_SMOOTHING = algebra.ACTIVITY_SMOOTHING = 0.0
from expressive_mocap.cli import main
sys.exit(main(["preprocess", sys.argv[2], "-o", sys.argv[3], "--model", "-q"]))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path, help="a folder of BVH clips (the bench above: dataset-2's)")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    times: dict[str, list[float]] = {"on": [], "off": []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for setting in ("on", "off") if r % 2 == 0 else ("off", "on"):
                out = Path(tmp) / setting
                shutil.rmtree(out, ignore_errors=True)
                start = time.perf_counter()
                subprocess.run([sys.executable, "-c", RUN, setting, str(args.data), str(out)], check=True)
                times[setting].append(time.perf_counter() - start)
    on, off = statistics.median(times["on"]), statistics.median(times["off"])
    print(f"smoothed {on:.2f} s, unsmoothed {off:.2f} s (medians of {args.rounds}): {100 * (on / off - 1):+.0f} %")


if __name__ == "__main__":
    main()
