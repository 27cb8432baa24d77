"""`manibench report`: the HTML page of a real evaluation holds summary.csv's
numbers per object, a row per failed episode, the figure, the certificate's
digests and, per object, videos of a success and a failure whose re-run is
the report's episode; opened in headless Chromium (Debian's chromium), the
page shows the overall rate and plays every video."""
import csv
import html.parser
import json
import os
import shutil
import subprocess

import pytest

BINARY = os.environ.get("MANIBENCH_BIN")
pytestmark = pytest.mark.skipif(not BINARY, reason="needs MANIBENCH_BIN (set by ctest)")


class Page(html.parser.HTMLParser):
    """The page's tables (by class: rows of cell texts), its videos'
    attributes and its images' sources."""

    def __init__(self):
        super().__init__()
        self.tables, self.videos, self.images, self.texts = {}, [], [], {}
        self._table = self._row = self._cell = None
        self._id = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table":
            self._table = self.tables.setdefault(attrs.get("class", ""), [])
        elif tag == "tr" and self._table is not None:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""
        elif tag == "video":
            self.videos.append(attrs)
        elif tag == "img":
            self.images.append(attrs.get("src", ""))
        self._id = attrs.get("id") or self._id

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell.strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self._table.append(self._row)
            self._row = None
        elif tag == "table":
            self._table = None
        if self._id and tag in ("b", "span"):
            self._id = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data
        if self._id:
            self.texts[self._id] = self.texts.get(self._id, "") + data


def parse(text):
    page = Page()
    page.feed(text)
    return page


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """A real evaluation of Reach's expert held to 25 steps (some episodes
    succeed, some run out of time), and its page with videos of 2 objects."""
    out = tmp_path_factory.mktemp("report")
    subprocess.run([BINARY, "eval", "Reach-v0", "--policy", "reach_expert", "--split", "train",
                    "--episodes-per-object", "2", "--trusted-policy", "--no-progress",
                    "--set", "episode.max_steps=25", "--out", str(out)], check=True, capture_output=True)
    run = subprocess.run([BINARY, "report", str(out), "--videos", "2"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    with open(out / "episodes.csv", newline="") as f:
        episodes = list(csv.DictReader(f))
    with open(out / "summary.csv", newline="") as f:
        summary = list(csv.DictReader(f))
    return out, episodes, summary


def test_the_tables_are_the_reports_numbers(report):
    out, episodes, summary = report
    page = parse((out / "report.html").read_text())
    rows = page.tables["rates"]
    head, body = rows[0], rows[1:]
    assert [r[0] for r in body] == [r["object"] for r in summary]
    success = head.index("success")
    for row, want in zip(body, summary):
        assert row[success] == f"{100 * float(want['success_rate']):.1f} %", row
        assert row[head.index("episodes")] == want["episodes"]
    failed = [e for e in episodes if e["success"] != "1"]
    assert failed and len(failed) < len(episodes), "the 25-step limit should fail some episodes, not all"
    assert [(r[0], r[1], r[2]) for r in page.tables["failed"][1:]] == [(e["object"], e["level"], e["seed"])
                                                                        for e in failed]
    assert any(src.startswith("data:image/png;base64,") for src in page.images)
    certificate = json.loads((out / "certificate.json").read_text())
    digests = {r[-1] for r in page.tables["certificate"][1:]}
    assert {i["sha256"] for i in certificate["inputs"]} <= digests
    assert certificate["configuration"]["sha256"] in digests


def test_each_video_is_the_reports_episode_run_again(report):
    out, episodes, _ = report
    text = (out / "report.html").read_text()
    page = parse(text)
    first_two = list(dict.fromkeys(e["object"] for e in episodes))[:2]
    wanted = {(e["object"], e["success"]) for e in episodes if e["object"] in first_two}
    assert len(page.videos) == len(wanted) >= 2
    assert text.count("the report&#x27;s episode") == len(wanted)
    assert "NOT the report" not in text


@pytest.mark.skipif(shutil.which("chromium") is None, reason="needs Debian's chromium (scripts/install-deps)")
def test_headless_chromium_shows_the_rate_and_plays_the_videos(report, tmp_path):
    out, _, summary = report
    page_url = (out / "report.html").as_uri()
    browser = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
               f"--user-data-dir={tmp_path / 'profile'}"]
    # Under make sanitize the interpreter preloads the ASan runtime; the
    # browser is not ours to check.
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    dom = subprocess.run(browser + ["--virtual-time-budget=10000", "--dump-dom", page_url],
                         capture_output=True, text=True, timeout=120, env=env)
    assert dom.returncode == 0, dom.stderr[-2000:]
    page = parse(dom.stdout)
    overall = next(r for r in summary if r["object"] == "all")
    assert page.texts["success"] == f"{100 * float(overall['success_rate']):.1f} %"
    assert page.videos
    for video in page.videos:
        # Set by the page's script once the browser has decoded the video's
        # header: it plays here.
        assert float(video.get("data-duration", "0")) > 0, {k: v for k, v in video.items() if k != "src"}
        assert video.get("data-width") == "480"
    shot = tmp_path / "page.png"
    subprocess.run(browser + ["--window-size=1200,1600", f"--screenshot={shot}", page_url],
                   capture_output=True, timeout=120, check=True, env=env)
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 20000


def test_a_folder_that_is_no_evaluation_and_a_bad_size_are_refused_naming_why(tmp_path, report):
    run = subprocess.run([BINARY, "report", str(tmp_path)], capture_output=True, text=True)
    assert run.returncode == 1
    assert f"{tmp_path}: no summary.json (not a `manibench eval --out` folder)" in run.stderr
    assert not (tmp_path / "report.html").exists()
    out = report[0]
    run = subprocess.run([BINARY, "report", str(out), "--video-size", "big"], capture_output=True, text=True)
    assert run.returncode == 2 and "--video-size must be WxH" in run.stderr


def test_a_task_with_categories_gets_a_table_per_category(tmp_path):
    """Two PartNet folders (the hand-made fixture's two cabinets, one per
    folder): the page's category table is summary.json's per_category."""
    source = os.path.join(os.environ.get("MANIBENCH_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..")),
                          "tests", "fixtures", "partnet_mini")
    folders = []
    for category, object_id in (("Cupboard", "100001"), ("Chest", "100002")):
        shutil.copytree(os.path.join(source, object_id), tmp_path / "data" / category / object_id)
        (tmp_path / "data" / category / "test.txt").write_text(object_id + "\n")
        folders.append(str(tmp_path / "data" / category))
    out = tmp_path / "out"
    subprocess.run([BINARY, "eval", "OpenCabinetDrawer-v0", "--policy", "open_cabinet_expert", "--levels", "0",
                    "--trusted-policy", "--no-progress", "--set", f"task.partnet_dir=[{', '.join(folders)}]",
                    "--set", "task.partnet_scale=1", "--out", str(out)], check=True, capture_output=True)
    run = subprocess.run([BINARY, "report", str(out), "--videos", "0"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    page = parse((out / "report.html").read_text())
    rows = page.tables["rates categories"]
    summary = json.loads((out / "summary.json").read_text())
    assert [r[0] for r in rows[1:]] == [c["category"] for c in summary["per_category"]] == ["Chest", "Cupboard"]
    assert [r[1] for r in rows[1:]] == ["1", "1"]
