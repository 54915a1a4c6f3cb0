"""Memory of one estimate_motion call on a large frame pair.

Two frames cut from a real seabed photo (../shared/data/sequences/
dtu_seabed_pair/scene1.png, enlarged by cv2.resize so that the frames fit),
the second moved by (300, 200) px, as 8-bit BGR arrays in memory. Each size
is measured in a fresh process: after the frames are made and the kernels
compiled (a first call on the frames shrunk 8 times), the peak resident
memory (VmHWM) of one ``estimate_motion`` call is read against the resident
memory just before it: what the call adds over the two images the caller
holds. Issue 13's target: at most 200 MiB for a 4000x3000 pair.

    python bench/bench_pair_memory.py              # the table (~20 s)
    python bench/bench_pair_memory.py --src DIR    # another checkout's src/ (before/after)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402

SIZES = ((1360, 1024), (1920, 1080), (4000, 3000))

_CHILD = r"""
import json, sys
import cv2, numpy as np
w, h = int(sys.argv[1]), int(sys.argv[2])
import seahough
from seahough._data import shared_data_dir

def status(key):
    for line in open('/proc/self/status'):
        if line.startswith(key):
            return int(line.split()[1]) / 1024.0

photo = cv2.imread(str(shared_data_dir() / 'sequences' / 'dtu_seabed_pair' / 'scene1.png'))
big = cv2.resize(photo, (w + 400, h + 300))
a = np.ascontiguousarray(big[:h, :w])
b = np.ascontiguousarray(big[200:200 + h, 300:300 + w])
del big, photo
seahough.estimate_motion(a[::8, ::8], b[::8, ::8])      # (the kernels compiled)
before = status('VmRSS')
m = seahough.estimate_motion(a, b)
print(json.dumps(dict(added=status('VmHWM') - before, before=before,
                      images=(a.nbytes + b.nbytes) / 2 ** 20,
                      answer=None if m is None else [round(m.dx, 1), round(m.dy, 1)])))
"""


def measure(w: int, h: int, src: str | None) -> dict:
    env = dict(os.environ)
    if src:
        env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, "-c", _CHILD, str(w), str(h)], env=env,
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        raise SystemExit(proc.stderr[-2000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", help="import seahough from this src/ folder (another checkout)")
    args = ap.parse_args(argv)
    lines = ["## One frame pair: estimate_motion's peak memory over the two images", "",
             f"Command: `{command()}`  ", f"Machine: {machine()}", "",
             "| frames | the two BGR images | added at the peak of the call | answer (dx, dy) |",
             "|---|---:|---:|---|"]
    for w, h in SIZES:
        r = measure(w, h, args.src)
        lines.append(f"| {w}x{h} | {r['images']:.0f} MiB | {r['added']:.0f} MiB | "
                     f"{r['answer']} |")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
