#!/bin/bash
# Columns: quality, soft_cells_across (empty: the preset), force on ball b along x (N), GMRES iterations
# (all Newton steps), Newton steps, last linear residual, converged, wall time of magbake eval.
# Usage: MAGBAKE=build/bake/magbake bash saturating_contact_ladder.sh (from the checkout).
# Two touching 5 mm steel balls (chi 700, saturation 2 T) in 0.1 T along their line.
for spec in "draft:" "default:" "high:" "high:18" "high:22" "high:26"; do
  q=${spec%%:*}; n=${spec##*:}
  extra=""; [ -n "$n" ] && extra=", soft_cells_across: $n"
  cat > satl.yaml <<EOT
magbake: 1.1
name: two_touching_saturating_balls
units: {length: mm, angle: deg}
magnetics: {quality: $q, induction: coupled, external_field: [0.1, 0, 0]$extra}
materials:
  steel: {kind: soft, chi: 700, saturation: 2.0, density: 7850}
bodies:
  - {name: a, shape: {sphere: {radius: 5.0}}, material: steel, position: [-5.0, 0, 0], motion: static}
  - {name: b, shape: {sphere: {radius: 5.0}}, material: steel, position: [5.0, 0, 0], motion: static}
EOT
  t0=$(date +%s.%N)
  out=$(${MAGBAKE:-build/bake/magbake} eval satl.yaml --json 2>/dev/null)
  t1=$(date +%s.%N)
  echo "$out" | python3 -c "
import sys,json; t=sys.stdin.read(); d=json.loads(t[:t.rfind('}')+1]); i=d['induction']
print('$q', '$n', d['bodies'][1]['force'][0], i['iterations'], i['nonlinear_iterations'], i['residual'], i['converged'], '%.1f s'%($t1-$t0), flush=True)"
done
