"""What the next frame of a dead-reckoning run needs: the keyframe, the last
measured frame, the motion per frame; rebuilt from the CSV rows alone, so a
resumed run goes on exactly as an uninterrupted one."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config import Config, OdometryTuning
from ..core.pattern import Pattern
from ..errors import SeahoughError
from ..geometry import compose, invert_matrix, matrix_power, overlap


@dataclass
class State:
    """Everything the next frame needs, rebuilt from the rows alone (resume)."""

    shape: tuple | None = None          # (h, w) of the first readable frame
    box: tuple | None = None            # its content box (see motion.framing.content_box)
    key: int | None = None              # keyframe index and its cumulative matrix
    key_cum: np.ndarray | None = None
    key_rate: float | None = None       # score / overlap of the first frame measured on it
    prev: int | None = None             # last readable frame with a pose
    prev_cum: np.ndarray | None = None
    meas: int | None = None             # last measured frame (for the prediction)
    meas_cum: np.ndarray | None = None
    vel: np.ndarray | None = None       # motion per frame (frame-to-frame matrix)
    last_pose: int | None = None        # last row with a pose, and whether measured
    last_pose_cum: np.ndarray | None = None
    last_pose_measured: bool = False
    heading: float = 0.0                # unwrapped heading of the last pose
    rates: list = field(default_factory=list)   # score/overlap of the last measurements


def advance(st: State, row: dict, tuning: OdometryTuning) -> None:
    """Update the state with one finished row (the same in a run and a resume)."""
    status = row["status"]
    i = row["index"]
    if status == "unreadable":
        return
    cum = row["_cum"]
    if status == "origin":
        st.key = st.prev = st.meas = st.last_pose = i
        st.key_cum = st.prev_cum = st.meas_cum = st.last_pose_cum = cum
        st.key_rate = None
        st.rates = []
        st.vel = None
        st.last_pose_measured = True
        return
    if status == "assumed":
        st.rates = []   # after a failure, no reference quality (a new scene is allowed)
        st.prev, st.prev_cum = i, cum
        st.last_pose, st.last_pose_cum, st.last_pose_measured = i, cum, False
        return
    # measured
    ref = row["ref"]
    rcum = ref_cum(st, ref)
    if st.last_pose_measured and st.last_pose is not None:
        st.vel = matrix_power(compose(cum, invert_matrix(st.last_pose_cum)), 1.0 / (i - st.last_pose))
    else:
        st.vel = matrix_power(compose(cum, invert_matrix(rcum)), 1.0 / max(i - ref, 1))
    if ref != st.key:
        st.key, st.key_cum, st.key_rate = ref, rcum, None
    rate = row["score"] / max(row["overlap"], 1e-6)
    st.rates = (st.rates + [rate])[-5:]
    if st.key_rate is None:
        st.key_rate = rate
    h, w = st.shape
    nxt = compose(st.vel, cum)
    faded = rate < tuning.rekey_match * st.key_rate
    if faded or overlap(compose(nxt, invert_matrix(st.key_cum)), w, h) < tuning.rekey_overlap:
        st.key, st.key_cum, st.key_rate = i, cum, None
    st.prev, st.prev_cum = i, cum
    st.meas, st.meas_cum = i, cum
    st.last_pose, st.last_pose_cum, st.last_pose_measured = i, cum, True


def ref_cum(st: State, ref: int) -> np.ndarray:
    """The cumulative matrix of a reference frame (the keyframe, the last
    measured frame or the previous frame)."""
    if ref == st.key:
        return st.key_cum
    return st.meas_cum if ref == st.meas else st.prev_cum



@dataclass
class Frame:
    """A readable frame kept in memory: its grey image and, once needed, its
    pattern (built once, reused while it is the keyframe)."""

    index: int
    gray: np.ndarray
    pattern: Pattern | None = None
    failed: bool = False

    def get_pattern(self, config: Config):
        if self.pattern is None and not self.failed:
            try:
                self.pattern = Pattern.from_frame(self.gray, config=config)
            except SeahoughError:
                self.failed = True
        return self.pattern
