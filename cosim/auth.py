"""Message authentication: every message of a run carries a MAC made with the run's own key.

A run has a secret key of 32 bytes (:func:`derive_run_key` from a secret and the run id). A
message of :mod:`cosim.wire` is a msgpack map of five fields (``0x85`` then the fields' bytes
``F``); signed, it is a map of six, the sixth ``"s"``: a 16-byte keyed BLAKE2b of the key
expression it is published on and of ``F``::

    raw = b"\x86" + F + b"\xa1s\xc4\x10" + blake2b(key=run_key, person="suscosim-msg-v1",
                                                digest_size=16)(keyexpr + b"\0" + F)

A reader without the key (a tap) ignores the extra field; a receiver with it rejects an
unsigned or badly signed message (:class:`AuthError`, counted) before decoding it. The key
expression is in the MAC: no replay on another channel or run. BLAKE2b: keyed natively, the
fastest keyed hash of :mod:`hashlib` (~1 us a message).

**A run instance's nonce.** One secret and run id can serve two runs (a sweep's ids repeat),
so the orchestrator draws a 16-byte nonce per run and every message is signed bound to it
(person ``suscosim-msg-v2`` over ``nonce + keyexpr + "\0" + F``), except the served scenario
(key alone), which announces the nonce (field ``session``, hex) for the nodes to bind to.

The key (:func:`run_key_from_env`): ``SUSCOSIM_RUN_KEY`` (hex, set by the orchestrator for
its nodes), else derived with the run id from the secret of ``SUSCOSIM_KEY_FILE`` (mode 0600,
e.g. ``RUN/run.key``) or ``SUSCOSIM_KEY``.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .errors import InputFileError, WireError

TAG_BYTES = 16
UNSIGNED_HEAD, SIGNED_HEAD = 0x85, 0x86  # msgpack fixmap of five fields, of six
SIG_FIELD = b"\xa1s\xc4\x10"  # the key "s" (fixstr) and the header of a 16-byte bin 8
SIG_BYTES = len(SIG_FIELD) + TAG_BYTES
KEY_BYTES = 32
ENV_RUN_KEY = "SUSCOSIM_RUN_KEY"
ENV_KEY_FILE = "SUSCOSIM_KEY_FILE"
ENV_KEY = "SUSCOSIM_KEY"
KEY_FILE_NAME = "run.key"
_PERSON = b"suscosim-msg-v1"
_PERSON_BOUND = b"suscosim-msg-v2"
NONCE_BYTES = 16
SESSION_FIELD = "session"  # the served scenario's field announcing the nonce (hex)
_CACHE_MAX = 256


class AuthError(WireError):
    """A message that is unsigned or whose signature does not match the run's key."""


class NoKeyError(InputFileError):
    """No run key could be found (exit 2)."""


def new_secret() -> bytes:
    return secrets.token_bytes(KEY_BYTES)


def derive_run_key(secret: bytes, run_id: str) -> bytes:
    """The key of run ``run_id`` from a secret: one secret serves many runs, each run has
    its own key (a message of one run never verifies under another)."""
    return hashlib.blake2b(run_id.encode(), key=hashlib.blake2b(secret).digest()[:64],
                           person=b"suscosim-run-key", digest_size=KEY_BYTES).digest()


def new_nonce() -> bytes:
    return secrets.token_bytes(NONCE_BYTES)


class RunKey:
    """Signs and verifies the messages of one run (of one instance of it, with ``nonce``)."""

    def __init__(self, key: bytes, nonce: bytes = b"") -> None:
        if not isinstance(key, bytes) or len(key) < 16:
            raise ValueError("a run key is at least 16 bytes")
        if not isinstance(nonce, bytes) or len(nonce) not in (0, NONCE_BYTES):
            raise ValueError(f"a run nonce is {NONCE_BYTES} bytes (or none)")
        self.key, self.nonce = key, nonce
        self._base = hashlib.blake2b(key=key, person=_PERSON_BOUND if nonce else _PERSON,
                                     digest_size=TAG_BYTES)
        if nonce:
            self._base.update(nonce)
        self._per: dict[str, Any] = {}

    def unbound(self) -> RunKey:  # what the served scenario is signed with
        return RunKey(self.key) if self.nonce else self

    def bound(self, nonce: bytes) -> RunKey:
        return RunKey(self.key, nonce)

    def _hasher(self, keyexpr: str) -> Any:
        h = self._per.get(keyexpr)
        if h is None:
            h = self._base.copy()
            h.update(keyexpr.encode() + b"\0")
            if len(self._per) < _CACHE_MAX:  # a flood of made-up keys cannot grow it
                self._per[keyexpr] = h
        return h

    def sign(self, keyexpr: str, body: bytes) -> bytes:
        """``body`` (a message of :func:`cosim.wire.encode`) signed for ``keyexpr``."""
        return _sign(self._hasher(keyexpr), body)

    def signer(self, keyexpr: str) -> Callable[[bytes], bytes]:  # its hasher prepared once
        base = self._base.copy()
        base.update(keyexpr.encode() + b"\0")
        return lambda body: _sign(base, body)

    def verify(self, keyexpr: str, raw: bytes) -> bytes:
        """``raw`` if signed with the run's key for ``keyexpr`` (else AuthError)."""
        if len(raw) <= SIG_BYTES or raw[0] != SIGNED_HEAD or \
                raw[-SIG_BYTES:-TAG_BYTES] != SIG_FIELD:
            raise AuthError("unsigned message (no signature field)")
        h = self._hasher(keyexpr).copy()
        h.update(memoryview(raw)[1:-SIG_BYTES])
        if not hmac.compare_digest(h.digest(), raw[-TAG_BYTES:]):
            raise AuthError("bad signature (not signed with this run's key)")
        return raw


def _sign(base: Any, body: bytes) -> bytes:
    """``body`` signed, the MAC from a copy of ``base`` (key and key expression in it)."""
    if not body or body[0] != UNSIGNED_HEAD:
        raise ValueError("not a message of five fields (cosim.wire.encode)")
    fields = memoryview(body)[1:]
    h = base.copy()
    h.update(fields)
    tag: bytes = h.digest()
    return b"\x86" + fields + SIG_FIELD + tag


def read_secret_file(path: str | Path) -> bytes:
    """A secret from a key file (hex, or any bytes); refuses a file others can read."""
    p = Path(path)
    try:
        mode = p.stat().st_mode
        data = p.read_bytes().strip()
    except OSError as exc:
        raise NoKeyError(str(p), f"cannot read the key file: {exc.strerror or exc}") from None
    if mode & 0o077:
        raise NoKeyError(str(p), f"key file is readable by group or others (mode "
                                 f"{mode & 0o777:o}): chmod 600 it")
    if len(data) < 16:
        raise NoKeyError(str(p), f"key file holds {len(data)} bytes, at least 16 expected")
    try:
        return bytes.fromhex(data.decode())
    except (UnicodeDecodeError, ValueError):
        return data


def write_secret_file(path: str | Path, secret: bytes) -> Path:
    """Write ``secret`` (hex) to ``path``, created with mode 0600 (never readable by others)."""
    p = Path(path)
    fd = os.open(p, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        os.fchmod(fd, 0o600)
        os.write(fd, secret.hex().encode() + b"\n")
    finally:
        os.close(fd)
    return p


def secret_from_env(environ: Mapping[str, str] | None = None) -> bytes | None:
    """The deployment secret of ``SUSCOSIM_KEY_FILE`` or ``SUSCOSIM_KEY``, if any."""
    env = os.environ if environ is None else environ
    if env.get(ENV_KEY_FILE):
        return read_secret_file(env[ENV_KEY_FILE])
    if env.get(ENV_KEY):
        secret = env[ENV_KEY].encode()
        if len(secret) < 16:
            raise NoKeyError(ENV_KEY, f"holds {len(secret)} bytes, at least 16 expected")
        return secret
    return None


def run_key_from_env(run_id: str, environ: Mapping[str, str] | None = None) -> bytes:
    """The run key a node uses (see the module's docstring); raises :class:`NoKeyError`."""
    env = os.environ if environ is None else environ
    direct = env.get(ENV_RUN_KEY)
    if direct:
        try:
            key = bytes.fromhex(direct)
        except ValueError:
            raise NoKeyError(ENV_RUN_KEY, "not a hex string") from None
        if len(key) < 16:
            raise NoKeyError(ENV_RUN_KEY, f"{len(key)} bytes, at least 16 expected")
        return key
    secret = secret_from_env(env)
    if secret is None:
        raise NoKeyError("run key", f"none for run '{run_id}': the messages of a run are "
                         "authenticated; give --key-file RUN_DIR/run.key (written by the "
                         f"orchestrator) or set {ENV_KEY_FILE} / {ENV_KEY} to the secret "
                         "the orchestrator uses")
    return derive_run_key(secret, run_id)


def served_scenario(key: str, raw: bytes, auth: RunKey | None
                    ) -> tuple[dict[str, Any], bytes | None]:
    """The resolved scenario a node fetched on ``key`` and the nonce it announces (None
    without a run key); WireError unless signed with the run's (unbound) key and whole."""
    from .wire import decode

    msg = decode(auth.unbound().verify(key, raw) if auth else raw)
    if msg.kind != "start" or not isinstance(msg.d.get("run"), dict):
        raise WireError("not a scenario")
    scenario = dict(msg.d)
    session = scenario.pop(SESSION_FIELD, None)
    if auth is None:
        return scenario, None
    try:
        nonce = bytes.fromhex(session) if isinstance(session, str) else b""
    except ValueError:
        nonce = b""
    if len(nonce) != NONCE_BYTES:
        raise WireError(f"the scenario announces no run nonce ('{SESSION_FIELD}': "
                        f"{session!r:.40})")
    return scenario, nonce
