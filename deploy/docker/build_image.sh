#!/usr/bin/env bash
# The suscosim image, with no registry: base image, wheelhouse, `docker build`.
#
#   deploy/docker/build_image.sh [TAG]      # default suscosim:latest
#
# Each step is skipped when it is current (base: recipe label; wheelhouse: stamp; docker
# build: its layer cache), so a second call with unchanged sources takes seconds.
set -euo pipefail
cd "$(dirname "$0")/../.."
TAG="${1:-suscosim:latest}"
BASE="${SUSCOSIM_BASE:-suscosim-base:bookworm}"
SUSCOSIM_BASE="$BASE" deploy/docker/build_base.sh
deploy/docker/build_wheelhouse.sh build/wheelhouse
# DOCKER_BUILDKIT=0: the classic builder ships with every engine (BuildKit's client, buildx,
# is a separate package); nothing here needs BuildKit. The two build stages are tagged too
# (suscosim-build:deps, :wheel) so that pruning the untagged leftovers of earlier builds
# keeps the layer cache: the dependency layer (~1 GB, minutes) is rebuilt only when the
# wheelhouse changes, a source change costs the project's wheel alone.
LOG="$(mktemp /tmp/suscosim-build.XXXXXX.log)"
build() {  # build TAG [--target STAGE]
  local tag=$1; shift
  if ! DOCKER_BUILDKIT=0 docker build --build-arg BASE="$BASE" -t "$tag" "$@" . \
       >>"$LOG" 2>&1; then
    tail -30 "$LOG" >&2
    echo "build_image: docker build of $tag failed (whole log: $LOG)" >&2
    exit 1
  fi
}
build suscosim-build:deps --target deps
build suscosim-build:wheel --target wheel
build "$TAG"
rm -f "$LOG"
# untagged images of earlier builds of this Dockerfile (all carry the base image's label)
docker image prune -f --filter label=org.suscosim.base-recipe >/dev/null
echo "build_image: $TAG built from $BASE"
