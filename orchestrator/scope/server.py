"""The scope's web server (stdlib ``http.server``, one thread per request, in a thread).

    GET /                 the page (scope.html)
    GET /data?since=K     JSON: the samples of steps k > K of every plotted line, progress,
                          steps/s, node states, fatigue numbers, damage map (``K`` default -1:
                          everything kept); see :meth:`ScopeState.snapshot`
    GET /meta             JSON: run id, lines and their units, the damage map's geometry
    GET /<file>           the page's script and style, and the vendored uPlot files

Loopback only unless told otherwise (``--host``): the page shows a run's data to whoever
reaches the port.
"""

from __future__ import annotations

import json
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


def _handler(state: ScopeState) -> type[BaseHTTPRequestHandler]:
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
                if url.path == "/data":
                    q = parse_qs(url.query)
                    try:
                        since = int(q.get("since", ["-1"])[0])
                    except ValueError:
                        self._json({"error": "since: expected a step index (integer)"}, 400)
                        return
                    self._json(state.snapshot(since))
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
    """The HTTP server on ``host:port`` (port 0: a free one), serving in a thread."""

    def __init__(self, state: ScopeState, host: str = "127.0.0.1", port: int = 0) -> None:
        self.httpd = ThreadingHTTPServer((host, port), _handler(state))
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
