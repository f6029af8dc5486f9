#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (GCC, MAGBAKE_SANITIZE):
#   scripts/sanitize.sh [BUILD_DIR] [--all]          default: build-asan, the CI subset
# Every test runs except, without --all, two whose instrumented run takes 7 minutes or more
# (listed in $slow below: the 390 s snapped-cubes sweep, and the kill -9 test, 416 s under ASan
# because it waits for progress lines); run them with --all, e.g. nightly. Any sanitizer
# report fails its test (-fno-sanitize-recover; LSan suppressions in tests/lsan.supp).
# The real-Slurm farm tests (Farm.Slurm_*) are in $slow too: they bake, export and preview the
# demo shot through the scheduler twice (the farm command's own code is covered by
# FarmCommand.* in both builds).
# Usd.BlenderImportsTheStageAndRendersIt is in $slow as well: it exercises the same instrumented
# export as Usd.ExportOpensInUsdCoreAndMatchesTheCache and would install Blender (bpy, 1 GB) a
# second time under the sanitizer build.
# So are the soft-material accuracy sweeps (SoftReference.CubeMomentAndSphereForceAtEveryPreset,
# SoftSphereSeries.ForceOnASoftBallNextToABallMagnetAtEveryPreset): 27 and 16 models up to 2744
# soft cells at the high preset, numbers against references; the same code runs instrumented in
# Induction.*, Cells.*, Scene.SoftPartsGetTheirOwnCellsAcross and
# SoftSphereSeries.FarSoftBallIsNotOneDipoleInTheBodyWalk (a 1633-cell graded ball).
# So are TwoBallSeries.PullOfTwoSoftBallsAtEveryPreset (26 models, two with 2,880 soft cells at
# high; 19 s in the normal build) and Induction.AutomaticRestartSolvesATouchingClusterInFewerIterations
# (two solves of 4,544 cells, 8 s): the same evaluation and GMRES run instrumented in Induction.*
# and SoftSphereSeries.FarSoftBallIsNotOneDipoleInTheBodyWalk.
# So are three contact shots whose instrumented runs were the longest of the 2026-12-07 run
# (580 s, 205 s, 125 s of its 1563 s; the whole stage, build included, took 41 minutes of CI's
# 90): Contact.SteelBallSnappingOntoAMagnetSettles, Simulator.LiftOffHeightMatchesTheForceBalance,
# Contact.CylinderTumblingOnABoxMagnetGainsNoEnergy. Their code (soft cells in contact, the
# force guard, hull contacts) runs instrumented in Contact.SnappedBallsStayTogetherAndGainNoEnergy,
# Contact.CylinderRollingOnItsRimDoesNotSinkIntoATable, Induction.TouchingSteelBallsStayBoundedAtEveryTurn
# and the paper scenes' short bakes.
# Bake.SameCacheOnEmulatedIntelAndAmdCpus never runs here: it runs the binary under qemu-user,
# and an instrumented binary's shadow memory and run time there test qemu, not magbake (the
# normal build runs it).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-asan}
all=${2:-}
slow='^(Contact\.SteelBallSnappingOntoAMagnetSettles|Simulator\.LiftOffHeightMatchesTheForceBalance|Contact\.CylinderTumblingOnABoxMagnetGainsNoEnergy|SoftReference\.CubeMomentAndSphereForceAtEveryPreset|SoftSphereSeries\.ForceOnASoftBallNextToABallMagnetAtEveryPreset|TwoBallSeries\.PullOfTwoSoftBallsAtEveryPreset|Induction\.AutomaticRestartSolvesATouchingClusterInFewerIterations|Contact\.SnappedCubesStayTogetherAndGainNoEnergy|Bake\.KillNineLeavesAReadableCacheWithEveryCompletedFrame|Bake\.SameCacheOnEmulatedIntelAndAmdCpus|Farm\.Slurm_.*|Usd\.BlenderImportsTheStageAndRendersIt)$'
never='^Bake\.SameCacheOnEmulatedIntelAndAmdCpus$'
if [ ! -f "$build/build.ninja" ]; then
  cmake -S . -B "$build" -G Ninja -DMAGBAKE_SANITIZE=ON -DMAGBAKE_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$build"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
if [ "$all" = "--all" ]; then
  ctest --test-dir "$build" --output-on-failure -j2 --timeout 3000 -E "$never"
else
  ctest --test-dir "$build" --output-on-failure -j2 --timeout 1500 -E "$slow"
fi
