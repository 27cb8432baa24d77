"""Figures of manibench's results through matplotlib (Debian's python3-matplotlib).

    manibench plot DIR [DIR ...] [--out FIGURE.png]
    python3 -m manibench.plot DIR [DIR ...] [--out FIGURE.png]

A DIR of ``manibench eval --out DIR`` (summary.csv, summary.json): per
object, the success rate and each success condition's satisfactory rate,
one bar per split when several results (``--split train`` and ``--split
test`` of one task, say) are given; the numbers are summary.csv's. A DIR of
``manibench train`` (log.csv, and eval.csv for behaviour cloning): the
training curves, each loss (and SAC's return and success rate) against the
iteration or environment step, and the evaluations' success rate per split.
A DIR of ``manibench render --out DIR`` (pointcloud.ply): the point cloud a
policy gets, each point in its colour, seen from above and behind the
robot. The default figure is DIR/results.png (first DIR), DIR/curves.png or
DIR/pointcloud.png.

Only the standard library and matplotlib: it never imports the extension
module. `manibench plot` runs this file (bin/manibench-plot finds it).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from typing import Any

SPLIT_COLOURS = {"train": "#4C72B0", "test": "#DD8452"}


def read_eval(directory: str) -> dict[str, Any]:
    """One evaluation's numbers: task, split and summary.csv's rows (the
    per-object rows; the "all" row apart) as floats."""
    summary_csv = os.path.join(directory, "summary.csv")
    if not os.path.exists(summary_csv):
        raise FileNotFoundError(f"{directory}: no summary.csv (not a `manibench eval --out` folder)")
    with open(os.path.join(directory, "summary.json"), encoding="utf-8") as f:
        meta = json.load(f)
    with open(summary_csv, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    conditions = [c[len("condition_"):] for c in rows[0] if c.startswith("condition_")] if rows else []
    objects = {}
    overall = None
    for row in rows:
        values = {"success_rate": float(row["success_rate"])}
        # The 95 % interval (Wilson per object, a bootstrap over objects
        # for "all"); reports from before intervals have none.
        if row.get("success_low") not in (None, ""):
            values["success_interval"] = (float(row["success_low"]), float(row["success_high"]))
        values.update({c: float(row["condition_" + c]) for c in conditions})
        # The opening curve (doors, drawers): opened_<fraction> with its
        # interval, in summary.csv's order; none for other tasks.
        values["opening_curve"] = [(float(c[len("opened_"):]), float(row[c]), float(row[c + "_low"]),
                                    float(row[c + "_high"]))
                                   for c in row if c.startswith("opened_") and not c.endswith(("_low", "_high"))]
        if row["object"] == "all":
            overall = values
        else:
            objects[row["object"]] = values
    return {"task": meta.get("task", ""), "split": meta.get("split", ""), "policy": meta.get("policy", {}).get("name", ""),
            "conditions": conditions, "objects": objects, "overall": overall}


def plot_eval(directories: list[str]):
    """The evaluation figure: one panel for the success rate and one per
    condition, a group of bars per object, one bar per result folder
    (labelled with its split). Each axis's ``manibench_metric`` names its
    summary.csv column (success_rate, or the condition)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    results = [read_eval(d) for d in directories]
    metrics = ["success_rate"] + [c for c in results[0]["conditions"] if c != "success"]
    objects = []
    for r in results:
        objects += [o for o in r["objects"] if o not in objects]
    width = 0.8 / len(results)
    # With an opening curve, one more panel at the bottom: the overall rate
    # of episodes that opened at least each fraction, per result folder.
    curve = any(r["overall"] and r["overall"]["opening_curve"] for r in results)
    rows = len(metrics) + (1 if curve else 0)
    fig, axes = plt.subplots(rows, 1, figsize=(max(6.0, 0.45 * len(objects) + 2), 2.4 * rows), squeeze=False)
    for ax in axes[1:len(metrics), 0]:
        ax.sharex(axes[0, 0])
    for ax, metric in zip(axes[:len(metrics), 0], metrics):
        ax.manibench_metric = "success_rate" if metric == "success_rate" else "condition_" + metric
        for i, r in enumerate(results):
            label = r["split"] or os.path.basename(os.path.normpath(directories[i]))
            xs = [j + (i - (len(results) - 1) / 2) * width for j, o in enumerate(objects) if o in r["objects"]]
            ys = [r["objects"][o][metric] for o in objects if o in r["objects"]]
            # The success rate's intervals as error bars (ErrorbarContainer
            # beside the bars: ax.manibench_intervals keeps them per label).
            intervals = [r["objects"][o].get("success_interval") for o in objects if o in r["objects"]]
            yerr = None
            if metric == "success_rate" and intervals and all(intervals):
                yerr = [[y - lo for y, (lo, _) in zip(ys, intervals)], [hi - y for y, (_, hi) in zip(ys, intervals)]]
                if not hasattr(ax, "manibench_intervals"):
                    ax.manibench_intervals = {}
                ax.manibench_intervals[label] = intervals
            ax.bar(xs, ys, width, label=label, color=SPLIT_COLOURS.get(label), yerr=yerr, capsize=2,
                   error_kw={"elinewidth": 0.8, "ecolor": "#333333"})
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("success" if metric == "success_rate" else metric.replace("_", " "))
        ax.grid(axis="y", alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize="small")
    axes[0, 0].set_title(f"{results[0]['task']}: {results[0]['policy']}, rate per object")
    for ax in axes[:len(metrics) - 1, 0]:
        ax.tick_params(labelbottom=False)
    bottom = axes[len(metrics) - 1, 0]
    bottom.set_xticks(range(len(objects)))
    bottom.set_xticklabels(objects, rotation=60, ha="right", fontsize="small")
    if curve:
        ax = axes[-1, 0]
        ax.manibench_metric = "opening_curve"
        for i, r in enumerate(results):
            points = r["overall"]["opening_curve"] if r["overall"] else []
            if not points:
                continue
            label = f"{r['policy']} ({r['split'] or os.path.basename(os.path.normpath(directories[i]))})"
            xs, ys = [p[0] for p in points], [p[1] for p in points]
            yerr = [[y - p[2] for y, p in zip(ys, points)], [p[3] - y for y, p in zip(ys, points)]]
            ax.errorbar(xs, ys, yerr=yerr, marker="o", capsize=3, label=label)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.05)
        ax.set_xlabel("fraction of the joint's range opened (at any step)")
        ax.set_ylabel("episodes")
        ax.set_title("opening curve, all objects (95 % intervals)", fontsize="medium")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower left", fontsize="small")
    fig.tight_layout()
    return fig


def read_csv_columns(path: str) -> dict[str, list]:
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    columns: dict[str, list] = {name: [] for name in (rows[0] if rows else {})}
    for row in rows:
        for name, value in row.items():
            try:
                columns[name].append(float(value))
            except (TypeError, ValueError):
                columns[name].append(value)
    return columns


def plot_training(directory: str):
    """The training curves of a `manibench train` folder: log.csv's columns
    against its first (iteration or env_steps), eval.csv's success rate per
    split."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    log = read_csv_columns(os.path.join(directory, "log.csv"))
    names = list(log)
    x_name = names[0]
    skip = {x_name, "seconds", "updates", "episodes", "iterations_per_second", "env_steps_per_second",
            "updates_per_second", "physics_share", "acting_share", "updates_share", "waiting_share"}
    curves = [n for n in names if n not in skip]
    eval_path = os.path.join(directory, "eval.csv")
    panels = len(curves) + (1 if os.path.exists(eval_path) else 0)
    fig, axes = plt.subplots(max(panels, 1), 1, figsize=(7, 2.2 * max(panels, 1)), squeeze=False, sharex=True)
    for ax, name in zip(axes[:, 0], curves):
        ax.plot(log[x_name], log[name], lw=1)
        ax.set_ylabel(name.replace("_", " "))
        ax.grid(alpha=0.3)
    if os.path.exists(eval_path):
        ev = read_csv_columns(eval_path)
        ax = axes[len(curves), 0]
        for split in sorted(set(ev.get("split", []))):
            pts = [(i, r) for i, s, r in zip(ev["iteration"], ev["split"], ev["success_rate"]) if s == split]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=split, color=SPLIT_COLOURS.get(split))
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("success rate")
        ax.legend(fontsize="small")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(x_name.replace("_", " "))
    axes[0, 0].set_title(os.path.basename(os.path.normpath(directory)))
    fig.tight_layout()
    return fig


PLY_TYPES = {"float": "<f4", "double": "<f8", "uchar": "u1", "char": "i1", "int": "<i4", "uint": "<u4",
             "short": "<i2", "ushort": "<u2"}


def read_ply(path: str):
    """The vertices of a binary little-endian PLY file (manibench render's
    point clouds) as a numpy structured array, one field per property."""
    import numpy as np

    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise ValueError(f"{path}: not a PLY file")
        count, fields = 0, []
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            words = line.decode("ascii", "replace").split()
            if words[:1] == ["format"] and words[1] != "binary_little_endian":
                raise ValueError(f"{path}: format {words[1]} (binary_little_endian expected)")
            if words[:2] == ["element", "vertex"]:
                count = int(words[2])
            elif words[:1] == ["property"]:
                if words[1] not in PLY_TYPES:
                    raise ValueError(f"{path}: property type {words[1]}")
                fields.append((words[2], PLY_TYPES[words[1]]))
            elif words[:1] == ["end_header"]:
                break
        data = np.frombuffer(f.read(), dtype=np.dtype(fields), count=count)
    return data


def plot_pointcloud(directory: str):
    """The point cloud of a render folder, coloured by its rgb."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    points = read_ply(os.path.join(directory, "pointcloud.ply"))
    fig = plt.figure(figsize=(6.4, 4.8))
    ax = fig.add_subplot(projection="3d")
    rgb = np.stack([points["red"], points["green"], points["blue"]], axis=1) / 255.0
    ax.scatter(points["x"], points["y"], points["z"], c=rgb, s=4, depthshade=False)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    # Equal scales on the three axes, so that shapes are not distorted.
    lo = np.array([points[k].min() for k in "xyz"])
    hi = np.array([points[k].max() for k in "xyz"])
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.view_init(elev=30, azim=-150)
    ax.set_title(f"{len(points)} points")
    return fig


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="manibench plot", description=__doc__.split("\n\n")[0])
    parser.add_argument("dirs", nargs="+", metavar="DIR",
                        help="eval --out folders, or one train --out or render --out folder")
    parser.add_argument("--out", help="the figure (.png, .pdf, .svg)")
    args = parser.parse_args(argv)
    try:
        if all(os.path.exists(os.path.join(d, "summary.csv")) for d in args.dirs):
            fig, default = plot_eval(args.dirs), os.path.join(args.dirs[0], "results.png")
        elif len(args.dirs) == 1 and os.path.exists(os.path.join(args.dirs[0], "log.csv")):
            fig, default = plot_training(args.dirs[0]), os.path.join(args.dirs[0], "curves.png")
        elif len(args.dirs) == 1 and os.path.exists(os.path.join(args.dirs[0], "pointcloud.ply")):
            fig, default = plot_pointcloud(args.dirs[0]), os.path.join(args.dirs[0], "pointcloud.png")
        else:
            raise FileNotFoundError("each DIR must hold summary.csv (manibench eval --out), or one DIR log.csv "
                                    "(manibench train --out) or pointcloud.ply (manibench render --out): " +
                                    ", ".join(args.dirs))
        out = args.out or default
        fig.savefig(out, dpi=120)
    except (OSError, ValueError, KeyError) as e:
        print(f"manibench plot: {e}", file=sys.stderr)
        return 1
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
