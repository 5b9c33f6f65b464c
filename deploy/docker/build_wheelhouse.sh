#!/usr/bin/env bash
# The image's Python packages, fetched on the host: every wheel the project needs for
# CPython 3.11 on x86_64 glibc (Debian bookworm's python3), at the versions installed on this
# host where it has them, into build/wheelhouse/. The Dockerfile installs from it with
# `pip install --no-index`: nothing is fetched inside the build (no registry, no TLS there).
#
#   deploy/docker/build_wheelhouse.sh [OUT_DIR]         # default build/wheelhouse
#
# Pinning to the host's versions makes the containers compute what a local run computes
# (same numpy / pybullet / scipy builds): tests/deploy/test_docker_compose.py compares the
# tables. A stamp (digest of the requirements and pins) skips the download when nothing
# changed. Uses the host's pip and its configuration (index, proxy, CA certificates).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT="${1:-build/wheelhouse}"
PY="${PYTHON:-python3}"
mkdir -p "$OUT"

# requirements.txt: the project's dependencies (pyproject.toml) and setuptools to build it;
# constraints.txt: name==version, as installed on this host, of every distribution those
# dependencies need (their closure: unrelated packages installed here change nothing).
"$PY" - "$OUT" <<'PYEOF'
import re
import sys
import tomllib
from importlib import metadata
from pathlib import Path

out = Path(sys.argv[1])
project = tomllib.loads(Path("pyproject.toml").read_text())
deps = project["project"]["dependencies"]
reqs = [*deps, *project["build-system"]["requires"]]
(out / "requirements.txt").write_text("\n".join(reqs) + "\n")


def name_of(req: str) -> str:
    return re.split(r"[\s\[<>=!~;(]", req.strip(), maxsplit=1)[0].lower().replace("_", "-")


pins, todo, seen = [], [name_of(r) for r in deps], set()
while todo:
    name = todo.pop()
    if name in seen:
        continue
    seen.add(name)
    try:
        dist = metadata.distribution(name)
    except metadata.PackageNotFoundError:
        continue  # not installed here: the newest allowed version is fetched
    pins.append(f"{name}=={dist.version}")
    for req in dist.requires or []:
        if "extra ==" not in req:  # extras are not installed by a plain requirement
            todo.append(name_of(req))
(out / "constraints.txt").write_text("\n".join(sorted(pins)) + "\n")
PYEOF

STAMP="$(cat "$OUT/requirements.txt" "$OUT/constraints.txt" | sha256sum | cut -c1-16)"
if [ "$(cat "$OUT/.stamp" 2>/dev/null || true)" = "$STAMP" ]; then
  echo "build_wheelhouse: $OUT is up to date ($(ls "$OUT"/*.whl | wc -l) wheels)"
  exit 0
fi
# Wheels only, for the image's interpreter (CPython 3.11, manylinux up to glibc 2.36),
# whatever Python runs this script.
PLATFORMS=()
for minor in $(seq 36 -1 17); do PLATFORMS+=(--platform "manylinux_2_${minor}_x86_64"); done
PLATFORMS+=(--platform manylinux2014_x86_64 --platform manylinux2010_x86_64
            --platform manylinux1_x86_64)
rm -f "$OUT"/*.whl
"$PY" -m pip download --quiet --dest "$OUT" --only-binary=:all: \
  --python-version 3.11 --implementation cp --abi cp311 --abi abi3 --abi none \
  "${PLATFORMS[@]}" -r "$OUT/requirements.txt" -c "$OUT/constraints.txt"
echo "$STAMP" > "$OUT/.stamp"
echo "build_wheelhouse: $(ls "$OUT"/*.whl | wc -l) wheels in $OUT ($(du -sh "$OUT" | cut -f1))"
