# curves.awk — how far apart fitted curves are over a domain (alpha units): ours under each fit light against the
# paper's printed Appendix curve, and ours frontal against ours 45 degrees. Part of `make paper`.
#   awk -v lo=A -v hi=B -v pp="c0..c4" -v pk="c0..c5" -v of=.. -v ok=.. -v ff=.. -v fk=.. -v sqs=0|1 -v sqt=0|1 \
#       -v title=TEXT -f curves.awk
# pp/pk the paper's roughness polynomial and slope, of/ok ours (frontal), ff/fk ours (45 degrees), as "c0 c1 ..."
# words; k = c0 + c1 e^(-c2 a) + c3 e^(-c4 a^2) + c5 / a (the paper's section 7 form). sqs=1: our transform reads
# Cycles' slider r = sqrt(alpha); sqt=1: it writes one (alpha = r^2). Prints two Markdown table rows (roughness,
# slope k): max |difference| over alpha <= 0.5, max and mean over the whole domain.
function poly(s, x,    c) { split(s, c, " "); return c[1] + c[2] * x + c[3] * x^2 + c[4] * x^3 + c[5] * x^4 }
function slope(s, x,    c, n) {
    n = split(s, c, " ")
    return c[1] + c[2] * exp(-c[3] * x) + c[4] * exp(-c[5] * x * x) + (n > 5 ? c[6] / x : 0)
}
function ours_r(s, a,    y) { y = poly(s, sqs ? sqrt(a) : a); return sqt ? y * y : y }
function ours_k(s, a) { return slope(s, sqs ? sqrt(a) : a) }
function abs(x) { return x < 0 ? -x : x }
function cell(k) { return sprintf("%.3g / %.3g (%.3g)", m5[k], mx[k], sum[k] / n) }
BEGIN {
    n = 400
    for (i = 0; i < n; i++) {
        a = lo + (hi - lo) * i / (n - 1)
        v["r", 1] = ours_r(of, a); v["r", 2] = ours_r(ff, a); v["r", 0] = poly(pp, a)
        v["k", 1] = ours_k(ok, a); v["k", 2] = ours_k(fk, a); v["k", 0] = slope(pk, a)
        for (q = 1; q <= 2; q++) {
            c = q == 1 ? "r" : "k"
            d[1] = abs(v[c, 1] - v[c, 0]); d[2] = abs(v[c, 2] - v[c, 0]); d[3] = abs(v[c, 1] - v[c, 2])
            for (j = 1; j <= 3; j++) {
                key = c j
                sum[key] += d[j]
                if (d[j] > mx[key]) mx[key] = d[j]
                if (a <= 0.5 && d[j] > m5[key]) m5[key] = d[j]
            }
        }
    }
    printf "| %s | target α | %s | %s | %.3g |\n", title, cell("r1"), cell("r2"), mx["r3"]
    printf "| | slope k(α) | %s | %s | %.3g |\n", cell("k1"), cell("k2"), mx["k3"]
}
