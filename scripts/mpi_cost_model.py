#!/usr/bin/env python3
"""How long experiment files take on N nodes, from the per-point costs they measured.

usage: scripts/mpi_cost_model.py [--nodes 1,8,64] [--speedup S] [--tables T.json ...] RESULT ...

Each RESULT is an experiment run's result.json, or a folder: its result.json, or else the
result.json of each folder one level below it (results/cpca-paper holds four runs). A
result.json lists its scenes (transfer_key: the exact transfer stage; transfer_seconds: the time
it took when it was computed, which the stage cache keeps, so a cache hit reports it too;
docs/experiments.md "Precomputation times and the cache") and its points (backend, scene,
measure_seconds: the point's whole time, its compression included when that was not cached; a
cached compression adds the compress_seconds it took when it was computed, which the cache
keeps). A transfer stage is computed once and read from the stage cache by every later file
that needs it, so it is counted once, in the first given file that names its transfer_key (at
the longest time any file recorded for it). The paper tables' JSON (results/table1.json,
table2.json; --tables) are only a fallback for a scene that records no transfer time: their
transfer_seconds (or, in older tables, precompute_minutes, which also holds the bicluster's
compression).

A distributed run (docs/distributed.md) hands out first the scenes, then the points, to
whichever node is free, in file order: this script replays that greedy list schedule on N
identical nodes, each `--speedup` times this machine (1: nodes like the one that measured),
file after file (the root's pass that writes the files is a cache read, counted as 0). Beside
each modelled time T_N it prints the parallel efficiency T_1 / (N x T_N) and the node-hours
N x T_N / 3600. Prints markdown: the table, then notes on what the model could not price.
"""
import argparse
import heapq
import json
import os
import sys
from collections import defaultdict


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


def result_paths(arg):
    """A result.json, or a folder: its result.json, else its sub-folders' result.json."""
    if not os.path.isdir(arg):
        return [arg]
    own = os.path.join(arg, "result.json")
    if os.path.isfile(own):
        return [own]
    below = sorted(os.path.join(arg, d, "result.json") for d in os.listdir(arg)
                   if os.path.isfile(os.path.join(arg, d, "result.json")))
    if not below:
        sys.exit(f"{arg}: no result.json in it or in the folders below it")
    return below


def point_cost(p):
    """The point's measured time, plus its compression's recorded time where that was cached."""
    cost = p.get("measure_seconds") or 0.0
    if p.get("compress_cache_hit"):
        cost += p.get("compress_seconds") or 0.0
    return cost


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--nodes", default="1,8,64")
    ap.add_argument("--speedup", type=float, default=1.0)
    ap.add_argument("--tables", nargs="*", default=[])
    a = ap.parse_args()
    nodes = [int(n) for n in a.nodes.split(",")]

    table_cost = {}  # scene name -> seconds, the fallback
    for path in a.tables:
        with open(path) as f:
            for row in json.load(f).get("rows", []):
                if row.get("transfer_seconds"):
                    table_cost[row["scene"]] = row["transfer_seconds"]
                elif row.get("precompute_minutes"):
                    table_cost[row["scene"]] = 60.0 * row["precompute_minutes"]

    files = []
    recorded = defaultdict(list)  # transfer key -> every recorded transfer_seconds
    for arg in a.results:
        for path in result_paths(arg):
            with open(path) as f:
                r = json.load(f)
            if "points" not in r or "scenes" not in r:
                sys.exit(f"{path}: not the result.json of an experiment run")
            files.append((path, r))
            for s in r["scenes"]:
                if s.get("transfer_seconds"):
                    recorded[s.get("transfer_key") or s["scene"]].append(s["transfer_seconds"])
    transfer_cost = {k: max(v) for k, v in recorded.items()}

    rows = []
    paid = set()  # transfer stages already computed by an earlier file (a cache read after that)
    unknown = set()
    unpriced = []  # (file, points) whose cached compression recorded no time
    repeated = defaultdict(list)  # compression (backend, params, transfer) -> its costs, per file
    for path, r in files:
        name = r["experiment"].get("name", path)
        variant = r["experiment"].get("variant") or "full"
        label = f"{name} ({variant})"
        keys = {}
        scenes = []
        for s in r["scenes"]:
            key = s.get("transfer_key") or s["scene"]
            keys[s["scene"]] = key
            if key in paid:
                continue
            paid.add(key)
            if key in transfer_cost:
                cost = transfer_cost[key]
            elif s["scene"] in table_cost:
                cost = table_cost[s["scene"]]
            else:
                cost = 0.0
                unknown.add(s["scene"])
            scenes.append(cost / a.speedup)
        points = [point_cost(p) / a.speedup for p in r["points"]]
        missing = sum(1 for p in r["points"]
                      if p.get("compress_cache_hit") and p.get("compress_seconds") is None)
        if missing:
            unpriced.append((label, missing, len(points)))
        for p in r["points"]:
            if p.get("compress_cache_hit") and p.get("compress_seconds"):
                ck = (p.get("backend"), json.dumps(p.get("canonical_params"), sort_keys=True),
                      keys.get(p.get("scene"), p.get("scene")))
                repeated[ck].append(p["compress_seconds"] / a.speedup)
        longest = max(range(len(points)), key=lambda i: points[i], default=None)
        where = ""
        if longest is not None:
            p = r["points"][longest]
            where = f" ({p.get('backend')}, {p.get('scene')})"
        spans = {n: schedule(scenes, n) + schedule(points, n) for n in nodes}
        one = sum(scenes) + sum(points)
        rows.append((label, len(points), (max(points, default=0.0), where), sum(scenes), one, spans))

    def cells(one, spans):
        out = []
        for n in nodes:
            t = spans[n]
            eff = one / (n * t) if t > 0 else 0.0
            out += [f"{t:.1f}", f"{eff:.2f}", f"{n * t / 3600:.3f}"]
        return out

    head = ["experiment", "points", "longest point s (backend, scene)", "transfers s"]
    for n in nodes:
        head += [f"{n} node{'s' if n > 1 else ''} s", "eff", "node-h"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for label, count, (longest, where), transfers, one, spans in rows:
        print("| " + " | ".join([label, str(count), f"{longest:.1f}{where}", f"{transfers:.1f}"] +
                               cells(one, spans)) + " |")
    serial = sum(r[4] for r in rows)
    total = {n: sum(r[5][n] for r in rows) for n in nodes}
    print("| " + " | ".join(["**all**", str(sum(r[1] for r in rows)), "",
                             f"{sum(r[3] for r in rows):.1f}"] +
                            [f"**{c}**" for c in cells(serial, total)]) + " |")
    print()
    print(f"Serial sum {serial:.1f} s; speedup on " +
          ", ".join(f"{n}: {serial / total[n]:.2f}x" for n in nodes if total[n] > 0) +
          ". eff = T_1 / (N x T_N); node-h = N x T_N / 3600.")
    print()
    print(f"Transfer stages counted once each: {len(paid)} ({sum(r[3] for r in rows):.1f} s).")
    spread = {k: v for k, v in recorded.items() if max(v) > 1.1 * min(v)}
    if spread:
        print("Transfer stages whose recorded times differ between files (the longest counted): " +
              "; ".join(f"{k[:8]} {', '.join(f'{t:.1f}' for t in sorted(set(v)))} s"
                        for k, v in sorted(spread.items())) + ".")
    again = [v for v in repeated.values() if len(v) > 1]
    if again:
        print(f"Cached compressions that more than one file counts (same backend, parameters and "
              f"transfer; counted in every file): {len(again)}, {sum(sum(v[1:]) for v in again):.1f} s "
              f"counted more than once.")
    if unpriced:
        print("Points whose cached compression recorded no time (counted as their measurement "
              "only, so these files' times are lower bounds): " +
              ", ".join(f"{label} {m} of {c}" for label, m, c in unpriced) + ".")
    if unknown:
        print(f"Scenes with no recorded transfer time (counted as 0): {', '.join(sorted(unknown))}.")


if __name__ == "__main__":
    main()
