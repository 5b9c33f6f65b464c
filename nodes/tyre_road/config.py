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
* power_law (thesis Eq. 4.10, S(n) = G n^-p): ``G`` [m^(3-p)] (> 0; the thesis: 1e-7 smooth
  motorway ... 5e-6 rough minor road), ``waviness`` p (default 2.5), ``seed``, ``correlation``
  (as iso8608), ``band`` = [n_min, n_max] [cycles/m] (default [0.011, 2.83])
* pave (synthetic Belgian block on long waves, :mod:`nodes.tyre_road.cobblestone`; every key
  optional, defaults the calibrated pavé): ``seed``, ``stone_length``, ``stone_length_std``,
  ``joint_width``, ``joint_depth``, ``stone_height_std``, ``crown`` [m]; long waves ``G``,
  ``waviness``, ``band``, ``correlation`` (as power_law)
* csv: ``path``, ``zero_start`` (bool, default true)
* opencrg (measured surface, :mod:`nodes.tyre_road.opencrg`): ``path`` (.crg), ``track_width``
  [m] (default the vehicle's 1.411), ``v_offset`` [m], ``u_start`` [m], ``reference`` ("grid" |
  "full"), ``zero_start``
* mdf4 (measured profile, :mod:`nodes.tyre_road.profile_mdf`): ``path`` (.mf4), ``left``
  (channel), ``right`` (channel, default left), ``distance`` (channel [m]) or
  ``recorded_speed_kmh``, ``zero_start``

Tyre keys (``[tyre]``): ``model`` (point_contact | fixed_footprint), ``stiffness`` [N/m],
fixed footprint: ``n`` (>= 1), ``contact_length`` [m].

Bad keys or values raise :class:`cosim.errors.ScenarioError` naming the dotted key.
"""

from __future__ import annotations

from collections.abc import Mapping

from cosim.channels import CORNERS as _CORNERS
from cosim.errors import ScenarioError

from .cobblestone import DEFAULTS as PAVE_DEFAULTS
from .cobblestone import PaveParameters, pave_road
from .iso8608 import DEFAULT_N_MAX, DEFAULT_N_MIN, GD_N0, iso8608_road
from .opencrg import VEHICLE_TRACK_M, opencrg_road
from .power_law import DEFAULT_WAVINESS, power_law_road
from .profile_csv import csv_road
from .profile_mdf import mdf_road
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


def _number(cfg: Mapping, key: str, prefix: str, *, default=None, positive=False,
            nonneg=False) -> float:
    v = cfg.get(key, default)
    if v is None:
        raise ScenarioError(f"{prefix}.{key}", None, "a number (missing)")
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ScenarioError(f"{prefix}.{key}", v, "a number")
    if positive and not v > 0:
        raise ScenarioError(f"{prefix}.{key}", v, "a number > 0")
    if nonneg and not v >= 0:
        raise ScenarioError(f"{prefix}.{key}", v, "a number >= 0")
    return float(v)


def _check_keys(cfg: Mapping, allowed: set[str], prefix: str) -> None:
    for k in cfg:
        if k not in allowed:
            raise ScenarioError(f"{prefix}.{k}", cfg[k],
                                f"one of the keys {sorted(allowed)}")


def _seed(cfg: Mapping, prefix: str, key: str = "seed") -> int:
    seed = cfg.get(key, 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ScenarioError(f"{prefix}.{key}", seed, "an integer >= 0")
    return seed


def _correlation(cfg: Mapping, prefix: str) -> str | float:
    corr = cfg.get("correlation", "independent")
    if isinstance(corr, bool) or not (
            corr in ("identical", "independent")
            or (isinstance(corr, (int, float)) and 0.0 <= corr <= 1.0)):
        raise ScenarioError(f"{prefix}.correlation", corr,
                            "'identical', 'independent' or a number in [0, 1]")
    return corr


def _band(cfg: Mapping, prefix: str, key: str = "band") -> tuple[float, float]:
    band = cfg.get(key, [DEFAULT_N_MIN, DEFAULT_N_MAX])
    if (not isinstance(band, (list, tuple)) or len(band) != 2
            or any(isinstance(b, bool) or not isinstance(b, (int, float)) for b in band)
            or not 0 < band[0] < band[1]):
        raise ScenarioError(f"{prefix}.{key}", band,
                            "[n_min, n_max] in cycles/m with 0 < n_min < n_max")
    return float(band[0]), float(band[1])


_POWER_LAW_KEYS = {"G", "waviness", "seed", "correlation", "band"}


def _power_law_keys(cfg: Mapping, prefix: str
                    ) -> tuple[float, float, int, str | float, tuple[float, float]]:
    """(G, waviness, seed, correlation, (n_min, n_max)) of an Eq. 4.10 road section."""
    G = _number(cfg, "G", prefix, positive=True)
    waviness = _number(cfg, "waviness", prefix, default=DEFAULT_WAVINESS, positive=True)
    return G, waviness, _seed(cfg, prefix), _correlation(cfg, prefix), _band(cfg, prefix)


def _event(cfg: Mapping, kind: str, speed: float, prefix: str) -> RoadEvent:
    if "x_start" in cfg and "t_start" in cfg:
        raise ScenarioError(f"{prefix}.t_start", cfg["t_start"],
                            "either x_start or t_start, not both")
    if "t_start" in cfg:
        x0 = _number(cfg, "t_start", prefix, nonneg=True) * speed
    else:
        x0 = _number(cfg, "x_start", prefix, default=0.0)
    if kind == "pothole":
        h = _number(cfg, "depth", prefix, positive=True)
    else:
        h = _number(cfg, "height", prefix)
    length = 0.0
    if kind != "step":
        length = _number(cfg, "length", prefix, positive=True)
    shape = cfg.get("shape", "cosine")
    if shape not in ("cosine", "rect"):
        raise ScenarioError(f"{prefix}.shape", shape, "'cosine' or 'rect'")
    tracks = cfg.get("tracks", "both")
    if tracks not in _TRACKS:
        raise ScenarioError(f"{prefix}.tracks", tracks, "'both', 'left' or 'right'")
    return RoadEvent(kind=kind, x_start=x0, height=h, length=length, shape=shape,
                     tracks=_TRACKS[tracks])


def build_road(cfg: Mapping, key_prefix: str = "road") -> Road:
    """A :class:`Road` from the ``[road]`` section (see the module docstring for the keys)."""
    p = key_prefix
    if not isinstance(cfg, Mapping):
        raise ScenarioError(p, cfg, "a table")
    kind = cfg.get("type")
    if kind not in _ROAD_TYPES:
        raise ScenarioError(f"{p}.type", kind, "one of " + ", ".join(_ROAD_TYPES))
    speed = _number(cfg, "speed_kmh", p, positive=True) * KMH
    length = cfg.get("length_m")
    if length is not None:
        length = _number(cfg, "length_m", p, positive=True)
    corners = cfg.get("corners")
    if corners is not None:
        if not isinstance(corners, (list, tuple)) or not corners or \
                any(c not in _CORNERS for c in corners):
            raise ScenarioError(f"{p}.corners", corners,
                                "a non-empty list of corner names from FL, FR, RL, RR")
        corners = tuple(corners)

    if kind in _EVENT_TYPES:
        _check_keys(cfg, _COMMON | _EVENT_KEYS[kind], p)
        road: Road = EventRoad(events=[_event(cfg, kind, speed, p)], name=kind)
    elif kind == "events":
        _check_keys(cfg, _COMMON | {"events"}, p)
        evs = cfg.get("events")
        if not isinstance(evs, (list, tuple)) or not evs:
            raise ScenarioError(f"{p}.events", evs, "a non-empty list of event tables")
        events = []
        for i, ev in enumerate(evs):
            q = f"{p}.events[{i}]"
            if not isinstance(ev, Mapping):
                raise ScenarioError(q, ev, "a table")
            ek = ev.get("type")
            if ek not in _EVENT_TYPES:
                raise ScenarioError(f"{q}.type", ek, "one of " + ", ".join(_EVENT_TYPES))
            _check_keys(ev, {"type"} | _EVENT_KEYS[ek], q)
            events.append(_event(ev, ek, speed, q))
        road = EventRoad(events=events, name="events")
    elif kind == "iso8608":
        _check_keys(cfg, _COMMON | {"class", "seed", "correlation", "n_min", "n_max"}, p)
        cls = cfg.get("class")
        if cls not in GD_N0:
            raise ScenarioError(f"{p}.class", cls, "an ISO 8608 class letter A-H")
        seed = _seed(cfg, p)
        corr = _correlation(cfg, p)
        n_min = _number(cfg, "n_min", p, default=DEFAULT_N_MIN, positive=True)
        n_max = _number(cfg, "n_max", p, default=DEFAULT_N_MAX, positive=True)
        if n_max <= n_min:
            raise ScenarioError(f"{p}.n_max", n_max, f"a number > n_min ({n_min})")
        if length is None:
            raise ScenarioError(f"{p}.length_m", None, "a number > 0 (needed for iso8608)")
        road = iso8608_road(cls, length, speed, seed, corr, n_min, n_max)
    elif kind == "power_law":
        _check_keys(cfg, _COMMON | _POWER_LAW_KEYS, p)
        G, waviness, seed, corr, (n_min, n_max) = _power_law_keys(cfg, p)
        if length is None:
            raise ScenarioError(f"{p}.length_m", None, "a number > 0 (needed for power_law)")
        road = power_law_road(G, length, speed, seed, waviness, corr, n_min, n_max)
    elif kind == "pave":
        _check_keys(cfg, _COMMON | _POWER_LAW_KEYS | set(PAVE_KEYS), p)
        seed, corr = _seed(cfg, p), _correlation(cfg, p)
        band = _band(cfg, p) if "band" in cfg else PAVE_DEFAULTS.band
        vals = {k: _number(cfg, k, p, default=getattr(PAVE_DEFAULTS, k),
                           positive=k in ("stone_length", "joint_width", "G", "waviness"),
                           nonneg=True)
                for k in PAVE_KEYS + ("G", "waviness")}
        if vals["stone_length_std"] >= vals["stone_length"]:
            raise ScenarioError(f"{p}.stone_length_std", vals["stone_length_std"],
                                f"a number < stone_length ({vals['stone_length']})")
        if length is None:
            raise ScenarioError(f"{p}.length_m", None, "a number > 0 (needed for pave)")
        road = pave_road(length, speed, seed,
                         PaveParameters(**vals, band=band, correlation=corr))
    else:  # measured: csv, opencrg, mdf4
        road = _measured_road(cfg, kind, speed, length, p)

    road.speed = speed
    road.length = length if length is not None else road.length
    road.corners = corners
    return road


_MEASURED_KEYS = {"csv": {"path", "zero_start"},
                  "opencrg": {"path", "zero_start", "track_width", "v_offset", "u_start",
                              "reference"},
                  "mdf4": {"path", "zero_start", "left", "right", "distance",
                           "recorded_speed_kmh"}}


def _text(cfg: Mapping, key: str, prefix: str, expected: str, required: bool = False):
    v = cfg.get(key)
    if v is None and not required:
        return None
    if not isinstance(v, str) or not v:
        raise ScenarioError(f"{prefix}.{key}", v, expected)
    return v


def _measured_road(cfg: Mapping, kind: str, speed: float, length: float | None,
                   p: str) -> Road:
    """A measured road profile (csv, opencrg, mdf4) from its ``[road]`` keys."""
    _check_keys(cfg, _COMMON | _MEASURED_KEYS[kind], p)
    path = _text(cfg, "path", p, "a file path", required=True)
    zero_start = cfg.get("zero_start", True)
    if not isinstance(zero_start, bool):
        raise ScenarioError(f"{p}.zero_start", zero_start, "true or false")
    if kind == "csv":
        return csv_road(path, speed, length, zero_start)
    if kind == "opencrg":
        reference = cfg.get("reference", "grid")
        if reference not in ("grid", "full"):
            raise ScenarioError(f"{p}.reference", reference, "'grid' or 'full'")
        u_start = _number(cfg, "u_start", p) if "u_start" in cfg else None
        return opencrg_road(path, speed, length,
                            _number(cfg, "track_width", p, default=VEHICLE_TRACK_M,
                                    positive=True),
                            _number(cfg, "v_offset", p, default=0.0), u_start, reference,
                            zero_start)
    if ("distance" in cfg) == ("recorded_speed_kmh" in cfg):
        raise ScenarioError(f"{p}.distance", cfg.get("distance"),
                            "either distance (a channel in m) or recorded_speed_kmh")
    rec = _number(cfg, "recorded_speed_kmh", p, positive=True) \
        if "recorded_speed_kmh" in cfg else None
    return mdf_road(path, speed, _text(cfg, "left", p, "a channel name", required=True),
                    _text(cfg, "right", p, "a channel name"),
                    _text(cfg, "distance", p, "a channel name"), rec, length, zero_start)


def build_tyre(cfg: Mapping, key_prefix: str = "tyre") -> Tyre:
    """A :class:`Tyre` from the ``[tyre]`` section."""
    p = key_prefix
    if not isinstance(cfg, Mapping):
        raise ScenarioError(p, cfg, "a table")
    model = cfg.get("model", "point_contact")
    if model == "point_contact":
        _check_keys(cfg, {"model", "stiffness"}, p)
        return PointContact(k_t=_number(cfg, "stiffness", p, positive=True))
    if model == "fixed_footprint":
        _check_keys(cfg, {"model", "stiffness", "n", "contact_length"}, p)
        n = cfg.get("n", 4)
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ScenarioError(f"{p}.n", n, "an integer >= 1")
        return FixedFootprint(n=n, contact_length=_number(cfg, "contact_length", p,
                                                          positive=True),
                              k_t=_number(cfg, "stiffness", p, positive=True))
    raise ScenarioError(f"{p}.model", model, "'point_contact' or 'fixed_footprint'")
