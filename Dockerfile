# suscosim: one image for every node, the orchestrator, the router and the certificate helper.
# Built without any registry (docs/deployment.md, "Building the image"):
#
#   deploy/docker/build_image.sh          # = the three steps below, each skipped when current
#   deploy/docker/build_base.sh           # FROM image: debootstrap bookworm + python3, imported
#   deploy/docker/build_wheelhouse.sh     # build/wheelhouse: the wheels, fetched on the host
#   docker build -t suscosim .
#   docker run --rm --init suscosim run scenarios/ch3_step_quarter_car.toml --mode monolithic
#
# Nothing is downloaded during the build: pip installs from the wheelhouse with --no-index.
# docker-compose.yml runs one container per node around a Zenoh router.
ARG BASE=suscosim-base:bookworm

# The dependencies: a venv of Debian's Python 3.11, from the host-built wheelhouse. This
# layer changes only when the wheelhouse does.
FROM ${BASE} AS deps
COPY build/wheelhouse /wheels
RUN python3 -m venv /opt/suscosim \
    && /opt/suscosim/bin/pip install --no-cache-dir --no-index --find-links /wheels \
       --disable-pip-version-check -r /wheels/requirements.txt -c /wheels/constraints.txt

# The project's own wheel (setuptools from the wheelhouse, offline build isolation).
FROM deps AS wheel
WORKDIR /src
COPY pyproject.toml README.md ./
COPY cosim cosim
COPY nodes nodes
COPY orchestrator orchestrator
RUN /opt/suscosim/bin/pip wheel --no-cache-dir --no-index --find-links /wheels --no-deps \
    --disable-pip-version-check --wheel-dir /dist .

FROM ${BASE}
COPY --from=deps /opt/suscosim /opt/suscosim
COPY --from=wheel /dist /dist
RUN /opt/suscosim/bin/pip install --no-cache-dir --no-index --no-deps \
    --disable-pip-version-check /dist/*.whl && rm -rf /dist
ENV PATH=/opt/suscosim/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    PYTHONUNBUFFERED=1
WORKDIR /app
COPY scenarios scenarios
COPY deploy deploy
# Python as PID 1 ignores SIGTERM: run with an init (compose: init: true; docker run --init).
ENTRYPOINT ["suscosim"]
CMD ["--help"]
