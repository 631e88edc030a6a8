#!/usr/bin/env bash
# Every backend's compression and relight time, two builds of prtlab on the same machine in one
# run (docs/build-options.md): `experiment run fig6 --quick` (the bunny, every transfer backend
# at the lossless bicluster's storage) by build A, then by build B, each from an empty stage
# cache; a table of compress seconds, C++ and OpenCL relight milliseconds and the error, A
# against B.
#   scripts/arch_ab.sh A_PRTLAB B_PRTLAB [OUT_DIR] [A_NAME] [B_NAME]
# Default OUT_DIR results/bench/arch-ab, names "portable" and "native". A_ENV / B_ENV: settings
# (VAR=value ...) in the environment of A's / B's run only, so that one binary against itself
# measures a run-time switch (scripts/lapack_ab.sh: PRTLAB_EIGEN_SOLVER=eigen).
set -euo pipefail
cd "$(dirname "$0")/.."
A="$1" B="$2" OUT="${3:-results/bench/arch-ab}" NA="${4:-portable}" NB="${5:-native}"
mkdir -p "$OUT"
for who in a b; do
  bin="$A" name="$NA" settings="${A_ENV:-}"
  [[ $who == b ]] && bin="$B" name="$NB" settings="${B_ENV:-}"
  cache="$(mktemp -d)"
  # shellcheck disable=SC2086
  env $settings PRTLAB_CACHE="$cache" "$bin" -q experiment run fig6 --quick --out "$OUT/$name" --force --no-plot \
    > "$OUT/$name.log" 2>&1 || { tail -20 "$OUT/$name.log"; exit 1; }
  rm -rf "$cache"
  echo "$name: done"
done
python3 - "$OUT" "$NA" "$NB" "$*" <<'PY'
import csv, os, subprocess, sys, datetime
out, na, nb, argv = sys.argv[1:5]
def load(name):
    rows = [r for r in csv.DictReader(l for l in open(f"{out}/{name}/fig6-quick/points.csv") if not l.startswith("#"))]
    return {r["backend"]: r for r in rows}
a, b = load(na), load(nb)
git = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], capture_output=True, text=True).stdout.strip()
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
def f(x):
    try: return float(x)
    except (TypeError, ValueError): return float("nan")
with open(f"{out}/ab.md", "w") as o:
    o.write(f"# {na} against {nb}: every backend's compression and relight, one run\n\n")
    envs = " ".join(f"{k}='{v}'" for k, v in (("A_ENV", os.environ.get("A_ENV", "")), ("B_ENV", os.environ.get("B_ENV", ""))) if v)
    o.write(f"- command: `{envs + ' ' if envs else ''}scripts/arch_ab.sh {argv}`; git {git}; {cpu}; {datetime.datetime.utcnow().isoformat(timespec='seconds')}Z\n")
    o.write(f"- each build ran `prtlab experiment run fig6 --quick` from an empty stage cache; {na} first\n\n")
    o.write(f"| backend | compress s {na} | {nb} | ratio | relight C++ ms {na} | {nb} | ratio | relight OpenCL ms {na} | {nb} | frobenius_rel {na} | {nb} |\n|---|---|---|---|---|---|---|---|---|---|---|\n")
    for k in a:
        if k not in b: continue
        ca, cb = f(a[k].get("compress_seconds")), f(b[k].get("compress_seconds"))
        ra, rb = f(a[k].get("relight_ms_cpp")), f(b[k].get("relight_ms_cpp"))
        oa, ob = f(a[k].get("relight_ms_opencl")), f(b[k].get("relight_ms_opencl"))
        o.write(f"| {k} | {ca:.2f} | {cb:.2f} | {ca/cb if cb else float('nan'):.2f}x | {ra:.3f} | {rb:.3f} | {ra/rb if rb else float('nan'):.2f}x | {oa:.3f} | {ob:.3f} | {a[k].get('frobenius_rel')} | {b[k].get('frobenius_rel')} |\n")
    o.write(f"\nratio: {na} time / {nb} time (above 1: {nb} faster).\n")
print(open(f"{out}/ab.md").read())
PY
