# smooth.awk — smoothness of a fitted curve y(x) (make analyses, scripts/analyses.sh). Input: lines "x y flag"
# in increasing x. Slopes |dy/dx| between consecutive points (on a uniform grid: the steps); a jump is a slope
# above FACTOR (default 3) times the median slope. With -v only=converged[,at-bound...] points whose flag is
# not listed are dropped first (then slopes span the gaps). Prints one line:
#   LABEL points=N median_step=S max_step=M ratio=M/S jumps=K [x0->x1 (flag0->flag1) step/median ...]
# Steps are reported per grid step h (the median x spacing), so on a uniform grid they are the plain |dy|.
# With -v ref=S the jump threshold is FACTOR * S instead (e.g. another strategy's median step).
BEGIN { if (factor == "") factor = 3; nkeep = 0; if (only != "") { m = split(only, o, ","); for (i = 1; i <= m; i++) ok[o[i]] = 1 } }
NF >= 2 { if (only != "" && !($3 in ok)) next; nkeep++; x[nkeep] = $1 + 0; y[nkeep] = $2 + 0; f[nkeep] = $3 }
END {
    if (nkeep < 3) { printf "%s points=%d (too few)\n", label, nkeep; exit }
    for (i = 1; i < nkeep; i++) { dx[i] = x[i + 1] - x[i]; s[i] = (y[i + 1] - y[i]) / dx[i]; if (s[i] < 0) s[i] = -s[i] }
    h = median(dx, nkeep - 1)
    for (i = 1; i < nkeep; i++) st[i] = s[i] * h
    med = median(st, nkeep - 1)
    if (ref != "") med = ref + 0
    mx = 0; for (i = 1; i < nkeep; i++) if (st[i] > mx) mx = st[i]
    nj = 0; list = ""
    for (i = 1; i < nkeep; i++) if (st[i] > factor * med) { nj++; list = list sprintf(" %g->%g(%s->%s,%.3gx)", x[i], x[i + 1], f[i], f[i + 1], (med > 0 ? st[i] / med : 1e300)) }
    printf "%s points=%d median_step=%.4g max_step=%.4g ratio=%.3g jumps=%d%s\n", label, nkeep, med, mx, (med > 0 ? mx / med : 1e300), nj, list
}
function median(a, n,    b, i, j, t) {
    for (i = 1; i <= n; i++) b[i] = a[i]
    for (i = 2; i <= n; i++) { t = b[i]; for (j = i - 1; j >= 1 && b[j] > t; j--) b[j + 1] = b[j]; b[j + 1] = t }
    return (n % 2) ? b[(n + 1) / 2] : (b[n / 2] + b[n / 2 + 1]) / 2
}
