#!/usr/bin/env bash
# lcm-spy (Java) decodes snapnav types written by a C++ process.
set -euo pipefail
BIN="$1"; JAR="$2"; SRC="$(dirname "$0")"
TMP="$(mktemp -d)"; trap 'rm -rf "$TMP"' EXIT
"$BIN/bus-check" publish --count 3 --sizes 100 --rate-hz 1000 --lcm-url "file://$TMP/p.lcmlog?mode=w" 2>/dev/null
CP="$JAR:/usr/share/java/lcm.jar"
javac -nowarn -cp "$CP" -d "$TMP" "$SRC/SpyTypesCheck.java"
java -cp "$TMP:$CP" SpyTypesCheck "$JAR" "$TMP/p.lcmlog"
