#!/usr/bin/env bash
# Imports the real reference recordings and checks the message counts of each channel.
#   tools/importers/check_reference_data.sh [BIN_DIR]     (default: build/bin)
# Not a ctest test: ../shared/data exists only beside the development checkout
# (SNAPNAV_SHARED_DATA overrides its location); the Malaga rawlog comes with mrpt-common.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/build/bin}
data=${SNAPNAV_SHARED_DATA:-$root/../shared/data}
malaga="/usr/share/mrpt/datasets/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
failures=0

# check NAME "CHANNEL=COUNT ..." log-import ARGS...
check() {
  local name=$1 expected=$2 summary status=0
  shift 2
  summary=$("$bin/log-import" "$@" --out "$out/$name.lcmlog" --quiet 2>&1) || status=$?
  if [[ $status -ne 0 ]]; then
    echo "FAIL $name: log-import exited with status $status"; echo "$summary"; failures=$((failures + 1)); return
  fi
  local pair channel count
  for pair in $expected; do
    channel=${pair%%=*} count=${pair#*=}
    if ! grep -Eq "^  $channel +$count " <<<"$summary"; then
      echo "FAIL $name: expected $count messages on $channel"; echo "$summary"; failures=$((failures + 1)); return
    fi
  done
  echo "ok   $name: $expected ($(grep -E '^import time' <<<"$summary"))"
}

check malaga "LASER_SCAN=225 ODOMETRY=224" rawlog "$malaga"
check mit-csail "LASER_SCAN=1988 ODOMETRY=1988 POSE_CARMEN=1988" carmen "$data/laser/mit-csail.clf"
check csail-corrected "LASER_SCAN=406 ODOMETRY=1988 POSE_CARMEN=406" carmen "$data/laser/csail-corrected.log.gz"
exit $((failures > 0))
