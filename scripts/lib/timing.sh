# timing.sh — what the benchmark and evaluation scripts share (sourced).
#   median            the median of the numbers on stdin, one per line
#   seconds_of CMD... wall-clock seconds of a whole command, its output discarded
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }

seconds_of() {
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null 2>&1
    t1=$(date +%s.%N)
    awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}'
}
