#!/usr/bin/env python3
"""The tables of results/cpca-paper/README.md, from the result.json files beside this script:
our total squared errors of the 25-D diffuse transfer vector beside the paper's (Sloan et al.
2003, Fig. 4), at both scales (t_p as computed, and times (1/pi)^2, the albedo-1 exiting
radiance of the paper's signal), and the ratios between methods.

    python3 results/cpca-paper/compare.py
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER = {"static": 17.7, "iterative": 4.28, "adaptive": 2.54}
PAPER_VERTICES = 48668


def load(name):
    with open(os.path.join(HERE, name, "result.json")) as f:
        return json.load(f)


def points(result):
    for p in result["points"]:
        yield p["canonical_params"], p["backend_metrics"], p


def fig3():
    r = load("cpca-paper-fig3")
    se = {}
    norm = None
    vertices = None
    for cp, m, p in points(r):
        se[(cp["adaptive_rule"], cp["method"], int(cp["vectors"]))] = m
        norm = m["signal_squared_norm"]
        vertices = p["vertices"]
    print(f"vertices {vertices}, sum ||t_p||^2 = {norm:.6g} (mean {norm / vertices:.4f} per vertex)")
    print()
    print("Fig. 4, n' = 3, 256 clusters:")
    print()
    print("| method | paper SE | ours: SE of t_p | ours x 1/pi^2 | ours x 1/pi^2 x 48,668 / vertices"
          " | ours: relative error | cost_model_floats |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    rows = {}
    for method, rule in [("static", "sloan"), ("iterative", "sloan"), ("adaptive", "sloan"),
                         ("adaptive", "storage")]:
        m = se[(rule, method, 3)]
        rows[(method, rule)] = m["signal_squared_error"]
        label = method if method != "adaptive" else f"adaptive ({rule} rule)"
        paper = PAPER[method] if rule == "sloan" else None
        s = m["signal_squared_error"]
        print(f"| {label} | {paper if paper else '-'} | {s:.4g} | {s / math.pi**2:.4g} | "
              f"{s / math.pi**2 * PAPER_VERTICES / vertices:.4g} | {m['signal_relative_error']:.4g} | "
              f"{m['cost_model_floats']:.0f} |")
    print()
    st, it, ad = rows[("static", "sloan")], rows[("iterative", "sloan")], rows[("adaptive", "sloan")]
    ads = rows[("adaptive", "storage")]
    print("| ratio | paper | ours (sloan rule) | ours (storage rule) |")
    print("|---|---:|---:|---:|")
    print(f"| iterative / static | {PAPER['iterative'] / PAPER['static']:.3f} | {it / st:.3f} | {it / st:.3f} |")
    print(f"| adaptive / static | {PAPER['adaptive'] / PAPER['static']:.3f} | {ad / st:.3f} | {ads / st:.3f} |")
    print(f"| adaptive / iterative | {PAPER['adaptive'] / PAPER['iterative']:.3f} | {ad / it:.3f} | {ads / it:.3f} |")
    print()
    print("Fig. 3, total squared error of t_p against n' (256 clusters):")
    print()
    ns = sorted({k[2] for k in se})
    print("| n' | " + " | ".join(["static", "iterative", "adaptive (sloan)", "adaptive (storage)"]) + " |")
    print("|---:|---:|---:|---:|---:|")
    for n in ns:
        cells = [se.get(("sloan", "static", n)), se.get(("sloan", "iterative", n)),
                 se.get(("sloan", "adaptive", n)), se.get(("storage", "adaptive", n))]
        print(f"| {n} | " + " | ".join(f"{c['signal_squared_error']:.4g}" if c else "-" for c in cells)
              + " |")
    # Static and iterative do not depend on the rule: the storage panel repeats them.
    for method in ("static", "iterative"):
        for n in ns:
            a = se[("sloan", method, n)]["signal_squared_error"]
            b = se[("storage", method, n)]["signal_squared_error"]
            assert a == b, (method, n, a, b)
    print()


def pca():
    try:
        r = load("cpca-paper-pca")
    except OSError:
        return
    print("Warm against converged PCA updates (256 clusters, n' = 3):")
    print()
    print("| method | rule | warm SE | converged SE | converged / warm |")
    print("|---|---|---:|---:|---:|")
    se = {}
    for cp, m, _ in points(r):
        se[(cp["method"], cp["adaptive_rule"], cp["pca_updates"])] = m["signal_squared_error"]
    for method, rule in (("iterative", "sloan"), ("adaptive", "sloan"), ("adaptive", "storage")):
        w, c = se[(method, rule, "warm")], se[(method, rule, "converged")]
        print(f"| {method} | {rule if method == 'adaptive' else '(none)'} | {w:.4g} | {c:.4g} | {c / w:.4f} |")
    # Iterative does not depend on the rule.
    for u in ("warm", "converged"):
        assert se[("iterative", "sloan", u)] == se[("iterative", "storage", u)]
    print()


def fig2():
    try:
        r = load("cpca-paper-fig2")
    except OSError:
        return
    print("Fig. 2, static: total squared error of t_p (rows: clusters, columns: n'):")
    print()
    se = {}
    for cp, m, _ in points(r):
        se[(int(cp["clusters"]), int(cp["vectors"]))] = (m["signal_squared_error"], m["cost_model_floats"])
    cs = sorted({k[0] for k in se})
    ns = sorted({k[1] for k in se})
    print("| clusters | " + " | ".join(f"n' = {n}" for n in ns) + " |")
    print("|---:|" + "---:|" * len(ns))
    for c in cs:
        print(f"| {c} | " + " | ".join(f"{se[(c, n)][0]:.4g}" if (c, n) in se else "-" for n in ns) + " |")
    print()
    # Where a curve of more vectors crosses below one of fewer at equal cost: the lowest error at
    # each cost decade, and which n' gives it.
    print("Lowest error reached within a storage cost (floats), and the n' that reaches it:")
    print()
    print("| cost at most | lowest SE | n' | clusters |")
    print("|---:|---:|---:|---:|")
    for budget in (5e4, 1e5, 2e5, 5e5, 1e6):
        best = min(((v[0], n, c) for (c, n), v in se.items() if v[1] <= budget), default=None)
        if best:
            print(f"| {budget:.0e} | {best[0]:.4g} | {best[1]} | {best[2]} |")
    print()


if __name__ == "__main__":
    fig3()
    pca()
    fig2()
