"""Smoke test of the benchmark suite: `bench/run.py --quick` completes and every
table is there with sane numbers (no thresholds on the results)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import DATA, run_bench_code
from seahough._data import shared_data_dir

ROOT = Path(__file__).resolve().parents[1]
RUN = ROOT / "bench" / "run.py"

SECTIONS = {
    "marker": "## Markers",
    "fragment": "## Seabed fragments",
    "pair": "## Frame pairs",
    "rope": "## Ropes",
    "negative": "## Negatives",
    "real": "## Real sequences",
}


def _quick_page(script: Path, out: Path, *extra: str) -> str:
    """Run ``script --quick --out out`` (and ``extra`` arguments) with this
    checkout's package; the page it wrote, checked to be what it printed."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, str(script), "--quick", "--out", str(out), *extra],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-3000:]
    text = out.read_text()
    assert text.strip() == proc.stdout.strip()
    return text


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    return _quick_page(RUN, tmp_path_factory.mktemp("bench") / "report.md")


def _section(text: str, title: str) -> str:
    start = text.index(title)
    nxt = text.find("\n## ", start + len(title))
    return text[start: nxt if nxt >= 0 else len(text)]


def _rows(section: str) -> list[list[str]]:
    rows = []
    for line in section.splitlines():
        if line.startswith("|") and not line.startswith("|---"):
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def _percentages(cells) -> list[float]:
    vals = []
    for c in cells:
        for m in re.finditer(r"(-?\d+(?:\.\d+)?) %", c):
            vals.append(float(m.group(1)) / 100.0)
    return vals


def test_quick_run_has_every_table_with_seahough(quick_report):
    text = quick_report
    assert "## Headline" in text
    assert "Machine:" in text and "Command:" in text and "Date:" in text
    for task, title in SECTIONS.items():
        if task == "real" and shared_data_dir() is None:
            assert "Skipped" in _section(text, title)
            continue
        sec = _section(text, title)
        rows = _rows(sec)
        assert len(rows) >= 3, f"{task}: no table"
        methods = [r[0] for r in rows[1:]] + [r[2] for r in rows[1:] if len(r) > 2]
        assert any(m.startswith("seahough") for m in methods), f"{task}: seahough missing"
        for r in rows[1:]:
            for v in _percentages(r):
                assert 0.0 <= v <= 1.0, f"{task}: rate out of [0, 1] in {r}"


def test_headline_rows_are_sane(quick_report):
    rows = _rows(_section(quick_report, "## Headline"))
    tasks = [r[0] for r in rows[1:]]
    for prefix in ("marker (moderate)", "marker (hard)", "fragment", "pair (near)", "pair (free)",
                   "rope", "negative"):
        assert any(t.startswith(prefix) for t in tasks), prefix
    for r in rows[1:]:
        for v in _percentages(r[1:2] + r[5:6]):
            assert 0.0 <= v <= 1.0
        for cell in (r[3], r[7]):  # milliseconds: positive when present
            if cell not in ("", "-"):
                assert float(cell) > 0
        m = re.search(r"AUC (\d\.\d+)", r[1])
        if m:
            assert 0.0 <= float(m.group(1)) <= 1.0


def test_auc_rank_formula():
    # in a subprocess: importing bench/run.py makes the process single-threaded
    code = ("import run\n"
            "assert run.auc([3, 4], [1, 2]) == 1.0\n"
            "assert run.auc([1, 2], [3, 4]) == 0.0\n"
            "assert run.auc([1, 1], [1, 1]) == 0.5\n"
            "assert abs(run.auc([0.9, 0.4, 0.8], [0.1, 0.5]) - 5 / 6) < 1e-12\n"
            "assert run.line_errors(179.5, 10.0, 0.5, -10.0) == (1.0, 0.0)\n")
    run_bench_code(code, timeout=60)


def test_survey_chain_benchmark_runs():
    """bench/bench_survey_chain.py chains synthetic chunks exactly as a survey does."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "bench_survey_chain.py"), "1200"],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert re.search(r"chained 1200 frames in 7 chunks of 200: [\d.]+ s wall", proc.stdout), \
        proc.stdout


def test_odometry_drift_by_frame_size_runs():
    """bench/bench_odometry.py --sizes's rows, on 8-frame turns of one seed."""
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import bench_odometry as B
    finally:
        sys.path.remove(str(ROOT / "bench"))
    rows = B.drift_by_size(n=8, seeds=(0,))
    assert [(r[0], r[2]) for r in rows] == [("320x240", "default"), ("320x240", "every frame"),
                                            ("640x480", "default"), ("640x480", "every frame")]
    for size, seed, policy, drift, heading_err, keys in rows:
        assert 0 <= drift < 5 and 0 <= heading_err < 3, (size, policy, drift, heading_err)
        assert keys == 7 if policy == "every frame" else 1 <= keys <= 7


@pytest.mark.skipif(DATA is None or not (DATA / "sequences" / "sparus_auv_seabed").is_dir(),
                    reason="needs ../shared/data/sequences")
def test_survey_joins_benchmark_quick():
    """bench/bench_survey_joins.py --quick: a chunked dead reckoning against one run."""
    pytest.importorskip("distributed")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "bench_survey_joins.py"),
                           "--quick"], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    m = re.search(r"\| sparus_auv_seabed \| 22 \| ([\d.]+) px \|", proc.stdout)
    assert m and float(m.group(1)) < 10.0, proc.stdout


def test_real_pairs_benchmark_quick(tmp_path):
    """bench/bench_real_pairs.py --quick: every table, counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    out = tmp_path / "real_pairs.md"
    text = _quick_page(ROOT / "bench" / "bench_real_pairs.py", out)
    assert "Machine:" in text and "Command:" in text and "Date:" in text
    assert "Split: tune part = sparus_auv_seabed, skerki_mud_pair" in text
    targets = _rows(_section(text, "## Targets"))[1:]
    assert len(targets) == 9 and all(r[-1] in ("met", "**missed**") for r in targets)
    # issue 13's dead reckoning: every sequence's pairs measured, and its median step
    # error against the spread of the two fits
    measured = next(r for r in targets if r[0].startswith("dead reckoning: consecutive"))
    assert all(re.fullmatch(r"\S+ \d+/\d+", c.strip()) for c in measured[2].split(";"))
    spread = next(r for r in targets if r[0].startswith("dead reckoning: median step error"))
    cell = r"\S+ [\d.]+ / [\d.]+ \(fits: [\d.]+\)"
    assert re.fullmatch(rf"{cell}(; {cell})*", spread[2]), spread
    # beside it the spread of robust similarity fits to the same SIFT-lowc matches
    refs = _rows(_section(text, "## Reference motions"))
    assert "median spread of similarity fits to the SIFT-lowc matches % diag" in refs[0]
    # issue 14's checks again on frames cropped by a pixel (a quick run: 1 px only)
    crop_row = next(r for r in targets if "cropped by 1 px" in r[0])
    assert re.fullmatch(r"\d+; \d+", crop_row[2]), crop_row
    # issue 13's time row: each test sequence, seahough's ms against ORB+RANSAC's
    # (a quick run has half size only)
    assert targets[-1][0].startswith("median CPU ms a pair from scratch, half size")
    assert len(re.findall(r"\d+\.\d / \d+\.\d", targets[-1][2])) == 3
    methods = _rows(_section(text, "## Methods"))
    head, body = methods[0], methods[1:]
    col = {h: i for i, h in enumerate(head)}
    assert {r[0] for r in body} >= {"seahough", "SIFT+RANSAC", "ORB+RANSAC", "phase correlation"}
    for r in body:
        n = int(r[col["pairs with a reference"]])
        answered = re.match(r"(\d+)/(\d+)", r[col["answered"]])
        good = re.match(r"(\d+)/(\d+)", r[col["within 1 % (of answers)"]])
        assert int(answered.group(2)) == n and int(answered.group(1)) <= n, r
        assert int(good.group(2)) == int(answered.group(1)) and int(good.group(1)) <= int(
            good.group(2)), r
        assert int(r[col["off > 3 %"]].split()[0]) <= int(answered.group(1)), r
    # the sequences' first 2 pairs at half size: 2 + 1 + 2 + 1 + 2 pairs
    refs = _rows(_section(text, "## Reference motions"))[1:]
    assert sum(int(r[2]) for r in refs) == 8 and len(refs) == 5
    odo = _rows(_section(text, "## Dead reckoning"))[1:]
    assert len(odo) == 5 and all(re.match(r"\d+/\d+", r[3]) for r in odo)
    # the runs on cropped frames beside the main one, which they must repeat in form
    crops = _rows(_section(text, "## The same frames cropped"))
    assert [r[0] for r in crops[1:]] == ["0", "1"]
    assert crops[1][1:3] == [targets[0][2], targets[1][2]], (crops, targets)
    assert crops[2][1].split()[0].split("/")[1] == crops[1][1].split()[0].split("/")[1]
    assert all(re.match(r"\d+/8 ", r[4]) for r in crops[1:]), crops


def test_relief_benchmark_quick(tmp_path):
    """bench/bench_relief.py --quick: every table, counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_relief.py", tmp_path / "relief.md")
    assert "Machine:" in text and "Command:" in text and "Split by photo: tune part" in text
    scored = _rows(_section(text, "## Scored pairs"))
    strong = _rows(_section(text, "## Pairs with strong parallax"))
    n_scored = {r[1]: int(r[2]) for r in scored[1:] if r[0] == "seahough"}
    n_strong = {r[1]: int(r[2]) for r in strong[1:] if r[0] == "seahough"}
    # one sequence a part, 3 pairs at half size: scored or not
    assert n_scored["tune"] + n_strong["tune"] == 3 and n_scored["test"] + n_strong["test"] == 3
    for r in scored[1:]:
        answered = re.match(r"(\d+)/(\d+)", r[3])
        assert int(answered.group(2)) == int(r[2]) and int(answered.group(1)) <= int(r[2]), r
    odo = _rows(_section(text, "## Dead reckoning"))[1:]
    assert [r[0] for r in odo] == ["test", "tune"]
    assert all(re.match(r"\d+/3 ", r[2]) for r in odo), odo


def test_oblique_benchmark_dev_part_quick(tmp_path):
    """bench/bench_oblique.py --part dev: the development floors alone, never
    written over docs/oblique.md."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_oblique.py", tmp_path / "dev.md", "--part", "dev")
    assert "## Dev part" in text and "## Test part" not in text and "## Tune part" not in text
    rows = _rows(_section(text, "## Dev part"))
    assert any(r[1] == "seahough" and r[2] == "5" for r in rows[1:]), rows
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "bench_oblique.py"), "--part",
                           "dev", "--write"], cwd=ROOT, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2 and "not a page of docs/" in proc.stderr


def test_oblique_benchmark_quick(tmp_path):
    """bench/bench_oblique.py --quick: both parts, every method, counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_oblique.py", tmp_path / "oblique.md")
    assert "Machine:" in text and "Command:" in text and "Split: tune part" in text
    assert re.search(r"Loops closed and consistent by seahough: \d+/2 ", text)
    for part in ("## Test part", "## Tune part"):
        rows = _rows(_section(text, part))
        head, body = rows[0], rows[1:]
        col = {h: i for i, h in enumerate(head)}
        assert {r[1] for r in body} >= {"seahough", "seahough, similarity only", "SIFT+RANSAC",
                                         "phase correlation"}
        for r in body:
            answered = re.match(r"(\d+)/(\d+)", r[col["answered"]])
            assert answered.group(2) == r[col["pairs"]] == "5", r
            right = re.match(r"(\d+)/(\d+)", r[col["within 2 % (of answers)"]])
            assert right.group(2) == answered.group(1), r
            flow = r[col["median excess flow RMS % diag"]]   # (the best similarity's is least)
            assert flow == "-" or float(flow) >= -0.01, r
            loops = re.match(r"(\d+)/(\d+)", r[col["loops closed"]])
            assert loops.group(2) == "2" and int(loops.group(1)) <= 2, r
    pairs = _rows(_section(text, "## The pairs"))[1:]
    assert len(pairs) == 10 and {r[0] for r in pairs} == {"test", "tune"}
    # the dead reckoning over each sequence: 3 consecutive pairs, steps that add up
    odo = _rows(_section(text, "## Dead reckoning"))
    col = {h: i for i, h in enumerate(odo[0])}
    assert [r[0] for r in odo[1:]] == ["test", "tune"]
    for r in odo[1:]:
        measured = re.match(r"(\d+)/(\d+)", r[col["pairs measured"]])
        assert measured.group(2) == "3" and int(measured.group(1)) <= 3, r
        within = re.match(r"(\d+)/(\d+)", r[col["steps within 2 %"]])
        assert int(within.group(2)) <= int(measured.group(1)), r
        off = re.match(r"(\d+) \(NFA <= 1: (\d+)\)", r[col["steps off > 5 %"]])
        assert int(off.group(2)) <= int(off.group(1)) <= int(within.group(2)), r
    # the longer runs over the tiled floors (5 frames in a quick run: 4 pairs)
    long = _rows(_section(text, "## Longer runs over the tiled floors (5 frames)"))
    col = {h: i for i, h in enumerate(long[0])}
    assert [r[0] for r in long[1:]] == ["test", "tune"]
    for r in long[1:]:
        assert r[1] == "tiled floor, 5 frames", r
        measured = re.match(r"(\d+)/(\d+)", r[col["pairs measured"]])
        assert measured.group(2) == "4" and int(measured.group(1)) <= 4, r
        within = re.match(r"(\d+)/(\d+)", r[col["steps within 2 %"]])
        assert int(within.group(2)) <= int(measured.group(1)), r


def test_small_patch_benchmark_quick(tmp_path):
    """bench/bench_small_patch.py --quick: the tables, counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_small_patch.py", tmp_path / "small_patch.md")
    assert "Machine:" in text and "Split by photo: tune part" in text
    totals = _rows(_section(text, "## Totals"))[1:]
    assert [r[0] for r in totals] == ["test"] * 3 + ["tune"] * 3
    for r in totals:
        found = re.match(r"(\d+)/(\d+)", r[2])
        # one photo a part, a 96 px patch in each of its two frames
        assert int(found.group(2)) == 2 and int(found.group(1)) + int(r[3]) <= 2, r


def test_degraded_pairs_benchmark_quick(tmp_path):
    """bench/bench_degraded_pairs.py --quick: every degradation and method, counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_degraded_pairs.py", tmp_path / "degraded.md")
    assert "Machine:" in text and "## Tune part" in text
    rows = _rows(_section(text, "## Tune part"))[1:]
    assert len(rows) == 8 * 3          # degradations x methods
    for r in rows:
        pairs, answered = int(r[2]), int(r[3])
        within, of = (int(v) for v in r[4].split("/"))
        assert pairs == 4 and of == answered <= pairs and within + int(r[5]) <= answered, r
    # the frames as recorded: seahough measures every Sparus pair within 1 %
    assert rows[0][:5] == ["as recorded", "**seahough**", "4", "4", "4/4"]


def test_keyframes_benchmark_quick(tmp_path):
    """bench/bench_keyframes.py --quick: both settings on Sparus and a simulated run."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_keyframes.py", tmp_path / "keyframes.md")
    rows = _rows(text)
    assert rows[0][2:] == ["default (keyframes)", "rekey_overlap=1.0 (every frame)"]
    assert rows[1][0].startswith("sparus_auv_seabed") and rows[1][1] == "tune"
    assert rows[2][0].startswith("simulated, 1 runs")
    steps = [float(re.search(r"median step ([\d.]+) %", c).group(1)) for c in rows[1][2:]]
    assert all(0 < v < 1 for v in steps)


def test_tiled_floor_benchmark_quick(tmp_path):
    """bench/bench_tiled_floor.py --quick: the dev floor's first 4 pairs, the
    three methods, none of seahough's answers wrong (procedural: no data needed)."""
    text = _quick_page(ROOT / "bench" / "bench_tiled_floor.py", tmp_path / "tiled.md")
    rows = [r for r in _rows(text) if r[0] == "all"]
    assert [r[1] for r in rows] == ["seahough", "SIFT+RANSAC", "ORB+RANSAC"]
    assert rows[0][2] == "4" and rows[0][5] == "0" and int(rows[0][4]) >= 3


def test_real_pairs_reference_rule():
    """The reference of two fits is their mean where their corners agree within
    0.5 % of the diagonal, none otherwise; the KLT fit recovers a known motion."""
    code = (
        "import numpy as np, bench_real_pairs as B, peers\n"
        "from seahough import sim\n"
        "shape = (300, 400)\n"                    # diagonal 500 px: 0.5 % = 2.5 px
        "a = np.array([[1.0, 0, 10], [0, 1, 5]])\n"
        "assert abs(B.corner_error(a, a + [[0, 0, 2.4], [0, 0, 0]], shape) - 2.4) < 1e-9\n"
        "m, why = B.reference(a, a + [[0, 0, 2.4], [0, 0, 0]], shape)\n"
        "assert why == 'agree' and abs(m[0, 2] - 11.2) < 1e-12\n"
        "m, why = B.reference(a, a + [[0, 0, 2.6], [0, 0, 0]], shape)\n"
        "assert m is None and why.startswith('disagree by 2.6 px'), why\n"
        "assert B.reference(None, a, shape)[0] is None\n"
        "prev, cur, t = sim.frame_pair(shift=(150.0, -40.0), angle=3.0, scale=1.02, seed=4,\n"
        "                              source='procedural')\n"
        "r = peers.klt_pair(prev, cur)\n"
        "assert B.corner_error(r.matrix, t.motion, prev.shape) < 0.5\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "bench"), str(ROOT / "src"),
                                         env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_colour_benchmark_quick(tmp_path):
    """bench/bench_colour.py --quick: the grey search always runs (the colour one when
    Config has it), every table is there, the counts add up, and grey images are
    searched alike with and without colour."""
    out = tmp_path / "colour.md"
    text = _quick_page(ROOT / "bench" / "bench_colour.py", out)
    assert "Machine:" in text and "Command:" in text and "Date:" in text
    has_colour = "colour (Config(colour=True))" in text.split("Variants that ran:", 1)[1]
    if has_colour:   # (what the defaults do with the painted markers, said on the page)
        assert "every marker pattern here, in every paint, is searched in colour" in text
    head = _rows(_section(text, "## Headline (test part)"))
    assert [r[0] for r in head[1:]] == (["grey", "colour"] if has_colour else ["grey"])
    for r in head[1:]:
        k, n = (int(v) for v in re.search(r"\((\d+)/(\d+)\)", r[1]).groups())
        assert n == 4 and 0 <= k <= n, r            # --quick: one test scene per marker kind
        assert r[-1] in ("met", "**missed**")
        for v in _percentages(r[1:6]):
            assert 0.0 <= v <= 1.0
    for title in ("## By marker kind and water", "## By distance", "## Grey contrast at the border",
                  "## How the best answer went",
                  "## Success by the grey step", "## Tune part"):
        assert len(_rows(_section(text, title))) >= 2, title
    grey = _section(text, "## Grey images")
    if has_colour:
        assert "in 4 of 4 grey images (as required)" in grey, grey
        agree = {r[0]: int(r[1]) for r in _rows(_section(text, "## Which scenes"))[1:]}
        assert sum(agree.values()) == 4


def test_robosub_benchmark_quick(tmp_path):
    """bench/bench_robosub.py --quick: the split named, every task's table with
    seahough and its peers, rates in [0, 1], counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    out = tmp_path / "robosub.md"
    text = _quick_page(ROOT / "bench" / "bench_robosub.py", out, "--cache", tmp_path / "rs.cache")
    assert "Machine:" in text and "Command:" in text and "Date:" in text
    assert "tune part = frames 100-999 and 1401-1469; test part = frames 1000-1400" in text
    targets = _rows(_section(text, "## Targets"))[1:]
    assert len(targets) == 12 and all(r[-1] in ("met", "**missed**") for r in targets)
    peers_of = {"## Buoys": ("HoughCircles", "HoughCircles ALT", "matchTemplate"),
                "## Gate posts": ("HoughLinesP", "matchTemplate"),
                "## The gate": ("GeneralizedHoughGuil", "matchTemplate")}
    for title, names in peers_of.items():
        rows = _rows(_section(text, title))
        head, body = rows[0], [r for r in rows[1:] if len(r) == len(rows[0])]
        col = {h: i for i, h in enumerate(head)}
        methods = [r[0] for r in body]
        assert {"seahough (defaults)", "seahough (tuned)", *names} <= set(methods), methods
        for r in body:
            m = re.match(r"(\d+) % \((\d+)/(\d+)\)", r[col["test recall"]])
            assert m and int(m.group(2)) <= int(m.group(3)), r
            assert abs(int(m.group(1)) - 100 * int(m.group(2)) / int(m.group(3))) <= 0.5, r
            false, photos = re.search(r"\((\d+)/(\d+)\)", r[col["test false / image"]]).groups()
            assert int(r[col["of which on other props"]]) <= int(false), r
            assert photos == "3", r                           # the quick run's 3 test photos
            assert float(r[col["test ms"]]) > 0, r
    # bench/robosub_unmatched.py: a tile for each unmatched buoy of the defaults row
    rows = _rows(_section(text, "## Buoys"))
    false = int(re.search(r"\((\d+)/3\)", [r for r in rows if r[0] == "seahough (defaults)"][0][
        rows[0].index("test false / image")]).group(1))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "robosub_unmatched.py"), "--cache",
                           str(tmp_path / "rs.cache"), "--out", str(tmp_path / "unm")], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    items = json.loads((tmp_path / "unm" / "items.json").read_text())
    assert len(items) == false and len(list((tmp_path / "unm").glob("*.png"))) == -(-false // 16)



def test_nfa_pool_split_quick():
    """bench_nfa --pool-split --quick: the pool photos' false alarms at the
    defaults, each pattern's rate split into those on a labelled prop and the
    rest (the two add up to the whole), over 20 photos."""
    if DATA is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = run_bench_code("import bench_nfa; bench_nfa.main(['--pool-split', '--quick'])")
    rows = {r[0]: r for r in (line.strip().strip("|").split("|") for line in text.splitlines()
                              if line.startswith("| cross |") or line.startswith("| ring |")
                              or line.startswith("| both |"))}
    assert {k.strip() for k in rows} == {"cross", "ring", "both"}, rows
    for name, r in rows.items():
        n, total, on, off = int(r[1]), float(r[2]), float(r[3]), float(r[4])
        assert n == (40 if name.strip() == "both" else 20), r
        assert abs(on + off - total) <= 0.0015 and min(on, off) >= 0.0, r


def test_nfa_calibration_benchmark_quick():
    """bench_nfa --quick --fit completes: the fitted constants, the tables
    before and after by kind of search, the defaults' false alarms; every
    count is a rate per search."""
    text = run_bench_code("import bench_nfa; bench_nfa.main(['--quick', '--fit'])")
    assert re.search(r"Fitted on the tune part's whole-image marker searches: DEPENDENCE [\d.]+, "
                     r"share of tries 10\^-?[\d.]+", text)
    assert "The same with the calibrated model" in text
    assert "False alarms per search at the defaults" in text
    for k in ("marker, whole image", "rope (line 96 x 8)", "L in a window",
              "cross in a window, pose known"):
        assert f"| {k} |" in text, k
    rates = 0
    for line in text.splitlines():
        if line.startswith("| tune |") or line.startswith("| test |"):
            for cell in line.strip().strip("|").split("|")[3:]:
                v = cell.split()[0] if cell.strip() else ""
                if re.fullmatch(r"\d+\.\d{3}", v):
                    assert 0.0 <= float(v) < 20.0, line
                    rates += 1
    assert rates > 50


FIT_CHECK = """
import math, json
import numpy as np
import bench_nfa as b
from seahough.core import nfa as N
from seahough.core.keypoints import find_edge_points
from seahough.core.preprocess import compute_gradients
from seahough.core.refine import Pose
from seahough import sim

# 1. the stored evidence re-read at any DEPENDENCE is what the product computes
# there; a share of the counted poses as tries, never fewer than one
g = sim.seabed((240, 320), seed=3)[:, :, 1].astype(np.float32)
e = find_edge_points(compute_gradients(g), 30.0)
idx = e.index_map()
tol = math.radians(15)
bg = N.background(e, 1.25, tol, None, idx)
rng = np.random.default_rng(4)
t = np.linspace(0, 2 * math.pi, 240, endpoint=False)
vx, vy = 50 * np.cos(t), 30 * np.sin(t)
vang = (t + math.pi / 2) % (2 * math.pi)
gaps = []
for i in range(12):
    pose = Pose.from_params(rng.uniform(60, 260), rng.uniform(40, 200), rng.uniform(0.6, 1.4),
                            rng.uniform(0, 2 * math.pi))
    for tests in (0.5, 3.0, 9.0):
        used = N.DEPENDENCE
        try:
            raw = {}
            for d in b.DEPENDENCES:
                N.DEPENDENCE = d
                raw[str(float(d))] = N.evidence(pose, vx, vy, vang, e, idx, bg, tests, tol=tol,
                                                either=False).log10_nfa
        finally:
            N.DEPENDENCE = used
        row = {"log_tests": tests, "log10_nfa": raw}
        for d in b.DEPENDENCES:
            want = raw[str(float(d))]
            gaps.append(abs(float(b.log_nfa([row], d)[0]) - want))
            if want > N.MIN_LOG10_NFA + 20:
                # 10 ** -2 of the poses: 2 decades fewer tries, floored at one
                got = float(b.log_nfa([row], d, -2.0)[0])
                gaps.append(abs(got - (want - tests + max(tests - 2.0, 0.0))))
print("gap", max(gaps))

# 2. the fit finds the constants that keep the promise on the tune part, and
# ignores the test part and the pool photos (made to prefer other constants)
rng = np.random.default_rng(0)
rows, searches = [], []
def add(group, split, share_ok, n=3000):
    for u in rng.uniform(0.0, 1.0, n):
        # one detection a search, log10 NFA = log10(U) at (8, share_ok): P[NFA <= e] = e
        tail8 = math.log10(u) - (5.0 + share_ok)
        raw = {str(float(d)): 5.0 + tail8 * 8.0 / d for d in b.DEPENDENCES}
        rows.append({"group": group, "split": split, "pattern": "L", "score": 0.6,
                     "log_tests": 5.0, "log10_nfa": raw})
        searches.append((group, split, "L"))
add("seabed photos", "tune", -2.0)
add("seabed photos", "test", -4.0)
add("pool photos (RoboSub)", "test", -1.0)
data = {"rows": rows, "searches": searches}
print("fit", json.dumps(b.fit(data)))
sel = lambda g, s, p: s == "tune"
_, obs = b.counts(data, sel, 8.0, -2.0)
_, old = b.counts(data, sel, 4.0, 0.0)
print("band", all(b.in_band(obs[x], x) for x in b.PROMISED),
      all(b.in_band(old[x], x) for x in b.PROMISED))
"""


def test_nfa_fit_reads_the_evidence_and_keeps_the_promise():
    """bench_nfa re-reads each detection's stored evidence at any DEPENDENCE
    exactly as the product computes it (at the floor of 1e-300 and with no
    observation too), and takes a share of the poses as tries, never fewer
    than one; and its fit, on made-up
    detections that keep the promise only at DEPENDENCE 8 and a share of -2 on
    the tune part, returns those, whatever the test part and the pool prefer."""
    out = run_bench_code(FIT_CHECK)
    gap = float(re.search(r"gap (\S+)", out).group(1))
    assert gap < 1e-9, out
    assert json.loads(re.search(r"fit (.+)", out).group(1)) == [8.0, -2.0], out
    assert "band True False" in out, out


def test_a_page_s_command_names_no_machine_path(tmp_path):
    """A benchmark page's Command line shows an absolute path given on the
    command line (a cache, an output) by its file name: a page once carried
    /tmp/... into the repository."""
    out = run_bench_code(
        "import sys, _common\n"
        f"sys.argv = ['bench/bench_robosub.py', '--write', '--cache', {str(tmp_path / 'rs.cache')!r},"
        f" '--out={tmp_path / 'page.md'}', 'bench/peers.py']\n"
        "print(_common.command())", timeout=60)
    assert out.strip() == ("python bench/bench_robosub.py --write --cache rs.cache --out=page.md "
                           "bench/peers.py")


def test_speckle_benchmark_quick(tmp_path):
    """bench/bench_speckle.py --quick: every search, counts that fall with e,
    and streaked speckle's chance lines, which break the bound (docs/speckle.md:
    the page says so; this fails when they stop doing it, and the page must change)."""
    text = _quick_page(ROOT / "bench" / "bench_speckle.py", tmp_path / "speckle.md")
    assert "Machine:" in text and "## Reading" in text
    rows = _rows(text)[1:]
    assert [r[1] for r in rows] == ["line:100,6", "rect:150,8", "rect:60,40", "curve:8"]
    for r in rows:       # (an answer an image at most: 5 kept, 2 images)
        assert all(0.0 <= float(c.split()[0]) <= 5.0 for c in r[3:7]), r
    line = rows[0]
    assert "(over)" in line[4] and float(line[7]) < 1e-2, line   # chance lines under 0.1


def test_counting_benchmark_quick(tmp_path):
    """bench/bench_counting.py --quick: both parts, both ways, counts that add up."""
    if shared_data_dir() is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    text = _quick_page(ROOT / "bench" / "bench_counting.py", tmp_path / "counting.md")
    assert "Machine:" in text and "## tune part" in text and "## test part" in text
    for part in ("tune", "test"):
        rows = _rows(_section(text, f"## {part} part"))[1:]
        totals = [r for r in rows if r[1] == "all"]
        assert len(totals) == 2, rows
        for r in totals:    # one photo, 20 rings and 20 squares
            found = re.match(r"\d+ % \((\d+)/(\d+)\)", r[2])
            assert int(found.group(2)) == 40 and int(found.group(1)) <= 40, r
