#!/usr/bin/env python3
"""The main job's comparison table (scripts/run.sh): one row per backend on the bunny.

Reads the JSON files run.sh wrote into OUT (compress, render, image diff, fps per backend) and
writes OUT/bunny-comparison.md (and prints it). Standard library only.

usage: main_table.py OUT BACKEND [BACKEND ...]
"""
import json
import pathlib
import sys


def load(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def fmt(x, spec):
    return "n/a" if x is None else format(x, spec)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out = pathlib.Path(sys.argv[1])
    backends = sys.argv[2:]
    rows = []
    provenance = None
    for b in backends:
        c = load(out / f"bunny-{b}.json")
        r = load(out / f"render-{b}.json")
        d = load(out / f"diff-{b}.json")
        f = load(out / f"fps-{b}.json")
        provenance = provenance or f.get("provenance")
        e = d["error"]
        rows.append(
            "| {b} | {mb} | {dp} | {mf} | {cp} | {rc} | {ro} | {fr} | {l2} | {psnr} | {vf} | {lf} |".format(
                b=b,
                mb=fmt(c["storage_bytes"] / 1e6, ".1f"),
                dp=fmt(c["data_percent"], ".2f"),
                mf=fmt(c["mflops_per_relight"], ".2f"),
                cp=fmt(c["computation_percent"], ".1f"),
                rc=fmt(c.get("ms_per_relight_cpp"), ".2f"),
                ro=fmt(c.get("ms_per_relight_opencl"), ".2f"),
                fr=fmt(c.get("frobenius_rel_error"), ".1e"),
                l2=fmt(e["relative_l2"], ".1e"),
                psnr="exact" if e["relative_l2"] == 0 else fmt(e["psnr_db"], ".1f"),
                vf=fmt(f["view_change"]["fps"], ".1f"),
                lf=fmt(f["light_change"]["fps"], ".1f"),
            )
        )
    paper = load(out / f"fps-{backends[0]}.json").get("paper") or {}
    lines = [
        "# Main job: every registered backend on the bunny",
        "",
        "Same scene, same light (`courtyard`), same camera (the scene's first view, 640 x 480).",
        "Image error is against the `uncompressed` render (the exact T); fps are medians over",
        "frames of `prtlab fps` (view change: G-buffer + shading, L* reused; light change:",
        "project + relight + shading).",
        "",
        "| backend | stored MB | data % | MFLOP/relight | computation % | relight C++ ms "
        "| relight OpenCL ms | Frobenius rel. error | image rel. L2 | PSNR dB | fps view | fps light |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        *rows,
    ]
    if paper:
        lines += [
            "",
            f"The paper's bunny (Table I, {paper.get('hardware', '')}): "
            f"{paper.get('view_fps')} fps view change, {paper.get('light_fps')} fps light change.",
        ]
    lines += ["", "Images: `bunny-courtyard-<backend>.png`; error map: `bunny-<backend>-error.png`."]
    if provenance:
        lines += [
            "",
            "## Provenance",
            "",
            f"- git: {provenance.get('git')}{' (dirty)' if provenance.get('git_dirty') else ''}",
            f"- machine: {provenance.get('machine', {}).get('cpu')}, "
            f"{provenance.get('machine', {}).get('cores')} cores",
            f"- OpenCL: {(provenance.get('opencl_device') or {}).get('label', 'none')}",
            f"- date: {provenance.get('date_utc')}",
            f"- command: `bash scripts/run.sh` (outputs in {out}/)",
        ]
    text = "\n".join(lines) + "\n"
    tmp = out / "bunny-comparison.md.tmp"
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(out / "bunny-comparison.md")
    print(text, end="")


if __name__ == "__main__":
    main()
