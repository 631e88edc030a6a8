#!/usr/bin/env bash
# srbf_cta's compression by two builds on the same machine in one run, interleaved (machines
# here are noisy): the previous code (BASE) against this checkout's (NEW).
#   scripts/srbf_cta_ab.sh BASE_PRTLAB [NEW_PRTLAB] [OUT_DIR]
# Environment: SCENE (bunny), PARAMS (rank_light=134, fig6 --quick's point), ROUNDS (1),
# BASE_LIBS (a folder put first on LD_LIBRARY_PATH for BASE: its own libprtlab_core.so).
# Writes OUT_DIR (results/srbf-cta-speed) /ab.md with per-phase times, the relative Frobenius
# error and the SE ratio of each run, and the runs' logs and JSON. REPORT_ONLY=1 rewrites ab.md
# from the logs already in OUT_DIR. Each build is named by its own version stamp (`--version`).
set -euo pipefail
cd "$(dirname "$0")/.."
BASE="$1" NEW="${2:-build/release/cli/prtlab}" OUT="${3:-results/srbf-cta-speed}"
SCENE="${SCENE:-bunny}" PARAMS="${PARAMS:-rank_light=134}" ROUNDS="${ROUNDS:-1}"
mkdir -p "$OUT"
if [[ "${REPORT_ONLY:-0}" != 1 ]]; then
LD_LIBRARY_PATH="${BASE_LIBS:-}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" "$BASE" --version > "$OUT/base.version"
"$NEW" --version > "$OUT/new.version"
cache="$(mktemp -d)"
trap 'rm -rf "$cache"' EXIT
export PRTLAB_CACHE="$cache"
"$NEW" -q precompute "$SCENE" > /dev/null  # T once, for both builds (the same stage key)
args=(-v --no-opencl compress "$SCENE" --backend srbf_cta --force --json --no-image)
for p in $PARAMS; do args+=(--param "$p"); done
for r in $(seq "$ROUNDS"); do
  for who in base new; do
    if [[ $who == base ]]; then
      LD_LIBRARY_PATH="${BASE_LIBS:-}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" /usr/bin/time -f "%e %M" \
        -o "$OUT/$who-$r.time" "$BASE" "${args[@]}" > "$OUT/$who-$r.json" 2> "$OUT/$who-$r.log"
    else
      /usr/bin/time -f "%e %M" -o "$OUT/$who-$r.time" "$NEW" "${args[@]}" \
        > "$OUT/$who-$r.json" 2> "$OUT/$who-$r.log"
    fi
    echo "round $r $who: $(cat "$OUT/$who-$r.time") (wall s, max RSS KB)"
  done
done
fi
python3 - "$OUT" "$ROUNDS" "$SCENE" "$PARAMS" "$*" <<'PY'
import json, re, subprocess, sys, platform, datetime
out, rounds, scene, params, argv = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
versions = {who: open(f"{out}/{who}.version").read().strip() for who in ("base", "new")}
pat = re.compile(r"projection ([\d.]+) s, CTA initialisation ([\d.]+) s, clustering ([\d.]+) s \((\d+) iterations\).*error ([\d.]+) s")
rows = []
for r in range(1, rounds + 1):
    for who in ("base", "new"):
        log = open(f"{out}/{who}-{r}.log").read()
        m = pat.search(log)
        wall, rss = open(f"{out}/{who}-{r}.time").read().split()
        j = json.load(open(f"{out}/{who}-{r}.json"))
        f = j["frobenius_rel_error"]
        rows.append((r, who, float(wall), int(rss) / 1024 / 1024, m.groups() if m else ("?",) * 5, f, j["storage_bytes"]))
with open(f"{out}/ab.md", "w") as o:
    o.write(f"# srbf_cta compression, previous code against this commit, one run\n\n")
    o.write(f"- command: `scripts/srbf_cta_ab.sh {argv}` (SCENE={scene}, PARAMS='{params}', ROUNDS={rounds})\n")
    o.write(f"- builds: base `{versions['base']}`, new `{versions['new']}`; machine: {cpu}, {subprocess.run(['nproc'], capture_output=True, text=True).stdout.strip()} cores; {platform.platform()}\n")
    o.write(f"- date (UTC): {datetime.datetime.utcnow().isoformat(timespec='seconds')}Z\n\n")
    o.write("| round | build | wall s | max RSS GiB | projection s | CTA init s | clustering s (iterations) | error s | relative Frobenius error | SE ratio % | storage bytes |\n|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r, who, wall, rss, g, f, st in rows:
        o.write(f"| {r} | {who} | {wall:.1f} | {rss:.2f} | {g[0]} | {g[1]} | {g[2]} ({g[3]}) | {g[4]} | {f:.6f} | {100*f*f:.3f} | {st} |\n")
    b = [x for x in rows if x[1] == "base"]; n = [x for x in rows if x[1] == "new"]
    sb = sum(x[2] for x in b) / len(b); sn = sum(x[2] for x in n) / len(n)
    fb = b[0][5] ** 2; fn = n[0][5] ** 2
    o.write(f"\nMean wall time: base {sb:.1f} s, new {sn:.1f} s: {sb / sn:.2f}x. SE ratio: new / base = {fn / fb:.4f} ({100 * (fn / fb - 1):+.2f} %).\n")
print(open(f"{out}/ab.md").read())
PY
