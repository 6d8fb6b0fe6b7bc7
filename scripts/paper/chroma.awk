# chroma.awk — how far a conversion moved each texel's specular colour (paper Fig. 19). Part of `make paper`.
#   paste <(oiiotool --dumpdata IN.exr) <(oiiotool --dumpdata OUT.exr) | awk -f chroma.awk
# Input: the two dumps side by side ("Pixel (x, y): r g b" twice per line; header lines skipped). Output, one line:
#   texels N angle_mean DEG angle_p95 DEG (an upper bound, to 0.01 degree) angle_max DEG rg_change_mean REL bg_change_mean REL
# angle: between the input and output RGB vectors (0 = the same chromaticity, whatever the intensity);
# rg/bg change: |(r/g)_out / (r/g)_in - 1| and the same for b/g, means over the texels.
/Pixel/ {
    n = split($0, f, /[ \t]+/)
    # fields: ... "Pixel" "(x," "y):" r g b ... "Pixel" "(x," "y):" r g b
    k = 0
    for (i = 1; i <= n; i++) if (f[i] == "Pixel") p[++k] = i
    if (k != 2) next
    r1 = f[p[1] + 3]; g1 = f[p[1] + 4]; b1 = f[p[1] + 5]
    r2 = f[p[2] + 3]; g2 = f[p[2] + 4]; b2 = f[p[2] + 5]
    n1 = sqrt(r1 * r1 + g1 * g1 + b1 * b1); n2 = sqrt(r2 * r2 + g2 * g2 + b2 * b2)
    if (n1 <= 0 || n2 <= 0 || g1 <= 0 || g2 <= 0) { skipped++; next }
    c = (r1 * r2 + g1 * g2 + b1 * b2) / (n1 * n2)
    if (c > 1) c = 1
    a = atan2(sqrt(1 - c * c), c) * 180 / 3.14159265358979
    angle[++m] = a; sum += a; if (a > amax) amax = a
    rg += abs((r2 / g2) / (r1 / g1) - 1); bg += abs((b2 / g2) / (b1 / g1) - 1)
}
function abs(x) { return x < 0 ? -x : x }
END {
    if (m == 0) { print "chroma.awk: no texels" > "/dev/stderr"; exit 2 }
    # 95th percentile, to 0.01 degree: the upper edge of the 0.01-degree bin that holds it (no sort in awk)
    for (i = 1; i <= m; i++) bin[int(angle[i] * 100)]++
    need = 0.95 * m; acc = 0
    for (b = 0; acc < need; b++) acc += bin[b]
    printf "texels %d angle_mean %.4g angle_p95 %.4g angle_max %.4g rg_change_mean %.4g bg_change_mean %.4g skipped %d\n",
        m, sum / m, b / 100, amax, rg / m, bg / m, skipped + 0
}
