#!/usr/bin/env python3
"""How long experiment files take on N nodes, from the per-point costs they measured.

usage: scripts/mpi_cost_model.py [--nodes 1,8,64] [--speedup S] [--tables T.json ...] RESULT.json ...

Each result.json (an experiment run's folder) lists its scenes (transfer_seconds, with
transfer_cache_hit) and its points (measure_seconds: the point's whole time, its compression
included when that was not cached; a cached compression adds the compress_seconds it took when
it was computed, which the cache keeps). The paper tables' JSON (results/table1.json,
table2.json; --tables) give each scene's precompute_minutes, the transfer's own time. A distributed run (docs/distributed.md) hands out first the
scenes, then the points, to whichever node is free, in file order: this script replays that
greedy list schedule on N identical nodes, each `--speedup` times this machine (1: nodes like
the one that measured), file after file (the root's pass that writes the files is a cache read,
counted as 0). A scene whose transfer came from the cache in every given file has no measured
cost and counts as 0 (named in the output). Prints a markdown table.
"""
import argparse
import heapq
import json
import sys


def schedule(costs, nodes):
    """Makespan of the greedy in-order list schedule (a work queue) on `nodes` nodes."""
    free = [0.0] * nodes
    heapq.heapify(free)
    end = 0.0
    for c in costs:
        t = heapq.heappop(free) + c
        end = max(end, t)
        heapq.heappush(free, t)
    return end


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--nodes", default="1,8,64")
    ap.add_argument("--speedup", type=float, default=1.0)
    ap.add_argument("--tables", nargs="*", default=[])
    a = ap.parse_args()
    nodes = [int(n) for n in a.nodes.split(",")]
    files = []
    transfer_cost = {}
    for path in a.tables:
        with open(path) as f:
            for row in json.load(f).get("rows", []):
                if row.get("precompute_minutes"):
                    transfer_cost[row["scene"]] = 60.0 * row["precompute_minutes"]
    for path in a.results:
        with open(path) as f:
            r = json.load(f)
        if "points" not in r or "scenes" not in r:
            sys.exit(f"{path}: not the result.json of an experiment run")
        files.append((path, r))
        for s in r["scenes"]:
            if not s.get("transfer_cache_hit") and s.get("transfer_seconds"):
                key = s["scene"]
                transfer_cost[key] = max(transfer_cost.get(key, 0.0), s["transfer_seconds"])
    rows = []
    total = {n: 0.0 for n in nodes}
    serial = 0.0
    unknown = set()
    for path, r in files:
        scenes = []
        for s in r["scenes"]:
            key = s["scene"]
            if key not in transfer_cost:
                unknown.add(s["scene"])
            scenes.append(transfer_cost.get(key, 0.0) / a.speedup)
        points = [((p.get("measure_seconds") or 0.0) +
                   ((p.get("compress_seconds") or 0.0) if p.get("compress_cache_hit") else 0.0)) /
                  a.speedup for p in r["points"]]
        one = sum(scenes) + sum(points)
        serial += one
        spans = {n: schedule(scenes, n) + schedule(points, n) for n in nodes}
        for n in nodes:
            total[n] += spans[n]
        name = r["experiment"].get("name", path)
        variant = r["experiment"].get("variant") or "full"
        rows.append((f"{name} ({variant})", len(points), max(points, default=0.0), spans))
    print(f"| experiment | points | longest point s | " + " | ".join(f"{n} node{'s' if n > 1 else ''} s" for n in nodes) + " |")
    print("|---|---|---|" + "---|" * len(nodes))
    for name, count, longest, spans in rows:
        print(f"| {name} | {count} | {longest:.1f} | " + " | ".join(f"{spans[n]:.1f}" for n in nodes) + " |")
    print(f"| **all** | {sum(r[1] for r in rows)} | | " + " | ".join(f"**{total[n]:.1f}**" for n in nodes) + " |")
    print()
    print(f"Serial sum {serial:.1f} s; speedup on " + ", ".join(f"{n}: {serial / total[n]:.2f}x" for n in nodes if total[n] > 0) + ".")
    if unknown:
        print(f"Scenes with no measured transfer (cached in every file, counted as 0): {', '.join(sorted(unknown))}.")


if __name__ == "__main__":
    main()
