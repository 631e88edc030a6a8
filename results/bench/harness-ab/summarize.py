import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
def med(files, f):
    return statistics.median(f(json.load(open(x))) for x in files)
print("| backend | quantity | previous (2c3fbd3) | now, no culling | now, culling | now / previous |")
print("|---|---|---:|---:|---:|---:|")
for b in ["uncompressed", "bicluster"]:
    for key, label in [("ms_per_relight_cpp", "relight C++ ms"), ("ms_per_relight_opencl", "relight OpenCL ms")]:
        o = med([f"{out}/compress-{b}-old-{r}.json" for r in range(1, rounds + 1)], lambda j: j[key])
        n = med([f"{out}/compress-{b}-new-{r}.json" for r in range(1, rounds + 1)], lambda j: j[key])
        print(f"| {b} | {label} (compress --repeat 30) | {o:.3f} | {n:.3f} | | {n/o:.2f} |")
    for loop, label in [("light_change", "light-change frame ms"), ("view_change", "view-change frame ms")]:
        f = lambda j: j[loop]["median_frame_ms"]
        o = med([f"{out}/fps-{b}-old-{r}.json" for r in range(1, rounds + 1)], f)
        nn = med([f"{out}/fps-{b}-new-nocull-{r}.json" for r in range(1, rounds + 1)], f)
        nc = med([f"{out}/fps-{b}-new-cull-{r}.json" for r in range(1, rounds + 1)], f)
        print(f"| {b} | {label} (fps --frames 20) | {o:.3f} | {nn:.3f} | {nc:.3f} | {nn/o:.2f} / {nc/o:.2f} |")
