"""The package's layout stays readable: small modules, each listed in the README."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "src" / "seahough"
MAX_LINES = 600


def _modules():
    return sorted(p.relative_to(PKG.parent).as_posix() for p in PKG.rglob("*.py")
                  if "__pycache__" not in p.parts)


def test_no_module_over_600_lines():
    long = {m: n for m in _modules()
            if (n := len((PKG.parent / m).read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_readme_layout_table_lists_every_module():
    readme = (ROOT / "README.md").read_text()
    table = readme.split("## Layout", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"`(seahough/[\w/]+\.py)`", table))
    modules = {m for m in _modules() if not m.endswith("__main__.py")}
    assert modules - listed == set(), "modules missing from the README's layout table"
    assert listed - modules == set(), "the README's layout table names modules that do not exist"


def test_core_imports_nothing_of_the_layers_above_it():
    # the recognition core takes arrays and returns dataclasses: it never
    # imports the pictures, the CLI, the simulator, the dead reckoning or the surveys
    for path in (PKG / "core").rglob("*.py"):
        text = path.read_text()
        bad = re.findall(r"^\s*(?:from|import) (?:\.\.(?:viz|cli|sim|motion|survey)\b"
                         r"|matplotlib|click|tqdm|dask|distributed|pyarrow)", text, flags=re.M)
        assert not bad, f"{path.relative_to(PKG)} imports {bad}"


def test_pictures_never_run_the_pipeline():
    for path in (PKG / "viz").rglob("*.py"):
        # (docstring examples run a search to have something to draw: not the module)
        text = "\n".join(line for line in path.read_text().splitlines()
                         if not line.lstrip().startswith((">>>", "...")))
        bad = re.findall(r"\b(extract_features|Detector|estimate_motion|run_odometry|accumulate)\(",
                         text)
        assert not bad, f"{path.relative_to(PKG)} runs {bad}"


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    block = readme.split("Set up and run the tests", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    setup, _, command = block.strip().rpartition(" && ")
    ci = (ROOT / ".ci" / "run").read_text()
    assert command.startswith("python -m pytest") and command in ci.splitlines()
    install = setup.rpartition(" && ")[2]          # e.g. pip install -e ".[test]"
    assert install.replace("pip install", "python -m pip install --quiet") in ci


def test_every_core_module_is_reachable_as_an_attribute():
    """``seahough.core.nfa`` and the like load on first access (a
    contributor found nfa, parts and symmetry missing: AttributeError unless
    something had imported them first)."""
    import subprocess
    import sys

    names = sorted(p.stem for p in (ROOT / "src" / "seahough" / "core").glob("*.py")
                   if p.stem != "__init__") + ["kernels"]
    code = ("import seahough.core as c; "
            f"print([n for n in {names!r} if getattr(c, n).__name__ != 'seahough.core.' + n])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "[]", out.stdout + out.stderr
