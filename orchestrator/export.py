"""``suscosim export JOURNAL|RUN_DIR``: a run's table rebuilt from its journal (streamed twice:
:mod:`cosim.table_writer`), or written in another format, in bounded memory
(docs/data_formats.md). Exit 2 naming the journal: not one, no complete step, records lost, or
the folder's table is larger (the last two: written as ``table.recovered.*``). ``export RUN_DIR
--format ...``: ``RUN_DIR/export/table.<ext>``, named by the ``--channels`` selection.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any

from cosim.errors import InputFileError

from .cli_util import parse_args

PROG = "suscosim export"


def build_parser() -> argparse.ArgumentParser:
    e = argparse.ArgumentParser(prog=PROG, description="a run's table from its journal, or "
                                "as MDF 4 / RPC III / CSV / Parquet")
    e.add_argument("journal", metavar="RUN_DIR|JOURNAL")
    e.add_argument("--out", help="output folder (default: the journal's folder; for RUN_DIR "
                                 "--format: RUN_DIR/export)")
    e.add_argument("--format", choices=("mdf4", "rpc3", "csv", "parquet"),
                   help="write the run's table in this format (names and SI units)")
    e.add_argument("--channels", nargs="+", metavar="PATTERN",
                   help="only these columns (shell patterns, e.g. 'plant/arm/*')")
    e.add_argument("--rpc3-type", choices=("int", "float"), default="int",
                   help="RPC III data type: int = 16-bit SHORT_INTEGER (resolution max|x|/32752 "
                        "per channel), float = 32-bit FLOATING_POINT")
    return e


def _err(text: str) -> int:
    print(f"{PROG}: {text}", file=sys.stderr)
    return 2


def selection_stem(patterns: list[str] | None) -> str:
    """``table``, or ``table.<patterns, '/' as '_' and '*' as 'x'>``."""
    if not patterns:
        return "table"
    slug = "+".join(re.sub(r"[^A-Za-z0-9_.\-\[\]]", "_", p.replace("*", "x")) for p in patterns)
    return f"table.{slug[:120]}"


def write_format(src: Path, fmt: str, path: Path, patterns: list[str] | None,
                 rpc3_type: str = "int") -> dict[str, Any]:
    """The table ``src`` in ``fmt`` at ``path`` (written aside, renamed); the format's facts."""
    import os

    from cosim.formats import ChannelSet, si_unit, write_channels
    from cosim.formats.stream import table_columns, write_stream
    from cosim.table import read_table

    names = [c for c in table_columns(src) if c not in ("k", "t")
             and (not patterns or any(fnmatchcase(c, p) for p in patterns))]
    if not names:
        raise ValueError(f"no column matches --channels {' '.join(patterns or [])}")
    units = {c: si_unit(c) for c in names}
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")  # writers go by suffix
    try:
        if fmt in ("csv", "parquet"):
            rows = write_stream(src, tmp, fmt, names, units)
            info: dict[str, Any] = {}
        else:
            wanted = set(names)
            table = read_table(src, keep=wanted.__contains__)
            rows = len(table["t"])
            cs = ChannelSet(t=table["t"], channels={c: table[c] for c in names}, units=units)
            opts = {"datatype": rpc3_type} if fmt == "rpc3" else {}
            info = write_channels(cs, tmp, fmt, **opts)
        if rows < 2:
            raise ValueError(f"{src}: fewer than 2 rows")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return {"channels": len(names), **info}


def _export_run_dir(run_dir: Path, args: argparse.Namespace) -> int:
    from cosim.formats.channel_set import EXTENSION
    from cosim.table import table_rows

    out = Path(args.out) if args.out else run_dir / "export"
    src = next((run_dir / n for n in ("table.parquet", "table.csv")
                if (run_dir / n).is_file()), None)
    if src is None:
        what = "a run folder" if (run_dir / "scenario.json").is_file() else "not a run folder"
        return _err(f"{run_dir}: {what} with no table.parquet or table.csv (give its "
                    "journal.msgpack to rebuild one)")
    path = out / f"{selection_stem(args.channels)}{EXTENSION[args.format]}"
    replaced = path.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
        info = write_format(src, args.format, path, args.channels, args.rpc3_type)
        rows = int(table_rows(src.parent, src.name.rsplit(".", 1)[0]) or 0)
    except (OSError, ValueError) as exc:
        return _err(str(exc))
    if replaced:
        print(f"{PROG}: replaced {path} (an export of the same channels)", file=sys.stderr)
    print(json.dumps({"rows": rows, "source": str(src),
                      "files": {args.format: str(path)}, **info}, indent=2))
    return 0


def export_journal(journal: Path, out: Path, fmt: str | None = None,
                   patterns: list[str] | None = None, rpc3_type: str = "int"
                   ) -> tuple[dict[str, Any], str, Any]:
    """Rebuild ``journal``'s table into ``out``: (result, why alongside, journal contents)."""
    from cosim.journal import JournalReader
    from cosim.table import export_target
    from cosim.table_writer import table_of_journal

    readers: list[JournalReader] = []

    def records() -> JournalReader:
        readers.append(JournalReader(journal))
        return readers[-1]

    out.mkdir(parents=True, exist_ok=True)
    writer, bad = table_of_journal(records, out)
    contents = readers[-1].contents()
    rows = writer.rows if writer is not None else 0
    files: dict[str, str] = {}
    why = ""
    if writer is not None:
        try:
            stem, why = export_target(out, rows, contents.damaged) if rows else (None, "")
            files = writer.close(stem)
        except BaseException:
            writer.abandon()
            raise
    info: dict[str, Any] = {}
    if fmt in ("mdf4", "rpc3") and rows > 1:
        from cosim.formats.channel_set import EXTENSION

        stem_now = Path(files["csv"]).name[:-len(".csv")]
        path = out / f"{stem_now}{EXTENSION[fmt]}"
        info = write_format(Path(files["parquet"]), fmt, path, patterns, rpc3_type)
        files = {**files, fmt: str(path)}
    result = {"rows": rows, "files": files, "torn": contents.torn, "undecodable": bad,
              "records": contents.count, "skipped_records": contents.skipped_records,
              "skipped": [vars(s) for s in contents.skipped], **info}
    return result, why, contents


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    journal = Path(args.journal)
    if journal.is_dir():
        if args.format:
            return _export_run_dir(journal, args)
        if not (journal / "journal.msgpack").is_file():
            what = ("a run folder without a journal" if (journal / "scenario.json").is_file()
                    else "not a run folder (no journal.msgpack, no scenario.json)")
            return _err(f"{journal}: {what}: nothing to export")
        journal = journal / "journal.msgpack"
    elif not journal.exists():
        return _err(f"{journal}: no such journal or run folder")
    out = Path(args.out) if args.out else journal.parent
    try:
        res, why, contents = export_journal(journal, out, args.format, args.channels,
                                            args.rpc3_type)
    except (OSError, ValueError, InputFileError) as exc:
        return _err(str(exc))
    print(json.dumps(res, indent=2))
    if contents.problem:
        print(f"{PROG}: {journal}: {contents.problem}", file=sys.stderr)
    rows = res["rows"]
    if not rows:
        return _err(f"{journal}: no complete step in the journal: nothing written")
    if why:
        lost = (f"{contents.skipped_records} damaged record(s) skipped, "
                if contents.damaged else "")
        return _err(f"{journal}: {lost}{rows} rows rebuilt; {why}: wrote "
                    f"{res['files']['csv']} and .parquet alongside, {out / 'table.csv'} left "
                    "as it was")
    return 0


if __name__ == "__main__":
    sys.exit(main())
