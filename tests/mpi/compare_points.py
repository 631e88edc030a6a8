#!/usr/bin/env python3
"""Compares two result files of one experiment cell by cell, timing columns aside
(docs/distributed.md).

usage: compare_points.py A/points.csv B/points.csv     (or errors.csv: any result table)
       compare_points.py A/result.json B/result.json   (its points and failures)
Exits 1 naming the first differing row and column (or JSON path). Timings (seconds,
milliseconds, frame rates, what is derived from them) and whether a stage came from the cache
differ between runs by nature; every other cell must be identical, text for text.
"""
import csv
import json
import re
import sys

TIMING = re.compile(r"(seconds|_ms|ms_|fps|cache_hit|pareto_time|cull_speedup)")


def rows(path):
    with open(path, newline="") as f:
        # The provenance comment lines above the header differ by nature (date, command, load).
        reader = csv.DictReader(line for line in f if not line.startswith("#"))
        keep = [c for c in reader.fieldnames if not TIMING.search(c)]
        return keep, [{c: r[c] for c in keep} for r in reader]


def compare_csv(a_path, b_path):
    ca, a = rows(a_path)
    cb, b = rows(b_path)
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
    print(f"{len(a)} rows, {len(ca)} columns identical")


def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if not TIMING.search(k)}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def first_difference(a, b, path="$"):
    if type(a) is not type(b):
        return f"{path}: {a!r} vs {b!r}"
    if isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                return f"{path}.{k}: present in one file only"
            d = first_difference(a[k], b[k], f"{path}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list):
        if len(a) != len(b):
            return f"{path}: {len(a)} entries vs {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            d = first_difference(x, y, f"{path}[{i}]")
            if d:
                return d
        return None
    return None if a == b else f"{path}: {a!r} vs {b!r}"


def compare_json(a_path, b_path):
    a, b = (json.load(open(p)) for p in (a_path, b_path))
    for key in ("points", "failures"):
        d = first_difference(strip(a.get(key)), strip(b.get(key)), key)
        if d:
            sys.exit(d)
    if not a.get("points"):
        sys.exit("no points")
    print(f"{len(a['points'])} points and {len(a.get('failures', []))} failures identical")


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    if sys.argv[1].endswith(".json"):
        compare_json(sys.argv[1], sys.argv[2])
    else:
        compare_csv(sys.argv[1], sys.argv[2])


if __name__ == "__main__":
    main()
