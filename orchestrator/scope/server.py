"""The scope's web server (stdlib ``http.server``, in a thread): ``GET /`` the page, ``/data?
since=K&coupling_since=C`` :meth:`ScopeState.snapshot`, ``/meta``, the page's files. A request
whose ``Host`` header names the server by no name it answers to (:func:`allowed_hosts`) gets
403, so a DNS-rebinding page cannot read the run's data through the browser.
"""

from __future__ import annotations

import ipaddress
import json
import socket
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

from .state import ScopeState

STATIC = Path(__file__).resolve().parent
FILES = {"/": ("scope.html", "text/html; charset=utf-8"),
         "/scope.js": ("scope.js", "text/javascript; charset=utf-8"),
         "/scope.css": ("scope.css", "text/css; charset=utf-8"),
         "/uPlot.iife.min.js": ("uPlot.iife.min.js", "text/javascript; charset=utf-8"),
         "/uPlot.min.css": ("uPlot.min.css", "text/css; charset=utf-8"),
         "/uPlot.LICENSE": ("uPlot.LICENSE", "text/plain; charset=utf-8")}


LOOPBACK_NAMES = ("localhost", "127.0.0.1", "[::1]")  # a loopback scope's names


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def _is_wildcard(host: str) -> bool:
    return host.strip("[]") in ("", "0.0.0.0", "::")


def allowed_hosts(host: str) -> tuple[set[str], bool]:
    """The ``Host`` names a scope on ``host`` answers to; whether any IP literal is too."""
    names = set(LOOPBACK_NAMES)
    if _is_loopback(host):
        return names, False
    if not _is_wildcard(host):
        bare = host.strip("[]").lower()
        names.add(f"[{bare}]" if ":" in bare else bare)
    for name in (socket.gethostname(), socket.getfqdn()):
        if name:
            names.add(name.lower())
    return names, _is_wildcard(host)


def host_header_ok(value: str | None, names: set[str], any_ip: bool, port: int) -> bool:
    """Whether a ``Host`` header names this server (with ``port``, or none for port 80)."""
    if not value:
        return False
    value = value.strip().lower()
    if value.startswith("["):
        name, _, rest = value.partition("]")
        name += "]"
        given = rest[1:] if rest.startswith(":") else None
        if rest and given is None:
            return False
    else:
        name, sep, given_s = value.rpartition(":")
        if not sep:
            name, given_s = value, ""
        given = given_s if sep else None
    if (given if given is not None else "80") != str(port):
        return False
    if name in names:
        return True
    if any_ip:
        try:
            ipaddress.ip_address(name.strip("[]"))
            return name.startswith("[") == (":" in name)  # IPv6 only in brackets
        except ValueError:
            return False
    return False


def _handler(state: ScopeState, names: set[str] | None = None,
             any_ip: bool = False) -> type[BaseHTTPRequestHandler]:
    """The request handler (``names`` None: every Host accepted)."""
    class Handler(BaseHTTPRequestHandler):
        server_version = "suscosim-scope"

        def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 (stdlib name)
            pass  # quiet: one line per poll would drown the terminal

        def _send(self, code: int, body: bytes, ctype: str) -> None:
            self.send_response(code)
            self.send_header("Content-Type", ctype)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(body)

        def _json(self, obj: Any, code: int = 200) -> None:
            body = json.dumps(obj, separators=(",", ":"), allow_nan=False).encode()
            self._send(code, body, "application/json")

        def do_GET(self) -> None:  # noqa: N802 (stdlib name)
            url = urlsplit(self.path)
            try:
                host = self.headers.get("Host")
                addr = self.server.server_address  # (host, port) of an IP socket
                port = int(addr[1]) if isinstance(addr, tuple) else 0
                if names is not None and not host_header_ok(host, names, any_ip, port):
                    self._json({"error": f"Host {host!r}: this scope answers to "
                                         f"{', '.join(sorted(names))} with port {port} "
                                         "(serve it with --host to be reached by another "
                                         "name)"}, 403)
                    return
                if url.path == "/data":
                    q = parse_qs(url.query)
                    try:
                        since = int(q.get("since", ["-1"])[0])
                        c_since = int(q.get("coupling_since", ["-1"])[0])
                    except ValueError:
                        self._json({"error": "since, coupling_since: expected a step index "
                                             "(integer)"}, 400)
                        return
                    self._json(state.snapshot(since, coupling_since=c_since))
                elif url.path == "/meta":
                    self._json(state.meta())
                elif url.path in FILES:
                    name, ctype = FILES[url.path]
                    self._send(200, (STATIC / name).read_bytes(), ctype)
                else:
                    self._json({"error": f"no such page: {url.path}"}, 404)
            except (BrokenPipeError, ConnectionResetError):
                pass  # the browser went away mid-answer

    return Handler


class ScopeServer:
    def __init__(self, state: ScopeState, host: str = "127.0.0.1", port: int = 0) -> None:
        self.allowed_names, any_ip = allowed_hosts(host)
        self.httpd = ThreadingHTTPServer((host, port), _handler(state, self.allowed_names, any_ip))
        self.httpd.daemon_threads = True
        self._thread = threading.Thread(target=self.httpd.serve_forever, name="scope-http",
                                        daemon=True)

    @property
    def url(self) -> str:
        host, port = self.httpd.server_address[:2]
        # an IP socket's host is a str (typeshed also allows the bytes of a Unix socket)
        name = host.decode() if isinstance(host, bytes) else str(host)
        name = f"[{name}]" if ":" in name else name
        return f"http://{name}:{port}/"

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()
