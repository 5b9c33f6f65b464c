#!/bin/sh
# A private certificate authority and the certificates of a suscosim deployment (openssl).
#
#   deploy/zenoh/make_certs.sh OUT_DIR [ROUTER_HOST ...]
#
# Writes into OUT_DIR (created, mode 700):
#   ca.pem, ca-key.pem                the CA (keep ca-key.pem off the machines that run nodes)
#   router.pem, router-key.pem        the router's certificate; subject alternative names:
#                                     router, localhost, 127.0.0.1 and every ROUTER_HOST
#                                     (a DNS name or an IPv4/IPv6 address the nodes connect to)
#   <name>.pem, <name>-key.pem        one client certificate per participant, common name =
#                                     <name>: orchestrator plant tyre_road controller recorder
#                                     fatigue (allowed to publish by router.json5) and observer
#                                     (a tap: may subscribe, may not publish)
#   suscosim.key                      the deployment's shared secret (hex, mode 600): every
#                                     participant given SUSCOSIM_KEY_FILE=<it> derives each
#                                     run's message-signing key from it (cosim/auth.py)
# ROUTER_HOSTS="h1 h2" adds router names like the arguments (for docker compose). Set
# CLIENTS="a b c" to choose other client names, DAYS to change the validity (default 365).
# Existing files are kept: run it again with a new name to add one client.
# Keys are ECDSA P-256 in PKCS#8 (what Zenoh's rustls reads).
set -eu

if [ $# -lt 1 ]; then
    echo "usage: $0 OUT_DIR [ROUTER_HOST ...]" >&2
    exit 2
fi
command -v openssl >/dev/null 2>&1 || { echo "$0: needs openssl" >&2; exit 2; }
OUT=$1
shift
# shellcheck disable=SC2086  # ROUTER_HOSTS is a space-separated list
set -- "$@" ${ROUTER_HOSTS:-}
DAYS=${DAYS:-365}
# >>> generated names by python -m orchestrator.compose_gen from cosim/node_kinds.py: do not edit
CLIENTS=${CLIENTS:-"orchestrator plant tyre_road controller recorder fatigue observer"}
# <<< generated names
mkdir -p "$OUT"
chmod 700 "$OUT"
umask 077

key() {  # key FILE
    [ -f "$1" ] || openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1"
}

if [ ! -f "$OUT/ca.pem" ]; then
    key "$OUT/ca-key.pem"
    openssl req -x509 -new -key "$OUT/ca-key.pem" -sha256 -days "$DAYS" \
        -subj "/CN=suscosim-ca" -out "$OUT/ca.pem" \
        -addext "basicConstraints=critical,CA:TRUE" \
        -addext "keyUsage=critical,keyCertSign,cRLSign"
fi

sign() {  # sign NAME EXTENSIONS
    [ -f "$OUT/$1.pem" ] && return 0
    key "$OUT/$1-key.pem"
    openssl req -new -key "$OUT/$1-key.pem" -subj "/CN=$1" -out "$OUT/$1.csr"
    printf '%s\n' "$2" > "$OUT/$1.ext"
    openssl x509 -req -in "$OUT/$1.csr" -CA "$OUT/ca.pem" -CAkey "$OUT/ca-key.pem" \
        -CAcreateserial -sha256 -days "$DAYS" -extfile "$OUT/$1.ext" -out "$OUT/$1.pem" \
        2>/dev/null
    rm -f "$OUT/$1.csr" "$OUT/$1.ext"
}

SAN="DNS:router,DNS:localhost,IP:127.0.0.1"
for host in "$@"; do
    case $host in
        *[!0-9.]*) case $host in *:*) SAN="$SAN,IP:$host" ;; *) SAN="$SAN,DNS:$host" ;; esac ;;
        *) SAN="$SAN,IP:$host" ;;
    esac
done
COMMON="basicConstraints=critical,CA:FALSE
keyUsage=critical,digitalSignature"
sign router "$COMMON
extendedKeyUsage=serverAuth,clientAuth
subjectAltName=$SAN"
for name in $CLIENTS; do
    sign "$name" "$COMMON
extendedKeyUsage=clientAuth"
done
# The run-key secret (cosim/auth.py): copy it, like the CA, to every machine of a deployment.
[ -f "$OUT/suscosim.key" ] || openssl rand -hex 32 > "$OUT/suscosim.key"
chmod 644 "$OUT"/*.pem
chmod 600 "$OUT"/*-key.pem "$OUT/suscosim.key"
echo "certificates in $OUT (router names: $SAN)"
