"""The underwater scene simulator: synthetic photos with exact ground truth.

Tests, benchmarks and the demo use it to make photos in which the answer is
known exactly: a docking marker pasted at a known pose
(:func:`marker_scene`), a patch of a photo seen again rotated and rescaled
(:func:`fragment_scene`), two camera frames related by a known similarity
motion (:func:`frame_pair`), a rope crossing the frame (:func:`rope_scene`)
or lying in a curve (:func:`curved_rope_scene`),
a whole camera path (:func:`sequence`), survey frames over a seabed in
relief that differ by parallax, or seen by a camera that looks ahead
(:func:`relief_sequence`; a pool floor: :func:`tiled_floor`; a fish-farm net: :func:`net`), a marker painted in a colour whose
red fades with distance in the water (:func:`colour_marker_scene`).

Scenes are built from a background (:mod:`.backgrounds`: a real seabed photo
from the shared data folder when it is there, else a procedural seabed),
then degraded by water (:mod:`.water`, which describes the image-formation
model). Markers, pasting and :class:`Truth` live in :mod:`.markers`;
coloured markers and the contrast left at their border in :mod:`.colour`.

Geometry conventions are those of :mod:`seahough.geometry` (equation 1):
a 2x3 matrix maps pattern-image (or previous-frame) pixel coordinates to
scene (current-frame) pixel coordinates, exactly as ``cv2.warpAffine(src, M,
(w, h))`` takes it; pixel ``(0, 0)`` is the centre of the top-left pixel; x
right, y down; angles in degrees, positive = counter-clockwise as displayed.
Everything is deterministic given ``seed`` (``numpy.random.default_rng``).

Examples
--------
>>> from seahough import sim
>>> scene, pattern, truth = sim.marker_scene(shape=(120, 160), seed=1, size=40,
...                                          source="procedural")
>>> scene.shape, pattern.shape, truth.corners.shape
((120, 160, 3), (48, 48), (4, 2))
"""

from .backgrounds import background, net, seabed, tiled_floor
from .colour import PAINTS, BorderContrast, border_contrast, colour_marker_scene, matched_paint
from .files import write_simulation
from .markers import MARKERS, Truth, marker, paste_pattern, random_pose
from .scenes import fragment_scene, frame_pair, marker_scene, negative_scene, rope_scene
from .scenes import CurveTruth, curved_rope_scene
from .relief import ReliefTruth, relief_sequence
from .sequences import sequence
from .water import PRESETS, Water, apply_water

__all__ = [
    "MARKERS",
    "PRESETS",
    "Water",
    "Truth",
    "apply_water",
    "seabed",
    "tiled_floor",
    "net",
    "background",
    "marker",
    "random_pose",
    "paste_pattern",
    "marker_scene",
    "negative_scene",
    "fragment_scene",
    "frame_pair",
    "rope_scene",
    "curved_rope_scene",
    "CurveTruth",
    "sequence",
    "relief_sequence",
    "ReliefTruth",
    "write_simulation",
    "PAINTS",
    "BorderContrast",
    "colour_marker_scene",
    "border_contrast",
    "matched_paint",
]
