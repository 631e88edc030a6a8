#!/usr/bin/python3
"""Speed of the Python archive reader (python/prtlab) against plain reads of the same file.

Writes one archive with a float32 section of SIZE MiB (tests/python/archive_builder.py, the
layout of docs/file-format.md), then times, best of REPEAT with the page cache hot:
  baseline   np.fromfile of the whole file (one read into fresh memory)
  xxhash     read_archive(path, xxh3="xxhash") (skipped when the module is missing)
  numpy      read_archive(path, xxh3="numpy"), the pure-numpy XXH3
and prints GB/s and each time relative to the baseline.

Usage: scripts/bench_python_reader.py [SIZE_MIB] [REPEAT]
"""

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT / "python"), str(ROOT / "tests" / "python")]

from archive_builder import build_archive  # noqa: E402
from prtlab import read_archive, xxhash_available  # noqa: E402


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    size_mib = int(sys.argv[1]) if len(sys.argv) > 1 else 256
    repeat = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    values = np.random.default_rng(1).random(size_mib * (1 << 20) // 4, dtype=np.float32)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "bench.prt"
        path.write_bytes(build_archive("bench", 1, {"note": "reader speed"}, [("values", values)]))
        nbytes = path.stat().st_size

        def touch_all(a):
            # A reader returns views; summing one value per page makes every page resident.
            return float(a.sections["values"][:: 4096 // 4].sum())

        rows = [("baseline np.fromfile", lambda: np.fromfile(path, dtype=np.uint8))]
        if xxhash_available():
            rows.append(
                ("read_archive xxhash", lambda: touch_all(read_archive(path, xxh3="xxhash")))
            )
        rows.append(("read_archive numpy", lambda: touch_all(read_archive(path, xxh3="numpy"))))
        print(
            f"file {nbytes / 2**20:.1f} MiB, best of {repeat}, page cache hot, "
            f"{os.cpu_count()} CPUs, numpy {np.__version__}"
        )
        base = None
        for name, fn in rows:
            fn()  # warm the page cache and the code paths
            t = best(fn, repeat)
            base = base or t
            print(
                f"{name:24s} {t * 1e3:9.1f} ms  {nbytes / t / 1e9:6.2f} GB/s  "
                f"{t / base:5.2f}x baseline"
            )


if __name__ == "__main__":
    main()
