"""Critical-plane fatigue (Findley) of stress tensor histories: pure numerics, no I/O.

**Findley's parameter** (Findley 1959, J. Eng. Ind. 81:301-306; Socie & Marquis, *Multiaxial
Fatigue*, SAE 2000, Ch. 4): on a material plane of unit normal n, a shear cycle of amplitude
τa [Pa] with the largest normal stress σn,max [Pa] on that plane during the cycle is as
damaging as f = τa + k σn,max; the critical plane is the plane of the largest damage.

**k from the fatigue limits** (Socie & Marquis 2000, Ch. 4): fully reversed bending σa on
the plane at angle θ to the load axis gives τa = σa sin2θ / 2, σn,max = σa (1 + cos2θ) / 2,
whose largest f is

    f_bend = σa (k + sqrt(1 + k²)) / 2     at tan 2θ = 1 / k;                 (1)

fully reversed torsion τa gives τa cos2φ and σn,max = τa |sin2φ|, the largest

    f_tors = τa sqrt(1 + k²)              at tan 2φ = k.                      (2)

Equal f at the two fatigue limits f₋₁ (bending) and t₋₁ (torsion), r = f₋₁ / t₋₁:

    k = (2 - r) / (2 sqrt(r - 1)).                                            (3)

t₋₁ / f₋₁ = 0.59: Shigley's load factor kc for torsion (Budynas & Nisbett, *Shigley's
Mechanical Engineering Design*, 10th ed., Eq. 6-26; the project's component curve takes kc
from the same table, :mod:`.material`), so k = 0.183 (:data:`FINDLEY_K`).

**Life.** A cycle's f is mapped to the fully reversed uniaxial amplitude of the same f by
(1): σ_eq = f / U, U = (k + sqrt(1 + k²)) / 2, whose life the project's S-N curve gives (no
further mean-stress correction: Findley's σn,max term is its mean-stress effect). So a
fully reversed uniaxial history gets exactly the S-N life of its amplitude, and fully
reversed torsion τa that of σ_eq = τa sqrt(1 + k²) / U = τa r (by (3)).

**Planes** (angular step :data:`STEP_DEG`): at a free surface the stress is traction free,
σ n_s = 0 for the outward normal n_s. n_s is found from the history itself, the direction of
least traction: the eigenvector of the smallest eigenvalue λ₁ of Σ_t σ(t)² (a stress
that is uniaxial all along leaves two such directions: either serves). Where sqrt(λ₁/λ₃) <=
:data:`TRACTION_MAX` the node is a surface node and the planes searched are those normal to
the surface (their normal n in the surface plane, every STEP_DEG over 180°, the best refined
every REFINE_DEG within ± STEP_DEG); the shear on such a plane has one component, along
m = n_s × n (n·σ·n_s = 0): a scalar path, counted as it is. Elsewhere (interior nodes, or no
traction-free direction) the normals cover the hemisphere (polar angle every STEP_DEG,
azimuth every STEP_DEG / sin θ) and the 2-D shear path on each plane is projected on
directions every STEP_DEG over 180°, each projection a scalar path counted alone (cheap and
vectorised; one direction lies within STEP_DEG/2 of the path's longest chord, so its range is
at least cos(STEP_DEG/2) of it, 99.6 % at 10°; the minimum circumscribed circle gives one
amplitude for the whole path, not the cycles rainflow counts of a variable history).

**Counting with the normal stress** (Bannantine & Socie 1991 take σn,max during each
shear cycle): each shear path is rainflow counted (the four-point rule of
:mod:`.counting`) with, on every residue point, the largest σn on the plane from that point
to the next; a cycle b-c closed by e gets the largest σn from b to e (the cycle, and at most
the rise from its end to the closing point: exact for a periodic history).

**Non-proportionality** (Kanazawa, Miller & Brown 1977, the rotation factor): F = Δτ on the
plane at 45° to the plane of largest shear range / that largest range (range: max - min over
the history); 0 for proportional loading, 1 for a circular shear path (90° out-of-phase
tension-torsion with σa = 2 τa). Where F is not small the principal directions turn and an
equivalent-stress life is not to be trusted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CRITICAL_PLANES = ("findley",)
"""``[fatigue] equivalent`` values that are critical-plane methods (:mod:`.critical_plane_run`)."""
RANKING = "abs_max_principal"
"""The equivalent stress whose pass ranks the nodes for a critical-plane method."""
TORSION_TO_BENDING = 0.59
"""t₋₁ / f₋₁: Shigley's kc for torsion (Budynas & Nisbett 10th ed. Eq. 6-26)."""
STEP_DEG = 10.0
"""Angular step of the plane search (and of the shear directions off the surface) [deg]."""
REFINE_DEG = 1.0
"""Surface nodes: the best plane of the STEP_DEG search is refined every REFINE_DEG within
± STEP_DEG (Eq. 2's torsion plane at tan 2φ = k, φ = 5.2°, fell between the 10° planes: its
f 1.4 % low, its damage 13 % low at b = -0.1)."""
TRACTION_MAX = 0.05
"""A node is on a free surface when its least RMS traction is <= this fraction of its largest
(sqrt(λ₁/λ₃)); the 50 hot spots of the Ch 6 arm are at 0.000-0.008."""
SERIES_CHUNK = 4_000_000
"""Elements (samples x shear paths) computed at a time (32 MB a float64 array)."""


def findley_k(torsion_to_bending: float = TORSION_TO_BENDING) -> float:
    """k of Eq. (3) from t₋₁/f₋₁ (0.5 < ratio < 1: k > 0 needs r < 2)."""
    if not 0.5 < torsion_to_bending < 1.0:
        raise ValueError(f"t-1/f-1 must lie in (0.5, 1), got {torsion_to_bending}")
    r = 1.0 / torsion_to_bending
    return (2.0 - r) / (2.0 * np.sqrt(r - 1.0))


FINDLEY_K = findley_k()
"""k = 0.183 (Eq. 3 with t₋₁/f₋₁ = 0.59)."""


def uniaxial_factor(k: float) -> float:
    """U of Eq. (1): f = U σa for fully reversed uniaxial stress σa."""
    return 0.5 * (k + np.sqrt(1.0 + k * k))


def tensors(s6: np.ndarray) -> np.ndarray:
    """3x3 stress tensors of components ``s6[..., 6]`` (σx, σy, σz, τxy, τyz, τzx) [Pa]."""
    sx, sy, sz, txy, tyz, tzx = (s6[..., i] for i in range(6))
    return np.stack([np.stack([sx, txy, tzx], -1), np.stack([txy, sy, tyz], -1),
                     np.stack([tzx, tyz, sz], -1)], -2)


def surface_normal(s6: np.ndarray) -> tuple[np.ndarray, float]:
    """(n_s, sqrt(λ₁/λ₃)): the direction of least traction over the history ``s6`` (n, 6)
    and its RMS traction relative to the largest (module docstring)."""
    T = tensors(np.asarray(s6, dtype=float))
    w, v = np.linalg.eigh(np.einsum("tij,tjk->ik", T, T))
    ratio = float(np.sqrt(max(w[0], 0.0) / w[2])) if w[2] > 0 else 0.0
    return v[:, 0], ratio


def _basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the unit vector ``n`` to a right-handed frame."""
    a = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = np.cross(n, a)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def surface_planes(n_s: np.ndarray, step_deg: float = STEP_DEG
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(normals, shear directions), each (P, 3): the planes normal to the surface of outward
    normal ``n_s``, every ``step_deg`` over 180°, and their shear direction m = n_s × n."""
    e1, e2 = _basis(np.asarray(n_s, dtype=float) / np.linalg.norm(n_s))
    th = np.deg2rad(np.arange(0.0, 180.0, step_deg))
    n = np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2
    return n, np.cross(n_s, n)


def hemisphere_planes(step_deg: float = STEP_DEG) -> tuple[np.ndarray, np.ndarray]:
    """(normals, shear directions), each (Q, 3): normals over the hemisphere z >= 0 (polar
    angle every ``step_deg``, azimuth every ``step_deg`` / sin θ; on the equator over 180°
    only), each with shear directions every ``step_deg`` over 180° in its plane."""
    normals = [np.array([0.0, 0.0, 1.0])]
    for th in np.deg2rad(np.arange(step_deg, 90.0 + 1e-9, step_deg)):
        span = 180.0 if np.isclose(th, np.pi / 2) else 360.0
        m = max(1, int(round(span * np.sin(th) / step_deg)))
        for ph in np.deg2rad(np.arange(m) * span / m):
            normals.append(np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph),
                                     np.cos(th)]))
    psi = np.deg2rad(np.arange(0.0, 180.0, step_deg))
    ns, ms = [], []
    for n in normals:
        e1, e2 = _basis(n)
        ms.append(np.cos(psi)[:, None] * e1 + np.sin(psi)[:, None] * e2)
        ns.append(np.repeat(n[None, :], psi.size, axis=0))
    return np.concatenate(ns), np.concatenate(ms)


def _weights(n: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(6, Q): m·σ·n = s6 @ W for the components (σx, σy, σz, τxy, τyz, τzx)."""
    return np.stack([m[:, 0] * n[:, 0], m[:, 1] * n[:, 1], m[:, 2] * n[:, 2],
                     m[:, 0] * n[:, 1] + m[:, 1] * n[:, 0],
                     m[:, 1] * n[:, 2] + m[:, 2] * n[:, 1],
                     m[:, 2] * n[:, 0] + m[:, 0] * n[:, 2]])


@dataclass
class ShearCycles:
    """Cycles of many shear paths: path index, shear amplitude τa [Pa], largest normal stress
    on the plane during the cycle σn,max [Pa], count (1 or 0.5)."""

    series: np.ndarray
    tau_a: np.ndarray
    sn_max: np.ndarray
    count: np.ndarray


def _reduce(x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each column's turning points of ``x`` (n, Q), with the largest ``p`` since the
    previous kept sample (inclusive) and ``p`` at the point; padded at the end with the last
    value (a no-op for the counter) and -inf payloads."""
    n, q = x.shape
    keep = np.ones((n, q), dtype=bool)
    if n > 2:
        d = np.diff(x, axis=0)
        keep[1:-1] = d[:-1] * d[1:] <= 0.0
    counts = keep.sum(axis=0)
    pos = np.nonzero(keep.T)  # column-major: (column, sample) in order
    flat = pos[0] * n + pos[1]
    starts = np.empty_like(flat)
    starts[0] = 0
    starts[1:] = flat[:-1] + 1
    first = np.cumsum(counts) - counts
    starts[first] = pos[0][first] * n  # each column's first segment starts at its sample 0
    seg = np.maximum.reduceat(p.T.ravel(), starts)
    m = int(counts.max())
    col = pos[0]
    row = np.arange(flat.size) - np.repeat(first, counts)
    X = np.repeat(x[-1][None, :], m, axis=0)
    PS = np.full((m, q), -np.inf)
    PN = np.full((m, q), -np.inf)
    X[row, col] = x.T.ravel()[flat]
    PS[row, col] = seg
    PN[row, col] = p.T.ravel()[flat]
    return X, PS, PN


def count_shear(x: np.ndarray, p: np.ndarray, residue: str = "repeated") -> ShearCycles:
    """Rainflow (the four-point rule) of the columns of ``x`` (n, Q) [Pa], each cycle with
    the largest ``p`` (n, Q) from its first turning point to the point that closes it
    (module docstring); ``residue`` "repeated" (fed once more) or "half_cycles"."""
    X, PS, PN = _reduce(np.asarray(x, dtype=float), np.asarray(p, dtype=float))
    q = X.shape[1]
    cap = X.shape[0] + 2
    S = np.zeros((q, 2 * cap))
    G = np.full((q, 2 * cap), -np.inf)  # largest p from entry j to entry j + 1 (or to now)
    N = np.full((q, 2 * cap), -np.inf)  # p at entry j
    d = np.zeros(q, dtype=np.int64)
    out: list[tuple[np.ndarray, ...]] = []
    _feed(X, PS, PN, S, G, N, d, out)
    if residue == "half_cycles":
        j = np.arange(max(int(d.max()) - 1, 0))
        r, c = np.nonzero(j[None, :] < (d - 1)[:, None])
        out.append((r, 0.5 * np.abs(S[r, c] - S[r, c + 1]), G[r, c], np.full(r.size, 0.5)))
    elif residue == "repeated":
        m = int(d.max())
        rows = np.arange(q)[:, None]
        take = np.minimum(np.arange(m)[None, :], np.maximum(d - 1, 0)[:, None])
        valid = np.arange(m)[None, :] < d[:, None]
        RX = S[rows, take].T
        prev = np.where(take > 0, take - 1, np.maximum(d - 1, 0)[:, None])
        RP = np.where(valid, G[rows, prev], -np.inf).T
        RP[0] = np.maximum(RP[0], N[:, 0])
        RN = np.where(valid, N[rows, take], -np.inf).T
        _feed(RX, RP, RN, S.copy(), G.copy(), N.copy(), d.copy(), out)
    else:
        raise ValueError(f"residue must be 'repeated' or 'half_cycles', got {residue!r}")
    if not out:
        z = np.zeros(0)
        return ShearCycles(np.zeros(0, dtype=np.int64), z, z.copy(), z.copy())
    return ShearCycles(*(np.concatenate([o[i] for o in out]) for i in range(4)))


def _feed(X: np.ndarray, PS: np.ndarray, PN: np.ndarray, S: np.ndarray, G: np.ndarray,
          N: np.ndarray, d: np.ndarray, out: list) -> None:
    """Lock-step four-point rainflow over the columns (:mod:`.counting`'s rule) carrying the
    payloads G, N (module docstring); appends closed cycles
    (series, τa, σn,max, 1) to ``out``."""
    rows = np.arange(S.shape[0])
    for x, ps, pn in zip(X, PS, PN, strict=True):
        empty = d == 0
        it = np.maximum(d - 1, 0)
        top = S[rows, it]
        prev = S[rows, np.maximum(d - 2, 0)]
        dx = x - top
        extend = (d >= 2) & (dx * (top - prev) > 0.0)
        push = empty | ((dx != 0.0) & ~extend)
        G[rows, it] = np.where(empty, G[rows, it], np.maximum(G[rows, it], ps))
        e = rows[extend]
        if e.size:
            te = it[e]
            G[e, te - 1] = np.maximum(G[e, te - 1], G[e, te])
            S[e, te], G[e, te], N[e, te] = x[e], pn[e], pn[e]
        p = rows[push]
        if p.size:
            ip = d[p]
            S[p, ip], G[p, ip], N[p, ip] = x[p], pn[p], pn[p]
            d[p] += 1
        cand = rows[d >= 4]
        while cand.size:
            dc = d[cand]
            a, b, c, f = (S[cand, dc - i] for i in (4, 3, 2, 1))
            r = np.abs(b - c)
            hit = (r <= np.abs(a - b)) & (r <= np.abs(c - f))
            if not hit.any():
                break
            h, k = cand[hit], dc[hit]
            gb, gc = G[h, k - 3], G[h, k - 2]
            out.append((h, 0.5 * r[hit], np.maximum(gb, gc), np.ones(h.size)))
            G[h, k - 4] = np.maximum(G[h, k - 4], np.maximum(gb, gc))
            S[h, k - 3], G[h, k - 3], N[h, k - 3] = S[h, k - 1], G[h, k - 1], N[h, k - 1]
            d[h] -= 2
            cand = h[d[h] >= 4]


@dataclass
class NodePlanes:
    """One node's critical plane: its damage per pass (Findley cycles on the S-N curve), unit
    normal and shear direction, largest cycle f [Pa], whether the surface planes were
    searched (else the hemisphere) and the traction ratio sqrt(λ₁/λ₃), the rotation factor
    F, and the planes x shear directions searched."""

    damage: float
    normal: np.ndarray
    shear_dir: np.ndarray
    f_max: float
    surface: bool
    traction_ratio: float
    rotation_factor: float
    n_paths: int


def findley_node(s6: np.ndarray, reversals, k: float = FINDLEY_K,
                 step_deg: float = STEP_DEG, residue: str = "repeated") -> NodePlanes:
    """The critical plane of one node's stress history ``s6`` (n, 6) [Pa].

    ``reversals(σ_eq)``: 2Nf of fully reversed uniaxial amplitudes σ_eq [Pa] (the S-N curve
    with its endurance treatment, inf for no damage). Damage per path = Σ count / (2Nf / 2)
    of its cycles at σ_eq = max(τa + k σn,max, 0) / U (module docstring)."""
    s6 = np.asarray(s6, dtype=float)
    n_s, ratio = surface_normal(s6)
    surface = ratio <= TRACTION_MAX
    n, m = surface_planes(n_s, step_deg) if surface else hemisphere_planes(step_deg)
    damage, fmax = _paths(s6, n, m, reversals, k, residue)
    j = int(np.argmax(damage)) if damage.any() else int(np.argmax(fmax))
    if surface:  # refine within ± step_deg of the best plane
        e1, e2 = _basis(n_s / np.linalg.norm(n_s))
        th0 = np.arctan2(n[j] @ e2, n[j] @ e1)
        th = th0 + np.deg2rad(np.arange(-step_deg, step_deg + 1e-9, REFINE_DEG))
        n = np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2
        m = np.cross(n_s, n)
        damage, fmax = _paths(s6, n, m, reversals, k, residue)
        j = int(np.argmax(damage)) if damage.any() else int(np.argmax(fmax))
    return NodePlanes(float(damage[j]), n[j], m[j], float(fmax[j]), bool(surface), ratio,
                      rotation_factor(s6, n_s if surface else None, step_deg),
                      int(n.shape[0]))


def _paths(s6: np.ndarray, n: np.ndarray, m: np.ndarray, reversals, k: float, residue: str
           ) -> tuple[np.ndarray, np.ndarray]:
    """Per shear path (plane ``n``, direction ``m``): Findley damage and largest cycle f."""
    U = uniaxial_factor(k)
    damage = np.zeros(n.shape[0])
    fmax = np.zeros(n.shape[0])
    step = max(1, SERIES_CHUNK // max(1, s6.shape[0]))
    for i in range(0, n.shape[0], step):
        nn, mm = n[i:i + step], m[i:i + step]
        cyc = count_shear(s6 @ _weights(nn, mm), s6 @ _weights(nn, nn), residue)
        f = cyc.tau_a + k * cyc.sn_max
        with np.errstate(divide="ignore"):
            dmg = cyc.count / (0.5 * reversals(np.maximum(f, 0.0) / U))
        damage[i:i + step] = np.bincount(cyc.series, weights=dmg, minlength=nn.shape[0])
        np.maximum.at(fmax[i:i + step], cyc.series, f)
    return damage, fmax


def rotation_factor(s6: np.ndarray, n_s: np.ndarray | None, step_deg: float = STEP_DEG
                    ) -> float:
    """Kanazawa's F (module docstring) of the history ``s6`` (n, 6): over the planes normal
    to the surface ``n_s`` every REFINE_DEG, else over :func:`hemisphere_planes`."""
    n, m = surface_planes(n_s, REFINE_DEG) if n_s is not None else hemisphere_planes(step_deg)
    tau = s6 @ _weights(n, m)
    rng = tau.max(axis=0) - tau.min(axis=0)
    w = int(np.argmax(rng))
    if not rng[w] > 0:
        return 0.0
    n45 = (n[w] + m[w]) / np.sqrt(2.0)
    m45 = (m[w] - n[w]) / np.sqrt(2.0)
    t45 = s6 @ _weights(n45[None, :], m45[None, :])[:, 0]
    return float((t45.max() - t45.min()) / rng[w])
