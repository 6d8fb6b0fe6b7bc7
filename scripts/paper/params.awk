# params.awk — how far two conversions of the same texture set differ, texel by texel (paper Fig. 18: a chain
# against a direct transform). Part of `make paper`.
#   paste <(oiiotool --dumpdata A_roughness.exr) <(oiiotool --dumpdata B_roughness.exr) \
#         <(oiiotool --dumpdata A_f0.exr) <(oiiotool --dumpdata B_f0.exr) | awk -v sq=1 -f params.awk
# Each input line holds four dumps' "Pixel (x, y): v ..." records: a one-channel roughness of A and B, then an RGB
# specular of A and B. sq=1 compares the roughness as alpha = roughness^2 (Cycles' slider) too. Output, one line:
#   texels N rough_mean_abs D rough_max_abs D alpha_mean_abs D spec_mean_rel R spec_max_rel R
/Pixel/ {
    n = split($0, f, /[ \t]+/)
    k = 0
    for (i = 1; i <= n; i++) if (f[i] == "Pixel") p[++k] = i
    if (k != 4) next
    ra = f[p[1] + 3]; rb = f[p[2] + 3]
    d = abs(ra - rb); rs += d; if (d > rmax) rmax = d
    as += abs(ra * ra - rb * rb)
    for (c = 0; c < 3; c++) {
        sa = f[p[3] + 3 + c]; sb = f[p[4] + 3 + c]
        if (sa > 1e-4) { e = abs(sb / sa - 1); ss += e; ns++; if (e > smax) smax = e }
    }
    m++
}
function abs(x) { return x < 0 ? -x : x }
END {
    if (m == 0) { print "params.awk: no texels" > "/dev/stderr"; exit 2 }
    printf "texels %d rough_mean_abs %.4g rough_max_abs %.4g alpha_mean_abs %.4g spec_mean_rel %.4g spec_max_rel %.4g\n",
        m, rs / m, rmax, as / m, ns ? ss / ns : 0, smax
}
