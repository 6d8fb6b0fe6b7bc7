# Analysis 5 (paper section 9): fits under the 45-degree light against fits under a frontal (head) light.
# Data: d/a1_LIGHT.dat (analysis 1), d/a3_auto_LIGHT.dat and d/a3_single_LIGHT.dat (analysis 3), d/xeval.txt
# (id fit_light eval_light outcome45 outcomeF ssim rmse source_rms relative_rmse).
load h.'/common.gp'
set terminal svg size 1100,820 dynamic enhanced font 'Helvetica,12' background rgb 'white'
set output o.'/light_position.svg'
set multiplot layout 2,2 title "Light position: 45° (solid, filled) vs frontal (dashed, open), strategy auto unless noted" font ',14'
set key bottom right font ',9' box opaque samplen 2 spacing 0.9
set title 'conductors AS → Ward: fitted specular (points: not converged)'
set xlabel 'source F_0'
set ylabel 'fitted Ward specular ρ_{s}'
set xrange [0:1]; set yrange [0:1.45]
sel = '0 1 3 5'
plot for [j=1:4] d.'/a1_45.dat' index int(word(sel, j)) using 2:3 with lines lw 1.5 lc j title sprintf('α = %.2f', 0.05 * (int(word(sel, j)) + 1)), \
     for [j=1:4] d.'/a1_frontal.dat' index int(word(sel, j)) using 2:3 with lines lw 1.5 dt 2 lc j notitle, \
     for [j=1:4] d.'/a1_45.dat' index int(word(sel, j)) using 2:(isconv(strcol(5)) ? NaN : $3) with points pt 7 ps 0.4 lc j notitle, \
     for [j=1:4] d.'/a1_frontal.dat' index int(word(sel, j)) using 2:(isconv(strcol(5)) ? NaN : $3) with points pt 6 ps 0.6 lc j notitle, \
     NaN with points pt 7 ps 0.6 lc rgb '#555555' title 'not converged', \
     1 with lines dt 3 lc rgb 'black' notitle
set title 'dielectrics AS → Ward: fitted specular'
set key top left
set xlabel 'source IOR'
set ylabel 'fitted Ward specular ρ_{s}, mean of RGB'
set xrange [1:2]; set yrange [0:*]
plot d.'/a3_auto_45.dat' using 1:2 with linespoints pt 7 ps 0.3 lc 1 title 'auto, 45°', \
     d.'/a3_auto_frontal.dat' using 1:2 with linespoints dt 2 pt 6 ps 0.4 lc 1 title 'auto, frontal', \
     d.'/a3_two_45.dat' using 1:2 with lines lc 2 title 'two, 45°', \
     d.'/a3_two_frontal.dat' using 1:2 with lines dt 2 lc 2 title 'two, frontal'
set title 'dielectrics: fitted Ward roughness α (auto)'
set ylabel 'fitted Ward α'
set logscale y
set yrange [0.05:1.2]
plot d.'/a3_auto_45.dat' using 1:6 with linespoints pt 7 ps 0.4 lc 1 title '45°', \
     d.'/a3_auto_frontal.dat' using 1:6 with linespoints dt 2 pt 6 ps 0.5 lc 1 title 'frontal'
unset logscale y
set title "cross-evaluation: 1 − SSIM against the source under the evaluation light"
set key top left font ',9' samplen 1 spacing 0.9
set xlabel '1 − SSIM of the fit made under 45°'
set ylabel '1 − SSIM of the fit made under frontal light'
set logscale xy
set xrange [1e-4:1]; set yrange [1e-4:1]
set format x '10^{%T}'; set format y '10^{%T}'
set size ratio -1
# pair rows of the same material and evaluation light: xeval.txt is sorted by id, fit light, eval light, so
# for one id the rows are (45,45) (45,frontal) (frontal,45) (frontal,frontal).
plot x with lines dt 2 lc rgb 'black' title 'equal', \
     '< awk ''$8 < 1e-4 {next} {k = $1 " " $3; if ($2 == "45") a[k] = 1 - $6; else b[k] = 1 - $6} END {for (k in a) {split(k, w, " "); print a[k], b[k], w[2], substr(w[1], 1, 1)}}'' '.d.'/xeval.txt' \
         using ($1 > 1e-5 ? $1 : 1e-5):($2 > 1e-5 ? $2 : 1e-5):(strcol(3) eq '45' ? (strcol(4) eq 'c' ? 0x1b9e77 : 0x7570b3) : (strcol(4) eq 'c' ? 0xd95f02 : 0xe7298a)) \
         with points pt 7 ps 0.6 lc rgb variable notitle, \
     NaN with points pt 7 lc rgb 0x1b9e77 title 'conductors, under 45°', \
     NaN with points pt 7 lc rgb 0xd95f02 title 'conductors, under frontal', \
     NaN with points pt 7 lc rgb 0x7570b3 title 'dielectrics, under 45°', \
     NaN with points pt 7 lc rgb 0xe7298a title 'dielectrics, under frontal'
unset multiplot
