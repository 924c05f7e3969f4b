#!/bin/sh
# Runs a test in its own network namespace with loopback multicast (no root needed), so
# multi-process tests neither need nor disturb the host's network. Where user namespaces are not
# allowed the test runs on the host: runs stay isolated by their own port and group.
if unshare -rn true 2>/dev/null; then
  exec unshare -rn sh -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec "$@"' sh "$@"
fi
exec "$@"
