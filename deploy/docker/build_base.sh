#!/usr/bin/env bash
# Build the project's base image without any registry: a Debian bookworm root file system
# made by debootstrap (minbase + Python 3.11 from Debian's packages) and `docker import`ed.
#
#   deploy/docker/build_base.sh [--force]        # tag: $SUSCOSIM_BASE or suscosim-base:bookworm
#
# Needs root, debootstrap, a running Docker engine and Debian's package mirror
# ($DEBIAN_MIRROR, default http://deb.debian.org/debian). The image is labelled with a
# digest of this recipe: when an image of that tag and recipe exists already, nothing is
# rebuilt (about 40-90 s otherwise), so CI builds it once per machine.
set -euo pipefail

TAG="${SUSCOSIM_BASE:-suscosim-base:bookworm}"
SUITE=bookworm
MIRROR="${DEBIAN_MIRROR:-http://deb.debian.org/debian}"
# python3-venv: the image's venv and its pip (ensurepip); openssl: deploy/zenoh/make_certs.sh.
PACKAGES="python3,python3-venv,openssl"
RECIPE="$(printf '%s|%s|%s|v1' "$SUITE" "$PACKAGES" "minbase" | sha256sum | cut -c1-16)"

if [ "${1:-}" != "--force" ] \
   && [ "$(docker image inspect -f '{{ index .Config.Labels "org.suscosim.base-recipe" }}' \
           "$TAG" 2>/dev/null || true)" = "$RECIPE" ]; then
  echo "build_base: $TAG is up to date (recipe $RECIPE)"
  exit 0
fi
for tool in debootstrap docker; do
  command -v "$tool" >/dev/null || { echo "build_base: '$tool' not found" >&2; exit 2; }
done
[ "$(id -u)" = 0 ] || { echo "build_base: debootstrap needs root" >&2; exit 2; }

ROOTFS="$(mktemp -d /tmp/suscosim-rootfs.XXXXXX)"
trap 'rm -rf "$ROOTFS"' EXIT
echo "build_base: debootstrap --variant=minbase $SUITE ($PACKAGES) into $ROOTFS"
debootstrap --variant=minbase --include="$PACKAGES" "$SUITE" "$ROOTFS" "$MIRROR" \
  > "$ROOTFS.log" 2>&1 || { tail -20 "$ROOTFS.log" >&2; exit 1; }
rm -f "$ROOTFS.log"
# Smaller and reproducible enough: no package lists, caches or logs in the image.
rm -rf "$ROOTFS"/var/lib/apt/lists/* "$ROOTFS"/var/cache/apt/*.bin \
       "$ROOTFS"/var/cache/apt/archives/*.deb "$ROOTFS"/var/log/*.log
tar -C "$ROOTFS" --numeric-owner -c . | docker import \
  --change "LABEL org.suscosim.base-recipe=$RECIPE" \
  --change 'ENV LANG=C.UTF-8' \
  --change 'CMD ["/bin/bash"]' \
  - "$TAG" >/dev/null
echo "build_base: $TAG built (recipe $RECIPE)"
