#!/usr/bin/env python3
"""Turns shadow_bench suite JSON (--suite paper) into PNG plots.

usage: plot_suite.py OUT_DIR SUITE.json [SUITE.json ...]

Writes, for the runs that ran (rt is skipped where the device lacked ray tracing):
  total_vs_triangles_<size>_spp<N>.png  total GPU ms against scene triangles, one line per technique
  total_vs_pixels_<scene>_spp<N>.png    total GPU ms against render pixels, one line per technique
  passes_<scene>_v<V>_<size>_spp<N>.png per-pass stacked bars, one bar per technique
Needs matplotlib (Debian: python3-matplotlib). Run by hand; the tests do not need it.
"""
import collections
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The technique's runs; the other coverage tests (Table 3) only change the CSM pass.
TECHNIQUES = [("sm", "none"), ("cascades", "none"), ("izb", "none"), ("izb+csm", "bary"),
              ("hybrid+csm", "bary"), ("rt", "none")]


def label(run):
    return run["mode"]


def size_label(run):
    return "%dx%d" % tuple(run["size"])


def base_scene(run):
    # "sponza x16" -> "sponza": the copies of one scene form one scaling series.
    return run["scene"].rsplit(" x", 1)[0]


def load(paths):
    runs = []
    for p in paths:
        with open(p) as f:
            runs.extend(r for r in json.load(f) if r.get("status", "ran") == "ran" and not r.get("csm_everything"))
    return [r for r in runs if (r["mode"], r["csm_test"]) in TECHNIQUES]


def device_of(runs):
    return runs[0]["device"] if runs else "?"


def line_plot(path, title, xlabel, series, device):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, points in series.items():
        points = sorted(points)
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=name)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("total GPU ms (median)")
    ax.set_title("%s\n%s" % (title, device), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print("wrote", path)


def main(argv):
    if len(argv) < 3:
        print(__doc__)
        return 2
    out_dir, paths = argv[1], argv[2:]
    os.makedirs(out_dir, exist_ok=True)
    runs = load(paths)
    if not runs:
        print("no runs that ran in", paths)
        return 1
    device = device_of(runs)

    # Total against triangles, per render size and spp, averaged over the views measured.
    by_size = collections.defaultdict(lambda: collections.defaultdict(lambda: collections.defaultdict(list)))
    for r in runs:
        by_size[(size_label(r), r["spp"], base_scene(r))][label(r)][r["triangles"]].append(r["gpu_ms"]["total"])
    for (size, spp, scene), techniques in by_size.items():
        if max(len(t) for t in techniques.values()) < 2:
            continue  # one scale only: nothing to plot against
        series = {name: [(tri, sum(v) / len(v)) for tri, v in points.items()] for name, points in techniques.items()}
        line_plot(os.path.join(out_dir, "total_vs_triangles_%s_%s_spp%d.png" % (scene, size, spp)),
                  "%s copies, %s, %d spp: total against triangles" % (scene, size, spp), "triangles", series, device)

    # Total against pixels, per scene (one scale) and spp.
    by_scene = collections.defaultdict(lambda: collections.defaultdict(lambda: collections.defaultdict(list)))
    for r in runs:
        by_scene[(r["scene"], r["spp"])][label(r)][r["size"][0] * r["size"][1]].append(r["gpu_ms"]["total"])
    for (scene, spp), techniques in by_scene.items():
        if max(len(t) for t in techniques.values()) < 2:
            continue
        series = {name: [(px, sum(v) / len(v)) for px, v in points.items()] for name, points in techniques.items()}
        line_plot(os.path.join(out_dir, "total_vs_pixels_%s_spp%d.png" % (scene.replace(" ", ""), spp)),
                  "%s, %d spp: total against pixels" % (scene, spp), "pixels", series, device)

    # Per-pass stacked bars, one chart per scene, view, size and spp.
    groups = collections.defaultdict(list)
    for r in runs:
        groups[(r["scene"], r["view"], size_label(r), r["spp"])].append(r)
    for (scene, view, size, spp), group in groups.items():
        group.sort(key=lambda r: TECHNIQUES.index((r["mode"], r["csm_test"])))
        passes = []
        for r in group:
            for p in r.get("passes", []):
                if p not in passes:
                    passes.append(p)
        fig, ax = plt.subplots(figsize=(7, 4.5))
        bottoms = [0.0] * len(group)
        cmap = plt.get_cmap("tab20")
        for i, p in enumerate(passes):
            values = [r["gpu_ms"].get(p, 0.0) if p in r.get("passes", []) else 0.0 for r in group]
            ax.bar(range(len(group)), values, bottom=bottoms, label=p, color=cmap(i % 20))
            bottoms = [b + v for b, v in zip(bottoms, values)]
        ax.set_xticks(range(len(group)))
        ax.set_xticklabels([label(r) for r in group], fontsize=8)
        ax.set_ylabel("GPU ms (median per pass)")
        ax.set_title("%s view %d, %s, %d spp: passes\n%s" % (scene, view, size, spp, device), fontsize=10)
        ax.legend(fontsize=7, ncol=2)
        fig.tight_layout()
        path = os.path.join(out_dir, "passes_%s_v%d_%s_spp%d.png" % (scene.replace(" ", ""), view, size, spp))
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print("wrote", path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
