"""A Docker engine for the deployment tests: is one reachable, which compose, a project.

``unavailable()`` gives the reason a docker test must be skipped (no client, no engine, no
compose, no way to build the base image), or None. ``Project`` drives one compose project
(its own name, so parallel or leftover projects never mix) and always takes it down.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
from datetime import UTC, datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
IMAGE = "suscosim:latest"
BASE = os.environ.get("SUSCOSIM_BASE", "suscosim-base:bookworm")


def _run(argv: list[str], timeout: float = 60.0, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(argv, capture_output=True, text=True, timeout=timeout, **kw)


def compose_command() -> list[str] | str:
    """The compose CLI (``docker compose`` v2, else Debian's ``docker-compose`` 1.29), or why
    there is none."""
    if shutil.which("docker") and _run(["docker", "compose", "version"]).returncode == 0:
        return ["docker", "compose"]
    if shutil.which("docker-compose") and _run(["docker-compose", "version"]).returncode == 0:
        return ["docker-compose"]
    return "neither the docker compose plugin nor docker-compose is installed"


def engine_unavailable() -> str | None:
    """Why no Docker engine answers here, or None."""
    if shutil.which("docker") is None:
        return "no docker client (apt-get install docker.io)"
    try:
        res = _run(["docker", "info", "--format", "{{.ServerVersion}}"], timeout=20)
    except subprocess.TimeoutExpired:
        return "the Docker engine does not answer 'docker info' within 20 s"
    if res.returncode != 0 or not res.stdout.strip():
        text = " ".join((res.stderr or res.stdout).split())[:200]
        return f"no Docker engine reachable (start dockerd as root; docker info: {text})"
    return None


def unavailable() -> str | None:
    """Why the docker tests cannot run here (reason for the skip), or None."""
    reason = engine_unavailable()
    if reason:
        return reason
    compose = compose_command()
    if isinstance(compose, str):
        return compose + " (apt-get install docker-compose)"
    if _run(["docker", "image", "inspect", BASE]).returncode != 0 and (
            shutil.which("debootstrap") is None or os.geteuid() != 0):
        return (f"no base image {BASE} and it cannot be built here (needs root and "
                "debootstrap): run deploy/docker/build_base.sh as root")
    return None


_built: list[bool] = []


def build_image() -> None:
    """Build (or find current) the base image, the wheelhouse and the project image; once
    per test session (a current image still costs ~15 s of build-context uploads)."""
    if _built:
        return
    res = _run(["bash", str(ROOT / "deploy/docker/build_image.sh"), IMAGE], timeout=1500,
               cwd=ROOT)
    assert res.returncode == 0, f"image build failed:\n{res.stdout}\n{res.stderr}"
    _built.append(True)


def free_port() -> int:
    """A TCP port free on this host now (for a published router port)."""
    with socket.socket() as s:
        s.bind(("0.0.0.0", 0))
        return s.getsockname()[1]


def inspect(container: str) -> dict:
    res = _run(["docker", "inspect", container])
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)[0]


def finished_at(container: str) -> datetime:
    """When the engine saw the container's process end (its own clock, ns resolution)."""
    text = inspect(container)["State"]["FinishedAt"]  # e.g. 2026-12-01T21:10:03.123456789Z
    head, _, frac = text.rstrip("Z").partition(".")
    return datetime.fromisoformat(f"{head}.{(frac + '000000')[:6]}")


def sigterm_times(since: float, until: float) -> dict[str, datetime]:
    """Container id -> when the engine sent it SIGTERM (its 'kill' events, signal 15),
    between two Unix times."""
    res = _run(["docker", "events", "--since", f"{since:.3f}", "--until", f"{until:.3f}",
                "--filter", "type=container", "--filter", "event=kill",
                "--format", "{{json .}}"], timeout=30)
    assert res.returncode == 0, res.stderr
    out: dict[str, datetime] = {}
    for line in res.stdout.splitlines():
        ev = json.loads(line)
        if ev.get("Actor", {}).get("Attributes", {}).get("signal") == "15":
            when = datetime.fromtimestamp(ev["timeNano"] / 1e9, UTC).replace(tzinfo=None)
            out.setdefault(ev["Actor"]["ID"], when)
    return out


class Project:
    """One compose project: ``docker compose -p NAME -f FILE ...`` with its environment."""

    def __init__(self, name: str, files: list[Path], env: dict[str, str]):
        compose = compose_command()
        assert not isinstance(compose, str), compose
        self.name = name
        self.argv = [*compose, "-p", name, "--project-directory", str(ROOT)]
        for f in files:
            self.argv += ["-f", str(f)]
        self.env = dict(os.environ, **env)

    def compose(self, *args: str, timeout: float = 180.0, check: bool = True
                ) -> subprocess.CompletedProcess:
        res = _run([*self.argv, *args], timeout=timeout, env=self.env, cwd=ROOT)
        if check:
            assert res.returncode == 0, f"compose {' '.join(args)}:\n{res.stdout}\n{res.stderr}"
        return res

    def container(self, service: str) -> str:
        """The id of the service's (single) container, running or exited."""
        out = self.compose("ps", "-a", "-q", service).stdout.split()
        assert len(out) == 1, f"{service}: containers {out}"
        return out[0]

    def volume_dir(self, volume: str) -> Path | None:
        """The host folder of one of the project's named volumes, if this process can read
        it (root, local driver); else None (go through a container)."""
        res = _run(["docker", "volume", "inspect", "-f", "{{.Mountpoint}}",
                    f"{self.name}_{volume}"])
        path = Path(res.stdout.strip()) if res.returncode == 0 else None
        return path if path and os.access(path, os.R_OK | os.X_OK) else None

    def logs(self) -> str:
        return self.compose("logs", "--no-color", check=False).stdout

    def down(self) -> None:
        """Remove the containers, network and volumes of the project (never fails)."""
        try:
            self.compose("down", "-v", "--remove-orphans", "-t", "3", check=False,
                         timeout=120)
        except subprocess.TimeoutExpired:
            pass
