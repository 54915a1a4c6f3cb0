"""The recognition core: image -> features -> votes -> poses -> detections.

No file I/O, plotting or odometry here: numpy arrays in, dataclasses out.
One module a stage, in the order the data flows:

``preprocess`` (working scale, Scharr gradients) -> ``keypoints`` (edge points,
the most contrasted key points) -> ``segments`` (short edge segments) ->
``features`` (all three in one call) ; ``pattern`` (the prepared model) ->
``accumulator`` (voting, its planes) -> ``candidates`` (peaks, refined
candidate poses) -> ``refine`` (sub-bin ICP and score) -> ``ranking``
(full-resolution finish, runner-up, confidence) -> ``detector`` (the search
that runs them). The Numba hot loops live in ``kernels``.
"""
