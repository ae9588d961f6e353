#!/usr/bin/env bash
# Builds the tests under AddressSanitizer and UndefinedBehaviorSanitizer (the `sanitize` preset,
# build-sanitize/) and runs a fast subset that steps every stage: bodies, voxelising, blast, loads,
# the paper's fracture, the lattice and the deformable phase, contacts, checkpoints and scenes.
# Any report fails the run. Usage: tools/sanitize.sh [gtest filter]
set -euo pipefail
cd "$(dirname "$0")/.."
filter=${1:-'Body.*:Links.*:MassProperties.*:Components.*:Voxelise.*:Friedlander.*:KingeryBulmash.*:Exposure.*:Fracture.*:Lattice.DampingKeeps*:Lattice.OneAndTwoThreads*:Deformable.HandOff*:Deformable.PiecesAreLookedAt*:Collisions.*:Checkpoint.*:Scene.*:Simulation.*'}
cmake --preset sanitize >/dev/null
cmake --build --preset sanitize --target spall_tests
ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 build-sanitize/spall_tests --gtest_filter="$filter" --gtest_brief=1
