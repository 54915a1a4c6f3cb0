"""``seahough demo``: the tour of :func:`seahough.demo.run_demo`, printed."""

from __future__ import annotations

import time

import click

from ._common import PROG, _stderr_is_terminal, _table


@click.command(short_help="A tour that needs no files: simulate, detect, dead-reckon.")
@click.option("--out", "-o", type=click.Path(file_okay=False), default="seahough-demo",
              show_default=True, help="Folder for the scenes and pictures.")
@click.option("--quiet", "-q", is_flag=True, help="No progress or file list; the table only.")
def demo(out, quiet):
    """A tour with no files and no network: simulate, detect, dead-reckon.

    Makes an underwater scene with a board marker, one with a rope and a
    short seabed sequence; finds the marker (from its clean image) and the
    rope (a line pattern), dead-reckons the sequence, writes every picture
    to --out and prints what was found against the truth.
    """
    from ..demo import run_demo

    t_start = time.perf_counter()
    note = None if quiet else (lambda stage: click.echo(f"demo: {stage} ...", err=True))
    result = run_demo(out, progress=not quiet and _stderr_is_terminal(), note=note)
    click.echo(f"{PROG} demo: found vs truth (simulated scenes, moderate water)")
    for line in _table(result.rows, ("what", "found", "truth", "error"), left=True):
        click.echo(line)
    if not quiet:
        click.echo(f"pictures in {result.out}: " + ", ".join(result.files))
    click.echo(f"done in {time.perf_counter() - t_start:.1f} s")
    return 0 if result.ok else 1
