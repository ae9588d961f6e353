#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (build-fuzz/) and runs each for SECONDS (default 60)
# from the seed corpus in fuzz/corpus/. Crashes land in fuzz/crashes/; each one found becomes a
# regression test under tests/. Usage: tools/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
cmake --preset fuzz > /dev/null
cmake --build --preset fuzz
mkdir -p fuzz/crashes build-fuzz/corpus/scene build-fuzz/corpus/mesh
export ASAN_OPTIONS=detect_leaks=0
for target in scene mesh; do
  echo "fuzz_$target: $seconds s"
  # New inputs go to build-fuzz/corpus (not committed); the seeds stay read-only.
  build-fuzz/fuzz_$target -max_total_time="$seconds" -max_len=65536 -timeout=20 -rss_limit_mb=4096 \
    -artifact_prefix=fuzz/crashes/$target- build-fuzz/corpus/$target fuzz/corpus/$target
done
echo "fuzz: no crash in ${seconds} s per target"
