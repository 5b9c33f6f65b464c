# suscosim: one image for every node, the orchestrator and the certificate helper.
#
#   docker build -t suscosim .
#   docker run --rm suscosim run scenarios/ch3_step_quarter_car.toml --mode monolithic
#
# docker-compose.yml runs one container per node around an eclipse/zenoh router; see
# docs/deployment.md.
FROM python:3.11-slim

# openssl: deploy/zenoh/make_certs.sh (the compose 'certs' service).
RUN apt-get update \
    && apt-get install -y --no-install-recommends openssl \
    && rm -rf /var/lib/apt/lists/*

WORKDIR /app
# The package first (the layer that changes least), then scenarios and deployment files.
COPY pyproject.toml README.md ./
COPY cosim cosim
COPY nodes nodes
COPY orchestrator orchestrator
RUN pip install --no-cache-dir .
COPY scenarios scenarios
COPY deploy deploy

ENV PYTHONUNBUFFERED=1
ENTRYPOINT ["suscosim"]
CMD ["--help"]
