"""One self-contained HTML page of an evaluation (Debian's python3 and matplotlib).

    manibench report DIR [--out PAGE.html] [--videos N] [--video-size WxH]

DIR is a ``manibench eval --out`` folder (summary.json, summary.csv,
episodes.csv, certificate.json). The page holds the overall and per-object
tables with their 95 % intervals (and the opening curve for doors and
drawers), why each failed episode failed, the figure of ``manibench plot``,
the certificate (what the results came from, with SHA-256), and for up to N
objects (default 5, 0 for none) a short video of one successful and one
failed episode. The videos are not recorded during the evaluation: the
report runs each chosen episode again with ``manibench run`` (the task,
policy, controller, observation mode and merged configuration of the
certificate, the episode's object and seed) and writes beside the video
whether the episode it recorded is the report's (its steps and return
against episodes.csv). Figures and videos are embedded, so the one file can
be mailed or attached. The default page is DIR/report.html.

Only the standard library and matplotlib: it never imports the extension
module. `manibench report` runs this file (bin/manibench-plot finds it).
"""

from __future__ import annotations

import argparse
import base64
import csv
import html
import importlib.util
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from typing import Any

# Options of the eval's command line that `manibench run` takes as they are
# (every other eval option is about how episodes are scheduled and logged).
RUN_OPTIONS = ("--policy", "--policy-config", "--controller", "--obs", "--config", "--set")


def read_report(directory: str) -> dict[str, Any]:
    """summary.json, episodes.csv's rows and certificate.json of an eval
    folder, and the names of what is missing."""
    def need(name):
        path = os.path.join(directory, name)
        if not os.path.exists(path):
            raise FileNotFoundError(f"{directory}: no {name} (not a `manibench eval --out` folder)")
        return path

    with open(need("summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    with open(need("episodes.csv"), newline="", encoding="utf-8") as f:
        episodes = list(csv.DictReader(f))
    certificate = None
    if os.path.exists(os.path.join(directory, "certificate.json")):
        with open(os.path.join(directory, "certificate.json"), encoding="utf-8") as f:
            certificate = json.load(f)
    return {"summary": summary, "episodes": episodes, "certificate": certificate}


def percent(rate: float) -> str:
    return f"{100 * rate:.1f} %"


def interval(pair) -> str:
    if not pair:
        return ""
    return f"[{100 * pair[0]:.1f}, {100 * pair[1]:.1f}]"


def esc(value: Any) -> str:
    return html.escape(str(value))


def rate_rows(summary: dict, by: str = "object") -> tuple[list[str], list[list[str]]]:
    """The per-object table (and the overall row last): episodes, success
    with its interval, success once and at the end, each condition and the
    opening curve where the task has one. by="category": the same per
    category (summary.json's per_category, where the task names them),
    with each category's number of objects and no overall row."""
    overall = summary.get("overall") or {}
    if by == "category":
        entries = summary.get("per_category", [])
    else:
        entries = summary.get("per_object", []) + ([dict(overall, object="all")] if overall else [])
    conditions = [c for c in summary.get("success_conditions", []) if c != "success"]
    fractions = [p["fraction"] for p in (overall.get("opening_curve") or [])]
    head = [by] + (["objects"] if by == "category" else [])
    head += ["episodes", "success", "95 % interval", "success once", "success at end"]
    head += conditions + [f"opened {100 * f:g} %" for f in fractions] + ["mean steps"]
    rows = []
    for entry in entries:
        row = [entry.get(by, "")] + ([str(entry.get("objects", ""))] if by == "category" else [])
        row += [str(entry.get("episodes", "")),
               percent(entry.get("success_rate", 0)), interval(entry.get("success_interval")),
               percent(entry.get("success_once_rate", entry.get("success_rate", 0))),
               percent(entry.get("success_at_end_rate", entry.get("success_rate", 0)))]
        rates = entry.get("condition_rates", {})
        row += [percent(rates[c]) if c in rates else "" for c in conditions]
        curve = {p["fraction"]: p for p in (entry.get("opening_curve") or [])}
        row += [f"{percent(curve[f]['rate'])} {interval(curve[f].get('interval'))}" if f in curve else ""
                for f in fractions]
        steps = entry.get("mean_steps")
        row.append(f"{steps:.1f}" if isinstance(steps, (int, float)) else "")
        rows.append(row)
    return head, rows


def table(head: list[str], rows: list[list[str]], css_class: str) -> str:
    out = [f'<table class="{css_class}"><thead><tr>']
    out += [f"<th>{esc(h)}</th>" for h in head]
    out.append("</tr></thead><tbody>")
    for row in rows:
        cls = ' class="overall"' if row and row[0] == "all" else ""
        out.append(f"<tr{cls}>" + "".join(f"<td>{esc(c)}</td>" for c in row) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def failed_episodes(episodes: list[dict], conditions: list[str]) -> list[list[str]]:
    """Each failed episode: object, level, seed, steps, the failure's kind
    (crash, timeout, ... or "not successful" for an episode that ran to its
    end unsuccessful) with its step, and the message (the failure's reason;
    for an unsuccessful episode the success conditions unmet at its end,
    from its condition columns)."""
    rows = []
    for e in episodes:
        if e.get("success") == "1":
            continue
        kind = e.get("failure") or "not successful"
        step = f" at step {e['failure_step']}" if e.get("failure_step") else ""
        message = e.get("message", "")
        if not message and not e.get("failure"):
            unmet = [c for c in conditions if c != "success" and e.get(c) == "0"]
            message = "unmet at the end: " + ", ".join(unmet) if unmet else ""
        rows.append([e.get("object", ""), e.get("level", ""), e.get("seed", ""), e.get("steps", ""),
                     kind + step, message])
    return rows


def figure_png(directory: str) -> bytes | None:
    """The evaluation figure of `manibench plot DIR`, as PNG bytes (None
    where matplotlib is missing or the report has no per-object rows)."""
    # plot.py beside this file, loaded by its path: importing the package
    # would load the extension module.
    spec = importlib.util.spec_from_file_location(
        "manibench_plot", os.path.join(os.path.dirname(os.path.abspath(__file__)), "plot.py"))
    plot = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(plot)
    try:
        fig = plot.plot_eval([directory])
    except (ImportError, ValueError, KeyError, IndexError):
        return None
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return buffer.getvalue()


def run_command(certificate: dict, summary: dict) -> list[str]:
    """The eval's task and the options of its command line that decide an
    episode (policy, controller, observation mode, configuration layers),
    for `manibench run`."""
    command = certificate.get("command", [])
    out = [summary["task"]]
    for i, word in enumerate(command):
        name = word.split("=", 1)[0]
        if name in RUN_OPTIONS:
            if "=" in word:
                out.append(word)
            elif i + 1 < len(command):
                out += [word, command[i + 1]]
    if not summary.get("early_done", True):
        out.append("--no-early-stop")
    return out


def choose_episodes(episodes: list[dict], objects: int) -> list[dict]:
    """For the first `objects` objects (in the report's order), the first
    successful and the first failed episode of each."""
    chosen, seen = [], []
    for e in episodes:
        if e["object"] not in seen:
            if len(seen) == objects:
                continue
            seen.append(e["object"])
        if not any(c["object"] == e["object"] and c["success"] == e["success"] for c in chosen):
            chosen.append(e)
    return chosen


def record_video(manibench: str, base: list[str], episode: dict, working_directory: str, size: str,
                 folder: str) -> dict:
    """Runs one episode again with a video; returns the video's bytes (or
    None) and what the run said of the episode, checked against the
    report's row."""
    path = os.path.join(folder, f"{episode['index']}.mp4")
    command = [manibench, "run"] + base + ["--object", episode["object"], "--seed", episode["seed"],
                                           "--video", path, "--video-size", size]
    # Relative paths of the command line (a --config file) are the eval's
    # working directory's, where it still exists (a report sent from
    # another machine: this one's).
    cwd = working_directory if working_directory and os.path.isdir(working_directory) else None
    run = subprocess.run(command, capture_output=True, text=True, cwd=cwd)
    if run.returncode != 0 or not os.path.exists(path):
        reason = (run.stderr.strip().splitlines() or ["no output"])[-1]
        return {"video": None, "note": f"could not record it: {reason}"}
    found = re.search(r":\s*(\d+) steps, return (\S+)", run.stdout)
    note = "the run printed no steps and return"
    if found:
        steps, ret = int(found.group(1)), float(found.group(2))
        same = steps == int(episode["steps"]) and abs(ret - float(episode["return"])) < 1e-3 * max(1, abs(ret))
        note = (f"{steps} steps, return {ret:g}: " +
                ("the report's episode" if same else
                 f"NOT the report's episode ({episode['steps']} steps, return {float(episode['return']):g})"))
    with open(path, "rb") as f:
        return {"video": f.read(), "note": note}


def videos_section(directory: str, report: dict, objects: int, size: str, manibench: str | None) -> str:
    summary, certificate = report["summary"], report["certificate"]
    if objects <= 0:
        return "<p>No videos (--videos 0).</p>"
    if certificate is None:
        return "<p>No videos: the report has no certificate.json to run its episodes again from.</p>"
    if not manibench:
        return "<p>No videos: the manibench program was not found beside this script or in PATH.</p>"
    if shutil.which("ffmpeg") is None:
        return "<p>No videos: they need the ffmpeg program (Debian package ffmpeg).</p>"
    base = run_command(certificate, summary)
    out = []
    with tempfile.TemporaryDirectory(prefix="manibench-report-") as folder:
        for episode in choose_episodes(report["episodes"], objects):
            result = record_video(manibench, base, episode, certificate.get("working_directory", ""), size, folder)
            outcome = "success" if episode["success"] == "1" else "failure"
            caption = (f"{esc(episode['object'])}, level {esc(episode['level'])}, seed {esc(episode['seed'])}: "
                       f"{outcome} ({esc(result['note'])})")
            if result["video"] is None:
                out.append(f'<figure class="video"><figcaption>{caption}</figcaption></figure>')
                continue
            data = base64.b64encode(result["video"]).decode("ascii")
            out.append(f'<figure class="video" data-outcome="{outcome}"><video controls muted loop preload="auto" '
                       f'src="data:video/mp4;base64,{data}"></video><figcaption>{caption}</figcaption></figure>')
    command = " ".join(esc(w) for w in ["manibench", "run"] + base)
    return (f"<p>Each episode run again: <code>{command} --object ID --seed SEED --video FILE</code>.</p>" +
            "".join(out))


def certificate_section(certificate: dict | None) -> str:
    if certificate is None:
        return "<p>This report has no certificate.json (it predates certificates).</p>"
    rows = [[i.get("role", ""), i.get("name", ""), i.get("file", ""), i.get("sha256", "")]
            for i in certificate.get("inputs", [])]
    config = certificate.get("configuration", {})
    rows.append(["configuration", "merged YAML", "", config.get("sha256", "")])
    objects = certificate.get("objects", {})
    files = sum(len(v) if isinstance(v, list) else 1 for v in objects.values())
    parts = [f"<p>manibench {esc(certificate.get('manibench_version', ''))}, build "
             f"<code>{esc(certificate.get('build_id', ''))}</code>; command "
             f"<code>manibench eval {' '.join(esc(w) for w in certificate.get('command', []))}</code>. "
             f"{len(objects)} objects with {files} digested files. "
             f"<code>manibench eval --verify DIR</code> checks the report against it and runs its episodes "
             f"again bit for bit.</p>",
             table(["role", "name", "file", "SHA-256"], rows, "certificate"),
             f"<details><summary>configuration</summary><pre>{esc(config.get('yaml', ''))}</pre></details>"]
    return "".join(parts)


STYLE = """
body { font-family: sans-serif; margin: 2em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; white-space: nowrap; }
th { background: #f0f0f0; } td:first-child { text-align: left; }
tr.overall td { font-weight: bold; background: #fafafa; }
table.certificate td { text-align: left; font-family: monospace; font-size: 0.85em; }
figure.video { display: inline-block; margin: 0.5em; vertical-align: top; max-width: 420px; }
figure.video video { width: 400px; }
img.figure { max-width: 100%; }
"""

# Each video says in the page whether the browser could play it (a test
# reads these attributes from the DOM that headless Chromium builds).
SCRIPT = """
for (const v of document.querySelectorAll('video')) {
  v.addEventListener('loadedmetadata', () => {
    v.dataset.duration = v.duration.toFixed(2);
    v.dataset.width = v.videoWidth;
  });
}
"""


def make_page(directory: str, objects: int = 5, size: str = "480x360", manibench: str | None = None) -> str:
    report = read_report(directory)
    summary = report["summary"]
    overall = summary.get("overall") or {}
    head, rows = rate_rows(summary)
    title = f"{summary.get('task', '')}: {summary.get('policy', {}).get('name', '')} on the {summary.get('split', '')} split"
    facts = (f"{summary.get('episodes_run', 0)} of {summary.get('episodes_planned', 0)} episodes"
             f"{'' if summary.get('complete', True) else ' (incomplete: ' + str(summary.get('stop_reason', '')) + ')'}; "
             f"seed {summary.get('seed', '')}; {summary.get('observation_mode', '')} observations; "
             f"controller {summary.get('controller', '')}; at most {summary.get('max_episode_steps', '')} steps; "
             f"early done {'on' if summary.get('early_done', True) else 'off'}.")
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{esc(title)}</title>",
             f"<style>{STYLE}</style></head><body>",
             f"<h1>{esc(title)}</h1>",
             f"<p class='headline'>Success <b id='success'>{percent(overall.get('success_rate', 0))}</b> "
             f"(95 % interval {interval(overall.get('success_interval'))}, a bootstrap over objects).</p>",
             f"<p>{esc(facts)}</p>",
             "<h2>Per object</h2>", table(head, rows, "rates"),
             "<p>Intervals: Wilson per object; the overall row's resamples the objects.</p>"]
    if summary.get("per_category"):
        parts += ["<h2>Per category</h2>", table(*rate_rows(summary, "category"), "rates categories"),
                  "<p>A category's rate pools its objects' episodes; its interval resamples its objects.</p>"]
    failures = summary.get("failures") or {}
    failed = failed_episodes(report["episodes"], summary.get("success_conditions", []))
    parts.append("<h2>Failed episodes</h2>")
    if failures:
        parts.append("<p>Failures by kind: " + ", ".join(f"{esc(k)} {esc(v)}" for k, v in failures.items()) + ".</p>")
    parts.append(table(["object", "level", "seed", "steps", "failure", "message"], failed, "failed")
                 if failed else "<p>None.</p>")
    png = figure_png(directory)
    parts.append("<h2>Figure</h2>")
    parts.append(f"<img class='figure' alt='success per object' src='data:image/png;base64,"
                 f"{base64.b64encode(png).decode('ascii')}'>" if png else "<p>No figure (matplotlib missing).</p>")
    parts.append("<h2>Videos</h2>")
    parts.append(videos_section(directory, report, objects, size, manibench))
    parts.append("<h2>Certificate</h2>")
    parts.append(certificate_section(report["certificate"]))
    parts.append(f"<script>{SCRIPT}</script></body></html>")
    return "\n".join(parts)


def find_manibench() -> str | None:
    """The manibench program of this installation or build tree (bin/
    beside this file's python/ or lib/python3*/dist-packages), else PATH's."""
    here = os.path.dirname(os.path.abspath(__file__))
    for prefix in (os.path.dirname(os.path.dirname(here)), os.path.dirname(os.path.dirname(os.path.dirname(here))),
                   os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(here))))):
        candidate = os.path.join(prefix, "bin", "manibench")
        if os.access(candidate, os.X_OK):
            return candidate
    return os.environ.get("MANIBENCH_BIN") or shutil.which("manibench")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="manibench report", description=__doc__.split("\n\n")[0])
    parser.add_argument("dir", metavar="DIR", help="a manibench eval --out folder")
    parser.add_argument("--out", help="the page (default DIR/report.html)")
    parser.add_argument("--videos", type=int, default=5, metavar="N",
                        help="objects with videos of a success and a failure (default 5; 0 for none)")
    parser.add_argument("--video-size", default="480x360", metavar="WxH", help="the videos' frame size")
    args = parser.parse_args(argv)
    if not re.fullmatch(r"\d+x\d+", args.video_size):
        parser.error(f"--video-size must be WxH, e.g. 480x360 (got '{args.video_size}')")
    try:
        page = make_page(args.dir, args.videos, args.video_size, find_manibench())
        out = args.out or os.path.join(args.dir, "report.html")
        with open(out, "w", encoding="utf-8") as f:
            f.write(page)
    except (OSError, ValueError, KeyError) as e:
        print(f"manibench report: {e}", file=sys.stderr)
        return 1
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
