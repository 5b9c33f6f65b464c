"""A longer run folder from a shorter one (#32's bench): ``table.parquet`` repeated ``times``
times end to end (time shifted by the run's duration each repeat, ``k`` renumbered), written
in row groups as the recorder writes them; the scenario and summary copied (``rows`` and
``run.t_end``/``road.length_m`` scaled). For measuring the post-processing commands
(``report``, batch ``fatigue``, ``export``) at 10^6 rows without a 10^6-step run; the loads
repeat, so it is a memory and time probe, not a result.

    python bench/tile_table.py RUN_DIR OUT_DIR TIMES
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np


def tile(src: Path, out: Path, times: int) -> int:
    """Write ``out`` (a run folder); the rows written."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out.mkdir(parents=True, exist_ok=True)
    f = pq.ParquetFile(src / "table.parquet")
    rg = f.metadata.row_group(0)
    comp = rg.column(0).compression.lower()
    t_all = f.read(columns=["t"]).column(0).to_numpy()
    n = t_all.size
    span = float(t_all[-1] - t_all[0] + (t_all[1] - t_all[0]))
    w = pq.ParquetWriter(out / "table.parquet", f.schema_arrow, compression=comp)
    for r in range(times):
        for i in range(f.metadata.num_row_groups):
            b = f.read_row_group(i)
            cols = []
            for name, col in zip(b.column_names, b.columns, strict=True):
                a = col.to_numpy()
                if name == "t":
                    a = a + r * span
                elif name == "k":
                    a = a + r * n
                cols.append(pa.array(a, type=col.type))
            w.write_table(pa.Table.from_arrays(cols, schema=f.schema_arrow))
    w.close()
    for name in ("scenario.json", "summary.json"):
        if (src / name).is_file():
            d = json.loads((src / name).read_text())
            if name == "summary.json":
                d["rows"] = n * times
            else:
                run, road = d.get("run", {}), d.get("road", {})
                if "t_end" in run:
                    run["t_end"] = float(np.float64(run["t_end"]) * times)
                if "length_m" in road:
                    road["length_m"] = float(road["length_m"]) * times
            (out / name).write_text(json.dumps(d, indent=1))
    for extra in ("fatigue",):
        if (src / extra).is_dir() and not (out / extra).exists():
            shutil.copytree(src / extra, out / extra)
    return n * times


if __name__ == "__main__":
    print(tile(Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3])))
