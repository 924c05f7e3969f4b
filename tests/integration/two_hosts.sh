#!/bin/sh
# Runs a scene across two "hosts": two network namespaces joined by a virtual ethernet link,
# each with its own address and a multicast route over the link (and only over the link).
# Host A runs `cosim run SCENE --remote NAME`; host B runs the `cosim join` line it prints.
# Usage: two_hosts.sh BIN_DIR SCENE RUNS_DIR PARTICIPANT
# Exits 77 when this machine cannot make network namespaces (the test then skips).
set -u
bin=$1 scene=$2 runs=$3 remote=$4

if ! unshare -n true 2>/dev/null; then
  echo "two_hosts: cannot create network namespaces here (needs unshare -rn first)"
  exit 77
fi
unshare -n sleep 600 </dev/null >/dev/null 2>&1 &
host_a=$!
unshare -n sleep 600 </dev/null >/dev/null 2>&1 &
host_b=$!
trap 'kill $host_a $host_b 2>/dev/null' EXIT
sleep 0.2

if ! ip link add cosim_a netns "$host_a" type veth peer name cosim_b netns "$host_b"; then
  echo "two_hosts: cannot create a veth pair here"
  exit 77
fi
link_up() {  # PID INTERFACE ADDRESS
  nsenter -t "$1" -n sh -c "ip link set lo up && ip addr add $3/24 dev $2 && ip link set $2 up \
    && ip route add 224.0.0.0/4 dev $2" || exit 1
}
link_up "$host_a" cosim_a 10.231.0.1
link_up "$host_b" cosim_b 10.231.0.2

coupler_out="$runs/host_a.out"
nsenter -t "$host_a" -n "$bin/cosim" run "$scene" --runs-dir "$runs" --quiet --network host \
  --remote "$remote" --startup-timeout 60 >"$coupler_out" 2>&1 &
coupler=$!
line=""
for _ in $(seq 1 600); do
  line=$(grep -m1 '^  cosim join ' "$coupler_out" 2>/dev/null) && break
  kill -0 "$coupler" 2>/dev/null || break
  sleep 0.1
done
if [ -z "$line" ]; then
  echo "two_hosts: cosim printed no join line"
  cat "$coupler_out"
  exit 1
fi
line=${line#  cosim }
nsenter -t "$host_b" -n sh -c "exec $bin/cosim $line" >"$runs/host_b.out" 2>&1 &
joined=$!
wait "$coupler"
code=$?
wait "$joined"
echo "--- host A (cosim run):"
cat "$coupler_out"
echo "--- host B (cosim join):"
cat "$runs/host_b.out"
exit $code
