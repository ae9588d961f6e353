#!/usr/bin/env bash
# The Blender add-on, installed from its zip into a fresh user folder and driven through bpy in
# Debian's Blender, headless (tests/blender_addon_test.py says what it checks).
#   tests/blender_addon.sh SPALL ADDON.zip WORKDIR
set -euo pipefail
spall=$(realpath "$1"); zip=$(realpath "$2"); dir=$3
rm -rf "$dir" && mkdir -p "$dir/scripts"
# The add-on installs into BLENDER_USER_SCRIPTS, not the user's own Blender folders.
BLENDER_USER_SCRIPTS="$dir/scripts" blender -b --factory-startup --python-exit-code 1 \
  --python "$(dirname "$0")/blender_addon_test.py" -- "$zip" "$spall" "$dir" > "$dir/blender.log" 2>&1 \
  || { grep -E "blender_addon_test|Error|Traceback|line [0-9]" "$dir/blender.log" | tail -15; exit 1; }
grep "blender_addon_test" "$dir/blender.log"
grep -q "blender_addon_test: passed" "$dir/blender.log"
