"""Studio latency, measured in the browser: from a typed change to the preview and to the exact
solid.

Starts ``torus-cad studio`` (default design) and headless Chromium, then alternates the blade
count between 3 and 4 ``--changes`` times, each time waiting for the exact solid and its files.
The page records when the change was typed (its ``input`` event) and when the preview's and the
exact solid's stamps changed (performance.now(), in the browser); the server's own breakdown of
the preview is printed too. Needs the ``test`` extra and Debian's chromium + chromium-driver::

    python scripts/bench_studio.py --changes 10
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

# the studio driver lives with the tests
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from studio_driver import StudioPage, StudioProcess, chromium


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--changes", type=int, default=10, help="blade-count changes to time (default 10)"
    )
    parser.add_argument("--json", type=Path, help="also write the timings here")
    args = parser.parse_args()

    rows = []
    with (
        tempfile.TemporaryDirectory() as downloads,
        StudioProcess() as studio,
        chromium(Path(downloads)) as driver,
    ):
        page = StudioPage(driver, studio.url)
        page.wait_idle()
        page.start_latency_probe()
        for change in range(args.changes):
            blades = "4" if change % 2 == 0 else "3"
            page.change("blades", blades)
            times = page.latencies_ms()
            rows.append({"blades": int(blades), **times, "server": page.text("preview-detail")})
            print(
                f"blades -> {blades}: preview {times['preview']:6.0f} ms, "
                f"exact solid {times['exact']:6.0f} ms"
                f"   ({page.text('preview-detail')})",
                flush=True,
            )
    preview = statistics.median(row["preview"] for row in rows)
    exact = statistics.median(row["exact"] for row in rows)
    load = os.getloadavg()
    print(
        f"median over {len(rows)} changes: preview {preview:.0f} ms, exact solid {exact:.0f} ms "
        f"(load average {load[0]:.1f} on {os.cpu_count()} CPUs)"
    )
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "changes": rows,
                    "median_preview_ms": preview,
                    "median_exact_ms": exact,
                    "load_average": load,
                },
                indent=2,
            )
            + "\n"
        )


if __name__ == "__main__":
    main()
