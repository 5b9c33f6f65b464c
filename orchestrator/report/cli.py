"""``suscosim report RUN_SWEEP_OR_DUTY_DIR [--out FILE.html] [--open]``: the command."""

from __future__ import annotations

import argparse
import sys
from functools import partial
from pathlib import Path

from cosim.run_folder import replaced

from ..cli_util import fail, parse_args
from .duty_page import render_duty
from .run_page import render_run
from .stream import BadInput, is_run_dir
from .sweep_page import render_sweep

_fail = partial(fail, "suscosim report")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim report",
                                 description="a self-contained HTML report of a run, a sweep "
                                             "or a duty cycle")
    ap.add_argument("dir", metavar="RUN_SWEEP_OR_DUTY_DIR",
                    help="a run folder, a sweep folder or a duty folder (suscosim duty)")
    ap.add_argument("--out", metavar="FILE.html", help="output file (default DIR/report.html)")
    ap.add_argument("--open", action="store_true", help="open the page in a web browser")
    ap.add_argument("--runs-dir", metavar="DIR",
                    help="a sweep's shared runs folder (suscosim sweep --runs-dir): its run "
                         "folders are read too (by default only those inside the sweep folder)")
    return ap


def render(d: Path, runs_dir: Path | None = None) -> tuple[str, str]:
    """(kind, HTML) of a run, sweep or duty folder; raises BadInput if it is none."""
    if not d.is_dir():
        raise BadInput(f"{d}: no such folder")
    if (d / "sweep.json").is_file():
        return "sweep", render_sweep(d, runs_dir)
    if (d / "duty.json").is_file():
        return "duty", render_duty(d)
    if is_run_dir(d):
        return "run", render_run(d)
    raise BadInput(f"{d}: neither a run folder (scenario.json, summary.json, table.*, "
                   "journal.msgpack) nor a sweep folder (sweep.json) nor a duty folder (duty.json)")


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    d = Path(args.dir)
    try:
        kind, text = render(d, Path(args.runs_dir) if args.runs_dir else None)
    except BadInput as exc:
        return _fail(str(exc))
    out = Path(args.out) if args.out else d / "report.html"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        with replaced(out) as fh:
            fh.write(text)
    except OSError as exc:
        return _fail(f"{out}: cannot write ({exc.strerror or exc})")
    print(f"suscosim report: {kind} {d} -> {out} ({len(text) / 1e6:.2f} MB)")
    if args.open:
        import webbrowser

        if not webbrowser.open(out.resolve().as_uri()):
            print(f"suscosim report: no browser found; open {out.resolve().as_uri()}",
                  file=sys.stderr)
    return 0
