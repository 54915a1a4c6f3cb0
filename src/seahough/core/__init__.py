"""The recognition core: image -> features -> votes -> poses -> detections.

Numpy arrays in (or image paths, read through :mod:`seahough.io`), dataclasses
out; no plotting, odometry or command line here.
One module a stage, in the order the data flows:

``preprocess`` (working scale, Scharr gradients) -> ``keypoints`` (edge points,
the most contrasted key points) -> ``segments`` (short edge segments) ->
``features`` (all three in one call) ; ``pattern`` (the prepared model) ->
``accumulator`` (voting, its planes) -> ``candidates`` (peaks, refined
candidate poses) -> ``refine`` (sub-bin ICP and score) -> ``ranking``
(full-resolution finish, runner-up, confidence) -> ``detector`` (the search
that runs them). The Numba hot loops live in ``kernels``.
"""
