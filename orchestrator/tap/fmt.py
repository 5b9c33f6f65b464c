"""Message fields as short text (the display) and as flat columns (the CSV)."""

from __future__ import annotations

from typing import Any

from cosim.wire import Message


def fmt_value(value: Any, max_items: int = 4) -> str:
    """A number as %.5g; a list shortened to its first items and its length."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, int | float):
        return f"{value:.5g}"
    if isinstance(value, list | tuple):
        items = [fmt_value(v) for v in value[:max_items]]
        if len(value) > max_items:
            return "[" + ", ".join(items[:max_items - 1]) + f", ...]({len(value)})"
        return "[" + ", ".join(items) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {fmt_value(v)}" for k, v in list(value.items())[:3]) + \
            (", ...}" if len(value) > 3 else "}")
    text = str(value)
    return text if len(text) <= 24 else text[:21] + "..."


def fmt_fields(msg: Message) -> str:
    body = " ".join(f"{name}={fmt_value(v)}" for name, v in msg.d.items())
    return body if msg.kind == "data" else f"<{msg.kind}> {body}".rstrip()


def flatten(d: dict[str, Any]) -> dict[str, Any]:
    """Data fields as CSV columns: a list ``x`` becomes ``x[0]``, ``x[1]``, ..."""
    out: dict[str, Any] = {}
    for name, value in d.items():
        if isinstance(value, list):
            for i, v in enumerate(value):
                out[f"{name}[{i}]"] = v
        else:
            out[name] = value
    return out
