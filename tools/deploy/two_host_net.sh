# Two hosts on one machine (sourced by tools/demo.sh --two-host): two network namespaces, "robot"
# and "base", joined by a veth pair, as two machines on one LAN segment. Run inside `./snapnav bus`
# (a namespace of its own, so nothing here touches the machine's network):
#   - each namespace holds one end of the veth pair with a link-local address (169.254.76.1 and
#     .2/16: addresses that exist only there), its loopback, and no other interface or route: no
#     default route, nothing can leave;
#   - multicast is routed over the veth (224.0.0.0/4 dev veth-...), and the bus URL has ttl=1, as
#     on a LAN without a router;
#   - the veth has Ethernet's MTU, 1500 bytes (TWO_HOST_MTU: 9000 for jumbo frames), so LCM's
#     64 KB datagrams are cut into IP fragments as on a real LAN.
# Each namespace is held by a `sleep` process; `nsenter` runs commands in it. The namespaces end
# with their holders (two_host_down, or when the bus namespace ends).
#
#   two_host_up          create them; sets TWO_HOST_LCM_URL
#   on_robot CMD...      run CMD in the robot's namespace (on_base: the base's)
#   exec_on HOST CMD...  exec CMD in HOST's namespace (robot or base): `(exec_on base CMD) &` gives
#                        CMD's own pid in $!, to signal it
#   two_host_describe    one line per host: address, routes
#   two_host_down        end the holders

TWO_HOST_LCM_URL='udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304'
TWO_HOST_ROBOT_ADDR=169.254.76.1
TWO_HOST_BASE_ADDR=169.254.76.2
TWO_HOST_HOLDERS=()
TWO_HOST_MTU=${TWO_HOST_MTU:-1500}

two_host_up() {
  local name addr holder
  ip link add veth-robot type veth peer name veth-base ||
    { echo "two-host: cannot create the veth pair (needs CAP_NET_ADMIN: run inside ./snapnav bus)" >&2; return 1; }
  for name in robot base; do
    unshare -n sleep infinity &
    holder=$!
    TWO_HOST_HOLDERS+=("$holder")
    # Wait until the holder is in its own namespace.
    for _ in $(seq 100); do
      [ "$(readlink "/proc/$holder/ns/net" 2>/dev/null)" != "$(readlink /proc/self/ns/net)" ] && break
      sleep 0.02
    done
    addr=$TWO_HOST_ROBOT_ADDR
    [ "$name" = base ] && addr=$TWO_HOST_BASE_ADDR
    ip link set "veth-$name" netns "$holder"
    nsenter -t "$holder" -n sh -c "
      set -e
      ip link set lo up
      ip link set veth-$name addrgenmode none mtu $TWO_HOST_MTU
      ip addr add $addr/16 dev veth-$name
      ip link set veth-$name up multicast on
      ip route add 224.0.0.0/4 dev veth-$name" ||
      { echo "two-host: cannot configure the $name namespace" >&2; return 1; }
  done
  TWO_HOST_ROBOT_PID=${TWO_HOST_HOLDERS[0]}
  TWO_HOST_BASE_PID=${TWO_HOST_HOLDERS[1]}
  export TWO_HOST_LCM_URL
  # The link is up when both ends have a carrier (the bus check that follows tests it end to end).
  for _ in $(seq 100); do
    on_robot ip -o link show veth-robot | grep -q "state UP" &&
      on_base ip -o link show veth-base | grep -q "state UP" && return 0
    sleep 0.05
  done
  echo "two-host: the veth pair between robot and base did not come up" >&2
  return 1
}

on_robot() { LCM_DEFAULT_URL="$TWO_HOST_LCM_URL" nsenter -t "$TWO_HOST_ROBOT_PID" -n -- "$@"; }
on_base() { LCM_DEFAULT_URL="$TWO_HOST_LCM_URL" nsenter -t "$TWO_HOST_BASE_PID" -n -- "$@"; }
exec_on() {
  local holder=$TWO_HOST_ROBOT_PID
  [ "$1" = base ] && holder=$TWO_HOST_BASE_PID
  shift
  LCM_DEFAULT_URL="$TWO_HOST_LCM_URL" exec nsenter -t "$holder" -n -- "$@"
}

two_host_describe() {
  local name
  for name in robot base; do
    printf '%s: %s, mtu %s; routes: %s\n' "$name" \
      "$("on_$name" ip -brief addr show "veth-$name" | tr -s ' ')" "$TWO_HOST_MTU" \
      "$("on_$name" ip route show | tr '\n' ';' | sed 's/;$//')"
  done
}

two_host_down() {
  local p
  for p in "${TWO_HOST_HOLDERS[@]:-}"; do [ -n "$p" ] && kill "$p" 2>/dev/null || true; done
  TWO_HOST_HOLDERS=()
}
