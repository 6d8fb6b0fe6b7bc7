# Analysis 2 (paper figure 7): AS -> Ward -> AS round trip: recovered F0 vs original F0, and its relative error.
# Data: d/roundtrip.dat, one block per alpha: alpha f0 forward_outcome recovered_f0 recovered_alpha back_outcome
# relative_error_percent forward_max(d+s).
load h.'/common.gp'
set terminal svg size 1100,500 dynamic enhanced font 'Helvetica,12' background rgb 'white'
set output o.'/roundtrip.svg'
n = words(alphas)
set multiplot layout 1,2 title "Round trip Ashikhmin-Shirley → Ward → Ashikhmin-Shirley (strategy auto, light 45°)" font ',14'
set title 'recovered vs original F_0'
set xlabel 'original F_0'
set ylabel 'recovered F_{0}, mean of RGB'
set xrange [0:1]; set yrange [0:1]
set size ratio -1
set key top left font ',10' box opaque
plot x with lines dt 2 lc rgb 'black' title 'identity', \
     for [i=1:n] d.'/roundtrip.dat' index (i-1) using 2:(isconv(strcol(3)) ? $4 : NaN) with points pt 7 ps 0.5 lc i title sprintf('α = %.2f', real(word(alphas, i))), \
     for [i=1:n] d.'/roundtrip.dat' index (i-1) using 2:(isconv(strcol(3)) ? NaN : $4) with points pt 6 ps 0.8 lc i notitle, \
     NaN with points pt 6 lc rgb '#555555' title 'forward fit unreachable (excluded)'
set size noratio
set title '|relative error| of the recovered F_0'
set ylabel '|recovered − original| / original  (%)'
set logscale y
set yrange [1e-5:100]
set format y '10^{%T}'
set key top left font ',10' box opaque
plot 1 with lines dt 2 lw 1.5 lc rgb 'black' title '1 %', \
     for [i=1:n] d.'/roundtrip.dat' index (i-1) using 2:(isconv(strcol(3)) && $2 > 0 ? abs($7) : NaN) with linespoints pt 7 ps 0.5 lc i notitle, \
     for [i=1:n] d.'/roundtrip.dat' index (i-1) using 2:(isconv(strcol(3)) || $2 == 0 ? NaN : abs($7)) with points pt 6 ps 0.8 lc i notitle, \
     for [i=1:n] d.'/roundtrip.dat' index (i-1) using 2:(isconv(strcol(3)) && $8 > 1 ? abs($7) : NaN) with points pt 2 ps 1.4 lw 1.5 lc rgb 'black' notitle, \
     NaN with points pt 2 ps 1.4 lw 1.5 lc rgb 'black' title 'forward converged, but d + s > 1 (trimmed)'
unset multiplot
