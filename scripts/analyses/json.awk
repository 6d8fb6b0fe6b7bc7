# json.awk — read one `matremap remap --json` result (one line) and print the fitted values of the given names,
# then relative_rmse, ssim and outcome: "v1 v2 ... relative_rmse ssim outcome". An RGB value prints as r g b.
# Part of `make analyses` (scripts/analyses.sh).   awk -v names=f0,alpha -f json.awk < result.json
BEGIN { n = split(names, want, ",") }
{
    rest = substr($0, index($0, "\"strategy\""))     # the fitted values follow the source block
    line = ""
    for (k = 1; k <= n; k++) line = line value(rest, want[k]) " "
    print line value(rest, "relative_rmse") " " value(rest, "ssim") " " str(rest, "outcome")
}
function value(s, key,    v) {
    if (!match(s, "\"" key "\": (\\[[^]]*\\]|[-+0-9.eEinfa]+)")) { print "json.awk: no '" key "'" > "/dev/stderr"; exit 2 }
    v = substr(s, RSTART + length(key) + 4, RLENGTH - length(key) - 4)
    gsub(/[][]/, "", v); gsub(/, /, " ", v)
    return v
}
function str(s, key) {
    if (!match(s, "\"" key "\": \"[^\"]*\"")) { print "json.awk: no '" key "'" > "/dev/stderr"; exit 2 }
    return substr(s, RSTART + length(key) + 5, RLENGTH - length(key) - 6)
}
