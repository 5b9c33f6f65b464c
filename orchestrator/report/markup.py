"""HTML primitives of the report: escaping, number formatting, tables, sections, the page
frame and its CSS (report.css, inlined: no scripts, no external resources)."""

from __future__ import annotations

import html
import math
import re
from collections.abc import Iterable, Sequence
from importlib import resources
from typing import Any, TypeGuard

CSS = resources.files(__package__).joinpath("report.css").read_text(encoding="utf-8")
"""The page's style sheet (report.css, package data), inlined in every page."""


def esc(x: Any) -> str:
    return html.escape(str(x), quote=True)


def fmt(v: Any) -> str:
    """A value for a table cell: numbers with 4 significant digits (``.4g``)."""
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "—" if math.isnan(v) else f"{v:.4g}"
    if isinstance(v, (list, tuple)):
        if all(isinstance(i, (int, float)) and not isinstance(i, bool) for i in v):
            return "[" + ", ".join(fmt(i) for i in v) + "]"
        if all(isinstance(i, dict) for i in v):
            return "; ".join(", ".join(f"{k}={fmt(x)}" for k, x in i.items()) for i in v)
        return ", ".join(fmt(i) for i in v)
    if isinstance(v, dict):
        return ", ".join(f"{k}={fmt(x)}" for k, x in v.items()) if v else "—"
    return str(v)


def is_num(v: Any) -> TypeGuard[int | float]:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def table_html(header: Sequence[str], rows: Iterable[Sequence[Any]], cls: str = "",
               raw_cols: Sequence[int] = ()) -> str:
    """An HTML table; cells :func:`fmt`-ed and escaped, but the columns ``raw_cols`` (HTML)."""
    out = [f'<div class="scroll"><table class="{cls}"><tr>']
    out += [f"<th>{esc(h)}</th>" for h in header]
    out.append("</tr>")
    for row in rows:
        out.append("<tr>")
        for i, v in enumerate(row):
            if i in raw_cols:
                out.append(f"<td>{v}</td>")
            else:
                out.append(f'<td class="num">{esc(fmt(v))}</td>' if is_num(v)
                           else f"<td>{esc(fmt(v))}</td>")
        out.append("</tr>")
    out.append("</table></div>")
    return "".join(out)


def kv_table(pairs: Iterable[tuple[str, Any]], title: str = "", cls: str = "kv") -> str:
    head = f"<h3>{esc(title)}</h3>" if title else ""
    return f"<div>{head}" + table_html(["key", "value"], list(pairs), cls=cls) + "</div>"


def row(*blocks: str) -> str:
    return '<div class="row">' + "".join(blocks) + "</div>"


def flatten(d: Any, prefix: str = "") -> list[tuple[str, Any]]:
    """Dotted ``(key, value)`` pairs of a nested dict (lists are kept whole)."""
    if not isinstance(d, dict):
        return [(prefix or "value", d)]
    out: list[tuple[str, Any]] = []
    for k, v in d.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict) and v:
            out += flatten(v, key)
        elif isinstance(v, list) and v and all(isinstance(i, dict) for i in v):
            out += [(f"{key}[{i}]", item) for i, item in enumerate(v)]
        else:
            out.append((key, v))
    return out


def note(text_html: str) -> str:
    return f'<div class="note">{text_html}</div>'


def section(anchor: str, title: str, body: str) -> str:
    return f'<section id="{esc(anchor)}"><h2>{esc(title)}</h2>\n{body}\n</section>\n'


def badge(status: str) -> str:
    cls = status if status in ("ok", "failed") else "unknown"
    return f'<span class="badge {cls}">{esc(status)}</span>'


def anchor_id(text: str) -> str:
    return "point-" + (re.sub(r"[^A-Za-z0-9_.-]+", "-", str(text)).strip("-") or "x")


def cmd(text: str) -> str:
    return f"<code>{esc(text)}</code>"


def nav(items: Sequence[tuple[str, str]]) -> str:
    return "<nav>" + "".join(f'<a href="#{esc(a)}">{esc(t)}</a>' for a, t in items) + "</nav>"


def page(title: str, body: str) -> str:
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{esc(title)}</title><style>\n{CSS}</style></head>\n<body><main>\n"
            f"{body}\n<p class=\"meta\">suscosim report · self-contained: no scripts, no "
            "external resources.</p></main></body></html>\n")
