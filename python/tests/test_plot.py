"""`manibench plot`: the evaluation figure of a two-split run (train and
test) shows exactly summary.csv's numbers, read back from the figure's bars
and the success rate's error bars (its 95 % intervals);
and the training curves of a log.csv."""
import csv
import os
import subprocess

import pytest

from manibench import plot

BINARY = os.environ.get("MANIBENCH_BIN")
pytestmark = pytest.mark.skipif(not BINARY, reason="needs MANIBENCH_BIN (set by ctest)")


def evaluate(split, out):
    subprocess.run([BINARY, "eval", "Reach-v0", "--policy", "reach_expert", "--split", split,
                    "--episodes-per-object", "2", "--trusted-policy", "--no-progress", "--out", str(out)],
                   check=True, capture_output=True)


def test_eval_figure_numbers_equal_summary_csv(tmp_path):
    train, test = tmp_path / "train", tmp_path / "test"
    evaluate("train", train)
    evaluate("test", test)
    figure = tmp_path / "results.png"
    run = subprocess.run([BINARY, "plot", str(train), str(test), "--out", str(figure)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    fig = plot.plot_eval([str(train), str(test)])
    axes = fig.get_axes()
    objects = [t.get_text() for t in axes[-1].get_xticklabels()]
    checked = 0
    for split, folder in (("train", train), ("test", test)):
        with open(folder / "summary.csv", newline="") as f:
            rows = {r["object"]: r for r in csv.DictReader(f) if r["object"] != "all"}
        assert rows, folder
        for ax in axes:
            bars = [c for c in ax.containers if c.get_label() == split]
            assert len(bars) == 1, (ax.manibench_metric, split)
            heights = [p.get_height() for p in bars[0].patches]
            # The bars of a split are its objects, in the figure's order.
            mine = [o for o in objects if o in rows]
            assert len(heights) == len(mine) == len(rows)
            assert heights == [float(rows[o][ax.manibench_metric]) for o in mine], ax.manibench_metric
            checked += len(heights)
            if ax.manibench_metric == "success_rate":
                # The error bars span summary.csv's 95 % intervals.
                segments = bars[0].errorbar.lines[2][0].get_segments()
                spans = [(s[0][1], s[1][1]) for s in segments]
                wanted = [(float(rows[o]["success_low"]), float(rows[o]["success_high"])) for o in mine]
                assert len(spans) == len(wanted)
                for (a, b), (lo, hi) in zip(spans, wanted):
                    assert a == pytest.approx(lo, abs=1e-9) and b == pytest.approx(hi, abs=1e-9)
    metrics = {ax.manibench_metric for ax in axes}
    assert "success_rate" in metrics and any(m.startswith("condition_") for m in metrics)
    assert checked >= 2 * len(axes)


def test_training_curves(tmp_path):
    (tmp_path / "log.csv").write_text("iteration,seconds,loss,iterations_per_second\n"
                                      "100,1.0,0.5,100\n200,2.0,0.25,100\n")
    (tmp_path / "eval.csv").write_text("iteration,split,episodes,successes,success_rate\n"
                                       "200,train,4,2,0.5\n200,test,4,1,0.25\n")
    fig = plot.plot_training(str(tmp_path))
    loss = fig.get_axes()[0]
    assert list(loss.get_lines()[0].get_ydata()) == [0.5, 0.25]
    rates = {line.get_label(): list(line.get_ydata()) for line in fig.get_axes()[1].get_lines()}
    assert rates == {"train": [0.5], "test": [0.25]}
    assert plot.main([str(tmp_path)]) == 0
    assert (tmp_path / "curves.png").exists()


def test_pointcloud_figure(tmp_path):
    """A render folder's pointcloud.ply: read back point for point (the
    sampled cloud's 1,200 points, their rgb), and drawn."""
    out = tmp_path / "frames"
    subprocess.run([BINARY, "render", "OpenCabinetDrawer-v0", "--seed", "1", "--obs", "pointcloud", "--out", str(out)],
                   check=True, capture_output=True)
    points = plot.read_ply(str(out / "pointcloud.ply"))
    assert len(points) == 1200
    assert {"x", "y", "z", "red", "green", "blue"} <= set(points.dtype.names)
    assert (points["z"] > -0.01).all()
    run = subprocess.run([BINARY, "plot", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (out / "pointcloud.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
