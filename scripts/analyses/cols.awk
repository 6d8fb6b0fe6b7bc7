# cols.awk — print selected columns of a `matremap sweep` CSV (docs/sweep.md), whitespace-separated, one line
# per sample. Part of `make analyses` (scripts/analyses.sh).
#
#   awk -v cols='f0_r,mean:to_specular,maxsum:to_diffuse:to_specular,outcome' -f cols.awk DATA.csv
#
# A column spec is a column name, or
#   mean:P  min:P  max:P   over P_r, P_g, P_b (an RGB parameter)
#   maxsum:A:B             max over the channels of A_c + B_c (Ward's trimming test: diffuse + specular > 1)
# '# ' lines are skipped; the first other line holds the column names. An unknown name is an error (exit 2).
BEGIN { FS = ","; n = split(cols, spec, ","); header = 0 }
/^#/ { next }
!header {
    for (i = 1; i <= NF; i++) idx[$i] = i
    for (k = 1; k <= n; k++) {
        m = split(spec[k], part, ":")
        if (m == 1) need(part[1])
        else if (m == 2) { need(part[2] "_r"); need(part[2] "_g"); need(part[2] "_b") }
        else { need(part[2] "_r"); need(part[3] "_r"); need(part[2] "_g"); need(part[3] "_g"); need(part[2] "_b"); need(part[3] "_b") }
    }
    header = 1
    next
}
{
    line = ""
    for (k = 1; k <= n; k++) {
        m = split(spec[k], part, ":")
        if (m == 1) v = $(idx[part[1]])
        else if (m == 2) {
            r = $(idx[part[2] "_r"]) + 0; g = $(idx[part[2] "_g"]) + 0; b = $(idx[part[2] "_b"]) + 0
            if (part[1] == "mean") v = sprintf("%.10g", (r + g + b) / 3)
            else if (part[1] == "min") v = sprintf("%.10g", r < g ? (r < b ? r : b) : (g < b ? g : b))
            else if (part[1] == "max") v = sprintf("%.10g", r > g ? (r > b ? r : b) : (g > b ? g : b))
            else bad(spec[k])
        } else if (part[1] == "maxsum") {
            s = -1e300
            split("r g b", ch, " ")
            for (c = 1; c <= 3; c++) { t = $(idx[part[2] "_" ch[c]]) + $(idx[part[3] "_" ch[c]]); if (t > s) s = t }
            v = sprintf("%.10g", s)
        } else bad(spec[k])
        line = line (k > 1 ? " " : "") v
    }
    print line
}
function need(name) { if (!(name in idx)) { printf "cols.awk: %s: no column '%s'\n", FILENAME, name > "/dev/stderr"; exit 2 } }
function bad(s) { printf "cols.awk: bad column spec '%s'\n", s > "/dev/stderr"; exit 2 }
