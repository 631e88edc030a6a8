#!/usr/bin/env python3
"""Plots of a prtlab result folder, from its result.json alone (docs/experiments.md).

    python3 scripts/plot_experiment.py results/fig6

Writes, depending on the experiment:
  figure-<scene>.png   equal storage: the exact image, every backend's image and its error map
  pareto-<scene>.png   sweeps: L* error against relight time (C++, OpenCL) and storage, each
                       backend's Pareto front drawn as a line
  scaling.png          sweeps over scene variants: storage and frame rates against the setting
  perceptual.json      SSIM of every kept image against the exact one (scikit-image), when
                       scikit-image is installed (Debian: python3-skimage)
`prtlab experiment report` runs this script, then writes README.md, which embeds the plots.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


def number(v):
    return v if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else None


def backend_colours(points):
    names = []
    for p in points:
        if p["backend"] not in names:
            names.append(p["backend"])
    cmap = plt.get_cmap("tab10")
    return {b: cmap(i % 10) for i, b in enumerate(names)}


def write_atomically(fig, path):
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110, bbox_inches="tight")
    os.replace(tmp, path)
    plt.close(fig)


def equal_storage_figure(result, folder):
    points = result["points"]
    for image_set in result.get("image_sets", []):
        scene = image_set["scene"]
        rows = image_set["images"]
        kept = [p for p in points if p["scene"] == scene and p.get("images")]
        if not rows or not kept:
            continue
        cols = 1 + len(kept)
        fig, axes = plt.subplots(2 * len(rows), cols, figsize=(2.6 * cols, 2.2 * 2 * len(rows)),
                                 squeeze=False)
        for r, row in enumerate(rows):
            ax = axes[2 * r][0]
            ax.imshow(mpimg.imread(os.path.join(folder, row["exact"])))
            ax.set_title(f"exact ({row['environment']}, {row['view']})", fontsize=8)
            axes[2 * r + 1][0].text(0.5, 0.5, f"error maps:\nrelative error\n0 to {row['error_scale']:.3g}",
                                    ha="center", va="center", fontsize=8)
            for c, p in enumerate(kept, start=1):
                entry = next(e for e in p["images"]
                             if e["environment"] == row["environment"] and e["view"] == row["view"])
                err = next((e for e in p["errors"]
                            if e["environment"] == row["environment"] and e["view"] == row["view"]), {})
                axes[2 * r][c].imshow(mpimg.imread(os.path.join(folder, entry["image"])))
                lstar = err.get("lstar_rel_l2")
                title = f"{p['backend']}\n{p['storage_bytes'] / 1e6:.2f} MB"
                if number(lstar) is not None:
                    title += f", L* err {lstar:.2g}"
                axes[2 * r][c].set_title(title, fontsize=8)
                axes[2 * r + 1][c].imshow(mpimg.imread(os.path.join(folder, entry["error_map"])))
                psnr = err.get("image_psnr_db")
                if err.get("image_rel_l2") == 0:
                    axes[2 * r + 1][c].set_title("identical to the exact image", fontsize=8)
                elif number(psnr) is not None:
                    axes[2 * r + 1][c].set_title(f"PSNR {psnr:.1f} dB", fontsize=8)
        for ax in axes.flat:
            ax.set_xticks([])
            ax.set_yticks([])
            for s in ax.spines.values():
                s.set_visible(False)
        target = next((s.get("target_bytes") for s in result["scenes"] if s["scene"] == scene), None)
        fig.suptitle(f"{scene}: every backend at {target / 1e6:.2f} MB" if target else scene, fontsize=10)
        write_atomically(fig, os.path.join(folder, f"figure-{scene}.png"))


def pareto_plots(result, folder):
    points = result["points"]
    colours = backend_colours(points)
    for scene in [s["scene"] for s in result["scenes"]]:
        pts = [p for p in points if p["scene"] == scene]
        panels = [("relight_ms_cpp", "relight time, C++ (ms)"),
                  ("relight_ms_opencl", "relight time, OpenCL kernels (ms)"),
                  ("storage_mb", "storage (MB)")]
        panels = [pn for pn in panels if any(number(p.get(pn[0])) for p in pts)]
        if not panels:
            continue
        rows = [("lstar_rel_l2_mean", "L* relative L2 error (mean over environments)"),
                ("lstar_rel_l2_max", "L* relative L2 error (worst environment)")]
        fig, axes = plt.subplots(len(rows), len(panels), figsize=(4.6 * len(panels), 3.8 * len(rows)),
                                 squeeze=False)
        for r, (ykey, ylabel) in enumerate(rows):
            for c, (xkey, xlabel) in enumerate(panels):
                ax = axes[r][c]
                for backend, colour in colours.items():
                    bp = [p for p in pts if p["backend"] == backend
                          and number(p.get(xkey)) and number(p.get(ykey)) is not None]
                    if not bp:
                        continue
                    xs = [p[xkey] for p in bp]
                    ys = [max(p[ykey], 1e-9) for p in bp]
                    ax.scatter(xs, ys, color=colour, s=18, label=backend, zorder=3)
                    # The backend's front in this panel's coordinates.
                    order = sorted(range(len(bp)), key=lambda i: (xs[i], ys[i]))
                    front, best = [], math.inf
                    for i in order:
                        if ys[i] < best:
                            front.append(i)
                            best = ys[i]
                    ax.plot([xs[i] for i in front], [ys[i] for i in front], color=colour, lw=1.2, zorder=2)
                ax.set_xscale("log")
                ax.set_yscale("log")
                ax.set_xlabel(xlabel)
                ax.set_ylabel(ylabel, fontsize=8)
                ax.grid(True, which="both", alpha=0.25)
                if r == 0 and c == 0:
                    ax.legend(fontsize=7)
        fig.suptitle(f"{scene}: error against cost (lines: each backend's Pareto front; "
                     f"errors below 1e-9 drawn at 1e-9)", fontsize=10)
        write_atomically(fig, os.path.join(folder, f"pareto-{scene}.png"))


def scaling_plot(result, folder):
    grid = result["experiment"].get("scene_grid") or {}
    if not grid:
        return
    key = sorted(grid)[0]
    overrides = {s["scene"]: s.get("overrides", {}) for s in result["scenes"]}
    points = [p for p in result["points"] if key in overrides.get(p["scene"], {})]
    if not points:
        return
    colours = backend_colours(points)
    base = {s["scene"]: s.get("base", s["scene"]) for s in result["scenes"]}
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    # One line per backend, base scene and combination of the other swept settings.
    groups = {}
    for p in points:
        others = tuple(sorted((k, v) for k, v in overrides[p["scene"]].items() if k != key))
        groups.setdefault((p["backend"], base[p["scene"]], others), []).append(p)
    for (backend, scene, others), bp in groups.items():
        colour = colours[backend]
        bp = sorted(bp, key=lambda p: overrides[p["scene"]][key])
        xs = [overrides[p["scene"]][key] for p in bp]
        label = backend if len(groups) == len(colours) else f"{backend}, {scene}" + "".join(
            f", {k}={v}" for k, v in others)
        a.plot(xs, [p["storage_bytes"] / 1e6 for p in bp], "o-", color=colour, label=label)
        for fkey, style, what in (("fps_view", "o-", "view change"), ("fps_light", "s--", "light change")):
            ys = [p.get(fkey) for p in bp]
            if any(number(y) for y in ys):
                b.plot(xs, [y if number(y) else float("nan") for y in ys], style, color=colour,
                       label=f"{label}, {what}")
    a.set_xlabel(key)
    a.set_ylabel("storage (MB)")
    a.grid(True, alpha=0.3)
    a.legend(fontsize=8)
    b.set_xlabel(key)
    b.set_ylabel("frames per second")
    b.grid(True, alpha=0.3)
    if b.lines:
        b.legend(fontsize=8)
    fig.suptitle(f"scaling with {key}", fontsize=10)
    write_atomically(fig, os.path.join(folder, "scaling.png"))


def perceptual(result, folder):
    try:
        from skimage.metrics import structural_similarity
    except ImportError:
        return
    out = []
    for image_set in result.get("image_sets", []):
        for row in image_set["images"]:
            exact = mpimg.imread(os.path.join(folder, row["exact"]))[..., :3]
            for p in result["points"]:
                for e in p.get("images") or []:
                    if e["environment"] == row["environment"] and e["view"] == row["view"] \
                            and p["scene"] == image_set["scene"]:
                        img = mpimg.imread(os.path.join(folder, e["image"]))[..., :3]
                        s = structural_similarity(exact, img, channel_axis=-1, data_range=1.0)
                        out.append({"image": e["image"], "backend": p["backend"], "ssim": float(s)})
    if out:
        tmp = os.path.join(folder, "perceptual.json.tmp")
        with open(tmp, "w") as f:
            json.dump({"metric": "SSIM (scikit-image structural_similarity, 8-bit tone-mapped PNGs, "
                                 "RGB, data range 1)", "ssim": out}, f, indent=2)
        os.replace(tmp, os.path.join(folder, "perceptual.json"))


def param_value(v):
    try:
        f = float(v)
        return int(f) if f.is_integer() else f
    except (TypeError, ValueError):
        return v


def point_value(p, key):
    """A points.csv column of the point, or "metrics.<name>": its backend metric <name>."""
    if key.startswith("metrics."):
        return (p.get("backend_metrics") or {}).get(key[len("metrics."):])
    return p.get(key)


def curve_plots(result, folder):
    """The experiment's [[curves]]: y against a parameter, a line per series value, a panel per
    panel value (the CPCA paper's Fig. 2 and 3 are such plots)."""
    points = result["points"]
    for n, curve in enumerate(result["experiment"].get("curves", [])):
        for scene in [s["scene"] for s in result["scenes"]]:
            pts = [p for p in points if p["scene"] == scene and p["backend"] == curve["backend"]
                   and number(point_value(p, curve["y"])) is not None]
            if not pts:
                continue
            # A parameter, or (x only) a points.csv column such as storage_mb.
            par = lambda p, k: (param_value(p["canonical_params"][k]) if k in p["canonical_params"]
                                else point_value(p, k)) if k else ""
            panels = sorted({par(p, curve["panel"]) for p in pts},
                            key=lambda v: (isinstance(v, str), v))
            fig, axes = plt.subplots(1, len(panels), figsize=(4.8 * len(panels), 3.9), squeeze=False,
                                     sharey=True)
            for c, panel in enumerate(panels):
                ax = axes[0][c]
                pp = [p for p in pts if par(p, curve["panel"]) == panel]
                series = sorted({par(p, curve["series"]) for p in pp},
                                key=lambda v: (isinstance(v, str), v))
                cmap = plt.get_cmap("viridis")
                for i, sv in enumerate(series):
                    sp = sorted([p for p in pp if par(p, curve["series"]) == sv],
                                key=lambda p: par(p, curve["x"]))
                    xs = [par(p, curve["x"]) for p in sp]
                    ys = [max(point_value(p, curve["y"]), 1e-12) for p in sp]
                    label = f'{curve["series"]} = {sv}' if curve["series"] else curve["backend"]
                    ax.plot(xs, ys, "o-", ms=3.5, lw=1.2, label=label,
                            color=cmap(i / max(1, len(series) - 1)))
                if curve.get("log_x"):
                    ax.set_xscale("log", base=2)
                if curve.get("log_y"):
                    ax.set_yscale("log")
                ax.set_xlabel(curve["x"])
                if c == 0:
                    ax.set_ylabel(curve["y"])
                if curve["panel"]:
                    ax.set_title(f'{curve["panel"]} = {panel}', fontsize=9)
                ax.grid(True, which="both", alpha=0.25)
                ax.legend(fontsize=7)
            title = curve.get("title") or f'{curve["backend"]}: {curve["y"]} against {curve["x"]}'
            fig.suptitle(f"{scene}: {title}", fontsize=10)
            write_atomically(fig, os.path.join(folder, f"curves{n}-{scene}.png"))


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: plot_experiment.py RESULT_FOLDER")
    folder = sys.argv[1]
    path = os.path.join(folder, "result.json")
    try:
        with open(path) as f:
            result = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"plot_experiment.py: {path}: {e}")
    if result["experiment"]["kind"] == "equal_storage":
        equal_storage_figure(result, folder)
        perceptual(result, folder)
    else:
        pareto_plots(result, folder)
        scaling_plot(result, folder)
    curve_plots(result, folder)
    print(f"plot_experiment.py: plots of {folder} written")


if __name__ == "__main__":
    main()
