# Analysis 1 (paper figure 6): fitted Ward specular vs Ashikhmin-Shirley F0, one curve per roughness.
# Data: d/a1_45.dat, one block per alpha: alpha f0 specular max(d+s) outcome rel_rmse ssim ward_alpha diffuse.
load h.'/common.gp'
set terminal svg size 820,560 dynamic enhanced font 'Helvetica,13' background rgb 'white'
set output o.'/conductors_as_ward.svg'
set title "Conductors: Ashikhmin-Shirley (Schlick F_0, diffuse 0) → Mitsuba Ward (trim on)\nstrategy auto, light 45°; per roughness 51 values of F_0"
set xlabel 'source F_{0}, Ashikhmin-Shirley (grey)'
set ylabel 'fitted Ward specular ρ_{s}, grey'
set xrange [0:1]
set yrange [0:1.45]
set key top left Left reverse spacing 1.1 font ',11' box opaque
n = words(alphas)
plot for [i=1:n] d.'/a1_45.dat' index (i-1) using 2:(isconv(strcol(5)) ? $3 : NaN) with linespoints lw 1.5 pt 7 ps 0.45 lc i \
         title sprintf('α = %.2f', real(word(alphas, i))), \
     for [i=1:n] d.'/a1_45.dat' index (i-1) using 2:(strcol(5) eq 'unreachable' ? $3 : NaN) with points pt 6 ps 1.1 lc i notitle, \
     for [i=1:n] d.'/a1_45.dat' index (i-1) using 2:(isconv(strcol(5)) && $4 > 1 ? $3 : NaN) with points pt 2 ps 1.4 lw 1.5 lc rgb 'black' notitle, \
     1 with lines dt 2 lw 1.5 lc rgb 'black' title 'Mitsuba trims when d + s > 1 (at ρ_{s}=1)', \
     NaN with points pt 6 ps 1.1 lc rgb '#555555' title 'outcome unreachable (trimming engaged)', \
     NaN with points pt 2 ps 1.4 lw 1.5 lc rgb 'black' title 'converged although d + s > 1 (gap < 1 %)'
