#!/usr/bin/python3
"""Frame rates of every registered transfer backend on the paper's scenes (Tables I and II).

Runs `prtlab fps` once per scene x backend (one process each, in sequence, so no two runs share
the machine), writing <out>/<scene>-<backend>.md and .json, then the summary <out>/README.md
(view- and light-change fps beside the paper's, stage medians) and <out>/fps.png. A run that
fails or passes --timeout is listed with the reason; rerunning skips scenes x backends whose
.json exists unless --force. `--summary-only` rewrites README.md and the plot from the JSONs. `--before-after DIR` instead
tabulates the runs of scripts/fps_before_after.sh in DIR (<scene>-<config>.json) into
DIR/README.md: per scene and configuration the fps and the stage medians, and the ratio of each
new configuration's fps to the base build's.

Usage:
  scripts/fps_table.py [--prtlab build/release/cli/prtlab] [--out results/fps/all]
      [--scenes bunny,armor,chair,temple,bunny-12k,bunny-48k] [--backends all]
      [--material full] [--frames 20] [--timeout 900] [--force] [--summary-only]
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ["bunny", "armor", "chair", "temple", "bunny-12k", "bunny-48k"]


def backends(prtlab):
    out = subprocess.run([prtlab, "list", "--json"], capture_output=True, text=True, check=True)
    listed = json.loads(out.stdout)
    return [b["name"] for b in listed.get("compressors", listed.get("backends", []))]


def write_atomically(path, text):
    tmp = path.with_name(path.name + f".tmp.{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


def run_one(args, scene, backend, out):
    md = out / f"{scene}-{backend}.md"
    cmd = [args.prtlab, "-q", "fps", scene, "--backend", backend, "--material", args.material,
           "--frames", str(args.frames), "--out", str(md)]
    for p in args.material_param:
        cmd += ["--material-param", p]
    t0 = time.time()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        status = "ok" if r.returncode == 0 else f"failed (exit {r.returncode}): " + (
            r.stderr.strip().splitlines() or [""])[-1][:200]
    except subprocess.TimeoutExpired:
        status = f"timed out after {args.timeout} s (compression or precomputation not cached)"
    return {"scene": scene, "backend": backend, "status": status, "command": " ".join(cmd),
            "seconds": round(time.time() - t0, 1)}


def summary(out, runs, args):
    rows = []
    for f in sorted(out.glob("*.json")):
        if f.name == "runs.json":
            continue
        j = json.loads(f.read_text())
        if "view_change" not in j:
            continue
        rows.append(j)
    order = {s: i for i, s in enumerate(SCENES)}
    rows.sort(key=lambda j: (order.get(j["scene"], 99), j["backend"]))
    md = ["# Frame rates of every transfer backend (PoCL)", ""]
    md.append("Written by `scripts/fps_table.py` (one `prtlab fps` run per scene and backend; each "
              "row's `.md` holds its command, provenance and stage table, its `.json` every "
              "number). 640 x 480, each scene's first view, nearest texels, view cache on, "
              "culling on, `courtyard`; medians over the frames of a loop of view changes (orbit "
              "about +y) and one of light changes (the environment rotated about +y).")
    md.append("")
    if rows:
        prov = rows[0].get("provenance", {})
        mach = prov.get("machine", {})
        machine = (f"{mach.get('cpu', '?')}, {mach.get('cores', '?')} cores, "
                   f"{mach.get('memory_gib', 0):.1f} GiB" if isinstance(mach, dict)
                   else str(mach or platform.node()))
        dates = sorted(j.get("provenance", {}).get("date_utc", "") for j in rows)
        md.append(f"Machine: {machine}; device: "
                  f"{(rows[0].get('device') or {}).get('label', 'C++ reference')}; build "
                  f"{prov.get('git', '?')}{' (dirty)' if prov.get('git_dirty') else ''} "
                  f"({prov.get('build_type', '?')}); runs from {dates[0]} to {dates[-1]}.")
        md.append("")
    md.append("| scene | backend | material | hit pixels | view fps | light fps | paper view / light "
              "| view ms: G-buffer + upload + shade | light ms: project + relight + upload + shade "
              "| load average |")
    md.append("|---|---|---|---:|---:|---:|---|---|---|---|")
    for j in rows:
        v, l = j["view_change"], j["light_change"]
        vs, ls = v["stages_median"], l["stages_median"]
        paper = j.get("paper")
        ptxt = f"{paper['view_fps']:.1f} / {paper['light_fps']:.1f} ({paper['table']})" if paper else "—"
        md.append(
            f"| {j['scene']} | `{j['backend']}` | `{j['material']}` | {j['hit_pixels']:,} | "
            f"{v['fps']:.1f} | {l['fps']:.1f} | {ptxt} | "
            f"{vs['gbuffer_ms']:.2f} + {vs['gbuffer_upload_ms']:.2f} + {vs['shade_ms']:.2f} | "
            f"{ls['project_ms']:.2f} + {ls['relight_ms']:.2f} + {ls['upload_ms']:.2f} + "
            f"{ls['shade_ms']:.2f} | {j.get('load_average', '')} |")
    failed = [r for r in runs if r["status"] != "ok"]
    if failed:
        md += ["", "## Runs without a result", "", "| scene | backend | what happened |",
               "|---|---|---|"]
        md += [f"| {r['scene']} | `{r['backend']}` | {r['status']} |" for r in failed]
    md += ["", "The paper's numbers are Table I (bunny, armor, chair, temple) and Table II (the "
           "bunny sizes) of Sun et al. (2008 quad Xeon + GTX 280, their bicluster renderer; its "
           "Table II lists the 3,286-vertex bunny at 277.9 / 86.8 fps, Table I at 97.0 / 56.1); "
           "they stand beside every backend for scale. Why ours differ: docs/rendering.md "
           "\"Frame rates\" and results/fps/README.md.", ""]
    write_atomically(out / "README.md", "\n".join(md) + "\n")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    scenes = [s for s in SCENES if any(j["scene"] == s for j in rows)]
    names = sorted({j["backend"] for j in rows})
    fig, axes = plt.subplots(1, 2, figsize=(14, 5), sharey=False)
    for ax, key, title in ((axes[0], "view_change", "view change"),
                           (axes[1], "light_change", "light change")):
        width = 0.8 / max(1, len(names))
        for k, b in enumerate(names):
            xs, ys = [], []
            for i, s in enumerate(scenes):
                for j in rows:
                    if j["scene"] == s and j["backend"] == b:
                        xs.append(i + k * width)
                        ys.append(j[key]["fps"])
            ax.bar(xs, ys, width, label=b)
        for i, s in enumerate(scenes):
            paper = next((j.get("paper") for j in rows if j["scene"] == s and j.get("paper")), None)
            if paper:
                y = paper["view_fps" if key == "view_change" else "light_fps"]
                ax.plot([i - 0.1, i + 0.8], [y, y], "k--", lw=1.5)
        ax.set_xticks([i + 0.4 - width / 2 for i in range(len(scenes))])
        ax.set_xticklabels(scenes)
        ax.set_yscale("log")
        ax.set_ylabel("fps (median)")
        ax.set_title(f"{title} (dashed: the paper, GTX 280)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(names), fontsize=8)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    tmp = out / "fps.png.tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, out / "fps.png")


def before_after(folder):
    folder = Path(folder)
    configs = ["base-full", "new-full", "new-packed-f16", "new-packed-u8"]
    md = ["# Frame rates before and after (bicluster, PoCL)", "",
          "Written by `scripts/fps_table.py --before-after` from the runs of "
          "`scripts/fps_before_after.sh` (each `<scene>-<config>.md` holds its command and "
          "provenance). `base` is the build before the change, `new` the build after it; the "
          "four configurations of a scene ran back to back. 640 x 480, first view, nearest "
          "texels, view cache on, culling on, `courtyard`.", "",
          "| scene | config | view fps | x base | light fps | x base | view: G-buffer + upload + "
          "relight + shade (view cache) ms | light: relight + upload + shade ms |",
          "|---|---|---:|---:|---:|---:|---|---|"]
    for scene in SCENES:
        base = None
        for c in configs:
            f = folder / f"{scene}-{c}.json"
            if not f.exists():
                continue
            j = json.loads(f.read_text())
            v, l = j["view_change"], j["light_change"]
            vs, ls = v["stages_median"], l["stages_median"]
            if c == "base-full":
                base = j
            rv = f"{v['fps'] / base['view_change']['fps']:.2f}" if base else "—"
            rl = f"{l['fps'] / base['light_change']['fps']:.2f}" if base else "—"
            md.append(
                f"| {scene} | {c} | {v['fps']:.1f} | {rv} | {l['fps']:.1f} | {rl} | "
                f"{vs['gbuffer_ms']:.2f} + {vs['gbuffer_upload_ms']:.2f} + {vs['relight_ms']:.2f} + "
                f"{vs['shade_ms']:.2f} ({vs['view_cache_kernel_ms']:.2f}) | "
                f"{ls['relight_ms']:.2f} + {ls['upload_ms']:.2f} + {ls['shade_ms']:.2f} |")
    write_atomically(folder / "README.md", "\n".join(md) + "\n")
    print(f"wrote {folder / 'README.md'}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--prtlab", default=str(ROOT / "build/release/cli/prtlab"))
    ap.add_argument("--out", default=str(ROOT / "results/fps/all"))
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--backends", default="all")
    ap.add_argument("--material", default="full")
    ap.add_argument("--material-param", action="append", default=[])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--timeout", type=int, default=900)
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--summary-only", action="store_true")
    ap.add_argument("--before-after", metavar="DIR")
    args = ap.parse_args()
    if args.before_after:
        before_after(args.before_after)
        return
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    runs_file = out / "runs.json"
    runs = json.loads(runs_file.read_text()) if runs_file.exists() else []
    if not args.summary_only:
        names = backends(args.prtlab) if args.backends == "all" else args.backends.split(",")
        for scene in args.scenes.split(","):
            for b in names:
                if (out / f"{scene}-{b}.json").exists() and not args.force:
                    continue
                r = run_one(args, scene, b, out)
                runs = [x for x in runs if (x["scene"], x["backend"]) != (scene, b)] + [r]
                write_atomically(runs_file, json.dumps(runs, indent=1) + "\n")
                print(f"{scene:10s} {b:15s} {r['status']} ({r['seconds']} s)", flush=True)
    summary(out, runs, args)
    print(f"wrote {out / 'README.md'}")


if __name__ == "__main__":
    main()
