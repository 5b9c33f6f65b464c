"""The material database file (the shipped materials.toml; schema in its header,
docs/fatigue.md): reading it. A material is built from its entry by
:func:`nodes.fatigue.lib.material.material_from_entry` (pure)."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..lib.material import _OPTIONAL, _REQUIRED, CYCLIC_CURVES, Material, material_from_entry

DATABASE = Path(__file__).with_name("materials.toml")
"""The shipped material database (schema in its header; docs/fatigue.md)."""


def load_database(path: Path | None = None) -> dict[str, dict[str, Any]]:
    """The material tables of a database file (default: the shipped one), by name.

    Raises ValueError naming the file and the material for a missing or non-numeric value.
    """
    path = Path(path) if path is not None else DATABASE
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"{path}: unreadable material database ({exc})") from None
    for name, entry in data.items():
        if not isinstance(entry, dict):
            raise ValueError(f"{path}: [{name}] is not a table")
        for k in _REQUIRED:
            if k not in entry:
                raise ValueError(f"{path}: [{name}] lacks {k}")
        for k in (*_REQUIRED, *_OPTIONAL):
            v = entry.get(k)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                raise ValueError(f"{path}: [{name}] {k} = {v!r} is not a number")
    return data


def material_names(path: Path | None = None) -> list[str]:
    """The names in a material database (default: the shipped one)."""
    return list(load_database(path))


def database_material(name: str = "817M40", cyclic: str = "uml",
                      path: Path | None = None,
                      base: Mapping[str, float] | None = None) -> Material:
    """Material ``name`` of the database file at ``path`` (default: the shipped one); ``cyclic``
    and ``base`` as in :func:`~nodes.fatigue.lib.material.material_from_entry`."""
    if cyclic not in CYCLIC_CURVES:
        raise ValueError(f"cyclic must be one of {CYCLIC_CURVES}, got {cyclic!r}")
    db = load_database(path)
    if name not in db:
        raise ValueError(f"material {name!r} is not in {path or DATABASE} (it has "
                         + ", ".join(db) + ")")
    return material_from_entry(name, db[name], cyclic, base)


def steel_817M40(cyclic: str = "uml") -> Material:
    """817M40 quenched and tempered (≈ EN24T / AISI 4340): Table 6.2 + UML estimates, from
    the shipped database (`database_material`).

    ``cyclic`` chooses K', n': "uml" (1.65 σu, 0.15; default), "table_6_2" (1166 MPa, 0.0246,
    implausible, see :mod:`nodes.fatigue.lib.material`) or "compatible" (σ'f/ε'f^(b/c), b/c).
    """
    return database_material("817M40", cyclic)
