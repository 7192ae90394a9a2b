"""Reading a CSV v1 log against ``pyarrow.csv.read_csv`` of the same file, in one process.

Run: ``.venv/bin/python benches/csv_read.py LOG.csv [--repeat 3]`` (e.g. the default soak log of
``uasnav simulate --preset ax1 --profile soak --out soak.csv``). The runs alternate ours and the
peer so that a change of machine load hits both; medians of wall and CPU time (all threads) are
printed. Ours: ``read_log`` (chunks through the extension's parser on every core, every cell
checked, t strictly increasing, an ImuLog built) and ``load_training_data`` (the calibration's
1 s block means while reading). Peer: ``pyarrow.csv.read_csv`` of all columns, types inferred,
no checks.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable


def timed(fn: Callable[[], object]) -> tuple[float, float]:
    w, c = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - w, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-calibration", action="store_true", help="skip load_training_data")
    a = ap.parse_args()

    import pyarrow.csv as pacsv

    from uasnav.io import read_log
    from uasnav.thermal import load_training_data

    with open(a.path, "rb") as fh:
        head = fh.read(1 << 16).split(b"\n")
    skip = next(i for i, ln in enumerate(head) if not ln.startswith(b"#"))  # comment lines
    opts = pacsv.ReadOptions(skip_rows=skip)
    runs: dict[str, list[tuple[float, float]]] = {
        "pyarrow.csv.read_csv": [],
        "read_log": [],
        "calibration": [],
    }
    for _ in range(a.repeat):
        runs["pyarrow.csv.read_csv"].append(timed(lambda: pacsv.read_csv(a.path, read_options=opts)))
        runs["read_log"].append(timed(lambda: read_log(a.path)))
        if not a.no_calibration:
            runs["calibration"].append(timed(lambda: load_training_data(a.path, 1.0)))
    size = os.path.getsize(a.path)
    print(f"{a.path}: {size / 1e6:.0f} MB, {a.repeat} runs each, alternating; load {os.getloadavg()[0]:.1f}")
    peer_w = statistics.median(w for w, _ in runs["pyarrow.csv.read_csv"])
    peer_c = statistics.median(c for _, c in runs["pyarrow.csv.read_csv"])
    for name, r in runs.items():
        if not r:
            continue
        w = statistics.median(x for x, _ in r)
        c = statistics.median(y for _, y in r)
        print(
            f"{name:22s} wall {w:7.2f} s  cpu {c:7.2f} s  |  ratio to pyarrow: wall {w / peer_w:4.2f}x "
            f"cpu {c / peer_c:4.2f}x  (walls: {', '.join(f'{x:.2f}' for x, _ in r)})"
        )


if __name__ == "__main__":
    main()
