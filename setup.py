"""Build hook: the wheel carries the Numba kernels compiled.

Everything about the package is in ``pyproject.toml``; this file only adds
one step to ``build_py``: after the sources are copied to the build tree,
``seahough._warmup`` runs from there, in a child process, and Numba caches
every kernel beside its source (``seahough/core/kernels/__pycache__``), so
the cache files go into the wheel. ``pip install .`` builds the wheel on the
machine it installs on: Numba reuses them as long as the kernels' sources,
the Numba version and the CPU are the same, and the first ``seahough
detect`` compiles nothing (else it compiles on first use, as without them).

Skipped for editable installs (the kernels are compiled on first use, into
the source tree's ``__pycache__``) and when ``SEAHOUGH_NO_WARMUP`` is set. A
warm-up that fails never fails the build: one warning line, and the kernels
are compiled on first use.
"""

from __future__ import annotations

import glob
import os
import subprocess
import sys
import tempfile

from setuptools import setup
from setuptools.command.build_py import build_py

#: The child process: imports seahough from the build tree (and nothing
#: else: checked), warms every kernel up.
_CHILD = """
import sys
sys.path.insert(0, sys.argv[1])
import seahough
if not seahough.__file__.startswith(sys.argv[1]):
    sys.exit("seahough imported from " + seahough.__file__ + ", not from the build tree")
from seahough._warmup import main
sys.exit(main(["--quiet"]))
"""


class BuildPyWithKernels(build_py):
    """``build_py``, then the kernels compiled into the build tree."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False) or os.environ.get("SEAHOUGH_NO_WARMUP"):
            return
        self.warm_up()

    def warm_up(self) -> None:
        build_lib = os.path.abspath(self.build_lib)
        cache = os.path.join(build_lib, "seahough", "core", "kernels", "__pycache__")
        # the files of an earlier build (other sources, other line numbers)
        for path in glob.glob(os.path.join(cache, "*.nb[ic]")):
            os.remove(path)
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg")
        env.pop("NUMBA_CACHE_DIR", None)        # Numba's cache: beside the kernels
        env.pop("NUMBA_DISABLE_JIT", None)
        why = None
        try:
            with tempfile.TemporaryDirectory() as cwd:
                proc = subprocess.run([sys.executable, "-c", _CHILD, build_lib], env=env,
                                      cwd=cwd, capture_output=True, text=True, timeout=1800)
            if proc.returncode != 0:
                lines = (proc.stderr or proc.stdout).strip().splitlines()
                why = lines[-1] if lines else f"exit status {proc.returncode}"
        except (OSError, subprocess.SubprocessError) as e:
            why = str(e)
        if why is None and not glob.glob(os.path.join(cache, "*.nbi")):
            why = "no cache files were written"
        if why is not None:   # (what was cached is kept: each file is valid on its own)
            self.warn(f"seahough: the Numba kernels were not compiled into the wheel "
                      f"({why}); they will be compiled on first use")
        else:
            self.announce(f"seahough: Numba kernels compiled into {cache}", level=2)


setup(cmdclass={"build_py": BuildPyWithKernels})
