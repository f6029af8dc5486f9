#!/usr/bin/env bash
# magbake export --usd, opened by the reference implementation (PyPI's usd-core) in a venv under
# the build folder (downloads cached there, so reruns do not download again): the golden
# sphere-pickup shot (a steel ball lifted by a kinematic magnet), with field volumes of three
# frames, exported and checked by check_usd.py against the cache. Skipped (exit 77, with the
# reason) only when the venv cannot be made or usd-core cannot be installed (no network).
#   usd_export_test.sh MAGBAKE SOURCE_DIR BUILD_DIR
set -uo pipefail
exe=$1 src=$2 build=$3
venv="$build/venv-usd"
export PIP_CACHE_DIR="$build/pip-cache"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import pxr" 2>/dev/null; then
  rm -rf "$venv"
  # Debian's h5py and numpy come from the system site packages.
  if ! /usr/bin/python3 -m venv --system-site-packages "$venv" >/dev/null 2>&1; then
    echo "SKIP: cannot make a Python venv (python3-venv missing?)"; exit 77
  fi
  if ! "$venv/bin/pip" install --quiet "usd-core==26.11" 2>&1 | tail -3; then :; fi
  if ! "$venv/bin/python" -c "import pxr" 2>/dev/null; then
    echo "SKIP: usd-core 26.11 could not be installed from PyPI (no network?)"; exit 77
  fi
fi
"$venv/bin/python" -c "import h5py" 2>/dev/null || { echo "FAIL: h5py missing (install-deps.sh installs python3-h5py)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
set -e
"$exe" --quiet bake "$src/tests/golden/sphere_pickup.yaml" -o "$work/shot"
"$exe" --quiet field "$work/shot/sphere_pickup.h5" --frames 1-3 -o "$work/shot/vdb/field.####.vdb"
"$exe" export "$work/shot/sphere_pickup.h5" --usd "$work/shot/usd/shot.usda" --field "$work/shot/vdb/field.####.vdb"
# Refusals: a stage name that is not .usda/.usdc/.usd, and a field pattern without a frame field.
set +e
"$exe" --quiet export "$work/shot/sphere_pickup.h5" --usd "$work/x.usdz" >/dev/null 2>&1
[ $? -eq 2 ] || { echo "FAIL: --usd x.usdz should exit 2"; exit 1; }
"$exe" --quiet export "$work/shot/sphere_pickup.h5" --usd "$work/x.usda" --field "$work/f.vdb" >/dev/null 2>&1
[ $? -eq 2 ] || { echo "FAIL: --field without #### should exit 2"; exit 1; }
[ ! -e "$work/x.usda" ] || { echo "FAIL: a refused export wrote a file"; exit 1; }
set -e
"$venv/bin/python" "$src/tests/usd/check_usd.py" "$work/shot/usd/shot.usda" "$work/shot/sphere_pickup.h5" 3
# The binary form (USDC, magbake's crate writer): the same checks, and the same stage as the text
# form value for value.
"$exe" export "$work/shot/sphere_pickup.h5" --usd "$work/shot/usd/shot.usdc" --field "$work/shot/vdb/field.####.vdb"
"$venv/bin/python" "$src/tests/usd/check_usd.py" "$work/shot/usd/shot.usdc" "$work/shot/sphere_pickup.h5" 3
"$venv/bin/python" "$src/tests/usd/compare_stages.py" "$work/shot/usd/shot.usda" "$work/shot/usd/shot.usdc"
# A frame range: the stage's time codes follow it.
"$exe" --quiet export "$work/shot/sphere_pickup.h5" --usd "$work/part.usda" --frames 5-9 --field none
"$venv/bin/python" - "$work/part.usda" <<'PY'
import sys
from pxr import Usd
s = Usd.Stage.Open(sys.argv[1])
assert (s.GetStartTimeCode(), s.GetEndTimeCode()) == (5, 9), (s.GetStartTimeCode(), s.GetEndTimeCode())
assert not s.GetPrimAtPath("/sphere_pickup/field").IsValid()
print("frames 5-9: start/end time codes 5, 9; no volume")
PY
# outputs.usd: the bake writes the stage itself, after its field volumes (every 2nd frame).
sed -e 's/frames: \[1, 25\]/frames: [1, 4]/' "$src/tests/golden/sphere_pickup.yaml" > "$work/sp.yaml"
printf 'outputs:\n  field: {path: vdb/f.####.vdb, voxel: 2, every: 2}\n  usd: usd/sp.usda\n' >> "$work/sp.yaml"
"$exe" --quiet bake "$work/sp.yaml" -o "$work/b" > /dev/null
"$venv/bin/python" - "$work/b/sp.usda" <<'PY'
import sys
from pxr import Usd, UsdVol
s = Usd.Stage.Open(sys.argv[1])
assert (s.GetStartTimeCode(), s.GetEndTimeCode()) == (1, 4)
b = UsdVol.OpenVDBAsset(s.GetPrimAtPath("/sphere_pickup/field/B"))
times = b.GetFilePathAttr().GetTimeSamples()
assert times == [1.0, 3.0], times
assert all(b.GetFilePathAttr().Get(t).resolvedPath for t in times)
print("outputs.usd: written by the bake, Volume at frames 1 and 3")
PY
# --field-lines: the previews' streamlines as BasisCurves, each frame's topology its own time
# sample; at frame 1 (the scene at t = 0) the lines run along B as `magbake probe` gives it.
"$exe" --quiet export "$work/shot/sphere_pickup.h5" --usd "$work/lines.usda" --frames 1-2 --field none --field-lines
"$exe" --quiet export "$work/shot/sphere_pickup.h5" --usd "$work/lines.usdc" --frames 1-2 --field none --field-lines
"$venv/bin/python" "$src/tests/usd/compare_stages.py" "$work/lines.usda" "$work/lines.usdc"
"$venv/bin/python" - "$work/lines.usda" "$work/mid.txt" <<'PY'
import sys
import numpy as np
from pxr import Usd, UsdGeom
s = Usd.Stage.Open(sys.argv[1])
c = UsdGeom.BasisCurves(s.GetPrimAtPath("/sphere_pickup/field_lines"))
assert c, "no BasisCurves prim"
assert c.GetTypeAttr().Get() == "linear"
for t in (1, 2):
    n, p = c.GetCurveVertexCountsAttr().Get(t), c.GetPointsAttr().Get(t)
    col = c.GetDisplayColorPrimvar().Get(t)
    assert len(n) >= 10 and sum(n) == len(p) == len(col), (t, len(n), sum(n), len(p), len(col))
    lo, hi = np.array(c.GetExtentAttr().Get(t))
    assert (np.array(p) >= lo - 1e-6).all() and (np.array(p) <= hi + 1e-6).all()
assert c.GetDisplayColorPrimvar().GetInterpolation() == "vertex"
# Midpoints and directions of every 7th segment of frame 1, for probe.
n, p = c.GetCurveVertexCountsAttr().Get(1), np.array(c.GetPointsAttr().Get(1), dtype=float)
mids, dirs, at = [], [], 0
for k in n:
    for j in range(at, at + k - 1, 7):
        mids.append((p[j] + p[j + 1]) / 2); dirs.append(p[j + 1] - p[j])
    at += k
np.savetxt(sys.argv[2], np.array(mids))
np.save(sys.argv[2] + ".dirs.npy", np.array(dirs))
print(f"field lines: {len(n)} curves, {len(p)} points at frame 1; {len(mids)} segments checked against probe")
PY
"$exe" probe "$src/tests/golden/sphere_pickup.yaml" --points "$work/mid.txt" --json 2>/dev/null > "$work/probe.json"
"$venv/bin/python" - "$work/mid.txt" "$work/probe.json" <<'PY'
import json, sys
import numpy as np
d = np.load(sys.argv[1] + ".dirs.npy")
B = np.array(json.load(open(sys.argv[2]))["B"])
strong = np.linalg.norm(B, axis=1) > 1e-4
cos = np.abs(np.sum(d * B, axis=1)) / (np.linalg.norm(d, axis=1) * np.linalg.norm(B, axis=1) + 1e-300)
share = float(np.mean(cos[strong] > 0.99))
print(f"segments along B (|cos| > 0.99): {100 * share:.1f}% of {strong.sum()}, median |cos| {np.median(cos[strong]):.5f}")
assert strong.sum() > 50 and share > 0.95, share
PY
echo "PASS"
