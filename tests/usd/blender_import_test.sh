#!/usr/bin/env bash
# Blender opens magbake's USD: PyPI's bpy 5.0.1 (Blender as a Python module, Python 3.11) in the
# venv under the build folder that tests/usd/usd_export_test.sh uses (downloads cached there),
# imports the golden sphere-pickup shot with field volumes of three frames, and
# check_blender.py compares every body's world matrix at three frames with the cache, loads the
# Volume's grids and renders a small Cycles frame that must not be blank. Skipped (exit 77, with
# the reason) only when the venv or bpy cannot be installed (no network).
#   blender_import_test.sh MAGBAKE SOURCE_DIR BUILD_DIR
set -uo pipefail
exe=$1 src=$2 build=$3
venv="$build/venv-usd"
export PIP_CACHE_DIR="$build/pip-cache"
if [ ! -x "$venv/bin/python" ]; then
  /usr/bin/python3 -m venv --system-site-packages "$venv" >/dev/null 2>&1 || { echo "SKIP: cannot make a Python venv"; exit 77; }
fi
if ! "$venv/bin/python" -c "import bpy" 2>/dev/null; then
  "$venv/bin/pip" install --quiet "bpy==5.0.1" 2>&1 | tail -3
  "$venv/bin/python" -c "import bpy" 2>/dev/null || { echo "SKIP: bpy 5.0.1 could not be installed from PyPI (no network?)"; exit 77; }
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
set -e
"$exe" --quiet bake "$src/tests/golden/sphere_pickup.yaml" -o "$work" > /dev/null
"$exe" --quiet field "$work/sphere_pickup.h5" --frames 1-3 -o "$work/vdb/field.####.vdb" > /dev/null
"$exe" --quiet export "$work/sphere_pickup.h5" --usd "$work/shot.usdc" --field "$work/vdb/field.####.vdb" --field-lines > /dev/null
# The field lines' size at frame 1 as usd-core reads it, for Blender's import to match.
lines=$("$venv/bin/python" -c "
import sys
from pxr import Usd, UsdGeom
stage = Usd.Stage.Open(sys.argv[1])  # held: a prim lives only as long as its stage
c = UsdGeom.BasisCurves(stage.GetPrimAtPath('/sphere_pickup/field_lines'))
n = c.GetCurveVertexCountsAttr().Get(1)
print(len(n), sum(n))" "$work/shot.usdc")
"$venv/bin/python" "$src/tests/usd/check_blender.py" "$work/shot.usdc" "$work/sphere_pickup.h5" "$work/render.png" $lines 2>&1 |
  grep -v '^Fra:'
echo "PASS"
