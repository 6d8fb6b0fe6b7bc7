# compare.gp — one Appendix pair: our fitted curves (both fit lights) beside the paper's printed ones, and the sweep
# data behind ours. Part of `make paper` (scripts/paper-appendix.sh), which sets with -e:
#   out, ttl, xl, yl              output SVG, title, axis labels (alpha units)
#   lo, hi                        the domain plotted (the sweep's, in alpha units)
#   pp, pk                        the paper's roughness polynomial "c0 c1 c2 c3 c4" and slope "c0 c1 c2 c3 c4 c5"
#   pp2                           an alternative reading of the paper's polynomial ("" for none), ppl2 its label
#   of, ok, ff, fk                ours, frontal light: polynomial and slope; the same for 45 degrees: ff/fk
#   sqs, sqt                      1: the source (target) roughness is Cycles' slider, alpha = roughness^2
#   dr, dk                        data files: "light alpha target_alpha" rows and "light alpha slope" rows
set terminal svg size 1000,500 dynamic font 'Helvetica,11' background rgb 'white'
set output out
set encoding utf8
c(s, i) = real(word(s, i))
poly(s, x) = c(s,1) + c(s,2)*x + c(s,3)*x**2 + c(s,4)*x**3 + c(s,5)*x**4
ksq(s, x) = c(s,1) + c(s,2)*exp(-c(s,3)*x) + c(s,4)*exp(-c(s,5)*x**2) + (words(s) > 5 ? c(s,6)/x : 0)
klin(s, x) = c(s,1) + c(s,2)*exp(-c(s,3)*x) + c(s,4)*exp(-c(s,5)*x) + (words(s) > 5 ? c(s,6)/x : 0)
xs(x) = sqs ? sqrt(x) : x
yt(y) = sqt ? y**2 : y
set samples 150
set grid lc rgb '#dddddd'
set key below horizontal maxrows 3 samplen 2 font ',10'
extra = (pp2 eq '') ? '' : \
        sprintf(", [lo:hi] poly(pp2, x) with lines lw 1.5 dt 2 lc rgb 'black' title '%s'", ppl2)
set multiplot layout 1,2 title ttl noenhanced
set xrange [0:hi*1.02]
set xlabel xl noenhanced
set ylabel yl noenhanced
set title 'roughness' noenhanced
plot x with lines dt 3 lc rgb '#999999' title 'identity', \
     dr using ($1 == 0 ? $2 : NaN):3 with points pt 6 ps 0.45 lc rgb '#cc3311' title 'rows, frontal', \
     dr using ($1 == 45 ? $2 : NaN):3 with points pt 2 ps 0.45 lc rgb '#0077bb' title 'rows, 45°', \
     [lo:hi] yt(poly(of, xs(x))) with lines lw 2 lc rgb '#cc3311' title 'ours, frontal', \
     [lo:hi] yt(poly(ff, xs(x))) with lines lw 2 lc rgb '#0077bb' title 'ours, 45°', \
     [lo:hi] poly(pp, x) with lines lw 2 lc rgb 'black' title 'paper' @extra
set title 'specular slope k(α)' noenhanced
set ylabel 'k = target specular / source specular' noenhanced
plot dk using ($1 == 0 ? $2 : NaN):3 with points pt 6 ps 0.6 lc rgb '#cc3311' title 'row slopes, frontal', \
     dk using ($1 == 45 ? $2 : NaN):3 with points pt 2 ps 0.6 lc rgb '#0077bb' title 'row slopes, 45°', \
     [lo:hi] ksq(ok, xs(x)) with lines lw 2 lc rgb '#cc3311' title 'ours, frontal', \
     [lo:hi] ksq(fk, xs(x)) with lines lw 2 lc rgb '#0077bb' title 'ours, 45°', \
     [lo:hi] ksq(pk, x) with lines lw 2 lc rgb 'black' title 'paper, e^{-c4 α²} (§7)', \
     [lo:hi] klin(pk, x) with lines lw 1.5 dt 2 lc rgb 'black' title 'paper as printed, e^{-c4 α}'
unset multiplot
