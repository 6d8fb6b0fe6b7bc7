# timing.sh — what the benchmark and evaluation scripts share (sourced).
#   median            the median of the numbers on stdin, one per line
#   seconds_of CMD... wall-clock seconds of a whole command, its output discarded
#   wall_peak_of CMD... "WALL PEAK": wall-clock seconds and peak resident memory (MB, the largest process the
#                     command ran) of a whole command, its output discarded
#   times_of LOG CMD... "WALL CPU": wall-clock and CPU (user + system, children included) seconds of a whole
#                     command, its output in LOG; returns the command's status. CPU time is the work done, which
#                     other jobs on a shared machine inflate much less than the wall clock.
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }

seconds_of() {
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null 2>&1
    t1=$(date +%s.%N)
    awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}'
}

times_of() {
    local log=$1 TIMEFORMAT='%R %U %S' t status=0
    shift
    t=$({ time "$@" >"$log" 2>&1; } 2>&1) || status=$?
    echo "$t" | awk '{ print $1, $2 + $3 }'
    return "$status"
}

wall_peak_of() {
    # A fresh python per command: RUSAGE_CHILDREN's ru_maxrss is then this command's largest process alone.
    python3 - "$@" <<'PY'
import resource, subprocess, sys, time
t = time.perf_counter()
subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
wall = time.perf_counter() - t
print("%.4f %.1f" % (wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0))
PY
}
