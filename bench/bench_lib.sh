# Shared by the bench shell scripts (source it): the median of whitespace-separated numbers on
# stdin, the machine/load line every result starts with, a timed bake and a cache's mean
# observable.
median() { tr ' ' '\n' | grep . | sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
machine_line() {
  echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); load before: $(cut -d' ' -f1-3 /proc/loadavg)"
}
# Seconds (wall) of one bake: timed_bake EXE SCENE FRAMES OUT_DIR (1 thread, cache only; the
# output folder is replaced).
timed_bake() {
  rm -rf "$4"
  local t0 t1
  t0=$(date +%s.%N)
  "$1" -q --threads 1 bake "$2" --frames "$3" -o "$4" >/dev/null 2>&1
  t1=$(date +%s.%N)
  echo "$t1 - $t0" | bc
}
# Mean over frames of one observable of the cache in a folder: cache_mean DIR NAME (e.g.
# induction_iterations); "?" when the cache has none.
cache_mean() {
  /usr/bin/python3 - "$1" "$2" <<'P'
import glob, sys, h5py
f = h5py.File(glob.glob(sys.argv[1] + "/*.h5")[0], "r")
found = []
f.visit(lambda n: found.append(n) if n.endswith(sys.argv[2] + "/value") else None)
print("%.1f" % f[found[0]][()].mean() if found else "?")
P
}
