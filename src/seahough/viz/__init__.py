"""Pictures of what seahough found, and of how it got there.

They draw what they are given and never run the pipeline. Every function
draws on a fresh :class:`matplotlib.figure.Figure` made without
:mod:`matplotlib.pyplot` (so no GUI backend is needed and no global figure
state is left behind; PNGs are rendered by Agg), saves it as a PNG when
given ``path`` and returns the figure. The PNG sizes are fixed (see each
function) so that pictures line up in reports and tests. A photo larger
than it is drawn is shrunk to its drawn size first (an area average), so a
4K photo costs about what a 640x480 one does; nothing is shared between
calls, so pictures can be drawn from several threads (matplotlib renders
one figure at a time: threads are safe, not faster).

- :mod:`.detections`: :func:`plot_detections` (the image, what was found)
  and :func:`detections_size`;
- :mod:`.curves`: :func:`plot_curves` (curved ropes found by
  :func:`seahough.find_curves`);
- :mod:`.accumulator`: :func:`plot_accumulator` (the accumulator's planes)
  and :func:`scale_angle_marker`;
- :mod:`.edges`: :func:`plot_edges` (edge points, key points, segments);
- :mod:`.trajectory`: :func:`plot_trajectory` (a dead-reckoned path) and
  :func:`save_mosaic`.

Examples
--------
>>> import numpy as np
>>> from seahough import viz
>>> fig = viz.plot_detections(np.zeros((48, 64), np.uint8), [])
>>> tuple(int(v) for v in fig.get_size_inches() * fig.dpi)
(1000, 775)
"""

from ._figure import DPI
from .accumulator import plot_accumulator, scale_angle_marker
from .curves import plot_curves
from .detections import detections_size, plot_detections
from .edges import plot_edges
from .trajectory import plot_trajectory, save_mosaic

__all__ = ["plot_detections", "plot_curves", "plot_accumulator", "plot_edges", "plot_trajectory",
           "save_mosaic", "detections_size", "scale_angle_marker", "DPI"]
