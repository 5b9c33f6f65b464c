"""Build a road and a tyre from their scenario sections (``[road]``, ``[tyre]``).

Road keys (``[road]``):

* ``type``: step | ramp | bump | pothole | events | iso8608 | power_law | pave | csv | opencrg |
  mdf4
* ``speed_kmh`` (> 0) forward speed; ``length_m`` (> 0) run distance; duration = length / speed
* ``corners`` (optional): list of corner names seeing the road, e.g. ["FR"] (Ch. 4 FVM test)
* events (step, ramp, bump, pothole): ``height`` [m] (pothole: ``depth`` [m], > 0),
  ``x_start`` [m] or ``t_start`` [s] (x_start = t_start * speed), ``length`` [m] (ramp, bump,
  pothole), ``shape`` (pothole: cosine | rect), ``tracks`` ("both" | "left" | "right")
* ``events``: a list of tables, each with its own ``type`` (step|ramp|bump|pothole) and the keys
  above (the Ch. 4 bump + pothole road)
* iso8608: ``class`` (A-H), ``seed`` (int), ``correlation`` ("identical" | "independent" |
  number in [0, 1]), ``n_min``, ``n_max`` [cycles/m]
* power_law (thesis Eq. 4.10, S(n) = G n^-p, :mod:`.iso8608`): ``G`` [m^(3-p)] (> 0),
  ``waviness`` p [2.5], ``seed``, ``correlation``, ``band`` [n_min, n_max] cycles/m
* pave (:mod:`.cobblestone`, every key optional, defaults the calibrated pavé): ``seed``, the
  stones' :data:`PAVE_KEYS` [m] and the long waves' ``G``, ``waviness``, ``band``, ``correlation``
* measured (csv, opencrg, mdf4: :mod:`.measured`): ``path``, ``zero_start``
  (default true) and the format's keys (docs/data_formats.md)

Tyre keys (``[tyre]``): ``model`` (point_contact | fixed_footprint), ``stiffness`` [N/m],
fixed footprint: ``n`` (>= 1), ``contact_length`` [m].

Bad keys or values raise :class:`cosim.errors.ScenarioError` naming the dotted key.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from cosim.channels import CORNERS as _CORNERS
from cosim.config import ConfigReader

from . import iso8608 as rr
from .cobblestone import DEFAULTS as PAVE_DEFAULTS
from .cobblestone import PaveParameters, pave_road
from .iso8608 import DEFAULT_N_MAX, DEFAULT_N_MIN, DEFAULT_WAVINESS, GD_N0, random_road
from .measured import VEHICLE_TRACK_M, measured_road
from .roads import KMH, EventRoad, Road, RoadEvent
from .tyres import FixedFootprint, PointContact, Tyre

_EVENT_TYPES = ("step", "ramp", "bump", "pothole")
_ROAD_TYPES = _EVENT_TYPES + ("events", "iso8608", "power_law", "pave", "csv", "opencrg",
                              "mdf4")
PAVE_KEYS = ("stone_length", "stone_length_std", "joint_width", "joint_depth",
             "stone_height_std", "crown")
"""Stone keys of a pave road (besides the long-wave keys of power_law)."""
_COMMON = {"type", "speed_kmh", "length_m", "corners"}
_EVENT_KEYS = {
    "step": {"height", "x_start", "t_start", "tracks"},
    "ramp": {"height", "x_start", "t_start", "length", "tracks"},
    "bump": {"height", "x_start", "t_start", "length", "tracks"},
    "pothole": {"depth", "x_start", "t_start", "length", "shape", "tracks"},
}
_TRACKS = {"both": (0, 1), "left": (0,), "right": (1,)}


def _correlation(r: ConfigReader) -> str | float:
    corr = r.value("correlation", "independent")
    if isinstance(corr, bool) or not (
            corr in ("identical", "independent")
            or (isinstance(corr, (int, float)) and 0.0 <= corr <= 1.0)):
        raise r.error("correlation", corr, "'identical', 'independent' or a number in [0, 1]")
    return corr


def _band(r: ConfigReader, key: str = "band") -> tuple[float, float]:
    expected = "[n_min, n_max] in cycles/m with 0 < n_min < n_max"
    band = r.number_list(key, [DEFAULT_N_MIN, DEFAULT_N_MAX], length=2, expected=expected)
    if not 0 < band[0] < band[1]:
        raise r.error(key, r.value(key), expected)
    return band[0], band[1]


_POWER_LAW_KEYS = {"G", "waviness", "seed", "correlation", "band"}


def _event(r: ConfigReader, kind: str, speed: float) -> RoadEvent:
    if r.has("x_start") and r.has("t_start"):
        raise r.error("t_start", r.value("t_start"), "either x_start or t_start, not both")
    x0 = r.number("t_start", lo=0.0) * speed if r.has("t_start") else r.number("x_start", 0.0)
    h = r.number("depth", positive=True) if kind == "pothole" else r.number("height")
    length = 0.0 if kind == "step" else r.number("length", positive=True)
    shape = r.choice("shape", ("cosine", "rect"), "cosine")
    tracks = r.choice("tracks", tuple(_TRACKS), "both")
    return RoadEvent(kind=kind, x_start=x0, height=h, length=length, shape=shape,
                     tracks=_TRACKS[tracks])


def build_road(cfg: Mapping[str, Any], key_prefix: str = "road") -> Road:
    """A :class:`Road` from the ``[road]`` section (see the module docstring for the keys)."""
    r = ConfigReader(cfg, key_prefix)
    kind = r.choice("type", _ROAD_TYPES)
    speed = r.number("speed_kmh", positive=True) * KMH
    length = r.optional_number("length_m", positive=True)
    corners = r.value("corners")
    if corners is not None:
        if not isinstance(corners, (list, tuple)) or not corners or \
                any(c not in _CORNERS for c in corners):
            raise r.error("corners", corners,
                          "a non-empty list of corner names from FL, FR, RL, RR")
        corners = tuple(corners)

    if kind in _EVENT_TYPES:
        r.only(_COMMON | _EVENT_KEYS[kind])
        road: Road = EventRoad(events=[_event(r, kind, speed)], name=kind)
    elif kind == "events":
        r.only(_COMMON | {"events"})
        events = []
        for ev in r.sections("events", expected="a non-empty list of event tables"):
            ek = ev.choice("type", _EVENT_TYPES)
            ev.only({"type"} | _EVENT_KEYS[ek])
            events.append(_event(ev, ek, speed))
        road = EventRoad(events=events, name="events")
    elif kind == "iso8608":
        r.only(_COMMON | {"class", "seed", "correlation", "n_min", "n_max"})
        cls = r.choice("class", GD_N0, expected="an ISO 8608 class letter A-H")
        seed, corr = r.integer("seed", 0, lo=0), _correlation(r)
        n_min = r.number("n_min", DEFAULT_N_MIN, positive=True)
        n_max = r.number("n_max", DEFAULT_N_MAX, positive=True)
        if n_max <= n_min:
            raise r.error("n_max", n_max, f"a number > n_min ({n_min})")
        if length is None:
            raise r.error("length_m", None, "a number > 0 (needed for iso8608)")
        road = random_road(rr.iso8608_psd(cls), length, speed, seed, corr, n_min, n_max,
                           f"iso8608_{cls}")
    elif kind == "power_law":
        r.only(_COMMON | _POWER_LAW_KEYS)
        G = r.number("G", positive=True)
        waviness = r.number("waviness", DEFAULT_WAVINESS, positive=True)
        seed, corr, (n_min, n_max) = r.integer("seed", 0, lo=0), _correlation(r), _band(r)
        if length is None:
            raise r.error("length_m", None, "a number > 0 (needed for power_law)")
        road = random_road(rr.power_law_psd(G, waviness), length, speed, seed, corr, n_min, n_max,
                           "power_law")
    elif kind == "pave":
        r.only(_COMMON | _POWER_LAW_KEYS | set(PAVE_KEYS))
        seed, corr = r.integer("seed", 0, lo=0), _correlation(r)
        band = _band(r) if r.has("band") else PAVE_DEFAULTS.band
        vals = {k: r.number(k, getattr(PAVE_DEFAULTS, k), lo=0.0,
                            lo_open=k in ("stone_length", "joint_width", "G", "waviness"))
                for k in PAVE_KEYS + ("G", "waviness")}
        if vals["stone_length_std"] >= vals["stone_length"]:
            raise r.error("stone_length_std", vals["stone_length_std"],
                          f"a number < stone_length ({vals['stone_length']})")
        if length is None:
            raise r.error("length_m", None, "a number > 0 (needed for pave)")
        road = pave_road(length, speed, seed,
                         PaveParameters(**vals, band=band, correlation=corr))
    else:  # measured: csv, opencrg, mdf4
        road = _measured_road(r, kind, speed, length)

    road.speed = speed
    road.length = length if length is not None else road.length
    road.corners = corners
    return road


_MEASURED_KEYS = {"csv": {"path", "zero_start"},
                  "opencrg": {"path", "zero_start", "track_width", "v_offset", "u_start",
                              "reference"},
                  "mdf4": {"path", "zero_start", "left", "right", "distance",
                           "recorded_speed_kmh"}}


def _measured_road(r: ConfigReader, kind: str, speed: float, length: float | None) -> Road:
    """A measured road profile (csv, opencrg, mdf4) from its ``[road]`` keys."""
    r.only(_COMMON | _MEASURED_KEYS[kind])
    path = r.string("path", expected="a file path")
    zero_start = r.boolean("zero_start", True)
    if kind == "csv":
        return measured_road(kind, path, speed, length, zero_start)
    if kind == "opencrg":
        reference = r.choice("reference", ("grid", "full"), "grid")
        u_start = r.optional_number("u_start")
        return measured_road(kind, path, speed, length, zero_start,
                             track_width=r.number("track_width", VEHICLE_TRACK_M, positive=True),
                             v_offset=r.number("v_offset", 0.0), u_start=u_start,
                             reference=reference)
    if r.has("distance") == r.has("recorded_speed_kmh"):
        raise r.error("distance", r.value("distance"),
                      "either distance (a channel in m) or recorded_speed_kmh")
    channel = "a channel name"
    rec = r.optional_number("recorded_speed_kmh", positive=True)
    return measured_road(kind, path, speed, length, zero_start,
                         left=r.string("left", expected=channel),
                         right=r.optional_string("right", expected=channel),
                         distance=r.optional_string("distance", expected=channel),
                         recorded_speed_kmh=rec)


def build_tyre(cfg: Mapping[str, Any], key_prefix: str = "tyre") -> Tyre:
    """A :class:`Tyre` from the ``[tyre]`` section."""
    r = ConfigReader(cfg, key_prefix)
    model = r.choice("model", ("point_contact", "fixed_footprint"), "point_contact")
    if model == "point_contact":
        r.only({"model", "stiffness"})
        return PointContact(k_t=r.number("stiffness", positive=True))
    r.only({"model", "stiffness", "n", "contact_length"})
    n = r.integer("n", 4, lo=1)
    return FixedFootprint(n=n, contact_length=r.number("contact_length", positive=True),
                          k_t=r.number("stiffness", positive=True))
