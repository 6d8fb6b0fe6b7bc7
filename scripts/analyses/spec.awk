# spec.awk — turn each row of a `matremap sweep` CSV into command-line material specs, so a row can be fed back to
# `matremap remap` / `matremap render`. Part of `make analyses` (scripts/analyses.sh). Prints, tab-separated:
#   index  FROM-MODEL name=value ...  TO-MODEL name=value ...  outcome
# RGB parameters (name_r, name_g, name_b) become name=r,g,b. Values are copied verbatim (%.17g in the file).
BEGIN { FS = ","; OFS = "\t" }
/^# from: / { split($0, w, " "); from = w[3]; next }
/^# to: / { split($0, w, " "); to = w[3]; next }
/^#/ { next }
!header {
    for (i = 1; i <= NF; i++) name[i] = $i
    first_to = 0
    for (i = 2; i <= NF; i++) if (substr(name[i], 1, 3) == "to_") { if (!first_to) first_to = i; last_to = i }
    for (i = 1; i <= NF; i++) if (name[i] == "outcome") oc = i
    if (!first_to || !oc || from == "" || to == "") { print "spec.awk: not a matremap sweep file" > "/dev/stderr"; exit 2 }
    header = 1
    next
}
{ print $1, from args(2, first_to - 1, ""), to args(first_to, last_to, "to_"), $(oc) }
function args(lo, hi, prefix,    s, i, nm) {
    s = ""
    for (i = lo; i <= hi; i++) {
        nm = substr(name[i], length(prefix) + 1)
        if (nm ~ /_r$/ && i + 2 <= hi && name[i + 1] == prefix substr(nm, 1, length(nm) - 2) "_g") {
            s = s " " substr(nm, 1, length(nm) - 2) "=" $i "," $(i + 1) "," $(i + 2)
            i += 2
        } else s = s " " nm "=" $i
    }
    return s
}
