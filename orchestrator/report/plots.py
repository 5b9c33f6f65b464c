"""Matplotlib helpers of the report: an Agg figure without pyplot, figures and PNG files as
``data:`` URIs, min/max decimation of long signals, stacked time-history panels."""

from __future__ import annotations

import base64
import io
import math
from pathlib import Path

import numpy as np

from cosim.channels import CORNERS
from cosim.safe_open import read_user_file

from .markup import esc

MAX_PLOT_POINTS = 4000
"""Longer signals are decimated (min/max per bucket): a panel is ~990 pixel columns (11 in at
90 dpi), so every peak is drawn and a 35-minute run as fast as a 4-second one."""


def new_figure(nrows: int, ncols: int = 1, width: float = 11.0, row_h: float = 2.6,
            sharex: bool = False):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, max(2.4, row_h * nrows)), layout="constrained")
    axes = fig.subplots(nrows, ncols, sharex=sharex, squeeze=False)
    return fig, [a for row in axes for a in row]


def fig_uri(fig, dpi: int = 90) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def file_uri(path: Path) -> str | None:
    """A PNG file inside its folder (no symlink out) as a data URI, else None."""
    try:
        data = read_user_file(path, "report", inside=path.parent)
    except (OSError, ValueError):  # InputFileError
        return None
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        return None
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def img(uri: str, alt: str) -> str:
    return f'<img class="plot" src="{uri}" alt="{esc(alt)}">'


def decimate(t: np.ndarray, x: np.ndarray, n_max: int = MAX_PLOT_POINTS,
             bucket: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """At most ~n_max points, each bucket's min and max in their order (NaN left out of a
    bucket; an all-NaN one stays a gap). ``bucket`` default: ``ceil(n / (n_max // 2))``."""
    n = x.size
    if n <= n_max and bucket is None:
        return t, x
    b = bucket if bucket is not None else int(math.ceil(n / (n_max // 2)))
    pad = (-n) % b  # the last bucket filled up with its own last sample
    if pad:
        x = np.concatenate([x, np.repeat(x[-1:], pad)])
        t = np.concatenate([t, np.repeat(t[-1:], pad)])
    xb, tb = x.reshape(-1, b), t.reshape(-1, b)
    with np.errstate(invalid="ignore"):
        nan = np.isnan(xb)
        i_lo = np.where(nan, np.inf, xb).argmin(axis=1)
        i_hi = np.where(nan, -np.inf, xb).argmax(axis=1)
    first = np.minimum(i_lo, i_hi)
    second = np.maximum(i_lo, i_hi)
    rows = np.arange(xb.shape[0])
    tt = np.column_stack([tb[rows, first], tb[rows, second]]).ravel()
    xx = np.column_stack([xb[rows, first], xb[rows, second]]).ravel()
    return tt, xx


def plot_panels(t: np.ndarray | None, panels: list[tuple], width: float = 11.0) -> str:
    """Stacked panels ``[(title, unit, [(label, y or (t, y))])]`` (``y`` decimated here)."""
    fig, axes = new_figure(len(panels), width=width, sharex=True)
    styles = ("-", "--", ":", "-.")
    for ax, (title, unit, lines) in zip(axes, panels, strict=True):
        quantities: list[str] = []
        for i, (lab, y) in enumerate(lines):
            head, _, last = lab.rpartition(" ")
            if last in CORNERS and head:  # full vehicle: colour = corner, style = quantity
                if head not in quantities:
                    quantities.append(head)
                style = dict(color=f"C{CORNERS.index(last)}",
                             ls=styles[quantities.index(head) % len(styles)])
            else:
                style = dict(color=f"C{i % 10}")
            if isinstance(y, tuple):
                tt, yy = y
            else:
                assert t is not None, "a signal without its times"
                tt, yy = decimate(t, y)
            ax.plot(tt, yy, lw=0.9, label=lab, **style)
        ax.set_title(title, fontsize=10, loc="left")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        if len(lines) > 1:
            ax.legend(fontsize=7, loc="upper right", ncol=min(4, len(lines)))
    axes[-1].set_xlabel("t [s]")
    return fig_uri(fig)
