#!/usr/bin/env bash
# spall's lattice step against Debian's ESyS-Particle on the same lattice, back to back on this
# machine: a 60^3 cubic block, a particle per voxel, each bonded to its six neighbours (ESyS: a
# brittle beam; spall: its beam bond with the volumetric term, damping and crushing, as in a run).
# Prints both rates and their ratio (issue 49).
#
#   tools/bench_peers.sh [--install] [--steps N] [BUILD_DIR]      (BUILD_DIR: build)
#
# --install installs Debian's esys-particle first when it is missing (as root). ESyS runs with 1
# and with 2 workers (a master process beside them), spall with every core (spall_bench).
set -euo pipefail
install=0; steps=100; build=build
while [ $# -gt 0 ]; do
    case "$1" in
        --install) install=1 ;;
        --steps) steps=${2:?--steps needs a number}; shift ;;
        -h|--help) sed -n 2,10p "$0"; exit 0 ;;
        -*) echo "bench_peers.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
        *) build=$1 ;;
    esac
    shift
done
root=$(cd "$(dirname "$0")/.." && pwd)
bench=$(cd "$build" && pwd)/spall_bench
[ -x "$bench" ] || { echo "bench_peers.sh: no spall_bench at $bench (build first: tools/build.sh)" >&2; exit 2; }
if ! command -v esysparticle > /dev/null; then
    [ "$install" = 1 ] || { echo "bench_peers.sh: ESyS-Particle is not installed: run with --install (apt-get install esys-particle)" >&2; exit 2; }
    apt-get install -y -q esys-particle > /dev/null
fi
n=60
rates=()
for workers in 1 2; do
    line=$(mpirun --allow-run-as-root --oversubscribe -np $((workers + 1)) esysparticle "$root/bench/peers/esys_block.py" $n "$steps" $workers 2>&1 \
           | grep "^esys-particle") || { echo "bench_peers.sh: ESyS-Particle failed with $workers worker(s)" >&2; exit 1; }
    echo "$line"
    rates+=("$(echo "$line" | sed -E 's/.* ([0-9.]+) M particle-steps\/s$/\1/')")
done
result=$(mktemp)
trap 'rm -f "$result"' EXIT
"$bench" --benchmark_filter='BM_Lattice_Step/60/' --benchmark_out="$result" --benchmark_out_format=json > /dev/null 2>&1
spall=$(python3 -c "import json, sys; b = json.load(open(sys.argv[1]))['benchmarks'][0]; print(f\"{b['particle_steps_per_s'] / 1e6:.2f}\")" "$result")
echo "spall ${n}^3 (BM_Lattice_Step/60, every core): $spall M particle-steps/s"
python3 - "$spall" "${rates[@]}" <<'PY'
import sys
spall, one, two = map(float, sys.argv[1:4])
print(f"ratio: spall / ESyS-Particle = {spall / one:.2f} (1 worker), {spall / two:.2f} (2 workers)")
PY
