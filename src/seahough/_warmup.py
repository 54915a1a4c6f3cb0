"""Compile every Numba kernel once, into the cache later processes read.

The kernels are compiled on their first call with the argument types of
that call, and cached by Numba (``cache=True``, see
:mod:`seahough.core.kernels._cache`). :func:`warm_up` runs small real tasks
that call every kernel with every signature the library uses (a shape
pattern, a line, an image pattern, the search of a motion with the full
ranges and with known scale and angle, a dead-reckoning run), so that a
later ``seahough detect`` or ``seahough odometry`` compiles nothing.

``pip install .`` runs it while the wheel is built (``setup.py``): the cache
files land beside the kernels in the build tree and are installed with
them. Numba reuses them when the kernels' source files are byte-identical,
the Numba version is the same and the CPU the same (the case when pip
builds the wheel on the machine it installs on); otherwise it compiles on
first use, as without them.

``python -m seahough._warmup`` warms the cache where Numba looks now (e.g.
after an editable install), and prints what it compiled.

Here, not in ``core``: it runs the dead reckoning too (``motion``), a layer
above the core.
"""

from __future__ import annotations

import importlib
import sys
import tempfile

import numpy as np

#: The modules that define kernels.
KERNEL_MODULES = ("seahough.core.kernels._common", "seahough.core.kernels.edges",
                  "seahough.core.kernels.voting", "seahough.core.kernels.matching",
                  "seahough.core.kernels.evidence")


def kernels() -> dict:
    """Every Numba function of the kernel modules, by ``module.name``.

    Returns
    -------
    dict
        ``{"edges.edge_points": dispatcher, ...}``.

    Examples
    --------
    >>> "edges.edge_points" in kernels()
    True
    """
    from numba.core.registry import CPUDispatcher

    found = {}
    for name in KERNEL_MODULES:
        module = importlib.import_module(name)
        for attr, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.__module__ == name:
                found[f"{name.rpartition('.')[2]}.{attr}"] = value
    return found


def cache_stats() -> dict[str, tuple[int, int]]:
    """How many signatures each kernel loaded from the cache, and compiled,
    in this process so far.

    Returns
    -------
    dict
        ``{"edges.edge_points": (loaded, compiled), ...}``; a kernel not yet
        called has ``(0, 0)``. A kernel called only from other kernels
        (``matching._solve``) is compiled with its callers and never
        counted.
    """
    return {name: (sum(k.stats.cache_hits.values()), sum(k.stats.cache_misses.values()))
            for name, k in kernels().items()}


def called_by_kernels() -> set[str]:
    """The kernels called only from other kernels (compiled with them, or
    inlined into them): never compiled on their own.

    >>> sorted(called_by_kernels())[:2]
    ['_common._placed', '_common._same_direction']
    """
    import inspect

    names = set(kernels())
    sources = {n: inspect.getsource(k.py_func) for n, k in kernels().items()}
    return {n for n in names
            if any(f"{n.partition('.')[2]}(" in src for m, src in sources.items() if m != n)}


def _scene(rng: np.random.Generator, shape=(480, 640)) -> np.ndarray:
    """A seabed-like texture (uint8) with a bright 90x50 rectangle, a dark
    8 px line and a bright disc on it."""
    import cv2

    noise = rng.random(shape).astype(np.float32) * 90 + 60
    img = cv2.GaussianBlur(noise, (0, 0), 2.5)
    h, w = shape
    cv2.rectangle(img, (w // 4 - 45, h // 3 - 25), (w // 4 + 44, h // 3 + 24), 230, -1)
    cv2.line(img, (w // 2, h - 40), (w - 40, h // 2), 15, 8)
    cv2.circle(img, (3 * w // 4, h // 4), 22, 220, -1)
    return np.clip(img, 0, 255).astype(np.uint8)


def warm_up() -> dict[str, tuple[int, int]]:
    """Call every kernel with the signatures the library uses.

    A few seconds with a warm cache, about a minute with an empty one (every
    kernel compiled once).

    Returns
    -------
    dict
        :func:`cache_stats` after the tasks: every kernel of the library
        loaded or compiled.
    """
    from . import Detector, Pattern, estimate_motion, run_odometry, sim

    rng = np.random.default_rng(17)
    scene = _scene(rng)
    colour = np.dstack([scene, scene, scene])
    # shapes as `seahough detect rect:W,H` etc. builds them, on grey and BGR
    for pattern in (Pattern.rectangle(90, 50), Pattern.line(200, 8), Pattern.circle(22),
                    Pattern.circle(22, inner_radius=10),
                    Pattern.polygon([(0, 0), (60, 0), (30, 40)])):
        Detector(pattern).detect(scene)
    Detector(Pattern.rectangle(90, 50)).detect(colour)
    # an image pattern (a crop of the scene), as `seahough detect marker.png`
    crop = scene[100:220, 80:240].copy()
    Detector(Pattern.from_image(crop)).detect(scene)
    # motion: full ranges and the 2-D case (known scale and heading)
    # (frames over Config.target_size are searched below full resolution, and
    # their verify points snapped to the full-resolution edges)
    frames, _ = sim.sequence(n_frames=4, frame_size=(300, 400), seed=3, source="procedural")
    estimate_motion(frames[0], frames[1])
    estimate_motion(frames[0], frames[1], scale_range=(1, 1), angle_range=(0, 0))
    # the homography refit of a pair whose vote is not distinct (a tiled floor)
    import math

    from .core.keypoints import find_edge_points
    from .core.preprocess import compute_gradients
    from .motion.parallax import strongest
    from .motion.perspective import homography_icp
    edges = find_edge_points(compute_gradients(scene.astype(np.float32)), 20)
    homography_icp(np.eye(3), strongest(edges), edges, edges.index_map(), math.radians(20))
    # full-resolution edges in a narrow band (the finish of a large frame)
    from .core.keypoints import edge_points_near_image
    # (of a frame's own levels too, which a pattern holds read-only: a type of its own)
    levels = scene.astype(np.float32)
    for writeable in (True, False):
        levels.flags.writeable = writeable
        edge_points_near_image(levels, [60.0, 200.0], [50.0, 120.0], 2.0, 20)
    # a short dead-reckoning run (keyframes, priors, the fallbacks, the mosaic)
    with tempfile.TemporaryDirectory() as out:
        try:
            run_odometry(frames, out, progress=False, metres_per_pixel=0.004)
        except ModuleNotFoundError as e:   # the trajectory picture, after every kernel ran
            if not (e.name or "").startswith("matplotlib"):
                raise
    return cache_stats()


def main(argv: list[str] | None = None) -> int:
    """``python -m seahough._warmup [--quiet]``: warm up, say what was
    compiled; exit status 1 when some kernel was never called."""
    import time

    argv = sys.argv[1:] if argv is None else argv
    t0 = time.perf_counter()
    stats = warm_up()
    missed = [name for name, (hit, miss) in stats.items() if hit + miss == 0
              and name not in called_by_kernels()]
    if "--quiet" not in argv:
        compiled = sum(miss for _, miss in stats.values())
        loaded = sum(hit for hit, _ in stats.values())
        print(f"seahough kernels: {compiled} signatures compiled, {loaded} loaded from the "
              f"cache, in {time.perf_counter() - t0:.1f} s")
    if missed:
        print(f"seahough kernels never called by the warm-up: {', '.join(missed)}",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
