#!/usr/bin/env python3
"""Compares two points.csv files cell by cell, timing columns aside (docs/distributed.md).

usage: compare_points.py A/points.csv B/points.csv
Exits 1 naming the first differing row and column. Timings (seconds, milliseconds, frame rates)
and whether a stage came from the cache differ between runs by nature; every other cell must be
identical, text for text.
"""
import csv
import re
import sys

TIMING = re.compile(r"(seconds|_ms|ms_|fps|cache_hit)")


def rows(path):
    with open(path, newline="") as f:
        # The provenance comment lines above the header differ by nature (date, command, load).
        reader = csv.DictReader(line for line in f if not line.startswith("#"))
        keep = [c for c in reader.fieldnames if not TIMING.search(c)]
        return keep, [{c: r[c] for c in keep} for r in reader]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    ca, a = rows(sys.argv[1])
    cb, b = rows(sys.argv[2])
    if ca != cb:
        sys.exit(f"columns differ: {ca} vs {cb}")
    if len(a) != len(b):
        sys.exit(f"{len(a)} rows vs {len(b)}")
    if not a:
        sys.exit("no points")
    for i, (x, y) in enumerate(zip(a, b)):
        for c in ca:
            if x[c] != y[c]:
                sys.exit(f"row {i + 1} ({x.get('backend')} {x.get('params')}), column {c}: "
                         f"{x[c]!r} vs {y[c]!r}")
    print(f"{len(a)} points, {len(ca)} columns identical")


if __name__ == "__main__":
    main()
