#!/usr/bin/env bash
# Sweeps for real: a single-node Slurm (tools/slurm_single_node.sh, as root) runs a sweep as a job
# array with a dependent summary job; the same sweep run locally gives the same summary, byte for
# byte; a failed variant is reported with its reason; a sweep stopped with SIGTERM resumes where
# it stopped and ends as an uninterrupted one. The daemons are stopped by their pids on exit.
# Usage: sweep_integration.sh SPALL_BINARY SCRATCH_DIR
set -euo pipefail
spall=$(realpath "$1")
dir=$(realpath -m "$2")
rm -rf "$dir" && mkdir -p "$dir"
tools=$(dirname "$0")/../tools
fail() { echo "FAIL: $*" >&2; exit 1; }

# A wall 5 m from 0.45-0.5 kg under the paper's rule: its random link strengths decide what
# breaks, so seeds differ. At 0.02 m voxels it exceeds max_voxels: those variants fail when they start.
cat > "$dir/wall.json" <<'JSON'
{"voxel_size_m": 0.1, "duration_s": 3.0, "frame_rate_hz": 24, "seed": 1, "max_voxels": 2000,
 "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [1.2, 0.2, 0.8]},
              "position_m": [0, 0, 0.4], "material": "brick-masonry", "anchor": "ground"}],
 "charges": [{"position_m": [0, -5.0, 0.2], "tnt_kg": 0.5}], "fracture": {"algorithm": "yield-limit"}}
JSON
sweep_args=("$dir/wall.json" --seeds 2 --vary 'charges[0].tnt_kg=0.45,0.5' --vary voxel_size_m=0.1,0.02 --jobs 2)

"$tools/slurm_single_node.sh" start "$dir/slurm" > "$dir/slurm.env"
trap '"$tools/slurm_single_node.sh" stop "$dir/slurm"' EXIT
source "$dir/slurm.env"
"$spall" sweep "${sweep_args[@]}" -o "$dir/on_slurm" --scheduler slurm > "$dir/submit.txt" || fail "submission: $(cat "$dir/submit.txt")"
grep -q "submitted job array" "$dir/submit.txt" || fail "no job array: $(cat "$dir/submit.txt")"
for _ in $(seq 600); do
  [[ -z "$(squeue -h -o %i)" ]] && break
  sleep 0.5
done
[[ -z "$(squeue -h -o %i)" ]] && [[ -s "$dir/on_slurm/summary.csv" ]] || fail "the Slurm sweep did not end with a summary: $(cat "$dir"/on_slurm/logs/*)"

set +e
"$spall" sweep "${sweep_args[@]}" -o "$dir/local" > "$dir/local.txt" 2>&1
code=$?
set -e
[[ $code == 1 ]] || fail "a sweep with failed variants exited $code, expected 1: $(cat "$dir/local.txt")"
for f in summary.csv summary_groups.csv; do
  cmp "$dir/on_slurm/$f" "$dir/local/$f" || fail "$f differs between Slurm and local runs"
done
/usr/bin/python3 - "$dir/local" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/summary.csv")))
assert len(rows) == 8, len(rows)
for r in rows:
    fine = r["overrides"].endswith("voxel_size_m=0.1")
    assert r["state"] == ("done" if fine else "failed"), r
    assert fine or "max_voxels" in r["message"], r
done = [r for r in rows if r["state"] == "done"]
assert len({r["fragments"] for r in done}) > 1, "seeds should change the outcome"
groups = list(csv.DictReader(open(sys.argv[1] + "/summary_groups.csv")))
assert len(groups) == 4 and all(g["variants"] == "2" for g in groups), groups
assert any(g["seeds_changed_anything"] == "1" for g in groups), groups
PY
# seeds of a scene whose materials do not scatter (brick masonry in the deformable phase): the
# sweep says they change nothing instead of printing a spread of 0
sed 's/, "fracture": {"algorithm": "yield-limit"}//; s/"duration_s": 3.0/"duration_s": 0.5/' "$dir/wall.json" > "$dir/still.json"
"$spall" sweep "$dir/still.json" --seeds 2 -o "$dir/still" > "$dir/still.txt" 2>&1 || fail "still sweep: $(cat "$dir/still.txt")"
grep -q "every figure the same for all 2 seeds" "$dir/still.txt" || fail "identical seeds not said: $(cat "$dir/still.txt")"
grep -q '^0,".*",2,2,0,' "$dir/still/summary_groups.csv" || fail "identical seeds not marked: $(cat "$dir/still/summary_groups.csv")"
# a re-run skips what finished and tries the failed variants again
set +e; "$spall" sweep "${sweep_args[@]}" -o "$dir/local" > "$dir/rerun.txt" 2>&1; set -e
grep -q "8 variants, 4 to run" "$dir/rerun.txt" || fail "re-run: $(head -3 "$dir/rerun.txt")"
# another sweep into the same directory is refused
if "$spall" sweep "$dir/wall.json" --seeds 3 -o "$dir/local" 2> "$dir/other.err"; then fail "a different sweep was accepted"; fi
grep -q "holds a different sweep" "$dir/other.err" || fail "unclear refusal: $(cat "$dir/other.err")"

# SIGTERM stops a local sweep between steps; the next run resumes the variant from its checkpoint
sed 's/"duration_s": 3.0/"duration_s": 30.0/; s/"max_voxels": 2000,/"max_voxels": 2000, "solver": {"sleep": false},/' "$dir/wall.json" > "$dir/long.json"
"$spall" sweep "$dir/long.json" --seeds 1 -o "$dir/stopped" > "$dir/stopped.txt" 2>&1 &
pid=$!
for _ in $(seq 300); do [[ -e "$dir/stopped/variants/v0000/out/fragments.0020.vdb" ]] && break; sleep 0.1; done
kill -TERM $pid
set +e; wait $pid; code=$?; set -e
[[ $code == 130 ]] || fail "stopped sweep exited $code, expected 130: $(cat "$dir/stopped.txt")"
grep -q '"stopped"' "$dir/stopped/variants/v0000/status.json" || fail "variant not marked stopped: $(cat "$dir/stopped/variants/v0000/status.json")"
[[ -e "$dir/stopped/variants/v0000/out/checkpoint.spall" ]] || fail "no checkpoint to resume from"
"$spall" sweep "$dir/long.json" --seeds 1 -o "$dir/stopped" > /dev/null || fail "resumed sweep failed"
"$spall" sweep "$dir/long.json" --seeds 1 -o "$dir/whole" > /dev/null || fail "uninterrupted sweep failed"
cmp "$dir/stopped/summary.csv" "$dir/whole/summary.csv" || fail "the resumed sweep differs from the uninterrupted one"
echo "sweep integration: ok"
