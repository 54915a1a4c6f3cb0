"""``seahough simulate``: synthetic scenes with exact ground truth (see
:func:`seahough.sim.files.write_simulation`)."""

from __future__ import annotations

import logging
from pathlib import Path

import click

from ..sim import MARKERS
from ..sim.files import KINDS, PATHS, WATERS, write_simulation
from ._common import PROG


@click.command(no_args_is_help=True)
@click.argument("kind", type=click.Choice(KINDS), metavar="KIND")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False),
              help="Folder for the PNG scenes and truth.json.")
@click.option("--n", "-n", "count", type=click.IntRange(min=1, max=10000), default=None,
              help="Number of scenes (default 1), or of frames for a sequence (default 10).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True)
@click.option("--water", type=click.Choice(WATERS), default="moderate", show_default=True,
              help="Water conditions (none: no degradation).")
@click.option("--marker", "marker_name", type=click.Choice(MARKERS),
              default="board", show_default=True, help="Marker drawn in marker scenes.")
@click.option("--size", nargs=2, type=click.IntRange(min=16, max=8192), default=None,
              metavar="W H", help="Scene size in px (default 640 480; sequence 320 240).")
@click.option("--path", "path_kind", type=click.Choice(PATHS), default="line",
              show_default=True, help="Camera path of a sequence.")
@click.option("--procedural", is_flag=True,
              help="Procedural seabed backgrounds only (default: real photos when the shared "
              "data folder is present).")
@click.option("--photo", type=click.Path(dir_okay=False), default=None, metavar="FILE",
              help="A seabed photo of yours to render the scenes from (a larger photo holds "
              "a long sequence's views without magnifying them). A photo taken underwater "
              "has its water already: --water none keeps it as it is.")
@click.option("--quiet", "-q", is_flag=True,
              help="No progress bar, hint or note; only the line saying what was written.")
def simulate(kind, out, count, seed, water, marker_name, size, path_kind, procedural, photo,
             quiet):
    """Write synthetic underwater scenes with exact ground truth.

    \b
    KIND: marker    a seabed photo with a docking marker (plus pattern.png)
          rope      a rope across the frame
          pair      two overlapping camera frames (a known motion)
          sequence  frames along a camera path (for `seahough odometry`)
          negative  seabed photos with no marker
    truth.json holds the poses (matrix, x, y, scale, angle), rope angle and
    offset, or motions (pair: motion, angle; sequence, per frame:
    matrix_from_first M, centre_in_first, motion_from_previous; odometry.csv's
    x, y are centre_in_first, its heading is atan2(M[1][0], M[0][0]) in
    degrees: the camera's turn, the opposite sign of the content's rotation;
    docs/odometry.md), so you can test your own settings. A progress bar
    is shown on stderr for several scenes when stderr is a terminal.
    """
    ctx = click.get_current_context()
    for name, opt, kinds in (("path_kind", "--path", ("sequence",)),
                             ("marker_name", "--marker", ("marker",))):
        given = ctx.get_parameter_source(name) == click.core.ParameterSource.COMMANDLINE
        if given and kind not in kinds:
            raise click.UsageError(f"{opt} applies to {' and '.join(kinds)} scenes, not {kind}")
    o = Path(out)   # (created by write_simulation once its settings are checked)
    # a scene that cannot be written raises a SeahoughError: main() prints its one line
    notes = logging.getLogger("seahough.sim")
    level = notes.level
    if quiet:   # (the note that a photo is magnified: a warning, not an error)
        notes.setLevel(logging.ERROR)
    try:
        truth = write_simulation(kind, o, n=count, seed=seed, water=water,
                                 marker_name=marker_name, size=tuple(size) if size else None,
                                 path=path_kind, procedural=procedural, photo=photo,
                                 progress=not quiet)
    finally:
        notes.setLevel(level)
    n_files = len(truth.get("frames", truth.get("scenes", [])))
    what = "frames" if kind == "sequence" else ("pairs" if kind == "pair" else "scenes")
    what = what[:-1] if n_files == 1 else what
    click.echo(f"wrote {n_files} {what} and {o / 'truth.json'}")
    if quiet:
        return 0
    if kind == "marker":
        click.echo(f"try: {PROG} detect {o / 'pattern.png'} {o / 'marker_*.png'}")
    elif kind == "rope":
        click.echo(f"try: {PROG} detect line:200,8 {o / 'rope_*.png'} --angle-range 0 180")
    elif kind == "negative":
        click.echo(f"try: {PROG} detect rect:60,60 {o / 'negative_*.png'}  (expect exit status 1)")
    elif kind == "sequence":
        click.echo(f"try: {PROG} odometry {o} --out {o.parent / (o.name + '_odometry')}")
    return 0
