"""HTML primitives of the report: escaping, number formatting, tables, sections, the page
frame and its inline CSS (no scripts, no external resources)."""

from __future__ import annotations

import html
import math
import re
from collections.abc import Iterable, Sequence
from typing import Any, TypeGuard

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;
 margin:0;background:#f4f5f7;color:#1d2330;font-size:15px;line-height:1.45}
main{max-width:1180px;margin:0 auto;padding:18px 26px 60px;background:#fff;
 box-shadow:0 0 8px rgba(0,0,0,.08)}
h1{font-size:1.6em;margin:.3em 0 .2em}h2{font-size:1.3em;margin:1.6em 0 .5em;
 border-bottom:2px solid #d7dbe3;padding-bottom:.2em}h3{font-size:1.08em;margin:1.1em 0 .4em}
table{border-collapse:collapse;margin:.4em 0 .8em;font-size:.88em}
th,td{border:1px solid #d7dbe3;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#eef1f6}td.num{text-align:right;font-variant-numeric:tabular-nums}
.scroll{overflow-x:auto;max-width:100%}
.kv td:first-child{color:#4a5568;white-space:nowrap}
.badge{display:inline-block;padding:1px 10px;border-radius:10px;font-weight:600;color:#fff}
.ok{background:#2f855a}.failed{background:#c53030}.unknown{background:#718096}
.note{background:#fffbea;border-left:4px solid #d69e2e;padding:6px 12px;margin:.6em 0}
.error{background:#fff5f5;border-left:4px solid #c53030;padding:6px 12px;margin:.6em 0;
 white-space:pre-wrap;font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.9em}
code,pre{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.92em}
pre{background:#f6f8fa;padding:8px;white-space:pre-wrap;word-break:break-word}
img.plot{max-width:100%;height:auto;display:block;margin:.4em 0}
nav{font-size:.92em;margin:.4em 0 1em}nav a{margin-right:12px}
.maps{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:12px}
figure{margin:0}figcaption{font-size:.88em;color:#4a5568}
.meta{color:#4a5568;font-size:.88em}
.row{display:flex;flex-wrap:wrap;gap:0 26px;align-items:flex-start}
.row>div{min-width:0}.kv td.num{text-align:left}
.glance{font-size:1.02em}.glance td:last-child{font-weight:600}
"""


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
            for i, item in enumerate(v):
                out.append((f"{key}[{i}]", item))
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
            f"<title>{esc(title)}</title><style>{CSS}</style></head>\n<body><main>\n"
            f"{body}\n<p class=\"meta\">suscosim report · self-contained: no scripts, no "
            "external resources.</p></main></body></html>\n")
