#!/usr/bin/env python3
"""Summary of run.sh: per configuration the storage, C++ and OpenCL ms per relight (each run's own
median of 20 relights) as the median and the minimum over rounds, the declared bound and measured
errors, and the ratios to `uncompressed`'s median and minimum of the same run. The minimum is
shown because the VMs here have slow periods that double a round's times (bimodal noise)."""
import json
import pathlib
import re
import statistics
import sys

folder = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
runs = {}
for p in sorted(folder.glob("bunny_*_r*.json")):
    name = re.match(r"bunny_(.*)_r\d+$", p.stem).group(1)
    runs.setdefault(name, []).append(json.loads(p.read_text()))

def med(name, key):
    return statistics.median(r[key] for r in runs[name])

def low(name, key):
    return min(r[key] for r in runs[name])

ref = {k: med("uncompressed", k) for k in ("storage_bytes", "ms_per_relight_cpp", "ms_per_relight_opencl")}
ref_low = {k: low("uncompressed", k) for k in ("ms_per_relight_cpp", "ms_per_relight_opencl")}
rounds = len(runs["uncompressed"])
print(f"{rounds} rounds; uncompressed per round, C++/OpenCL ms: " +
      ", ".join("%.2f/%.2f" % (r["ms_per_relight_cpp"], r["ms_per_relight_opencl"]) for r in runs["uncompressed"]))
print("| configuration | storage B | vs uncompressed | C++ ms median (min) | vs | OpenCL ms median (min) | vs | declared bound | rel L2 max (8 lights) | Frobenius | compress s |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name, rs in runs.items():
    first = rs[0]
    cpp, cl = med(name, "ms_per_relight_cpp"), med(name, "ms_per_relight_opencl")
    cpp_low, cl_low = low(name, "ms_per_relight_cpp"), low(name, "ms_per_relight_opencl")
    # compress_seconds: the first round compressed, later rounds hit the stage cache.
    print(f"| {name} | {first['storage_bytes']} | {first['storage_bytes'] / ref['storage_bytes']:.3f} | "
          f"{cpp:.2f} ({cpp_low:.2f}) | {cpp / ref['ms_per_relight_cpp']:.2f} ({cpp_low / ref_low['ms_per_relight_cpp']:.2f}) | "
          f"{cl:.2f} ({cl_low:.2f}) | {cl / ref['ms_per_relight_opencl']:.2f} ({cl_low / ref_low['ms_per_relight_opencl']:.2f}) | "
          f"{first['declared_error_bound']:.3g} | {first['rel_l2_error_max']:.3g} | "
          f"{first['frobenius_rel_error']:.3g} | {first['compress_seconds']:.2f} |")
