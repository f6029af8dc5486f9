#!/usr/bin/env bash
# magbake farm on a real Slurm (issue 15): a single-node cluster on this machine
# (scripts/slurm-local.sh: munged, slurmctld, slurmd as root), then
#   shot:    `magbake farm --submit` of the demo scene (a 90-frame bake, field volumes every 3rd
#            frame, 90 previews), waits for the jobs and checks the cache against a local bake
#            of the same binary (diff --exact), the volumes and the previews;
#   preempt: the same shot's simulation job is requeued (`scontrol requeue`) mid-bake; it must
#            exit 75 with a partial cache, run again, resume, and end bit for bit equal to the
#            uninterrupted local bake;
#   wedge:   `--wedge` of two settings x two values: four bakes in one array job, the summary
#            table, each cache equal to a local bake of its resolved scene.
# Exit 77 (skipped, with the reason) only where Slurm cannot run: not root, or no slurm-wlm.
#   tests/farm/slurm_farm_test.sh MAGBAKE SOURCE_DIR shot|preempt|wedge
set -uo pipefail
exe=$1 src=$2 which=$3
skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }
[ "$(id -u)" = 0 ] || skip "needs root to start a local Slurm (munged, slurmctld, slurmd)"
for t in sbatch slurmctld slurmd munged; do
  command -v "$t" >/dev/null || skip "$t is missing: apt-get install slurm-wlm munge (scripts/install-deps.sh)"
done
bash "$src/scripts/slurm-local.sh" || fail "the local Slurm cluster did not start (scripts/slurm-local.sh)"

work=$(mktemp -d /tmp/magbake_farm_XXXXXX)
trap 'rm -rf "$work"' EXIT
cd "$work"
scene="$src/scenes/demo.yaml"

# The reference: the same binary, locally, uninterrupted.
"$exe" -q bake "$scene" -o "$work/local" --cache-only >/dev/null || fail "local bake"
ref="$work/local/demo.h5"

# Waits until none of the given jobs (ids) is pending or running; 15 minutes at most. A job
# requeued after preemption is held until its eligible time (Slurm adds about 2 minutes): the
# test makes it eligible at once, as an operator would with `scontrol update`.
wait_jobs() {
  local ids=$1
  for _ in $(seq 900); do
    local left
    left=$(squeue -h -j "$ids" -o '%i %r' 2>/dev/null || true)
    [ -z "$left" ] && return 0
    while read -r id reason; do
      if [ "$reason" = BeginTime ]; then scontrol update JobId="$id" StartTime=now >/dev/null 2>&1 || true; fi
    done <<< "$left"
    sleep 1
  done
  squeue
  return 1
}

submit() {  # folder -> prints the job ids "bake field preview usd"
  "$exe" farm "$scene" -o "$1" --chunk 45 --submit > "$1.submit.txt" 2>&1 || { cat "$1.submit.txt"; fail "magbake farm --submit"; }
  /usr/bin/python3 -c "import json,sys; j=json.load(open(sys.argv[1]))['jobs']; print(j['bake'], j['field'], j['preview'], j['usd'])" \
    "$1/farm/jobs.json"
}

check_outputs() {  # folder
  local d=$1
  [ -f "$d/demo.h5" ] || fail "no cache in $d: $(ls "$d"); logs: $(tail -n 5 "$d"/farm/logs/*)"
  [ ! -e "$d/demo.h5.partial" ] || fail "a partial cache is left in $d"
  "$exe" diff "$ref" "$d/demo.h5" --exact || fail "the farm's cache differs from the local bake"
  local vdb png
  vdb=$(ls "$d"/field.*.vdb 2>/dev/null | wc -l)
  png=$(ls "$d"/preview.*.png 2>/dev/null | wc -l)
  [ "$vdb" = 30 ] || fail "expected 30 field volumes (frames 1-88 every 3), found $vdb"
  [ "$png" = 90 ] || fail "expected 90 previews, found $png"
  # Every 3rd frame from the shot's first, in both array tasks (chunks of 45 rounded to 45).
  for f in 0001 0043 0046 0088; do [ -f "$d/field.$f.vdb" ] || fail "field.$f.vdb missing"; done
  /usr/bin/python3 - "$d" <<'PY' || fail "a field volume does not hold the B grid"
import sys, pyopenvdb as openvdb
grids = {g.name for g in openvdb.readAllGridMetadata(sys.argv[1] + "/field.0046.vdb")}
assert "B" in grids, grids
PY
  [ "$(head -c 8 "$d/preview.0045.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || fail "preview.0045.png is not a PNG"
  # The USD stage, written after the volumes: every body and a time sample for each volume.
  [ "$(head -n 1 "$d/demo.usda")" = "#usda 1.0" ] || fail "no USD stage in $d"
  [ "$(grep -c "field\.[0-9]*\.vdb" "$d/demo.usda")" -ge 30 ] || fail "the USD stage does not reference the 30 volumes"
}

case "$which" in
  shot)
    read -r bake field preview usd < <(submit "$work/shot")
    echo "jobs: bake $bake, field $field, preview $preview, usd $usd"
    wait_jobs "$bake,$field,$preview,$usd" || fail "jobs did not finish in 15 minutes"
    grep -q "^Progress: bake 100% frame 90/90" "$work/shot/farm/logs/bake-$bake.log" || fail "no final progress line in the bake log"
    check_outputs "$work/shot"
    echo "PASSED: shot baked, exported and equal to the local bake"
    ;;
  preempt)
    read -r bake field preview usd < <(submit "$work/pre")
    echo "jobs: bake $bake, field $field, preview $preview, usd $usd"
    log="$work/pre/farm/logs/bake-$bake.log"
    # Requeue once the bake is past 20% and before it ends.
    for _ in $(seq 6000); do grep -qE "^Progress: bake ([2-9][0-9])% " "$log" 2>/dev/null && break; sleep 0.02; done
    grep -qE "^Progress: bake ([2-9][0-9])% " "$log" || fail "the bake never reached 20%: $(cat "$log")"
    grep -q "^Progress: bake 100%" "$log" && fail "the bake finished before it could be preempted"
    scontrol requeue "$bake" || fail "scontrol requeue $bake"
    wait_jobs "$bake,$field,$preview,$usd" || fail "jobs did not finish in 15 minutes"
    grep -v "^Progress\|^ALF" "$log"
    grep -q "interrupted: frames up to" "$log" || fail "the preempted bake did not stop at a frame (exit 75)"
    grep -q "resuming after frame" "$log" || fail "the requeued bake did not resume from its partial cache"
    [ "$(scontrol show job "$bake" | grep -o 'Restarts=[0-9]*')" != "Restarts=0" ] || fail "the job was not restarted"
    check_outputs "$work/pre"
    echo "PASSED: preempted bake resumed and equals the uninterrupted one bit for bit"
    ;;
  wedge)
    # Two settings, two values each: four bakes as one array job, then the summary (afterany).
    golden="$src/tests/golden/magnets_in_space.yaml"
    "$exe" farm "$golden" -o "$work/w" --wedge magnetics.theta=0.3,0.5 --wedge "bodies.b.position=[14, 3, 2],[15, 3, 2]" \
      --submit > "$work/w.submit.txt" 2>&1 || { cat "$work/w.submit.txt"; fail "magbake farm --wedge --submit"; }
    ids=$(/usr/bin/python3 -c "import json,sys; j=json.load(open(sys.argv[1]))['jobs']; print(j['wedge'] + ',' + j['summary'])" \
      "$work/w/farm/jobs.json")
    wait_jobs "$ids" || fail "jobs did not finish in 15 minutes"
    cat "$work/w/wedges/summary.md"
    [ "$(grep -c '| complete |' "$work/w/wedges/summary.md")" = 4 ] || fail "expected 4 complete caches in summary.md"
    # Moving body b by 1 mm changes the shot; each case's cache is its resolved scene's local bake.
    grep -q '^| 001_magnetics.theta=0.3_bodies.b.position=_15__3__2_ | complete | differ' "$work/w/wedges/summary.md" \
      || fail "the moved body's case does not differ from the first"
    d="$work/w/wedges/003_magnetics.theta=0.5_bodies.b.position=_15__3__2_"
    grep -q 'theta: 0.5' "$d/scene.yaml" && grep -q 'position: \[15, 3, 2\]' "$d/scene.yaml" || fail "settings not in $d/scene.yaml"
    "$exe" -q bake "$d/scene.yaml" -o "$work/w_local" >/dev/null || fail "local bake of a wedge scene"
    "$exe" diff "$work/w_local/magnets_in_space.h5" "$d/magnets_in_space.h5" --exact || fail "wedge cache differs from its scene's bake"
    echo "PASSED: four wedge cases baked on Slurm and summarized"
    ;;
  *) fail "unknown case $which" ;;
esac
